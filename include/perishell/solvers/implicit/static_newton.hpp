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
#include <perishell/assembly/nodal_block_crs.hpp>
#include <perishell/pd/bond_tangent.hpp>
#include <perishell/shell/shell_body.hpp>
#include <perishell/solvers/belos/cg_solve.hpp>
#include <perishell/solvers/direct/factorization_preconditioner.hpp>
#include <perishell/solvers/explicit/external_actions.hpp>
#include <perishell/solvers/multigrid/smoothed_aggregation.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace perishell::solvers {

// The two end nodes of every half bond, as the block pattern takes them (a free function:
// nvcc refuses extended lambdas in constructors).
template <class ExecutionSpaceT, class MemorySpaceT>
Kokkos::View<LocalIndex* [2], Kokkos::LayoutRight, MemorySpaceT> bondEndNodes(const ExecutionSpaceT& space,
                                                                             const pd::BondList<MemorySpaceT>& bonds) {
  Kokkos::View<LocalIndex* [2], Kokkos::LayoutRight, MemorySpaceT> nodes("bond end nodes", bonds.numBonds());
  const auto halfBonds = bonds.halfBonds;
  Kokkos::parallel_for(
      "perishell::newton::bondEndNodes", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, nodes.extent(0)),
      KOKKOS_LAMBDA(const RowOffset b) {
        nodes(b, 0) = halfBonds(b, 0);
        nodes(b, 1) = halfBonds(b, 1);
      });
  return nodes;
}

struct NewtonOptions {
  int maxIterations = 100;
  // Converged on the residual when |r_free| <= tolerance * max(|P(s)|, |reactions|) (2-norms
  // over all DOF), or on the displacement increment when the last correction's largest
  // translation is <= tolerance * the increment's largest translation while |r_free| <=
  // sqrt(tolerance) * max(|P|, |reactions|): Newton has then stopped moving, and what is left
  // of r is the round-off of the internal forces (sums of large element and bond forces that
  // cancel), which at small load levels can exceed tolerance * |P|.
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
  // Symmetric: PCG, quadratic convergence where no moment is applied. Exact: GMRES with the
  // non-symmetric tangent, which stays quadratic under applied (fixed-axis) moments; with
  // the symmetric one Newton converges linearly there and fails past the half circle of
  // Sze 3.2 (tstStaticNewton).
  TangentForm tangent = TangentForm::Symmetric;
  int maxLinearIterations = 20000;
  // The AMG hierarchy is rebuilt at the first Newton iteration of every attempt and reused
  // for the later ones while the tangent changes little: until a solve needs more than
  // amgReuseGrowth times the Krylov iterations of the solve right after the rebuild, or fails
  // (then it is rebuilt and that solve repeated). 0 rebuilds it at every iteration. The
  // rebuild (Galerkin products, lambda_max, coarse inverse) costs as much as a few dozen
  // PCG iterations (docs/implicit.md).
  double amgReuseGrowth = 1.5;
};

// Newton gave up on an increment after every allowed cut; the state is the last converged one.
class NewtonFailure : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
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
  StaticNewtonSolver(const ExecutionSpaceT& space, LocalIndex numNodes, std::optional<shell::ShellBody<Memory>> shellBody,
                     std::optional<pd::PdBody<Memory>> pdBody, ExternalActions<Memory> actions,
                     const NewtonOptions& options)
      : space_(space),
        numNodes_(numNodes),
        shell_(std::move(shellBody)),
        pd_(std::move(pdBody)),
        actions_(std::move(actions)),
        options_(options),
        state_(numNodes),
        saved_(numNodes),
        iterateStart_(numNodes),
        outOfBalance_("perishell::newton::outOfBalance", numNodes),
        correction_("perishell::newton::correction", numNodes),
        isConstrained_("perishell::newton::isConstrained", 6 * std::size_t(numNodes)),
        zeros_("perishell::newton::zeros", 6 * std::size_t(numNodes)) {
    if (pd_ && pd_->numNodes() != numNodes)
      throw std::invalid_argument("StaticNewtonSolver: the PD body must cover every mesh node (got " +
                                  std::to_string(pd_->numNodes()) + " of " + std::to_string(numNodes) + ")");
    const auto quads = shell_ ? shell_->quads : QuadConnectivityView<Memory>("no quads", 0);
    Kokkos::View<LocalIndex* [2], Kokkos::LayoutRight, Memory> bondNodes("no bonds", 0);
    if (pd_) {
      intact_ = pd::makeIntactFlags(pd_->bonds, "perishell::newton::intact");
      intactScratch_ = pd::makeIntactFlags(pd_->bonds, "perishell::newton::intactScratch");
      fractureScratch_ = VectorView<Memory>("perishell::newton::fractureScratch", numNodes);
      bondNodes = bondEndNodes(space_, pd_->bonds);
    }
    pattern_ = assembly::buildNodalBlockPattern(space_, numNodes, quads, bondNodes);
    values_ = VectorView<Memory>("perishell::newton::tangentValues", pattern_.columns.extent(0));
    markConstrainedDofs();
    freeDofs_ = countFreeDofs();
    active_ = options_.preconditioner;
    if (active_ == deck::Preconditioner::Auto)
      active_ = freeDofs_ <= options_.autoCholeskyDofs ? deck::Preconditioner::Cholesky : deck::Preconditioner::Amg;
  }

  // Moves the load factor from its current value to loadFactor (>= current) in sub-steps
  // sized by the Newton iterations of the last one (NewtonOptions::easyIterations), halving a
  // step Newton fails on or needs many iterations for. Throws NewtonFailure after maxCuts
  // halvings in all within this increment.
  IncrementReport advanceTo(double loadFactor) {
    IncrementReport report;
    const double fullStep = loadFactor - loadFactor_;
    double step = preferredStep_ > 0.0 ? std::min(fullStep, preferredStep_) : fullStep;
    std::string lastReason;
    auto cut = [&](const std::string& reason, double target) {
      lastReason = reason;
      if (++report.cuts > options_.maxCuts)
        throw NewtonFailure("Newton did not reach load factor " + std::to_string(loadFactor) + " after " +
                            std::to_string(options_.maxCuts) + " cuts of the increment (solver.max-cuts; last " +
                            "sub-step towards " + std::to_string(target) + ", from " + std::to_string(loadFactor_) +
                            "): " + lastReason);
      step *= 0.5;
      preferredStep_ = step;
      notifyIteration(target, report);
    };
    while (loadFactor_ < loadFactor) {
      const double target = loadFactor_ + step >= loadFactor - 1e-12 * fullStep ? loadFactor : loadFactor_ + step;
      ++report.attempts;
      saveState();
      const int iterationsBefore = report.newtonIterations;
      const auto attempt = iterate(target, report);
      if (attempt.empty()) {
        loadFactor_ = target;
        const int iterations = report.newtonIterations - iterationsBefore;
        // A hard sub-step halves the next one: a cut while the increment has load left.
        if (iterations > options_.hardIterations && loadFactor_ < loadFactor)
          cut("the sub-step converged only in " + std::to_string(iterations) + " Newton iterations", target);
        else if (iterations > options_.hardIterations)
          step *= 0.5;
        if (iterations <= options_.easyIterations) step *= 2.0;
        preferredStep_ = step;
        step = std::min(step, fullStep);
        continue;
      }
      restoreState();
      cut(attempt, target);
    }
    report.loadFactor = loadFactor_;
    if (usesFactor()) factorConvergedTangent(report);
    switchToCholeskyWhenAmgStruggles(report);
    return report;
  }

  // The tangent assembled at the current state with the supports eliminated symmetrically;
  // rhs takes the elimination's right-hand side terms.
  Matrix constrainedTangent(const VectorView<Memory>& rhs, IncrementReport& report) {
    using Clock = std::chrono::steady_clock;
    auto start = Clock::now();
    assembleTangent();
    report.seconds.assembly += fencedSecondsSince(space_, start);
    start = Clock::now();
    assembly::eliminateDirichlet(space_, pattern_.rowMap, pattern_.columns, values_, rhs, isConstrained_, zerosConst());
    report.seconds.constraints += fencedSecondsSince(space_, start);
    const auto numRows = static_cast<LocalIndex>(rhs.extent(0));
    return Matrix("perishell::newton::tangent", numRows, numRows, static_cast<RowOffset>(values_.extent(0)), values_,
                  pattern_.rowMap, pattern_.columns);
  }

  // Krylov method and simple preconditioner for the tangent in use, to the given tolerance.
  belos::CgOptions linearOptions(double tolerance) const {
    belos::CgOptions linear;
    linear.method = options_.tangent == TangentForm::Exact ? belos::CgOptions::Method::Gmres : belos::CgOptions::Method::Cg;
    linear.preconditioner = active_ == deck::Preconditioner::Jacobi ? belos::CgOptions::Preconditioner::Jacobi
                                                                    : belos::CgOptions::Preconditioner::BlockJacobi;
    linear.maxIterations = options_.maxLinearIterations;
    linear.tolerance = tolerance;
    return linear;
  }

  // The tangent at the converged state, factored: its inertia says whether the equilibrium
  // is stable (report.negativePivots), and the next increment starts from this fresh factor.
  void factorConvergedTangent(IncrementReport& report) {
    // The elimination's right-hand side is scratch here.
    const Matrix K = constrainedTangent(flatCorrection(), report);
    try {
      const bool passedBefore = report.passedUnstableState;
      report.negativePivots = factorize(K, report).negativePivots;
      report.passedUnstableState = passedBefore && report.negativePivots == 0;
    } catch (const direct::FactorizationError& error) {
      // A singular converged tangent (exactly at a bifurcation): the next solve refactors.
      factorCurrent_ = false;
      report.notes.push_back(std::string("the tangent at the converged state could not be factored: ") + error.what());
    }
  }

  // The preconditioner in use (Auto resolved).
  deck::Preconditioner activePreconditioner() const { return active_; }
  long long numFreeDofs() const { return freeDofs_; }
  TangentForm tangentForm() const { return options_.tangent; }

  // Why arc-length control cannot run this model (it scales every load and prescribed value
  // by one factor), or empty: load curves, and supports with nonzero prescribed values.
  std::string arcLengthObstacle() const {
    for (std::size_t p = 0; p < actions_.patternCurves.size(); ++p)
      if (actions_.patternCurves[p]) return "a load follows a curve";
    const auto values = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, actions_.prescribedValue);
    for (std::size_t node = 0; node < values.extent(0); ++node)
      for (int d = 0; d < 6; ++d)
        if (values(node, d) != 0.0) return "a support prescribes a nonzero displacement or rotation";
    return "";
  }

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
  IncrementReport advanceByArcLength(double stopAt = 1.0) {
    IncrementReport report;
    if (referenceLoad_.extent(0) == 0) makeArcLengthVectors();
    const double startFactor = loadFactor_;
    std::string lastReason;
    for (;;) {
      ++report.attempts;
      saveState();
      const auto attempt = arcLengthIterate(report);
      if (attempt.empty()) {
        recordArcDirection();
        const int iterations = std::max(report.newtonIterations, 1);
        const double growth = std::clamp(std::sqrt(double(options_.desiredIterations) / iterations), 0.5, 2.0);
        arcLength_ = std::min(maxArcLength_, growth * arcLength_);
        break;
      }
      restoreState();
      loadFactor_ = startFactor;
      lastReason = attempt;
      if (++report.cuts > options_.maxCuts)
        throw NewtonFailure("the arc-length increment from load factor " + std::to_string(startFactor) +
                            " did not converge after " + std::to_string(options_.maxCuts) +
                            " cuts of the arc length: " + lastReason);
      arcLength_ *= 0.5;
      report.newtonIterations = 0;
    }
    if (startFactor < stopAt && loadFactor_ > stopAt) {
      // The path rose through stopAt within this arc: end on it exactly, under load control
      // from the increment's start (the load rises between the two states).
      restoreState();
      loadFactor_ = startFactor;
      const IncrementReport toStop = advanceTo(stopAt);
      report.newtonIterations += toStop.newtonIterations;
      report.linearIterations += toStop.linearIterations;
      report.factorizations += toStop.factorizations;
      report.cuts += toStop.cuts;
      report.negativePivots = toStop.negativePivots;
      report.loadFactor = loadFactor_;
      return report;
    }
    report.loadFactor = loadFactor_;
    if (usesFactor()) factorConvergedTangent(report);
    return report;
  }

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
  std::string iterate(double target, IncrementReport& report) {
    applyPrescribedValues(target);
    double initialResidual = 0.0, lastCorrection = 0.0;
    using Clock = std::chrono::steady_clock;
    std::optional<ResidualNorms> evaluated;  // r after the last update (and line search)
    for (int iteration = 0;; ++iteration) {
      auto start = Clock::now();
      const ResidualNorms norms = evaluated ? *evaluated : computeOutOfBalance(target);
      report.seconds.residual += fencedSecondsSince(space_, start);
      if (!std::isfinite(norms.free) || !std::isfinite(norms.reference))
        return "the out-of-balance force is not finite at iteration " + std::to_string(iteration);
      const double reference = std::max(norms.reference, 1e-300);
      report.relativeResidual = norms.free / reference;
      report.convergedOnDisplacement = false;
      if (norms.free <= options_.tolerance * reference) return "";
      if (iteration > 0 && lastCorrection <= options_.tolerance * largestTranslation(true) &&
          norms.free <= std::sqrt(options_.tolerance) * reference) {
        report.convergedOnDisplacement = true;
        return "";
      }
      if (iteration == 0) initialResidual = norms.free;
      if (iteration >= options_.maxIterations)
        return "no convergence in " + std::to_string(options_.maxIterations) + " iterations (relative residual " +
               detail::scientific(report.relativeResidual) + ", tolerance " + detail::scientific(options_.tolerance) +
               ")";
      if (iteration > 2 && norms.free > 1e4 * initialResidual)
        return "diverging (residual grew " + detail::scientific(norms.free / initialResidual) + " x)";
      // Solve only as accurately as the Newton target needs (10 % of it), within [1e-10, 1e-3].
      belos::CgOptions linear =
          linearOptions(std::clamp(0.1 * options_.tolerance * reference / norms.free, 1e-10, 1e-3));
      // A CG breakdown (an indefinite tangent away from equilibrium) cuts the increment.
      linear.fallbackOnBreakdown = false;
      // r is the right-hand side in place: the next iteration evaluates it afresh.
      const VectorView<Memory> rhs = flatOutOfBalance();
      const Matrix K = constrainedTangent(rhs, report);
      const VectorView<Memory> solution = flatCorrection();
      belos::CgResult result;
      std::string linearFailure;
      try {
        result = solveLinear(K, rhs, solution, linear, iteration == 0, report);
        if (!result.converged && !(result.achievedTolerance < 1e-2))
          linearFailure = "the linear solve did not converge (" + std::to_string(result.iterations) + " " +
                          result.method + " iterations, relative residual " +
                          detail::scientific(result.achievedTolerance) + ")";
      } catch (const std::runtime_error& error) {
        linearFailure = std::string("the linear solve failed: ") + error.what();
      }
      // At the undeformed state no smaller increment can help: the tangent itself is singular.
      if (!linearFailure.empty() && loadFactor_ == 0.0 && report.attempts == 1 && iteration == 0)
        throw NewtonFailure("the tangent stiffness of the undeformed model is singular: " + linearFailure +
                            "; check the supports: the model must not be free to move as a rigid body or a mechanism");
      if (!linearFailure.empty()) return linearFailure;
      ++report.newtonIterations;
      notifyIteration(target, report);
      start = Clock::now();
      // s(0) = du . r: > 0 where du descends the energy.
      const double slope = options_.lineSearch ? freeDot() : 0.0;
      if (options_.lineSearch) saveIterate();
      applyCorrection(1.0);
      report.seconds.update += fencedSecondsSince(space_, start);
      start = Clock::now();
      evaluated = computeOutOfBalance(target);
      double eta = 1.0;
      if (options_.lineSearch && slope > 0.0 && !(evaluated->free <= norms.free))
        eta = searchLine(target, slope, *evaluated, report);
      report.seconds.residual += fencedSecondsSince(space_, start);
      lastCorrection = eta * largestTranslation(false);
    }
  }

  // Regula falsi for s(eta) = du . r(u + eta du) = 0 between 0 (s(0) = slope > 0) and 1, where
  // s(1) < 0 (the full step overshoots) or r is not finite; at most 4 trial states, eta >= 1/16.
  // Leaves the state at the trial with the smallest |r| (the full step if none is smaller) and
  // `evaluated` at its residual; returns its eta.
  double searchLine(double target, double slope, ResidualNorms& evaluated, IncrementReport& report) {
    double high = 1.0, slopeHigh = std::isfinite(evaluated.free) ? freeDot() : std::nan("");
    if (slopeHigh >= 0.0) return 1.0;  // still descending at the full step: r grew elsewhere
    double low = 0.0, slopeLow = slope;
    double bestEta = 1.0, bestNorm = std::isfinite(evaluated.free) ? evaluated.free : HUGE_VAL, eta = 1.0;
    for (int trial = 0; trial < 4; ++trial) {
      eta = std::isfinite(slopeHigh) ? high - slopeHigh * (high - low) / (slopeHigh - slopeLow) : 0.5 * (low + high);
      eta = std::clamp(eta, low + 0.1 * (high - low), high - 0.1 * (high - low));
      eta = std::max(eta, 1.0 / 16.0);
      restoreIterate();
      applyCorrection(eta);
      evaluated = computeOutOfBalance(target);
      const double s = std::isfinite(evaluated.free) ? freeDot() : std::nan("");
      if (evaluated.free < bestNorm) {
        bestNorm = evaluated.free;
        bestEta = eta;
      }
      if (std::abs(s) <= 0.5 * slope) break;  // close enough to the minimum along du
      if (!(s >= 0.0)) {
        high = eta;
        slopeHigh = s;
      } else {
        low = eta;
        slopeLow = s;
      }
    }
    if (bestEta != eta) {
      restoreIterate();
      applyCorrection(bestEta);
      evaluated = computeOutOfBalance(target);
    }
    ++report.lineSearches;
    return bestEta;
  }

  // du . r over the free DOF (r: the out-of-balance force as last evaluated).
  double freeDot() const { return dofDot(correction_, outOfBalance_, false); }

  // Largest |translation| of the last correction du, or of the increment (u minus the state
  // saved at its start).
  double largestTranslation(bool ofIncrement) const {
    const auto du = correction_;
    const auto u = state_.displacements;
    const auto start = saved_.displacements;
    double largest = 0.0;
    Kokkos::parallel_reduce(
        "perishell::newton::largestTranslation", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, numNodes_),
        KOKKOS_LAMBDA(const LocalIndex node, double& value) {
          for (int d = 0; d < 3; ++d) {
            const double magnitude = Kokkos::Experimental::fabs(ofIncrement ? u(node, d) - start(node, d) : du(node, d));
            value = magnitude > value ? magnitude : value;
          }
        },
        Kokkos::Max<double>(largest));
    return largest;
  }

  // r = P(s) - F_int; returns |r| over free DOF and max(|P(s)|, |r| over prescribed DOF).
  ResidualNorms computeOutOfBalance(double loadFactor) {
    const auto factors = loadFactors(loadFactor);
    const auto patterns = actions_.loadPatterns;
    const auto r = outOfBalance_;
    const int numPatterns = actions_.numPatterns();
    double loadSquared = 0.0;
    Kokkos::parallel_reduce(
        "perishell::newton::loads", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, numNodes_),
        KOKKOS_LAMBDA(const LocalIndex node, double& sum) {
          for (int d = 0; d < 6; ++d) {
            double load = 0.0;
            for (int p = 0; p < numPatterns; ++p) load += factors.values[p] * patterns(node, 6 * p + d);
            r(node, d) = load;
            sum += load * load;
          }
        },
        loadSquared);
    if (pd_) {
      const pd::BondForceOutputs<Memory> outputs{r, VectorView<Memory>(), fractureScratch_, intactScratch_};
      // Node-gather, as the explicit step: in the app (libperishell, where the explicit driver
      // instantiates the same kernels) the bond-scatter launch from here jumped to address 0
      // on the H200 (cuda-gdb), while test binaries ran it; node-gather, no atomics, runs.
      pd::computeBondForces(space_, deck::ForceKernel::NodeGather, *pd_, state_, intact_, outputs);
    }
    if (shell_) shell::subtractShellForces(space_, *shell_, state_, r);
    return {outOfBalanceNorm(false), std::max(std::sqrt(loadSquared), outOfBalanceNorm(true))};
  }

  // 2-norm of the out-of-balance force over the prescribed DOF (reactions) or the free ones.
  double outOfBalanceNorm(bool overPrescribedDofs) const {
    return std::sqrt(dofDot(outOfBalance_, outOfBalance_, overPrescribedDofs));
  }

  // a . b over the prescribed DOF or the free ones, for nodal 6-vectors.
  double dofDot(const pd::NodalVectorView<Memory>& a, const pd::NodalVectorView<Memory>& b,
                bool overPrescribedDofs) const {
    const auto constrained = actions_.constrainedDofs;
    double dot = 0.0;
    Kokkos::parallel_reduce(
        "perishell::newton::dofDot", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, numNodes_),
        KOKKOS_LAMBDA(const LocalIndex node, double& sum) {
          for (int d = 0; d < 6; ++d)
            if (((constrained(node) >> d) & 1u) == (overPrescribedDofs ? 1u : 0u)) sum += a(node, d) * b(node, d);
        },
        dot);
    return dot;
  }

  // K du = rhs. The multigrid hierarchy of the last solve is reused unless this is an
  // attempt's first iteration or the last solve needed too many iterations
  // (NewtonOptions::amgReuseGrowth); a reused hierarchy that fails is rebuilt and the solve
  // repeated. Throws what the solve with a fresh preconditioner throws.
  belos::CgResult solveLinear(const Matrix& K, const VectorView<Memory>& rhs, const VectorView<Memory>& solution,
                              const belos::CgOptions& linear, bool attemptStart, IncrementReport& report) {
    if (usesFactor()) {
      try {
        return solveWithFactor(K, rhs, solution, linear, report);
      } catch (const direct::FactorizationError& error) {
        // A singular tangent stays singular under any preconditioner: that failure goes on.
        if (options_.preconditioner != deck::Preconditioner::Auto ||
            error.kind() != direct::FactorizationError::Kind::Resources)
          throw;
        report.notes.push_back(std::string("the Cholesky factorization failed (") + error.what() +
                               "); continuing with the AMG preconditioner");
        active_ = deck::Preconditioner::Amg;
        factor_.reset();
      }
    }
    if (active_ == deck::Preconditioner::Amg && !attemptStart && multigridReusable_) {
      try {
        const belos::CgResult result = solveOnce(K, rhs, solution, linear, false, report);
        if (result.converged) return result;
      } catch (const std::runtime_error&) {
        // A breakdown with the old hierarchy says nothing about the new tangent: rebuild.
      }
    }
    return solveOnce(K, rhs, solution, linear, true, report);
  }

  // K du = rhs from du = 0. rebuild: the block-Jacobi family is rebuilt from K; the multigrid
  // hierarchy is built once (its aggregates and product patterns depend only on the pattern)
  // and updated with K and the current node positions (its rigid-body modes). Without
  // rebuild the hierarchy is reused, with no more PCG iterations than the reuse allows.
  belos::CgResult solveOnce(const Matrix& K, const VectorView<Memory>& rhs, const VectorView<Memory>& solution,
                            const belos::CgOptions& linear, bool rebuild, IncrementReport& report) {
    using Clock = std::chrono::steady_clock;
    const bool amg = active_ == deck::Preconditioner::Amg;
    auto start = Clock::now();
    belos::CgOptions limited = linear;
    Teuchos::RCP<const Belos::Operator<double>> preconditioner;
    if (!amg) {
      preconditioner = belos::detail::makePreconditioner(K, linear);
    } else {
      if (!multigrid_ || rebuild) {
        ++report.preconditionerBuilds;
        updateCurrentPositions();
        if (multigrid_)
          multigrid_->update(K, currentPositions_);
        else
          multigrid_ =
              std::make_shared<multigrid::SmoothedAggregationPreconditioner<ExecutionSpaceT>>(space_, K, currentPositions_);
      } else {
        limited.maxIterations = std::min(linear.maxIterations, reuseIterationLimit());
      }
      preconditioner = Teuchos::rcp<const Belos::Operator<double>>(multigrid_.get(), false);
    }
    report.seconds.preconditioner += fencedSecondsSince(space_, start);
    Kokkos::deep_copy(space_, solution, 0.0);
    start = Clock::now();
    const belos::CgResult result = belos::solveCg<ExecutionSpaceT>(K, rhs, solution, limited, preconditioner);
    report.seconds.linearSolve += fencedSecondsSince(space_, start);
    report.linearIterations += result.iterations;
    if (amg) {
      if (rebuild) iterationsAfterRebuild_ = result.iterations;
      multigridReusable_ = options_.amgReuseGrowth > 0.0 && result.iterations <= reuseIterationLimit();
    }
    return result;
  }

  bool usesFactor() const {
    return active_ == deck::Preconditioner::Cholesky || active_ == deck::Preconditioner::Direct;
  }

  // K du = rhs preconditioned by a Cholesky factor of a recent tangent: reused while solves
  // stay within factorRefreshIterations (Direct: refactored for every solve), refreshed when
  // a solve needed more, or at once when the reused factor does not converge in 3x as many.
  belos::CgResult solveWithFactor(const Matrix& K, const VectorView<Memory>& rhs, const VectorView<Memory>& solution,
                                  const belos::CgOptions& linear, IncrementReport& report) {
    const int refresh = options_.factorRefreshIterations;
    if (factor_ && factorCurrent_ && active_ != deck::Preconditioner::Direct) {
      belos::CgOptions limited = linear;
      limited.maxIterations = std::min(linear.maxIterations, 3 * refresh);
      try {
        const belos::CgResult result = krylovWithFactor(K, rhs, solution, limited, report);
        if (result.converged) {
          factorCurrent_ = result.iterations <= refresh;
          return result;
        }
      } catch (const std::runtime_error&) {
        // A breakdown with an old factor says nothing about the new tangent: refactor.
      }
    }
    factorize(K, report);
    const belos::CgResult result = krylovWithFactor(K, rhs, solution, linear, report);
    factorCurrent_ = result.iterations <= refresh;
    return result;
  }

  // A fresh factor of K (counted, timed, its switch to or from L D L^T noted).
  direct::FactorizationInfo factorize(const Matrix& K, IncrementReport& report) {
    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    if (!factor_) factor_ = std::make_unique<direct::FactorizationPreconditioner<ExecutionSpaceT>>(K);
    factorCurrent_ = false;  // a failed factorization leaves none
    direct::FactorizationInfo info;
    try {
      info = factor_->factorize(K);
    } catch (const direct::FactorizationError& error) {
      if (error.kind() != direct::FactorizationError::Kind::Singular || error.row() < 0) throw;
      static const char* dofNames[6] = {"ux", "uy", "uz", "rx", "ry", "rz"};
      throw direct::FactorizationError(error.kind(),
                                       "the tangent is singular (a mechanism, or a DOF that nothing holds): a pivot vanished at "
                                       "DOF " + std::string(dofNames[error.row() % 6]) + " of mesh node " +
                                           std::to_string(error.row() / 6 + 1) + " (1-based, in mesh order)",
                                       error.row());
    }
    report.seconds.preconditioner += fencedSecondsSince(space_, start);
    ++report.factorizations;
    if (!info.positiveDefinite) report.passedUnstableState = true;
    if (!info.positiveDefinite && !indefiniteNoted_) {
      report.notes.push_back("a tangent was not positive definite (" + std::to_string(info.negativePivots) +
                             " negative pivots): L D L^T factor and GMRES wherever that recurs");
      indefiniteNoted_ = true;
    }
    factorPositiveDefinite_ = info.positiveDefinite;
    factorCurrent_ = true;
    return info;
  }

  belos::CgResult krylovWithFactor(const Matrix& K, const VectorView<Memory>& rhs, const VectorView<Memory>& solution,
                                   belos::CgOptions linear, IncrementReport& report) {
    // CG needs an SPD preconditioner: an indefinite L D L^T goes with GMRES.
    if (!factorPositiveDefinite_) linear.method = belos::CgOptions::Method::Gmres;
    Kokkos::deep_copy(space_, solution, 0.0);
    const auto start = std::chrono::steady_clock::now();
    const belos::CgResult result = belos::solveCg<ExecutionSpaceT>(
        K, rhs, solution, linear, Teuchos::rcp<const Belos::Operator<double>>(factor_.get(), false));
    report.seconds.linearSolve += fencedSecondsSince(space_, start);
    report.linearIterations += result.iterations;
    return result;
  }

  // Auto: AMG gives way to the factorization after an increment whose solves averaged more
  // than autoSwitchIterations Krylov iterations (thin curved shells, large rotations).
  void switchToCholeskyWhenAmgStruggles(IncrementReport& report) {
    if (options_.preconditioner != deck::Preconditioner::Auto || active_ != deck::Preconditioner::Amg) return;
    const double perSolve = double(report.linearIterations) / std::max(report.newtonIterations, 1);
    if (perSolve <= options_.autoSwitchIterations || freeDofs_ > options_.autoSwitchDofs) return;
    active_ = deck::Preconditioner::Cholesky;
    multigrid_.reset();
    report.notes.push_back("AMG needed " + std::to_string(int(perSolve)) +
                           " Krylov iterations per solve: switching to the Cholesky preconditioner");
  }

  long long countFreeDofs() const {
    const auto flags = isConstrained_;
    long long count = 0;
    Kokkos::parallel_reduce(
        "perishell::newton::countFreeDofs", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, flags.extent(0)),
        KOKKOS_LAMBDA(const std::size_t dof, long long& sum) { sum += flags(dof) ? 0 : 1; }, count);
    return count;
  }

  int reuseIterationLimit() const {
    return static_cast<int>(std::ceil(options_.amgReuseGrowth * std::max(iterationsAfterRebuild_, 1)));
  }

  void updateCurrentPositions() {
    if (currentPositions_.extent(0) != static_cast<std::size_t>(numNodes_))
      currentPositions_ = CoordinateView<Memory>("perishell::newton::currentPositions", numNodes_);
    const auto reference = shell_ ? shell_->referencePositions : pd_->referencePositions;
    const auto u = state_.displacements;
    const auto x = currentPositions_;
    Kokkos::parallel_for(
        "perishell::newton::currentPositions", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, numNodes_),
        KOKKOS_LAMBDA(const LocalIndex node) {
          for (int d = 0; d < 3; ++d) x(node, d) = reference(node, d) + u(node, d);
        });
  }

  void assembleTangent() {
    Kokkos::deep_copy(space_, values_, 0.0);
    if (shell_) shell::assembleShellTangent(space_, *shell_, state_, pattern_, values_, options_.tangent);
    if (pd_) pd::assembleBondTangent(space_, *pd_, state_, intact_, pattern_, values_, options_.tangent);
  }

  // Prescribed DOF take value x factor(s) (docs/deck.md: a support without a curve ramps
  // with s in an implicit run); a prescribed rotation component replaces that component
  // of the node's rotation vector.
  void applyPrescribedValues(double loadFactor) {
    CurveFactors factors = actions_.supportFactors(loadFactor);
    const auto constrained = actions_.constrainedDofs;
    const auto value = actions_.prescribedValue;
    const auto curve = actions_.supportCurveIndex;
    const auto u = state_.displacements;
    const auto q = state_.rotations;
    Kokkos::parallel_for(
        "perishell::newton::applyPrescribedValues", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, numNodes_),
        KOKKOS_LAMBDA(const LocalIndex node) {
          const unsigned mask = constrained(node);
          if (mask == 0) return;
          auto target = [&](int d) { return value(node, d) * (curve(node, d) < 0 ? loadFactor : factors.values[curve(node, d)]); };
          for (int d = 0; d < 3; ++d)
            if (mask & (1u << d)) u(node, d) = target(d);
          if ((mask >> 3) == 0) return;
          const double quaternion[4] = {q(node, 0), q(node, 1), q(node, 2), q(node, 3)};
          double R[3][3], theta[3], updated[4];
          rotation::toMatrix(quaternion, R);
          rotation::logarithm(R, theta);
          for (int d = 0; d < 3; ++d)
            if (mask & (1u << (3 + d))) theta[d] = target(3 + d);
          rotation::exponential(theta, updated);
          for (int k = 0; k < 4; ++k) q(node, k) = updated[k];
        });
  }

  // u += eta du; R <- exp(eta dphi) R.
  void applyCorrection(double eta) {
    const auto du = correction_;
    const auto u = state_.displacements;
    const auto q = state_.rotations;
    Kokkos::parallel_for(
        "perishell::newton::applyCorrection", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, numNodes_),
        KOKKOS_LAMBDA(const LocalIndex node) {
          for (int d = 0; d < 3; ++d) u(node, d) += eta * du(node, d);
          const double phi[3] = {eta * du(node, 3), eta * du(node, 4), eta * du(node, 5)};
          double quaternion[4] = {q(node, 0), q(node, 1), q(node, 2), q(node, 3)};
          rotation::rotateBySpatialIncrement(phi, quaternion);
          for (int k = 0; k < 4; ++k) q(node, k) = quaternion[k];
        });
  }

  // The load at factor 1 (every pattern, no curves) with the constrained rows zeroed, and the
  // work vectors of the arc-length method.
  void makeArcLengthVectors() {
    referenceLoad_ = pd::NodalVectorView<Memory>("perishell::newton::referenceLoad", numNodes_);
    tangentDirection_ = pd::NodalVectorView<Memory>("perishell::newton::tangentDirection", numNodes_);
    lastArcDirection_ = CoordinateView<Memory>("perishell::newton::lastArcDirection", numNodes_);
    const auto patterns = actions_.loadPatterns;
    const auto constrained = actions_.constrainedDofs;
    const auto load = referenceLoad_;
    const int numPatterns = actions_.numPatterns();
    Kokkos::parallel_for(
        "perishell::newton::referenceLoad", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, numNodes_),
        KOKKOS_LAMBDA(const LocalIndex node) {
          for (int d = 0; d < 6; ++d) {
            double sum = 0.0;
            for (int p = 0; p < numPatterns; ++p) sum += patterns(node, 6 * p + d);
            load(node, d) = (constrained(node) >> d) & 1u ? 0.0 : sum;
          }
        });
  }

  // Sums over the nodes of a . b for translations, with a, b chosen by index: 0 the corrector
  // dr (correction_), 1 the tangent direction dt, 2 the increment delta u = u - u_start, 3 the
  // last converged increment's direction.
  double translationDot(int first, int second) const {
    const auto dr = correction_;
    const auto dt = tangentDirection_;
    const auto u = state_.displacements;
    const auto start = saved_.displacements;
    const auto last = lastArcDirection_;
    double dot = 0.0;
    Kokkos::parallel_reduce(
        "perishell::newton::translationDot", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, numNodes_),
        KOKKOS_LAMBDA(const LocalIndex node, double& sum) {
          auto pick = [&](int which, int d) {
            return which == 0 ? dr(node, d) : which == 1 ? dt(node, d) : which == 2 ? u(node, d) - start(node, d) : last(node, d);
          };
          for (int d = 0; d < 3; ++d) sum += pick(first, d) * pick(second, d);
        },
        dot);
    return dot;
  }

  void recordArcDirection() {
    const auto u = state_.displacements;
    const auto start = saved_.displacements;
    const auto last = lastArcDirection_;
    Kokkos::parallel_for(
        "perishell::newton::recordArcDirection", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, numNodes_),
        KOKKOS_LAMBDA(const LocalIndex node) {
          for (int d = 0; d < 3; ++d) last(node, d) = u(node, d) - start(node, d);
        });
    hasArcDirection_ = true;
  }

  // correction_ = dr + ds dt (all six DOF).
  void combineCorrection(double ds) {
    const auto dr = correction_;
    const auto dt = tangentDirection_;
    Kokkos::parallel_for(
        "perishell::newton::combineCorrection", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, numNodes_),
        KOKKOS_LAMBDA(const LocalIndex node) {
          for (int d = 0; d < 6; ++d) dr(node, d) += ds * dt(node, d);
        });
  }

  // Solves K x = rhs (rhs with its constrained rows zero, consumed); x is `into`
  // (correction_ or tangentDirection_). Returns why it failed, or empty.
  std::string solveTangent(const Matrix& K, const pd::NodalVectorView<Memory>& rhs,
                           const pd::NodalVectorView<Memory>& into, double tolerance, bool attemptStart,
                           IncrementReport& report) {
    const VectorView<Memory> flatRhs(rhs.data(), 6 * std::size_t(numNodes_));
    belos::CgOptions linear = linearOptions(tolerance);
    linear.fallbackOnBreakdown = true;  // past a limit point the tangent is indefinite
    try {
      const belos::CgResult result =
          solveLinear(K, flatRhs, VectorView<Memory>(into.data(), flatRhs.extent(0)), linear, attemptStart, report);
      if (!result.converged && !(result.achievedTolerance < 1e-2))
        return "the linear solve did not converge (" + std::to_string(result.iterations) + " " + result.method +
               " iterations)";
    } catch (const std::runtime_error& error) {
      return std::string("the linear solve failed: ") + error.what();
    }
    return "";
  }

  std::string arcLengthIterate(IncrementReport& report) {
    // Predictor: dt = K^-1 P_ref at the converged state.
    Kokkos::deep_copy(space_, outOfBalance_, referenceLoad_);
    std::string failure =
        solveTangent(constrainedTangent(flatOutOfBalance(), report), outOfBalance_, tangentDirection_, 1e-8,
                     true, report);
    if (!failure.empty()) return failure;
    const double tangentNorm = std::sqrt(translationDot(1, 1));
    if (!(tangentNorm > 0.0)) return "the reference load moves no translation (is any load applied?)";
    if (arcLength_ <= 0.0) {
      arcLength_ = options_.arcLengthFirstStep * tangentNorm;
      maxArcLength_ = options_.maxArcLengthGrowth * arcLength_;
    }
    double direction = hasArcDirection_ && translationDot(1, 3) < 0.0 ? -1.0 : 1.0;
    double ds = direction * arcLength_ / tangentNorm;
    Kokkos::deep_copy(space_, correction_, tangentDirection_);
    applyCorrection(ds);
    loadFactor_ += ds;
    double initialResidual = 0.0;
    for (int iteration = 0;; ++iteration) {
      const auto norms = computeOutOfBalance(loadFactor_);
      if (!std::isfinite(norms.free)) return "the out-of-balance force is not finite at iteration " + std::to_string(iteration);
      const double reference = std::max(norms.reference, 1e-300);
      report.relativeResidual = norms.free / reference;
      if (iteration > 0 && norms.free <= options_.tolerance * reference) return "";
      if (iteration == 0) initialResidual = norms.free;
      if (iteration >= options_.maxIterations)
        return "no convergence in " + std::to_string(options_.maxIterations) + " iterations (relative residual " +
               detail::scientific(report.relativeResidual) + ")";
      if (iteration > 2 && norms.free > 1e4 * initialResidual) return "diverging";
      // Corrector: K dr = r and K dt = P_ref with the same tangent.
      const double tolerance = std::clamp(0.1 * options_.tolerance * reference / std::max(norms.free, 1e-300), 1e-10, 1e-3);
      const Matrix K = constrainedTangent(flatOutOfBalance(), report);
      failure = solveTangent(K, outOfBalance_, correction_, tolerance, false, report);
      if (!failure.empty()) return failure;
      Kokkos::deep_copy(space_, outOfBalance_, referenceLoad_);  // constrained rows zero already
      failure = solveTangent(K, outOfBalance_, tangentDirection_, 1e-8, false, report);
      if (!failure.empty()) return failure;
      // |delta u + dr + ds dt|^2 = l^2: a ds^2 + b ds + c = 0.
      const double tt = translationDot(1, 1), rt = translationDot(0, 1), ut = translationDot(2, 1);
      const double rr = translationDot(0, 0), ur = translationDot(2, 0), uu = translationDot(2, 2);
      const double a = tt, b = 2.0 * (ut + rt), c = uu + 2.0 * ur + rr - arcLength_ * arcLength_;
      const double discriminant = b * b - 4.0 * a * c;
      if (!(discriminant >= 0.0)) return "the arc-length constraint has no real root (the arc is too long here)";
      const double root = std::sqrt(discriminant);
      const double roots[2] = {(-b + root) / (2.0 * a), (-b - root) / (2.0 * a)};
      // The root whose new increment (delta u + dr + ds dt) lies closer to the current delta u.
      auto alignment = [&](double candidate) { return uu + ur + candidate * ut; };
      ds = alignment(roots[0]) >= alignment(roots[1]) ? roots[0] : roots[1];
      combineCorrection(ds);
      applyCorrection(1.0);
      loadFactor_ += ds;
      ++report.newtonIterations;
      notifyIteration(loadFactor_, report);
    }
  }

  void markConstrainedDofs() {
    const auto constrained = actions_.constrainedDofs;
    const auto flags = isConstrained_;
    Kokkos::parallel_for(
        "perishell::newton::markConstrainedDofs", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, numNodes_),
        KOKKOS_LAMBDA(const LocalIndex node) {
          for (int d = 0; d < 6; ++d) flags(6 * std::size_t(node) + d) = (constrained(node) & (1u << d)) != 0;
        });
  }

 private:
  void notifyIteration(double target, const IncrementReport& report) const {
    if (observer_) observer_(target, report);
  }

  CurveFactors loadFactors(double s) const {
    CurveFactors factors;
    for (int p = 0; p < actions_.numPatterns(); ++p)
      factors.values[p] = actions_.patternCurves[p] ? deck::evaluateCurve(*actions_.patternCurves[p], s) : s;
    return factors;
  }

  // Node-major 6-DOF views seen as one vector of 6 N entries (LayoutRight: the same memory).
  VectorView<Memory> flatOutOfBalance() const { return VectorView<Memory>(outOfBalance_.data(), 6 * std::size_t(numNodes_)); }
  VectorView<Memory> flatCorrection() const { return VectorView<Memory>(correction_.data(), 6 * std::size_t(numNodes_)); }
  Kokkos::View<const double*, Memory> zerosConst() const { return zeros_; }

  void copyKinematics(const pd::PdKinematics<Memory>& to, const pd::PdKinematics<Memory>& from) const {
    Kokkos::deep_copy(space_, to.displacements, from.displacements);
    Kokkos::deep_copy(space_, to.rotations, from.rotations);
  }
  void saveState() { copyKinematics(saved_, state_); }
  void restoreState() { copyKinematics(state_, saved_); }
  // The state before a Newton update, for the line search's trial states.
  void saveIterate() { copyKinematics(iterateStart_, state_); }
  void restoreIterate() { copyKinematics(state_, iterateStart_); }

  ExecutionSpaceT space_;
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
  assembly::NodalBlockPattern<Memory> pattern_;
  VectorView<Memory> values_;
  CoordinateView<Memory> currentPositions_;
  std::shared_ptr<multigrid::SmoothedAggregationPreconditioner<ExecutionSpaceT>> multigrid_;
  deck::Preconditioner active_ = deck::Preconditioner::BlockJacobi;
  long long freeDofs_ = 0;
  std::unique_ptr<direct::FactorizationPreconditioner<ExecutionSpaceT>> factor_;
  bool factorCurrent_ = false;  // the factor is fresh enough to be reused
  bool factorPositiveDefinite_ = true;
  bool indefiniteNoted_ = false;  // the switch to L D L^T is noted once per run
  bool multigridReusable_ = false;
  int iterationsAfterRebuild_ = 0;
  double loadFactor_ = 0.0;
  double preferredStep_ = 0.0;  // the next sub-step's size (advanceTo), 0 before the first
  // Arc-length control: the load at factor 1, the tangent direction dt, the last increment's
  // translations, and the arc length (0 before the first increment).
  pd::NodalVectorView<Memory> referenceLoad_, tangentDirection_;
  CoordinateView<Memory> lastArcDirection_;
  bool hasArcDirection_ = false;
  double arcLength_ = 0.0, maxArcLength_ = 0.0;
};

}  // namespace perishell::solvers
