#include <perishell/solvers/run_checkpoint.hpp>

#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <string>

namespace perishell::solvers {

namespace {

std::string runDirectoryPath(const model::Model& model, const RunOptions& options) {
  if (!options.restartDirectory.empty()) return options.restartDirectory;
  return options.outputDirectory.empty() ? model.deck.output.directory : options.outputDirectory;
}

}  // namespace

RunDirectory::RunDirectory(const model::Model& model, const RunOptions& options, const std::string& solver,
                           std::ostream& log)
    : path_(runDirectoryPath(model, options)),
      lock_(path_, log,
            options.restartDirectory.empty() ? io::OutputDirectoryLock::EarlierResults::Clear
                                             : io::OutputDirectoryLock::EarlierResults::Keep) {
  if (!options.restartDirectory.empty()) checkpoint_ = readRunCheckpoint(path_, model, solver);
}

std::string checkpointPath(const std::string& directory) {
  return (std::filesystem::path(directory) / io::checkpointFileName).string();
}

CheckpointSchedule::CheckpointSchedule(const deck::Output& output)
    : every_(output.checkpointEvery), minutes_(output.checkpointMinutes), last_(std::chrono::steady_clock::now()) {}

bool CheckpointSchedule::dueByClock() const {
  return minutes_ > 0.0 &&
         std::chrono::duration<double>(std::chrono::steady_clock::now() - last_).count() >= 60.0 * minutes_;
}

void agreeOnRanks(const parallel::Communicator& communicator, int& stopSignal, bool& checkpointByClock) {
  if (!communicator.distributed()) return;
  double votes[2] = {static_cast<double>(stopSignal), checkpointByClock ? 1.0 : 0.0};
  communicator.max(votes, 2);
  stopSignal = static_cast<int>(votes[0]);
  checkpointByClock = votes[1] > 0.0;
}

// Field steps as the checkpoint keeps them: their times, and per step a line
// "name:components name:components ...".
void putOutputPosition(io::Checkpoint& checkpoint, const OutputPosition& position) {
  checkpoint.putInteger("output.history-rows", static_cast<long long>(position.historyRows));
  std::vector<double> times;
  std::string layout;
  for (const auto& step : position.fieldSteps) {
    times.push_back(step.time);
    for (std::size_t k = 0; k < step.fields.size(); ++k)
      layout += (k ? " " : "") + step.fields[k].name + ":" + std::to_string(step.fields[k].components);
    layout += "\n";
  }
  checkpoint.putReals("output.field-times", times);
  checkpoint.putText("output.field-layout", layout);
}

OutputPosition takeOutputPosition(const io::Checkpoint& checkpoint) {
  OutputPosition position;
  position.historyRows = static_cast<std::size_t>(checkpoint.integer("output.history-rows"));
  const auto& times = checkpoint.reals("output.field-times");
  std::istringstream lines(checkpoint.text("output.field-layout"));
  std::string line;
  for (const double time : times) {
    if (!std::getline(lines, line))
      throw io::CheckpointError(checkpoint.context() + "'output.field-layout' lists fewer steps than their times");
    io::XdmfTimeSeriesWriter::StepRecord step{time, {}};
    std::istringstream words(line);
    std::string word;
    while (words >> word) {
      const auto colon = word.rfind(':');
      if (colon == std::string::npos)
        throw io::CheckpointError(checkpoint.context() + "'output.field-layout' has no components in '" + word + "'");
      step.fields.push_back({word.substr(0, colon), std::stoi(word.substr(colon + 1))});
    }
    position.fieldSteps.push_back(std::move(step));
  }
  return position;
}

void writeRunCheckpoint(io::Checkpoint& checkpoint, const model::Model& model, const std::string& solver,
                        const std::string& directory) {
  checkpoint.putText("run.solver", solver);
  checkpoint.putText("run.deck", model.deck.sourceName);
  checkpoint.putIntegers("run.model", {model.shell.mesh.numNodes(), model.shell.mesh.numElements()});
  checkpoint.write(checkpointPath(directory));
}

io::Checkpoint readRunCheckpoint(const std::string& directory, const model::Model& model, const std::string& solver) {
  auto checkpoint = io::Checkpoint::read(checkpointPath(directory));
  const std::string& saved = checkpoint.text("run.solver");
  if (saved != solver)
    throw io::CheckpointError(checkpoint.context() + "written by an " + saved + " run; the deck " +
                              model.deck.sourceName + " is " + solver + " (solver.type)");
  const auto& counts = checkpoint.integers("run.model");
  const long long nodes = model.shell.mesh.numNodes(), elements = model.shell.mesh.numElements();
  if (counts.size() != 2 || counts[0] != nodes || counts[1] != elements)
    throw io::CheckpointError(checkpoint.context() + "its run's model had " +
                              (counts.size() == 2 ? std::to_string(counts[0]) + " nodes and " +
                                                        std::to_string(counts[1]) + " elements"
                                                  : std::string("another size")) +
                              ", the deck " + model.deck.sourceName + " makes " + std::to_string(nodes) + " and " +
                              std::to_string(elements) + " (support layer included): restart with the deck of "
                              "that run (" + checkpoint.text("run.deck") + ")");
  return checkpoint;
}

std::optional<io::Checkpoint> readCheckpointOnOtherRanks(const model::Model& model, const RunOptions& options,
                                                         const std::string& solver,
                                                         const parallel::Communicator& communicator) {
  if (!communicator.distributed() || options.restartDirectory.empty()) return std::nullopt;
  communicator.broadcast(std::string());  // after the root's check: an error there ends every rank
  if (communicator.root()) return std::nullopt;
  return readRunCheckpoint(runDirectoryPath(model, options), model, solver);
}

}  // namespace perishell::solvers
