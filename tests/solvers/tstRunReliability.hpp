// Runs that do not lie (issue 22, docs/reliability.md): an explicit run that blows up between
// two energy-monitor steps stops at its next write or its last step, naming the step, the
// quantity and the deck's likely cause (never a key the deck does not set); Newton's
// solver.max-cuts bounds the cuts of an increment in all; a run refuses an output directory
// another run holds, and a rerun leaves none of an earlier run's step files; a stop request
// (SIGINT, SIGTERM) ends a run after its current step or increment, written, with its summary.
#include <perishell/core/stop_request.hpp>
#include <perishell/io/checkpoint.hpp>
#include <perishell/io/output_directory.hpp>
#include <perishell/model/model.hpp>
#include <perishell/solvers/explicit/central_difference.hpp>
#include <perishell/solvers/explicit/explicit_run.hpp>
#include <perishell/solvers/implicit/implicit_run.hpp>
#include <perishell/solvers/implicit/static_newton.hpp>
#include <perishell/solvers/state_check.hpp>

#include <perishell/solvers/implicit/static_solver_from_model.hpp>

#include <scratch_directory.hpp>
#include <solvers/run_files.hpp>
#include <test_files.hpp>

#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <chrono>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

// Each test's run writes into a fresh /tmp directory.
using RunDirectory = perishell_test::ScratchDirectory;

// The issue's plate: 20 x 6 mm steel, clamped on the left, an edge traction on the right,
// for explicit runs ramped from 0 (so that the energy monitor's check at step 0 passes);
// implicit runs take it in their increments.
std::string plateDeck(const std::string& traction, const std::string& solverLine, const std::string& output,
                      bool ramped = true) {
  return R"(perishell:
  version: 1
  mesh: {generator: plate, length-x: 0.020, length-y: 0.006, spacing: 1.0e-3}
  material: {young-modulus: 210.0e9, poisson-ratio: 0.3, density: 7850.0, thickness: 1.0e-3}
  supports:
    clamp: {set: left, dofs: [ux, uy, uz, rx, ry, rz]}
  loads:
    pull: {type: edge-traction, set: right, value: )" +
         traction + (ramped ? R"(, curve: ramp}
  curves:
    ramp: {type: ramp, end-time: 1.0e-5})" : "}") + R"(
  solver: )" + solverLine + R"(
  output: )" + output + "\n";
}

std::string runExplicitError(const std::string& deckText, const std::string& directory) {
  using namespace perishell_test_run_files;
  const auto model = perishell::model::buildModel(perishell::parseDeck(deckText, "plate.yaml"));
  std::ostringstream log;
  try {
    perishell::solvers::runExplicit(model, {directory, backendOf<TEST_EXECSPACE>()}, log);
  } catch (const perishell::solvers::ExplicitInstability& error) {
    return error.what();
  }
  ADD_FAILURE() << "the run ended normally:\n" << log.str();
  return "";
}

int gridsIn(const std::string& xmfPath) {
  std::ifstream file(xmfPath);
  std::ostringstream text;
  text << file.rdbuf();
  int grids = 0;
  for (auto at = text.str().find("<Grid Name=\"step_"); at != std::string::npos;
       at = text.str().find("<Grid Name=\"step_", at + 1))
    ++grids;
  return grids;
}

}  // namespace

TEST(TEST_CATEGORY, explicit_run_with_a_blown_up_state_stops_naming_step_quantity_and_load) {
  // The issue's reproducer: 50 steps under a traction ramped to 1e300 Pa, the monitor every
  // 100 steps, one field write at the end. It ended with exit 0, "energy balance error 0" and
  // NaN fields. Its nodal forces leave double precision: it is now refused when the model is
  // built (model_loads_whose_nodal_forces_overflow_or_underflow_are_refused).
  EXPECT_THROW(perishell::model::buildModel(perishell::parseDeck(
                   plateDeck("1.0e300", "{type: explicit, steps: 50}", "{every: 50}"), "plate.yaml")),
               perishell::DeckError);
  // At 1e95 Pa the forces are ordinary doubles and the state blows up all the same.
  const RunDirectory directory;
  const std::string message = runExplicitError(
      plateDeck("1.0e95", "{type: explicit, steps: 50}", "{every: 50, fields: [displacement]}"), directory.path());
  EXPECT_NE(message.find("explicit solver: unstable at step 50 (t = "), std::string::npos) << message;
  EXPECT_NE(message.find("the largest displacement is |u| = "), std::string::npos) << message;
  EXPECT_NE(message.find(" (more than 1000 x the model's size)"), std::string::npos) << message;
  EXPECT_NE(message.find("the time step was the estimated critical step "), std::string::npos) << message;
  EXPECT_NE(message.find(" x 0.9 (the deck sets no dt); the loads are the likely cause: the largest load is "
                         "loads.pull.value = 1e+95 Pa"),
            std::string::npos)
      << message;
  EXPECT_EQ(message.find("solver.dt"), std::string::npos) << message;
  // Only the initial state was written: the bad one never reaches the files.
  EXPECT_EQ(gridsIn(directory.path() + "/results.xmf"), 1);
  EXPECT_FALSE(fs::exists(directory.path() + "/results_000001.h5"));
}

TEST(TEST_CATEGORY, explicit_run_at_ten_times_the_critical_step_stops_naming_solver_dt) {
  using namespace perishell_test_run_files;
  const RunDirectory directory;
  // The critical step of this plate, from a one-step run.
  const auto probe = perishell::model::buildModel(perishell::parseDeck(
      plateDeck("50.0e6", "{type: explicit, steps: 1}", "{every: 1}"), "plate.yaml"));
  std::ostringstream log;
  const double critical =
      perishell::solvers::runExplicit(probe, {directory.path(), backendOf<TEST_EXECSPACE>()}, log).criticalTimeStep;
  ASSERT_GT(critical, 1e-9);
  ASSERT_LT(critical, 1e-6);
  std::ostringstream dt;
  dt.precision(17);
  dt << 10.0 * critical;
  // 60 steps, the monitor at step 0 only: |u| reached 1.55e7 m with exit 0 before.
  const std::string message = runExplicitError(
      plateDeck("50.0e6", "{type: explicit, steps: 60, dt: " + dt.str() + "}", "{every: 0}"), directory.path());
  EXPECT_NE(message.find("explicit solver: unstable at step 60 (t = "), std::string::npos) << message;
  EXPECT_NE(message.find("the energies are no longer finite; the largest displacement is |u| = "), std::string::npos)
      << message;
  EXPECT_NE(message.find(" (more than 1000 x the model's size)"), std::string::npos) << message;
  EXPECT_NE(message.find("Likely cause: solver.dt = "), std::string::npos) << message;
  EXPECT_NE(message.find(" s is 10 x the estimated critical step "), std::string::npos) << message;
  EXPECT_NE(message.find("lower solver.dt, or leave it out"), std::string::npos) << message;
  EXPECT_EQ(gridsIn(directory.path() + "/results.xmf"), 1);  // the initial state only
}

TEST(TEST_CATEGORY, implicit_run_with_a_blown_up_state_stops_naming_increment_quantity_and_load) {
  using namespace perishell_test_run_files;
  const RunDirectory directory;
  // 1e15 Pa on the 20 mm strip: Newton converges at half the load on a state with |u| =
  // 35.4 m, and at the full load 70.8 m, which the run wrote out with exit 0 before.
  const auto model = perishell::model::buildModel(perishell::parseDeck(
      plateDeck("1.0e15", "{type: implicit, increments: 2}", "{every: 1}", false), "plate.yaml"));
  std::ostringstream log;
  try {
    perishell::solvers::runImplicit(model, {directory.path(), backendOf<TEST_EXECSPACE>()}, log);
    ADD_FAILURE() << "the run ended normally:\n" << log.str();
  } catch (const perishell::solvers::RunStateError& error) {
    const std::string message = error.what();
    // One of the two loaded corners (they move alike, to round-off).
    EXPECT_EQ(message.rfind("implicit solver: increment 1 of 2 (load factor 0.5): the largest displacement is "
                            "|u| = 35.39 m at the node at [0.02, ",
                            0),
              0u)
        << message;
    EXPECT_NE(message.find(", 0] m (more than 1000 x the model's size). Likely cause: the loads (the largest load is "
                           "loads.pull.value = 1e+15 Pa), or supports that leave the model free to move. This state "
                           "was not written"),
              std::string::npos)
        << message;
  }
  EXPECT_EQ(gridsIn(directory.path() + "/results.xmf"), 1);  // the initial state only
}

TEST(TEST_CATEGORY, newton_max_cuts_bounds_the_halvings_of_an_increment_in_all) {
  using perishell::solvers::IncrementReport;
  using perishell::solvers::NewtonOptions;
  // Every converged sub-step counts as hard here, so each one halves the next. Those halvings
  // were not counted as cuts: the increment crept on in ever smaller sub-steps (a series that
  // never reaches its end) with no output and no bound.
  const auto model = perishell::model::buildModel(perishell::parseDeck(
      plateDeck("50.0e6", "{type: implicit, increments: 2, max-cuts: 3}", "{every: 1}", false), "plate.yaml"));
  auto solver = perishell::solvers::makeStaticSolver(TEST_EXECSPACE{}, model, [](NewtonOptions& options) {
    options.easyIterations = 0;
    options.hardIterations = 0;
  });
  int iterations = 0;
  solver.observeIterations([&iterations](double, const IncrementReport&) {
    if (++iterations > 500) throw std::runtime_error("Newton crept on past 500 iterations");
  });
  // One full sub-step ends the first increment: no cut, the next sub-step halved.
  const IncrementReport first = solver.advanceTo(0.5);
  EXPECT_EQ(first.attempts, 1);
  EXPECT_EQ(first.cuts, 0);
  try {
    solver.advanceTo(1.0);
    ADD_FAILURE() << "the increment ended";
  } catch (const perishell::solvers::NewtonFailure& failure) {
    const std::string message = failure.what();
    EXPECT_NE(message.find("Newton did not reach load factor 1.000000 after 3 cuts of the increment (solver.max-cuts; "
                           "last sub-step towards 0.968750, from 0.968750): the sub-step converged only in "),
              std::string::npos)
        << message;
  }
  // 0.5 + 0.25 + 0.125 + 0.0625 + 0.03125: four converged sub-steps, then the fourth cut stops it.
  EXPECT_DOUBLE_EQ(solver.loadFactor(), 0.96875);
  EXPECT_LT(iterations, 100);
}

TEST(TEST_CATEGORY, implicit_run_prints_progress_lines_within_an_increment) {
  using namespace perishell_test_run_files;
  const RunDirectory directory;
  const auto model = perishell::model::buildModel(perishell::parseDeck(
      plateDeck("50.0e6", "{type: implicit, increments: 2}", "{every: 1}", false), "plate.yaml"));
  perishell::solvers::RunOptions options{directory.path(), backendOf<TEST_EXECSPACE>()};
  options.progressEverySeconds = 0.0;  // a line after every Newton iteration and cut
  std::ostringstream log;
  perishell::solvers::runImplicit(model, options, log);
  const std::string text = log.str();
  EXPECT_NE(text.find("implicit: increment 1 in progress: load factor 0.5  Newton 1  cuts 0  relative residual "),
            std::string::npos)
      << text;
  EXPECT_NE(text.find("implicit: increment 2 in progress: load factor 1  Newton 1  cuts 0  relative residual "),
            std::string::npos)
      << text;
}

TEST(TEST_CATEGORY, run_refuses_a_held_output_directory_and_a_rerun_leaves_no_stale_steps) {
  using namespace perishell_test_run_files;
  const RunDirectory directory;
  const auto run = [&](int steps) {
    const auto model = perishell::model::buildModel(perishell::parseDeck(
        plateDeck("50.0e6", "{type: explicit, steps: " + std::to_string(steps) + "}", "{every: 10}"), "plate.yaml"));
    std::ostringstream log;
    perishell::solvers::runExplicit(model, {directory.path(), backendOf<TEST_EXECSPACE>()}, log);
    return log.str();
  };
  {
    // Another run holds the directory: refused before anything is written, the holder named.
    std::ostringstream holderLog;
    const perishell::io::OutputDirectoryLock holder(directory.path(), holderLog);
    try {
      run(20);
      ADD_FAILURE() << "a held directory was written";
    } catch (const perishell::io::OutputDirectoryError& error) {
      EXPECT_NE(std::string(error.what()).find("is in use by run " + std::to_string(getpid()) + " on "),
                std::string::npos)
          << error.what();
    }
    EXPECT_FALSE(fs::exists(directory.path() + "/results.xmf"));
  }
  run(50);  // steps 0, 10, .., 50: six step files
  EXPECT_TRUE(fs::exists(directory.path() + "/results_000005.h5"));
  const std::string log = run(20);  // three step files; the longer run's others are removed
  EXPECT_NE(log.find("output: removed 10 file(s) of an earlier run from " + directory.path() + " ("), std::string::npos)
      << log;
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(directory.path())) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"history.csv", "results.xmf", "results_000000.h5", "results_000001.h5",
                                             "results_000002.h5", "results_mesh.h5", "timings.csv"}));
  EXPECT_EQ(gridsIn(directory.path() + "/results.xmf"), 3);
}

// A stop request taken before the run (as if SIGTERM came during the first step): the explicit
// run ends after step 1 with that step written and counted, the implicit one after increment 1
// of 4; both say so in the summary and return the signal.
TEST(TEST_CATEGORY, a_stop_request_ends_a_run_after_its_current_step_written) {
  using namespace perishell_test_run_files;
  struct ClearStopRequest {  // whatever fails here, later tests run unstopped
    ~ClearStopRequest() { perishell::requestStop(0); }
  } clearStopRequest;
  const RunDirectory explicitDirectory, implicitDirectory;
  const auto explicitModel = perishell::model::buildModel(
      perishell::parseDeck(plateDeck("50.0e6", "{type: explicit, steps: 50}", "{every: 10, history: [energy]}"),
                           "plate.yaml"));
  std::ostringstream explicitLog;
  perishell::requestStop(SIGTERM);
  const auto explicitSummary =
      perishell::solvers::runExplicit(explicitModel, {explicitDirectory.path(), backendOf<TEST_EXECSPACE>()}, explicitLog);
  EXPECT_EQ(explicitSummary.stoppedBySignal, SIGTERM);
  EXPECT_EQ(explicitSummary.steps, 1);
  EXPECT_NE(explicitLog.str().find("steps                 1 of 50 (stopped by SIGTERM)"), std::string::npos)
      << explicitLog.str();
  const auto explicitHistory = readHistory(explicitDirectory.path() + "/history.csv");
  ASSERT_EQ(explicitHistory.rows.size(), 2u);  // step 0 and the step it stopped at
  EXPECT_EQ(explicitHistory.rows.back().at("step"), 1.0);
  EXPECT_EQ(gridsIn(explicitDirectory.path() + "/results.xmf"), 2);

  const auto implicitModel = perishell::model::buildModel(perishell::parseDeck(
      plateDeck("1.0e6", "{type: implicit, increments: 4}", "{every: 1}", false), "plate.yaml"));
  std::ostringstream implicitLog;
  perishell::requestStop(SIGINT);
  const auto implicitSummary =
      perishell::solvers::runImplicit(implicitModel, {implicitDirectory.path(), backendOf<TEST_EXECSPACE>()}, implicitLog);
  EXPECT_EQ(implicitSummary.stoppedBySignal, SIGINT);
  EXPECT_EQ(implicitSummary.increments, 1);
  EXPECT_NE(implicitLog.str().find("1 of 4 (0 cuts), stopped by SIGINT"), std::string::npos) << implicitLog.str();
  EXPECT_EQ(readHistory(implicitDirectory.path() + "/history.csv").rows.size(), 1u);
  EXPECT_EQ(gridsIn(implicitDirectory.path() + "/results.xmf"), 2);  // the initial state and increment 1
}

TEST(TEST_CATEGORY, explicit_runs_repeat_bit_for_bit_on_any_thread_count) {
  // Sums whose order follows thread timing (atomic scatter) would make two runs of one deck
  // differ; node areas and normals gather in element order (mesh/node_incidence.hpp), bonds by
  // node, and on host backends the shell elements too. So two runs of the adaptive glass plate
  // (bonds break, the zone grows) end in the same bits on 2 OpenMP threads. The device scatters
  // the shell elements' forces (faster there): on it, the plate 100 % PD.
  using namespace perishell_test_run_files;
  constexpr bool host = std::is_same_v<TEST_EXECSPACE, Kokkos::DefaultHostExecutionSpace>;
  const auto path = perishell_test::testDataDirectory / "decks" / "run" / "small_adaptive_plate.yaml";
  std::string text = perishell_test::readTextFile(path) + "    checkpoint-every: 1000\n";
  if (!host) {
    const std::string adaptive = "    default: ccm\n    adaptive: {strain-fraction: 0.3, check-every: 10}\n";
    text.replace(text.find(adaptive), adaptive.size(), "    default: pd\n");
  }
  const auto model = perishell::model::buildModel(perishell::parseDeck(text, path.string()));
  const RunDirectory first, second;
  std::ostringstream log;
  perishell::solvers::runExplicit(model, {first.path(), backendOf<TEST_EXECSPACE>()}, log);
  perishell::solvers::runExplicit(model, {second.path(), backendOf<TEST_EXECSPACE>()}, log);
  const auto a = perishell::io::Checkpoint::read(first.path() + "/checkpoint.h5");
  const auto b = perishell::io::Checkpoint::read(second.path() + "/checkpoint.h5");
  for (const char* name : {"explicit.displacements", "explicit.rotations", "explicit.velocities",
                           "explicit.fracture-energy", "explicit.external-work", "explicit.clock"}) {
    const auto& x = a.reals(name);
    const auto& y = b.reals(name);
    ASSERT_EQ(x.size(), y.size()) << name;
    std::ostringstream values;
    values.precision(17);
    for (std::size_t k = 0; k < x.size() && k < 8; ++k) values << " " << x[k] << "/" << y[k];
    EXPECT_EQ(std::memcmp(x.data(), y.data(), x.size() * sizeof(double)), 0) << name << values.str();
  }
  const auto& broken = a.integers("explicit.broken-bonds");
  EXPECT_EQ(broken, b.integers("explicit.broken-bonds"));
  EXPECT_GT(broken.size(), 0u);  // bonds broke
  EXPECT_EQ(perishell_test::readTextFile(first.path() + "/history.csv"),
            perishell_test::readTextFile(second.path() + "/history.csv"));
}
