#pragma once
// Per-node geometry of the shell mid-surface: unit normals and volumes (model.md §1).
// Element mapping: one thread per quad, then one per node gathering its quads' values in
// element order (mesh/node_incidence.hpp): the same bits on every run and backend.
#include <perishell/mesh/node_areas.hpp>
#include <perishell/mesh/quad_mesh.hpp>

#include <climits>
#include <cmath>
#include <stdexcept>
#include <string>

namespace perishell::mesh {

// Node normal n_i = normalize(sum over adjacent elements of the element's vector area
// a_e = 1/2 (x_2 - x_0) x (x_3 - x_1)): the area-weighted facet normal. a_e is the exact
// integral of g_1 x g_2 over a bilinear quad, so warped quads are weighted correctly too.
// Throws std::runtime_error naming the first node whose adjacent vector areas cancel or
// vanish (a node outside every quad, or degenerate quads).
template <class ExecutionSpaceT, class MemorySpaceT>
CoordinateView<MemorySpaceT> computeNodeNormals(const ExecutionSpaceT& space,
                                                const QuadMesh<MemorySpaceT>& mesh) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  const auto coordinates = mesh.coordinates;
  const auto quads = mesh.quads;
  CoordinateView<MemorySpaceT> vectorAreas("element vector areas", mesh.numElements());
  Kokkos::parallel_for(
      "perishell::computeNodeNormals::elements",
      Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, mesh.numElements()),
      KOKKOS_LAMBDA(const int element) {
        double x[4][3];
        bilinear::gatherNodes(coordinates, quads, element, x);
        double d1[3], d2[3];
        for (int k = 0; k < 3; ++k) {
          d1[k] = x[2][k] - x[0][k];
          d2[k] = x[3][k] - x[1][k];
        }
        // A triangle (a b c c) has three corners: its vector area, 1/2 (c - a) x (c - b), is
        // the formula's with x_3 = x_2.
        vectorAreas(element, 0) = 0.5 * (d1[1] * d2[2] - d1[2] * d2[1]);
        vectorAreas(element, 1) = 0.5 * (d1[2] * d2[0] - d1[0] * d2[2]);
        vectorAreas(element, 2) = 0.5 * (d1[0] * d2[1] - d1[1] * d2[0]);
      });
  const auto incidence = makeNodeIncidence(space, quads, mesh.numNodes());
  CoordinateView<MemorySpaceT> normals("node normals", mesh.numNodes());
  Kokkos::parallel_for(
      "perishell::computeNodeNormals::gather", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, mesh.numNodes()),
      KOKKOS_LAMBDA(const int node) {
        double sum[3] = {0.0, 0.0, 0.0};
        for (RowOffset i = incidence.offsets(node); i < incidence.offsets(node + 1); ++i)
          for (int k = 0; k < 3; ++k) sum[k] += vectorAreas(incidence.entries(i) / 4, k);
        for (int k = 0; k < 3; ++k) normals(node, k) = sum[k];
      });
  int firstDegenerateNode = INT_MAX;
  Kokkos::parallel_reduce(
      "perishell::computeNodeNormals::normalise",
      Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, mesh.numNodes()),
      KOKKOS_LAMBDA(const int node, int& firstDegenerate) {
        const double length = Kokkos::Experimental::sqrt(normals(node, 0) * normals(node, 0) +
                                                         normals(node, 1) * normals(node, 1) +
                                                         normals(node, 2) * normals(node, 2));
        if (length > 0.0) {
          for (int k = 0; k < 3; ++k) normals(node, k) /= length;
        } else if (node < firstDegenerate) {
          firstDegenerate = node;
        }
      },
      Kokkos::Min<int>(firstDegenerateNode));
  if (firstDegenerateNode != INT_MAX)
    throw std::runtime_error("node normals: node " + std::to_string(firstDegenerateNode) +
                             " has no normal (it belongs to no quad, or its quads have zero area)");
  return normals;
}

// Node volumes V_i = A_i t for a shell of uniform thickness t (model.md §1), with A_i the
// tributary areas of computeNodeAreas.
template <class ExecutionSpaceT, class MemorySpaceT>
VectorView<MemorySpaceT> computeNodeVolumes(const ExecutionSpaceT& space,
                                            const QuadMesh<MemorySpaceT>& mesh, double thickness) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  if (!(std::isfinite(thickness) && thickness > 0.0))
    throw std::invalid_argument("node volumes: thickness must be positive and finite, got " +
                                std::to_string(thickness));
  VectorView<MemorySpaceT> volumes = computeNodeAreas(space, mesh);
  Kokkos::parallel_for(
      "perishell::computeNodeVolumes",
      Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, mesh.numNodes()),
      KOKKOS_LAMBDA(const int node) { volumes(node) *= thickness; });
  return volumes;
}

}  // namespace perishell::mesh
