#pragma once
// A model's loads and supports (model/nodal_loads.hpp) as the solvers apply them on the
// device, shared by the explicit and the implicit drivers.
#include <perishell/model/nodal_loads.hpp>
#include <perishell/solvers/explicit/external_actions.hpp>

#include <optional>
#include <string>
#include <vector>

namespace perishell::solvers {

// localNodes: the mesh node of each node the actions are for (a distributed run's local
// nodes, parallel/domain.hpp), with their support layer; empty: every mesh node, the model's.
// Loads and supports are built on the whole model first, so a node's values are the same
// on any rank count.
template <class MemorySpaceT>
ExternalActions<MemorySpaceT> makeExternalActions(const model::Model& model,
                                                  const std::vector<LocalIndex>& localNodes = {},
                                                  const mesh::SupportLayer* localLayer = nullptr) {
  const auto curveNamed = [&](const std::string& name) -> std::optional<deck::Curve> {
    if (name.empty()) return std::nullopt;
    return *model.deck.findCurve(name);
  };
  const auto loads = model::buildNodalLoads(model);
  const auto supports = model::buildSupportConditions(model);
  const bool everyNode = localNodes.empty();
  const LocalIndex numNodes = everyNode ? model.shell.mesh.numNodes() : static_cast<LocalIndex>(localNodes.size());
  const auto meshNode = [&](LocalIndex node) { return everyNode ? node : localNodes[node]; };
  ExternalActions<MemorySpaceT> actions;
  Kokkos::View<double**, Kokkos::LayoutRight, Kokkos::HostSpace> patterns("load patterns", numNodes,
                                                                         6 * loads.patterns.size());
  for (std::size_t p = 0; p < loads.patterns.size(); ++p) {
    for (LocalIndex node = 0; node < numNodes; ++node)
      for (int d = 0; d < 6; ++d) patterns(node, 6 * p + d) = loads.patterns[p].nodal(meshNode(node), d);
    actions.patternCurves.push_back(curveNamed(loads.patterns[p].curve));
  }
  actions.loadPatterns = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, patterns);
  if (everyNode) {
    actions.constrainedDofs = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, supports.constrainedDofs);
    actions.prescribedValue = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, supports.prescribedValue);
    actions.supportCurveIndex = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, supports.curveIndex);
  } else {
    Kokkos::View<std::uint8_t*, Kokkos::HostSpace> constrained("constrained dofs", numNodes);
    model::HostNodalValues value("prescribed values", numNodes);
    Kokkos::View<std::int8_t* [6], Kokkos::LayoutRight, Kokkos::HostSpace> curveIndex("support curves", numNodes);
    for (LocalIndex node = 0; node < numNodes; ++node) {
      constrained(node) = supports.constrainedDofs(meshNode(node));
      for (int d = 0; d < 6; ++d) {
        value(node, d) = supports.prescribedValue(meshNode(node), d);
        curveIndex(node, d) = supports.curveIndex(meshNode(node), d);
      }
    }
    actions.constrainedDofs = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, constrained);
    actions.prescribedValue = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, value);
    actions.supportCurveIndex = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, curveIndex);
  }
  for (const auto& name : supports.curves) actions.supportCurves.push_back(*curveNamed(name));
  actions.mirrorImages = assembly::makeMirrorImages<MemorySpaceT>(localLayer ? *localLayer : model.supportLayer, numNodes);
  return actions;
}

}  // namespace perishell::solvers
