// The support layer (mesh/support_layer.hpp): beyond clamped edges of a plate, the mirror
// images of the elements within the depth, corners filled, nodes shared with the edge.
#include <perishell/mesh/generators.hpp>
#include <perishell/mesh/node_geometry.hpp>
#include <perishell/io/deck.hpp>
#include <perishell/mesh/support_layer.hpp>

#include <cmath>
#include <set>
#include <utility>

namespace support_layer_test {

using perishell::LocalIndex;

// A 1 m x 0.6 m plate at spacing 0.1 m with a layer three spacings deep beyond the edges
// of `set`.
struct LayeredPlate {
  perishell::mesh::ShellMesh plate = perishell::mesh::makePlate(1.0, 0.6, 0.1);
  LocalIndex numNodes = plate.mesh.numNodes(), numElements = plate.mesh.numElements();
  perishell::mesh::SupportLayer layer;

  explicit LayeredPlate(const std::string& set, double depth = 0.3) {
    std::vector<std::uint8_t> all(numElements, 1);
    layer = perishell::mesh::addSupportLayer(plate.mesh, {{set, plate.sets.nodesOfNodeOrEdgeSet(set)}}, all, depth, 0.1);
  }
  std::array<double, 3> node(LocalIndex n) const {
    return {plate.mesh.coordinates(n, 0), plate.mesh.coordinates(n, 1), plate.mesh.coordinates(n, 2)};
  }
};

// Grid coordinates (in spacings) of every layer node; each must lie on the plate's grid.
std::set<std::pair<long, long>> layerGridPoints(const LayeredPlate& layered) {
  std::set<std::pair<long, long>> points;
  for (LocalIndex n = layered.numNodes; n < layered.plate.mesh.numNodes(); ++n) {
    const auto x = layered.node(n);
    const long i = std::lround(x[0] / 0.1), j = std::lround(x[1] / 0.1);
    EXPECT_NEAR(x[0], 0.1 * i, 1e-12);
    EXPECT_NEAR(x[1], 0.1 * j, 1e-12);
    EXPECT_EQ(x[2], 0.0);
    EXPECT_TRUE(points.insert({i, j}).second) << "layer node " << n << " repeats a point";
  }
  return points;
}

TEST(TEST_CATEGORY, support_layer_frames_a_clamped_plate) {
  const LayeredPlate layered("boundary");
  EXPECT_EQ(layered.layer.firstNode, layered.numNodes);
  EXPECT_EQ(layered.layer.firstElement, layered.numElements);
  const auto points = layerGridPoints(layered);
  // The frame 3 elements deep (centroids within the depth) around the 10 x 6 plate: every
  // grid point within three spacings of the plate, and no other.
  for (long i = -5; i <= 15; ++i)
    for (long j = -5; j <= 11; ++j) {
      const bool inPlate = i >= 0 && i <= 10 && j >= 0 && j <= 6;
      const bool inFrame = i >= -3 && i <= 13 && j >= -3 && j <= 9 && !inPlate;
      EXPECT_EQ(points.count({i, j}), inFrame ? 1u : 0u) << i << ", " << j;
    }
  EXPECT_EQ(layered.layer.nodesOfSet.at("boundary").size(), points.size());
  EXPECT_TRUE(layered.layer.skippedSets.empty());

  // Layer elements keep the plate's orientation and tile the frame: the layer's area is
  // the frame's, and every node (the edge's included) gets its full or edge share.
  const auto mesh = perishell::mesh::mirrorTo<TEST_MEMSPACE>(layered.plate.mesh);
  const auto normals = Kokkos::create_mirror_view_and_copy(
      Kokkos::HostSpace{}, perishell::mesh::computeNodeNormals(TEST_EXECSPACE{}, mesh));
  for (LocalIndex n = 0; n < layered.plate.mesh.numNodes(); ++n) EXPECT_NEAR(normals(n, 2), 1.0, 1e-12);
  const auto areas = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{},
                                                         perishell::mesh::computeNodeVolumes(TEST_EXECSPACE{}, mesh, 1.0));
  double total = 0.0;
  for (LocalIndex n = 0; n < layered.plate.mesh.numNodes(); ++n) total += areas(n);
  const double layerElements = layered.plate.mesh.numElements() - layered.numElements;
  EXPECT_NEAR(total, 0.6 + 0.01 * layerElements, 1e-12);
  EXPECT_EQ(layerElements, 2 * 3 * (10 + 6) + 4 * 9);  // strips, and corners of 3 x 3
  for (const LocalIndex n : layered.plate.sets.nodesOfNodeOrEdgeSet("boundary")) EXPECT_NEAR(areas(n), 0.01, 1e-14);
}

TEST(TEST_CATEGORY, support_layer_beyond_one_edge_and_not_over_material) {
  const LayeredPlate left("left");
  const auto points = layerGridPoints(left);
  EXPECT_EQ(points.size(), 3u * 7u);  // columns -1 .. -3, rows 0 .. 6
  for (const auto& [i, j] : points) EXPECT_TRUE(i < 0 && j >= 0 && j <= 6);

  // A single node holds no edge: no layer, and nothing skipped.
  LayeredPlate none("bottom-left");
  EXPECT_EQ(none.plate.mesh.numNodes(), none.numNodes);
  EXPECT_TRUE(none.layer.skippedSets.empty());
}

TEST(TEST_CATEGORY, support_layer_names_sets_where_the_model_is_narrower_than_its_depth) {
  // 1 m across the left edge, 0.6 m across the bottom one.
  EXPECT_TRUE(LayeredPlate("left", 0.7).layer.narrowSets.empty());
  const LayeredPlate bottom("bottom", 0.7);
  ASSERT_EQ(bottom.layer.narrowSets.size(), 1u);
  EXPECT_EQ(bottom.layer.narrowSets.front(), "bottom");
  EXPECT_TRUE(LayeredPlate("bottom", 0.6).layer.narrowSets.empty());
}

TEST(TEST_CATEGORY, support_layer_never_covers_the_far_face_of_a_slit) {
  // Two 0.5 m x 0.6 m plates side by side, not connected: their edges at x = 0.5 coincide.
  const auto half = perishell::mesh::makeRectangularPlate(0.5, 0.6, 5, 6);
  const LocalIndex n = half.numNodes(), e = half.numElements();
  perishell::mesh::HostQuadMesh slit{perishell::CoordinateView<Kokkos::HostSpace>("slit coordinates", 2 * n),
                                     perishell::QuadConnectivityView<Kokkos::HostSpace>("slit quads", 2 * e)};
  for (LocalIndex k = 0; k < n; ++k)
    for (int d = 0; d < 3; ++d) {
      slit.coordinates(k, d) = half.coordinates(k, d);
      slit.coordinates(n + k, d) = half.coordinates(k, d) + (d == 0 ? 0.5 : 0.0);
    }
  for (LocalIndex k = 0; k < e; ++k)
    for (int a = 0; a < 4; ++a) {
      slit.quads(k, a) = half.quads(k, a);
      slit.quads(e + k, a) = n + half.quads(k, a);
    }
  std::vector<LocalIndex> slitFace, outerEdge;  // the left plate's x = 0.5 and x = 0 columns
  for (LocalIndex k = 0; k < n; ++k) {
    if (std::abs(slit.coordinates(k, 0) - 0.5) < 1e-12) slitFace.push_back(k);
    if (std::abs(slit.coordinates(k, 0)) < 1e-12) outerEdge.push_back(k);
  }
  const std::vector<std::uint8_t> all(2 * e, 1);
  const auto layer = perishell::mesh::addSupportLayer(slit, {{"slit-face", slitFace}, {"outer", outerEdge}}, all, 0.3, 0.1);
  ASSERT_EQ(layer.skippedSets.size(), 1u);
  EXPECT_EQ(layer.skippedSets.front(), "slit-face");
  EXPECT_EQ(layer.nodesOfSet.count("slit-face"), 0u);
  EXPECT_EQ(layer.nodesOfSet.at("outer").size(), 3u * 7u);
  for (LocalIndex k = layer.firstNode; k < slit.numNodes(); ++k) EXPECT_LT(slit.coordinates(k, 0), 0.0);
}

// The edge frame of a plate's edge x = const: n = +x, t = +y, z = +z.
perishell::mesh::FreeEdge edgeAlongY() {
  perishell::mesh::FreeEdge edge{};
  edge.outward = {1.0, 0.0, 0.0};
  edge.tangent = {0.0, 1.0, 0.0};
  edge.normal = {0.0, 0.0, 1.0};
  edge.length = 0.1;
  return edge;
}

std::uint8_t dofs(std::initializer_list<perishell::deck::Dof> held) {
  std::uint8_t mask = 0;
  for (const auto dof : held) mask |= std::uint8_t(1u << static_cast<int>(dof));
  return mask;
}

void expectDiagonal(const std::array<double, 9>& map, std::array<double, 3> diagonal, const char* what) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(map[3 * r + c], r == c ? diagonal[r] : 0.0, 1e-14) << what << " " << r << c;
}

TEST(TEST_CATEGORY, support_layer_mirror_maps_follow_the_held_dofs) {
  using perishell::deck::Dof;
  using perishell::mesh::mirrorMaps;
  const auto edge = edgeAlongY();
  // Symmetry plane x = const (u_n, theta_t, theta_z held): the reflection, u -> P u, theta -> -P theta.
  const auto symmetry = mirrorMaps(edge, dofs({Dof::Ux, Dof::Ry, Dof::Rz}));
  ASSERT_TRUE(symmetry);
  expectDiagonal(symmetry->displacement, {-1.0, 1.0, 1.0}, "symmetry u");
  expectDiagonal(symmetry->rotation, {1.0, -1.0, -1.0}, "symmetry theta");
  // A rigid diaphragm (u_t, w held): the antisymmetric image, u -> -P u, theta -> P theta.
  const auto diaphragm = mirrorMaps(edge, dofs({Dof::Uy, Dof::Uz}));
  ASSERT_TRUE(diaphragm);
  expectDiagonal(diaphragm->displacement, {1.0, -1.0, -1.0}, "diaphragm u");
  expectDiagonal(diaphragm->rotation, {-1.0, 1.0, 1.0}, "diaphragm theta");
  // A hinge (all displacements held): membrane held, bending odd (w and theta_n odd, theta_t even).
  const auto hinge = mirrorMaps(edge, dofs({Dof::Ux, Dof::Uy, Dof::Uz}));
  ASSERT_TRUE(hinge);
  expectDiagonal(hinge->displacement, {0.0, 0.0, -1.0}, "hinge u");
  expectDiagonal(hinge->rotation, {-1.0, 1.0, 0.0}, "hinge theta");
  // w alone leaves the membrane free, u_n alone the bending: no image is exact, none is made.
  EXPECT_FALSE(mirrorMaps(edge, dofs({Dof::Uz})));
  EXPECT_FALSE(mirrorMaps(edge, dofs({Dof::Ux})));
  // An edge at 45 degrees: u_x held is not u_n held.
  auto oblique = edge;
  oblique.outward = {std::sqrt(0.5), std::sqrt(0.5), 0.0};
  oblique.tangent = {-std::sqrt(0.5), std::sqrt(0.5), 0.0};
  EXPECT_FALSE(mirrorMaps(oblique, dofs({Dof::Ux, Dof::Ry, Dof::Rz})));
  const auto obliqueSymmetry = mirrorMaps(oblique, dofs({Dof::Ux, Dof::Uy, Dof::Rx, Dof::Ry, Dof::Rz}));
  ASSERT_TRUE(obliqueSymmetry);  // u_n, u_t held: membrane held; theta_t held, w free: bending even
  EXPECT_NEAR(obliqueSymmetry->displacement[8], 1.0, 1e-15);
  EXPECT_NEAR(obliqueSymmetry->displacement[0], 0.0, 1e-15);
}

TEST(TEST_CATEGORY, support_layer_mirrored_nodes_image_their_masters) {
  using perishell::deck::Dof;
  auto plate = perishell::mesh::makePlate(1.0, 0.6, 0.1);
  const LocalIndex numNodes = plate.mesh.numNodes();
  std::vector<std::uint8_t> all(plate.mesh.numElements(), 1);
  // Symmetry at x = 1 (mirrored), a clamp at y = 0 (held): the corner beyond both is held.
  const auto layer = perishell::mesh::addSupportLayer(
      plate.mesh,
      {{"right", plate.sets.nodesOfNodeOrEdgeSet("right"), perishell::mesh::LayerMotion::Mirrored,
        dofs({Dof::Ux, Dof::Ry, Dof::Rz})},
       {"bottom", plate.sets.nodesOfNodeOrEdgeSet("bottom")}},
      all, 0.3, 0.1);
  ASSERT_EQ(layer.mirroredNodesOfSet.count("right"), 1u);
  EXPECT_EQ(layer.mirroredNodesOfSet.at("right").size(), 3u * 6u);  // columns 11 .. 13, rows 1 .. 6
  EXPECT_EQ(layer.mirrorImages.size(), 3u * 6u);
  // The strip, the corner, and the clamp's line y = 0 beyond the symmetry plane.
  EXPECT_EQ(layer.nodesOfSet.at("bottom").size(), 3u * 11u + 3u * 3u + 3u);
  const auto x = [&](LocalIndex n, int d) { return plate.mesh.coordinates(n, d); };
  for (const auto& image : layer.mirrorImages) {
    EXPECT_GE(image.node, numNodes);
    EXPECT_LT(image.master, numNodes);
    EXPECT_NEAR(x(image.node, 0), 2.0 - x(image.master, 0), 1e-12);  // reflected across x = 1
    EXPECT_NEAR(x(image.node, 1), x(image.master, 1), 1e-12);
    EXPECT_GT(x(image.node, 1), 0.05);  // the corner's nodes are the clamp's
    expectDiagonal(image.maps.displacement, {-1.0, 1.0, 1.0}, "u");
  }
}

}  // namespace support_layer_test
