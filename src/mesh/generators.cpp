#include <perishell/mesh/generators.hpp>

#include <algorithm>
#include <climits>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace perishell::mesh {

namespace {

constexpr double pi = 3.14159265358979323846;

std::string show(double value) {
  std::ostringstream text;
  text << value;
  return text.str();
}

void requirePositive(const std::string& mesh, const char* name, double value) {
  if (!(std::isfinite(value) && value > 0.0))
    throw std::invalid_argument(mesh + ": " + name + " must be positive and finite, got " +
                                show(value));
}

// cells = round(length / spacing), at least minimumCells, and few enough that node indices
// fit LocalIndex (checked again on the product by requireIndexable).
int cellsForSpacing(const std::string& mesh, const char* direction, double length,
                    double spacing, int minimumCells) {
  const double ratio = length / spacing;
  if (!(ratio < 0.5 * INT_MAX))
    throw std::invalid_argument(mesh + ": spacing " + show(spacing) + " m gives " + show(ratio) +
                                " cells " + direction + ", more than a mesh can index");
  const int cells = static_cast<int>(std::lround(ratio));
  if (cells < minimumCells)
    throw std::invalid_argument(mesh + ": spacing " + show(spacing) + " m gives " +
                                std::to_string(cells) + " cell(s) " + direction +
                                " (length " + show(length) + " m); need at least " +
                                std::to_string(minimumCells) + ", so reduce the spacing");
  return cells;
}

void requireIndexable(const std::string& mesh, double numNodes) {
  if (numNodes > static_cast<double>(INT_MAX))
    throw std::invalid_argument(mesh + ": " + show(numNodes) +
                                " nodes exceed the index range; increase the spacing");
}

void insertNodeSetFromEdges(MeshSets& sets, const std::string& name) {
  std::vector<LocalIndex> nodes;
  for (const auto& edge : sets.edgeSets.at(name)) {
    nodes.push_back(edge.first);
    nodes.push_back(edge.second);
  }
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  sets.nodeSets[name] = std::move(nodes);
}

// A closed tube: the polygon `ring` (counter-clockwise about +z, so facet normals point
// outward) swept along z over [0, length] with `along` cells. Node j * ringSize + i is ring
// point i at height j; quad j * ringSize + i spans ring points i and i + 1 (mod ringSize),
// so the seam reuses ring point 0 instead of duplicating it.
ShellMesh makeTube(const std::vector<std::array<double, 2>>& ring, double length, int along) {
  const int ringSize = static_cast<int>(ring.size());
  ShellMesh shell;
  auto& mesh = shell.mesh;
  mesh.coordinates = CoordinateView<Kokkos::HostSpace>("tube coordinates", ringSize * (along + 1));
  mesh.quads = QuadConnectivityView<Kokkos::HostSpace>("tube quads", ringSize * along);
  for (int j = 0; j <= along; ++j)
    for (int i = 0; i < ringSize; ++i) {
      const int node = j * ringSize + i;
      mesh.coordinates(node, 0) = ring[i][0];
      mesh.coordinates(node, 1) = ring[i][1];
      mesh.coordinates(node, 2) = length * j / along;
    }
  for (int j = 0; j < along; ++j)
    for (int i = 0; i < ringSize; ++i) {
      const int element = j * ringSize + i;
      const int first = j * ringSize + i;
      const int next = j * ringSize + (i + 1) % ringSize;
      mesh.quads(element, 0) = first;
      mesh.quads(element, 1) = next;
      mesh.quads(element, 2) = next + ringSize;
      mesh.quads(element, 3) = first + ringSize;
    }
  // Rim edges as their quads traverse them: forward along the bottom, backward along the top.
  auto& bottom = shell.sets.edgeSets["bottom"];
  auto& top = shell.sets.edgeSets["top"];
  const int topElements = (along - 1) * ringSize;
  for (int i = 0; i < ringSize; ++i) {
    bottom.emplace_back(mesh.quads(i, 0), mesh.quads(i, 1));
    top.emplace_back(mesh.quads(topElements + i, 2), mesh.quads(topElements + i, 3));
  }
  insertNodeSetFromEdges(shell.sets, "bottom");
  insertNodeSetFromEdges(shell.sets, "top");
  return shell;
}

}  // namespace

ShellMesh makePlateWithCells(double lengthX, double lengthY, int cellsX, int cellsY) {
  requireIndexable("rectangular plate", (cellsX + 1.0) * (cellsY + 1.0));
  ShellMesh shell;
  shell.mesh = makeRectangularPlate(lengthX, lengthY, cellsX, cellsY);
  const int nodesX = cellsX + 1;
  auto node = [nodesX](int i, int j) { return j * nodesX + i; };
  // Edges counter-clockwise round the plate, each as its quad traverses it.
  auto& sets = shell.sets;
  for (int i = 0; i < cellsX; ++i) sets.edgeSets["bottom"].emplace_back(node(i, 0), node(i + 1, 0));
  for (int j = 0; j < cellsY; ++j)
    sets.edgeSets["right"].emplace_back(node(cellsX, j), node(cellsX, j + 1));
  for (int i = cellsX; i > 0; --i)
    sets.edgeSets["top"].emplace_back(node(i, cellsY), node(i - 1, cellsY));
  for (int j = cellsY; j > 0; --j) sets.edgeSets["left"].emplace_back(node(0, j), node(0, j - 1));
  for (const char* side : {"bottom", "right", "top", "left"}) insertNodeSetFromEdges(sets, side);
  sets.nodeSets["bottom-left"] = {node(0, 0)};
  sets.nodeSets["bottom-right"] = {node(cellsX, 0)};
  sets.nodeSets["top-right"] = {node(cellsX, cellsY)};
  sets.nodeSets["top-left"] = {node(0, cellsY)};
  const auto boundary = plateBoundaryNodes(cellsX, cellsY);
  sets.nodeSets["boundary"].assign(boundary.data(), boundary.data() + boundary.extent(0));
  return shell;
}

ShellMesh makePlate(double lengthX, double lengthY, double spacing) {
  const std::string name = "rectangular plate";
  requirePositive(name, "length x", lengthX);
  requirePositive(name, "length y", lengthY);
  requirePositive(name, "spacing", spacing);
  return makePlateWithCells(lengthX, lengthY, cellsForSpacing(name, "along x", lengthX, spacing, 1),
                            cellsForSpacing(name, "along y", lengthY, spacing, 1));
}

ShellMesh makeCylinder(double radius, double height, double spacing) {
  const std::string name = "cylinder";
  requirePositive(name, "radius", radius);
  requirePositive(name, "height", height);
  requirePositive(name, "spacing", spacing);
  // Three facets are the fewest that close a tube.
  const int around = cellsForSpacing(name, "around the circumference", 2.0 * pi * radius, spacing, 3);
  const int along = cellsForSpacing(name, "along the height", height, spacing, 1);
  requireIndexable(name, around * (along + 1.0));
  std::vector<std::array<double, 2>> ring(around);
  for (int i = 0; i < around; ++i) {
    const double angle = 2.0 * pi * i / around;
    ring[i] = {radius * std::cos(angle), radius * std::sin(angle)};
  }
  return makeTube(ring, height, along);
}

ShellMesh makeHexagonalPrism(double sideLength, double length, double spacing) {
  const std::string name = "hexagonal prism";
  requirePositive(name, "side length", sideLength);
  requirePositive(name, "length", length);
  requirePositive(name, "spacing", spacing);
  const int across = cellsForSpacing(name, "across a face", sideLength, spacing, 1);
  const int along = cellsForSpacing(name, "along the prism", length, spacing, 1);
  requireIndexable(name, 6.0 * across * (along + 1.0));
  // Unit hexagon from exact cos/sin of multiples of 60 degrees, so faces are exact widths.
  const double h = 0.5 * std::sqrt(3.0);
  const double vertex[7][2] = {{1.0, 0.0}, {0.5, h}, {-0.5, h}, {-1.0, 0.0},
                               {-0.5, -h}, {0.5, -h}, {1.0, 0.0}};
  std::vector<std::array<double, 2>> ring(6 * across);
  for (int face = 0; face < 6; ++face)
    for (int m = 0; m < across; ++m) {
      const double s = static_cast<double>(m) / across;
      ring[face * across + m] = {
          sideLength * ((1.0 - s) * vertex[face][0] + s * vertex[face + 1][0]),
          sideLength * ((1.0 - s) * vertex[face][1] + s * vertex[face + 1][1])};
    }
  ShellMesh shell = makeTube(ring, length, along);
  const int ringSize = 6 * across;
  for (int face = 0; face < 6; ++face) {
    const std::string faceName = "face-" + std::to_string(face);
    auto& elements = shell.sets.elementSets[faceName];
    auto& nodes = shell.sets.nodeSets[faceName];
    for (int j = 0; j < along; ++j)
      for (int m = 0; m < across; ++m) elements.push_back(j * ringSize + face * across + m);
    for (int j = 0; j <= along; ++j)
      for (int m = 0; m <= across; ++m) nodes.push_back(j * ringSize + (face * across + m) % ringSize);
    std::sort(nodes.begin(), nodes.end());
  }
  return shell;
}

CrackSegment makeCrack(const std::array<double, 3>& start, const std::array<double, 3>& end,
                       const std::array<double, 3>& normal) {
  auto requireFinite = [](const char* name, const std::array<double, 3>& v) {
    for (double component : v)
      if (!std::isfinite(component))
        throw std::invalid_argument(std::string("crack: ") + name + " has a non-finite component");
  };
  requireFinite("start", start);
  requireFinite("end", end);
  requireFinite("normal", normal);
  auto norm = [](const std::array<double, 3>& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); };
  const std::array<double, 3> along = {end[0] - start[0], end[1] - start[1], end[2] - start[2]};
  const double segmentLength = norm(along);
  // Relative to the coordinates' size: below that the direction is round-off.
  const double scale = std::max({norm(start), norm(end), 1e-300});
  if (segmentLength <= 1e-12 * scale)
    throw std::invalid_argument("crack: start and end coincide (segment length " +
                                show(segmentLength) + " m); a crack needs a non-degenerate segment");
  const double normalLength = norm(normal);
  if (!(normalLength > 0.0)) throw std::invalid_argument("crack: normal is the zero vector");
  const std::array<double, 3> cutNormal = {along[1] * normal[2] - along[2] * normal[1],
                                           along[2] * normal[0] - along[0] * normal[2],
                                           along[0] * normal[1] - along[1] * normal[0]};
  // sin(angle between segment and normal) below 1e-6: the cut plane is undefined.
  if (norm(cutNormal) <= 1e-6 * segmentLength * normalLength)
    throw std::invalid_argument("crack: normal is parallel to the segment; it must be the shell "
                                "normal, across the crack's path");
  CrackSegment crack{};
  for (int k = 0; k < 3; ++k) {
    crack.start[k] = start[k];
    crack.end[k] = end[k];
    crack.normal[k] = normal[k] / normalLength;
  }
  return crack;
}

}  // namespace perishell::mesh
