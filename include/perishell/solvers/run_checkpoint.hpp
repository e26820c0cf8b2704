#pragma once
// Checkpoints of a run, for both solvers (docs/reliability.md §9): when one is due, where it
// goes, what the run's outputs record in it, and the checks a restart makes against the deck.
// A checkpoint holds the solver's state (CentralDifferenceSolver / StaticNewtonSolver
// ::saveTo), the adaptive zone, the run's counters, and how far history.csv and the field
// series had got on the run's schedule; `perishell run DECK --restart DIR` continues from it,
// cutting off what the interrupted run wrote after it, so that the continued run's files and
// state equal the uninterrupted run's.
#include <perishell/io/checkpoint.hpp>
#include <perishell/io/output_directory.hpp>
#include <perishell/io/xdmf_writer.hpp>
#include <perishell/model/model.hpp>
#include <perishell/parallel/communicator.hpp>
#include <perishell/solvers/run_options.hpp>

#include <chrono>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

namespace perishell::solvers {

// Where a run writes, held for it (io/output_directory.hpp): the directory a restart continues,
// else --output, else the deck's output.directory; and with a restart, the checkpoint to
// continue from, read and checked against the model (readRunCheckpoint).
class RunDirectory {
 public:
  // solver: "explicit" or "implicit".
  RunDirectory(const model::Model& model, const RunOptions& options, const std::string& solver, std::ostream& log);
  const std::string& path() const { return path_; }
  const std::optional<io::Checkpoint>& checkpoint() const { return checkpoint_; }

 private:
  std::string path_;
  io::OutputDirectoryLock lock_;
  std::optional<io::Checkpoint> checkpoint_;
};

// DIR/checkpoint.h5.
std::string checkpointPath(const std::string& directory);

// A restart of a distributed run: the root's RunDirectory has read and checked the checkpoint;
// once it has, every other rank reads the same file (each takes its nodes' rows from it).
// Empty on the root, on a single rank and without --restart. Collective.
std::optional<io::Checkpoint> readCheckpointOnOtherRanks(const model::Model& model, const RunOptions& options,
                                                         const std::string& solver,
                                                         const parallel::Communicator& communicator);

// When checkpoints are due: every output.checkpoint-every steps (increments) and/or minutes
// of wall time since the last one (or the run's start).
class CheckpointSchedule {
 public:
  explicit CheckpointSchedule(const deck::Output& output);
  bool dueByStep(long long step) const { return every_ > 0 && step % every_ == 0; }
  // This rank's clock: a distributed run agrees on it first (agreeOnRanks).
  bool dueByClock() const;
  void written() { last_ = std::chrono::steady_clock::now(); }

 private:
  long long every_ = 0;
  double minutes_ = 0.0;
  std::chrono::steady_clock::time_point last_;
};

// A stop request (a signal's number, 0 for none) and a checkpoint by the wall clock, made the
// same on every rank (the maxima over the ranks) in one reduction: each rank has its own clock
// and may get the signal alone. A no-op on a single rank. Collective.
void agreeOnRanks(const parallel::Communicator& communicator, int& stopSignal, bool& checkpointByClock);

// How far the outputs had got on the run's schedule: the history rows and the field steps.
struct OutputPosition {
  std::size_t historyRows = 0;
  std::vector<io::XdmfTimeSeriesWriter::StepRecord> fieldSteps;
};
void putOutputPosition(io::Checkpoint& checkpoint, const OutputPosition& position);
OutputPosition takeOutputPosition(const io::Checkpoint& checkpoint);

// Stamps a checkpoint with the solver ("explicit", "implicit"), the model's node and element
// counts and the deck's name; writes it atomically to DIR/checkpoint.h5.
void writeRunCheckpoint(io::Checkpoint& checkpoint, const model::Model& model, const std::string& solver,
                        const std::string& directory);

// The checkpoint in DIR, checked against this run's solver and model (io::CheckpointError in
// the user's terms otherwise).
io::Checkpoint readRunCheckpoint(const std::string& directory, const model::Model& model, const std::string& solver);

}  // namespace perishell::solvers
