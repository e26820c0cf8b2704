#pragma once
// `perishell run` for an explicit deck: model -> PD body and loads on the device ->
// central-difference steps with progress -> XDMF fields every output.every steps and a CSV
// history every output.history-every steps -> DIR/timings.csv and a summary table. Runs on
// the build's default execution space or its host space (RunOptions::backend); only output
// steps copy data to the host.
#include <perishell/model/model.hpp>
#include <perishell/solvers/run_options.hpp>

#include <array>
#include <iosfwd>
#include <optional>
#include <string>

namespace perishell::solvers {

// The damaged node (damage >= 0.4) farthest from the first pre-crack's start (or the origin).
struct CrackTip {
  std::array<double, 3> position{};  // [m]
  double length = 0.0;               // its distance from that start [m]
};

struct ExplicitRunSummary {
  long long steps = 0;
  double timeStep = 0.0, criticalTimeStep = 0.0;  // [s]
  double endTime = 0.0;                           // [s]
  double wallSeconds = 0.0;
  long long brokenBonds = 0;
  PhaseTimes phases;  // as written to timingsPath
  std::string xdmfPath, historyPath, timingsPath;
  std::optional<CrackTip> crackTip;  // at the last history row, when the history tracks it
  int stoppedBySignal = 0;           // SIGINT/SIGTERM that ended the run early (core/stop_request.hpp)
};

// Throws std::invalid_argument (naming the deck key) for models the explicit solver cannot
// run yet, ExplicitInstability when the run goes unstable (files written up to then stay
// valid), std::runtime_error for output failures.
ExplicitRunSummary runExplicit(const model::Model& model, const RunOptions& options, std::ostream& log);

// Under mpirun (docs/parallel.md): throws std::invalid_argument, naming the deck key or option,
// for what a distributed explicit run does not support yet (an adaptive zone). The same on
// every rank; runExplicit checks it too.
void requireDistributableExplicitRun(const model::Model& model);

}  // namespace perishell::solvers
