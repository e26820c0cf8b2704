#pragma once
// Tributary area of every node, A_i = sum over elements of the integral of N_i dA: the
// row sums of the consistent mass matrix per unit areal density, so sum_i A_i is the
// mesh area. Element mapping: one thread per element, scattered with atomic_add.
#include <perishell/mesh/bilinear_quad.hpp>
#include <perishell/mesh/quad_mesh.hpp>

namespace perishell::mesh {

template <class ExecutionSpaceT, class MemorySpaceT>
VectorView<MemorySpaceT> computeNodeAreas(const ExecutionSpaceT& space,
                                          const QuadMesh<MemorySpaceT>& mesh) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  VectorView<MemorySpaceT> areas("node areas", mesh.numNodes());
  const auto coordinates = mesh.coordinates;
  const auto quads = mesh.quads;
  Kokkos::parallel_for(
      "perishell::computeNodeAreas",
      Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, mesh.numElements()),
      KOKKOS_LAMBDA(const int element) {
        double x[4][3];
        bilinear::gatherNodes(coordinates, quads, element, x);
        double nodeArea[4] = {0.0, 0.0, 0.0, 0.0};
        for (int q = 0; q < bilinear::numGaussPoints; ++q) {
          const auto point = bilinear::evaluate(x, bilinear::gaussXi(q), bilinear::gaussEta(q));
          for (int a = 0; a < 4; ++a) nodeArea[a] += point.shape[a] * point.areaElement;
        }
        for (int a = 0; a < 4; ++a) Kokkos::atomic_add(&areas(quads(element, a)), nodeArea[a]);
      });
  return areas;
}

}  // namespace perishell::mesh
