// The model a deck describes: zones (regions, PD ratio), deck node sets, set references,
// DOF counts, pre-crack placement, and the device bond list of the PD nodes.
#include <perishell/model/model.hpp>

#include <cmath>
#include <string>

namespace perishell_test_model {

// A 20 mm x 10 mm plate at 1 mm: 20 x 10 quads, 21 x 11 nodes.
std::string plateDeck(const std::string& zones, const std::string& extraMesh = "",
                      const std::string& supports = "") {
  return "perishell:\n"
         "  version: 1\n"
         "  mesh:\n"
         "    generator: plate\n"
         "    length-x: 0.020\n"
         "    length-y: 0.010\n"
         "    spacing: 1.0e-3\n" +
         extraMesh +
         "  material: {young-modulus: 72.0e9, poisson-ratio: 0.3, density: 2440.0, thickness: 1.0e-3}\n"
         "  zones:\n" +
         zones + supports + "  solver: {type: explicit, steps: 10}\n";
}

perishell::model::Model build(const std::string& text) {
  return perishell::model::buildModel(perishell::parseDeck(text, "model-test.yaml"));
}

std::string deckErrorKey(const std::string& text) {
  try {
    build(text);
  } catch (const perishell::DeckError& error) {
    return error.keyPath() + ": " + error.reason();
  }
  return "no error";
}

double centroidX(const perishell::model::Model& model, int element) {
  double x = 0.0;
  for (int a = 0; a < 4; ++a) x += 0.25 * model.shell.mesh.coordinates(model.shell.mesh.quads(element, a), 0);
  return x;
}

template <class ExecutionSpaceT>
std::size_t bondCount(const perishell::model::Model& model) {
  return perishell::model::buildPdBonds(ExecutionSpaceT{}, model).numBonds();
}

// Pairs of nodes at most 3 dx apart on an nx x ny lattice, counted directly.
std::size_t latticeBondCount(int nx, int ny) {
  std::size_t count = 0;
  for (int a = -3; a <= 3; ++a)
    for (int b = 0; b <= 3; ++b) {
      if ((b == 0 && a <= 0) || a * a + b * b > 9) continue;
      count += static_cast<std::size_t>(std::max(0, nx - std::abs(a))) * std::max(0, ny - b);
    }
  return count;
}

TEST(TEST_CATEGORY, model_all_pd_plate_counts_dofs_and_bonds) {
  const auto model = build(plateDeck("    default: pd\n", "",
                                     "  supports:\n    clamp: {set: left, dofs: [ux, uy, uz, rx, ry, rz]}\n"));
  EXPECT_EQ(model.numMeshElements(), 200);
  EXPECT_EQ(model.numPdElements, 200);
  EXPECT_DOUBLE_EQ(model.pdRatio(), 1.0);
  // The clamp's support layer: three columns of 11 nodes and 10 quads beyond x = 0, all held.
  EXPECT_EQ(model.numMeshNodes(), 231);
  EXPECT_EQ(model.numLayerNodes(), 33);
  EXPECT_EQ(model.shell.mesh.numElements(), 230);
  EXPECT_EQ(model.pdNodes.extent(0), 231u + 33u);
  EXPECT_EQ(model.numConstrainedDofs, (11 + 33) * 6);
  EXPECT_EQ(model.paperDofCount(), 200 * 24);
  EXPECT_EQ(model.freeDofCount(), 231 * 6 - 66);
  EXPECT_DOUBLE_EQ(model.horizon(), 3.0e-3);
  // The 24-column lattice without the pairs inside the layer (both ends held).
  EXPECT_EQ(bondCount<TEST_EXECSPACE>(model), latticeBondCount(24, 11) - latticeBondCount(3, 11));
}

TEST(TEST_CATEGORY, model_pd_box_flags_elements_by_centroid) {
  // Centroids sit at x = 0.5, 1.5, ... mm; the box [5, 15] mm holds columns 5..14.
  const auto model = build(plateDeck(
      "    default: ccm\n    pd-regions:\n      middle:\n"
      "        box: {min: [0.005, -1.0, -1.0], max: [0.015, 1.0, 1.0]}\n"));
  EXPECT_EQ(model.numPdElements, 100);
  EXPECT_DOUBLE_EQ(model.pdRatio(), 0.5);
  for (int element = 0; element < model.shell.mesh.numElements(); ++element) {
    const double x = centroidX(model, element);
    EXPECT_EQ(model.elementIsPd(element), (x > 0.005 && x < 0.015) ? 1 : 0) << "element " << element;
  }
  // PD nodes: the 11 node columns x = 5..15 mm, 11 rows each.
  EXPECT_EQ(model.pdNodes.extent(0), 121u);
  EXPECT_EQ(bondCount<TEST_EXECSPACE>(model), latticeBondCount(11, 11));
}

TEST(TEST_CATEGORY, model_pd_ratio_takes_the_nearest_elements) {
  const auto model = build(plateDeck(
      "    default: ccm\n    pd-ratio:\n      target: 0.25\n      around: {tip: [0.020, 0.005, 0.0]}\n"));
  EXPECT_EQ(model.numPdElements, 50);
  EXPECT_DOUBLE_EQ(model.pdRatio(), 0.25);
  double farthestPd = 0.0, nearestCcm = INFINITY;
  for (int element = 0; element < model.shell.mesh.numElements(); ++element) {
    double y = 0.0;
    for (int a = 0; a < 4; ++a) y += 0.25 * model.shell.mesh.coordinates(model.shell.mesh.quads(element, a), 1);
    const double distance = std::hypot(centroidX(model, element) - 0.020, y - 0.005);
    if (model.elementIsPd(element))
      farthestPd = std::max(farthestPd, distance);
    else
      nearestCcm = std::min(nearestCcm, distance);
  }
  EXPECT_LE(farthestPd, nearestCcm);
}

TEST(TEST_CATEGORY, model_pre_crack_removes_bonds_and_must_lie_in_pd) {
  const std::string crack =
      "    pre-cracks:\n      slit: {start: [0.0, 0.0055, 0.0], end: [0.010, 0.0055, 0.0], normal: [0, 0, 1]}\n";
  const auto intact = build(plateDeck("    default: pd\n"));
  const auto cracked = build(plateDeck("    default: pd\n", crack));
  // A cut between node rows 5 and 6 from x = 0 to 10 mm: bonds (i, j) crossing it, counted
  // directly: both ends in x <= 10 mm columns... the count is checked by the neighbour test;
  // here it must simply remove a band of bonds.
  const std::size_t removed = bondCount<TEST_EXECSPACE>(intact) - bondCount<TEST_EXECSPACE>(cracked);
  EXPECT_GT(removed, 100u);
  EXPECT_LT(removed, 400u);

  const std::string ccmBox =
      "    default: ccm\n    pd-regions:\n      far:\n        box: {min: [0.015, 0, -1], max: [0.020, 0.010, 1]}\n";
  EXPECT_EQ(deckErrorKey(plateDeck(ccmBox, crack)).rfind("mesh.pre-cracks.slit: lies outside every PD zone", 0), 0u)
      << deckErrorKey(plateDeck(ccmBox, crack));
}

// A pre-crack normal in the shell's plane would cut along the surface and separate nothing:
// refused by its key; 45 degrees off the shell normal still cuts through the thickness.
TEST(TEST_CATEGORY, model_pre_crack_normal_in_the_shell_plane_is_refused) {
  const auto crackWithNormal = [](const std::string& normal) {
    return "    pre-cracks:\n      slit: {start: [0.0, 0.0055, 0.0], end: [0.010, 0.0055, 0.0], normal: " + normal +
           "}\n";
  };
  const std::string inPlane = deckErrorKey(plateDeck("    default: pd\n", crackWithNormal("[0, 1, 0]")));
  EXPECT_EQ(inPlane.rfind("mesh.pre-cracks.slit.normal: [0, 1, 0] (unit) is 90 degrees from the shell normal [0, 0, 1]", 0),
            0u)
      << inPlane;
  EXPECT_NE(inPlane.find("separate nothing"), std::string::npos) << inPlane;
  const auto tilted = build(plateDeck("    default: pd\n", crackWithNormal("[0, 1, 1]")));
  const auto intact = build(plateDeck("    default: pd\n"));
  EXPECT_GT(bondCount<TEST_EXECSPACE>(intact) - bondCount<TEST_EXECSPACE>(tilted), 100u);
}

// Extreme but finite material values are refused by their keys, naming the scale that leaves
// double precision, before any solver reports a symptom of it.
TEST(TEST_CATEGORY, model_material_values_whose_products_overflow_or_underflow_are_refused) {
  const auto withMaterial = [](const std::string& from, const std::string& to) {
    std::string text = plateDeck("    default: pd\n");
    text.replace(text.find(from), from.size(), to);
    return deckErrorKey(text);
  };
  const std::string thin = withMaterial("thickness: 1.0e-3", "thickness: 1.0e-200");
  EXPECT_EQ(thin.rfind("material.young-modulus and material.thickness: these values make the membrane stiffness E t = "
                       "7.2e-190 N/m, outside what the solvers can carry in double precision (1e-100 to 1e+100 in SI "
                       "units)",
                       0),
            0u)
      << thin;
  const std::string bending = withMaterial("thickness: 1.0e-3", "thickness: 1.0e-40");
  EXPECT_NE(bending.find("the bending stiffness E t^3 / (12 (1 - nu^2)) = 6.59341e-111 N m"), std::string::npos) << bending;
  const std::string heavy = withMaterial("density: 2440.0", "density: 1.0e300");
  EXPECT_EQ(heavy.rfind("material.density, material.thickness and mesh.spacing: these values make a node's mass", 0), 0u)
      << heavy;
  EXPECT_EQ(withMaterial("thickness: 1.0e-3", "thickness: 1.0e-9"), "no error");
}

// Loads likewise: the nodal forces a load makes must be ordinary doubles; a zero load (a probe)
// is fine.
TEST(TEST_CATEGORY, model_loads_whose_nodal_forces_overflow_or_underflow_are_refused) {
  const auto withLoad = [](const std::string& load) {
    return deckErrorKey(plateDeck("    default: pd\n", "", "  loads:\n    " + load + "\n"));
  };
  const std::string tiny = withLoad("q: {type: pressure, value: 1.0e-95}");
  EXPECT_EQ(tiny.rfind("loads.q.value: has magnitude 1e-95 Pa, which makes nodal forces of about 1e-101 N, outside "
                       "what the solvers can carry in double precision (1e-100 to 1e+100 in SI units)",
                       0),
            0u)
      << tiny;
  const std::string huge = withLoad("pull: {type: edge-traction, set: right, vector: [1.0e200, 0.0, 0.0]}");
  EXPECT_EQ(huge.rfind("loads.pull.vector: has magnitude 1e+200 Pa", 0), 0u) << huge;
  const std::string twist = withLoad("turn: {type: point-force, set: right, moment: [0.0, 0.0, 1.0e120]}");
  EXPECT_EQ(twist.rfind("loads.turn.moment: has magnitude 1e+120 N m, which makes nodal forces of about 1e+120 N m", 0),
            0u)
      << twist;
  EXPECT_EQ(withLoad("probe: {type: point-force, set: right, vector: [0.0, 0.0, 0.0]}"), "no error");
  EXPECT_EQ(withLoad("q: {type: pressure, value: 1.0e-60}"), "no error");
}

TEST(TEST_CATEGORY, model_deck_node_sets_and_unknown_sets) {
  const std::string flank = "    node-sets:\n      flank: {box: {min: [0.0095, 0.0, -1], max: [0.0105, 0.0025, 1]}}\n";
  const auto model = build(plateDeck("    default: pd\n", flank,
                                     "  loads:\n    push: {type: point-force, set: flank, vector: [0, 0, 1.0]}\n"));
  const auto& nodes = model.shell.sets.nodeSet("flank");
  ASSERT_EQ(nodes.size(), 3u);  // x = 10 mm, y = 0, 1, 2 mm
  for (const auto node : nodes) EXPECT_NEAR(model.shell.mesh.coordinates(node, 0), 0.010, 1e-15);

  const std::string empty = "    node-sets:\n      nothing: {box: {min: [1, 1, 1], max: [2, 2, 2]}}\n";
  EXPECT_EQ(deckErrorKey(plateDeck("    default: pd\n", empty)),
            "mesh.node-sets.nothing.box: contains no node of the mesh");
  const std::string clash = "    node-sets:\n      left: {box: {min: [0, 0, -1], max: [1, 1, 1]}}\n";
  EXPECT_EQ(deckErrorKey(plateDeck("    default: pd\n", clash)),
            "mesh.node-sets.left: the mesh already has a set named 'left'");

  const std::string unknownSupport = deckErrorKey(
      plateDeck("    default: pd\n", "", "  supports:\n    clamp: {set: lefty, dofs: [ux]}\n"));
  EXPECT_EQ(unknownSupport.rfind("supports.clamp.set: mesh has no node set 'lefty' (node sets: ", 0), 0u)
      << unknownSupport;
  const std::string unknownEdge = deckErrorKey(plateDeck(
      "    default: pd\n", "", "  loads:\n    pull: {type: edge-traction, set: rim, value: 1.0e6}\n"));
  EXPECT_EQ(unknownEdge.rfind("loads.pull.set: mesh has no edge set 'rim' (edge sets: 'bottom', 'left'", 0), 0u)
      << unknownEdge;
  const std::string unknownRegionSet = deckErrorKey(plateDeck(
      "    default: ccm\n    pd-regions:\n      named: {element-set: {name: crack-zone}}\n"));
  EXPECT_EQ(unknownRegionSet.rfind("zones.pd-regions.named.element-set.name: mesh has no element set 'crack-zone'", 0),
            0u)
      << unknownRegionSet;
}

}  // namespace perishell_test_model
