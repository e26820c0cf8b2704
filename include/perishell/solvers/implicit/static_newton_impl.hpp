#pragma once
// The member functions of StaticNewtonSolver (static_newton.hpp). They instantiate Belos, the
// smoothed-aggregation multigrid and the factorization, minutes of compile time each: so
// they are compiled once per execution space, in src/solvers/static_newton_<space>.cpp,
// and a file that uses the solver includes static_newton.hpp only.
#include <perishell/solvers/implicit/static_newton.hpp>

#include <exception>

namespace perishell::solvers {

namespace detail {

// The diagonal of the nodes' bounding box [m], over every rank (a free function: CUDA allows
// no device lambda in a constructor).
template <class ExecutionSpaceT, class MemorySpaceT>
double boundingBoxDiagonal(const ExecutionSpaceT& space, const CoordinateView<MemorySpaceT>& positions,
                           const parallel::Communicator& communicator) {
  double low[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, high[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (int d = 0; d < 3; ++d)
    Kokkos::parallel_reduce(
        "perishell::newton::modelExtent", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, positions.extent(0)),
        KOKKOS_LAMBDA(const LocalIndex node, double& lowest, double& highest) {
          lowest = positions(node, d) < lowest ? positions(node, d) : lowest;
          highest = positions(node, d) > highest ? positions(node, d) : highest;
        },
        Kokkos::Min<double>(low[d]), Kokkos::Max<double>(high[d]));
  communicator.min(low, 3);
  communicator.max(high, 3);
  if (!(low[0] <= high[0])) return 0.0;
  return std::hypot(high[0] - low[0], high[1] - low[1], high[2] - low[2]);
}

// 1 for every DOF of a node this rank owns.
template <class ExecutionSpaceT, class MemorySpaceT>
Kokkos::View<std::uint8_t*, MemorySpaceT> ownedDofs(const ExecutionSpaceT& space,
                                                    const Kokkos::View<std::uint8_t*, MemorySpaceT>& ownedNodes) {
  Kokkos::View<std::uint8_t*, MemorySpaceT> dofs("perishell::newton::ownedDofs", 6 * ownedNodes.extent(0));
  Kokkos::parallel_for(
      "perishell::newton::ownedDofs", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, dofs.extent(0)),
      KOKKOS_LAMBDA(const std::size_t dof) { dofs(dof) = ownedNodes(dof / 6); });
  return dofs;
}

// The code of a failure for every rank to agree on (StaticNewtonSolver::onEveryRank): 0 none,
// 1-3 a factorization's kind, 4 any other error.
inline int failureCode(const std::exception_ptr& failure) {
  if (!failure) return 0;
  try {
    std::rethrow_exception(failure);
  } catch (const direct::FactorizationError& error) {
    return 1 + static_cast<int>(error.kind());
  } catch (...) {
    return 4;
  }
}

}  // namespace detail

template <class ExecutionSpaceT>
StaticNewtonSolver<ExecutionSpaceT>::StaticNewtonSolver(const ExecutionSpaceT& space, LocalIndex numNodes,
                                                        std::optional<shell::ShellBody<Memory>> shellBody,
                                                        std::optional<pd::PdBody<Memory>> pdBody,
                                                        ExternalActions<Memory> actions, const NewtonOptions& options,
                                                        parallel::NodeDistribution<Memory> distribution)
    : space_(space),
      distribution_(std::move(distribution)),
      ownedNodes_("perishell::newton::ownedNodes", numNodes),
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
    bondNodes = bondEndNodes(space_, pd_->bonds, actions_.mirrorImages);
  }
  pattern_ = assembly::buildNodalBlockPattern(space_, numNodes, quads, bondNodes,
                                              actions_.mirrorImages.empty() ? assembly::SelfBonds::Refused
                                                                            : assembly::SelfBonds::Allowed);
  values_ = VectorView<Memory>("perishell::newton::tangentValues", pattern_.columns.extent(0));
  nodeRegions_ = nodeRegions(space_, numNodes, quads, bondNodes);
  if (distribution_.distributed()) {
    Kokkos::deep_copy(space_, ownedNodes_, distribution_.owned());
    auto rows = std::make_shared<belos::DistributedRows<Memory>>();
    rows->owned = detail::ownedDofs(space_, ownedNodes_);
    rows->communicator = communicator();
    rows->globalRows = 6 * distribution_.meshNodes(numNodes);
    // Its own copy of the exchange: the solver may move, the operator's halo filling stays.
    const auto halo = std::make_shared<parallel::NodeDistribution<Memory>>(distribution_);
    rows->fillHalo = [halo, space](const VectorView<Memory>& vector) {
      halo->exchange(space, pd::NodalVectorView<Memory>(vector.data(), vector.extent(0) / 6));
    };
    rows_ = rows;
  } else {
    Kokkos::deep_copy(space_, ownedNodes_, 1);
  }
  markConstrainedDofs();
  freeDofs_ = countFreeDofs();
  modelSize_ = detail::boundingBoxDiagonal(space_,
                                           shell_ ? shell_->referencePositions
                                           : pd_  ? pd_->referencePositions
                                                  : CoordinateView<Memory>("no nodes", 0),
                                           communicator());
  active_ = options_.preconditioner;
  if (active_ == deck::Preconditioner::Auto)
    active_ = freeDofs_ <= options_.autoCholeskyDofs ? deck::Preconditioner::Cholesky : deck::Preconditioner::Amg;
}

template <class ExecutionSpaceT>
IncrementReport StaticNewtonSolver<ExecutionSpaceT>::advanceTo(double loadFactor) {
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

template <class ExecutionSpaceT>
void StaticNewtonSolver<ExecutionSpaceT>::saveTo(io::Checkpoint& checkpoint, const parallel::NodeGather& gather) const {
  parallel::putNodalView(checkpoint, "implicit.displacements", state_.displacements, gather);
  parallel::putNodalView(checkpoint, "implicit.rotations", state_.rotations, gather);
  checkpoint.putReals("implicit.factors", {loadFactor_, prescribedFactor_, preferredStep_, arcLength_, maxArcLength_});
  checkpoint.putIntegers("implicit.flags", {static_cast<long long>(active_), factor_ && factorCurrent_ ? 1 : 0,
                                            indefiniteNoted_ ? 1 : 0, hasArcDirection_ ? 1 : 0});
  if (hasArcDirection_) parallel::putNodalView(checkpoint, "implicit.arc-direction", lastArcDirection_, gather);
}

template <class ExecutionSpaceT>
void StaticNewtonSolver<ExecutionSpaceT>::restoreFrom(const io::Checkpoint& checkpoint,
                                                    const parallel::NodeGather& gather) {
  const std::string mismatch =
      "the deck's model is not the one the checkpoint's run solved (another mesh, zones or horizon)";
  parallel::takeNodalView(checkpoint, "implicit.displacements", state_.displacements, gather, mismatch);
  parallel::takeNodalView(checkpoint, "implicit.rotations", state_.rotations, gather, mismatch);
  ++stateVersion_;
  const auto& factors = checkpoint.reals("implicit.factors");
  const auto& flags = checkpoint.integers("implicit.flags");
  if (factors.size() != 5 || flags.size() != 4)
    throw io::CheckpointError(checkpoint.context() + "'implicit.factors' or 'implicit.flags' is not of this version");
  loadFactor_ = factors[0];
  prescribedFactor_ = factors[1];
  preferredStep_ = factors[2];
  arcLength_ = factors[3];
  maxArcLength_ = factors[4];
  // Auto may have switched during the run; a preconditioner the deck names stays the deck's.
  if (options_.preconditioner == deck::Preconditioner::Auto)
    active_ = flags[0] == static_cast<long long>(deck::Preconditioner::Cholesky) ? deck::Preconditioner::Cholesky
                                                                                  : deck::Preconditioner::Amg;
  indefiniteNoted_ = flags[2] != 0;
  hasArcDirection_ = flags[3] != 0;
  if (hasArcDirection_) {
    makeArcLengthVectors();
    parallel::takeNodalView(checkpoint, "implicit.arc-direction", lastArcDirection_, gather, mismatch);
  }
  if (flags[1] != 0 && usesFactor()) {
    IncrementReport scratch;
    factorConvergedTangent(scratch);
  }
}

template <class ExecutionSpaceT>
auto StaticNewtonSolver<ExecutionSpaceT>::constrainedTangent(const VectorView<Memory>& rhs, IncrementReport& report)
    -> Matrix {
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

template <class ExecutionSpaceT>
belos::CgOptions StaticNewtonSolver<ExecutionSpaceT>::linearOptions(double tolerance) const {
  belos::CgOptions linear;
  linear.method =
      options_.tangent == TangentForm::Exact ? belos::CgOptions::Method::Gmres : belos::CgOptions::Method::Cg;
  linear.preconditioner = active_ == deck::Preconditioner::Jacobi ? belos::CgOptions::Preconditioner::Jacobi
                                                                  : belos::CgOptions::Preconditioner::BlockJacobi;
  linear.maxIterations = options_.maxLinearIterations;
  linear.tolerance = tolerance;
  return linear;
}

template <class ExecutionSpaceT>
void StaticNewtonSolver<ExecutionSpaceT>::factorConvergedTangent(IncrementReport& report) {
  mixedForcesCurrent_ = false;  // the converged state's own tangent
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

template <class ExecutionSpaceT>
std::string StaticNewtonSolver<ExecutionSpaceT>::arcLengthObstacle() const {
  for (std::size_t p = 0; p < actions_.patternCurves.size(); ++p)
    if (actions_.patternCurves[p]) return "a load follows a curve";
  const auto values = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, actions_.prescribedValue);
  bool prescribesMotion = false;
  for (std::size_t node = 0; node < values.extent(0); ++node)
    for (int d = 0; d < 6; ++d) prescribesMotion = prescribesMotion || values(node, d) != 0.0;
  return communicator().any(prescribesMotion) ? "a support prescribes a nonzero displacement or rotation" : "";
}

template <class ExecutionSpaceT>
IncrementReport StaticNewtonSolver<ExecutionSpaceT>::advanceByArcLength(double stopAt) {
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

template <class ExecutionSpaceT>
std::string StaticNewtonSolver<ExecutionSpaceT>::iterate(double target, IncrementReport& report) {
  applyPrescribedValues(target);
  double initialResidual = 0.0, lastCorrection = 0.0, floor = 0.0;
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
    report.convergedAtRoundOff = false;
    if (norms.free <= options_.tolerance * reference) return "";
    if (iteration > 0) {
      const double moved = largestTranslation(true);
      if (lastCorrection <= options_.tolerance * moved && norms.free <= std::sqrt(options_.tolerance) * reference) {
        report.convergedOnDisplacement = true;
        return "";
      }
      if (lastCorrection <= std::sqrt(options_.tolerance) * moved && norms.free <= floor) {
        report.convergedAtRoundOff = true;
        return "";
      }
    }
    if (iteration == 0) initialResidual = norms.free;
    if (iteration >= options_.maxIterations)
      return "no convergence in " + std::to_string(options_.maxIterations) + " iterations (relative residual " +
             detail::scientific(report.relativeResidual) + ", tolerance " + detail::scientific(options_.tolerance) +
             ")";
    if (iteration > 2 && norms.free > 1e4 * initialResidual)
      return "diverging (residual grew " + detail::scientific(norms.free / initialResidual) + " x)";
    // Solve only as accurately as the Newton target needs (10 % of it), within [1e-10, 1e-3].
    belos::CgOptions linear = linearOptions(std::clamp(0.1 * options_.tolerance * reference / norms.free, 1e-10, 1e-3));
    // A CG breakdown (an indefinite tangent away from equilibrium) cuts the increment.
    linear.fallbackOnBreakdown = false;
    // r is the right-hand side in place: the next iteration evaluates it afresh.
    const VectorView<Memory> rhs = flatOutOfBalance();
    const Matrix K = constrainedTangent(rhs, report);
    floor = roundOffFloor(K);
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

template <class ExecutionSpaceT>
double StaticNewtonSolver<ExecutionSpaceT>::searchLine(double target, double slope, ResidualNorms& evaluated,
                                                       IncrementReport& report) {
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

template <class ExecutionSpaceT>
double StaticNewtonSolver<ExecutionSpaceT>::roundOffFloor(const Matrix& K) const {
  const auto rowMap = K.graph.row_map;
  const auto columns = K.graph.entries;
  const auto values = K.values;
  const double size = modelSize_;
  const auto owned = ownedNodes_;
  double sumOfSquares = 0.0;
  Kokkos::parallel_reduce(
      "perishell::newton::roundOffFloor", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, K.numRows()),
      KOKKOS_LAMBDA(const LocalIndex row, double& sum) {
        if (!owned(row / 6)) return;
        double magnitude = 0.0;
        for (auto entry = rowMap(row); entry < rowMap(row + 1); ++entry)
          magnitude += Kokkos::Experimental::fabs(values(entry)) * (columns(entry) % 6 < 3 ? size : 1.0);
        sum += magnitude * magnitude;
      },
      sumOfSquares);
  return std::numeric_limits<double>::epsilon() * std::sqrt(communicator().sum(sumOfSquares));
}

template <class ExecutionSpaceT>
double StaticNewtonSolver<ExecutionSpaceT>::largestTranslation(bool ofIncrement) const {
  const auto du = correction_;
  const auto u = state_.displacements;
  const auto start = saved_.displacements;
  const auto owned = ownedNodes_;
  double largest = 0.0;
  Kokkos::parallel_reduce(
      "perishell::newton::largestTranslation", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, numNodes_),
      KOKKOS_LAMBDA(const LocalIndex node, double& value) {
        if (!owned(node)) return;
        for (int d = 0; d < 3; ++d) {
          const double magnitude = Kokkos::Experimental::fabs(ofIncrement ? u(node, d) - start(node, d) : du(node, d));
          value = magnitude > value ? magnitude : value;
        }
      },
      Kokkos::Max<double>(largest));
  return communicator().max(largest);
}

template <class ExecutionSpaceT>
auto StaticNewtonSolver<ExecutionSpaceT>::computeOutOfBalance(double loadFactor) -> ResidualNorms {
  const auto factors = loadFactors(loadFactor);
  const auto patterns = actions_.loadPatterns;
  const auto r = outOfBalance_;
  const int numPatterns = actions_.numPatterns();
  const auto owned = ownedNodes_;
  double loadSquared = 0.0;
  Kokkos::parallel_reduce(
      "perishell::newton::loads", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, numNodes_),
      KOKKOS_LAMBDA(const LocalIndex node, double& sum) {
        for (int d = 0; d < 6; ++d) {
          double load = 0.0;
          for (int p = 0; p < numPatterns; ++p) load += factors.values[p] * patterns(node, 6 * p + d);
          r(node, d) = load;
          if (owned(node)) sum += load * load;
        }
      },
      loadSquared);
  loadSquared = communicator().sum(loadSquared);
  if (pd_) {
    const pd::BondForceOutputs<Memory> outputs{r, VectorView<Memory>(), fractureScratch_, intactScratch_};
    // Node-gather, as the explicit step: in the app (libperishell, where the explicit driver
    // instantiates the same kernels) the bond-scatter launch from here jumped to address 0
    // on the H200 (cuda-gdb), while test binaries ran it; node-gather, no atomics, runs.
    pd::computeBondForces(space_, deck::ForceKernel::NodeGather, *pd_, state_, intact_, outputs);
  }
  if (shell_) shell::subtractShellForces(space_, *shell_, state_, r);
  assembly::condenseImageForces(space_, actions_.mirrorImages, r);
  return {outOfBalanceNorm(false), std::max(std::sqrt(loadSquared), outOfBalanceNorm(true))};
}

template <class ExecutionSpaceT>
double StaticNewtonSolver<ExecutionSpaceT>::outOfBalanceNorm(bool overPrescribedDofs) const {
  return std::sqrt(dofDot(outOfBalance_, outOfBalance_, overPrescribedDofs));
}

template <class ExecutionSpaceT>
double StaticNewtonSolver<ExecutionSpaceT>::dofDot(const pd::NodalVectorView<Memory>& a,
                                                   const pd::NodalVectorView<Memory>& b,
                                                   bool overPrescribedDofs) const {
  const auto constrained = actions_.constrainedDofs;
  const auto owned = ownedNodes_;
  double dot = 0.0;
  Kokkos::parallel_reduce(
      "perishell::newton::dofDot", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, numNodes_),
      KOKKOS_LAMBDA(const LocalIndex node, double& sum) {
        if (!owned(node)) return;
        for (int d = 0; d < 6; ++d)
          if (((constrained(node) >> d) & 1u) == (overPrescribedDofs ? 1u : 0u)) sum += a(node, d) * b(node, d);
      },
      dot);
  return communicator().sum(dot);
}

template <class ExecutionSpaceT>
belos::CgResult StaticNewtonSolver<ExecutionSpaceT>::solveLinear(const Matrix& K, const VectorView<Memory>& rhs,
                                                                 const VectorView<Memory>& solution,
                                                                 const belos::CgOptions& linear, bool attemptStart,
                                                                 IncrementReport& report) {
  // The halo rows are other ranks' equations: zero here, they stay zero through the Krylov
  // method (belos::DistributedRows), and the solution's are filled from their owners.
  if (rows_) {
    const auto owned = rows_->owned;
    Kokkos::parallel_for(
        "perishell::newton::zeroHaloRows", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, rhs.extent(0)),
        KOKKOS_LAMBDA(const std::size_t dof) {
          if (!owned(dof)) rhs(dof) = 0.0;
        });
  }
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

template <class ExecutionSpaceT>
belos::CgResult StaticNewtonSolver<ExecutionSpaceT>::solveOnce(const Matrix& K, const VectorView<Memory>& rhs,
                                                               const VectorView<Memory>& solution,
                                                               const belos::CgOptions& linear, bool rebuild,
                                                               IncrementReport& report) {
  using Clock = std::chrono::steady_clock;
  const bool amg = active_ == deck::Preconditioner::Amg;
  auto start = Clock::now();
  belos::CgOptions limited = linear;
  Teuchos::RCP<const Belos::Operator<double>> preconditioner;
  if (!amg) {
    onEveryRank("the block-Jacobi preconditioner",
                [&] { preconditioner = belos::detail::makePreconditioner(preconditionerMatrix(K), linear); });
    coupled_ = Teuchos::null;
  } else {
    if (!multigrid_ || rebuild) {
      coupled_ = Teuchos::null;
      ++report.preconditionerBuilds;
      updateCurrentPositions();
      multigrid::SmoothedAggregationOptions multigridOptions;
      multigridOptions.dropTolerance = options_.amgDropTolerance;
      multigridOptions.maxCoarseNodes = options_.amgCoarseNodes;
      multigridOptions.regionScaling = options_.amgRegionScaling;
      multigridOptions.symmetric = linear.method == belos::CgOptions::Method::Cg;
      onEveryRank("the multigrid preconditioner", [&] {
        if (multigrid_)
          multigrid_->update(preconditionerMatrix(K), currentPositions_);
        else
          multigrid_ = std::make_shared<multigrid::SmoothedAggregationPreconditioner<ExecutionSpaceT>>(
              space_, preconditionerMatrix(K), currentPositions_, multigridOptions, nodeRegions_);
      });
    } else {
      limited.maxIterations = std::min(linear.maxIterations, reuseIterationLimit());
    }
    preconditioner = Teuchos::rcp<const Belos::Operator<double>>(multigrid_.get(), false);
  }
  preconditioner = coupleRanks(K, preconditioner);
  report.seconds.preconditioner += fencedSecondsSince(space_, start);
  Kokkos::deep_copy(space_, solution, 0.0);
  start = Clock::now();
  const belos::CgResult result = belos::solveCg<ExecutionSpaceT>(K, rhs, solution, limited, preconditioner, rows_);
  fillHalo(solution);
  report.seconds.linearSolve += fencedSecondsSince(space_, start);
  report.linearIterations += result.iterations;
  if (amg) {
    if (rebuild) iterationsAfterRebuild_ = result.iterations;
    multigridReusable_ = options_.amgReuseGrowth > 0.0 && result.iterations <= reuseIterationLimit();
  }
  return result;
}

template <class ExecutionSpaceT>
bool StaticNewtonSolver<ExecutionSpaceT>::usesFactor() const {
  return active_ == deck::Preconditioner::Cholesky || active_ == deck::Preconditioner::Direct;
}

template <class ExecutionSpaceT>
belos::CgResult StaticNewtonSolver<ExecutionSpaceT>::solveWithFactor(const Matrix& K, const VectorView<Memory>& rhs,
                                                                     const VectorView<Memory>& solution,
                                                                     const belos::CgOptions& linear,
                                                                     IncrementReport& report) {
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

template <class ExecutionSpaceT>
direct::FactorizationInfo StaticNewtonSolver<ExecutionSpaceT>::factorize(const Matrix& K, IncrementReport& report) {
  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  factorCurrent_ = false;  // a failed factorization leaves none
  direct::FactorizationInfo info;
  onEveryRank("the Cholesky factorization", [&] {
    try {
      if (!factor_)
        factor_ = std::make_unique<direct::FactorizationPreconditioner<ExecutionSpaceT>>(
            K, options_.factorization == deck::Factorization::Device ||
                   (options_.factorization == deck::Factorization::Auto &&
                    K.numRows() >= options_.autoDeviceFactorizationRows));
      info = factor_->factorize(preconditionerMatrix(K));
    } catch (const direct::FactorizationError& error) {
      if (error.kind() != direct::FactorizationError::Kind::Singular || error.row() < 0) throw;
      static const char* dofNames[6] = {"ux", "uy", "uz", "rx", "ry", "rz"};
      long long node = error.row() / 6;
      if (distribution_.distributed()) {
        const auto globalIds = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, distribution_.globalIds());
        node = globalIds(node);
      }
      throw direct::FactorizationError(
          error.kind(),
          "the tangent is singular (a mechanism, or a DOF that nothing holds): a pivot vanished at "
          "DOF " +
              std::string(dofNames[error.row() % 6]) + " of mesh node " + std::to_string(node + 1) +
              " (1-based, in mesh order)",
          error.row());
    }
  });
  // Over ranks: the owned blocks' negative pivots. A block that is not positive definite makes
  // the tangent indefinite; the converse may miss a limit point (docs/parallel.md).
  info.negativePivots = static_cast<long>(communicator().sum(static_cast<long long>(info.negativePivots)));
  info.positiveDefinite = !communicator().any(!info.positiveDefinite);
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
  coupled_ = Teuchos::null;
  return info;
}

template <class ExecutionSpaceT>
belos::CgResult StaticNewtonSolver<ExecutionSpaceT>::krylovWithFactor(const Matrix& K, const VectorView<Memory>& rhs,
                                                                      const VectorView<Memory>& solution,
                                                                      belos::CgOptions linear,
                                                                      IncrementReport& report) {
  // CG needs an SPD preconditioner: an indefinite L D L^T goes with GMRES.
  if (!factorPositiveDefinite_) linear.method = belos::CgOptions::Method::Gmres;
  const auto preconditioner = coupleRanks(K, Teuchos::rcp<const Belos::Operator<double>>(factor_.get(), false));
  Kokkos::deep_copy(space_, solution, 0.0);
  const auto start = std::chrono::steady_clock::now();
  const belos::CgResult result = belos::solveCg<ExecutionSpaceT>(K, rhs, solution, linear, preconditioner, rows_);
  fillHalo(solution);
  report.seconds.linearSolve += fencedSecondsSince(space_, start);
  report.linearIterations += result.iterations;
  return result;
}

template <class ExecutionSpaceT>
void StaticNewtonSolver<ExecutionSpaceT>::switchToCholeskyWhenAmgStruggles(IncrementReport& report) {
  if (options_.preconditioner != deck::Preconditioner::Auto || active_ != deck::Preconditioner::Amg) return;
  const double perSolve = double(report.linearIterations) / std::max(report.newtonIterations, 1);
  if (perSolve <= options_.autoSwitchIterations || freeDofs_ > options_.autoSwitchDofs) return;
  active_ = deck::Preconditioner::Cholesky;
  multigrid_.reset();
  report.notes.push_back("AMG needed " + std::to_string(int(perSolve)) +
                         " Krylov iterations per solve: switching to the Cholesky preconditioner");
}

template <class ExecutionSpaceT>
long long StaticNewtonSolver<ExecutionSpaceT>::countFreeDofs() const {
  const auto flags = isConstrained_;
  const auto owned = ownedNodes_;
  long long count = 0;
  Kokkos::parallel_reduce(
      "perishell::newton::countFreeDofs", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, flags.extent(0)),
      KOKKOS_LAMBDA(const std::size_t dof, long long& sum) { sum += flags(dof) || !owned(dof / 6) ? 0 : 1; }, count);
  return communicator().sum(count);
}

template <class ExecutionSpaceT>
int StaticNewtonSolver<ExecutionSpaceT>::reuseIterationLimit() const {
  return static_cast<int>(std::ceil(options_.amgReuseGrowth * std::max(iterationsAfterRebuild_, 1)));
}

template <class ExecutionSpaceT>
void StaticNewtonSolver<ExecutionSpaceT>::updateCurrentPositions() {
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

template <class ExecutionSpaceT>
void StaticNewtonSolver<ExecutionSpaceT>::assembleTangent() {
  // Where nothing moved since the last assembly (an increment's first iteration after the
  // converged tangent was factored), values_ still hold it: its elimination is idempotent.
  if (tangentVersion_ == stateVersion_ && !mixedForcesCurrent_ && !tangentUsedMixedForces_) return;
  tangentVersion_ = stateVersion_;
  tangentUsedMixedForces_ = mixedForcesCurrent_;
  Kokkos::deep_copy(space_, values_, 0.0);
  if (shell_)
    shell::assembleShellTangent(space_, *shell_, state_, pattern_, values_, options_.tangent,
                                mixedForcesCurrent_ ? mixedForces_ : shell::ElementLocalForcesView<Memory>());
  if (pd_)
    pd::assembleBondTangent(space_, *pd_, state_, intact_, pattern_, values_, options_.tangent, actions_.mirrorImages);
}

template <class ExecutionSpaceT>
void StaticNewtonSolver<ExecutionSpaceT>::applyPrescribedValues(double loadFactor) {
  mixedForcesCurrent_ = false;  // the supports' move is no Newton correction
  CurveFactors factors = actions_.supportFactors(loadFactor);
  const auto constrained = actions_.constrainedDofs;
  const auto value = actions_.prescribedValue;
  const auto curve = actions_.supportCurveIndex;
  const auto u = state_.displacements;
  const auto q = state_.rotations;
  int changed = 0;
  Kokkos::parallel_reduce(
      "perishell::newton::applyPrescribedValues", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, numNodes_),
      KOKKOS_LAMBDA(const LocalIndex node, int& count) {
        const unsigned mask = constrained(node);
        if (mask == 0) return;
        auto target = [&](int d) {
          return value(node, d) * (curve(node, d) < 0 ? loadFactor : factors.values[curve(node, d)]);
        };
        for (int d = 0; d < 3; ++d)
          if (mask & (1u << d)) {
            const double prescribed = target(d);
            count += u(node, d) != prescribed;
            u(node, d) = prescribed;
          }
        if ((mask >> 3) == 0) return;
        const double quaternion[4] = {q(node, 0), q(node, 1), q(node, 2), q(node, 3)};
        double R[3][3], theta[3], updated[4];
        rotation::toMatrix(quaternion, R);
        rotation::logarithm(R, theta);
        for (int d = 0; d < 3; ++d)
          if (mask & (1u << (3 + d))) theta[d] = target(3 + d);
        rotation::exponential(theta, updated);
        for (int k = 0; k < 4; ++k) {
          count += q(node, k) != updated[k];
          q(node, k) = updated[k];
        }
      },
      changed);
  // Every rank alike: the tangent is reused, or not, on all.
  if (communicator().max(changed) > 0) ++stateVersion_;
  prescribedFactor_ = loadFactor;
  assembly::imposeMirrorImages(space_, actions_.mirrorImages, u, q, actions_.prescribedAt(loadFactor, loadFactor));
}

template <class ExecutionSpaceT>
void StaticNewtonSolver<ExecutionSpaceT>::applyCorrection(double eta) {
  if (options_.mixedFormat && shell_ && shell_->numElements() > 0) {
    if (mixedForces_.extent(0) == 0)
      mixedForces_ = shell::ElementLocalForcesView<Memory>("perishell::newton::mixedForces", shell_->numElements());
    shell::linearizeShellLocalForces(space_, *shell_, state_, correction_, eta, mixedForces_);
    mixedForcesCurrent_ = true;
  }
  ++stateVersion_;
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
  assembly::imposeMirrorImages(space_, actions_.mirrorImages, u, q,
                               actions_.prescribedAt(prescribedFactor_, prescribedFactor_));
}

template <class ExecutionSpaceT>
void StaticNewtonSolver<ExecutionSpaceT>::makeArcLengthVectors() {
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

template <class ExecutionSpaceT>
double StaticNewtonSolver<ExecutionSpaceT>::translationDot(int first, int second) const {
  const auto dr = correction_;
  const auto dt = tangentDirection_;
  const auto u = state_.displacements;
  const auto start = saved_.displacements;
  const auto last = lastArcDirection_;
  const auto owned = ownedNodes_;
  double dot = 0.0;
  Kokkos::parallel_reduce(
      "perishell::newton::translationDot", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, numNodes_),
      KOKKOS_LAMBDA(const LocalIndex node, double& sum) {
        if (!owned(node)) return;
        auto pick = [&](int which, int d) {
          return which == 0   ? dr(node, d)
                 : which == 1 ? dt(node, d)
                 : which == 2 ? u(node, d) - start(node, d)
                              : last(node, d);
        };
        for (int d = 0; d < 3; ++d) sum += pick(first, d) * pick(second, d);
      },
      dot);
  return communicator().sum(dot);
}

template <class ExecutionSpaceT>
void StaticNewtonSolver<ExecutionSpaceT>::recordArcDirection() {
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

template <class ExecutionSpaceT>
void StaticNewtonSolver<ExecutionSpaceT>::combineCorrection(double ds) {
  const auto dr = correction_;
  const auto dt = tangentDirection_;
  Kokkos::parallel_for(
      "perishell::newton::combineCorrection", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, numNodes_),
      KOKKOS_LAMBDA(const LocalIndex node) {
        for (int d = 0; d < 6; ++d) dr(node, d) += ds * dt(node, d);
      });
}

template <class ExecutionSpaceT>
std::string StaticNewtonSolver<ExecutionSpaceT>::solveTangent(const Matrix& K, const pd::NodalVectorView<Memory>& rhs,
                                                              const pd::NodalVectorView<Memory>& into, double tolerance,
                                                              bool attemptStart, IncrementReport& report) {
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

template <class ExecutionSpaceT>
std::string StaticNewtonSolver<ExecutionSpaceT>::arcLengthIterate(IncrementReport& report) {
  // Predictor: dt = K^-1 P_ref at the converged state.
  Kokkos::deep_copy(space_, outOfBalance_, referenceLoad_);
  std::string failure = solveTangent(constrainedTangent(flatOutOfBalance(), report), outOfBalance_, tangentDirection_,
                                     1e-8, true, report);
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
    if (!std::isfinite(norms.free))
      return "the out-of-balance force is not finite at iteration " + std::to_string(iteration);
    const double reference = std::max(norms.reference, 1e-300);
    report.relativeResidual = norms.free / reference;
    if (iteration > 0 && norms.free <= options_.tolerance * reference) return "";
    if (iteration == 0) initialResidual = norms.free;
    if (iteration >= options_.maxIterations)
      return "no convergence in " + std::to_string(options_.maxIterations) + " iterations (relative residual " +
             detail::scientific(report.relativeResidual) + ")";
    if (iteration > 2 && norms.free > 1e4 * initialResidual) return "diverging";
    // Corrector: K dr = r and K dt = P_ref with the same tangent.
    const double tolerance =
        std::clamp(0.1 * options_.tolerance * reference / std::max(norms.free, 1e-300), 1e-10, 1e-3);
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

template <class ExecutionSpaceT>
void StaticNewtonSolver<ExecutionSpaceT>::markConstrainedDofs() {
  const auto constrained = actions_.constrainedDofs;
  const auto flags = isConstrained_;
  Kokkos::parallel_for(
      "perishell::newton::markConstrainedDofs", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, numNodes_),
      KOKKOS_LAMBDA(const LocalIndex node) {
        for (int d = 0; d < 6; ++d) flags(6 * std::size_t(node) + d) = (constrained(node) & (1u << d)) != 0;
      });
}

template <class ExecutionSpaceT>
auto StaticNewtonSolver<ExecutionSpaceT>::preconditionerMatrix(const Matrix& K) -> Matrix {
  if (!rows_) return K;
  if (options_.overlap) return overlapImport(K).overlapped(K);
  if (preconditionerValues_.extent(0) != K.values.extent(0))
    preconditionerValues_ = VectorView<Memory>("perishell::newton::preconditionerValues", K.values.extent(0));
  const auto rowMap = K.graph.row_map;
  const auto columns = K.graph.entries;
  const auto values = K.values;
  const auto blockValues = preconditionerValues_;
  const auto owned = rows_->owned;
  Kokkos::parallel_for(
      "perishell::newton::ownedBlock", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, K.numRows()),
      KOKKOS_LAMBDA(const LocalIndex row) {
        for (auto entry = rowMap(row); entry < rowMap(row + 1); ++entry) {
          const LocalIndex column = columns(entry);
          blockValues(entry) = owned(row) ? (owned(column) ? values(entry) : 0.0) : (column == row ? 1.0 : 0.0);
        }
      });
  return Matrix("perishell::newton::ownedBlock", K.numRows(), K.numCols(), K.nnz(), blockValues, rowMap, columns);
}

template <class ExecutionSpaceT>
belos::OverlapImport<ExecutionSpaceT>& StaticNewtonSolver<ExecutionSpaceT>::overlapImport(const Matrix& K) {
  if (!overlapImport_)
    overlapImport_ = std::make_unique<belos::OverlapImport<ExecutionSpaceT>>(
        space_, K, std::make_shared<parallel::NodeDistribution<Memory>>(distribution_));
  return *overlapImport_;
}

template <class ExecutionSpaceT>
Teuchos::RCP<const Belos::Operator<double>> StaticNewtonSolver<ExecutionSpaceT>::coupleRanks(
    const Matrix& K, const Teuchos::RCP<const Belos::Operator<double>>& local) {
  if (!rows_) return local;
  if (coupled_.is_null()) {
    coupled_ = local;
    if (options_.overlap)
      coupled_ = Teuchos::rcp(new belos::AdditiveSchwarz<ExecutionSpaceT>(space_, overlapImport(K).distribution(),
                                                                          coupled_, K.numRows()));
    if (options_.coarseSpace) {
      updateCurrentPositions();
      coupled_ = Teuchos::rcp(new belos::SubdomainCoarseSpace<ExecutionSpaceT>(
          space_, K, distribution_.ownerSlots(), distribution_.neighbourRanks(), isConstrained_, currentPositions_,
          communicator(), coupled_));
    }
  }
  return coupled_;
}

template <class ExecutionSpaceT>
void StaticNewtonSolver<ExecutionSpaceT>::fillHalo(const VectorView<Memory>& vector) {
  if (!distribution_.distributed()) return;
  space_.fence();
  distribution_.exchange(space_, pd::NodalVectorView<Memory>(vector.data(), vector.extent(0) / 6));
}

template <class ExecutionSpaceT>
template <class Build>
void StaticNewtonSolver<ExecutionSpaceT>::onEveryRank(const char* what, Build&& build) {
  if (!distribution_.distributed()) {
    build();
    return;
  }
  std::exception_ptr failure;
  try {
    build();
  } catch (...) {
    failure = std::current_exception();
  }
  const int mine = detail::failureCode(failure);
  const int agreed = communicator().max(mine);
  if (agreed == 0) return;
  // The root's message reaches the user through the run's error; another rank's, here.
  if (failure && !communicator().root()) {
    try {
      std::rethrow_exception(failure);
    } catch (const std::exception& error) {
      std::fprintf(stderr, "perishell (rank %d of %d): %s failed: %s\n", communicator().rank(), communicator().size(),
                   what, error.what());
    }
  }
  if (mine == agreed) std::rethrow_exception(failure);
  const std::string elsewhere = std::string(what) + " failed on another rank (its message is on standard error)";
  if (agreed == 4) throw std::runtime_error(elsewhere);
  throw direct::FactorizationError(static_cast<direct::FactorizationError::Kind>(agreed - 1), elsewhere);
}

template <class ExecutionSpaceT>
void StaticNewtonSolver<ExecutionSpaceT>::notifyIteration(double target, const IncrementReport& report) const {
  if (observer_) observer_(target, report);
}

template <class ExecutionSpaceT>
CurveFactors StaticNewtonSolver<ExecutionSpaceT>::loadFactors(double s) const {
  CurveFactors factors;
  for (int p = 0; p < actions_.numPatterns(); ++p)
    factors.values[p] = actions_.patternCurves[p] ? deck::evaluateCurve(*actions_.patternCurves[p], s) : s;
  return factors;
}

template <class ExecutionSpaceT>
void StaticNewtonSolver<ExecutionSpaceT>::copyKinematics(const pd::PdKinematics<Memory>& to,
                                                         const pd::PdKinematics<Memory>& from) const {
  Kokkos::deep_copy(space_, to.displacements, from.displacements);
  Kokkos::deep_copy(space_, to.rotations, from.rotations);
}

}  // namespace perishell::solvers
