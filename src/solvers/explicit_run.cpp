#include <perishell/core/stop_request.hpp>
#include <perishell/io/csv_history.hpp>
#include <perishell/io/progress.hpp>
#include <perishell/io/xdmf_writer.hpp>
#include <perishell/model/nodal_loads.hpp>
#include <perishell/coupling/adaptive_zone.hpp>
#include <perishell/parallel/gather_nodes.hpp>
#include <perishell/solvers/explicit/central_difference.hpp>
#include <perishell/solvers/explicit/explicit_run.hpp>
#include <perishell/solvers/history_columns.hpp>
#include <perishell/solvers/local_model.hpp>
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

// Whether two ranks of a node run on one GPU (more ranks than GPUs, or a device id chosen
// alike): their contexts take turns on it, so a step's exchange cannot overlap its forces
// (ExplicitOptions::overlapExchange). Host backends share nothing. Collective.
template <class ExecutionSpaceT>
bool ranksShareDevice(const parallel::Communicator& communicator, const ExecutionSpaceT& space) {
#ifdef KOKKOS_ENABLE_CUDA
  if constexpr (std::is_same_v<ExecutionSpaceT, Kokkos::Cuda>) return communicator.anySharedOnNode(space.cuda_device());
#endif
  (void)communicator;
  (void)space;
  return false;
}

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
  // Every rank makes one and calls it alike (its fields are gathered to the root, which
  // alone writes); directory is the root's.
  RunOutput(const model::Model& model, const std::string& directory, const Solver& solver,
            const HistoryColumns& shared, const io::Checkpoint* restart, const parallel::NodeGather& gather)
      : model_(model),
        solver_(solver),
        shared_(shared),
        gather_(gather),
        damage_("pd damage", solver.kinematics().displacements.extent(0)),
        zoneNodes_(model.pdNodes) {
    if (gather.root()) writer_.emplace(createdDirectory(directory), "results", model.outputMesh());
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
          if (gather.root()) hostActions_ = makeExternalActions<Kokkos::HostSpace>(model);
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
    if (!gather.root()) return;
    if (restart) {
      auto position = takeOutputPosition(*restart);
      writer_->continueSeries(std::move(position.fieldSteps));
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

  std::string xdmfPath() const { return writer_ ? writer_->xdmfPath() : std::string(); }
  // How far the outputs have got, and the crack tip's last row, for a checkpoint.
  void saveTo(io::Checkpoint& checkpoint) const {
    putOutputPosition(checkpoint, {history_->numRows(), writer_->steps()});
    const CrackTip tip = crackTip_.value_or(CrackTip{});
    checkpoint.putReals("output.crack-tip", {lastTipTime_, lastTipDistance_, crackTip_ ? 1.0 : 0.0, tip.position[0],
                                             tip.position[1], tip.position[2], tip.length});
  }
  // The nodes of PD elements, for the zone field (the adaptive zone grows them).
  void setZoneNodes(const Kokkos::View<LocalIndex*, Kokkos::HostSpace>& nodes) { zoneNodes_ = nodes; }
  std::string historyPath() const { return history_ ? history_->path() : std::string(); }
  // The crack tip of the last history row, when the history tracks it (deck: history: crack-tip).
  std::optional<CrackTip> crackTip() const { return crackTip_; }

  // Collective.
  void writeFields() {
    const auto& deck = model_.deck;
    const bool root = writer_.has_value();
    std::vector<io::NodalField> fields;
    for (const auto field : deck.output.fields) {
      switch (field) {
        case deck::OutputField::Displacement:
          fields.push_back({"displacement", 3, hostDisplacements()});
          break;
        case deck::OutputField::Rotation: {
          const auto rotations = gather_.gather(solver_.kinematics().rotations);
          if (root) fields.push_back(io::makeRotationVectorField("rotation", rotations));
          break;
        }
        case deck::OutputField::Velocity: {
          const auto velocities = gather_.gather(solver_.velocities());
          const LocalIndex numNodes = static_cast<LocalIndex>(velocities.extent(0));
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
          if (!root) break;
          Kokkos::View<int*, Kokkos::HostSpace> zone("zone", model_.shell.mesh.numNodes());
          for (std::size_t k = 0; k < zoneNodes_.extent(0); ++k) zone(zoneNodes_(k)) = 1;
          fields.push_back(io::makeScalarField("zone", zone));
          break;
        }
      }
    }
    if (!root) return;
    for (auto& field : fields) field = io::firstNodes(field, model_.numMeshNodes());
    writer_->writeStep(solver_.time(), fields);
  }

  // energy: the row's state's (Solver::checkState(), which also leaves its forces for the
  // reactions). Collective: the root computes and writes the row from gathered fields.
  void appendHistory(Solver& solver, const EnergyReport& energy) {
    const bool root = history_.has_value();
    const auto& deck = model_.deck;
    std::vector<double> row = {double(solver.stepIndex()), solver.time()};
    for (const auto& curve : curves_) row.push_back(deck::evaluateCurve(*deck.findCurve(curve), solver.time()));
    // Gathered once per row on every rank (the root's copy alone holds rows).
    std::optional<HostVector3> displacements;
    auto currentDisplacements = [&] {
      if (!displacements) displacements = hostDisplacements();
      return *displacements;
    };
    for (const auto quantity : deck.output.history) {
      switch (quantity) {
        case deck::HistoryQuantity::Energy: {
          const auto& e = energy;
          row.insert(row.end(),
                     {e.kinetic, e.strain, e.fracture, e.damping, e.externalWork, e.supportWork, e.balanceError()});
          break;
        }
        case deck::HistoryQuantity::Reactions: {
          const auto sum = outOfBalance();
          if (root) shared_.appendReactions(sum, row);
          break;
        }
        case deck::HistoryQuantity::BrokenBonds: row.push_back(double(solver.brokenBonds())); break;
        case deck::HistoryQuantity::CrackTip: appendCrackTip(solver.time(), row); break;
        case deck::HistoryQuantity::LoadPoints: {
          const auto u = currentDisplacements();
          if (root) shared_.appendLoadPoints(u, row);
          break;
        }
      }
    }
    if (!shared_.probes().empty()) {
      const auto u = currentDisplacements();
      const auto rotations = gather_.gather(solver.kinematics().rotations);
      if (root) shared_.appendProbes(u, rotations, row);
    }
    if (root) history_->append(row);
  }

 private:
  HostVector3 hostDisplacements() const { return gather_.gather(solver_.kinematics().displacements); }

  // P + the bond and element forces at every node DOF at the row's time, the forces being those
  // of the last evaluation (energies() takes the row's state): what the supports balance where
  // they prescribe a DOF (the inertia of prescribed nodes left out).
  model::HostNodalValues outOfBalance() const {
    const model::HostNodalValues sum = gather_.gather(solver_.forces());
    if (sum.extent(0) == 0) return sum;
    const auto factors = hostActions_.loadFactors(solver_.time());
    for (std::size_t node = 0; node < sum.extent(0); ++node)
      for (int p = 0; p < hostActions_.numPatterns(); ++p)
        for (int d = 0; d < 6; ++d) sum(node, d) += factors.values[p] * hostActions_.loadPatterns(node, 6 * p + d);
    return sum;
  }

  Kokkos::View<double*, Kokkos::HostSpace> hostDamage() {
    solver_.computeDamage(damage_);
    return gather_.gather(damage_);
  }


  // The damaged node farthest from the first pre-crack's start; its speed is the growth of
  // that distance between rows (the tip speed while the crack runs away from its origin).
  void appendCrackTip(double time, std::vector<double>& row) {
    const auto damage = hostDamage();
    if (!history_) return;
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
  const parallel::NodeGather& gather_;
  ExternalActions<Kokkos::HostSpace> hostActions_;  // with reactions only
  std::optional<io::XdmfTimeSeriesWriter> writer_;  // the root's
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
// Empty when the state is healthy.
template <class Solver, class DisplacementsT>
std::string unhealthyStateMessage(const model::Model& model, const Solver& solver,
                                  const typename Solver::StateCheck& check, long long step, double time,
                                  const DisplacementsT& displacements) {
  const auto extent = displacementExtent(model, displacements);
  if (check.healthy() && !extent.blownUp()) return {};
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
  return message.str();
}

// Collective: the root judges the gathered displacements and every rank throws its verdict.
template <class Solver>
void requireHealthyState(const model::Model& model, const Solver& solver, const typename Solver::StateCheck& check,
                         long long step, double time, const parallel::NodeGather& gather) {
  const auto displacements = gather.gather(solver.kinematics().displacements);
  const auto& communicator = solver.distribution().communicator();
  const std::string verdict =
      communicator.broadcast(gather.root() ? unhealthyStateMessage(model, solver, check, step, time, displacements)
                                           : std::string());
  if (!verdict.empty()) throw ExplicitInstability(verdict);
}

std::string ranksText(const parallel::Communicator& communicator) {
  return communicator.distributed() ? " x " + std::to_string(communicator.size()) + " MPI ranks" : std::string();
}

// The model's bonds: on many ranks, each counted on the rank owning its first node. Collective.
template <class Solver, class LocalModelT>
long long bondCount(const Solver& solver, const std::optional<LocalModelT>& local) {
  if (!local) return static_cast<long long>(solver.body().bonds.numBonds());
  return solver.distribution().communicator().sum(local->partitionRow().bonds);
}

// The bond carriers (alpha > 0): on many ranks, each counted on the rank that owns it. Collective.
template <class BodiesT, class LocalModelT>
long long bondCarrierCount(const parallel::Communicator& communicator, const BodiesT& bodies,
                           const std::optional<LocalModelT>& local) {
  if (!local) return static_cast<long long>(bodies.pdNodes.extent(0));
  long long owned = 0;
  for (std::size_t k = 0; k < bodies.pdNodes.extent(0); ++k) owned += local->domain.owned[bodies.pdNodes(k)];
  return communicator.sum(owned);
}

// The shell elements: on many ranks, each counted on the rank owning its first node. Collective.
template <class Solver, class LocalModelT>
long long elementCount(const parallel::Communicator& communicator, const Solver& solver,
                       const std::optional<LocalModelT>& local) {
  if (!local) return solver.numElements();
  const auto& domain = local->domain;
  long long owned = 0;
  for (const LocalIndex e : local->bodies.ccmElements) owned += domain.owned[domain.mesh.quads(e, 0)];
  return communicator.sum(owned);
}

template <class ExecutionSpaceT>
ExplicitRunSummary runExplicitOn(const ExecutionSpaceT& space, const model::Model& model, const RunOptions& runOptions,
                                 std::ostream& log) {
  using MemorySpace = typename ExecutionSpaceT::memory_space;
  const auto communicator = parallel::Communicator::world();
  requireRunnableModel(model);
  requireDistributableExplicitRun(model);
  using Clock = std::chrono::steady_clock;
  const auto& deck = model.deck;
  // Before the set-up: a directory another run holds is refused at once. The root writes.
  std::optional<RunDirectory> runDirectory;
  if (communicator.root()) runDirectory.emplace(model, runOptions, "explicit", log);
  const std::string directory = runDirectory ? runDirectory->path() : std::string();
  const auto otherRanksCheckpoint = readCheckpointOnOtherRanks(model, runOptions, "explicit", communicator);
  const auto& checkpoint = runDirectory ? runDirectory->checkpoint() : otherRanksCheckpoint;
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
                     coupling::couplingInputs(model), deck.zones.adaptive->strainFraction,
                     deck.zones.adaptive->margin);
  // A distributed run builds this rank's part only (solvers/local_model.hpp).
  std::optional<LocalModel<ExecutionSpaceT>> local;
  if (communicator.distributed()) local.emplace(makeLocalModel(space, model, communicator));
  const auto bodies = local ? local->bodies : adaptive ? adaptive->bodies() : coupling::makeCoupledBodies(space, model);
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
  options.overlapExchange = runOptions.exchangeOverlap.value_or(!ranksShareDevice(communicator, space));
  CentralDifferenceSolver<ExecutionSpaceT> solver(
      space, body, bodies.shellElements(), local ? local->actions : makeExternalActions<MemorySpace>(model), options,
      local ? local->distribution : parallel::NodeDistribution<MemorySpace>());
  const parallel::NodeGather gather(local ? &local->domain : nullptr, communicator, model.shell.mesh.numNodes());
  if (checkpoint) solver.restoreFrom(*checkpoint, gather);
  const long long deckSteps =
      settings.steps ? *settings.steps
                     : std::max(1LL, static_cast<long long>(std::ceil(*settings.endTime / solver.timeStep() - 1e-9)));
  const long long totalSteps = std::min(deckSteps, runOptions.maxSteps.value_or(deckSteps));
  const double setupSeconds = fencedSecondsSince(space, setupStart);
  if (local) printPartition(local->partitionRow(), solver.haloDoublesPerNode, communicator, log);
  const long long numBonds = bondCount(solver, local), numElements = elementCount(communicator, solver, local);
  log << "explicit: " << bondCarrierCount(communicator, bodies, local) << " PD nodes, " << numBonds
      << " bonds, " << numElements << " shell elements ("
      << (settings.shellElement == deck::ExplicitSettings::ShellElement::OnePoint ? "one-point" : "MITC4") << ") on "
      << ExecutionSpaceT::name() << ranksText(communicator) << "; dt = " << solver.timeStep() << " s (critical estimate "
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
        << deck.zones.adaptive->strainFraction << " x s_c = " << adaptive->threshold()
        << ", with the CCM elements within " << deck.zones.adaptive->margin << " m of it (checked every "
        << deck.zones.adaptive->checkEvery << " steps); " << model.numPdElements << " PD elements at the start\n";
  if (solver.timeStep() > solver.criticalTimeStep())
    log << "warning: solver.dt is " << solver.timeStep() / solver.criticalTimeStep()
        << " x the estimated critical step; the run is expected to go unstable\n";

  // The run's wall time starts with the first output, so total = setup + run.
  const auto runStart = Clock::now();
  auto outputStart = runStart;
  RunOutput<ExecutionSpaceT> output(model, directory, solver, historyColumns, checkpoint ? &*checkpoint : nullptr,
                                    gather);
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
    solver.saveTo(state, gather);
    if (communicator.root()) {
      output.saveTo(state);
      if (adaptive) putView(state, "adaptive.element-is-pd", adaptive->elementIsPd());
      state.putInteger("explicit-run.zone-switches", switches);
      writeRunCheckpoint(state, model, "explicit", directory);
    }
    // Every rank restarts its clock: the next checkpoint by the clock is due on all alike.
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
                          solver.time() + solver.timeStep(), gather);
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
            << solver.body().bonds.numBonds() << " bonds, " << solver.numElements() << " shell elements; critical step "
            << solver.criticalTimeStep() << " s (" << solver.lanczosProducts() << " force evaluations)\n";
      }
      adaptiveSeconds += fencedSecondsSince(space, checkStart);
    }
    // A stop request (SIGINT, SIGTERM) ends the run here, with this step written as the last;
    // on every rank at the same step.
    // A checkpoint by the wall clock, on every rank at the same step too.
    stoppedBy = stopRequestSignal();
    bool checkpointByClock = checkpointSchedule.dueByClock();
    agreeOnRanks(communicator, stoppedBy, checkpointByClock);
    const bool last = step == totalSteps || stoppedBy != 0;
    const bool historyOnSchedule = step % historyEvery == 0;
    const bool fieldsOnSchedule = fieldEvery > 0 && step % fieldEvery == 0;
    // A checkpoint on its schedule, where the run stops before the deck's end (to be
    // continued), and at the deck's end when the deck asks for checkpoints (to be extended).
    const bool checkpointDue = checkpointSchedule.dueByStep(step) || checkpointByClock ||
                               (last && (step < deckSteps || deck.output.checkpoints()));
    outputStart = Clock::now();
    if (last || historyOnSchedule || fieldsOnSchedule || checkpointDue) {
      const auto check = solver.checkState();
      requireHealthyState(model, solver, check, step, solver.time(), gather);
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
  if (runOptions.timePhases) {
    summary.phases.insert(summary.phases.end(), {{"forces", phase.forces},
                                                 {"integration", phase.integration},
                                                 {"monitor", phase.monitor}});
    if (communicator.distributed()) summary.phases.emplace_back("exchange", phase.exchange);
  }
  if (adaptive) summary.phases.emplace_back("adaptive-zone", adaptiveSeconds);
  summary.phases.emplace_back("output", outputSeconds);
  summary.phases.emplace_back("total", setupSeconds + summary.wallSeconds);
  if (communicator.root()) summary.timingsPath = writePhaseTimes(directory, summary.phases);

  const auto energy = solver.energies();
  const long long finalBonds = bondCount(solver, local);  // collective; an adaptive zone adds bonds
  if (!communicator.root()) return summary;
  std::ostringstream balance;
  balance.precision(3);
  balance << energy.balanceError();
  io::SummaryTable table("explicit run summary");
  table.add("backend", ExecutionSpaceT::name() + ranksText(communicator))
      .add("steps", std::to_string(summary.steps) +
                        (summary.steps < deckSteps ? " of " + std::to_string(deckSteps) : "") +
                        (stoppedBy != 0 ? std::string(" (stopped by ") + stopSignalName(stoppedBy) + ")" : ""))
      .add("time step", formatSeconds(summary.timeStep) + " (critical " + formatSeconds(summary.criticalTimeStep) + ")")
      .add("simulated time", formatSeconds(summary.endTime))
      .add("wall time", io::formatDuration(summary.wallSeconds) + " (" +
                            formatSeconds(summary.wallSeconds / double(std::max(1LL, summary.steps))) + " per step)");
  if (runOptions.timePhases) {
    table.add("  forces", formatSeconds(phase.forces))
        .add("  integration", formatSeconds(phase.integration))
        .add("  energy monitor", formatSeconds(phase.monitor));
    if (communicator.distributed()) table.add("  halo exchange", formatSeconds(phase.exchange) + " (rank 0)");
  }
  if (adaptive) table.add("  adaptive zone", formatSeconds(adaptiveSeconds));
  table.add("  output", formatSeconds(outputSeconds))
      .add("setup", formatSeconds(setupSeconds))
      .add("broken bonds", std::to_string(summary.brokenBonds) + " of " + std::to_string(finalBonds))
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

void requireDistributableExplicitRun(const model::Model& model) {
  const auto communicator = parallel::Communicator::world();
  if (!communicator.distributed()) return;
  const auto& deck = model.deck;
  const std::string ranks = " in a run on " + std::to_string(communicator.size()) + " ranks";
  if (deck.zones.adaptive)
    throw std::invalid_argument(deck.sourceName + ": zones.adaptive: an adaptive PD zone is not supported" + ranks +
                                " yet; run it on one rank, or set the PD zone in the deck");
}

ExplicitRunSummary runExplicit(const model::Model& model, const RunOptions& options, std::ostream& log) {
  if constexpr (!std::is_same_v<ExecutionSpace, HostExecutionSpace>)
    if (options.backend == Backend::Host) return runExplicitOn(HostExecutionSpace{}, model, options, log);
  return runExplicitOn(ExecutionSpace{}, model, options, log);
}

}  // namespace perishell::solvers
