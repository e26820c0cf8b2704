// The `perishell run` driver on a quasi-static case with a known answer: a clamped strip
// pulled by an edge traction, heavily damped, settles where the clamp's reaction balances
// the load (-sigma t W); the history and field files are written with the documented columns.
#include <perishell/model/model.hpp>
#include <perishell/solvers/explicit/explicit_run.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

namespace perishell_test_explicit_run {

std::vector<std::string> splitCsv(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream stream(line);
  for (std::string cell; std::getline(stream, cell, ',');) cells.push_back(cell);
  return cells;
}

// The run driver's backend that runs on ExecutionSpaceT.
template <class ExecutionSpaceT>
perishell::solvers::Backend backendOf() {
  return std::is_same_v<ExecutionSpaceT, perishell::ExecutionSpace> ? perishell::solvers::Backend::Device
                                                                     : perishell::solvers::Backend::Host;
}

}  // namespace perishell_test_explicit_run

TEST(TEST_CATEGORY, explicit_run_settles_to_the_static_reaction_and_writes_its_history) {
  using namespace perishell_test_explicit_run;
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
)";
  const auto model = perishell::model::buildModel(perishell::parseDeck(text, "strip.yaml"));
  std::ostringstream log;
  const auto summary = perishell::solvers::runExplicit(model, {directory, backendOf<TEST_EXECSPACE>()}, log);
  EXPECT_EQ(summary.steps, 3000);
  EXPECT_EQ(summary.brokenBonds, 0);
  EXPECT_NE(log.str().find("explicit run summary"), std::string::npos) << log.str();
  EXPECT_TRUE(std::filesystem::exists(directory + "/results.xmf"));

  std::ifstream history(summary.historyPath);
  std::string line;
  ASSERT_TRUE(std::getline(history, line));
  const auto columns = splitCsv(line);
  const std::vector<std::string> expected = {
      "step", "time", "load-factor-ramp", "kinetic", "strain", "fracture", "damping", "external-work", "support-work",
      "energy-balance-error", "reaction-clamp-x", "reaction-clamp-y", "reaction-clamp-z", "broken-bonds", "crack-tip-x",
      "crack-tip-y", "crack-tip-z", "crack-length", "crack-tip-speed"};
  EXPECT_EQ(columns, expected);
  std::vector<std::vector<std::string>> rows;
  while (std::getline(history, line)) rows.push_back(splitCsv(line));
  ASSERT_EQ(rows.size(), 31u);  // step 0 and every 100 steps
  const auto& last = rows.back();
  EXPECT_EQ(std::stoll(last[0]), 3000);
  EXPECT_DOUBLE_EQ(std::stod(last[2]), 1.0);
  // Static balance: the clamp holds the pull, -sigma t W = -300 N along x.
  EXPECT_NEAR(std::stod(last[10]) / (-traction * thickness * width), 1.0, 0.01);
  EXPECT_NEAR(std::stod(last[11]), 0.0, 1e-6 * traction * thickness * width);
  // Damping took what the load put in beyond the strain energy; the balance closes.
  EXPECT_LT(std::abs(std::stod(last[9])), 0.02);
  EXPECT_GT(std::stod(last[6]), 0.0);
  EXPECT_EQ(std::stod(last[13]), 0.0);
  EXPECT_EQ(std::stod(last[17]), 0.0);  // no damaged node, no crack

  // timings.csv: the phases of the summary, the steps and the output within the total.
  std::ifstream timings(summary.timingsPath);
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
  EXPECT_LE(seconds["setup"] + seconds["steps"] + seconds["output"], seconds["total"] * (1 + 1e-9));
  std::filesystem::remove_all(directory);
}
