#pragma once
// Geometrically nonlinear statics (paper eq. 34-43, model.md §6): Newton-Raphson under load
// control. Per iteration the out-of-balance force r = P(s) - F_int(u) and the tangent K_T
// are assembled on the device from the shell elements and the PD bonds (atomic_add into a
// 6x6-block CRS matrix), supports are eliminated symmetrically, K_T du = r is solved by
// Belos PCG (block-Jacobi or smoothed-aggregation multigrid preconditioner; the multigrid
// hierarchy is built at the first solve and updated, not rebuilt, at every later one),
// translations are added and rotations composed, R <- exp(dphi) R (model.md §5).
// An increment that does not converge is restored and bisected, a bounded number of times.
// The state lives on the device; callers copy it to the host only for output.
#include <perishell/assembly/dirichlet.hpp>
#include <perishell/core/fenced_seconds.hpp>
#include <perishell/assembly/nodal_block_crs.hpp>
#include <perishell/pd/bond_tangent.hpp>
#include <perishell/shell/shell_body.hpp>
#include <perishell/solvers/belos/cg_solve.hpp>
#include <perishell/solvers/explicit/external_actions.hpp>
#include <perishell/solvers/multigrid/smoothed_aggregation.hpp>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>

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
  int maxCuts = 8;  // bisections in a row before giving up
  belos::CgOptions::Preconditioner preconditioner = belos::CgOptions::Preconditioner::BlockJacobi;
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
  }

  // Moves the load factor from its current value to loadFactor (>= current), cutting the
  // step in halves when Newton fails and doubling it again after each success. Throws
  // NewtonFailure when maxCuts cuts in a row do not get past one load level.
  IncrementReport advanceTo(double loadFactor) {
    IncrementReport report;
    double step = loadFactor - loadFactor_;
    const double fullStep = step;
    std::string lastReason;
    int consecutiveCuts = 0;
    while (loadFactor_ < loadFactor) {
      const double target = loadFactor_ + step >= loadFactor - 1e-12 * fullStep ? loadFactor : loadFactor_ + step;
      ++report.attempts;
      saveState();
      const auto attempt = iterate(target, report);
      if (attempt.empty()) {
        loadFactor_ = target;
        step = std::min(fullStep, 2.0 * step);
        consecutiveCuts = 0;
        continue;
      }
      restoreState();
      lastReason = attempt;
      ++report.cuts;
      if (++consecutiveCuts > options_.maxCuts) {
        throw NewtonFailure("Newton did not converge towards load factor " + std::to_string(loadFactor) +
                            " after " + std::to_string(options_.maxCuts) + " cuts of the increment (last try: " +
                            std::to_string(target) + "): " + lastReason);
      }
      step *= 0.5;
    }
    report.loadFactor = loadFactor_;
    return report;
  }

  double loadFactor() const { return loadFactor_; }
  const pd::PdKinematics<Memory>& kinematics() const { return state_; }
  // P - F_int at the last evaluation (the converged state after advanceTo): zero to the
  // tolerance at free DOF, minus the support reaction at prescribed DOF.
  const pd::NodalVectorView<Memory>& outOfBalance() const { return outOfBalance_; }
  LocalIndex numBonds() const { return pd_ ? static_cast<LocalIndex>(pd_->bonds.numBonds()) : 0; }
  LocalIndex numElements() const { return shell_ ? shell_->numElements() : 0; }
  RowOffset numMatrixEntries() const { return pattern_.columns.extent(0); }

  // ---- public for nvcc (extended lambdas need public enclosing functions) ----

  // One Newton solve at load factor target; returns the empty string when it converged,
  // else why not.
  std::string iterate(double target, IncrementReport& report) {
    applyPrescribedValues(target);
    double initialResidual = 0.0, lastCorrection = 0.0;
    using Clock = std::chrono::steady_clock;
    for (int iteration = 0;; ++iteration) {
      auto start = Clock::now();
      const auto norms = computeOutOfBalance(target);
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
      start = Clock::now();
      assembleTangent();
      report.seconds.assembly += fencedSecondsSince(space_, start);
      belos::CgOptions linear;
      linear.method = options_.tangent == TangentForm::Exact ? belos::CgOptions::Method::Gmres : belos::CgOptions::Method::Cg;
      linear.preconditioner = options_.preconditioner;
      linear.maxIterations = options_.maxLinearIterations;
      // A CG breakdown (an indefinite tangent away from equilibrium) cuts the increment.
      linear.fallbackOnBreakdown = false;
      // Solve only as accurately as the Newton target needs (10 % of it), within [1e-10, 1e-3].
      linear.tolerance = std::clamp(0.1 * options_.tolerance * reference / norms.free, 1e-10, 1e-3);
      // r is the right-hand side in place: the next iteration evaluates it afresh.
      const VectorView<Memory> rhs = flatOutOfBalance();
      start = Clock::now();
      assembly::eliminateDirichlet(space_, pattern_.rowMap, pattern_.columns, values_, rhs, isConstrained_, zerosConst());
      report.seconds.constraints += fencedSecondsSince(space_, start);
      const auto numRows = static_cast<LocalIndex>(rhs.extent(0));
      const Matrix K("perishell::newton::tangent", numRows, numRows, static_cast<RowOffset>(values_.extent(0)), values_,
                     pattern_.rowMap, pattern_.columns);
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
      start = Clock::now();
      applyCorrection();
      lastCorrection = largestTranslation(false);
      report.seconds.update += fencedSecondsSince(space_, start);
    }
  }

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

  struct ResidualNorms {
    double free = 0.0, reference = 0.0;
  };

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
      pd::computeBondForces(space_, deck::ForceKernel::BondScatter, *pd_, state_, intact_, outputs);
    }
    if (shell_) shell::subtractShellForces(space_, *shell_, state_, r);
    return {outOfBalanceNorm(false), std::max(std::sqrt(loadSquared), outOfBalanceNorm(true))};
  }

  // 2-norm of the out-of-balance force over the prescribed DOF (reactions) or the free ones.
  double outOfBalanceNorm(bool overPrescribedDofs) const {
    const auto constrained = actions_.constrainedDofs;
    const auto r = outOfBalance_;
    double squared = 0.0;
    Kokkos::parallel_reduce(
        "perishell::newton::residualNorm", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, numNodes_),
        KOKKOS_LAMBDA(const LocalIndex node, double& sum) {
          for (int d = 0; d < 6; ++d)
            if (((constrained(node) >> d) & 1u) == (overPrescribedDofs ? 1u : 0u)) sum += r(node, d) * r(node, d);
        },
        squared);
    return std::sqrt(squared);
  }

  // K du = rhs. The multigrid hierarchy of the last solve is reused unless this is an
  // attempt's first iteration or the last solve needed too many iterations
  // (NewtonOptions::amgReuseGrowth); a reused hierarchy that fails is rebuilt and the solve
  // repeated. Throws what the solve with a fresh preconditioner throws.
  belos::CgResult solveLinear(const Matrix& K, const VectorView<Memory>& rhs, const VectorView<Memory>& solution,
                              const belos::CgOptions& linear, bool attemptStart, IncrementReport& report) {
    if (options_.preconditioner == belos::CgOptions::Preconditioner::Amg && !attemptStart && multigridReusable_) {
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
    const bool amg = options_.preconditioner == belos::CgOptions::Preconditioner::Amg;
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

  // u += du; R <- exp(dphi) R.
  void applyCorrection() {
    const auto du = correction_;
    const auto u = state_.displacements;
    const auto q = state_.rotations;
    Kokkos::parallel_for(
        "perishell::newton::applyCorrection", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, numNodes_),
        KOKKOS_LAMBDA(const LocalIndex node) {
          for (int d = 0; d < 3; ++d) u(node, d) += du(node, d);
          const double phi[3] = {du(node, 3), du(node, 4), du(node, 5)};
          double quaternion[4] = {q(node, 0), q(node, 1), q(node, 2), q(node, 3)};
          rotation::rotateBySpatialIncrement(phi, quaternion);
          for (int k = 0; k < 4; ++k) q(node, k) = quaternion[k];
        });
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

  void saveState() {
    Kokkos::deep_copy(space_, saved_.displacements, state_.displacements);
    Kokkos::deep_copy(space_, saved_.rotations, state_.rotations);
  }
  void restoreState() {
    Kokkos::deep_copy(space_, state_.displacements, saved_.displacements);
    Kokkos::deep_copy(space_, state_.rotations, saved_.rotations);
  }

  ExecutionSpaceT space_;
  LocalIndex numNodes_;
  std::optional<shell::ShellBody<Memory>> shell_;
  std::optional<pd::PdBody<Memory>> pd_;
  ExternalActions<Memory> actions_;
  NewtonOptions options_;
  pd::PdKinematics<Memory> state_, saved_;
  pd::NodalVectorView<Memory> outOfBalance_, correction_;
  Kokkos::View<bool*, Memory> isConstrained_;
  VectorView<Memory> zeros_;
  pd::BondFlagView<Memory> intact_, intactScratch_;
  VectorView<Memory> fractureScratch_;
  assembly::NodalBlockPattern<Memory> pattern_;
  VectorView<Memory> values_;
  CoordinateView<Memory> currentPositions_;
  std::shared_ptr<multigrid::SmoothedAggregationPreconditioner<ExecutionSpaceT>> multigrid_;
  bool multigridReusable_ = false;
  int iterationsAfterRebuild_ = 0;
  double loadFactor_ = 0.0;
};

}  // namespace perishell::solvers
