#pragma once
// A quad-meshed shell mid-surface: node coordinates and 4-node connectivity, in memory
// space MemorySpaceT. Generators build it on the host; mirrorTo moves it to the device.
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
