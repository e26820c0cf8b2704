#pragma once
// A model's loads and supports (model/nodal_loads.hpp) as the solvers apply them on the
// device, shared by the explicit and the implicit drivers.
#include <perishell/model/nodal_loads.hpp>
#include <perishell/solvers/explicit/external_actions.hpp>

#include <optional>
#include <string>

namespace perishell::solvers {

template <class MemorySpaceT>
ExternalActions<MemorySpaceT> makeExternalActions(const model::Model& model) {
  const auto curveNamed = [&](const std::string& name) -> std::optional<deck::Curve> {
    if (name.empty()) return std::nullopt;
    return *model.deck.findCurve(name);
  };
  const auto loads = model::buildNodalLoads(model);
  const auto supports = model::buildSupportConditions(model);
  const LocalIndex numNodes = model.shell.mesh.numNodes();
  ExternalActions<MemorySpaceT> actions;
  Kokkos::View<double**, Kokkos::LayoutRight, Kokkos::HostSpace> patterns("load patterns", numNodes,
                                                                         6 * loads.patterns.size());
  for (std::size_t p = 0; p < loads.patterns.size(); ++p) {
    for (LocalIndex node = 0; node < numNodes; ++node)
      for (int d = 0; d < 6; ++d) patterns(node, 6 * p + d) = loads.patterns[p].nodal(node, d);
    actions.patternCurves.push_back(curveNamed(loads.patterns[p].curve));
  }
  actions.loadPatterns = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, patterns);
  actions.constrainedDofs = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, supports.constrainedDofs);
  actions.prescribedValue = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, supports.prescribedValue);
  actions.supportCurveIndex = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, supports.curveIndex);
  for (const auto& name : supports.curves) actions.supportCurves.push_back(*curveNamed(name));
  actions.mirrorImages = assembly::makeMirrorImages<MemorySpaceT>(model.supportLayer, numNodes);
  return actions;
}

}  // namespace perishell::solvers
