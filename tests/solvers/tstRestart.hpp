// Checkpoint and restart (issue 22, docs/reliability.md §9): a run stopped at several points
// and continued with --restart ends in the state and files of the uninterrupted run, bit for
// bit on one backend: explicit with bonds breaking and an adaptive PD zone growing, implicit
// under arc-length control with the Cholesky preconditioner and under load control with AMG.
// A checkpoint that does not fit the deck is refused in the user's terms.
#include <perishell/io/checkpoint.hpp>
#include <perishell/model/model.hpp>
#include <perishell/solvers/explicit/explicit_run.hpp>
#include <perishell/solvers/implicit/implicit_run.hpp>
#include <perishell/solvers/run_checkpoint.hpp>

#include <scratch_directory.hpp>
#include <solvers/run_files.hpp>
#include <test_files.hpp>

#include <algorithm>
#include <cmath>
#include <type_traits>
#include <cstring>
#include <map>
#include <utility>
#include <sstream>
#include <string>
#include <vector>

namespace {

using perishell_test::readTextFile;
using perishell_test::ScratchDirectory;
using perishell_test::testDataDirectory;

// A shipped run deck with `addition` (checkpoint-every, so that the end state is checkpointed
// too) inserted after `outputKey`, `from` replaced by `to`, and its relative paths kept.
perishell::Deck runDeck(const std::string& name, const std::string& outputKey, const std::string& addition,
                        const std::string& from = "", const std::string& to = "") {
  const auto path = testDataDirectory / "decks" / "run" / name;
  std::string text = readTextFile(path);
  if (!from.empty()) {
    const auto where = text.find(from);
    if (where == std::string::npos) throw std::runtime_error(name + ": no '" + from + "'");
    text.replace(where, from.size(), to);
  }
  const auto at = text.find(outputKey);
  if (at == std::string::npos) throw std::runtime_error(name + ": no '" + outputKey + "'");
  text.insert(at + outputKey.size(), addition);
  return perishell::parseDeck(text, path.string());
}

enum class Solver { Explicit, Implicit };

// Runs the model into `directory` (a restart when `restart`), up to maxSteps; returns the log.
std::string run(Solver solver, const perishell::model::Model& model, const std::string& directory, bool restart,
                std::optional<long long> maxSteps) {
  perishell::solvers::RunOptions options;
  (restart ? options.restartDirectory : options.outputDirectory) = directory;
  options.backend = perishell_test_run_files::backendOf<TEST_EXECSPACE>();
  options.maxSteps = maxSteps;
  std::ostringstream log;
  if (solver == Solver::Explicit)
    perishell::solvers::runExplicit(model, options, log);
  else
    perishell::solvers::runImplicit(model, options, log);
  return log.str();
}

// Runs repeat bit for bit where no floating-point atomic sums race (tangent assembly, node
// areas, the device's shell scatter): on one host thread. Elsewhere two uninterrupted runs
// differ at round-off already, and a continued run agrees with them to that.
bool runsRepeatBitwise() {
  return std::is_same_v<TEST_EXECSPACE, Kokkos::DefaultHostExecutionSpace> && TEST_EXECSPACE().concurrency() == 1;
}
constexpr double roundOffTolerance = 1e-8;

// The entries of two checkpoints agree: bit for bit where runs repeat so, else each real entry
// within roundOffTolerance of its largest magnitude.
void expectSameState(const perishell::io::Checkpoint& expected, const perishell::io::Checkpoint& actual,
                     const std::vector<std::string>& realEntries, const std::vector<std::string>& otherEntries) {
  const bool bitwise = runsRepeatBitwise();
  for (const auto& name : realEntries) {
    const auto& a = expected.reals(name);
    const auto& b = actual.reals(name);
    ASSERT_EQ(a.size(), b.size()) << name;
    double scale = 0.0;
    for (const double value : a) scale = std::max(scale, std::abs(value));
    std::size_t differing = 0;
    for (std::size_t k = 0; k < a.size(); ++k)
      differing += bitwise ? std::memcmp(&a[k], &b[k], sizeof(double)) != 0
                           : !(std::abs(a[k] - b[k]) <= roundOffTolerance * scale);
    EXPECT_EQ(differing, 0u) << name << ": " << differing << " of " << a.size() << " values differ"
                             << (bitwise ? " in their bits" : " beyond round-off");
  }
  for (const auto& name : otherEntries) {
    const bool bytes = name.find("element-is-pd") != std::string::npos;
    if (bytes)
      EXPECT_EQ(expected.bytes(name), actual.bytes(name)) << name;
    else
      EXPECT_EQ(expected.integers(name), actual.integers(name)) << name;
  }
}

// history.csv the same: as text where runs repeat bit for bit, else value by value to round-off.
void expectSameHistory(const std::string& expectedPath, const std::string& actualPath) {
  const auto expected = readTextFile(expectedPath), actual = readTextFile(actualPath);
  if (runsRepeatBitwise()) {
    EXPECT_EQ(expected, actual);
    return;
  }
  const auto a = perishell_test_run_files::readHistory(expectedPath), b = perishell_test_run_files::readHistory(actualPath);
  ASSERT_EQ(a.columns, b.columns);
  ASSERT_EQ(a.rows.size(), b.rows.size());
  // Each column to round-off of its own scale, and of the largest value in the history: a
  // column at the residual's level (a reaction that balances to zero) is round-off itself.
  std::map<std::string, double> scales;
  double largest = 0.0;
  for (const auto& column : a.columns)
    for (const auto& row : a.rows) {
      scales[column] = std::max(scales[column], std::abs(row.at(column)));
      largest = std::max(largest, std::abs(row.at(column)));
    }
  for (const auto& column : a.columns)
    for (std::size_t k = 0; k < a.rows.size(); ++k)
      EXPECT_NEAR(a.rows[k].at(column), b.rows[k].at(column), roundOffTolerance * scales[column] + 1e-12 * largest)
          << column << " row " << k;
}

// results.xmf the same: as text where runs repeat bit for bit, else the same steps.
void expectSameSeries(const std::string& expected, const std::string& actual) {
  if (runsRepeatBitwise()) {
    EXPECT_EQ(expected, actual);
    return;
  }
  const auto steps = [](const std::string& text) {
    int count = 0;
    for (auto at = text.find("<Grid Name=\"step_"); at != std::string::npos; at = text.find("<Grid Name=\"step_", at + 1))
      ++count;
    return count;
  };
  EXPECT_EQ(steps(expected), steps(actual));
}

struct RunFiles {
  std::string history, xmf;
  perishell::io::Checkpoint checkpoint;
};

RunFiles filesOf(const std::string& directory) {
  return {directory + "/history.csv", readTextFile(directory + "/results.xmf"),
          perishell::io::Checkpoint::read(perishell::solvers::checkpointPath(directory))};
}

// The interrupted run (pieces) ends as the uninterrupted one (whole): the checkpoints' entries,
// history.csv and results.xmf. Returns both runs' files for further checks.
std::pair<RunFiles, RunFiles> expectSameRun(const std::string& whole, const std::string& pieces,
                                            const std::vector<std::string>& realEntries,
                                            const std::vector<std::string>& otherEntries) {
  auto expected = filesOf(whole), actual = filesOf(pieces);
  expectSameState(expected.checkpoint, actual.checkpoint, realEntries, otherEntries);
  expectSameHistory(expected.history, actual.history);
  expectSameSeries(expected.xmf, actual.xmf);
  return {std::move(expected), std::move(actual)};
}

}  // namespace

TEST(TEST_CATEGORY, explicit_run_stopped_twice_and_continued_equals_the_uninterrupted_run) {
  // The adaptive plate: bonds break and the PD zone grows within its 200 steps. Checkpoints
  // every 70 steps; the interrupted run stops at 50 (between checkpoints, off the history
  // schedule) and 130, and is continued each time.
  const auto model = perishell::model::buildModel(
      runDeck("small_adaptive_plate.yaml", "    history: [energy, broken-bonds]\n", "    checkpoint-every: 70\n"));
  const ScratchDirectory whole, pieces;
  run(Solver::Explicit, model, whole.path(), false, std::nullopt);
  run(Solver::Explicit, model, pieces.path(), false, 50);
  EXPECT_EQ(perishell::io::Checkpoint::read(perishell::solvers::checkpointPath(pieces.path())).integer("explicit.step"),
            50);
  const std::string secondLog = run(Solver::Explicit, model, pieces.path(), true, 130);
  EXPECT_NE(secondLog.find("restart: continuing from step 50 (t = "), std::string::npos) << secondLog;
  run(Solver::Explicit, model, pieces.path(), true, std::nullopt);

  const auto [expected, actual] = expectSameRun(
      whole.path(), pieces.path(),
      {"explicit.displacements", "explicit.rotations", "explicit.velocities", "explicit.fracture-energy",
       "explicit.external-work", "explicit.support-work", "explicit.damping-work", "explicit.clock", "output.crack-tip"},
      {"explicit.broken-bonds", "adaptive.element-is-pd", "explicit-run.zone-switches", "output.history-rows"});
  EXPECT_EQ(actual.checkpoint.integer("explicit.step"), 200);
  // The case is one the restart must carry: bonds broke and the zone grew before step 130.
  EXPECT_GT(expected.checkpoint.integers("explicit.broken-bonds").size(), 0u);
  EXPECT_GT(expected.checkpoint.integer("explicit-run.zone-switches"), 0);
  // 11 history rows (steps 0, 20, ..., 200) and 3 field steps (0, 100, 200), none twice.
  EXPECT_EQ(perishell_test_run_files::readHistory(pieces.path() + "/history.csv").rows.size(), 11u);
  EXPECT_EQ(actual.checkpoint.reals("output.field-times").size(), 3u);
}

TEST(TEST_CATEGORY, implicit_arc_length_run_stopped_and_continued_equals_the_uninterrupted_run) {
  // The hinged roof towards its limit points under arc-length control (Cholesky-preconditioned:
  // the restart refactors the converged tangent, as the uninterrupted run has it), 10 of its
  // 12 increments, stopped after 3 and 6.
  const auto model = perishell::model::buildModel(runDeck("hinged_roof_arc_length.yaml", "every: 0",
                                                          ", history-every: 1, checkpoint-every: 4",
                                                          "max-increments: 10", "max-increments: 12"));
  const ScratchDirectory whole, pieces;
  run(Solver::Implicit, model, whole.path(), false, 10);
  run(Solver::Implicit, model, pieces.path(), false, 3);
  const std::string secondLog = run(Solver::Implicit, model, pieces.path(), true, 6);
  EXPECT_NE(secondLog.find("restart: continuing after increment 3 (load factor "), std::string::npos) << secondLog;
  run(Solver::Implicit, model, pieces.path(), true, 10);

  const auto actual = expectSameRun(whole.path(), pieces.path(),
                                    {"implicit.displacements", "implicit.rotations", "implicit.factors",
                                     "implicit.arc-direction"},
                                    {"implicit.flags", "implicit-run.counters", "output.history-rows"})
                          .second;
  EXPECT_EQ(actual.checkpoint.integers("implicit-run.counters").front(), 10);
}

TEST(TEST_CATEGORY, implicit_amg_run_stopped_and_continued_equals_the_uninterrupted_run) {
  // The mixed PD-CCM strip under load control with smoothed-aggregation AMG (the restart builds
  // its hierarchy afresh where the uninterrupted run updates its own), stopped after increment 1
  // of 2, whose extra history row and field step the continued run replaces.
  const auto model = perishell::model::buildModel(
      runDeck("small_mixed_implicit_strip.yaml", "    history: [reactions]\n", "    checkpoint-every: 1\n"));
  const ScratchDirectory whole, pieces;
  run(Solver::Implicit, model, whole.path(), false, std::nullopt);
  run(Solver::Implicit, model, pieces.path(), false, 1);
  EXPECT_EQ(perishell_test_run_files::readHistory(pieces.path() + "/history.csv").rows.size(), 1u);
  run(Solver::Implicit, model, pieces.path(), true, std::nullopt);

  expectSameRun(whole.path(), pieces.path(), {"implicit.displacements", "implicit.rotations", "implicit.factors"},
                {"implicit.flags", "output.history-rows"});
  EXPECT_EQ(perishell_test_run_files::readHistory(pieces.path() + "/history.csv").rows.size(), 1u);

  // A deck with another load schedule cannot continue it: increment 1 of 4 is not the
  // checkpoint's load factor 0.5.
  const auto otherSchedule = perishell::model::buildModel(runDeck("small_mixed_implicit_strip.yaml",
                                                                  "    history: [reactions]\n", "",
                                                                  "    increments: 2\n", "    increments: 4\n"));
  const ScratchDirectory stopped;
  run(Solver::Implicit, model, stopped.path(), false, 1);
  try {
    run(Solver::Implicit, otherSchedule, stopped.path(), true, std::nullopt);
    ADD_FAILURE() << "a restart with another load schedule ran";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("restart: the checkpoint is after increment 1 at load factor 0.5, which "
                                             "solver.increments = 4 puts at 0.25: keep the increments"),
              std::string::npos)
        << error.what();
  }
}

TEST(TEST_CATEGORY, restart_refuses_a_checkpoint_that_does_not_fit_the_deck) {
  const auto strip =
      runDeck("small_tearing_strip.yaml", "    history: [energy, reactions, broken-bonds]\n", "");
  const auto model = perishell::model::buildModel(strip);
  const ScratchDirectory directory, empty;
  run(Solver::Explicit, model, directory.path(), false, 30);

  // No checkpoint in the directory.
  try {
    run(Solver::Explicit, model, empty.path(), true, std::nullopt);
    ADD_FAILURE() << "a directory without a checkpoint was continued";
  } catch (const perishell::io::CheckpointError& error) {
    EXPECT_NE(std::string(error.what()).find("checkpoint " + empty.path() + "/checkpoint.h5: no such file"),
              std::string::npos)
        << error.what();
  }
  // Another mesh (a finer spacing).
  std::string finer = readTextFile(testDataDirectory / "decks" / "run" / "small_tearing_strip.yaml");
  finer.replace(finer.find("spacing: 1.0e-3"), 15, "spacing: 0.5e-3");
  const auto finerModel = perishell::model::buildModel(perishell::parseDeck(finer, "finer_strip.yaml"));
  try {
    run(Solver::Explicit, finerModel, directory.path(), true, std::nullopt);
    ADD_FAILURE() << "a checkpoint of another mesh was continued";
  } catch (const perishell::io::CheckpointError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("its run's model had "), std::string::npos) << message;
    EXPECT_NE(message.find(", the deck finer_strip.yaml makes "), std::string::npos) << message;
    EXPECT_NE(message.find(" (support layer included): restart with the deck of that run ("), std::string::npos)
        << message;
  }
  // An implicit deck of the same strip on the explicit run's checkpoint.
  const auto implicitModel = perishell::model::buildModel(
      perishell::readDeck((testDataDirectory / "decks" / "run" / "small_implicit_strip.yaml").string()));
  try {
    run(Solver::Implicit, implicitModel, directory.path(), true, std::nullopt);
    ADD_FAILURE() << "an explicit checkpoint was continued by an implicit run";
  } catch (const perishell::io::CheckpointError& error) {
    EXPECT_NE(std::string(error.what()).find("written by an explicit run; the deck "), std::string::npos)
        << error.what();
    EXPECT_NE(std::string(error.what()).find("small_implicit_strip.yaml is implicit (solver.type)"), std::string::npos)
        << error.what();
  }
  // A checkpoint at the run's end leaves nothing to run.
  try {
    run(Solver::Explicit, model, directory.path(), true, 30);
    ADD_FAILURE() << "a restart with nothing left to run ran";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("restart: the checkpoint is at step 30, and this run ends at step 30: "
                                             "nothing is left to run"),
              std::string::npos)
        << error.what();
  }
  // A broken bond the model does not have (two far-apart nodes): the checkpoint is of another
  // horizon or zone layout.
  auto edited = perishell::io::Checkpoint::read(perishell::solvers::checkpointPath(directory.path()));
  auto pairs = edited.integers("explicit.broken-bonds");
  const std::size_t listed = pairs.size() / 2 + 1;
  pairs.insert(pairs.end(), {0, model.shell.mesh.numNodes() - 1});
  edited.putIntegers("explicit.broken-bonds", pairs);
  edited.write(perishell::solvers::checkpointPath(directory.path()));
  try {
    run(Solver::Explicit, model, directory.path(), true, std::nullopt);
    ADD_FAILURE() << "a checkpoint listing a bond the model lacks was continued";
  } catch (const perishell::io::CheckpointError& error) {
    EXPECT_NE(std::string(error.what()).find("'explicit.broken-bonds' lists " + std::to_string(listed) +
                                             " broken bonds, of which this model has " + std::to_string(listed - 1)),
              std::string::npos)
        << error.what();
  }
}
