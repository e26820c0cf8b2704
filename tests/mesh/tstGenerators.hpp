// Built-in meshes (plate, cylinder, hexagonal prism) with their sets, node normals and
// node volumes on the device, and the generators' and makeCrack's input checks.
#include <perishell/mesh/generators.hpp>
#include <perishell/mesh/node_geometry.hpp>

#include <algorithm>
#include <cmath>
#include <set>
#include <string>

namespace generators_test {

using perishell::LocalIndex;
using perishell::mesh::HostQuadMesh;
using perishell::mesh::ShellMesh;
using HostVectors = perishell::CoordinateView<Kokkos::HostSpace>;
using HostScalars = Kokkos::View<double*, Kokkos::HostSpace>;

constexpr double pi = 3.14159265358979323846;

template <class ExecutionSpaceT>
HostVectors nodeNormalsOnHost(const HostQuadMesh& hostMesh) {
  const auto mesh = perishell::mesh::mirrorTo<typename ExecutionSpaceT::memory_space>(hostMesh);
  const auto normals = perishell::mesh::computeNodeNormals(ExecutionSpaceT{}, mesh);
  return Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, normals);
}

template <class ExecutionSpaceT>
HostScalars nodeVolumesOnHost(const HostQuadMesh& hostMesh, double thickness) {
  const auto mesh = perishell::mesh::mirrorTo<typename ExecutionSpaceT::memory_space>(hostMesh);
  const auto volumes = perishell::mesh::computeNodeVolumes(ExecutionSpaceT{}, mesh, thickness);
  return Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, volumes);
}

double sum(const HostScalars& values) {
  double total = 0.0;
  for (std::size_t i = 0; i < values.extent(0); ++i) total += values(i);
  return total;
}

// Every set edge (a, b) is an edge that some quad traverses from a to b.
bool isTraversedEdge(const HostQuadMesh& mesh, const perishell::mesh::MeshEdge& edge) {
  for (int e = 0; e < mesh.numElements(); ++e)
    for (int k = 0; k < 4; ++k)
      if (mesh.quads(e, k) == edge.first && mesh.quads(e, (k + 1) % 4) == edge.second) return true;
  return false;
}

void expectEdgeSet(const ShellMesh& shell, const std::string& name, std::size_t numEdges) {
  const auto& edges = shell.sets.edgeSet(name);
  EXPECT_EQ(edges.size(), numEdges) << name;
  for (const auto& edge : edges) EXPECT_TRUE(isTraversedEdge(shell.mesh, edge)) << name;
  // The edge set's nodes are exactly the node set of the same name.
  std::set<LocalIndex> edgeNodes;
  for (const auto& edge : edges) edgeNodes.insert({edge.first, edge.second});
  const auto& nodes = shell.sets.nodeSet(name);
  EXPECT_EQ(std::vector<LocalIndex>(edgeNodes.begin(), edgeNodes.end()), nodes) << name;
}

std::vector<int> quadsPerNode(const HostQuadMesh& mesh) {
  std::vector<int> count(mesh.numNodes(), 0);
  for (int e = 0; e < mesh.numElements(); ++e)
    for (int a = 0; a < 4; ++a) ++count[mesh.quads(e, a)];
  return count;
}

template <class FunctionT>
void expectInvalidArgument(FunctionT&& makeMesh, const std::string& expectedPart) {
  try {
    makeMesh();
    ADD_FAILURE() << "no exception; expected one mentioning '" << expectedPart << "'";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find(expectedPart), std::string::npos) << error.what();
  }
}

TEST(TEST_CATEGORY, generated_plate_counts_sets_normals_and_volumes) {
  const double lengthX = 0.3, lengthY = 0.1, thickness = 1e-3;
  const auto shell = perishell::mesh::makePlate(lengthX, lengthY, 0.01);
  const auto& mesh = shell.mesh;
  ASSERT_EQ(mesh.numNodes(), 31 * 11);
  ASSERT_EQ(mesh.numElements(), 30 * 10);

  const auto& sets = shell.sets;
  expectEdgeSet(shell, "bottom", 30);
  expectEdgeSet(shell, "right", 10);
  expectEdgeSet(shell, "top", 30);
  expectEdgeSet(shell, "left", 10);
  auto expectOnLine = [&](const char* name, int axis, double value) {
    for (LocalIndex node : sets.nodeSet(name)) EXPECT_EQ(mesh.coordinates(node, axis), value) << name;
  };
  expectOnLine("left", 0, 0.0);
  expectOnLine("right", 0, lengthX);
  expectOnLine("bottom", 1, 0.0);
  expectOnLine("top", 1, lengthY);
  EXPECT_EQ(sets.nodeSet("bottom-left"), std::vector<LocalIndex>{0});
  EXPECT_EQ(sets.nodeSet("bottom-right"), std::vector<LocalIndex>{30});
  EXPECT_EQ(sets.nodeSet("top-right"), std::vector<LocalIndex>{31 * 11 - 1});
  EXPECT_EQ(sets.nodeSet("top-left"), std::vector<LocalIndex>{31 * 10});
  EXPECT_EQ(sets.nodeSet("boundary").size(), 2u * (30 + 10));

  const auto normals = nodeNormalsOnHost<TEST_EXECSPACE>(mesh);
  for (int node = 0; node < mesh.numNodes(); ++node) {
    EXPECT_EQ(normals(node, 0), 0.0);
    EXPECT_EQ(normals(node, 1), 0.0);
    EXPECT_EQ(normals(node, 2), 1.0);
  }
  const auto volumes = nodeVolumesOnHost<TEST_EXECSPACE>(mesh, thickness);
  const double volume = lengthX * lengthY * thickness;
  EXPECT_NEAR(sum(volumes), volume, 1e-13 * volume);
  // A corner node carries a quarter cell.
  EXPECT_NEAR(volumes(0), 0.25 * 0.01 * 0.01 * thickness, 1e-12 * volume);
}

TEST(TEST_CATEGORY, generated_cylinder_closes_its_seam_with_radial_normals) {
  const double radius = 0.1, height = 0.3, thickness = 3.048e-3;
  const auto shell = perishell::mesh::makeCylinder(radius, height, 0.02);
  const auto& mesh = shell.mesh;
  const int around = 31, along = 15;  // round(2 pi 0.1 / 0.02) = round(31.4), round(15)
  ASSERT_EQ(mesh.numNodes(), around * (along + 1));
  ASSERT_EQ(mesh.numElements(), around * along);

  // Closed seam: no two nodes coincide, rim nodes touch 2 quads and all others 4.
  for (int a = 0; a < mesh.numNodes(); ++a)
    for (int b = a + 1; b < mesh.numNodes(); ++b) {
      const double dx = mesh.coordinates(a, 0) - mesh.coordinates(b, 0);
      const double dy = mesh.coordinates(a, 1) - mesh.coordinates(b, 1);
      const double dz = mesh.coordinates(a, 2) - mesh.coordinates(b, 2);
      ASSERT_GT(dx * dx + dy * dy + dz * dz, 1e-6 * 0.02 * 0.02) << "nodes " << a << ", " << b;
    }
  const auto count = quadsPerNode(mesh);
  for (int node = 0; node < mesh.numNodes(); ++node) {
    const bool onRim = node < around || node >= around * along;
    EXPECT_EQ(count[node], onRim ? 2 : 4) << "node " << node;
  }
  expectEdgeSet(shell, "bottom", around);
  expectEdgeSet(shell, "top", around);
  for (LocalIndex node : shell.sets.nodeSet("bottom")) EXPECT_EQ(mesh.coordinates(node, 2), 0.0);
  for (LocalIndex node : shell.sets.nodeSet("top")) EXPECT_EQ(mesh.coordinates(node, 2), height);

  // Facet area: n flat rectangles of width 2 r sin(pi / n).
  const auto volumes = nodeVolumesOnHost<TEST_EXECSPACE>(mesh, thickness);
  const double facetArea = around * 2.0 * radius * std::sin(pi / around) * height;
  EXPECT_NEAR(sum(volumes), facetArea * thickness, 1e-13 * facetArea * thickness);

  // A node's two facet columns are mirror images about its radial plane with equal areas,
  // so the area-weighted normal is exactly radial; only round-off of cos/sin (~1e-16) and
  // of the sums remains.
  const auto normals = nodeNormalsOnHost<TEST_EXECSPACE>(mesh);
  double worst = 0.0;
  for (int node = 0; node < mesh.numNodes(); ++node) {
    const double x = mesh.coordinates(node, 0), y = mesh.coordinates(node, 1);
    const double r = std::hypot(x, y);
    worst = std::max({worst, std::abs(normals(node, 0) - x / r), std::abs(normals(node, 1) - y / r),
                      std::abs(normals(node, 2))});
  }
  EXPECT_LT(worst, 1e-14);
}

TEST(TEST_CATEGORY, generated_hexagonal_prism_faces_sets_and_normals) {
  const double side = 0.05, length = 0.12, thickness = 2e-3;
  const auto shell = perishell::mesh::makeHexagonalPrism(side, length, 0.01);
  const auto& mesh = shell.mesh;
  const int across = 5, along = 12, ringSize = 6 * across;
  ASSERT_EQ(mesh.numNodes(), ringSize * (along + 1));
  ASSERT_EQ(mesh.numElements(), ringSize * along);
  expectEdgeSet(shell, "bottom", ringSize);
  expectEdgeSet(shell, "top", ringSize);

  const auto volumes = nodeVolumesOnHost<TEST_EXECSPACE>(mesh, thickness);
  const double area = 6.0 * side * length;
  EXPECT_NEAR(sum(volumes), area * thickness, 1e-14 * area * thickness);

  const auto normals = nodeNormalsOnHost<TEST_EXECSPACE>(mesh);
  const double apothem = 0.5 * std::sqrt(3.0) * side;
  std::vector<int> facesOfNode(mesh.numNodes(), 0);
  for (int face = 0; face < 6; ++face) {
    const std::string name = "face-" + std::to_string(face);
    const auto& elements = shell.sets.elementSet(name);
    const auto& nodes = shell.sets.nodeSet(name);
    ASSERT_EQ(elements.size(), std::size_t(across * along)) << name;
    ASSERT_EQ(nodes.size(), std::size_t((across + 1) * (along + 1))) << name;
    const double angle = pi / 3.0 * face + pi / 6.0;
    const double n[2] = {std::cos(angle), std::sin(angle)};
    // Every node of the face lies on the face's plane n . x = apothem.
    for (LocalIndex node : nodes) {
      EXPECT_NEAR(n[0] * mesh.coordinates(node, 0) + n[1] * mesh.coordinates(node, 1), apothem, 1e-15)
          << name << " node " << node;
      ++facesOfNode[node];
    }
    for (LocalIndex element : elements)
      for (int a = 0; a < 4; ++a)
        EXPECT_TRUE(std::binary_search(nodes.begin(), nodes.end(), mesh.quads(element, a))) << name;
  }
  // Face-interior nodes: the face normal; prism-edge nodes: the bisector of two equal faces.
  for (int node = 0; node < mesh.numNodes(); ++node) {
    const int ringPoint = node % ringSize;
    const int face = ringPoint / across;
    const bool onPrismEdge = ringPoint % across == 0;
    ASSERT_EQ(facesOfNode[node], onPrismEdge ? 2 : 1) << "node " << node;
    const double angle = pi / 3.0 * face + (onPrismEdge ? 0.0 : pi / 6.0);
    EXPECT_NEAR(normals(node, 0), std::cos(angle), 1e-15) << "node " << node;
    EXPECT_NEAR(normals(node, 1), std::sin(angle), 1e-15) << "node " << node;
    EXPECT_NEAR(normals(node, 2), 0.0, 1e-15) << "node " << node;
  }
}

TEST(TEST_CATEGORY, generators_reproduce_paper_element_counts) {
  // Paper examples: plate 90 x 30 mm at 1 mm; cylinder H 600 mm, diameter 200 mm at 4.5 mm
  // (paper: 18,621 elements); prism L 304.8 mm, side 65.33 mm at 2.5 mm (paper: 19,052).
  EXPECT_EQ(perishell::mesh::makePlate(0.09, 0.03, 0.001).mesh.numElements(), 90 * 30);
  EXPECT_EQ(perishell::mesh::makeCylinder(0.1, 0.6, 0.0045).mesh.numElements(), 140 * 133);
  EXPECT_EQ(perishell::mesh::makeHexagonalPrism(0.06533, 0.3048, 0.0025).mesh.numElements(), 6 * 26 * 122);
}

TEST(TEST_CATEGORY, generators_reject_bad_sizes_naming_the_parameter) {
  using namespace perishell::mesh;
  expectInvalidArgument([] { makePlate(0.0, 1.0, 0.1); }, "rectangular plate: length x must be positive");
  expectInvalidArgument([] { makePlate(1.0, 1.0, NAN); }, "rectangular plate: spacing must be positive");
  expectInvalidArgument([] { makePlate(1.0, 0.01, 0.1); }, "gives 0 cell(s) along y");
  expectInvalidArgument([] { makePlate(1.0, 1.0, 1e-300); }, "more than a mesh can index");
  expectInvalidArgument([] { makeCylinder(-0.1, 1.0, 0.1); }, "cylinder: radius must be positive");
  expectInvalidArgument([] { makeCylinder(0.1, INFINITY, 0.1); }, "cylinder: height must be positive");
  expectInvalidArgument([] { makeCylinder(0.01, 1.0, 0.05); },
                        "gives 1 cell(s) around the circumference");
  expectInvalidArgument([] { makeCylinder(1.0, 1.0, 1e-5); }, "nodes exceed the index range");
  expectInvalidArgument([] { makeHexagonalPrism(0.0, 1.0, 0.1); },
                        "hexagonal prism: side length must be positive");
  expectInvalidArgument([] { makeHexagonalPrism(0.1, 0.001, 0.01); }, "cell(s) along the prism");
}

TEST(TEST_CATEGORY, node_geometry_rejects_nodes_outside_quads_and_bad_thickness) {
  auto mesh = perishell::mesh::makeRectangularPlate(1.0, 1.0, 1, 1);
  HostVectors withStrayNode("coordinates", 5);
  for (int node = 0; node < 4; ++node)
    for (int k = 0; k < 3; ++k) withStrayNode(node, k) = mesh.coordinates(node, k);
  mesh.coordinates = withStrayNode;
  try {
    nodeNormalsOnHost<TEST_EXECSPACE>(mesh);
    ADD_FAILURE() << "no exception for a node outside every quad";
  } catch (const std::runtime_error& error) {
    EXPECT_STREQ(error.what(), "node normals: node 4 has no normal (it belongs to no quad, or its "
                               "quads have zero area)");
  }
  EXPECT_THROW(nodeVolumesOnHost<TEST_EXECSPACE>(mesh, 0.0), std::invalid_argument);
}

TEST(TEST_CATEGORY, make_crack_normalises_and_rejects_degenerate_input) {
  using perishell::mesh::makeCrack;
  const auto crack = makeCrack({0.05, 0.0, 0.0}, {0.05, 0.02, 0.0}, {0.0, 0.0, 2.0});
  EXPECT_EQ(crack.start[0], 0.05);
  EXPECT_EQ(crack.end[1], 0.02);
  EXPECT_EQ(crack.normal[2], 1.0);
  expectInvalidArgument([] { makeCrack({1.0, 1.0, 0.0}, {1.0, 1.0, 0.0}, {0.0, 0.0, 1.0}); },
                        "crack: start and end coincide");
  expectInvalidArgument([] { makeCrack({0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {0.0, 0.0, 0.0}); },
                        "crack: normal is the zero vector");
  expectInvalidArgument([] { makeCrack({0.0, 0.0, 0.0}, {1.0, 0.0, 0.0}, {-3.0, 0.0, 0.0}); },
                        "crack: normal is parallel to the segment");
  expectInvalidArgument([] { makeCrack({0.0, NAN, 0.0}, {1.0, 0.0, 0.0}, {0.0, 0.0, 1.0}); },
                        "crack: start has a non-finite component");
}

}  // namespace generators_test
