// Case decks: the paper's glass-plate deck and a deck using every key parse into the expected
// numbers; defaults, curves and relative paths behave as docs/deck.md says; every validation
// rule is broken once and its message must name the key path and the reason.
#include <perishell/io/deck.hpp>
#include <perishell/solvers/history_columns.hpp>

#include <test_files.hpp>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace {

using namespace perishell;
namespace fs = std::filesystem;

using perishell_test::testDataDirectory;
using perishell_test::testsDirectory;
const auto& readText = perishell_test::readTextFile;

// A scratch directory per process (OpenMP and CUDA binaries may run at the same time).
fs::path scratchDirectory() {
  const fs::path directory =
      fs::temp_directory_path() / ("perishell-tstDeck-" + std::to_string(::getpid()));
  fs::create_directories(directory);
  return directory;
}

// Valid; an implicit plate with one support, one load and one curve, for the bad decks to break.
const std::string baseDeck = R"(perishell:
  version: 1
  title: base
  mesh:
    generator: plate
    length-x: 0.09
    length-y: 0.03
    spacing: 1.0e-3
  material:
    young-modulus: 210.0e9
    poisson-ratio: 0.3
    density: 7850.0
    thickness: 0.8e-3
    fracture-energy: 255.0e3
  peridynamics:
    horizon-factor: 3
  zones:
    default: pd
  supports:
    left:
      set: left
      dofs: [ux, uy, uz, rx, ry, rz]
  loads:
    push:
      type: pressure
      value: 1.0e6
      curve: ramp
  curves:
    ramp:
      type: ramp
      end-time: 1.0
  solver:
    type: implicit
    increments: 10
  output:
    every: 1
)";

struct Edit {
  std::string find, replace;
};

std::string edited(std::string text, const std::vector<Edit>& edits) {
  for (const auto& edit : edits) {
    const auto at = text.find(edit.find);
    if (at == std::string::npos) {
      ADD_FAILURE() << "test bug: '" << edit.find << "' is not in the deck";
      continue;
    }
    text.replace(at, edit.find.size(), edit.replace);
  }
  return text;
}

DeckError deckErrorOf(const std::string& text, const std::string& source = "bad.yaml") {
  try {
    parseDeck(text, source);
  } catch (const DeckError& error) {
    return error;
  }
  ADD_FAILURE() << "the deck was accepted:\n" << text;
  return DeckError(source, "<accepted>", "<accepted>");
}

TEST(TEST_CATEGORY, deck_glass_plate_example_reads_the_paper_numbers) {
  const fs::path path = testDataDirectory / "decks/glass_plate_4_1_2.yaml";
  if (!fs::exists(path)) GTEST_SKIP() << "source tree not present: " << path;
  const Deck deck = readDeck(path.string());

  EXPECT_EQ(deck.sourceName, path.string());
  EXPECT_EQ(deck.version, 1);
  EXPECT_EQ(deck.title, "4.1.2 Y-branching of a pre-cracked glass plate");
  EXPECT_EQ(deck.mesh.generator, deck::MeshGenerator::Plate);
  EXPECT_DOUBLE_EQ(deck.mesh.lengthX, 0.100);
  EXPECT_DOUBLE_EQ(deck.mesh.lengthY, 0.040);
  EXPECT_DOUBLE_EQ(deck.mesh.spacing, 0.5e-3);
  ASSERT_EQ(deck.mesh.preCracks.size(), 1u);
  const auto& crack = deck.mesh.preCracks[0];
  EXPECT_EQ(crack.name, "initial");
  const double start[3] = {0.0, 0.020, 0.0}, end[3] = {0.050, 0.020, 0.0}, normal[3] = {0, 0, 1};
  for (int d = 0; d < 3; ++d) {
    EXPECT_DOUBLE_EQ(crack.segment.start[d], start[d]);
    EXPECT_DOUBLE_EQ(crack.segment.end[d], end[d]);
    EXPECT_DOUBLE_EQ(crack.segment.normal[d], normal[d]);
  }

  EXPECT_DOUBLE_EQ(deck.material.youngModulus, 72.0e9);
  EXPECT_DOUBLE_EQ(deck.material.poissonRatio, 0.33);
  EXPECT_DOUBLE_EQ(deck.material.density, 2440.0);
  EXPECT_DOUBLE_EQ(deck.material.thickness, 1.0e-3);
  ASSERT_TRUE(deck.material.fractureEnergy.has_value());
  EXPECT_DOUBLE_EQ(*deck.material.fractureEnergy, 135.0);
  EXPECT_DOUBLE_EQ(deck.peridynamics.horizonFactor, 3.0);
  EXPECT_EQ(deck.peridynamics.forceKernel, deck::ForceKernel::NodeGather);

  EXPECT_EQ(deck.zones.defaultKind, deck::ZoneKind::Ccm);
  ASSERT_EQ(deck.zones.pdRegions.size(), 1u);
  const auto& region = deck.zones.pdRegions[0];
  EXPECT_EQ(region.name, "crack-path");
  EXPECT_EQ(region.shape, deck::RegionShape::Box);
  EXPECT_EQ(region.boxMin, (deck::Vector3{0.045, 0.005, -0.001}));
  EXPECT_EQ(region.boxMax, (deck::Vector3{0.100, 0.035, 0.001}));
  EXPECT_TRUE(deck.zones.hasPd());

  EXPECT_TRUE(deck.supports.empty());
  ASSERT_EQ(deck.loads.size(), 2u);
  const char* edges[2] = {"top", "bottom"};
  for (int i = 0; i < 2; ++i) {
    const auto& load = deck.loads[i];
    EXPECT_EQ(load.name, std::string(edges[i]) + "-traction");
    EXPECT_EQ(load.type, deck::LoadType::EdgeTraction);
    EXPECT_EQ(load.set, edges[i]);
    ASSERT_TRUE(load.value.has_value());
    EXPECT_DOUBLE_EQ(*load.value, 12.0e6);
    EXPECT_FALSE(load.vector.has_value());
    EXPECT_FALSE(load.follower);
    EXPECT_EQ(load.curve, "sudden");
  }
  ASSERT_EQ(deck.curves.size(), 1u);
  EXPECT_EQ(deck.curves[0].type, deck::CurveType::Step);
  EXPECT_DOUBLE_EQ(deck.curves[0].stepTime, 0.0);

  EXPECT_EQ(deck.solver.type, deck::SolverType::Explicit);
  ASSERT_TRUE(deck.solver.explicitSettings.endTime.has_value());
  EXPECT_DOUBLE_EQ(*deck.solver.explicitSettings.endTime, 46.0e-6);
  EXPECT_FALSE(deck.solver.explicitSettings.steps.has_value());
  EXPECT_FALSE(deck.solver.explicitSettings.timeStep.has_value());
  EXPECT_DOUBLE_EQ(deck.solver.explicitSettings.safetyFactor, 0.9);
  EXPECT_DOUBLE_EQ(deck.solver.explicitSettings.damping, 0.0);

  EXPECT_EQ(deck.output.directory, (path.parent_path() / "output/glass-plate").string());
  EXPECT_EQ(deck.output.every, 500);
  EXPECT_EQ(deck.output.historyEvery, 500);  // defaults to every
  EXPECT_EQ(deck.output.fields,
            (std::vector<deck::OutputField>{deck::OutputField::Displacement, deck::OutputField::Velocity,
                                            deck::OutputField::Damage, deck::OutputField::Zone}));
  EXPECT_EQ(deck.output.history,
            (std::vector<deck::HistoryQuantity>{deck::HistoryQuantity::Energy,
                                                deck::HistoryQuantity::BrokenBonds,
                                                deck::HistoryQuantity::CrackTip}));
  // Free flight is legal for the explicit solver, with a warning.
  ASSERT_EQ(deck.warnings.size(), 1u);
  EXPECT_NE(deck.warnings[0].find("supports: none given"), std::string::npos) << deck.warnings[0];
}

TEST(TEST_CATEGORY, deck_docs_show_the_example_deck_and_every_block_parses) {
  const fs::path docs = testsDirectory.parent_path() / "docs/deck.md";
  const fs::path example = testsDirectory / "data/decks/glass_plate_4_1_2.yaml";
  if (!fs::exists(docs) || !fs::exists(example)) GTEST_SKIP() << "source tree not present";
  const std::string markdown = readText(docs);
  EXPECT_NE(markdown.find("```yaml\n" + readText(example) + "```"), std::string::npos)
      << "docs/deck.md must show " << example << " verbatim";
  int complete = 0;
  for (auto open = markdown.find("```yaml\n"); open != std::string::npos;
       open = markdown.find("```yaml\n", open + 1)) {
    const auto begin = open + 8;
    const std::string block = markdown.substr(begin, markdown.find("```", begin) - begin);
    if (block.find("\nperishell:\n") == std::string::npos && block.rfind("perishell:\n", 0) != 0) continue;
    ++complete;
    EXPECT_NO_THROW(parseDeck(block, "docs/deck.md")) << block;
  }
  EXPECT_GE(complete, 2);
}

TEST(TEST_CATEGORY, deck_with_every_key_parses_into_the_expected_struct) {
  const std::string text = R"(%YAML 1.1
---
perishell:
  version: 1
  title: 'every key: cylinder'
  mesh:
    generator: cylinder
    radius: 0.1
    height: 0.6
    spacing: 4.5e-3
    pre-cracks:
      mid:
        start: [0.1, 0, 0.29]
        end: [0.1, 0, 0.31]
        normal: [2, 0, 0]
  material:
    young-modulus: 65.0e9
    poisson-ratio: 0.25
    density: 7850
    thickness: 3.048e-3
    fracture-energy: 150.0e3
  peridynamics:
    horizon-factor: 2.5
    force-kernel: bond-scatter
  zones:
    default: ccm
    pd-regions:
      around-crack:
        box: {min: [0.05, -0.05, 0.25], max: [0.15, 0.05, 0.35]}
      ring:
        cylinder: {center: [0, 0, 0.3], axis: [0, 0, 2], radius: 0.11, half-length: 0.02}
      band:
        element-set: {name: crack-band}
  supports:
    ends:
      set: ends
      dofs: [ux, uy, uz, rx, ry, rz]
    pull:
      set: top
      dofs: uz
      value: 1.0e-3
      curve: linear
  loads:
    side:
      type: pressure
      value: -1.0e6
      follower: true
      curve: table
    tip:
      type: point-force
      set: tip
      vector: [0, 0, -1800]
      moment: [0, 25.0, 0]
      curve: later
    shear:
      type: edge-traction
      set: top
      vector: [0, 1.0e5, 0]
    window:
      type: pressure
      element-set: window
      value: 5.0e5
  curves:
    linear:
      type: ramp
      end-time: 2.0
    table:
      type: table
      time: [0, 0.5, 1]
      value: [0, 0.25, 1]
    later:
      type: step
      time: 0.5
  solver:
    type: implicit
    increments: 100
    max-iterations: 50
    tolerance: 1.0e-6
    preconditioner: jacobi
    tangent: exact
    amg-reuse: 2.0
    amg-drop-tolerance: 0.1
    amg-coarse-nodes: 120
    amg-region-scaling: false
    coarse-space: false
    overlap: false
    newton: displacement
    factorization: host
  output:
    directory: /tmp/perishell-results
    every: 10
    history-every: 2
    fields: [displacement, rotation, damage, zone]
    history: [energy, reactions, load-points]
    probes: {mid: [0.1, 0, 0.3], base: [0.1, 0, 0]}
...
)";
  const Deck deck = parseDeck(text, "cases/every_key.yaml");
  EXPECT_EQ(deck.title, "every key: cylinder");
  EXPECT_EQ(deck.mesh.generator, deck::MeshGenerator::Cylinder);
  EXPECT_DOUBLE_EQ(deck.mesh.radius, 0.1);
  EXPECT_DOUBLE_EQ(deck.mesh.height, 0.6);
  EXPECT_DOUBLE_EQ(deck.mesh.lengthX, 0.0);
  EXPECT_DOUBLE_EQ(deck.mesh.spacing, 4.5e-3);
  ASSERT_EQ(deck.mesh.preCracks.size(), 1u);
  EXPECT_DOUBLE_EQ(deck.mesh.preCracks[0].segment.end[2], 0.31);
  EXPECT_DOUBLE_EQ(deck.mesh.preCracks[0].segment.normal[0], 1.0);  // normalised from [2, 0, 0]

  EXPECT_DOUBLE_EQ(deck.material.youngModulus, 65.0e9);
  EXPECT_DOUBLE_EQ(deck.material.poissonRatio, 0.25);
  EXPECT_DOUBLE_EQ(deck.material.density, 7850.0);  // an integer in YAML
  EXPECT_DOUBLE_EQ(deck.material.thickness, 3.048e-3);
  EXPECT_DOUBLE_EQ(*deck.material.fractureEnergy, 150.0e3);
  EXPECT_DOUBLE_EQ(deck.peridynamics.horizonFactor, 2.5);
  EXPECT_EQ(deck.peridynamics.forceKernel, deck::ForceKernel::BondScatter);

  ASSERT_EQ(deck.zones.pdRegions.size(), 3u);
  EXPECT_EQ(deck.zones.pdRegions[0].name, "around-crack");  // deck order is kept
  EXPECT_EQ(deck.zones.pdRegions[0].boxMax, (deck::Vector3{0.15, 0.05, 0.35}));
  const auto& ring = deck.zones.pdRegions[1];
  EXPECT_EQ(ring.shape, deck::RegionShape::Cylinder);
  EXPECT_EQ(ring.center, (deck::Vector3{0.0, 0.0, 0.3}));
  EXPECT_EQ(ring.axis, (deck::Vector3{0.0, 0.0, 1.0}));
  EXPECT_DOUBLE_EQ(ring.radius, 0.11);
  EXPECT_DOUBLE_EQ(ring.halfLength, 0.02);
  EXPECT_EQ(deck.zones.pdRegions[2].shape, deck::RegionShape::ElementSet);
  EXPECT_EQ(deck.zones.pdRegions[2].elementSet, "crack-band");
  EXPECT_FALSE(deck.zones.pdRatio.has_value());

  ASSERT_EQ(deck.supports.size(), 2u);
  EXPECT_EQ(deck.supports[0].dofs.size(), 6u);
  EXPECT_EQ(int(deck.supports[0].dofs[5]), 5);
  EXPECT_DOUBLE_EQ(deck.supports[0].value, 0.0);
  EXPECT_EQ(deck.supports[1].dofs, std::vector<deck::Dof>{deck::Dof::Uz});
  EXPECT_DOUBLE_EQ(deck.supports[1].value, 1.0e-3);
  EXPECT_EQ(deck.supports[1].curve, "linear");

  ASSERT_EQ(deck.loads.size(), 4u);
  EXPECT_EQ(deck.loads[0].type, deck::LoadType::Pressure);
  EXPECT_DOUBLE_EQ(*deck.loads[0].value, -1.0e6);
  EXPECT_TRUE(deck.loads[0].follower);
  EXPECT_EQ(deck.loads[0].set, "");  // all elements
  EXPECT_EQ(deck.loads[1].type, deck::LoadType::PointForce);
  EXPECT_EQ(*deck.loads[1].vector, (deck::Vector3{0.0, 0.0, -1800.0}));
  EXPECT_EQ(*deck.loads[1].moment, (deck::Vector3{0.0, 25.0, 0.0}));
  EXPECT_EQ(deck.loads[2].type, deck::LoadType::EdgeTraction);
  EXPECT_EQ(*deck.loads[2].vector, (deck::Vector3{0.0, 1.0e5, 0.0}));
  EXPECT_EQ(deck.loads[2].curve, "");
  EXPECT_EQ(deck.loads[3].set, "window");
  EXPECT_FALSE(deck.loads[3].follower);

  ASSERT_EQ(deck.curves.size(), 3u);
  ASSERT_NE(deck.findCurve("table"), nullptr);
  EXPECT_EQ(deck.findCurve("table")->values, (std::vector<double>{0.0, 0.25, 1.0}));
  EXPECT_EQ(deck.findCurve("missing"), nullptr);

  EXPECT_EQ(deck.solver.type, deck::SolverType::Implicit);
  EXPECT_EQ(deck.solver.implicitSettings.increments, 100);
  EXPECT_EQ(deck.solver.implicitSettings.maxIterations, 50);
  EXPECT_DOUBLE_EQ(deck.solver.implicitSettings.tolerance, 1.0e-6);
  EXPECT_EQ(deck.solver.implicitSettings.preconditioner, deck::Preconditioner::Jacobi);
  EXPECT_EQ(deck.solver.implicitSettings.tangent, deck::Tangent::Exact);
  EXPECT_DOUBLE_EQ(deck.solver.implicitSettings.amgReuse, 2.0);
  EXPECT_DOUBLE_EQ(deck.solver.implicitSettings.amgDropTolerance, 0.1);
  EXPECT_EQ(deck.solver.implicitSettings.amgCoarseNodes, 120);
  EXPECT_FALSE(deck.solver.implicitSettings.amgRegionScaling);
  EXPECT_FALSE(deck.solver.implicitSettings.coarseSpace);
  EXPECT_FALSE(deck.solver.implicitSettings.overlap);
  EXPECT_EQ(deck.solver.implicitSettings.newton, deck::ImplicitSettings::Newton::Displacement);
  EXPECT_EQ(deck.solver.implicitSettings.factorization, deck::Factorization::Host);

  EXPECT_EQ(deck.output.directory, "/tmp/perishell-results");  // absolute stays
  EXPECT_EQ(deck.output.every, 10);
  EXPECT_EQ(deck.output.historyEvery, 2);
  EXPECT_EQ(deck.output.fields.size(), 4u);
  EXPECT_EQ(deck.output.history,
            (std::vector<deck::HistoryQuantity>{deck::HistoryQuantity::Energy, deck::HistoryQuantity::Reactions,
                                                deck::HistoryQuantity::LoadPoints}));
  ASSERT_EQ(deck.output.probes.size(), 2u);  // in deck order
  EXPECT_EQ(deck.output.probes[0].name, "mid");
  EXPECT_EQ(deck.output.probes[0].position, (deck::Vector3{0.1, 0.0, 0.3}));
  EXPECT_EQ(deck.output.probes[1].name, "base");
  EXPECT_EQ(deck.output.probes[1].position, (deck::Vector3{0.1, 0.0, 0.0}));
  EXPECT_TRUE(deck.warnings.empty());
}

TEST(TEST_CATEGORY, deck_defaults_fill_what_a_minimal_deck_leaves_out) {
  const std::string text = R"(perishell:
  version: 1
  mesh: {generator: hexagonal-prism, side: 65.33e-3, length: 304.8e-3, spacing: 2.5e-3}
  material: {young-modulus: 193e9, poisson-ratio: 0.33, density: 7980, thickness: 3.048e-3}
  solver:
    type: explicit
    steps: 5e4
)";
  const Deck deck = parseDeck(text, "minimal.yaml");
  EXPECT_EQ(deck.title, "");
  EXPECT_DOUBLE_EQ(deck.mesh.side, 65.33e-3);
  EXPECT_DOUBLE_EQ(deck.mesh.length, 304.8e-3);
  EXPECT_FALSE(deck.material.fractureEnergy.has_value());
  EXPECT_DOUBLE_EQ(deck.peridynamics.horizonFactor, 3.0);
  EXPECT_EQ(deck.peridynamics.forceKernel, deck::ForceKernel::NodeGather);
  EXPECT_EQ(deck.zones.defaultKind, deck::ZoneKind::Pd);
  EXPECT_TRUE(deck.zones.hasPd());
  EXPECT_TRUE(deck.loads.empty());
  EXPECT_EQ(*deck.solver.explicitSettings.steps, 50000);  // 5e4 is a whole number
  EXPECT_FALSE(deck.solver.explicitSettings.endTime.has_value());
  EXPECT_DOUBLE_EQ(deck.solver.explicitSettings.safetyFactor, 0.9);
  EXPECT_EQ(deck.output.directory, "output");
  EXPECT_EQ(deck.output.every, 0);
  EXPECT_EQ(deck.output.historyEvery, 100);  // every: 0 writes the final state only
  EXPECT_EQ(deck.output.fields,
            (std::vector<deck::OutputField>{deck::OutputField::Displacement, deck::OutputField::Damage}));
  EXPECT_TRUE(deck.output.history.empty());
  EXPECT_TRUE(deck.output.probes.empty());
  ASSERT_EQ(deck.warnings.size(), 1u);  // no supports

  const Deck implicitDeck = parseDeck(edited(baseDeck, {{"    increments: 10\n", ""}}), "base.yaml");
  const auto& implicitSettings = implicitDeck.solver.implicitSettings;
  EXPECT_EQ(implicitSettings.increments, 1);
  EXPECT_EQ(implicitSettings.maxIterations, 100);
  EXPECT_DOUBLE_EQ(implicitSettings.tolerance, 1e-8);
  EXPECT_EQ(implicitSettings.preconditioner, deck::Preconditioner::Auto);
  EXPECT_EQ(implicitSettings.tangent, deck::Tangent::Auto);
  EXPECT_DOUBLE_EQ(implicitSettings.amgReuse, 1.5);
  EXPECT_DOUBLE_EQ(implicitSettings.amgDropTolerance, 0.05);
  EXPECT_EQ(implicitSettings.amgCoarseNodes, 200);
  EXPECT_TRUE(implicitSettings.amgRegionScaling);
  EXPECT_TRUE(implicitSettings.coarseSpace);
  EXPECT_TRUE(implicitSettings.overlap);
  EXPECT_EQ(implicitSettings.newton, deck::ImplicitSettings::Newton::Mixed);
  EXPECT_TRUE(implicitDeck.warnings.empty());
}

TEST(TEST_CATEGORY, deck_explicit_settings_pd_ratio_and_relative_paths) {
  const fs::path directory = scratchDirectory() / "case";
  fs::create_directories(directory);
  const fs::path path = directory / "prism.yaml";
  std::ofstream(path) << R"(perishell:
  version: 1
  mesh:
    generator: gmsh
    file: ../meshes/prism.msh
    spacing: 2.5e-3
  material: {young-modulus: 193e9, poisson-ratio: 0.33, density: 7980, thickness: 3.048e-3}
  zones:
    default: ccm
    pd-ratio:
      target: 0.5
      around:
        tip-a: [0.1, 0, 0]
        tip-b: [-0.1, 0, 0.2]
  solver:
    type: explicit
    end-time: 2.0e-3
    dt: 1.0e-7
    safety-factor: 1
    damping: 150
)";
  const Deck deck = readDeck(path.string());
  EXPECT_EQ(deck.mesh.generator, deck::MeshGenerator::Gmsh);
  EXPECT_EQ(deck.mesh.file, (scratchDirectory() / "meshes/prism.msh").string());
  EXPECT_EQ(deck.output.directory, (directory / "output").string());
  ASSERT_TRUE(deck.zones.pdRatio.has_value());
  EXPECT_DOUBLE_EQ(deck.zones.pdRatio->target, 0.5);
  ASSERT_EQ(deck.zones.pdRatio->around.size(), 2u);
  EXPECT_EQ(deck.zones.pdRatio->around[1].name, "tip-b");
  EXPECT_EQ(deck.zones.pdRatio->around[1].position, (deck::Vector3{-0.1, 0.0, 0.2}));
  const auto& settings = deck.solver.explicitSettings;
  EXPECT_DOUBLE_EQ(*settings.endTime, 2.0e-3);
  EXPECT_DOUBLE_EQ(*settings.timeStep, 1.0e-7);
  EXPECT_DOUBLE_EQ(settings.safetyFactor, 1.0);
  EXPECT_DOUBLE_EQ(settings.damping, 150.0);
  fs::remove_all(scratchDirectory());
}

TEST(TEST_CATEGORY, deck_curves_evaluate_as_documented) {
  deck::Curve ramp{"r", deck::CurveType::Ramp, 2.0, 0.0, {}, {}};
  EXPECT_DOUBLE_EQ(deck::evaluateCurve(ramp, -1.0), 0.0);
  EXPECT_DOUBLE_EQ(deck::evaluateCurve(ramp, 0.5), 0.25);
  EXPECT_DOUBLE_EQ(deck::evaluateCurve(ramp, 3.0), 1.0);
  deck::Curve step{"s", deck::CurveType::Step, 0.0, 0.5, {}, {}};
  EXPECT_DOUBLE_EQ(deck::evaluateCurve(step, 0.4999), 0.0);
  EXPECT_DOUBLE_EQ(deck::evaluateCurve(step, 0.5), 1.0);
  deck::Curve table{"t", deck::CurveType::Table, 0.0, 0.0, {0.0, 0.5, 1.0}, {0.0, 0.25, 1.0}};
  EXPECT_DOUBLE_EQ(deck::evaluateCurve(table, -1.0), 0.0);
  EXPECT_DOUBLE_EQ(deck::evaluateCurve(table, 0.25), 0.125);
  EXPECT_DOUBLE_EQ(deck::evaluateCurve(table, 0.75), 0.625);
  EXPECT_DOUBLE_EQ(deck::evaluateCurve(table, 2.0), 1.0);
}

TEST(TEST_CATEGORY, deck_poisson_ratio_above_one_third_is_fine_without_pd) {
  const Deck deck = parseDeck(
      edited(baseDeck, {{"poisson-ratio: 0.3", "poisson-ratio: 0.45"}, {"default: pd", "default: ccm"}}),
      "ccm.yaml");
  EXPECT_DOUBLE_EQ(deck.material.poissonRatio, 0.45);
  EXPECT_FALSE(deck.zones.hasPd());
  // G_c is given but only PD bonds fracture.
  ASSERT_EQ(deck.warnings.size(), 1u);
  EXPECT_NE(deck.warnings[0].find("material.fracture-energy"), std::string::npos);
}

struct BadDeck {
  std::string name;
  std::vector<Edit> edits;
  std::string keyPath;
  std::vector<std::string> reasonParts;
};

// Each edited base deck is refused, naming its key path, with every part in the reason, in
// the message "bad.yaml: <key path>: <reason>".
void expectDeckErrors(const std::vector<BadDeck>& cases) {
  for (const auto& bad : cases) {
    SCOPED_TRACE(bad.name);
    const DeckError error = deckErrorOf(edited(baseDeck, bad.edits));
    EXPECT_EQ(error.keyPath(), bad.keyPath) << error.what();
    for (const auto& part : bad.reasonParts)
      EXPECT_NE(error.reason().find(part), std::string::npos) << "reason: " << error.reason();
    EXPECT_EQ(std::string(error.what()), "bad.yaml: " + bad.keyPath + ": " + error.reason());
  }
}

TEST(TEST_CATEGORY, deck_every_rule_rejects_with_key_path_and_reason) {
  const std::string pdRegion =
      "    default: ccm\n    pd-regions:\n      zone:\n        box: {min: [0, 0, -1], max: [1, 1, 1]}\n";
  const std::vector<BadDeck> cases{
      {"unknown top-level key", {{"  title: base", "  titel: base"}}, "titel",
       {"unknown key", "allowed keys here: version, title, mesh, material"}},
      {"unknown nested key", {{"young-modulus:", "youngs-modulus:"}}, "material.youngs-modulus",
       {"unknown key", "young-modulus, poisson-ratio, density, thickness, fracture-energy"}},
      {"unknown key in a named item", {{"      set: left\n", "      set: left\n      fixed: true\n"}},
       "supports.left.fixed", {"unknown key", "set, dofs, value, curve"}},
      {"key of another generator", {{"    length-y: 0.03\n", "    length-y: 0.03\n    radius: 0.1\n"}},
       "mesh.radius", {"key not allowed for generator plate"}},
      {"key of another solver type", {{"    increments: 10\n", "    end-time: 1.0\n"}}, "solver.end-time",
       {"key not allowed for solver type implicit", "increments"}},
      {"key of another load type", {{"      value: 1.0e6\n", "      value: 1.0e6\n      set: top\n"}},
       "loads.push.set", {"key not allowed for type pressure", "element-set"}},
      {"pressure with both value and vector",
       {{"      value: 1.0e6\n", "      value: 1.0e6\n      vector: [0.0, 0.0, -1.0]\n"}}, "loads.push",
       {"needs exactly one of value (pressure [Pa] along the element normal) or vector"}},
      {"follower traction vector",
       {{"      value: 1.0e6\n", "      vector: [0.0, 0.0, -1.0]\n      follower: true\n"}}, "loads.push.follower",
       {"applies to value only"}},
      {"point force with neither force nor moment",
       {{"      type: pressure\n      value: 1.0e6\n", "      type: point-force\n      set: top\n"}},
       "loads.push", {"needs a vector (force [N]), a moment (moment [N m]) or both"}},
      {"missing material key", {{"    density: 7850.0\n", ""}}, "material.density", {"missing required key"}},
      {"missing version", {{"  version: 1\n", ""}}, "version", {"missing required key"}},
      {"missing solver", {{"  solver:\n    type: implicit\n    increments: 10\n", ""}}, "solver",
       {"missing required key"}},
      {"string for a number", {{"young-modulus: 210.0e9", "young-modulus: stiff"}}, "material.young-modulus",
       {"expected a number, got the string 'stiff'"}},
      {"list for a number", {{"spacing: 1.0e-3", "spacing: [1, 2]"}}, "mesh.spacing",
       {"expected a number, got a list"}},
      {"scalar for a map", {{"  zones:\n    default: pd\n", "  zones: pd\n"}}, "zones",
       {"expected a map", "the string 'pd'"}},
      {"two components for a vector",
       {{"    spacing: 1.0e-3\n",
         "    spacing: 1.0e-3\n    pre-cracks:\n      c:\n        start: [0, 0.015]\n"
         "        end: [0.045, 0.015, 0]\n        normal: [0, 0, 1]\n"}},
       "mesh.pre-cracks.c.start", {"expected 3 numbers [x, y, z], got 2"}},
      {"word for a whole number", {{"version: 1", "version: one"}}, "version",
       {"expected a whole number, got the string 'one'"}},
      {"number for a flag", {{"      curve: ramp\n", "      curve: ramp\n      follower: 3\n"}},
       "loads.push.follower", {"expected true or false, got the number 3"}},
      {"infinite number", {{"young-modulus: 210.0e9", "young-modulus: .inf"}}, "material.young-modulus",
       {"not a finite number ('.inf')"}},
      {"nan", {{"density: 7850.0", "density: nan"}}, "material.density", {"not a finite number ('nan')"}},
      {"overflowing number", {{"thickness: 0.8e-3", "thickness: 1e400"}}, "material.thickness",
       {"not a finite number ('1e400')"}},
      {"nan inside a vector",
       {{"    spacing: 1.0e-3\n",
         "    spacing: 1.0e-3\n    pre-cracks:\n      c:\n        start: [0, nan, 0]\n"
         "        end: [0.045, 0.015, 0]\n        normal: [0, 0, 1]\n"}},
       "mesh.pre-cracks.c.start[1]", {"not a finite number ('nan')"}},
      {"zero Young's modulus", {{"young-modulus: 210.0e9", "young-modulus: 0"}}, "material.young-modulus",
       {"must be positive, got 0"}},
      {"negative Young's modulus", {{"young-modulus: 210.0e9", "young-modulus: -72e9"}},
       "material.young-modulus", {"must be positive, got -7.2e+10"}},
      {"negative thickness", {{"thickness: 0.8e-3", "thickness: -0.8e-3"}}, "material.thickness",
       {"must be positive, got -0.0008"}},
      {"zero density", {{"density: 7850.0", "density: 0.0"}}, "material.density", {"must be positive, got 0"}},
      {"negative fracture energy", {{"fracture-energy: 255.0e3", "fracture-energy: -1"}},
       "material.fracture-energy", {"must be >= 0", "got -1"}},
      {"Poisson ratio 0.5", {{"poisson-ratio: 0.3", "poisson-ratio: 0.5"}}, "material.poisson-ratio",
       {"must lie in (-1, 0.5), got 0.5"}},
      {"Poisson ratio -1", {{"poisson-ratio: 0.3", "poisson-ratio: -1"}}, "material.poisson-ratio",
       {"must lie in (-1, 0.5), got -1"}},
      {"Poisson ratio above 1/3 with default pd", {{"poisson-ratio: 0.3", "poisson-ratio: 0.34"}},
       "material.poisson-ratio",
       {"microbeam PD needs nu <= 1/3 (model.md §2): c_bz and c_tor turn negative", "got 0.34",
        "zones.default is pd"}},
      {"Poisson ratio above 1/3 with a pd region",
       {{"poisson-ratio: 0.3", "poisson-ratio: 0.4"}, {"    default: pd\n", pdRegion}},
       "material.poisson-ratio", {"microbeam PD needs nu <= 1/3", "zones.pd-regions is set"}},
      {"Poisson ratio above 1/3 with a pd ratio",
       {{"poisson-ratio: 0.3", "poisson-ratio: 0.4"},
        {"    default: pd\n", "    default: ccm\n    pd-ratio:\n      target: 0.2\n      around: {tip: [0, 0, 0]}\n"}},
       "material.poisson-ratio", {"microbeam PD needs nu <= 1/3", "zones.pd-ratio is set"}},
      {"horizon smaller than the spacing", {{"horizon-factor: 3", "horizon-factor: 0.5"}},
       "peridynamics.horizon-factor", {"must be >= 1", "δ = m Δx >= Δx", "got 0.5"}},
      {"zero spacing", {{"spacing: 1.0e-3", "spacing: 0"}}, "mesh.spacing",
       {"the grid spacing Δx must be positive, got 0"}},
      {"negative spacing", {{"spacing: 1.0e-3", "spacing: -1.0e-3"}}, "mesh.spacing",
       {"must be positive, got -0.001"}},
      {"unknown curve in a load", {{"      curve: ramp\n", "      curve: rmp\n"}}, "loads.push.curve",
       {"unknown curve 'rmp'; defined curves: ramp"}},
      {"unknown curve in a support", {{"      set: left\n", "      set: left\n      curve: pull\n"}},
       "supports.left.curve", {"unknown curve 'pull'"}},
      {"implicit without supports",
       {{"  supports:\n    left:\n      set: left\n      dofs: [ux, uy, uz, rx, ry, rz]\n", ""}}, "supports",
       {"an unsupported model is singular"}},
      {"unknown tangent", {{"    increments: 10\n", "    increments: 10\n    tangent: skew\n"}}, "solver.tangent",
       {"'skew' is not one of auto, symmetric, exact"}},
      {"unknown newton format", {{"    increments: 10\n", "    increments: 10\n    newton: modified\n"}},
       "solver.newton", {"'modified' is not one of mixed, displacement"}},
      {"unknown factorization place", {{"    increments: 10\n", "    increments: 10\n    factorization: gpu\n"}},
       "solver.factorization", {"'gpu' is not one of auto, host, device"}},
      {"amg reuse below 1", {{"    increments: 10\n", "    increments: 10\n    amg-reuse: 0.5\n"}}, "solver.amg-reuse",
       {"must be 0 (rebuild the multigrid hierarchy at every Newton iteration) or a growth factor in [1, 100], got 0.5"}},
      {"amg drop tolerance of 1", {{"    increments: 10\n", "    increments: 10\n    amg-drop-tolerance: 1\n"}},
       "solver.amg-drop-tolerance", {"must be in [0, 1) (0 aggregates over every coupling), got 1"}},
      {"amg coarse nodes of 0", {{"    increments: 10\n", "    increments: 10\n    amg-coarse-nodes: 0\n"}},
       "solver.amg-coarse-nodes", {"must be a whole number in [1, 2000]", "got 0"}},
      {"amg local scaling not a flag", {{"    increments: 10\n", "    increments: 10\n    amg-region-scaling: 20\n"}},
       "solver.amg-region-scaling", {"expected true or false"}},
      {"overlap not a flag", {{"    increments: 10\n", "    increments: 10\n    overlap: 2\n"}},
       "solver.overlap", {"expected true or false"}},
      {"unknown generator", {{"generator: plate", "generator: disc"}}, "mesh.generator",
       {"'disc' is not one of plate, cylinder, hexagonal-prism, gmsh"}},
      {"unsupported version", {{"version: 1", "version: 2"}}, "version", {"unsupported deck version 2"}},
      {"unknown dof", {{"dofs: [ux, uy, uz, rx, ry, rz]", "dofs: [ux, uw]"}}, "supports.left.dofs",
       {"'uw' is not one of ux, uy, uz, rx, ry, rz"}},
      {"dof twice", {{"dofs: [ux, uy, uz, rx, ry, rz]", "dofs: [ux, ux]"}}, "supports.left.dofs",
       {"'ux' is listed twice"}},
      {"pd region with two shapes",
       {{"    default: pd\n",
         "    default: ccm\n    pd-regions:\n      zone:\n        box: {min: [0, 0, 0], max: [1, 1, 1]}\n"
         "        element-set: {name: e}\n"}},
       "zones.pd-regions.zone", {"needs exactly one of box, cylinder, element-set; got box, element-set"}},
      {"inverted box",
       {{"    default: pd\n",
         "    default: ccm\n    pd-regions:\n      zone:\n        box: {min: [0, 0, 0], max: [1, -1, 1]}\n"}},
       "zones.pd-regions.zone.box.max", {"component 1 is -1 < 0"}},
      {"pd regions on a pd default",
       {{"    default: pd\n", "    default: pd\n    pd-regions:\n      zone:\n        element-set: {name: e}\n"}},
       "zones.pd-regions", {"needs default: ccm"}},
      {"pd ratio out of range",
       {{"    default: pd\n", "    default: ccm\n    pd-ratio:\n      target: 1.5\n      around: {tip: [0, 0, 0]}\n"}},
       "zones.pd-ratio.target", {"must lie in [0, 1]", "got 1.5"}},
      {"table time not increasing",
       {{"      type: ramp\n      end-time: 1.0\n",
         "      type: table\n      time: [0, 0.2, 0.1]\n      value: [0, 1, 1]\n"}},
       "curves.ramp.time", {"must be strictly increasing: time[2] = 0.1 is not greater than time[1] = 0.2"}},
      {"explicit with both end-time and steps",
       {{"    type: implicit\n    increments: 10\n", "    type: explicit\n    end-time: 1.0\n    steps: 10\n"}},
       "solver", {"exactly one of end-time [s] or steps"}},
      {"velocity for the implicit solver", {{"    every: 1\n", "    every: 1\n    fields: [displacement, velocity]\n"}},
       "output.fields", {"velocity exists only for the explicit solver"}},
      {"history every zero", {{"    every: 1\n", "    every: 1\n    history-every: 0\n"}}, "output.history-every",
       {"must be >= 1, got 0"}},
      {"checkpoint every zero steps", {{"    every: 1\n", "    every: 1\n    checkpoint-every: 0\n"}},
       "output.checkpoint-every", {"must be >= 1 step, got 0"}},
      {"checkpoint every hour", {{"    every: 1\n", "    every: 1\n    checkpoint-every: 2 h\n"}},
       "output.checkpoint-every", {"unknown unit 'h' (only 'min')"}},
      {"checkpoint every zero minutes", {{"    every: 1\n", "    every: 1\n    checkpoint-every: 0 min\n"}},
       "output.checkpoint-every", {"a wall time must be > 0 minutes, got '0 min'"}},
      {"checkpoint every fraction of a step", {{"    every: 1\n", "    every: 1\n    checkpoint-every: [2.5, 3 min]\n"}},
       "output.checkpoint-every", {"a number of steps must be a whole number >= 1, got '2.5'"}},
      {"checkpoint every three things", {{"    every: 1\n", "    every: 1\n    checkpoint-every: [1, 2, 3]\n"}},
       "output.checkpoint-every", {"a wall time such as '30 min', or a list of both", "got a list of numbers"}},
      {"probe given as a number", {{"    every: 1\n", "    every: 1\n    probes: {tip: 3}\n"}}, "output.probes.tip",
       {"expected a list of numbers like [1, 2.5], got the number 3"}},
      {"probe with two coordinates", {{"    every: 1\n", "    every: 1\n    probes: {tip: [0.09, 0.03]}\n"}},
       "output.probes.tip", {"expected 3 numbers [x, y, z], got 2"}},
      {"probes as a list, not named points", {{"    every: 1\n", "    every: 1\n    probes: [0.09, 0.03, 0]\n"}},
       "output.probes", {"expected a map", "got a list"}},
      {"probe name with a comma", {{"    every: 1\n", "    every: 1\n    probes: {'tip,1': [0, 0, 0]}\n"}},
       "output.probes.tip,1", {"may not hold commas, quotes or line breaks"}},
      {"probe named like a load point",
       {{"      type: pressure\n      value: 1.0e6\n",
         "      type: point-force\n      set: left\n      vector: [0, 0, 1]\n"},
        {"    every: 1\n", "    every: 1\n    history: [load-points]\n    probes: {push: [0, 0, 0]}\n"}},
       "output.probes.push", {"would repeat the load-points columns of loads.push; rename the probe"}},
  };
  expectDeckErrors(cases);
}

TEST(TEST_CATEGORY, deck_checkpoint_every_takes_steps_minutes_or_both) {
  const auto outputOf = [](const std::string& value) {
    return parseDeck(edited(baseDeck, {{"    every: 1\n", "    every: 1\n    checkpoint-every: " + value + "\n"}}),
                     "checkpoints.yaml")
        .output;
  };
  EXPECT_FALSE(parseDeck(baseDeck, "base.yaml").output.checkpoints());
  const auto steps = outputOf("5000");
  EXPECT_EQ(steps.checkpointEvery, 5000);
  EXPECT_EQ(steps.checkpointMinutes, 0.0);
  EXPECT_TRUE(steps.checkpoints());
  const auto minutes = outputOf("2.5 min");
  EXPECT_EQ(minutes.checkpointEvery, 0);
  EXPECT_EQ(minutes.checkpointMinutes, 2.5);
  const auto both = outputOf("[30 min, 200]");
  EXPECT_EQ(both.checkpointEvery, 200);
  EXPECT_EQ(both.checkpointMinutes, 30.0);
}

TEST(TEST_CATEGORY, deck_probes_snap_to_the_nearest_node_or_name_the_distance) {
  // The base plate: 0.09 m x 0.03 m in z = 0, spacing 1 mm, nodes on the millimetre grid.
  auto probesOf = [](const std::string& probes) {
    const auto model =
        model::buildModel(parseDeck(edited(baseDeck, {{"    every: 1\n", "    every: 1\n" + probes}}), "bad.yaml"));
    return std::make_pair(solvers::snapProbes(model), model);
  };
  const auto [probes, model] = probesOf("    probes: {tip: [0.0902, 0.0303, 0.0], centre: [0.045, 0.015, 0.0006]}\n");
  EXPECT_NEAR(solvers::probeReach(model), 1.0e-3, 1e-15);  // the longest edge, to round-off
  ASSERT_EQ(probes.size(), 2u);
  const auto& x = model.shell.mesh.coordinates;
  EXPECT_EQ(probes[0].name, "tip");
  EXPECT_NEAR(x(probes[0].node, 0), 0.09, 1e-15);  // the top-right corner
  EXPECT_NEAR(x(probes[0].node, 1), 0.03, 1e-15);
  EXPECT_NEAR(probes[0].distance, std::hypot(2e-4, 3e-4), 1e-15);
  EXPECT_EQ(probes[1].name, "centre");
  EXPECT_NEAR(x(probes[1].node, 0), 0.045, 1e-15);
  EXPECT_NEAR(x(probes[1].node, 1), 0.015, 1e-15);
  EXPECT_NEAR(probes[1].distance, 6e-4, 1e-15);

  // 2 mm above the plate: farther than the 1 mm spacing and the 1 mm elements.
  try {
    probesOf("    probes: {tip: [0.09, 0.03, 0.0], above: [0.045, 0.015, 0.002]}\n");
    ADD_FAILURE() << "a probe 2 mm off a plate meshed at 1 mm was accepted";
  } catch (const DeckError& error) {
    EXPECT_EQ(error.keyPath(), "output.probes.above");
    EXPECT_EQ(error.reason(),
              "the nearest mesh node to [0.045, 0.015, 0.002] m, node 1410 at [0.045, 0.015, 0] m, is 0.002 m away, "
              "farther than 0.001 m (the larger of mesh.spacing and the longest element edge): a probe must lie on "
              "the shell");
  }
}

TEST(TEST_CATEGORY, deck_yaml_errors_name_the_line) {
  // The unclosed list opens on the thickness line; Teuchos notices on the next one.
  const std::string unclosed = edited(baseDeck, {{"thickness: 0.8e-3", "thickness: [0.8e-3"}});
  const auto beforeThickness = unclosed.substr(0, unclosed.find("thickness"));
  const int thicknessLine = 1 + int(std::count(beforeThickness.begin(), beforeThickness.end(), '\n'));
  ASSERT_EQ(thicknessLine, 13);
  const DeckError syntax = deckErrorOf(unclosed);
  EXPECT_EQ(syntax.keyPath(), "");
  EXPECT_EQ(syntax.line(), thicknessLine + 1);
  EXPECT_NE(syntax.reason().find("YAML error at line 14, column 5"), std::string::npos) << syntax.reason();
  EXPECT_NE(syntax.reason().find("Expected one of {',', ]}"), std::string::npos) << syntax.reason();
  EXPECT_EQ(std::string(syntax.what()), "bad.yaml: " + syntax.reason());

  const DeckError duplicate =
      deckErrorOf(edited(baseDeck, {{"    density: 7850.0\n", "    density: 7850.0\n    density: 2440\n"}}));
  EXPECT_NE(duplicate.reason().find("duplicate key 'density'"), std::string::npos) << duplicate.reason();
  EXPECT_GT(duplicate.line(), 0);

  const DeckError listOfMaps = deckErrorOf(
      edited(baseDeck, {{"  supports:\n    left:\n      set: left\n", "  supports:\n    - set: left\n"}}));
  EXPECT_NE(listOfMaps.reason().find("write repeated items as named maps"), std::string::npos)
      << listOfMaps.reason();

  const DeckError noRoot = deckErrorOf(edited(baseDeck, {{"perishell:\n", "deck:\n"}}));
  EXPECT_EQ(noRoot.line(), 1);
  EXPECT_NE(noRoot.reason().find("one map under the root key 'perishell:'"), std::string::npos)
      << noRoot.reason();
  const DeckError secondRoot = deckErrorOf(baseDeck + "extra: 1\n");
  EXPECT_NE(secondRoot.reason().find("a second top-level key 'extra'"), std::string::npos)
      << secondRoot.reason();
  // Comments may hold any UTF-8; values may not (Teuchos' lexer is ASCII only).
  const std::string unicodeComment =
      edited(baseDeck, {{"  title: base\n", "  title: base  # Δx, m², it's ok\n"}});
  EXPECT_EQ(parseDeck(unicodeComment, "ok.yaml").title, "base");
  const DeckError unicodeValue = deckErrorOf(edited(baseDeck, {{"title: base", "title: \"Δx study\""}}));
  EXPECT_EQ(unicodeValue.line(), 3);
  EXPECT_NE(unicodeValue.reason().find("line 3, column 11: non-ASCII character"), std::string::npos)
      << unicodeValue.reason();

  const DeckError empty = deckErrorOf("# nothing here\n");
  EXPECT_NE(empty.reason().find("empty deck"), std::string::npos) << empty.reason();
}

TEST(TEST_CATEGORY, deck_without_a_final_newline_or_ending_in_a_comment_parses) {
  // Issue 22: both gave "YAML error ...: Expected one of {',', NEWLINE, ...}; Got: EOF".
  ASSERT_EQ(baseDeck.back(), '\n');
  const std::string noNewline = baseDeck.substr(0, baseDeck.size() - 1);
  EXPECT_EQ(parseDeck(noNewline, "no-newline.yaml").solver.implicitSettings.increments, 10);
  EXPECT_EQ(parseDeck(noNewline + "  # the end", "comment.yaml").solver.implicitSettings.increments, 10);
  EXPECT_EQ(parseDeck(baseDeck + "# the end", "comment.yaml").output.every, 1);
  EXPECT_EQ(parseDeck(baseDeck + "# the end\n", "comment.yaml").output.every, 1);
  EXPECT_EQ(parseDeck(noNewline + "\r\n", "crlf.yaml").output.every, 1);
}

// parseDeck's message for a text it refuses ("" when it accepts it).
std::string refusalOf(const std::string& text) {
  try {
    parseDeck(text, "big.yaml");
  } catch (const DeckError& error) {
    return error.what();
  }
  return "";
}

TEST(TEST_CATEGORY, deck_over_one_mib_or_of_pathological_shape_is_refused) {
  // Issue 22: a 300 k-character scalar took 28-59 s to parse, a 1e5-item list 34 s, a 4 MB
  // scalar over 10 minutes; there was no size limit. These limits bound the parse time, which
  // perf/deck_limits.cpp measures on the same shapes.
  const std::string oversized = baseDeck + "# " + std::string(maxDeckBytes, 'x') + "\n";
  const std::string oversizedMessage = refusalOf(oversized);
  EXPECT_EQ(oversizedMessage, "big.yaml: the deck is " + std::to_string(oversized.size()) +
                                  " bytes, over the limit of 1048576 bytes (1 MiB); a deck holds settings, and a "
                                  "large mesh goes in its own file (mesh.file)");
  // readDeck reads no more than the limit (and one byte) of a larger file.
  const fs::path file = scratchDirectory() / "oversized.yaml";
  { std::ofstream(file) << oversized; }
  try {
    readDeck(file.string());
    ADD_FAILURE() << "an oversized deck file was read";
  } catch (const DeckError& error) {
    EXPECT_NE(error.reason().find("the deck is " + std::to_string(oversized.size()) + " bytes, over the limit"),
              std::string::npos)
        << error.reason();
  }
  fs::remove_all(scratchDirectory());

  const std::string longScalar = edited(baseDeck, {{"title: base", "title: " + std::string(300000, 'a')}});
  const std::string scalarMessage = refusalOf(longScalar);
  EXPECT_EQ(scalarMessage, "big.yaml: line 3: the line is 300009 characters long, over the limit of "
                           "4096 characters of a deck line");
  std::string items;
  for (int k = 0; k < 100000; ++k) items += (k ? ", " : "") + std::to_string(k % 10);
  const std::string longList = edited(baseDeck, {{"title: base", "title: base\n  notes: [" + items + "]"}});
  const std::string listMessage = refusalOf(longList);
  EXPECT_EQ(listMessage.rfind("big.yaml: line 4: the line is 300009 characters long", 0), 0u) << listMessage;

  // Flow maps 3,000 deep took 6.5 s; the same list of 100,000 items over short lines, 0.9 s.
  std::string nested = "1";
  for (int level = 0; level < 12; ++level) nested = "{a: " + nested + "}";
  EXPECT_EQ(deckErrorOf(edited(baseDeck, {{"title: base", "title: base\n  notes: " + nested}})).reason(),
            "line 4: maps and lists nest more than 12 levels deep");
  std::string shortLines;
  for (int k = 0; k < 20000; ++k) shortLines += "    k" + std::to_string(k) + ": 1\n";
  const DeckError many = deckErrorOf(edited(baseDeck, {{"title: base", "title: base\n  notes:\n" + shortLines}}));
  EXPECT_EQ(many.line(), 20001);
  EXPECT_EQ(many.reason().rfind("line 20001: the deck has more than 20000 entries (keys, list items and lines)", 0), 0u)
      << many.reason();

  // The costliest decks within the bounds: 19,900 entries 11 levels deep, or in flow maps 10
  // deep; each is read whole and refused by the schema for its unknown key.
  std::string block;
  for (int group = 0; group < 1800; ++group) {
    block += "  b" + std::to_string(group) + ":\n";
    for (int level = 0; level < 9; ++level) block += std::string(4 + 2 * level, ' ') + "k:\n";
    block += std::string(22, ' ') + "x: 1\n";
  }
  std::string flowMaps, flow = "1";
  for (int level = 0; level < 10; ++level) flow = "{a: " + flow + "}";
  for (int k = 0; k < 1800; ++k) flowMaps += "  n" + std::to_string(k) + ": " + flow + "\n";
  for (const auto& within : {block, flowMaps}) {
    const std::string message = refusalOf(edited(baseDeck, {{"  version: 1\n", "  version: 1\n" + within}}));
    EXPECT_NE(message.find(": unknown key; allowed keys here: version, title"), std::string::npos) << message;
  }
}

TEST(TEST_CATEGORY, deck_messages_never_show_the_parser_internals) {
  // Issue 22: any_cast text with build-cache paths, "bug in YAMLParameterList::Reader", C++
  // class names reached the user. Each of these decks is refused in the deck's own terms.
  const std::vector<std::string> bad = {
      edited(baseDeck, {{"thickness: 0.8e-3", "thickness: [1, a]"}}),
      edited(baseDeck, {{"thickness: 0.8e-3", "thickness: [[1, 2], [3]]"}}),
      edited(baseDeck, {{"thickness: 0.8e-3", "thickness: {a: [1, 2], b: x}"}}),
      edited(baseDeck, {{"thickness: 0.8e-3", "thickness: &anchor 1"}}),
      edited(baseDeck, {{"thickness: 0.8e-3", "thickness: !!binary aGVsbG8="}}),
      edited(baseDeck, {{"thickness: 0.8e-3", "thickness: |\n      block"}}),
      edited(baseDeck, {{"thickness: 0.8e-3", "thickness: ? a"}}),
      edited(baseDeck, {{"thickness: 0.8e-3", "thickness: []"}}),
      edited(baseDeck, {{"thickness: 0.8e-3", "thickness: [1, 2.5]"}}),
      edited(baseDeck, {{"  version: 1\n", "  version: 1\n  version2: *x\n"}}),
      "perishell: 1\n",
      "perishell:\n  - a\n  - b\n",
      "perishell: {version: 1, mesh: [}\n",
      "perishell:\n\tversion: 1\n",
  };
  for (const auto& text : bad) {
    std::string message;
    try {
      parseDeck(text, "bad.yaml");
      continue;  // some are valid YAML that the schema refuses below, or accepts
    } catch (const DeckError& error) {
      message = error.what();
    } catch (const std::exception& error) {
      ADD_FAILURE() << "not a DeckError: " << error.what() << "\n" << text;
      continue;
    }
    EXPECT_EQ(message.rfind("bad.yaml: ", 0), 0u) << message;
    for (const char* internal : {"Teuchos", "any_cast", "YAMLParameterList", "::", ".cpp", ".hpp", "bug in",
                                 "Throw", "/root", "std::", "typeid", "RCP"})
      EXPECT_EQ(message.find(internal), std::string::npos) << "'" << internal << "' in: " << message;
  }
}

TEST(TEST_CATEGORY, deck_unreadable_files_are_reported) {
  const fs::path missing = scratchDirectory() / "no-such-deck.yaml";
  try {
    readDeck(missing.string());
    ADD_FAILURE() << "a missing file was read";
  } catch (const DeckError& error) {
    EXPECT_EQ(std::string(error.what()), missing.string() + ": cannot read the deck: no such file");
  }
  try {
    readDeck(scratchDirectory().string());
    ADD_FAILURE() << "a directory was read";
  } catch (const DeckError& error) {
    EXPECT_EQ(error.reason(), "cannot read the deck: it is a directory");
  }
  fs::remove_all(scratchDirectory());
}

}  // namespace

TEST(TEST_CATEGORY, deck_zones_transition_defaults_values_and_rules) {
  const std::string region = "    default: ccm\n    pd-regions:\n      zone:\n        box: {min: [0, 0, -1], max: [1, 1, 1]}\n";
  // Default: 2 delta = 2 x 3 x 1 mm, cubic, whatever the zones.
  const Deck plain = parseDeck(baseDeck, "plain.yaml");
  EXPECT_DOUBLE_EQ(plain.zones.transition.width, 6e-3);
  EXPECT_EQ(plain.zones.transition.profile, deck::TransitionProfile::Cubic);
  const Deck given = parseDeck(
      edited(baseDeck, {{"    default: pd\n", region + "    transition: {width: 8.0e-3, profile: linear}\n"}}), "given.yaml");
  EXPECT_DOUBLE_EQ(given.zones.transition.width, 8e-3);
  EXPECT_EQ(given.zones.transition.profile, deck::TransitionProfile::Linear);
  // Exactly 2 delta, written out, passes.
  EXPECT_DOUBLE_EQ(
      parseDeck(edited(baseDeck, {{"    default: pd\n", region + "    transition: {width: 6.0e-3}\n"}}), "exact.yaml")
          .zones.transition.width,
      6e-3);
  const std::vector<BadDeck> cases{
      {"narrower than 2 delta", {{"    default: pd\n", region + "    transition: {width: 5.0e-3}\n"}},
       "zones.transition.width", {"must be >= 2 delta = 0.006 m", "model.md §4", "got 0.005"}},
      {"unknown profile", {{"    default: pd\n", region + "    transition: {profile: quintic}\n"}},
       "zones.transition.profile", {"quintic"}},
      {"unknown key", {{"    default: pd\n", region + "    transition: {length: 1.0}\n"}}, "zones.transition.length",
       {"unknown key", "width, profile"}},
      {"with default pd", {{"    default: pd\n", "    default: pd\n    transition: {width: 8.0e-3}\n"}},
       "zones.transition", {"needs default: ccm"}},
      {"in a pure CCM model", {{"    default: pd\n", "    default: ccm\n    transition: {width: 8.0e-3}\n"}},
       "zones.transition", {"needs a PD zone"}},
  };
  expectDeckErrors(cases);
}

TEST(TEST_CATEGORY, deck_zones_adaptive_values_and_rules) {
  const Edit explicitSolver{"    type: implicit\n    increments: 10\n", "    type: explicit\n    steps: 10\n"};
  const Edit adaptiveZone{"    default: pd\n",
                          "    default: ccm\n    adaptive: {strain-fraction: 0.3, check-every: 5, margin: 4.0e-3}\n"};
  const Deck given = parseDeck(edited(baseDeck, {explicitSolver, adaptiveZone}), "adaptive.yaml");
  ASSERT_TRUE(given.zones.adaptive.has_value());
  EXPECT_DOUBLE_EQ(given.zones.adaptive->strainFraction, 0.3);
  EXPECT_EQ(given.zones.adaptive->checkEvery, 5);
  EXPECT_DOUBLE_EQ(given.zones.adaptive->margin, 4.0e-3);
  EXPECT_TRUE(given.zones.hasPd());  // the nu <= 1/3 rule applies
  const Deck defaults = parseDeck(
      edited(baseDeck, {explicitSolver, {"    default: pd\n", "    default: ccm\n    adaptive: {check-every: 10}\n"}}),
      "defaults.yaml");
  ASSERT_TRUE(defaults.zones.adaptive.has_value());
  EXPECT_DOUBLE_EQ(defaults.zones.adaptive->strainFraction, 0.5);
  EXPECT_EQ(defaults.zones.adaptive->checkEvery, 10);
  EXPECT_DOUBLE_EQ(defaults.zones.adaptive->margin, 2.0 * defaults.peridynamics.horizonFactor * defaults.mesh.spacing);
  EXPECT_FALSE(parseDeck(baseDeck, "plain.yaml").zones.adaptive.has_value());
  const std::vector<BadDeck> cases{
      {"fraction above 1", {explicitSolver, {"    default: pd\n", "    default: ccm\n    adaptive: {strain-fraction: 1.5}\n"}},
       "zones.adaptive.strain-fraction", {"must lie in (0, 1]", "got 1.5"}},
      {"fraction 0", {explicitSolver, {"    default: pd\n", "    default: ccm\n    adaptive: {strain-fraction: 0.0}\n"}},
       "zones.adaptive.strain-fraction", {"must lie in (0, 1]"}},
      {"check every 0", {explicitSolver, {"    default: pd\n", "    default: ccm\n    adaptive: {check-every: 0}\n"}},
       "zones.adaptive.check-every", {"must be >= 1"}},
      {"negative margin", {explicitSolver, {"    default: pd\n", "    default: ccm\n    adaptive: {margin: -1.0e-3}\n"}},
       "zones.adaptive.margin", {"must be >= 0", "got -0.001"}},
      {"unknown key", {explicitSolver, {"    default: pd\n", "    default: ccm\n    adaptive: {threshold: 0.5}\n"}},
       "zones.adaptive.threshold", {"unknown key"}},
      {"with default pd", {explicitSolver, {"    default: pd\n", "    default: pd\n    adaptive: {check-every: 5}\n"}},
       "zones.adaptive", {"needs default: ccm"}},
      {"implicit", {adaptiveZone}, "zones.adaptive", {"only in explicit runs"}},
      {"no fracture energy", {explicitSolver, adaptiveZone, {"    fracture-energy: 255.0e3\n", ""}}, "zones.adaptive",
       {"needs material.fracture-energy"}},
      {"nu above 1/3", {explicitSolver, adaptiveZone, {"poisson-ratio: 0.3", "poisson-ratio: 0.4"}},
       "material.poisson-ratio", {"zones.adaptive is set"}},
  };
  expectDeckErrors(cases);
}

TEST(TEST_CATEGORY, deck_explicit_shell_element_and_hourglass_keys) {
  const std::string explicitSolver = "    type: explicit\n    steps: 10\n";
  const Deck plain = parseDeck(edited(baseDeck, {{"    type: implicit\n    increments: 10\n", explicitSolver}}),
                               "plain.yaml");
  EXPECT_EQ(plain.solver.explicitSettings.shellElement, deck::ExplicitSettings::ShellElement::OnePoint);
  EXPECT_DOUBLE_EQ(plain.solver.explicitSettings.hourglassCoefficient, 0.1);
  const Deck given = parseDeck(
      edited(baseDeck, {{"    type: implicit\n    increments: 10\n", explicitSolver + "    shell-element: mitc4\n    hourglass: 0.05\n"}}),
      "given.yaml");
  EXPECT_EQ(given.solver.explicitSettings.shellElement, deck::ExplicitSettings::ShellElement::Mitc4);
  EXPECT_DOUBLE_EQ(given.solver.explicitSettings.hourglassCoefficient, 0.05);
  const std::vector<BadDeck> cases{
      {"unknown element", {{"    type: implicit\n    increments: 10\n", explicitSolver + "    shell-element: blt\n"}},
       "solver.shell-element", {"blt", "one-point", "mitc4"}},
      {"hourglass zero", {{"    type: implicit\n    increments: 10\n", explicitSolver + "    hourglass: 0\n"}},
       "solver.hourglass", {"must lie in (0, 1]", "got 0"}},
      {"implicit", {{"    increments: 10\n", "    increments: 10\n    shell-element: one-point\n"}},
       "solver.shell-element", {"key not allowed for solver type implicit"}},
  };
  expectDeckErrors(cases);
}
