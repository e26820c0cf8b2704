#pragma once
// The Newton solver of an implicit deck's model: shell elements and PD bonds coupled by the
// morphing field (coupling/make_coupled_model.hpp; CCM-only and 100 % PD are its end
// cases), loads and supports on the device, the deck's Newton settings.
#include <perishell/coupling/make_coupled_model.hpp>
#include <perishell/model/model.hpp>
#include <perishell/solvers/implicit/static_newton.hpp>
#include <perishell/solvers/local_model.hpp>
#include <perishell/solvers/model_actions.hpp>

#include <functional>
#include <vector>

namespace perishell::solvers {

// Throws std::invalid_argument naming the deck key for what the implicit solver cannot run:
// follower pressure.
void requireImplicitModel(const model::Model& model);

// Whether any load pattern has a moment component (checked once, at set-up).
template <class MemorySpaceT>
bool appliesMoments(const ExternalActions<MemorySpaceT>& actions) {
  const auto patterns = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, actions.loadPatterns);
  for (std::size_t node = 0; node < patterns.extent(0); ++node)
    for (std::size_t column = 0; column < patterns.extent(1); ++column)
      if (column % 6 >= 3 && patterns(node, column) != 0.0) return true;
  return false;
}

static_assert(deck::ImplicitSettings{}.amgDropTolerance == multigrid::SmoothedAggregationOptions{}.dropTolerance,
              "the deck's default solver.amg-drop-tolerance is the multigrid's default");
static_assert(deck::ImplicitSettings{}.amgCoarseNodes == multigrid::SmoothedAggregationOptions{}.maxCoarseNodes,
              "the deck's default solver.amg-coarse-nodes is the multigrid's default");
static_assert(deck::ImplicitSettings{}.amgRegionScaling == multigrid::SmoothedAggregationOptions{}.regionScaling,
              "the deck's default solver.amg-region-scaling is the multigrid's default");
static_assert(deck::ImplicitSettings{}.coarseSpace == NewtonOptions{}.coarseSpace,
              "the deck's default solver.coarse-space is the solver's default");
static_assert(deck::ImplicitSettings{}.overlap == NewtonOptions{}.overlap,
              "the deck's default solver.overlap is the solver's default");

// The deck's Newton settings; momentsApplied: whether any load has a moment component (on any rank).
inline NewtonOptions newtonOptions(const model::Model& model, bool momentsApplied) {
  const auto& settings = model.deck.solver.implicitSettings;
  NewtonOptions options;
  options.maxIterations = settings.maxIterations;
  options.tolerance = settings.tolerance;
  options.maxCuts = settings.maxCuts;
  options.lineSearch = settings.lineSearch;
  options.mixedFormat = settings.newton == deck::ImplicitSettings::Newton::Mixed;
  options.arcLengthFirstStep = 1.0 / settings.increments;
  options.amgReuseGrowth = settings.amgReuse;
  options.amgDropTolerance = settings.amgDropTolerance;
  options.amgCoarseNodes = settings.amgCoarseNodes;
  options.amgRegionScaling = settings.amgRegionScaling;
  options.coarseSpace = settings.coarseSpace;
  options.overlap = settings.overlap;
  options.preconditioner = settings.preconditioner;
  options.factorization = settings.factorization;
  options.tangent = settings.tangent == deck::Tangent::Exact || (settings.tangent == deck::Tangent::Auto && momentsApplied)
                        ? TangentForm::Exact
                        : TangentForm::Symmetric;
  return options;
}

// adjust, where given, changes the options the deck gave (the Newton settings no deck key
// reaches, e.g. auto's thresholds in tests).
template <class ExecutionSpaceT>
StaticNewtonSolver<ExecutionSpaceT> makeStaticSolver(const ExecutionSpaceT& space, const model::Model& model,
                                                     const std::function<void(NewtonOptions&)>& adjust = {}) {
  requireImplicitModel(model);
  using Memory = typename ExecutionSpaceT::memory_space;
  // Shell elements where the model is CCM or in the transition, bonds where alpha > 0 (model.md §4).
  const auto bodies = coupling::makeCoupledBodies(space, model);
  auto actions = makeExternalActions<Memory>(model);
  NewtonOptions options = newtonOptions(model, appliesMoments(actions));
  if (adjust) adjust(options);
  return StaticNewtonSolver<ExecutionSpaceT>(space, model.shell.mesh.numNodes(), bodies.shellElements(),
                                             bodies.bondCarriers(), std::move(actions), options);
}

// The solver of this rank's part of a distributed run (solvers/local_model.hpp). Collective.
template <class ExecutionSpaceT>
StaticNewtonSolver<ExecutionSpaceT> makeStaticSolver(const ExecutionSpaceT& space, const model::Model& model,
                                                     const LocalModel<ExecutionSpaceT>& local) {
  requireImplicitModel(model);
  const auto& communicator = local.distribution.communicator();
  const NewtonOptions options = newtonOptions(model, communicator.any(appliesMoments(local.actions)));
  return StaticNewtonSolver<ExecutionSpaceT>(space, local.domain.numNodes(), local.bodies.shellElements(),
                                             local.bodies.bondCarriers(), local.actions, options, local.distribution);
}

}  // namespace perishell::solvers
