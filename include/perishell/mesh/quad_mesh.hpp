#pragma once
// A shell mid-surface meshed with quads and triangles: node coordinates and 4-node
// connectivity, in memory space MemorySpaceT. Generators build it on the host; mirrorTo
// moves it to the device.
//
// A triangle a b c is stored as the quad a b c c (its fourth corner repeats the third).
// The collapsed bilinear map of such a quad covers the triangle exactly and its 2x2 Gauss
// rule integrates the triangle's area, and each corner's share A/3 of it, exactly; so
// areas, node weights and pressure loads need no second code path. What walks corners or
// edges uses cornerCount (an element has cornerCount edges, (k, k + 1 mod cornerCount)),
// and the shell element builds a triangle's own stiffness (shell/mitc3_triangle.hpp).
#include <perishell/core/types.hpp>

#include <string>

namespace perishell::mesh {

template <class MemorySpaceT>
struct QuadMesh {
  CoordinateView<MemorySpaceT> coordinates;
  QuadConnectivityView<MemorySpaceT> quads;

  LocalIndex numNodes() const { return static_cast<LocalIndex>(coordinates.extent(0)); }
  LocalIndex numElements() const { return static_cast<LocalIndex>(quads.extent(0)); }
};

// Whether element e is a triangle (its fourth corner repeats the third).
template <class ConnectivityT>
KOKKOS_INLINE_FUNCTION bool isTriangle(const ConnectivityT& quads, LocalIndex e) {
  return quads(e, 3) == quads(e, 2);
}

// The number of distinct corners (and of edges) of element e: 3 or 4.
template <class ConnectivityT>
KOKKOS_INLINE_FUNCTION int cornerCount(const ConnectivityT& quads, LocalIndex e) {
  return isTriangle(quads, e) ? 3 : 4;
}

using HostQuadMesh = QuadMesh<Kokkos::HostSpace>;

template <class MemorySpaceT>
QuadMesh<MemorySpaceT> mirrorTo(const HostQuadMesh& host) {
  QuadMesh<MemorySpaceT> mesh;
  mesh.coordinates = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, host.coordinates);
  mesh.quads = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, host.quads);
  return mesh;
}

// Flat rectangular plate [0, lengthX] x [0, lengthY] in the z = 0 plane, cellsX x cellsY
// quads, nodes numbered row by row (x fastest). Throws std::invalid_argument on
// non-positive or non-finite sizes.
HostQuadMesh makeRectangularPlate(double lengthX, double lengthY, int cellsX, int cellsY);

// Node indices on the boundary of a plate made by makeRectangularPlate.
Kokkos::View<LocalIndex*, Kokkos::HostSpace> plateBoundaryNodes(int cellsX, int cellsY);

}  // namespace perishell::mesh
