#include <perishell/core/fenced_seconds.hpp>
#include <perishell/core/stop_request.hpp>
#include <perishell/io/csv_history.hpp>
#include <perishell/io/progress.hpp>
#include <perishell/io/xdmf_writer.hpp>
#include <perishell/solvers/history_columns.hpp>
#include <perishell/parallel/communicator.hpp>
#include <perishell/parallel/gather_nodes.hpp>
#include <perishell/solvers/implicit/implicit_run.hpp>
#include <perishell/solvers/implicit/static_solver_from_model.hpp>
#include <perishell/solvers/run_checkpoint.hpp>
#include <perishell/solvers/state_check.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <ostream>
#include <sstream>
#include <type_traits>

namespace perishell::solvers {

void requireImplicitModel(const model::Model& model) {
  const auto& deck = model.deck;
  for (const auto& load : deck.loads)
    if (load.follower)
      throw std::invalid_argument(deck.sourceName + ": loads." + load.name +
                                  ".follower: the implicit solver applies pressure in the reference direction only; "
                                  "set follower: false");
}

namespace {

using HostVector3 = Kokkos::View<double* [3], Kokkos::LayoutRight, Kokkos::HostSpace>;

std::string formatNumber(double value, int precision = 4) {
  std::ostringstream text;
  text.precision(precision);
  text << value;
  return text.str();
}

// Every rank of a distributed run makes one and calls it alike: the fields are gathered to the
// root, which alone writes (directory is the root's).
template <class ExecutionSpaceT>
class ImplicitOutput {
 public:
  using Solver = StaticNewtonSolver<ExecutionSpaceT>;
  // restart: continue the outputs of the run that wrote it (solvers/run_checkpoint.hpp).
  ImplicitOutput(const model::Model& model, const std::string& directory, const Solver& solver,
                 const HistoryColumns& shared, const io::Checkpoint* restart, const parallel::NodeGather& gather)
      : model_(model), solver_(solver), shared_(shared), gather_(gather) {
    if (!gather.root()) return;
    writer_.emplace((std::filesystem::create_directories(directory), directory), "results", model.outputMesh());
    std::vector<std::string> columns = {"increment", "load-factor", "newton-iterations", "linear-iterations", "cuts",
                                        "relative-residual", "max-displacement"};
    auto add = [&columns](const std::vector<std::string>& more) {
      columns.insert(columns.end(), more.begin(), more.end());
    };
    for (const auto quantity : model.deck.output.history) {
      if (quantity == deck::HistoryQuantity::Reactions) add(shared.reactionColumns());
      if (quantity == deck::HistoryQuantity::LoadPoints) add(shared.loadPointColumns());
    }
    add(shared.probeColumns());
    if (restart) {
      auto position = takeOutputPosition(*restart);
      writer_->continueSeries(std::move(position.fieldSteps));
      history_.emplace(directory + "/history.csv", columns, position.historyRows);
    } else {
      history_.emplace(directory + "/history.csv", columns);
    }
  }

  // The root's (empty elsewhere).
  std::string xdmfPath() const { return writer_ ? writer_->xdmfPath() : std::string(); }
  OutputPosition position() const { return {history_->numRows(), writer_->steps()}; }
  std::string historyPath() const { return history_ ? history_->path() : std::string(); }

  // Collective.
  void writeFields() {
    const LocalIndex numNodes = model_.shell.mesh.numNodes();
    const auto& requested = model_.deck.output.fields;
    const bool wantsDisplacement = std::count(requested.begin(), requested.end(), deck::OutputField::Displacement) > 0;
    const bool wantsRotation = std::count(requested.begin(), requested.end(), deck::OutputField::Rotation) > 0;
    const auto u = wantsDisplacement ? displacements() : HostVector3();
    const auto rotations = wantsRotation ? gather_.gather(solver_.kinematics().rotations)
                                         : decltype(gather_.gather(solver_.kinematics().rotations))();
    if (!gather_.root()) return;
    std::vector<io::NodalField> fields;
    for (const auto field : requested) {
      switch (field) {
        case deck::OutputField::Displacement: fields.push_back({"displacement", 3, u}); break;
        case deck::OutputField::Rotation: fields.push_back(io::makeRotationVectorField("rotation", rotations)); break;
        case deck::OutputField::Zone: {
          Kokkos::View<int*, Kokkos::HostSpace> zone("zone", numNodes);
          for (std::size_t k = 0; k < model_.pdNodes.extent(0); ++k) zone(model_.pdNodes(k)) = 1;
          fields.push_back(io::makeScalarField("zone", zone));
          break;
        }
        case deck::OutputField::Damage:  // no bond breaks in a static run
          fields.push_back(io::makeScalarField("damage", Kokkos::View<double*, Kokkos::HostSpace>("damage", numNodes)));
          break;
        case deck::OutputField::Velocity: break;  // rejected for implicit decks by the deck reader
      }
    }
    for (auto& field : fields) field = io::firstNodes(field, model_.numMeshNodes());
    writer_->writeStep(solver_.loadFactor(), fields);
  }

  // Returns the largest nodal displacement magnitude (on the root; 0 elsewhere). Collective.
  double appendHistory(int increment, const IncrementReport& report) {
    const auto u = displacements();
    const auto& history = model_.deck.output.history;
    const bool wantsReactions = std::count(history.begin(), history.end(), deck::HistoryQuantity::Reactions) > 0;
    const auto outOfBalance = wantsReactions ? gather_.gather(solver_.outOfBalance())
                                             : decltype(gather_.gather(solver_.outOfBalance()))();
    const auto rotations = shared_.probes().empty() ? decltype(gather_.gather(solver_.kinematics().rotations))()
                                                    : gather_.gather(solver_.kinematics().rotations);
    if (!gather_.root()) return 0.0;
    double maxDisplacement = 0.0;
    for (LocalIndex node = 0; node < model_.numMeshNodes(); ++node)
      maxDisplacement = std::max(maxDisplacement, std::hypot(u(node, 0), u(node, 1), u(node, 2)));
    std::vector<double> row = {double(increment), report.loadFactor, double(report.newtonIterations),
                               double(report.linearIterations), double(report.cuts), report.relativeResidual,
                               maxDisplacement};
    for (const auto quantity : model_.deck.output.history) {
      // The support carries what the out-of-balance force lacks: R = F_int - P = -r.
      if (quantity == deck::HistoryQuantity::Reactions) shared_.appendReactions(outOfBalance, row);
      if (quantity == deck::HistoryQuantity::LoadPoints) shared_.appendLoadPoints(u, row);
    }
    if (!shared_.probes().empty()) shared_.appendProbes(u, rotations, row);
    history_->append(row);
    return maxDisplacement;
  }

 private:
  HostVector3 displacements() const { return gather_.gather(solver_.kinematics().displacements); }

  const model::Model& model_;
  const Solver& solver_;
  const HistoryColumns& shared_;
  const parallel::NodeGather& gather_;
  std::optional<io::XdmfTimeSeriesWriter> writer_;
  std::optional<io::CsvHistory> history_;
};

const char* preconditionerName(deck::Preconditioner preconditioner) {
  switch (preconditioner) {
    case deck::Preconditioner::Jacobi: return "Jacobi";
    case deck::Preconditioner::BlockJacobi: return "6x6 block-Jacobi";
    case deck::Preconditioner::Amg: return "smoothed-aggregation AMG";
    case deck::Preconditioner::Cholesky: return "sparse Cholesky";
    case deck::Preconditioner::Direct: return "direct (Cholesky per iteration)";
    case deck::Preconditioner::Auto: return "auto";
  }
  return "?";
}

// The progress line of a static increment: where the load is and what it took.
std::string incrementState(const IncrementReport& report) {
  std::ostringstream text;
  text << "load factor " << formatNumber(report.loadFactor, 6) << "  Newton " << report.newtonIterations << "  Krylov "
       << report.linearIterations << "  cuts " << report.cuts;
  if (report.factorizations > 0) text << "  factorizations " << report.factorizations;
  return text.str();
}

// Stops the run on a non-finite or blown-up converged state (docs/reliability.md), naming the
// increment, the quantity and the deck's likely cause; the files hold the increments before.
// Collective: the root judges the gathered displacements and every rank throws its verdict.
template <class Solver>
void requireHealthyState(const model::Model& model, const Solver& solver, int increment, int increments,
                         const parallel::NodeGather& gather, const parallel::Communicator& communicator) {
  const auto displacements = gather.gather(solver.kinematics().displacements);
  std::string verdict;
  if (gather.root()) {
    const auto extent = displacementExtent(model, displacements);
    if (extent.blownUp())
      verdict = "implicit solver: increment " + std::to_string(increment) + " of " + std::to_string(increments) +
                " (load factor " + formatNumber(solver.loadFactor(), 6) + "): " + extent.describe() +
                ". Likely cause: " + implicitBlowUpCause(model.deck) +
                ". This state was not written; the result files hold the increments before it.";
  }
  verdict = communicator.broadcast(verdict);
  if (!verdict.empty()) throw RunStateError(verdict);
}

std::string ranksText(const parallel::Communicator& communicator) {
  return communicator.distributed() ? " x " + std::to_string(communicator.size()) + " MPI ranks" : std::string();
}

template <class ExecutionSpaceT>
ImplicitRunSummary runImplicitOn(const ExecutionSpaceT& space, const model::Model& model, const RunOptions& runOptions,
                                 std::ostream& log) {
  using Clock = std::chrono::steady_clock;
  const auto& deck = model.deck;
  const auto communicator = parallel::Communicator::world();
  requireDistributableImplicitRun(model);
  // Before the set-up: a directory another run holds is refused at once. The root writes.
  std::optional<RunDirectory> runDirectory;
  if (communicator.root()) runDirectory.emplace(model, runOptions, "implicit", log);
  const std::string directory = runDirectory ? runDirectory->path() : std::string();
  const auto otherRanksCheckpoint = readCheckpointOnOtherRanks(model, runOptions, "implicit", communicator);
  const auto& checkpoint = runDirectory ? runDirectory->checkpoint() : otherRanksCheckpoint;
  const auto& settings = deck.solver.implicitSettings;
  const bool arcLength = settings.control == deck::ImplicitSettings::Control::ArcLength;
  // Under arc-length control the run ends at load factor 1; maxIncrements bounds it.
  const int deckIncrements = arcLength ? settings.maxIncrements : settings.increments;
  const int increments = static_cast<int>(std::min<long long>(deckIncrements, runOptions.maxSteps.value_or(deckIncrements)));
  const auto setupStart = Clock::now();
  // Before the solver's set-up, so that a probe off the shell stops the run at once.
  const HistoryColumns historyColumns(model);
  printProbes(model, historyColumns.probes(), log);
  // A distributed run builds this rank's part only (solvers/local_model.hpp).
  std::optional<LocalModel<ExecutionSpaceT>> local;
  if (communicator.distributed()) local.emplace(makeLocalModel(space, model, communicator));
  auto solver = local ? makeStaticSolver(space, model, *local) : makeStaticSolver(space, model);
  const parallel::NodeGather gather(local ? &local->domain : nullptr, communicator, model.shell.mesh.numNodes());
  if (arcLength) {
    const std::string obstacle = solver.arcLengthObstacle();
    if (!obstacle.empty())
      throw std::invalid_argument(deck.sourceName + ": solver.control: arc-length scales every load and prescribed "
                                  "value by the one load factor it solves for, but " + obstacle +
                                  "; use control: load, or remove the curve / prescribed value");
  }
  // The run's counters so far (a restart adds to them): increments, then the summary's totals.
  std::vector<long long> counters(11, 0);
  double maxDisplacement = 0.0;
  if (checkpoint) {
    solver.restoreFrom(*checkpoint, gather);
    counters = checkpoint->integers("implicit-run.counters");
    if (counters.size() != 11)
      throw io::CheckpointError(checkpoint->context() + "'implicit-run.counters' is not of this version");
    maxDisplacement = checkpoint->real("implicit-run.max-displacement");
  }
  const int firstIncrement = static_cast<int>(counters[0]) + 1;
  const double setupSeconds = fencedSecondsSince(space, setupStart);
  // On many ranks: bonds and shell elements counted on the rank owning their first node, the
  // tangent's entries of every rank's rows (halo rows included).
  if (local) printPartition(local->partitionRow(), 6, communicator, log, "Krylov iteration");
  const auto row = local ? local->partitionRow() : parallel::PartitionRow();
  const long long numElements = local ? communicator.sum(row.elements) : solver.numElements();
  const long long numBonds = local ? communicator.sum(row.bonds) : solver.numBonds();
  log << "implicit: " << numElements << " shell elements, " << numBonds << " bonds on " << ExecutionSpaceT::name()
      << ranksText(communicator) << "; " << model.freeDofCount() << " free DOF, "
      << communicator.sum(static_cast<long long>(solver.numMatrixEntries())) << " tangent entries; "
      << (arcLength ? "arc-length control to load factor 1, at most " : "") << deckIncrements
      << " increments; setup " << formatNumber(setupSeconds) << " s\n";
  if (increments < deckIncrements)
    log << "implicit: stopping after " << increments << " of the deck's " << deckIncrements
        << " increments (--max-steps)\n";
  if (checkpoint)
    log << "restart: continuing after increment " << firstIncrement - 1 << " (load factor "
        << formatNumber(solver.loadFactor(), 6) << ") of " << checkpoint->source() << "\n";
  // Under load control increment k ends at load factor k / increments: the deck must keep the
  // schedule of the run that wrote the checkpoint.
  if (checkpoint && !arcLength &&
      std::abs(solver.loadFactor() - double(firstIncrement - 1) / deckIncrements) > 1e-12 * solver.loadFactor())
    throw std::invalid_argument("restart: the checkpoint is after increment " + std::to_string(firstIncrement - 1) +
                                " at load factor " + formatNumber(solver.loadFactor(), 6) + ", which solver.increments = " +
                                std::to_string(deckIncrements) + " puts at " +
                                formatNumber(double(firstIncrement - 1) / deckIncrements, 6) +
                                ": keep the increments of the run that wrote it (the load schedule ends at factor 1)");
  if (checkpoint && (firstIncrement > increments || (arcLength && solver.loadFactor() >= 1.0)))
    throw std::invalid_argument("restart: the checkpoint is at increment " + std::to_string(firstIncrement - 1) +
                                " (load factor " + formatNumber(solver.loadFactor(), 6) + "), and this run ends at "
                                "increment " + std::to_string(increments) + (arcLength ? " or load factor 1" : "") +
                                ": nothing is left to run (raise solver.increments, or --max-steps)");

  // The run's wall time starts with the first output, so total = setup + run.
  const auto runStart = Clock::now();
  auto outputStart = runStart;
  ImplicitOutput<ExecutionSpaceT> output(model, directory, solver, historyColumns, checkpoint ? &*checkpoint : nullptr,
                                         gather);
  if (!checkpoint) output.writeFields();
  double outputSeconds = fencedSecondsSince(space, outputStart);
  // Every increment prints: static increments are few and each one's iterations matter.
  io::ProgressReporter progress(increments, log, 0.0);
  progress.continueFrom(firstIncrement - 1);
  const char* initialPreconditioner = preconditionerName(solver.activePreconditioner());
  log << "implicit: linear solver: " << initialPreconditioner << " preconditioned "
      << (solver.tangentForm() == TangentForm::Exact ? "GMRES (exact tangent)" : "CG") << "\n";
  bool limitPointReported = counters[8] != 0, snapReported = counters[9] != 0, roundOffReported = counters[10] != 0;
  ImplicitRunSummary summary;
  summary.newtonIterations = counters[1];
  summary.linearIterations = counters[2];
  summary.cuts = static_cast<int>(counters[3]);
  summary.factorizations = counters[4];
  summary.lineSearches = counters[5];
  summary.preconditionerBuilds = counters[6];
  summary.negativePivots = static_cast<long>(counters[7]);
  summary.maxDisplacement = maxDisplacement;
  PhaseSeconds phases;
  int taken = firstIncrement - 1;
  bool reachedDeckEnd = false;
  CheckpointSchedule checkpointSchedule(deck.output);
  int checkpointsWritten = 0;
  const auto writeCheckpoint = [&](int increment) {
    io::Checkpoint state;
    solver.saveTo(state, gather);
    if (communicator.root()) {
      putOutputPosition(state, output.position());
      state.putIntegers("implicit-run.counters",
                        {increment, summary.newtonIterations, summary.linearIterations, summary.cuts,
                         summary.factorizations, summary.lineSearches, summary.preconditionerBuilds,
                         summary.negativePivots, limitPointReported, snapReported, roundOffReported});
      state.putReal("implicit-run.max-displacement", summary.maxDisplacement);
      writeRunCheckpoint(state, model, "implicit", directory);
    }
    // Every rank restarts its clock: the next checkpoint by the clock is due on all alike.
    checkpointSchedule.written();
    ++checkpointsWritten;
  };
  // A long increment shows where Newton is at least every progressEverySeconds.
  int currentIncrement = 0;
  auto lastLine = Clock::now();
  solver.observeIterations([&](double target, const IncrementReport& sofar) {
    if (std::chrono::duration<double>(Clock::now() - lastLine).count() < runOptions.progressEverySeconds) return;
    lastLine = Clock::now();
    log << "implicit: increment " << currentIncrement << " in progress: load factor " << formatNumber(target, 6)
        << "  Newton " << sofar.newtonIterations << "  cuts " << sofar.cuts << "  relative residual "
        << formatNumber(sofar.relativeResidual, 3) << std::endl;
  });
  for (int increment = firstIncrement; increment <= increments; ++increment) {
    currentIncrement = increment;
    lastLine = Clock::now();
    IncrementReport report;
    try {
      report = arcLength ? solver.advanceByArcLength() : solver.advanceTo(double(increment) / deckIncrements);
    } catch (const NewtonFailure& failure) {
      output.writeFields();
      throw NewtonFailure("increment " + std::to_string(increment) + " of " + std::to_string(deckIncrements) + ": " +
                          failure.what() + "; the last converged state (load factor " +
                          formatNumber(solver.loadFactor()) + ") is in " + output.xdmfPath());
    }
    for (const auto& note : report.notes) log << "implicit: increment " << increment << ": " << note << "\n";
    if (report.convergedAtRoundOff && !roundOffReported) {
      log << "implicit: note: increment " << increment << " stopped at the round-off floor of the internal forces "
          << "(relative residual " << formatNumber(report.relativeResidual, 3) << ", above solver.tolerance): the "
          << "load is small against the model's stiffness times its size, and Newton had stopped moving; the "
          << "displacements are as accurate as double precision allows (a larger load reaches the tolerance, and "
          << "a linear response scales back).\n";
      roundOffReported = true;
    }
    if (report.negativePivots > 0 && !limitPointReported) {
      log << "implicit: warning: increment " << increment << ": the tangent has " << report.negativePivots
          << " negative pivot(s) at load factor " << formatNumber(solver.loadFactor(), 6)
          << ": a limit or bifurcation point has been reached or passed"
          << (arcLength ? " (arc-length control follows the path on)"
                        : ". Load control cannot follow a load path that falls past a limit point; results beyond it "
                          "may be off the equilibrium path (solver.control: arc-length follows it)")
          << ".\n";
      limitPointReported = true;
    }
    if (report.passedUnstableState && !arcLength && !snapReported) {
      log << "implicit: warning: increment " << increment << " (load factor " << formatNumber(solver.loadFactor(), 6)
          << ") passed through unstable states to a stable one: the model snapped past a limit point, and the path "
             "in between was not followed (solver.control: arc-length follows it).\n";
      snapReported = true;
    }
    summary.negativePivots = std::max(summary.negativePivots, report.negativePivots);
    summary.factorizations += report.factorizations;
    summary.lineSearches += report.lineSearches;
    summary.cuts += report.cuts;
    phases.residual += report.seconds.residual;
    phases.assembly += report.seconds.assembly;
    phases.constraints += report.seconds.constraints;
    phases.preconditioner += report.seconds.preconditioner;
    phases.linearSolve += report.seconds.linearSolve;
    phases.update += report.seconds.update;
    summary.newtonIterations += report.newtonIterations;
    summary.linearIterations += report.linearIterations;
    summary.preconditionerBuilds += report.preconditionerBuilds;
    taken = increment;
    // A stop request (SIGINT, SIGTERM) ends the run after this converged increment, written.
    // A checkpoint by the wall clock, on every rank after the same increment too.
    summary.stoppedBySignal = stopRequestSignal();
    bool checkpointByClock = checkpointSchedule.dueByClock();
    agreeOnRanks(communicator, summary.stoppedBySignal, checkpointByClock);
    const bool deckEnd = increment == deckIncrements || (arcLength && solver.loadFactor() >= 1.0);
    reachedDeckEnd = deckEnd;
    const bool last = increment == increments || deckEnd || summary.stoppedBySignal != 0;
    const bool historyOnSchedule = increment % deck.output.historyEvery == 0;
    const bool fieldsOnSchedule = deck.output.every > 0 && increment % deck.output.every == 0;
    // A checkpoint on its schedule, where the run stops before the deck's end (to be
    // continued), and at the deck's end when the deck asks for checkpoints (to be extended).
    const bool checkpointDue = checkpointSchedule.dueByStep(increment) || checkpointByClock ||
                               (last && (!deckEnd || deck.output.checkpoints()));
    outputStart = Clock::now();
    if (last || historyOnSchedule || fieldsOnSchedule || checkpointDue)
      requireHealthyState(model, solver, increment, deckIncrements, gather, communicator);
    if (historyOnSchedule) summary.maxDisplacement = output.appendHistory(increment, report);
    if (fieldsOnSchedule) output.writeFields();
    // Before the last increment's extra outputs: a continued run cuts them off and writes its own.
    if (checkpointDue) writeCheckpoint(increment);
    if (last && !historyOnSchedule) summary.maxDisplacement = output.appendHistory(increment, report);
    if (last && !fieldsOnSchedule) output.writeFields();
    outputSeconds += std::chrono::duration<double>(Clock::now() - outputStart).count();
    progress.update(last ? increments : increment, incrementState(report));
    if (last) break;
  }
  summary.increments = taken;
  // Arc-length control that ran out of increments short of the full load did not finish the
  // deck's job: an error after the summary, unless --max-steps asked for fewer increments.
  const bool stoppedShort =
      arcLength && solver.loadFactor() < 1.0 && increments == deckIncrements && summary.stoppedBySignal == 0;
  summary.wallSeconds = std::chrono::duration<double>(Clock::now() - runStart).count();
  summary.xdmfPath = output.xdmfPath();
  summary.historyPath = output.historyPath();
  summary.phases = {{"setup", setupSeconds},
                    {"internal-forces", phases.residual},
                    {"assembly", phases.assembly},
                    {"constraints", phases.constraints},
                    {"preconditioner", phases.preconditioner},
                    {"linear-solve", phases.linearSolve},
                    {"update", phases.update},
                    {"output", outputSeconds},
                    {"total", setupSeconds + summary.wallSeconds}};
  if (communicator.root()) summary.timingsPath = writePhaseTimes(directory, summary.phases);
  io::SummaryTable("implicit run summary")
      .add("backend", ExecutionSpaceT::name() + ranksText(communicator))
      .add("increments", std::to_string(taken) +
                             (!arcLength && taken < deckIncrements ? " of " + std::to_string(deckIncrements)
                                                                   : std::string()) +
                             " (" + std::to_string(summary.cuts) + " cuts)" +
                             (summary.stoppedBySignal != 0
                                  ? std::string(", stopped by ") + stopSignalName(summary.stoppedBySignal)
                                  : std::string()))
      .add("load factor", formatNumber(solver.loadFactor(), 6) + (arcLength ? " (arc-length control)" : ""))
      .add("Newton iterations", std::to_string(summary.newtonIterations) + " (" +
                                    std::to_string(summary.lineSearches) + " shortened by the line search)")
      .add("linear iterations", std::to_string(summary.linearIterations) + " (" +
                                    preconditionerName(solver.activePreconditioner()) + ")")
      .add("tangent", summary.negativePivots > 0 ? "lost positive definiteness (up to " +
                                                       std::to_string(summary.negativePivots) + " negative pivots)"
                                                 : std::string(summary.factorizations > 0 ? "positive definite" : "-"))
      .add("max displacement", formatNumber(summary.maxDisplacement, 6) + " m")
      .add("wall time", io::formatDuration(summary.wallSeconds))
      .add("  internal forces", formatNumber(phases.residual) + " s")
      .add("  tangent assembly", formatNumber(phases.assembly) + " s")
      .add("  constraints", formatNumber(phases.constraints) + " s")
      .add("  preconditioner", formatNumber(phases.preconditioner) + " s" +
                                   (summary.preconditionerBuilds > 0
                                        ? " (" + std::to_string(summary.preconditionerBuilds) + " AMG build" +
                                              (summary.preconditionerBuilds == 1 ? ")" : "s)")
                                        : std::string()) +
                                   (summary.factorizations > 0
                                        ? " (" + std::to_string(summary.factorizations) + " factorizations" +
                                              (solver.factorizationPlace().empty()
                                                   ? std::string()
                                                   : ", the last on the " + solver.factorizationPlace()) +
                                              ")"
                                        : std::string()))
      .add("  linear solve", formatNumber(phases.linearSolve) + " s")
      .add("  update", formatNumber(phases.update) + " s")
      .add("  output", formatNumber(outputSeconds) + " s")
      .add("setup", formatNumber(setupSeconds) + " s")
      .add("fields", summary.xdmfPath)
      .add("history", summary.historyPath)
      .add("timings", summary.timingsPath)
      .add("checkpoint", checkpointsWritten == 0 ? std::string("-")
                                                 : checkpointPath(directory) + " (increment " + std::to_string(taken) +
                                                       (!reachedDeckEnd
                                                            ? "; continue with --restart " + directory
                                                            : std::string()) + ")")
      .print(log);
  if (stoppedShort)
    throw NewtonFailure("arc-length control reached load factor " + formatNumber(solver.loadFactor(), 6) +
                        ", not 1, in the deck's solver.max-increments (" + std::to_string(deckIncrements) +
                        "); raise it, or raise solver.increments for a longer first arc. The states reached are in " +
                        summary.xdmfPath);
  return summary;
}

}  // namespace

void requireDistributableImplicitRun(const model::Model& model) {
  const auto communicator = parallel::Communicator::world();
  if (!communicator.distributed()) return;
  const auto& deck = model.deck;
  const std::string ranks = " in a run on " + std::to_string(communicator.size()) + " ranks";
  if (deck.solver.implicitSettings.preconditioner == deck::Preconditioner::Direct)
    throw std::invalid_argument(deck.sourceName + ": solver.preconditioner: direct factors the whole tangent, which no "
                                "rank holds" + ranks + "; use cholesky (each rank's block factored, preconditioning "
                                "CG over all ranks), amg or block-jacobi");
}

ImplicitRunSummary runImplicit(const model::Model& model, const RunOptions& options, std::ostream& log) {
  if constexpr (!std::is_same_v<ExecutionSpace, HostExecutionSpace>)
    if (options.backend == Backend::Host) return runImplicitOn(HostExecutionSpace{}, model, options, log);
  return runImplicitOn(ExecutionSpace{}, model, options, log);
}

}  // namespace perishell::solvers
