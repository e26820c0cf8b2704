#pragma once
// `perishell run` for an implicit deck: model -> shell elements or PD bonds, loads and
// supports on the device -> Newton load increments (solvers/implicit/static_newton.hpp) with
// progress -> XDMF fields every output.every increments, a CSV history row per increment ->
// DIR/timings.csv and a summary table, on the build's default execution space or its host
// space (RunOptions::backend). Only converged increments copy data to the host.
#include <perishell/model/model.hpp>
#include <perishell/solvers/run_options.hpp>

#include <iosfwd>
#include <string>

namespace perishell::solvers {

struct ImplicitRunSummary {
  int increments = 0;
  int cuts = 0;
  long long newtonIterations = 0, linearIterations = 0;
  long long preconditionerBuilds = 0;
  long long factorizations = 0;
  long long lineSearches = 0;
  long negativePivots = 0;  // the most any factorization found (> 0: past a limit point)
  double wallSeconds = 0.0;
  double maxDisplacement = 0.0;  // largest |u| of a node at the end [m]
  PhaseTimes phases;  // as written to timingsPath
  std::string xdmfPath, historyPath, timingsPath;
  int stoppedBySignal = 0;  // SIGINT/SIGTERM that ended the run after an increment (core/stop_request.hpp)
};

// Throws NewtonFailure (after writing the last converged state) when an increment cannot be
// converged within its cuts.
ImplicitRunSummary runImplicit(const model::Model& model, const RunOptions& options, std::ostream& log);

// Under mpirun: throws std::invalid_argument naming the deck key or option that a distributed
// implicit run refuses (the direct preconditioner). The same on every rank.
void requireDistributableImplicitRun(const model::Model& model);

}  // namespace perishell::solvers
