#include <perishell/core/stop_request.hpp>
#include <perishell/io/csv_history.hpp>
#include <perishell/io/progress.hpp>
#include <perishell/io/xdmf_writer.hpp>
#include <perishell/model/nodal_loads.hpp>
#include <perishell/coupling/adaptive_zone.hpp>
#include <perishell/solvers/explicit/central_difference.hpp>
#include <perishell/solvers/explicit/explicit_run.hpp>
#include <perishell/solvers/history_columns.hpp>
#include <perishell/solvers/model_actions.hpp>
#include <perishell/solvers/run_checkpoint.hpp>
#include <perishell/solvers/state_check.hpp>

#include <algorithm>
#include <array>
#include <optional>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <ostream>
#include <sstream>
#include <type_traits>

namespace perishell::solvers {
namespace {

using HostVector3 = Kokkos::View<double* [3], Kokkos::LayoutRight, Kokkos::HostSpace>;

// A node is on the crack when it has lost this share of its neighbour volume (docs/deck.md).
constexpr double crackDamage = 0.4;

void requireRunnableModel(const model::Model& model) {
  const auto& deck = model.deck;
  for (const auto& load : deck.loads)
    if (load.follower)
      throw std::invalid_argument(deck.sourceName + ": loads." + load.name +
                                  ".follower: the explicit solver applies pressure in the reference direction "
                                  "only; set follower: false");
}

const std::string& createdDirectory(const std::string& directory) {
  std::filesystem::create_directories(directory);
  return directory;
}

std::string formatSeconds(double seconds) {
  std::ostringstream text;
  text.precision(4);
  text << seconds << " s";
  return text.str();
}

// Writes fields and history rows of one run; copies device data only when called.
template <class ExecutionSpaceT>
class RunOutput {
 public:
  using Solver = CentralDifferenceSolver<ExecutionSpaceT>;
  // restart: continue the outputs of the run that wrote it (solvers/run_checkpoint.hpp).
  RunOutput(const model::Model& model, const std::string& directory, const Solver& solver,
            const HistoryColumns& shared, const io::Checkpoint* restart)
      : model_(model),
        solver_(solver),
        shared_(shared),
        writer_(createdDirectory(directory), "results", model.outputMesh()),
        damage_("pd damage", model.shell.mesh.numNodes()),
        zoneNodes_(model.pdNodes) {
    const auto& deck = model.deck;
    std::vector<std::string> columns = {"step", "time"};
    for (const auto& load : deck.loads)
      if (!load.curve.empty() && std::find(curves_.begin(), curves_.end(), load.curve) == curves_.end())
        curves_.push_back(load.curve);
    for (const auto& curve : curves_) columns.push_back("load-factor-" + curve);
    auto add = [&columns](const std::vector<std::string>& more) {
      columns.insert(columns.end(), more.begin(), more.end());
    };
    for (const auto quantity : deck.output.history) {
      switch (quantity) {
        case deck::HistoryQuantity::Energy:
          for (const char* name : {"kinetic", "strain", "fracture", "damping", "external-work", "support-work",
                                   "energy-balance-error"})
            columns.push_back(name);
          break;
        case deck::HistoryQuantity::Reactions:
          add(shared.reactionColumns());
          // The loads on prescribed DOFs go straight into the supports (host copies of the patterns).
          hostActions_ = makeExternalActions<Kokkos::HostSpace>(model);
          break;
        case deck::HistoryQuantity::BrokenBonds: columns.push_back("broken-bonds"); break;
        case deck::HistoryQuantity::CrackTip:
          for (const char* name : {"crack-tip-x", "crack-tip-y", "crack-tip-z", "crack-length", "crack-tip-speed"})
            columns.push_back(name);
          break;
        case deck::HistoryQuantity::LoadPoints: add(shared.loadPointColumns()); break;
      }
    }
    add(shared.probeColumns());
    if (restart) {
      auto position = takeOutputPosition(*restart);
      writer_.continueSeries(std::move(position.fieldSteps));
      history_.emplace(directory + "/history.csv", columns, position.historyRows);
      const auto& tip = restart->reals("output.crack-tip");
      if (tip.size() != 7) throw io::CheckpointError(restart->context() + "'output.crack-tip' is not of this version");
      lastTipTime_ = tip[0];
      lastTipDistance_ = tip[1];
      if (tip[2] != 0.0) crackTip_ = CrackTip{{tip[3], tip[4], tip[5]}, tip[6]};
    } else {
      history_.emplace(directory + "/history.csv", columns);
    }
    if (!deck.mesh.preCracks.empty()) {
      const auto& start = deck.mesh.preCracks.front().segment.start;
      crackOrigin_ = {start[0], start[1], start[2]};
    }
  }

  std::string xdmfPath() const { return writer_.xdmfPath(); }
  // How far the outputs have got, and the crack tip's last row, for a checkpoint.
  void saveTo(io::Checkpoint& checkpoint) const {
    putOutputPosition(checkpoint, {history_->numRows(), writer_.steps()});
    const CrackTip tip = crackTip_.value_or(CrackTip{});
    checkpoint.putReals("output.crack-tip", {lastTipTime_, lastTipDistance_, crackTip_ ? 1.0 : 0.0, tip.position[0],
                                             tip.position[1], tip.position[2], tip.length});
  }
  // The nodes of PD elements, for the zone field (the adaptive zone grows them).
  void setZoneNodes(const Kokkos::View<LocalIndex*, Kokkos::HostSpace>& nodes) { zoneNodes_ = nodes; }
  std::string historyPath() const { return history_->path(); }
  // The crack tip of the last history row, when the history tracks it (deck: history: crack-tip).
  std::optional<CrackTip> crackTip() const { return crackTip_; }

  void writeFields() {
    const auto& deck = model_.deck;
    const LocalIndex numNodes = model_.shell.mesh.numNodes();
    std::vector<io::NodalField> fields;
    for (const auto field : deck.output.fields) {
      switch (field) {
        case deck::OutputField::Displacement:
          fields.push_back({"displacement", 3, hostDisplacements()});
          break;
        case deck::OutputField::Rotation:
          fields.push_back(io::makeRotationVectorField(
              "rotation", Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, solver_.kinematics().rotations)));
          break;
        case deck::OutputField::Velocity: {
          const auto velocities = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, solver_.velocities());
          HostVector3 translational("velocity", numNodes);
          for (LocalIndex node = 0; node < numNodes; ++node)
            for (int d = 0; d < 3; ++d) translational(node, d) = velocities(node, d);
          fields.push_back({"velocity", 3, translational});
          break;
        }
        case deck::OutputField::Damage:
          fields.push_back(io::makeScalarField("damage", hostDamage()));
          break;
        case deck::OutputField::Zone: {
          Kokkos::View<int*, Kokkos::HostSpace> zone("zone", numNodes);
          for (std::size_t k = 0; k < zoneNodes_.extent(0); ++k) zone(zoneNodes_(k)) = 1;
          fields.push_back(io::makeScalarField("zone", zone));
          break;
        }
      }
    }
    for (auto& field : fields) field = io::firstNodes(field, model_.numMeshNodes());
    writer_.writeStep(solver_.time(), fields);
  }

  // energy: the row's state's (Solver::checkState(), which also leaves its forces for the reactions).
  void appendHistory(Solver& solver, const EnergyReport& energy) {
    const auto& deck = model_.deck;
    std::vector<double> row = {double(solver.stepIndex()), solver.time()};
    for (const auto& curve : curves_) row.push_back(deck::evaluateCurve(*deck.findCurve(curve), solver.time()));
    HostVector3 displacements;
    auto currentDisplacements = [&] {
      if (displacements.extent(0) == 0) displacements = hostDisplacements();
      return displacements;
    };
    for (const auto quantity : deck.output.history) {
      switch (quantity) {
        case deck::HistoryQuantity::Energy: {
          const auto& e = energy;
          row.insert(row.end(),
                     {e.kinetic, e.strain, e.fracture, e.damping, e.externalWork, e.supportWork, e.balanceError()});
          break;
        }
        case deck::HistoryQuantity::Reactions: shared_.appendReactions(outOfBalance(), row); break;
        case deck::HistoryQuantity::BrokenBonds: row.push_back(double(solver.brokenBonds())); break;
        case deck::HistoryQuantity::CrackTip: appendCrackTip(solver.time(), row); break;
        case deck::HistoryQuantity::LoadPoints: shared_.appendLoadPoints(currentDisplacements(), row); break;
      }
    }
    if (!shared_.probes().empty())
      shared_.appendProbes(currentDisplacements(),
                           Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, solver.kinematics().rotations),
                           row);
    history_->append(row);
  }

 private:
  HostVector3 hostDisplacements() const {
    return Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, solver_.kinematics().displacements);
  }

  // P + the bond and element forces at every node DOF at the row's time, the forces being those
  // of the last evaluation (energies() takes the row's state): what the supports balance where
  // they prescribe a DOF (the inertia of prescribed nodes left out).
  model::HostNodalValues outOfBalance() const {
    model::HostNodalValues sum("out of balance", model_.shell.mesh.numNodes());
    Kokkos::deep_copy(sum, solver_.forces());
    const auto factors = hostActions_.loadFactors(solver_.time());
    for (std::size_t node = 0; node < sum.extent(0); ++node)
      for (int p = 0; p < hostActions_.numPatterns(); ++p)
        for (int d = 0; d < 6; ++d) sum(node, d) += factors.values[p] * hostActions_.loadPatterns(node, 6 * p + d);
    return sum;
  }

  Kokkos::View<double*, Kokkos::HostSpace> hostDamage() {
    solver_.computeDamage(damage_);
    return Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, damage_);
  }


  // The damaged node farthest from the first pre-crack's start; its speed is the growth of
  // that distance between rows (the tip speed while the crack runs away from its origin).
  void appendCrackTip(double time, std::vector<double>& row) {
    const auto damage = hostDamage();
    const auto& x = model_.shell.mesh.coordinates;
    double farthest = 0.0;
    double tip[3] = {crackOrigin_[0], crackOrigin_[1], crackOrigin_[2]};
    for (LocalIndex node = 0; node < model_.numMeshNodes(); ++node) {
      if (damage(node) < crackDamage) continue;
      const double distance = std::hypot(x(node, 0) - crackOrigin_[0], x(node, 1) - crackOrigin_[1], x(node, 2) - crackOrigin_[2]);
      if (distance > farthest) {
        farthest = distance;
        for (int d = 0; d < 3; ++d) tip[d] = x(node, d);
      }
    }
    crackTip_ = CrackTip{{tip[0], tip[1], tip[2]}, farthest};
    // No speed across the row where the crack first shows (its distance jumps from nothing).
    const double speed = time > lastTipTime_ && lastTipDistance_ > 0.0 ? (farthest - lastTipDistance_) / (time - lastTipTime_) : 0.0;
    lastTipTime_ = time;
    lastTipDistance_ = farthest;
    row.insert(row.end(), {tip[0], tip[1], tip[2], farthest, speed});
  }

  const model::Model& model_;
  const Solver& solver_;
  const HistoryColumns& shared_;
  ExternalActions<Kokkos::HostSpace> hostActions_;  // with reactions only
  io::XdmfTimeSeriesWriter writer_;
  std::optional<io::CsvHistory> history_;
  VectorView<typename ExecutionSpaceT::memory_space> damage_;
  Kokkos::View<LocalIndex*, Kokkos::HostSpace> zoneNodes_;
  std::vector<std::string> curves_;
  std::array<double, 3> crackOrigin_{0.0, 0.0, 0.0};
  double lastTipTime_ = -1.0, lastTipDistance_ = 0.0;
  std::optional<CrackTip> crackTip_;
};

// The adaptive zone a checkpoint recorded: the elements that had turned PD.
Kokkos::View<std::uint8_t*, Kokkos::HostSpace> checkpointZone(const io::Checkpoint& checkpoint,
                                                              const model::Model& model) {
  Kokkos::View<std::uint8_t*, Kokkos::HostSpace> zone("checkpoint zone", model.elementIsPd.extent(0));
  takeView(checkpoint, "adaptive.element-is-pd", zone, "the deck's mesh is not the one of the checkpoint's run");
  return zone;
}

// Stops the run on a non-finite, runaway or blown-up state (docs/reliability.md), naming the
// step, the quantity and the deck's likely cause; the files hold the steps before.
template <class Solver>
void requireHealthyState(const model::Model& model, const Solver& solver, const typename Solver::StateCheck& check,
                         long long step, double time) {
  const auto extent = displacementExtent(
      model, Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, solver.kinematics().displacements));
  if (check.healthy() && !extent.blownUp()) return;
  std::ostringstream message;
  message.precision(4);
  message << "explicit solver: unstable at step " << step << " (t = " << time << " s): ";
  if (extent.finite && !check.finite)
    message << "the energies are no longer finite; ";
  else if (extent.finite && check.runaway)
    message << "the stored energy " << check.energy.stored() << " J exceeds the work done on the body "
            << check.energy.input() << " J; ";
  message << extent.describe();
  message << ". Likely cause: " << explicitBlowUpCause(model.deck, solver.timeStep(), solver.criticalTimeStep())
          << ". This state was not written; the result files hold the steps before it.";
  throw ExplicitInstability(message.str());
}

template <class ExecutionSpaceT>
ExplicitRunSummary runExplicitOn(const ExecutionSpaceT& space, const model::Model& model, const RunOptions& runOptions,
                                 std::ostream& log) {
  requireRunnableModel(model);
  using Clock = std::chrono::steady_clock;
  const auto& deck = model.deck;
  // Before the set-up: a directory another run holds is refused at once.
  const RunDirectory runDirectory(model, runOptions, "explicit", log);
  const std::string& directory = runDirectory.path();
  const auto& checkpoint = runDirectory.checkpoint();
  const auto& settings = deck.solver.explicitSettings;
  const auto setupStart = Clock::now();
  // Before the solver's set-up, so that a probe off the shell stops the run at once.
  const HistoryColumns historyColumns(model);
  printProbes(model, historyColumns.probes(), log);
  // Bonds where alpha > 0, shell elements where the model is CCM or in the transition (model.md §4);
  // with zones.adaptive the zone object owns them and grows the PD zone during the run.
  std::optional<coupling::AdaptivePdZone<ExecutionSpaceT>> adaptive;
  if (deck.zones.adaptive)
    adaptive.emplace(space, model.shell.mesh, checkpoint ? checkpointZone(*checkpoint, model) : model.elementIsPd,
                     coupling::couplingInputs(model), deck.zones.adaptive->strainFraction);
  const auto bodies = adaptive ? adaptive->bodies() : coupling::makeCoupledBodies(space, model);
  const auto& body = bodies.pdBody;
  // The support layer's elements are PD from the start; the counts are the deck's mesh's.
  const LocalIndex layerElements = model.shell.mesh.numElements() - model.numMeshElements();
  ExplicitOptions options;
  options.density = deck.material.density;
  options.thickness = deck.material.thickness;
  options.timeStep = settings.timeStep.value_or(0.0);
  options.safetyFactor = settings.safetyFactor;
  options.damping = settings.damping;
  options.forceKernel = deck.peridynamics.forceKernel;
  options.monitorEvery = std::min<long long>(100, deck.output.historyEvery);
  options.timePhases = runOptions.timePhases;
  CentralDifferenceSolver<ExecutionSpaceT> solver(space, body, bodies.shellElements(),
                                                  makeExternalActions<typename ExecutionSpaceT::memory_space>(model),
                                                  options);
  if (checkpoint) solver.restoreFrom(*checkpoint);
  const long long deckSteps =
      settings.steps ? *settings.steps
                     : std::max(1LL, static_cast<long long>(std::ceil(*settings.endTime / solver.timeStep() - 1e-9)));
  const long long totalSteps = std::min(deckSteps, runOptions.maxSteps.value_or(deckSteps));
  const double setupSeconds = fencedSecondsSince(space, setupStart);
  log << "explicit: " << bodies.pdNodes.extent(0) << " PD nodes, " << body.bonds.numBonds() << " bonds, "
      << solver.numElements() << " shell elements ("
      << (settings.shellElement == deck::ExplicitSettings::ShellElement::OnePoint ? "one-point" : "MITC4") << ") on "
      << ExecutionSpaceT::name() << "; dt = " << solver.timeStep() << " s (critical estimate "
      << solver.criticalTimeStep() << " s), " << totalSteps << " steps to t = " << totalSteps * solver.timeStep()
      << " s; setup " << formatSeconds(setupSeconds) << "\n";
  if (totalSteps < deckSteps)
    log << "explicit: stopping after " << totalSteps << " of the deck's " << deckSteps << " steps (--max-steps)\n";
  if (checkpoint)
    log << "restart: continuing from step " << solver.stepIndex() << " (t = " << solver.time() << " s) of "
        << checkpoint->source() << "; dt " << solver.timeStep() << " s as that run had it\n";
  if (checkpoint && solver.stepIndex() >= totalSteps)
    throw std::invalid_argument("restart: the checkpoint is at step " + std::to_string(solver.stepIndex()) +
                                ", and this run ends at step " + std::to_string(totalSteps) +
                                ": nothing is left to run (raise solver.steps or solver.end-time, or --max-steps)");
  if (adaptive)
    log << "adaptive PD zone: a CCM element turns PD when its surface strain reaches "
        << deck.zones.adaptive->strainFraction << " x s_c = " << adaptive->threshold() << " (checked every "
        << deck.zones.adaptive->checkEvery << " steps); " << model.numPdElements << " PD elements at the start\n";
  if (solver.timeStep() > solver.criticalTimeStep())
    log << "warning: solver.dt is " << solver.timeStep() / solver.criticalTimeStep()
        << " x the estimated critical step; the run is expected to go unstable\n";

  // The run's wall time starts with the first output, so total = setup + run.
  const auto runStart = Clock::now();
  auto outputStart = runStart;
  RunOutput<ExecutionSpaceT> output(model, directory, solver, historyColumns, checkpoint ? &*checkpoint : nullptr);
  if (!checkpoint) {
    output.writeFields();
    output.appendHistory(solver, solver.checkState().energy);
  } else if (adaptive) {
    output.setZoneNodes(adaptive->pdElementNodes());
  }
  double outputSeconds = fencedSecondsSince(space, outputStart), adaptiveSeconds = 0.0;
  io::ProgressReporter progress(totalSteps, log);
  progress.continueFrom(solver.stepIndex());
  const long long fieldEvery = deck.output.every, historyEvery = deck.output.historyEvery;
  long long switches = checkpoint ? checkpoint->integer("explicit-run.zone-switches") : 0;
  int stoppedBy = 0;
  CheckpointSchedule checkpointSchedule(deck.output);
  int checkpointsWritten = 0;
  const auto writeCheckpoint = [&] {
    io::Checkpoint state;
    solver.saveTo(state);
    output.saveTo(state);
    if (adaptive) putView(state, "adaptive.element-is-pd", adaptive->elementIsPd());
    state.putInteger("explicit-run.zone-switches", switches);
    writeRunCheckpoint(state, model, "explicit", directory);
    checkpointSchedule.written();
    ++checkpointsWritten;
  };
  while (solver.stepIndex() < totalSteps) {
    try {
      solver.step();
    } catch (const ExplicitInstability&) {
      // The monitor (step() advanced the state, not yet the counter) names solver.dt whether or
      // not the deck sets it: the diagnosis in the deck's terms replaces its message.
      requireHealthyState(model, solver, solver.checkState(), solver.stepIndex() + 1,
                          solver.time() + solver.timeStep());
      throw;
    }
    const long long step = solver.stepIndex();
    if (adaptive && step % deck.zones.adaptive->checkEvery == 0) {
      const auto checkStart = Clock::now();
      const LocalIndex switched = coupling::growPdZone(*adaptive, solver);
      if (switched > 0) {
        output.setZoneNodes(adaptive->pdElementNodes());
        ++switches;
        log << "adaptive PD zone: step " << step << " (t = " << solver.time() << " s): " << switched
            << " elements turned PD, now " << adaptive->numPdElements() - layerElements << " PD elements, "
            << solver.body().bonds.numBonds() << " bonds, " << solver.numElements() << " shell elements\n";
      }
      adaptiveSeconds += fencedSecondsSince(space, checkStart);
    }
    // A stop request (SIGINT, SIGTERM) ends the run here, with this step written as the last.
    stoppedBy = stopRequestSignal();
    const bool last = step == totalSteps || stoppedBy != 0;
    const bool historyOnSchedule = step % historyEvery == 0;
    const bool fieldsOnSchedule = fieldEvery > 0 && step % fieldEvery == 0;
    // A checkpoint on its schedule, where the run stops before the deck's end (to be
    // continued), and at the deck's end when the deck asks for checkpoints (to be extended).
    const bool checkpointDue =
        checkpointSchedule.due(step) || (last && (step < deckSteps || deck.output.checkpoints()));
    outputStart = Clock::now();
    if (last || historyOnSchedule || fieldsOnSchedule || checkpointDue) {
      const auto check = solver.checkState();
      requireHealthyState(model, solver, check, step, solver.time());
      if (historyOnSchedule) output.appendHistory(solver, check.energy);
      if (fieldsOnSchedule) output.writeFields();
      // Before the last step's extra outputs: a continued run cuts them off and writes its own.
      if (checkpointDue) writeCheckpoint();
      if (last && !historyOnSchedule) output.appendHistory(solver, check.energy);
      if (last && !fieldsOnSchedule) output.writeFields();
    }
    outputSeconds += std::chrono::duration<double>(Clock::now() - outputStart).count();
    progress.update(step, solver.time());
    if (stoppedBy != 0) break;
  }
  space.fence();
  ExplicitRunSummary summary;
  summary.steps = solver.stepIndex();
  summary.stoppedBySignal = stoppedBy;
  summary.timeStep = solver.timeStep();
  summary.criticalTimeStep = solver.criticalTimeStep();
  summary.endTime = solver.time();
  summary.wallSeconds = std::chrono::duration<double>(Clock::now() - runStart).count();
  summary.brokenBonds = solver.brokenBonds();
  summary.xdmfPath = output.xdmfPath();
  summary.historyPath = output.historyPath();
  summary.crackTip = output.crackTip();
  // The steps' share: the run less output and zone growth; split by phase when timed.
  const auto& phase = solver.phaseSeconds();
  const double stepSeconds = summary.wallSeconds - outputSeconds - adaptiveSeconds;
  summary.phases = {{"setup", setupSeconds}, {"steps", stepSeconds}};
  if (runOptions.timePhases)
    summary.phases.insert(summary.phases.end(), {{"forces", phase.forces},
                                                 {"integration", phase.integration},
                                                 {"monitor", phase.monitor}});
  if (adaptive) summary.phases.emplace_back("adaptive-zone", adaptiveSeconds);
  summary.phases.emplace_back("output", outputSeconds);
  summary.phases.emplace_back("total", setupSeconds + summary.wallSeconds);
  summary.timingsPath = writePhaseTimes(directory, summary.phases);

  const auto energy = solver.energies();
  std::ostringstream balance;
  balance.precision(3);
  balance << energy.balanceError();
  io::SummaryTable table("explicit run summary");
  table.add("backend", ExecutionSpaceT::name())
      .add("steps", std::to_string(summary.steps) +
                        (summary.steps < deckSteps ? " of " + std::to_string(deckSteps) : "") +
                        (stoppedBy != 0 ? std::string(" (stopped by ") + stopSignalName(stoppedBy) + ")" : ""))
      .add("time step", formatSeconds(summary.timeStep) + " (critical " + formatSeconds(summary.criticalTimeStep) + ")")
      .add("simulated time", formatSeconds(summary.endTime))
      .add("wall time", io::formatDuration(summary.wallSeconds) + " (" +
                            formatSeconds(summary.wallSeconds / double(std::max(1LL, summary.steps))) + " per step)");
  if (runOptions.timePhases)
    table.add("  forces", formatSeconds(phase.forces))
        .add("  integration", formatSeconds(phase.integration))
        .add("  energy monitor", formatSeconds(phase.monitor));
  if (adaptive) table.add("  adaptive zone", formatSeconds(adaptiveSeconds));
  table.add("  output", formatSeconds(outputSeconds))
      .add("setup", formatSeconds(setupSeconds))
      .add("broken bonds", std::to_string(summary.brokenBonds) + " of " + std::to_string(solver.body().bonds.numBonds()))
      .add("energy balance error", balance.str());
  if (summary.crackTip) {
    std::ostringstream tip;
    tip.precision(4);
    const auto& at = summary.crackTip->position;
    tip << summary.crackTip->length << " m from the first pre-crack's start, tip at (" << at[0] << ", " << at[1]
        << ", " << at[2] << ") m";
    table.add("crack length", tip.str());
  }
  table.add("fields", summary.xdmfPath)
      .add("history", summary.historyPath)
      .add("timings", summary.timingsPath);
  if (checkpointsWritten > 0)
    table.add("checkpoint", checkpointPath(directory) + " (step " + std::to_string(summary.steps) +
                                (stoppedBy != 0 || summary.steps < deckSteps ? "; continue with --restart " + directory
                                                                             : std::string()) + ")");
  if (adaptive)
    table.add("adaptive PD zone", std::to_string(model.numPdElements) + " -> " +
                                      std::to_string(adaptive->numPdElements() - layerElements) + " PD elements in " +
                                      std::to_string(switches) + " switches");
  table.print(log);
  return summary;
}

}  // namespace

ExplicitRunSummary runExplicit(const model::Model& model, const RunOptions& options, std::ostream& log) {
  if constexpr (!std::is_same_v<ExecutionSpace, HostExecutionSpace>)
    if (options.backend == Backend::Host) return runExplicitOn(HostExecutionSpace{}, model, options, log);
  return runExplicitOn(ExecutionSpace{}, model, options, log);
}

}  // namespace perishell::solvers
