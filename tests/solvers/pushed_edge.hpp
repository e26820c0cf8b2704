#pragma once
// Supports of the plane-wave tests: uniaxial strain (every DOF but u_x held at zero) and the
// nodes with x < edgeWidth pushed along x at pushSpeed (a ramp of their displacement that
// ends at rampTime), so that a front of speed sqrt(E / (rho (1 - nu^2))) leaves the edge.
#include <perishell/mesh/quad_mesh.hpp>
#include <perishell/solvers/explicit/external_actions.hpp>

template <class MemorySpaceT>
perishell::solvers::ExternalActions<MemorySpaceT> pushedEdgeActions(const perishell::mesh::HostQuadMesh& mesh,
                                                                    double edgeWidth, double pushSpeed,
                                                                    double rampTime) {
  auto actions = perishell::solvers::makeFreeActions<MemorySpaceT>(mesh.numNodes());
  auto constrained = Kokkos::create_mirror_view(actions.constrainedDofs);
  auto value = Kokkos::create_mirror_view(actions.prescribedValue);
  auto curveIndex = Kokkos::create_mirror_view(actions.supportCurveIndex);
  Kokkos::deep_copy(curveIndex, std::int8_t(-1));
  for (perishell::LocalIndex node = 0; node < mesh.numNodes(); ++node) {
    constrained(node) = 0b111110;  // everything but u_x
    if (mesh.coordinates(node, 0) < edgeWidth) {
      constrained(node) = 0b111111;
      value(node, 0) = pushSpeed * rampTime;
      curveIndex(node, 0) = 0;
    }
  }
  Kokkos::deep_copy(actions.constrainedDofs, constrained);
  Kokkos::deep_copy(actions.prescribedValue, value);
  Kokkos::deep_copy(actions.supportCurveIndex, curveIndex);
  perishell::deck::Curve ramp;
  ramp.type = perishell::deck::CurveType::Ramp;
  ramp.endTime = rampTime;
  actions.supportCurves = {ramp};
  return actions;
}
