#pragma once
// Geometrically nonlinear statics (paper eq. 34-43, model.md §6): Newton-Raphson under load
// control. Per iteration the out-of-balance force r = P(s) - F_int(u) and the tangent K_T
// are assembled on the device from the shell elements and the PD bonds (atomic_add into a
// 6x6-block CRS matrix), supports are eliminated symmetrically, K_T du = r is solved by
// Belos PCG (GMRES for the exact tangent) with a Jacobi, smoothed-aggregation multigrid or
// sparse-Cholesky preconditioner (each kept across Newton iterations while the Krylov
// iterations stay low, then refreshed), translations are added and rotations composed,
// R <- exp(dphi) R (model.md §5).
// An increment that does not converge is restored and bisected, a bounded number of times.
// The state lives on the device; callers copy it to the host only for output.
#include <perishell/assembly/dirichlet.hpp>
#include <perishell/core/fenced_seconds.hpp>
#include <perishell/io/checkpoint.hpp>
#include <perishell/assembly/nodal_block_crs.hpp>
#include <perishell/pd/bond_tangent.hpp>
#include <perishell/shell/shell_body.hpp>
#include <perishell/solvers/belos/cg_solve.hpp>
#include <perishell/solvers/belos/overlapping_schwarz.hpp>
#include <perishell/solvers/belos/subdomain_coarse_space.hpp>
#include <perishell/solvers/direct/factorization_preconditioner.hpp>
#include <perishell/solvers/explicit/external_actions.hpp>
#include <perishell/solvers/multigrid/smoothed_aggregation.hpp>
#include <perishell/solvers/state_check.hpp>
#include <perishell/parallel/gather_nodes.hpp>
#include <perishell/parallel/node_distribution.hpp>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace perishell::solvers {

// The nodes that carry the DOFs of every half bond's two ends (a mirror image's master for
// the image, assembly/mirror_images.hpp), as the block pattern takes them (a free function:
// nvcc refuses extended lambdas in constructors).
template <class ExecutionSpaceT, class MemorySpaceT>
Kokkos::View<LocalIndex* [2], Kokkos::LayoutRight, MemorySpaceT> bondEndNodes(
    const ExecutionSpaceT& space, const pd::BondList<MemorySpaceT>& bonds,
    const assembly::MirrorImages<MemorySpaceT>& images = {}) {
  Kokkos::View<LocalIndex* [2], Kokkos::LayoutRight, MemorySpaceT> nodes("bond end nodes", bonds.numBonds());
  const auto halfBonds = bonds.halfBonds;
  Kokkos::parallel_for(
      "perishell::newton::bondEndNodes", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, nodes.extent(0)),
      KOKKOS_LAMBDA(const RowOffset b) {
        nodes(b, 0) = images.carrier(halfBonds(b, 0));
        nodes(b, 1) = images.carrier(halfBonds(b, 1));
      });
  return nodes;
}

// Each node's region for the AMG's scaling by region
// (multigrid::SmoothedAggregationPreconditioner): 1 where a bond ends (the PD zone and its
// transition), 2 at the other corners of shell elements, 0 elsewhere. The transition's nodes
// go with the PD zone: as a third region of their own, the simply supported 1 m plate of
// docs/implicit.md ("Scaling by region") took 169 PCG iterations instead of 154-156.
template <class ExecutionSpaceT, class MemorySpaceT>
Kokkos::View<int*, MemorySpaceT> nodeRegions(
    const ExecutionSpaceT& space, LocalIndex numNodes, const QuadConnectivityView<MemorySpaceT>& quads,
    const Kokkos::View<LocalIndex* [2], Kokkos::LayoutRight, MemorySpaceT>& bondNodes) {
  Kokkos::View<int*, MemorySpaceT> regions("perishell::newton::nodeRegions", numNodes);
  Kokkos::parallel_for(
      "perishell::newton::bondRegions", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, bondNodes.extent(0)),
      KOKKOS_LAMBDA(const RowOffset b) {
        Kokkos::atomic_fetch_or(&regions(bondNodes(b, 0)), 1);
        Kokkos::atomic_fetch_or(&regions(bondNodes(b, 1)), 1);
      });
  Kokkos::parallel_for(
      "perishell::newton::shellRegions", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, quads.extent(0)),
      KOKKOS_LAMBDA(const LocalIndex e) {
        for (int a = 0; a < 4; ++a) Kokkos::atomic_fetch_or(&regions(quads(e, a)), 2);
      });
  Kokkos::parallel_for(
      "perishell::newton::transitionRegion", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, numNodes),
      KOKKOS_LAMBDA(const LocalIndex node) {
        if (regions(node) & 1) regions(node) = 1;
      });
  return regions;
}

struct NewtonOptions {
  int maxIterations = 100;
  // Converged on the residual when |r_free| <= tolerance * max(|P(s)|, |reactions|) (2-norms
  // over all DOF), or on the displacement increment when the last correction's largest
  // translation is <= tolerance * the increment's largest translation while |r_free| <=
  // sqrt(tolerance) * max(|P|, |reactions|): Newton has then stopped moving, and what is left
  // of r is the round-off of the internal forces (sums of large element and bond forces that
  // cancel), which at small load levels can exceed tolerance * |P|. At the smallest loads even
  // sqrt(tolerance) is out of reach: the forces come from coordinates whose last bits carry
  // the displacement (x = X + u, total form), so their round-off floor is about
  // eps |K| |X| per DOF (roundOffFloor), whatever the load. Newton stops there too when its
  // last correction was below sqrt(tolerance) of the increment (convergedAtRoundOff): a 1 m
  // clamped plate 1 mm thick under 1e-3 Pa stalled at a relative residual of 2e-2 before.
  double tolerance = 1e-8;
  // Bisections of one increment in all before giving up: the halvings after a failed sub-step
  // and those after a hard one (below) together, so that a load no step converges easily under
  // stops the run rather than creeping on in ever smaller sub-steps.
  int maxCuts = 8;
  // Automatic sub-steps: the step that converged in at most easyIterations Newton iterations
  // is doubled for the next one, one that needed more than hardIterations is halved (before
  // it needs a cut, and counted as one); the step carries over to the next increment, never
  // beyond its size.
  int easyIterations = 8;
  int hardIterations = 16;
  // Line search along du where the full step overshoots: regula falsi on s(eta) = du . r(u +
  // eta du), the energy's slope along du (Crisfield, Non-linear Finite Element Analysis of
  // Solids and Structures, vol. 1, §9.3), when |r| grows and s changes sign over the step.
  // Off by default: on the slit annular plate (Sze 3.3) it took 4,015 Newton iterations where
  // plain Newton took about 1,000 (docs/implicit.md).
  bool lineSearch = false;
  // Arc-length control (advanceByArcLength): the first increment's load step, as a fraction
  // of the full load; the arc length then follows the Newton iterations (desiredIterations).
  double arcLengthFirstStep = 0.05;
  int desiredIterations = 5;
  double maxArcLengthGrowth = 2.0;  // the arc length stays within this factor of the first
  // Auto: Cholesky up to autoCholeskyDofs free DOF, else Amg, which gives way to Cholesky
  // (up to autoSwitchDofs) after an increment whose linear solves averaged more than
  // autoSwitchIterations Krylov iterations; a factorization that fails (memory) goes back to Amg.
  deck::Preconditioner preconditioner = deck::Preconditioner::BlockJacobi;
  // H200 and 2 CPU threads, reference BLAS (docs/implicit.md): the factorization wins by 2-4x
  // on the curved shells of a few thousand DOF, AMG by 35x on the GPU for the flat pressed
  // plate of 65,880 DOF (1.8 s per factorization).
  long long autoCholeskyDofs = 20000;
  long long autoSwitchDofs = 300000;
  double autoSwitchIterations = 60.0;
  // The Cholesky factor is reused while a solve needs at most this many Krylov iterations;
  // a solve that needs more refreshes it for the next one, and a reused factor that has not
  // converged after 3x as many is refreshed at once and the solve repeated (hemisphere 3.4:
  // 8.9 Krylov iterations per Newton iteration, 91 factorizations for 116 iterations; with
  // 8 and 4x: 13.8 and 77, the same wall time).
  int factorRefreshIterations = 5;
  // Where a GPU run factors (deck solver.factorization, direct/factorization_preconditioner.hpp);
  // Auto: on the device from autoDeviceFactorizationRows rows of the factored matrix, on the
  // host below. Measured on an H100 (docs/implicit.md, "Device factorization"): cuSOLVER's
  // csrchol factors faster than CHOLMOD but its triangular solves are slow, so per Newton
  // iteration of the pressed plate 4.2.1 it loses at 65,880 free DOF (0.92 s against 0.73 s),
  // wins at 261,360 (3.3 s against 4.3 s) and at 1.6 M (18 s against 51 s); on the curved
  // shells of a few thousand DOF the host is 1.3-2.7x faster over a whole run.
  deck::Factorization factorization = deck::Factorization::Auto;
  long long autoDeviceFactorizationRows = 150000;
  // Symmetric: PCG, quadratic convergence where no moment is applied. Exact: GMRES with the
  // non-symmetric tangent, which stays quadratic under applied (fixed-axis) moments; with
  // the symmetric one Newton converges linearly there and fails past the half circle of
  // Sze 3.2 (tstStaticNewton).
  TangentForm tangent = TangentForm::Symmetric;
  int maxLinearIterations = 20000;
  // The AMG hierarchy is rebuilt at the first Newton iteration of every attempt and reused
  // for the later ones while the tangent changes little: until a solve needs more than
  // amgReuseGrowth times the Krylov iterations of the solve right after the rebuild, or fails
  // (then it is rebuilt and that solve repeated). 0 rebuilds it at every iteration. A
  // rebuild (lambda_max, Galerkin products, coarse inverse) costs about as much as 13-36 PCG
  // iterations, so a fresh hierarchy for each increment's hardest solve pays: carried across
  // increments it cost more PCG time than it saved (docs/implicit.md, "Cheaper set-up").
  double amgReuseGrowth = 1.5;
  // multigrid::SmoothedAggregationOptions::dropTolerance (deck solver.amg-drop-tolerance).
  double amgDropTolerance = multigrid::SmoothedAggregationOptions{}.dropTolerance;
  // multigrid::SmoothedAggregationOptions::maxCoarseNodes (deck solver.amg-coarse-nodes).
  LocalIndex amgCoarseNodes = multigrid::SmoothedAggregationOptions{}.maxCoarseNodes;
  // multigrid::SmoothedAggregationOptions::regionScaling (deck solver.amg-region-scaling).
  bool amgRegionScaling = true;
  // Distributed runs: the ranks' preconditioners (AMG, Cholesky or block Jacobi of each owned
  // block) are coupled by a coarse space of every rank's six rigid-body modes, balancing
  // two-level Schwarz (belos/subdomain_coarse_space.hpp, docs/parallel.md); false: each rank's
  // preconditioner alone, added over the ranks (deck solver.coarse-space).
  bool coarseSpace = true;
  // Distributed runs: each rank's preconditioner covers its owned nodes and the halo nodes the
  // exchange fills, their rows imported whole from their owners (overlapping additive Schwarz,
  // belos/overlapping_schwarz.hpp); false: the owned block alone (deck solver.overlap).
  bool overlap = true;
  // Mixed-format Newton (docs/implicit.md): the shell elements' local forces s are carried
  // from iteration to iteration as independent unknowns, s <- K_l (d + B du), and the next
  // tangent's initial-stress term takes them in place of K_l d at the new state. Converged
  // states are the same; thin shells whose membrane stiffens under a tangent step converge in
  // far fewer iterations. Off: the displacement-based Newton.
  bool mixedFormat = true;
};

// Wall time of the phases of the paper's Table 3, summed over the Newton iterations of an
// advance (each phase fenced, so the times are the device's).
struct PhaseSeconds {
  double residual = 0.0;        // loads and internal forces (stress update)
  double assembly = 0.0;        // tangent into the CRS values (atomic_add)
  double constraints = 0.0;     // Dirichlet elimination
  double preconditioner = 0.0;  // set-up or update of the preconditioner
  double linearSolve = 0.0;     // PCG
  double update = 0.0;          // u += du, R <- exp(dphi) R
};

// What it took to reach one load level.
struct IncrementReport {
  double loadFactor = 0.0;
  int attempts = 0, cuts = 0, newtonIterations = 0;
  long long linearIterations = 0;
  int preconditionerBuilds = 0;  // AMG hierarchies built or updated (NewtonOptions::amgReuseGrowth)
  int factorizations = 0;        // Cholesky factorizations (NewtonOptions::factorRefreshIterations)
  // Negative pivots of the tangent at the converged state (Cholesky and Direct only): > 0 says
  // the equilibrium is unstable, a limit or bifurcation point was reached or passed.
  long negativePivots = 0;
  // A tangent on the way was not positive definite though the converged one may be: under load
  // control the increment snapped past a limit point (the path between was not followed).
  bool passedUnstableState = false;
  int lineSearches = 0;  // Newton updates the line search shortened
  std::vector<std::string> notes;  // what the solver changed on its own, for the log
  double relativeResidual = 0.0;
  // Whether the last increment converged on the displacement increment rather than the residual.
  bool convergedOnDisplacement = false;
  // Whether it stopped at the round-off floor of the internal forces instead (NewtonOptions::
  // tolerance): the residual could not fall below that floor, and Newton had stopped moving.
  bool convergedAtRoundOff = false;
  PhaseSeconds seconds;
};

namespace detail {
inline std::string scientific(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3e", value);
  return text;
}
}  // namespace detail

template <class ExecutionSpaceT>
class StaticNewtonSolver {
  static_assert(is_execution_space_v<ExecutionSpaceT>);

 public:
  using Memory = typename ExecutionSpaceT::memory_space;
  using Matrix = belos::CrsMatrix<ExecutionSpaceT>;

  // Either body may be empty (no elements / no PD nodes). The PD body's node k must be mesh
  // node k (pd::indexByMeshNodes; coupling/make_coupled_model.hpp builds both bodies).
  // distribution: in a distributed run (docs/parallel.md), this rank's part: the bodies and
  // actions are its local model's, its owned rows of the tangent are complete, and every
  // reduction, convergence test and linear solve is global, so that all ranks take the same
  // decisions. The preconditioner is per rank (additive over ranks: the tangent's owned block,
  // coupling to other ranks' rows dropped). Collective in every member then.
  StaticNewtonSolver(const ExecutionSpaceT& space, LocalIndex numNodes, std::optional<shell::ShellBody<Memory>> shellBody,
                     std::optional<pd::PdBody<Memory>> pdBody, ExternalActions<Memory> actions,
                     const NewtonOptions& options,
                     parallel::NodeDistribution<Memory> distribution = parallel::NodeDistribution<Memory>());

  // Moves the load factor from its current value to loadFactor (>= current) in sub-steps
  // sized by the Newton iterations of the last one (NewtonOptions::easyIterations), halving a
  // step Newton fails on or needs many iterations for. Throws NewtonFailure after maxCuts
  // halvings in all within this increment.
  IncrementReport advanceTo(double loadFactor);

  // The tangent assembled at the current state with the supports eliminated symmetrically;
  // rhs takes the elimination's right-hand side terms.
  Matrix constrainedTangent(const VectorView<Memory>& rhs, IncrementReport& report);

  // Krylov method and simple preconditioner for the tangent in use, to the given tolerance.
  belos::CgOptions linearOptions(double tolerance) const;

  // The tangent at the converged state, factored: its inertia says whether the equilibrium
  // is stable (report.negativePivots), and the next increment starts from this fresh factor.
  void factorConvergedTangent(IncrementReport& report);

  // The preconditioner in use (Auto resolved).
  deck::Preconditioner activePreconditioner() const { return active_; }
  // Where the last factorization ran (NewtonOptions::factorization): "device (cuSOLVER)",
  // "host (CHOLMOD)", or empty before the first.
  std::string factorizationPlace() const {
    if (!factor_) return {};
    return factor_->factoredOnDevice() ? "device (cuSOLVER)" : "host (CHOLMOD)";
  }
  long long numFreeDofs() const { return freeDofs_; }
  // Where the AMG hierarchy's set-up time went, over every build and update of this solver
  // (zeros before the first AMG solve).
  multigrid::SmoothedAggregationSetupSeconds multigridSetupSeconds() const {
    return multigrid_ ? multigrid_->setupSeconds() : multigrid::SmoothedAggregationSetupSeconds{};
  }
  TangentForm tangentForm() const { return options_.tangent; }

  // Why arc-length control cannot run this model (it scales every load and prescribed value
  // by one factor), or empty: load curves, and supports with nonzero prescribed values.
  std::string arcLengthObstacle() const;

  // One increment of Crisfield's cylindrical arc-length method (Non-linear Finite Element
  // Analysis of Solids and Structures, vol. 1, §9.3.2; model.md §6's Newton with the load
  // factor as an unknown): the load factor s and the displacements move together along the
  // equilibrium path by a fixed length |delta u| (translations) from the last converged state,
  // so the path is followed through limit points, where the load falls, and snap-backs. The
  // predictor goes along the tangent K dt = P_ref in the direction of the last increment
  // (the sign of dt . delta u_prev); each corrector solves K dr = r and K dt = P_ref and picks
  // ds from the constraint's quadratic, the root closer to the last direction. The arc
  // length grows or shrinks with the Newton iterations; an increment that fails is restored
  // and retried at half the length, at most maxCuts times. Needs proportional loading
  // (arcLengthObstacle() empty).
  IncrementReport advanceByArcLength(double stopAt = 1.0);

  // The converged state between increments, for a checkpoint (io/checkpoint.hpp, entries
  // "implicit.*"): displacements, rotations, the load factor and where the supports stand, the
  // next sub-step's size, the preconditioner in use, and the arc-length state. Nodal entries in
  // mesh-node order, as a single-rank run writes them, on the root (parallel/gather_nodes.hpp).
  // Collective.
  void saveTo(io::Checkpoint& checkpoint, const parallel::NodeGather& gather) const;
  // Continues from saveTo's state on a solver of the same model, on this or any other rank
  // count. Where the saved solver held a fresh factor of the converged tangent, the same factor
  // is made again here, so the next increment runs as the saved solver's would have (bit for
  // bit on one backend, build and rank count). Throws io::CheckpointError when the checkpoint
  // is not of this model. Collective.
  void restoreFrom(const io::Checkpoint& checkpoint, const parallel::NodeGather& gather);

  double loadFactor() const { return loadFactor_; }
  // Called after every Newton iteration and every cut with the load factor being tried and
  // the increment's report so far: the run's progress lines during long increments.
  using IterationObserver = std::function<void(double target, const IncrementReport& report)>;
  void observeIterations(IterationObserver observer) { observer_ = std::move(observer); }
  const pd::PdKinematics<Memory>& kinematics() const { return state_; }
  // P - F_int at the last evaluation (the converged state after advanceTo): zero to the
  // tolerance at free DOF, minus the support reaction at prescribed DOF.
  const pd::NodalVectorView<Memory>& outOfBalance() const { return outOfBalance_; }
  LocalIndex numBonds() const { return pd_ ? static_cast<LocalIndex>(pd_->bonds.numBonds()) : 0; }
  LocalIndex numElements() const { return shell_ ? shell_->numElements() : 0; }
  RowOffset numMatrixEntries() const { return pattern_.columns.extent(0); }

  // ---- public for nvcc (extended lambdas need public enclosing functions) ----

  struct ResidualNorms {
    double free = 0.0, reference = 0.0;
  };

  // One Newton solve at load factor target; returns the empty string when it converged,
  // else why not.
  std::string iterate(double target, IncrementReport& report);

  // Regula falsi for s(eta) = du . r(u + eta du) = 0 between 0 (s(0) = slope > 0) and 1, where
  // s(1) < 0 (the full step overshoots) or r is not finite; at most 4 trial states, eta >= 1/16.
  // Leaves the state at the trial with the smallest |r| (the full step if none is smaller) and
  // `evaluated` at its residual; returns its eta.
  double searchLine(double target, double slope, ResidualNorms& evaluated, IncrementReport& report);

  // du . r over the free DOF (r: the out-of-balance force as last evaluated).
  double freeDot() const { return dofDot(correction_, outOfBalance_, false); }

  // Largest |translation| of the last correction du, or of the increment (u minus the state
  // saved at its start).
  double largestTranslation(bool ofIncrement) const;
  // The round-off floor of the out-of-balance force: the 2-norm over rows of eps sum_j |K_ij| s_j,
  // s_j the model's size for a translation column and 1 for a rotation (NewtonOptions::tolerance).
  double roundOffFloor(const belos::CrsMatrix<ExecutionSpaceT>& K) const;

  // r = P(s) - F_int; returns |r| over free DOF and max(|P(s)|, |r| over prescribed DOF).
  ResidualNorms computeOutOfBalance(double loadFactor);

  // 2-norm of the out-of-balance force over the prescribed DOF (reactions) or the free ones.
  double outOfBalanceNorm(bool overPrescribedDofs) const;

  // a . b over the prescribed DOF or the free ones, for nodal 6-vectors.
  double dofDot(const pd::NodalVectorView<Memory>& a, const pd::NodalVectorView<Memory>& b,
                bool overPrescribedDofs) const;

  // K du = rhs. The multigrid hierarchy of the last solve is reused unless this is an
  // attempt's first iteration or the last solve needed too many iterations
  // (NewtonOptions::amgReuseGrowth); a reused hierarchy that fails is rebuilt and the solve
  // repeated. Throws what the solve with a fresh preconditioner throws.
  belos::CgResult solveLinear(const Matrix& K, const VectorView<Memory>& rhs, const VectorView<Memory>& solution,
                              const belos::CgOptions& linear, bool attemptStart, IncrementReport& report);

  // K du = rhs from du = 0. rebuild: the block-Jacobi family is rebuilt from K; the multigrid
  // hierarchy is built once (its aggregates and product patterns depend only on the pattern)
  // and updated with K and the current node positions (its rigid-body modes). Without
  // rebuild the hierarchy is reused, with no more PCG iterations than the reuse allows.
  belos::CgResult solveOnce(const Matrix& K, const VectorView<Memory>& rhs, const VectorView<Memory>& solution,
                            const belos::CgOptions& linear, bool rebuild, IncrementReport& report);

  bool usesFactor() const;

  // K du = rhs preconditioned by a Cholesky factor of a recent tangent: reused while solves
  // stay within factorRefreshIterations (Direct: refactored for every solve), refreshed when
  // a solve needed more, or at once when the reused factor does not converge in 3x as many.
  belos::CgResult solveWithFactor(const Matrix& K, const VectorView<Memory>& rhs, const VectorView<Memory>& solution,
                                  const belos::CgOptions& linear, IncrementReport& report);

  // A fresh factor of K (counted, timed, its switch to or from L D L^T noted).
  direct::FactorizationInfo factorize(const Matrix& K, IncrementReport& report);

  belos::CgResult krylovWithFactor(const Matrix& K, const VectorView<Memory>& rhs, const VectorView<Memory>& solution,
                                   belos::CgOptions linear, IncrementReport& report);

  // Auto: AMG gives way to the factorization after an increment whose solves averaged more
  // than autoSwitchIterations Krylov iterations (thin curved shells, large rotations).
  void switchToCholeskyWhenAmgStruggles(IncrementReport& report);

  long long countFreeDofs() const;

  int reuseIterationLimit() const;

  void updateCurrentPositions();

  void assembleTangent();

  // Prescribed DOF take value x factor(s) (docs/deck.md: a support without a curve ramps
  // with s in an implicit run); a prescribed rotation component replaces that component
  // of the node's rotation vector.
  void applyPrescribedValues(double loadFactor);

  // u += eta du; R <- exp(eta dphi) R. With the mixed format, the shell's local forces
  // linearised along eta du first.
  void applyCorrection(double eta);

  // The load at factor 1 (every pattern, no curves) with the constrained rows zeroed, and the
  // work vectors of the arc-length method.
  void makeArcLengthVectors();

  // Sums over the nodes of a . b for translations, with a, b chosen by index: 0 the corrector
  // dr (correction_), 1 the tangent direction dt, 2 the increment delta u = u - u_start, 3 the
  // last converged increment's direction.
  double translationDot(int first, int second) const;

  void recordArcDirection();

  // correction_ = dr + ds dt (all six DOF).
  void combineCorrection(double ds);

  // Solves K x = rhs (rhs with its constrained rows zero, consumed); x is `into`
  // (correction_ or tangentDirection_). Returns why it failed, or empty.
  std::string solveTangent(const Matrix& K, const pd::NodalVectorView<Memory>& rhs,
                           const pd::NodalVectorView<Memory>& into, double tolerance, bool attemptStart,
                           IncrementReport& report);

  std::string arcLengthIterate(IncrementReport& report);

  void markConstrainedDofs();

  // The tangent's block for the per-rank preconditioner (distributed runs): with
  // NewtonOptions::overlap the tangent on the owned and exchanged halo nodes, the halo rows
  // imported from their owners (belos::OverlapImport); without, the owned block, entries
  // coupling an owned row to a halo column dropped, halo rows the identity. K itself on a
  // single rank. Symmetric and, where K is positive definite, positive definite. Collective.
  Matrix preconditionerMatrix(const Matrix& K);
  // The overlap's import of halo rows (made from K's pattern on first use, once: the pattern
  // never changes). Its distribution, a copy of distribution_ (the exchange buffers shared, used
  // one at a time), also serves every AdditiveSchwarz, so their reverse buffers are made once.
  // Collective.
  belos::OverlapImport<ExecutionSpaceT>& overlapImport(const Matrix& K);

  // Distributed runs: `local` (this rank's preconditioner, of preconditionerMatrix(K)) as the
  // Krylov method applies it: with NewtonOptions::overlap its overlapping Schwarz, with
  // NewtonOptions::coarseSpace within the coarse space over the ranks (built from K). Made when
  // there is none: the callers drop it whenever they rebuild `local`. `local` itself on a
  // single rank. Collective.
  Teuchos::RCP<const Belos::Operator<double>> coupleRanks(const Matrix& K,
                                                          const Teuchos::RCP<const Belos::Operator<double>>& local);

  // Sets the halo rows of a vector of 6 DOF per local node to their owners' values (distributed
  // runs; nothing on a single rank).
  void fillHalo(const VectorView<Memory>& vector);

  // A fresh factor (or a multigrid hierarchy, or the block-Jacobi family) made on every rank:
  // a failure on one rank is thrown on all, so none waits in a collective.
  template <class Build>
  void onEveryRank(const char* what, Build&& build);

  const parallel::Communicator& communicator() const { return distribution_.communicator(); }

 private:
  void notifyIteration(double target, const IncrementReport& report) const;

  CurveFactors loadFactors(double s) const;

  // Node-major 6-DOF views seen as one vector of 6 N entries (LayoutRight: the same memory).
  VectorView<Memory> flatOutOfBalance() const { return VectorView<Memory>(outOfBalance_.data(), 6 * std::size_t(numNodes_)); }
  VectorView<Memory> flatCorrection() const { return VectorView<Memory>(correction_.data(), 6 * std::size_t(numNodes_)); }
  Kokkos::View<const double*, Memory> zerosConst() const { return zeros_; }

  void copyKinematics(const pd::PdKinematics<Memory>& to, const pd::PdKinematics<Memory>& from) const;
  void saveState() { copyKinematics(saved_, state_); }
  void restoreState() {
    copyKinematics(state_, saved_);
    mixedForcesCurrent_ = false;
    ++stateVersion_;
  }
  // The state before a Newton update, for the line search's trial states.
  void saveIterate() { copyKinematics(iterateStart_, state_); }
  void restoreIterate() {
    copyKinematics(state_, iterateStart_);
    ++stateVersion_;
  }

  ExecutionSpaceT space_;
  parallel::NodeDistribution<Memory> distribution_;
  // 1 for the nodes this rank owns (every node on a single rank): sums and norms take these.
  Kokkos::View<std::uint8_t*, Memory> ownedNodes_;
  belos::SharedRows<Memory> rows_;  // null on a single rank
  VectorView<Memory> preconditionerValues_;
  IterationObserver observer_;
  LocalIndex numNodes_;
  std::optional<shell::ShellBody<Memory>> shell_;
  std::optional<pd::PdBody<Memory>> pd_;
  ExternalActions<Memory> actions_;
  NewtonOptions options_;
  pd::PdKinematics<Memory> state_, saved_, iterateStart_;
  pd::NodalVectorView<Memory> outOfBalance_, correction_;
  Kokkos::View<bool*, Memory> isConstrained_;
  VectorView<Memory> zeros_;
  pd::BondFlagView<Memory> intact_, intactScratch_;
  VectorView<Memory> fractureScratch_;
  // The mixed-format Newton's shell local forces, and whether they belong to the current
  // state (set by a correction; a converged or restored state or moved supports take K_l d).
  shell::ElementLocalForcesView<Memory> mixedForces_;
  bool mixedForcesCurrent_ = false;
  // Counts the changes of the kinematic state; the tangent's values were assembled at
  // tangentVersion_ (with the mixed forces or not), and are reused while neither moved.
  std::uint64_t stateVersion_ = 0, tangentVersion_ = std::numeric_limits<std::uint64_t>::max();
  bool tangentUsedMixedForces_ = false;
  assembly::NodalBlockPattern<Memory> pattern_;
  VectorView<Memory> values_;
  CoordinateView<Memory> currentPositions_;
  std::shared_ptr<multigrid::SmoothedAggregationPreconditioner<ExecutionSpaceT>> multigrid_;
  Kokkos::View<int*, Memory> nodeRegions_;  // the AMG's regions (nodeRegions)
  deck::Preconditioner active_ = deck::Preconditioner::BlockJacobi;
  long long freeDofs_ = 0;
  std::unique_ptr<direct::FactorizationPreconditioner<ExecutionSpaceT>> factor_;
  Teuchos::RCP<const Belos::Operator<double>> coupled_;  // distributed runs (coupleRanks)
  std::unique_ptr<belos::OverlapImport<ExecutionSpaceT>> overlapImport_;  // distributed runs (overlapImport)
  bool factorCurrent_ = false;  // the factor is fresh enough to be reused
  bool factorPositiveDefinite_ = true;
  bool indefiniteNoted_ = false;  // the switch to L D L^T is noted once per run
  bool multigridReusable_ = false;
  int iterationsAfterRebuild_ = 0;
  double modelSize_ = 0.0;  // the bounding-box diagonal of the reference nodes [m]
  double loadFactor_ = 0.0;
  double prescribedFactor_ = 0.0;  // where applyPrescribedValues last put the supports (mirror images follow)
  double preferredStep_ = 0.0;  // the next sub-step's size (advanceTo), 0 before the first
  // Arc-length control: the load at factor 1, the tangent direction dt, the last increment's
  // translations, and the arc length (0 before the first increment).
  pd::NodalVectorView<Memory> referenceLoad_, tangentDirection_;
  CoordinateView<Memory> lastArcDirection_;
  bool hasArcDirection_ = false;
  double arcLength_ = 0.0, maxArcLength_ = 0.0;
};

// Compiled once per execution space (static_newton_impl.hpp, src/solvers/static_newton_*.cpp):
// these declarations keep every other file from compiling the solver again.
#ifdef KOKKOS_ENABLE_OPENMP
extern template class StaticNewtonSolver<Kokkos::OpenMP>;
#endif
#ifdef KOKKOS_ENABLE_CUDA
extern template class StaticNewtonSolver<Kokkos::Cuda>;
#endif

}  // namespace perishell::solvers
