// Gmsh MSH 4.1 import: the hand-written tests/data/plate_4x2.msh equals the generated
// 0.4 m x 0.2 m plate (nodes, quads, orientation, area, sets); orientation repair; files
// in the style of Mesh.SaveAll = 0; one "file:line: reason" message per reader error; and the
// quad shape checks (coincident corners, zero area, bow-tie, re-entrant corner).
#include <perishell/mesh/generators.hpp>
#include <perishell/mesh/gmsh_reader.hpp>
#include <perishell/mesh/node_geometry.hpp>
#include <perishell/mesh/quad_shape.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace gmsh_reader_test {

using perishell::LocalIndex;
using perishell::mesh::HostQuadMesh;
using perishell::mesh::MeshEdge;
using perishell::mesh::ShellMesh;

// tests/data, next to this file's directory; PERISHELL_TEST_DATA_DIR overrides it where the
// binaries run away from the source tree.
std::string dataPath(const std::string& name) {
  if (const char* directory = std::getenv("PERISHELL_TEST_DATA_DIR")) return std::string(directory) + "/" + name;
  std::string here = __FILE__;
  here = here.substr(0, here.find_last_of('/'));           // tests/mesh
  return here.substr(0, here.find_last_of('/')) + "/data/" + name;  // tests/data
}

std::string plateText() {
  std::ifstream file(dataPath("plate_4x2.msh"));
  std::ostringstream text;
  text << file.rdbuf();
  return text.str();
}

// The text with `from` (which must occur) replaced by `to`.
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto position = text.find(from);
  EXPECT_NE(position, std::string::npos) << from;
  if (position != std::string::npos) text.replace(position, from.size(), to);
  return text;
}

template <class ExecutionSpaceT>
perishell::CoordinateView<Kokkos::HostSpace> nodeNormalsOnHost(const HostQuadMesh& hostMesh) {
  const auto mesh = perishell::mesh::mirrorTo<typename ExecutionSpaceT::memory_space>(hostMesh);
  return Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{},
                                             perishell::mesh::computeNodeNormals(ExecutionSpaceT{}, mesh));
}

template <class ExecutionSpaceT>
double totalArea(const HostQuadMesh& hostMesh) {
  const auto mesh = perishell::mesh::mirrorTo<typename ExecutionSpaceT::memory_space>(hostMesh);
  const auto areas = Kokkos::create_mirror_view_and_copy(
      Kokkos::HostSpace{}, perishell::mesh::computeNodeAreas(ExecutionSpaceT{}, mesh));
  double total = 0.0;
  for (std::size_t i = 0; i < areas.extent(0); ++i) total += areas(i);
  return total;
}

std::vector<std::array<double, 3>> sortedCoordinates(const HostQuadMesh& mesh) {
  std::vector<std::array<double, 3>> points(mesh.numNodes());
  for (int node = 0; node < mesh.numNodes(); ++node)
    for (int k = 0; k < 3; ++k) points[node][k] = mesh.coordinates(node, k);
  std::sort(points.begin(), points.end());
  return points;
}

// For each imported node, the generated node at the same place (within 1e-12 m), or -1.
std::vector<LocalIndex> matchNodes(const HostQuadMesh& imported, const HostQuadMesh& generated) {
  std::vector<LocalIndex> match(imported.numNodes(), -1);
  for (int i = 0; i < imported.numNodes(); ++i)
    for (int g = 0; g < generated.numNodes(); ++g) {
      double distance = 0.0;
      for (int k = 0; k < 3; ++k)
        distance = std::max(distance, std::abs(imported.coordinates(i, k) - generated.coordinates(g, k)));
      if (distance < 1e-12) match[i] = g;
    }
  return match;
}

// A quad's nodes rotated to start at the smallest index: equal for the same oriented quad.
std::array<LocalIndex, 4> canonicalQuad(std::array<LocalIndex, 4> quad) {
  std::rotate(quad.begin(), std::min_element(quad.begin(), quad.end()), quad.end());
  return quad;
}

std::vector<std::array<LocalIndex, 4>> orientedQuads(const HostQuadMesh& mesh,
                                                     const std::vector<LocalIndex>& rename) {
  std::vector<std::array<LocalIndex, 4>> quads(mesh.numElements());
  for (int e = 0; e < mesh.numElements(); ++e) {
    for (int a = 0; a < 4; ++a) quads[e][a] = rename[mesh.quads(e, a)];
    quads[e] = canonicalQuad(quads[e]);
  }
  std::sort(quads.begin(), quads.end());
  return quads;
}

std::vector<LocalIndex> renamedNodes(const std::vector<LocalIndex>& nodes, const std::vector<LocalIndex>& rename) {
  std::vector<LocalIndex> result;
  for (LocalIndex node : nodes) result.push_back(rename[node]);
  std::sort(result.begin(), result.end());
  return result;
}

std::vector<MeshEdge> renamedEdges(const std::vector<MeshEdge>& edges, const std::vector<LocalIndex>& rename) {
  std::vector<MeshEdge> result;
  for (const auto& edge : edges) result.emplace_back(rename[edge.first], rename[edge.second]);
  std::sort(result.begin(), result.end());
  return result;
}

std::vector<MeshEdge> sortedEdges(std::vector<MeshEdge> edges) {
  std::sort(edges.begin(), edges.end());
  return edges;
}

std::vector<LocalIndex> identity(int size) {
  std::vector<LocalIndex> result(size);
  for (int i = 0; i < size; ++i) result[i] = i;
  return result;
}

std::string readerError(const std::string& text) {
  try {
    perishell::mesh::parseGmsh(text, "mem.msh");
  } catch (const std::runtime_error& error) {
    return error.what();
  }
  return "no error";
}

std::string fileError(const std::string& path) {
  try {
    perishell::mesh::readGmsh(path);
  } catch (const std::runtime_error& error) {
    return error.what();
  }
  return "no error";
}

TEST(TEST_CATEGORY, gmsh_plate_equals_generated_plate) {
  const ShellMesh imported = perishell::mesh::readGmsh(dataPath("plate_4x2.msh"));
  const ShellMesh generated = perishell::mesh::makePlate(0.4, 0.2, 0.1);
  ASSERT_EQ(imported.mesh.numNodes(), 15);
  ASSERT_EQ(imported.mesh.numElements(), 8);
  ASSERT_EQ(generated.mesh.numNodes(), 15);

  const auto importedPoints = sortedCoordinates(imported.mesh);
  const auto generatedPoints = sortedCoordinates(generated.mesh);
  for (int i = 0; i < 15; ++i)
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(importedPoints[i][k], generatedPoints[i][k], 1e-15) << "sorted node " << i;

  const auto toGenerated = matchNodes(imported.mesh, generated.mesh);
  for (LocalIndex g : toGenerated) ASSERT_GE(g, 0);
  // Same quads with the same counter-clockwise orientation.
  EXPECT_EQ(orientedQuads(imported.mesh, toGenerated), orientedQuads(generated.mesh, identity(15)));
  const auto normals = nodeNormalsOnHost<TEST_EXECSPACE>(imported.mesh);
  for (int node = 0; node < 15; ++node) {
    EXPECT_EQ(normals(node, 0), 0.0);
    EXPECT_EQ(normals(node, 1), 0.0);
    EXPECT_EQ(normals(node, 2), 1.0);
  }
  EXPECT_NEAR(totalArea<TEST_EXECSPACE>(imported.mesh), 0.08, 1e-16);

  const auto& sets = imported.sets;
  for (const char* side : {"left", "right"}) {
    EXPECT_EQ(renamedNodes(sets.nodeSet(side), toGenerated), generated.sets.nodeSet(side)) << side;
    EXPECT_EQ(renamedEdges(sets.edgeSet(side), toGenerated), sortedEdges(generated.sets.edgeSet(side))) << side;
  }
  EXPECT_EQ(sets.elementSet("plate"), identity(8));
  EXPECT_EQ(sets.nodeSet("plate"), identity(15));
  EXPECT_EQ(sets.nodeSets.size(), 3u);
  EXPECT_EQ(sets.edgeSets.size(), 2u);
  EXPECT_EQ(sets.elementSets.size(), 1u);
}

// tests/data/plate_triangle.msh: plate_4x2.msh with its first quad (tags 1 5 13 12) cut into
// the triangles 1 5 13 and 1 13 12, written after the quads.
std::string mixedPlateText() {
  std::ifstream file(dataPath("plate_triangle.msh"));
  std::ostringstream text;
  text << file.rdbuf();
  return text.str();
}

// The z component of each triangle's vector area, (x1 - x0) x (x2 - x0).
std::vector<double> triangleNormalsZ(const HostQuadMesh& mesh) {
  std::vector<double> normals;
  for (LocalIndex e = 0; e < mesh.numElements(); ++e) {
    if (!perishell::mesh::isTriangle(mesh.quads, e)) continue;
    const auto x = [&](int a, int k) { return mesh.coordinates(mesh.quads(e, a), k); };
    normals.push_back((x(1, 0) - x(0, 0)) * (x(2, 1) - x(0, 1)) - (x(1, 1) - x(0, 1)) * (x(2, 0) - x(0, 0)));
  }
  return normals;
}

TEST(TEST_CATEGORY, gmsh_mixed_quads_and_triangles_are_read) {
  const ShellMesh mixed = perishell::mesh::parseGmsh(mixedPlateText(), "mixed.msh");
  ASSERT_EQ(mixed.mesh.numNodes(), 15);
  ASSERT_EQ(mixed.mesh.numElements(), 9);
  const auto triangleNormals = triangleNormalsZ(mixed.mesh);
  ASSERT_EQ(triangleNormals.size(), 2u);
  for (const double z : triangleNormals) EXPECT_NEAR(z, 0.01, 1e-15);  // 2 x 0.005 m^2, along +z
  EXPECT_NEAR(totalArea<TEST_EXECSPACE>(mixed.mesh), 0.08, 1e-16);
  const auto normals = nodeNormalsOnHost<TEST_EXECSPACE>(mixed.mesh);
  for (int node = 0; node < 15; ++node) EXPECT_EQ(normals(node, 2), 1.0) << node;
  EXPECT_EQ(mixed.sets.elementSet("plate").size(), 9u);
  const ShellMesh generated = perishell::mesh::makePlate(0.4, 0.2, 0.1);
  const auto toGenerated = matchNodes(mixed.mesh, generated.mesh);
  EXPECT_EQ(renamedEdges(mixed.sets.edgeSet("left"), toGenerated), sortedEdges(generated.sets.edgeSet("left")));

  // A triangle written clockwise is turned to its patch's orientation; the whole patch
  // follows the first element when that is reversed.
  const auto oneFlipped = perishell::mesh::parseGmsh(replaced(mixedPlateText(), "13 1 13 12", "13 12 13 1"), "one.msh");
  for (const double z : triangleNormalsZ(oneFlipped.mesh)) EXPECT_NEAR(z, 0.01, 1e-15);
  const auto allFlipped =
      perishell::mesh::parseGmsh(replaced(mixedPlateText(), "6 5 6 14 13", "6 13 14 6 5"), "all.msh");
  for (const double z : triangleNormalsZ(allFlipped.mesh)) EXPECT_NEAR(z, -0.01, 1e-15);
  const auto flippedNormals = nodeNormalsOnHost<TEST_EXECSPACE>(allFlipped.mesh);
  for (int node = 0; node < 15; ++node) EXPECT_EQ(flippedNormals(node, 2), -1.0) << node;
}

TEST(TEST_CATEGORY, gmsh_degenerate_triangles_are_named) {
  EXPECT_EQ(readerError(replaced(mixedPlateText(), "5 1 5 13\n", "5 1 5 1\n")),
            "mem.msh:81: triangle element 5 repeats node tag 1");
  // Nodes 1, 5 and 6 lie on y = 0.
  EXPECT_EQ(readerError(replaced(mixedPlateText(), "5 1 5 13\n", "5 1 5 6\n")),
            "mem.msh:81: triangle element 5 (node tags 1 5 6) has zero area: its nodes lie on one line");
  EXPECT_EQ(readerError(replaced(mixedPlateText(), "2 1 2 2\n", "2 1 9 2\n")),
            "mem.msh:80: second-order element type 9 is not supported; mesh with Mesh.ElementOrder = 1");
}

TEST(TEST_CATEGORY, gmsh_quads_are_oriented_like_their_patch_first_quad) {
  const ShellMesh generated = perishell::mesh::makePlate(0.4, 0.2, 0.1);
  // Quad 6 written clockwise: turned back to counter-clockwise (+z).
  const auto oneFlipped = perishell::mesh::parseGmsh(replaced(plateText(), "6 5 6 14 13", "6 13 14 6 5"), "one.msh");
  const auto toGenerated = matchNodes(oneFlipped.mesh, generated.mesh);
  EXPECT_EQ(orientedQuads(oneFlipped.mesh, toGenerated), orientedQuads(generated.mesh, identity(15)));

  // The first quad written clockwise: the whole patch follows it, normals -z, edges reversed.
  const auto allFlipped = perishell::mesh::parseGmsh(replaced(plateText(), "5 1 5 13 12", "5 12 13 5 1"), "all.msh");
  const auto normals = nodeNormalsOnHost<TEST_EXECSPACE>(allFlipped.mesh);
  for (int node = 0; node < allFlipped.mesh.numNodes(); ++node) EXPECT_EQ(normals(node, 2), -1.0);
  std::vector<MeshEdge> reversedLeft;
  for (const auto& edge : generated.sets.edgeSet("left")) reversedLeft.emplace_back(edge.second, edge.first);
  const auto toGeneratedFlipped = matchNodes(allFlipped.mesh, generated.mesh);
  EXPECT_EQ(renamedEdges(allFlipped.sets.edgeSet("left"), toGeneratedFlipped), sortedEdges(reversedLeft));
}

TEST(TEST_CATEGORY, gmsh_save_all_off_style_file) {
  // As Gmsh writes with Mesh.SaveAll = 0: node tags with gaps, nodes of an entity without
  // quads (dropped), an unnamed physical point (node set "point-4").
  std::string text = plateText();
  text = replaced(text, "9 15 1 15", "10 16 1 100");
  text = replaced(text, "$EndNodes", "0 5 0 1\n100\n1 1 0\n$EndNodes");
  text = replaced(text, "1 0 0 0 0\n", "1 0 0 0 1 4\n");
  text = replaced(text, "3 12 1 12", "4 13 1 20");
  text = replaced(text, "$EndElements", "0 1 15 1\n20 1\n$EndElements");
  const auto shell = perishell::mesh::parseGmsh(text, "saveall.msh");
  EXPECT_EQ(shell.mesh.numNodes(), 15);
  EXPECT_EQ(shell.mesh.numElements(), 8);
  const auto& corner = shell.sets.nodeSet("point-4");
  ASSERT_EQ(corner.size(), 1u);
  EXPECT_EQ(shell.mesh.coordinates(corner[0], 0), 0.0);
  EXPECT_EQ(shell.mesh.coordinates(corner[0], 1), 0.0);
  EXPECT_NEAR(totalArea<TEST_EXECSPACE>(shell.mesh), 0.08, 1e-16);
}

TEST(TEST_CATEGORY, gmsh_negative_tags_keep_their_group_names_and_sets) {
  // Gmsh writes a tag negative where an entity is used reversed (Extrude, Physical Curve{-4}):
  // a signed physical tag in $Entities, an element block on a signed entity. Here the left
  // curve (entity 4) is in "left" as -1 and its lines' block names entity -4; the right
  // curve lists "right" with both signs. Names and sets come out as in the unsigned file.
  const std::string plate = plateText();
  std::string text = replaced(plate, "4 0 0 0 0 0.2 0 1 1 2 4 -1", "4 0 0 0 0 0.2 0 1 -1 2 4 -1");
  text = replaced(text, "2 0.4 0 0 0.4 0.2 0 1 2 2 2 -3", "2 0.4 0 0 0.4 0.2 0 2 -2 2 2 2 -3");
  text = replaced(text, "1 4 1 2\n3 4 12", "1 -4 1 2\n3 4 12");
  const ShellMesh signedTags = perishell::mesh::parseGmsh(text, "signed.msh");
  const ShellMesh unsignedTags = perishell::mesh::parseGmsh(plate, "plate.msh");
  EXPECT_EQ(signedTags.sets.nodeSets, unsignedTags.sets.nodeSets);
  EXPECT_EQ(signedTags.sets.edgeSets, unsignedTags.sets.edgeSets);
  EXPECT_EQ(signedTags.sets.elementSets, unsignedTags.sets.elementSets);
  EXPECT_EQ(signedTags.sets.edgeSet("left").size(), 2u);
  EXPECT_EQ(signedTags.sets.edgeSet("right").size(), 2u);  // once, though listed with both signs
  EXPECT_EQ(readerError(replaced(plate, "1 4 1 2\n3 4 12", "1 0 1 2\n3 4 12")),
            "mem.msh:69: an element block's entity tag 0 is not a Gmsh tag (tags start at 1)");
}

TEST(TEST_CATEGORY, gmsh_written_cylinder_joins_its_patches) {
  // Written by gmsh 4.8.4 (Mesh.SaveAll = 0) from: four quarter circles of radius 0.1 with
  // 3 nodes each, extruded 0.3 along z in 2 recombined layers; Physical Surface("wall") = the
  // four patches, Physical Curve("bottom") = the circles. The circle centre and its
  // extruded copy lie on no quad and are dropped.
  const ShellMesh shell = perishell::mesh::readGmsh(dataPath("cylinder_gmsh.msh"));
  const auto& mesh = shell.mesh;
  const double pi = 3.14159265358979323846;
  ASSERT_EQ(mesh.numNodes(), 8 * 3);
  ASSERT_EQ(mesh.numElements(), 8 * 2);
  // Patches share their seam nodes: each node is in 2 (rims) or 4 quads.
  std::vector<int> quadsPerNode(mesh.numNodes(), 0);
  for (int e = 0; e < mesh.numElements(); ++e)
    for (int a = 0; a < 4; ++a) ++quadsPerNode[mesh.quads(e, a)];
  for (int node = 0; node < mesh.numNodes(); ++node) {
    const double z = mesh.coordinates(node, 2);
    EXPECT_EQ(quadsPerNode[node], (z == 0.0 || z == 0.3) ? 2 : 4) << "node " << node;
  }
  EXPECT_NEAR(totalArea<TEST_EXECSPACE>(mesh), 8 * 2.0 * 0.1 * std::sin(pi / 8) * 0.3, 1e-12);
  // Gmsh orients the four patches alike; the normals come out radial (outward here).
  const auto normals = nodeNormalsOnHost<TEST_EXECSPACE>(mesh);
  for (int node = 0; node < mesh.numNodes(); ++node) {
    const double x = mesh.coordinates(node, 0), y = mesh.coordinates(node, 1);
    EXPECT_NEAR((normals(node, 0) * x + normals(node, 1) * y) / std::hypot(x, y), 1.0, 1e-12) << "node " << node;
  }
  EXPECT_EQ(shell.sets.elementSet("wall"), identity(16));
  EXPECT_EQ(shell.sets.edgeSet("bottom").size(), 8u);
  ASSERT_EQ(shell.sets.nodeSet("bottom").size(), 8u);
  for (LocalIndex node : shell.sets.nodeSet("bottom")) EXPECT_EQ(mesh.coordinates(node, 2), 0.0);
}

// A 4-quad Moebius band: rails a0..a3 (tags 1-4) and b0..b3 (tags 5-8); the last quad
// joins a3-b3 to b0-a0 with a half twist.
// A Moebius strip of 6 quads (radius 1, width 0.4, a half twist): each quad is a valid shape,
// the surface is not orientable.
std::string moebiusText() {
  const double pi = 3.14159265358979323846;
  std::ostringstream text;
  text.precision(17);
  text << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 12 1 12\n2 1 0 12\n";
  for (int tag = 1; tag <= 12; ++tag) text << tag << "\n";
  for (int column = 0; column < 6; ++column) {
    const double angle = 2.0 * pi * column / 6.0;
    const double across[3] = {std::cos(angle / 2) * std::cos(angle), std::cos(angle / 2) * std::sin(angle),
                              std::sin(angle / 2)};
    for (const double side : {-0.2, 0.2})
      text << std::cos(angle) + side * across[0] << " " << std::sin(angle) + side * across[1] << " "
           << side * across[2] << "\n";
  }
  // Column c has the node tags 2c + 1 (inner side) and 2c + 2; past the last column the
  // half twist joins the inner side to column 0's outer one.
  text << "$EndNodes\n$Elements\n1 6 1 6\n2 1 3 6\n";
  for (int column = 0; column < 5; ++column)
    text << column + 1 << " " << 2 * column + 1 << " " << 2 * column + 3 << " " << 2 * column + 4 << " "
         << 2 * column + 2 << "\n";
  text << "6 11 2 1 12\n$EndElements\n";
  return text.str();
}

TEST(TEST_CATEGORY, gmsh_reader_errors_name_file_line_and_reason) {
  const std::string plate = plateText();
  EXPECT_EQ(fileError("/nonexistent/plate.msh"),
            "/nonexistent/plate.msh:0: cannot open the file (No such file or directory)");
  EXPECT_EQ(readerError(replaced(plate, "4.1 0 8", "2.2 0 8")),
            "mem.msh:2: MSH version 2.2 is not supported; save as MSH 4.1 (Mesh.MshFileVersion = 4.1)");
  EXPECT_EQ(readerError(replaced(plate, "4.1 0 8", "4.1 1 8")),
            "mem.msh:2: binary MSH files are not supported; save as ASCII (Mesh.Binary = 0)");
  EXPECT_EQ(readerError("$Nodes\n"), "mem.msh:1: expected $MeshFormat first (is this a Gmsh MSH file?), got '$Nodes'");
  EXPECT_EQ(fileError(dataPath("plate_truncated.msh")),
            dataPath("plate_truncated.msh") +
                ":40: truncated $Nodes section: the file ends while reading a node coordinate");
  EXPECT_EQ(readerError(replaced(plate, "12 15 8 3 9", "12 15 8 3 99")),
            "mem.msh:80: element 12 refers to unknown node tag 99");
  EXPECT_EQ(readerError(replaced(plate, "2 8 3\n", "2 8 4\n")),
            "mem.msh:68: line element 2 (node tags 8 4) is not an edge of any quad or triangle");
  EXPECT_EQ(readerError(replaced(plate, "9 15 1 15", "9 16 1 15")),
            "mem.msh:23: the header announces 16 nodes but the blocks hold 15");
  EXPECT_EQ(readerError(replaced(plate, "0.2 0.1 0\n", "0.2 abc 0\n")),
            "mem.msh:61: expected a node coordinate (a finite number), got 'abc'");
  EXPECT_EQ(readerError(replaced(plate, "2 1 3 8", "2 9 3 8")),
            "mem.msh:72: element block on surface 9, which $Entities does not list");
  EXPECT_EQ(readerError(replaced(plate, "$EndElements", "$EndElement")),
            "mem.msh:81: expected $EndElements, got '$EndElement'");
  EXPECT_EQ(readerError(replaced(plate, "14 15 9 10", "14 15 9 14")),
            "mem.msh:79: quad element 11 repeats node tag 14");
  EXPECT_EQ(readerError(moebiusText()),
            "mem.msh:38: elements 5 and 4 cannot be oriented consistently: the surface is not orientable");
}

// Each defect on its own, in both orientations; a valid quad passes in both orientations and
// when warped out of its plane.
TEST(TEST_CATEGORY, quad_shape_check_names_each_defect_in_either_orientation) {
  using perishell::mesh::checkQuadShape;
  using perishell::mesh::QuadShapeDefect;
  using Quad = std::array<std::array<double, 3>, 4>;
  const auto reversed = [](Quad quad) {
    std::swap(quad[1], quad[3]);
    return quad;
  };
  const auto defectOf = [&](const Quad& quad) { return checkQuadShape(quad).defect; };
  const Quad square = {{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}};
  const Quad warped = {{{0, 0, 0}, {1, 0, 0.05}, {1, 1, 0}, {0, 1, 0.05}}};
  const Quad skewed = {{{0, 0, 0}, {2e-3, 0, 0}, {3e-3, 1e-3, 0}, {1e-3, 1e-3, 0}}};
  for (const Quad& valid : {square, warped, skewed}) {
    EXPECT_EQ(defectOf(valid), QuadShapeDefect::none);
    EXPECT_EQ(defectOf(reversed(valid)), QuadShapeDefect::none);
  }
  const Quad coincident = {{{0, 0, 0}, {1, 0, 0}, {1, 0, 0}, {0, 1, 0}}};
  const auto check = checkQuadShape(coincident);
  EXPECT_EQ(check.defect, QuadShapeDefect::coincidentCorners);
  EXPECT_EQ(check.corner, 1);
  EXPECT_EQ(check.otherCorner, 2);
  const Quad collinear = {{{0, 0, 0}, {1, 0, 0}, {0.7, 0, 0}, {0.5, 0, 0}}};
  EXPECT_EQ(defectOf(collinear), QuadShapeDefect::zeroArea);
  // A symmetric bow-tie (no net area) and a lopsided one (the lobes' areas differ).
  const Quad figureEight = {{{0, 0, 0}, {1, 1, 0}, {1, 0, 0}, {0, 1, 0}}};
  const Quad lopsided = {{{0, 0, 0}, {2, 0, 0}, {0, 1, 0}, {1, 1, 0}}};
  for (const Quad& crossing : {figureEight, lopsided}) {
    EXPECT_EQ(defectOf(crossing), QuadShapeDefect::selfCrossing);
    EXPECT_EQ(defectOf(reversed(crossing)), QuadShapeDefect::selfCrossing);
  }
  const Quad dart = {{{0, 0, 0}, {1, 0, 0}, {0.3, 0.3, 0}, {0, 1, 0}}};
  EXPECT_EQ(checkQuadShape(dart).defect, QuadShapeDefect::reentrantCorner);
  EXPECT_EQ(checkQuadShape(dart).corner, 2);
  EXPECT_EQ(checkQuadShape(reversed(dart)).corner, 2);
  const Quad straightCorner = {{{0, 0, 0}, {1, 0, 0}, {0.5, 0.5, 0}, {0, 1, 0}}};
  EXPECT_EQ(checkQuadShape(straightCorner).defect, QuadShapeDefect::reentrantCorner);
  EXPECT_EQ(checkQuadShape(straightCorner).corner, 2);
}

// The reader refuses a quad it cannot build an element on, by tags and line, before anything
// is built (element 5 of plate_4x2.msh, file line 73, is the first quad of node 13).
TEST(TEST_CATEGORY, gmsh_reader_refuses_misshapen_quads_by_tags_and_line) {
  const std::string plate = plateText();
  EXPECT_EQ(readerError(replaced(plate, "\n5 1 5 13 12\n", "\n5 1 13 5 12\n")),
            "mem.msh:73: quad element 5 (node tags 1 13 5 12) crosses itself (a bow-tie): its nodes are not "
            "listed in order around its outline");
  EXPECT_EQ(readerError(replaced(plate, "\n0.1 0.1 0\n", "\n0.03 0.03 0\n")),
            "mem.msh:73: quad element 5 (node tags 1 5 13 12) is not convex: its corner at node 13 points "
            "inward or is straight, where the element map folds");
  EXPECT_EQ(readerError(replaced(plate, "\n0.1 0.1 0\n", "\n0.1 0 0\n")),
            "mem.msh:73: quad element 5 (node tags 1 5 13 12): nodes 5 and 13 are at the same point; a quad "
            "needs four distinct corners");
  EXPECT_EQ(readerError(replaced(replaced(plate, "\n0 0.1 0\n", "\n0.05 0 0\n"), "\n0.1 0.1 0\n", "\n0.07 0 0\n")),
            "mem.msh:73: quad element 5 (node tags 1 5 13 12) has zero area: its nodes lie on one line");
}

}  // namespace gmsh_reader_test
