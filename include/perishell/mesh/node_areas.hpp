#pragma once
// Tributary area of every node, A_i = sum over elements of the integral of N_i dA: the
// row sums of the consistent mass matrix per unit areal density, so sum_i A_i is the
// mesh area. Element mapping: one thread per element writes its corners' shares, then one
// thread per node gathers them in element order (mesh/node_incidence.hpp), so the areas are
// the same bits on every run and backend.
#include <perishell/mesh/bilinear_quad.hpp>
#include <perishell/mesh/node_incidence.hpp>
#include <perishell/mesh/quad_mesh.hpp>

namespace perishell::mesh {

template <class ExecutionSpaceT, class MemorySpaceT>
VectorView<MemorySpaceT> computeNodeAreas(const ExecutionSpaceT& space,
                                          const QuadMesh<MemorySpaceT>& mesh) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  const auto coordinates = mesh.coordinates;
  const auto quads = mesh.quads;
  const Kokkos::View<double* [4], Kokkos::LayoutRight, MemorySpaceT> cornerAreas("corner areas", mesh.numElements());
  Kokkos::parallel_for(
      "perishell::computeNodeAreas::corners",
      Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, mesh.numElements()),
      KOKKOS_LAMBDA(const int element) {
        double x[4][3];
        bilinear::gatherNodes(coordinates, quads, element, x);
        double nodeArea[4] = {0.0, 0.0, 0.0, 0.0};
        for (int q = 0; q < bilinear::numGaussPoints; ++q) {
          const auto point = bilinear::evaluate(x, bilinear::gaussXi(q), bilinear::gaussEta(q));
          for (int a = 0; a < 4; ++a) nodeArea[a] += point.shape[a] * point.areaElement;
        }
        // A triangle a b c c: node c takes both of its corners' shares.
        if (isTriangle(quads, element)) nodeArea[2] += nodeArea[3];
        for (int a = 0; a < 4; ++a) cornerAreas(element, a) = nodeArea[a];
      });
  const auto incidence = makeNodeIncidence(space, quads, mesh.numNodes());
  VectorView<MemorySpaceT> areas("node areas", mesh.numNodes());
  Kokkos::parallel_for(
      "perishell::computeNodeAreas::gather", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, mesh.numNodes()),
      KOKKOS_LAMBDA(const int node) {
        double sum = 0.0;
        for (RowOffset i = incidence.offsets(node); i < incidence.offsets(node + 1); ++i)
          sum += cornerAreas(incidence.entries(i) / 4, incidence.entries(i) % 4);
        areas(node) = sum;
      });
  return areas;
}

}  // namespace perishell::mesh
