// Deck loads and supports as per-node 6-DOF data: edge tractions, pressure, point
// forces/moments, load patterns per curve, follower pressures, support masks and conflicts.
#include <perishell/mesh/node_areas.hpp>
#include <perishell/model/nodal_loads.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

namespace perishell_test_nodal_loads {

using perishell::model::HostNodalValues;

constexpr double pi = 3.14159265358979323846;

// A 20 mm x 10 mm plate, 1 mm thick, at 1 mm: 20 x 10 quads, 21 x 11 nodes numbered row by
// row (node j * 21 + i sits at (i, j) mm).
std::string plateDeck(const std::string& body, const std::string& extraMesh = "") {
  return "perishell:\n"
         "  version: 1\n"
         "  mesh:\n"
         "    generator: plate\n"
         "    length-x: 0.020\n"
         "    length-y: 0.010\n"
         "    spacing: 1.0e-3\n" +
         extraMesh +
         "  material: {young-modulus: 72.0e9, poisson-ratio: 0.3, density: 2440.0, thickness: 1.0e-3}\n" + body +
         "  solver: {type: explicit, steps: 10}\n";
}

int plateNode(int i, int j) { return j * 21 + i; }

perishell::model::Model build(const std::string& text) {
  return perishell::model::buildModel(perishell::parseDeck(text, "loads-test.yaml"));
}

// The DeckError a call throws as "<key path>: <reason>", or "no error".
template <class BuildT>
std::string deckError(const BuildT& buildSomething) {
  try {
    buildSomething();
  } catch (const perishell::DeckError& error) {
    return error.keyPath() + ": " + error.reason();
  }
  return "no error";
}

struct Totals {
  double sum[6] = {0, 0, 0, 0, 0, 0};
  double sumOfForceNorms = 0.0;
};

Totals totals(const HostNodalValues& nodal) {
  Totals result;
  for (std::size_t node = 0; node < nodal.extent(0); ++node) {
    for (int dof = 0; dof < 6; ++dof) result.sum[dof] += nodal(node, dof);
    result.sumOfForceNorms += std::sqrt(nodal(node, 0) * nodal(node, 0) + nodal(node, 1) * nodal(node, 1) +
                                        nodal(node, 2) * nodal(node, 2));
  }
  return result;
}

// By value: the view keeps its data alive after the NodalLoads temporary is gone.
HostNodalValues onlyPattern(const perishell::model::NodalLoads& loads) {
  EXPECT_EQ(loads.patterns.size(), 1u);
  EXPECT_EQ(loads.patterns.at(0).curve, "");
  return loads.patterns.at(0).nodal;
}

// Sum of every column of a pattern, computed on the test's execution space from its mirror.
template <class ExecutionSpaceT>
std::array<double, 6> deviceColumnSums(const HostNodalValues& host) {
  // Assigned to the explicit LayoutRight type a solver would hold on the device.
  const Kokkos::View<double* [6], Kokkos::LayoutRight, typename ExecutionSpaceT::memory_space> nodal =
      Kokkos::create_mirror_view_and_copy(typename ExecutionSpaceT::memory_space{}, host);
  std::array<double, 6> sums{};
  for (int dof = 0; dof < 6; ++dof)
    Kokkos::parallel_reduce(
        "column sum", Kokkos::RangePolicy<ExecutionSpaceT>(0, nodal.extent(0)),
        KOKKOS_LAMBDA(const int node, double& sum) { sum += nodal(node, dof); }, sums[dof]);
  return sums;
}

template <class ExecutionSpaceT>
Kokkos::View<double*, Kokkos::HostSpace> hostNodeAreas(const perishell::mesh::HostQuadMesh& host) {
  const auto mesh = perishell::mesh::mirrorTo<typename ExecutionSpaceT::memory_space>(host);
  return Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{},
                                             perishell::mesh::computeNodeAreas(ExecutionSpaceT{}, mesh));
}

TEST(TEST_CATEGORY, nodal_loads_edge_traction_by_value_pulls_outward) {
  const auto model = build(plateDeck(
      "  loads:\n"
      "    top: {type: edge-traction, set: top, value: 5.0e6}\n"
      "    bottom: {type: edge-traction, set: bottom, value: 5.0e6}\n"));
  const auto nodal = onlyPattern(perishell::model::buildNodalLoads(model));
  // sigma t dx = 5e6 Pa x 1 mm x 1 mm = 5 N per interior node, half at the corners.
  double topSum = 0.0, bottomSum = 0.0;
  for (int j = 0; j <= 10; ++j)
    for (int i = 0; i <= 20; ++i) {
      const int node = plateNode(i, j);
      const double expected = (j == 0 || j == 10) ? ((i == 0 || i == 20) ? 2.5 : 5.0) : 0.0;
      EXPECT_NEAR(nodal(node, 1), j == 0 ? -expected : expected, 1e-12) << "node " << node;
      for (const int dof : {0, 2, 3, 4, 5}) EXPECT_EQ(nodal(node, dof), 0.0) << "node " << node;
      (j == 0 ? bottomSum : topSum) += nodal(node, 1);
    }
  EXPECT_NEAR(topSum, 5.0e6 * 1.0e-3 * 0.020, 1e-11);  // sigma t L = 100 N
  EXPECT_NEAR(bottomSum, -100.0, 1e-11);
}

TEST(TEST_CATEGORY, nodal_loads_edge_traction_by_vector_keeps_its_direction) {
  const auto model = build(plateDeck(
      "  loads:\n"
      "    shear: {type: edge-traction, set: right, vector: [3.0e6, -1.0e6, 2.0e6]}\n"));
  const auto nodal = onlyPattern(perishell::model::buildNodalLoads(model));
  const double perNode[3] = {3.0, -1.0, 2.0};  // traction x t x dx [N]
  for (int j = 0; j <= 10; ++j) {
    const double share = (j == 0 || j == 10) ? 0.5 : 1.0;
    for (int d = 0; d < 3; ++d) EXPECT_NEAR(nodal(plateNode(20, j), d), share * perNode[d], 1e-12);
  }
  const Totals sums = totals(nodal);
  EXPECT_NEAR(sums.sum[0], 3.0e6 * 1.0e-3 * 0.010, 1e-11);  // traction x t x L = 30 N
  EXPECT_NEAR(sums.sum[1], -10.0, 1e-11);
  EXPECT_NEAR(sums.sum[2], 20.0, 1e-11);
  EXPECT_NEAR(sums.sumOfForceNorms, 10.0 * std::sqrt(14.0), 1e-11);  // nothing off the edge
}

TEST(TEST_CATEGORY, nodal_loads_edge_traction_on_cylinder_rims_points_along_the_axis) {
  // 63 quads round (round(2 pi 50 / 5)), 8 along: the rims' outward in-plane normals are -z, +z.
  const auto model = build(
      "perishell:\n  version: 1\n"
      "  mesh: {generator: cylinder, radius: 0.05, height: 0.04, spacing: 0.005}\n"
      "  material: {young-modulus: 72.0e9, poisson-ratio: 0.3, density: 2440.0, thickness: 2.0e-3}\n"
      "  loads:\n"
      "    top: {type: edge-traction, set: top, value: 1.0e6}\n"
      "    bottom: {type: edge-traction, set: bottom, value: 1.0e6}\n"
      "  solver: {type: explicit, steps: 10}\n");
  const auto nodal = onlyPattern(perishell::model::buildNodalLoads(model));
  const double chord = 2.0 * 0.05 * std::sin(pi / 63);
  const double perNode = 1.0e6 * 2.0e-3 * chord;  // two half edges
  const auto& x = model.shell.mesh.coordinates;
  for (int node = 0; node < model.shell.mesh.numNodes(); ++node) {
    const double z = x(node, 2);
    const double expected = z < 1e-9 ? -perNode : (z > 0.04 - 1e-9 ? perNode : 0.0);
    EXPECT_NEAR(nodal(node, 2), expected, 1e-9) << "node " << node;
    EXPECT_NEAR(nodal(node, 0), 0.0, 1e-9) << "node " << node;
    EXPECT_NEAR(nodal(node, 1), 0.0, 1e-9) << "node " << node;
  }
  EXPECT_NEAR(totals(nodal).sumOfForceNorms, 2.0 * 63 * perNode, 1e-9);
}

TEST(TEST_CATEGORY, nodal_loads_pressure_on_flat_plate_is_p_times_tributary_area) {
  const auto model = build(plateDeck("  loads:\n    p: {type: pressure, value: 2.0e3}\n"));
  const auto nodal = onlyPattern(perishell::model::buildNodalLoads(model));
  const auto areas = hostNodeAreas<TEST_EXECSPACE>(model.shell.mesh);
  for (int node = 0; node < model.shell.mesh.numNodes(); ++node) {
    EXPECT_NEAR(nodal(node, 2), 2.0e3 * areas(node), 1e-15) << "node " << node;
    EXPECT_EQ(nodal(node, 0), 0.0);
    EXPECT_EQ(nodal(node, 1), 0.0);
  }
  EXPECT_NEAR(nodal(plateNode(10, 5), 2), 2.0e-3, 1e-15);  // p dx^2
  EXPECT_NEAR(nodal(plateNode(0, 0), 2), 0.5e-3, 1e-15);
  EXPECT_NEAR(totals(nodal).sum[2], 2.0e3 * 0.020 * 0.010, 1e-14);  // p A = 0.4 N along +z
}

TEST(TEST_CATEGORY, nodal_loads_pressure_on_a_prism_face_follows_its_normal) {
  const auto model = build(
      "perishell:\n  version: 1\n"
      "  mesh: {generator: hexagonal-prism, side: 0.01, length: 0.02, spacing: 0.0025}\n"
      "  material: {young-modulus: 72.0e9, poisson-ratio: 0.3, density: 2440.0, thickness: 1.0e-3}\n"
      "  loads:\n    p: {type: pressure, element-set: face-0, value: 1.0e4}\n"
      "  solver: {type: explicit, steps: 10}\n");
  const auto nodal = onlyPattern(perishell::model::buildNodalLoads(model));
  const Totals sums = totals(nodal);
  // p x side x length = 2 N along face 0's outward normal at 30 degrees.
  EXPECT_NEAR(sums.sum[0], 2.0 * std::cos(pi / 6), 1e-12);
  EXPECT_NEAR(sums.sum[1], 2.0 * std::sin(pi / 6), 1e-12);
  EXPECT_NEAR(sums.sum[2], 0.0, 1e-12);
  EXPECT_NEAR(sums.sumOfForceNorms, 2.0, 1e-12);
  const auto& faceNodes = model.shell.sets.nodeSet("face-0");
  for (int node = 0; node < model.shell.mesh.numNodes(); ++node) {
    if (std::binary_search(faceNodes.begin(), faceNodes.end(), node)) continue;
    for (int d = 0; d < 3; ++d) EXPECT_EQ(nodal(node, d), 0.0) << "node " << node;
  }
}

TEST(TEST_CATEGORY, nodal_loads_uniform_pressure_on_a_cylinder_cancels) {
  const auto model = build(
      "perishell:\n  version: 1\n"
      "  mesh: {generator: cylinder, radius: 0.05, height: 0.04, spacing: 0.005}\n"
      "  material: {young-modulus: 72.0e9, poisson-ratio: 0.3, density: 2440.0, thickness: 1.0e-3}\n"
      "  loads:\n    inflate: {type: pressure, value: 1.0e5}\n"
      "  solver: {type: explicit, steps: 10}\n");
  const auto nodal = onlyPattern(perishell::model::buildNodalLoads(model));
  const Totals sums = totals(nodal);
  const double facetArea = 63 * 2.0 * 0.05 * std::sin(pi / 63) * 0.04;
  for (int d = 0; d < 3; ++d) EXPECT_NEAR(sums.sum[d], 0.0, 1e-9 * 1.0e5 * facetArea);
  // Each node takes p A_e / 4 from each of its quads, whose normals sit pi/63 either side of
  // the node's radius: |F| sums to p A cos(pi / 63) exactly.
  EXPECT_NEAR(sums.sumOfForceNorms, 1.0e5 * facetArea * std::cos(pi / 63), 1e-10);
  // And within the polygon's area deficit of the true cylinder's p 2 pi R H.
  const double trueArea = 2.0 * pi * 0.05 * 0.04;
  EXPECT_NEAR(sums.sumOfForceNorms / (1.0e5 * trueArea), 1.0, 2e-3);
  EXPECT_GT(std::abs(sums.sumOfForceNorms / (1.0e5 * trueArea) - 1.0), 1e-4);
}

// Self-weight: a traction vector per unit area keeps its global direction on every facet, so
// on the cylinder, unlike the pressure, it sums to vector x area rather than cancelling.
TEST(TEST_CATEGORY, nodal_loads_surface_traction_vector_keeps_its_direction) {
  const auto model = build(
      "perishell:\n  version: 1\n"
      "  mesh: {generator: cylinder, radius: 0.05, height: 0.04, spacing: 0.005}\n"
      "  material: {young-modulus: 72.0e9, poisson-ratio: 0.3, density: 2440.0, thickness: 1.0e-3}\n"
      "  loads:\n    weight: {type: pressure, vector: [0.0, -24.0, 0.0]}\n"
      "  solver: {type: explicit, steps: 10}\n");
  const auto nodal = onlyPattern(perishell::model::buildNodalLoads(model));
  const Totals sums = totals(nodal);
  const double facetArea = 63 * 2.0 * 0.05 * std::sin(pi / 63) * 0.04;
  EXPECT_NEAR(sums.sum[0], 0.0, 1e-14);
  EXPECT_NEAR(sums.sum[1], -24.0 * facetArea, 1e-12);
  EXPECT_NEAR(sums.sum[2], 0.0, 1e-14);
  EXPECT_NEAR(sums.sumOfForceNorms, 24.0 * facetArea, 1e-12);  // every nodal force points along -y
  for (int node = 0; node < model.shell.mesh.numNodes(); ++node) {
    EXPECT_EQ(nodal(node, 0), 0.0);
    EXPECT_EQ(nodal(node, 2), 0.0);
  }
}

TEST(TEST_CATEGORY, nodal_loads_point_forces_and_moments_act_on_every_node_of_the_set) {
  const auto model = build(plateDeck(
      "  loads:\n"
      "    tip: {type: point-force, set: top-right, vector: [1.0, -2.0, 3.0], moment: [0.5, 0.0, -0.25]}\n"
      "    row: {type: point-force, set: top, vector: [0.0, 0.0, -1.5]}\n"
      "    twist: {type: point-force, set: middle, moment: [0.0, 0.0, 2.0]}\n",
      "    node-sets:\n      middle: {box: {min: [0.0095, -1.0, -1.0], max: [0.0105, 1.0, 1.0]}}\n"));
  const auto nodal = onlyPattern(perishell::model::buildNodalLoads(model));
  const double tip[6] = {1.0, -2.0, 3.0 - 1.5, 0.5, 0.0, -0.25};
  for (int dof = 0; dof < 6; ++dof) EXPECT_DOUBLE_EQ(nodal(plateNode(20, 10), dof), tip[dof]);
  EXPECT_DOUBLE_EQ(nodal(plateNode(3, 10), 2), -1.5);
  EXPECT_DOUBLE_EQ(nodal(plateNode(10, 10), 5), 2.0);  // top and middle meet here
  EXPECT_DOUBLE_EQ(nodal(plateNode(10, 10), 2), -1.5);
  EXPECT_DOUBLE_EQ(nodal(plateNode(10, 4), 5), 2.0);
  const Totals sums = totals(nodal);
  const double expected[6] = {1.0, -2.0, 3.0 - 21 * 1.5, 0.5, 0.0, -0.25 + 11 * 2.0};
  for (int dof = 0; dof < 6; ++dof) EXPECT_NEAR(sums.sum[dof], expected[dof], 1e-12) << "dof " << dof;
}

TEST(TEST_CATEGORY, nodal_loads_group_by_curve_and_keep_followers_apart) {
  const auto model = build(plateDeck(
      "  loads:\n"
      "    a: {type: point-force, set: top-right, vector: [1.0, 0.0, 0.0], curve: slow}\n"
      "    b: {type: point-force, set: bottom-right, vector: [0.0, 1.0, 0.0], curve: fast}\n"
      "    c: {type: pressure, value: 10.0, follower: true, curve: inflate}\n"
      "    d: {type: point-force, set: top-left, vector: [0.0, 0.0, 1.0], curve: slow}\n"
      "    e: {type: point-force, set: bottom-left, vector: [0.0, 0.0, -1.0]}\n"
      "  curves:\n"
      "    slow: {type: ramp, end-time: 1.0}\n"
      "    fast: {type: step, time: 0.0}\n"
      "    inflate: {type: ramp, end-time: 2.0}\n"));
  const auto loads = perishell::model::buildNodalLoads(model);
  ASSERT_EQ(loads.patterns.size(), 3u);
  EXPECT_EQ(loads.patterns[0].curve, "slow");
  EXPECT_EQ(loads.patterns[1].curve, "fast");
  EXPECT_EQ(loads.patterns[2].curve, "");
  const auto slow = totals(loads.patterns[0].nodal);
  EXPECT_DOUBLE_EQ(slow.sum[0], 1.0);
  EXPECT_DOUBLE_EQ(slow.sum[2], 1.0);
  EXPECT_DOUBLE_EQ(slow.sumOfForceNorms, 2.0);
  EXPECT_DOUBLE_EQ(loads.patterns[0].nodal(plateNode(0, 10), 2), 1.0);
  EXPECT_DOUBLE_EQ(loads.patterns[1].nodal(plateNode(20, 0), 1), 1.0);
  EXPECT_DOUBLE_EQ(totals(loads.patterns[1].nodal).sumOfForceNorms, 1.0);
  EXPECT_DOUBLE_EQ(loads.patterns[2].nodal(plateNode(0, 0), 2), -1.0);
  EXPECT_DOUBLE_EQ(totals(loads.patterns[2].nodal).sumOfForceNorms, 1.0);
  ASSERT_EQ(loads.followerPressures.size(), 1u);
  const auto& follower = loads.followerPressures[0];
  EXPECT_EQ(follower.name, "c");
  EXPECT_EQ(follower.curve, "inflate");
  EXPECT_EQ(follower.pressure, 10.0);
  ASSERT_EQ(follower.elements.size(), 200u);
  for (int element = 0; element < 200; ++element) EXPECT_EQ(follower.elements[element], element);
}

TEST(TEST_CATEGORY, nodal_loads_pattern_mirrors_to_the_device_intact) {
  const auto model = build(plateDeck(
      "  loads:\n"
      "    p: {type: pressure, value: 2.0e3}\n"
      "    tip: {type: point-force, set: top-right, vector: [1.0, -2.0, 0.0], moment: [0.5, 0.25, -0.25]}\n"));
  const auto nodal = onlyPattern(perishell::model::buildNodalLoads(model));
  const auto onDevice = deviceColumnSums<TEST_EXECSPACE>(nodal);
  const double expected[6] = {1.0, -2.0, 0.4, 0.5, 0.25, -0.25};
  for (int dof = 0; dof < 6; ++dof) EXPECT_NEAR(onDevice[dof], expected[dof], 1e-13) << "dof " << dof;
}

TEST(TEST_CATEGORY, nodal_loads_reject_non_finite_values_and_undefined_edge_normals) {
  // A 2 x 1 cell plate 2e10 m long and 10 m thick: 1e300 Pa x 1e10 m x 10 m overflows. The
  // model refuses such a deck (model_loads_whose_nodal_forces_overflow_or_underflow_are_refused);
  // the nodal loads still refuse a non-finite sum should a model carry one.
  const std::string huge =
      "perishell:\n  version: 1\n"
      "  mesh: {generator: plate, length-x: 2.0e10, length-y: 1.0e10, spacing: 1.0e10}\n"
      "  material: {young-modulus: 72.0e9, poisson-ratio: 0.3, density: 2440.0, thickness: 10.0}\n"
      "  loads:\n    huge: {type: edge-traction, set: top, value: 1.0e30}\n"
      "  solver: {type: explicit, steps: 10}\n";
  auto hugeModel = build(huge);
  hugeModel.deck.loads[0].value = 1.0e300;
  const std::string hugeError = deckError([&] { perishell::model::buildNodalLoads(hugeModel); });
  EXPECT_EQ(hugeError.rfind("loads.huge.value: gives a non-finite nodal load", 0), 0u) << hugeError;

  auto model = build(plateDeck(""));
  model.shell.sets.edgeSets["collapsed"] = {{5, 5}};
  perishell::deck::Load pull;
  pull.name = "pull";
  pull.type = perishell::deck::LoadType::EdgeTraction;
  pull.set = "collapsed";
  pull.value = 1.0e6;
  model.deck.loads.push_back(pull);
  EXPECT_EQ(deckError([&] { perishell::model::buildNodalLoads(model); }),
            "loads.pull.set: edge (5, 5) has no outward in-plane normal (zero length, or along the shell normal)");
}

TEST(TEST_CATEGORY, nodal_loads_support_masks_values_and_curves) {
  const auto model = build(plateDeck(
      "  supports:\n"
      "    clamp: {set: left, dofs: [ux, uy, uz, rx, ry, rz]}\n"
      "    roller: {set: bottom, dofs: [uy]}\n"
      "    pull: {set: right, dofs: [ux], value: 1.0e-4, curve: ramp}\n"
      "    hold: {set: top-right, dofs: [uz], value: 0.0, curve: late}\n"
      "  curves:\n"
      "    ramp: {type: ramp, end-time: 1.0}\n"
      "    late: {type: step, time: 0.5}\n"));
  const auto supports = perishell::model::buildSupportConditions(model);
  // left 11 x 6 and its support layer (3 columns of 11) x 6, bottom 20 more uy, right 11 ux,
  // one uz at the top-right corner.
  EXPECT_EQ(supports.numConstrainedDofs(), 66 + 198 + 20 + 11 + 1);
  EXPECT_EQ(supports.numConstrainedDofs(), model.numConstrainedDofs);
  EXPECT_EQ(supports.constrainedDofs(plateNode(0, 0)), 0x3F);
  EXPECT_EQ(supports.constrainedDofs(plateNode(0, 7)), 0x3F);
  EXPECT_EQ(supports.constrainedDofs(plateNode(20, 0)), 0x03);   // ux, uy
  EXPECT_EQ(supports.constrainedDofs(plateNode(20, 10)), 0x05);  // ux, uz
  EXPECT_EQ(supports.constrainedDofs(plateNode(20, 5)), 0x01);
  EXPECT_EQ(supports.constrainedDofs(plateNode(10, 0)), 0x02);
  EXPECT_EQ(supports.constrainedDofs(plateNode(10, 5)), 0x00);
  // A zero value is fixed whatever its curve, so only 'ramp' is a support curve.
  ASSERT_EQ(supports.curves.size(), 1u);
  EXPECT_EQ(supports.curves[0], "ramp");
  EXPECT_EQ(supports.prescribedValue(plateNode(20, 5), 0), 1.0e-4);
  EXPECT_EQ(supports.curveIndex(plateNode(20, 5), 0), 0);
  EXPECT_EQ(supports.prescribedValue(plateNode(20, 10), 2), 0.0);
  EXPECT_EQ(supports.curveIndex(plateNode(20, 10), 2), -1);
  for (int dof = 0; dof < 6; ++dof) {
    EXPECT_EQ(supports.prescribedValue(plateNode(0, 3), dof), 0.0);
    EXPECT_EQ(supports.curveIndex(plateNode(0, 3), dof), -1);
    EXPECT_EQ(supports.curveIndex(plateNode(10, 5), dof), -1);
  }
}

TEST(TEST_CATEGORY, nodal_loads_conflicting_supports_name_both) {
  const std::string curves =
      "  curves:\n    slow: {type: ramp, end-time: 1.0}\n    fast: {type: ramp, end-time: 0.1}\n";
  auto supportError = [&](const std::string& supports) {
    const auto model = build(plateDeck("  supports:\n" + supports + curves));
    return deckError([&] { perishell::model::buildSupportConditions(model); });
  };
  EXPECT_EQ(supportError("    clamp: {set: left, dofs: [ux, uy, uz]}\n"
                         "    push: {set: bottom-left, dofs: [ux], value: 1.0e-3}\n"),
            "supports.push: prescribes ux = 0.001 at node 0 (0, 0, 0), where supports.clamp prescribes 0");
  EXPECT_EQ(supportError("    a: {set: right, dofs: [uz], value: 1.0e-3, curve: slow}\n"
                         "    b: {set: top-right, dofs: [uz], value: 1.0e-3, curve: fast}\n"),
            "supports.b: prescribes uz = 0.001 x curve 'fast' at node 230 (0.02, 0.01, 0), "
            "where supports.a prescribes 0.001 x curve 'slow'");
  // Agreeing overlaps are fine: equal values and curves, or zero under any curve.
  EXPECT_EQ(supportError("    a: {set: right, dofs: [uz], value: 1.0e-3, curve: slow}\n"
                         "    b: {set: top-right, dofs: [uz], value: 1.0e-3, curve: slow}\n"
                         "    c: {set: left, dofs: [ux], curve: fast}\n"
                         "    d: {set: top, dofs: [ux]}\n"),
            "no error");
}

}  // namespace perishell_test_nodal_loads
