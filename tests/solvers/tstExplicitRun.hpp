// The `perishell run` driver on a quasi-static case with a known answer: a clamped strip
// pulled by an edge traction, heavily damped, settles where the supports' reactions balance
// the load (-sigma t W; a pin shares the clamp's corner); the history and field files are
// written with the documented columns.
#include <perishell/model/model.hpp>
#include <perishell/solvers/explicit/explicit_run.hpp>

#include <solvers/run_files.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

TEST(TEST_CATEGORY, explicit_run_settles_to_the_static_reaction_and_writes_its_history) {
  using namespace perishell_test_run_files;
  char pattern[] = "/tmp/perishell_run_XXXXXX";
  ASSERT_NE(mkdtemp(pattern), nullptr);
  const std::string directory = pattern;
  const double traction = 50e6, thickness = 1e-3, width = 6e-3;
  const std::string text = R"(perishell:
  version: 1
  mesh: {generator: plate, length-x: 0.020, length-y: 0.006, spacing: 1.0e-3}
  material: {young-modulus: 210.0e9, poisson-ratio: 0.3, density: 7850.0, thickness: 1.0e-3}
  supports:
    clamp: {set: left, dofs: [ux, uy, uz, rx, ry, rz]}
    pin: {set: bottom-left, dofs: [ux, uy]}
  loads:
    pull: {type: edge-traction, set: right, value: 50.0e6, curve: ramp}
  curves:
    ramp: {type: ramp, end-time: 5.0e-6}
  solver: {type: explicit, steps: 3000, damping: 5.0e5}
  output:
    every: 1500
    history-every: 100
    fields: [displacement, damage]
    history: [energy, reactions, broken-bonds, crack-tip]
    probes: {tip: [0.020, 0.003, 0.0]}
)";
  const auto model = perishell::model::buildModel(perishell::parseDeck(text, "strip.yaml"));
  std::ostringstream log;
  const auto summary = perishell::solvers::runExplicit(model, {directory, backendOf<TEST_EXECSPACE>()}, log);
  EXPECT_EQ(summary.steps, 3000);
  EXPECT_EQ(summary.brokenBonds, 0);
  EXPECT_NE(log.str().find("explicit run summary"), std::string::npos) << log.str();
  EXPECT_NE(log.str().find("probe tip: node 83 at [0.02, 0.003, 0] m, 0 m from the deck's point"), std::string::npos)
      << log.str();
  EXPECT_TRUE(std::filesystem::exists(directory + "/results.xmf"));

  const auto history = readHistory(summary.historyPath);
  const std::vector<std::string> expected = {
      "step", "time", "load-factor-ramp", "kinetic", "strain", "fracture", "damping", "external-work", "support-work",
      "energy-balance-error", "reaction-clamp-x", "reaction-clamp-y", "reaction-clamp-z", "reaction-pin-x",
      "reaction-pin-y", "reaction-pin-z", "reaction-total-x", "reaction-total-y", "reaction-total-z", "broken-bonds",
      "crack-tip-x", "crack-tip-y", "crack-tip-z", "crack-length", "crack-tip-speed", "tip-ux", "tip-uy", "tip-uz",
      "tip-rx", "tip-ry", "tip-rz"};
  EXPECT_EQ(history.columns, expected);
  ASSERT_EQ(history.rows.size(), 31u);  // step 0 and every 100 steps
  auto last = history.rows.back();
  EXPECT_EQ(last["step"], 3000);
  EXPECT_DOUBLE_EQ(last["load-factor-ramp"], 1.0);
  // Static balance: the supports hold the pull, -sigma t W = -300 N along x; the clamp and the
  // pin share the corner node's ux and uy, and together count it once.
  const double load = traction * thickness * width;
  EXPECT_NEAR(last["reaction-total-x"] / -load, 1.0, 0.01);
  EXPECT_NEAR(last["reaction-total-y"], 0.0, 1e-6 * load);
  for (const char* axis : {"x", "y", "z"})
    EXPECT_NEAR(last[std::string("reaction-clamp-") + axis] + last[std::string("reaction-pin-") + axis],
                last[std::string("reaction-total-") + axis], 1e-12 * load) << axis;
  EXPECT_LT(last["reaction-pin-x"], -1e-3 * load);  // half the corner's share of the pull
  EXPECT_EQ(last["reaction-pin-z"], 0.0);            // the pin holds no uz
  // The right edge's middle node: stretched about sigma L / E, not turned (the strip pulls
  // symmetrically about its middle line).
  EXPECT_NEAR(last["tip-ux"] / (traction * 0.020 / 210.0e9), 1.0, 0.1);
  EXPECT_NEAR(last["tip-uy"], 0.0, 1e-6 * last["tip-ux"]);
  EXPECT_NEAR(last["tip-rz"], 0.0, 1e-6 * last["tip-ux"] / 0.020);
  // Damping took what the load put in beyond the strain energy; the balance closes.
  EXPECT_LT(std::abs(last["energy-balance-error"]), 0.02);
  EXPECT_GT(last["damping"], 0.0);
  EXPECT_EQ(last["broken-bonds"], 0.0);
  EXPECT_EQ(last["crack-length"], 0.0);  // no damaged node, no crack

  // timings.csv: the phases of the summary, the steps and the output within the total.
  std::ifstream timings(summary.timingsPath);
  std::string line;
  ASSERT_TRUE(std::getline(timings, line));
  EXPECT_EQ(line, "phase,seconds");
  std::map<std::string, double> seconds;
  while (std::getline(timings, line)) {
    const auto fields = splitCsv(line);
    ASSERT_EQ(fields.size(), 2u) << line;
    seconds[fields[0]] = std::stod(fields[1]);
  }
  ASSERT_EQ(seconds.size(), summary.phases.size());
  for (const char* phase : {"setup", "steps", "output", "total"}) EXPECT_EQ(seconds.count(phase), 1u) << phase;
  EXPECT_EQ(seconds.count("forces"), 0u);  // phases of a step only with RunOptions::timePhases
  EXPECT_GT(seconds["steps"], 0.0);
  // Each value is written to 9 significant digits (up to 5e-9 of it off): the sum may pass the
  // total by that much.
  EXPECT_LE(seconds["setup"] + seconds["steps"] + seconds["output"], seconds["total"] * (1 + 2e-8));
  std::filesystem::remove_all(directory);
}
