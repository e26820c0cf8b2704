#include <perishell/mesh/quad_mesh.hpp>

#include <cmath>
#include <stdexcept>
#include <string>

namespace perishell::mesh {

HostQuadMesh makeRectangularPlate(double lengthX, double lengthY, int cellsX, int cellsY) {
  auto requirePositive = [](const char* name, double value) {
    if (!(std::isfinite(value) && value > 0.0))
      throw std::invalid_argument(std::string("rectangular plate: ") + name +
                                  " must be positive and finite, got " + std::to_string(value));
  };
  requirePositive("length x", lengthX);
  requirePositive("length y", lengthY);
  requirePositive("cells x", cellsX);
  requirePositive("cells y", cellsY);

  const int nodesX = cellsX + 1;
  const int nodesY = cellsY + 1;
  HostQuadMesh mesh;
  mesh.coordinates = CoordinateView<Kokkos::HostSpace>("plate coordinates", nodesX * nodesY);
  mesh.quads = QuadConnectivityView<Kokkos::HostSpace>("plate quads", cellsX * cellsY);
  for (int j = 0; j < nodesY; ++j)
    for (int i = 0; i < nodesX; ++i) {
      const int node = j * nodesX + i;
      mesh.coordinates(node, 0) = lengthX * i / cellsX;
      mesh.coordinates(node, 1) = lengthY * j / cellsY;
      mesh.coordinates(node, 2) = 0.0;
    }
  for (int j = 0; j < cellsY; ++j)
    for (int i = 0; i < cellsX; ++i) {
      const int element = j * cellsX + i;
      const int first = j * nodesX + i;
      mesh.quads(element, 0) = first;
      mesh.quads(element, 1) = first + 1;
      mesh.quads(element, 2) = first + 1 + nodesX;
      mesh.quads(element, 3) = first + nodesX;
    }
  return mesh;
}

Kokkos::View<LocalIndex*, Kokkos::HostSpace> plateBoundaryNodes(int cellsX, int cellsY) {
  const int nodesX = cellsX + 1;
  const int nodesY = cellsY + 1;
  Kokkos::View<LocalIndex*, Kokkos::HostSpace> nodes("plate boundary nodes", 2 * (cellsX + cellsY));
  int count = 0;
  for (int j = 0; j < nodesY; ++j)
    for (int i = 0; i < nodesX; ++i)
      if (i == 0 || j == 0 || i == cellsX || j == cellsY) nodes(count++) = j * nodesX + i;
  return nodes;
}

}  // namespace perishell::mesh
