#pragma once
// Explicit dynamics of a shell by central differences (model.md §6, paper eq. 44-53), as
// leapfrog: velocities live at half steps, displacements and forces at whole steps;
// rotations are finite and updated multiplicatively, q <- exp(dt omega) q (model.md §5).
// The forces come from PD bonds (pd/bond_forces.hpp, one thread per bond or node) and, in a
// mixed PD-CCM model, from shell elements (shell/shell_body.hpp, one thread per element),
// both on one state per mesh node; the nodal update below is one thread per node. All
// state stays on the device.
//
// The run watches itself every monitorEvery steps: the energy balance
//   kinetic + strain + fracture + damping = initial energy + work of loads and supports
// must hold (to the scheme's O(dt^2)).
//
// In a distributed run (parallel/node_distribution.hpp) the solver holds one rank's owned
// nodes and their halo: after every step the halo takes its owners' state, and every sum
// (energies, broken bonds, the critical step's Lanczos products) runs over owned nodes only,
// through parallel::reproducibleSum, so that it does not depend on the rank or thread count.
//
// A time step above the stability limit makes the highest mode grow by a factor of several
// per step; its energy then far exceeds the work done on the body, and the run stops with
// ExplicitInstability instead of producing garbage.
#include <perishell/core/fenced_seconds.hpp>
#include <perishell/core/tridiagonal.hpp>
#include <perishell/fracture/carry_broken_bonds.hpp>
#include <perishell/fracture/damage.hpp>
#include <perishell/io/checkpoint.hpp>
#include <perishell/parallel/gather_nodes.hpp>
#include <perishell/parallel/node_distribution.hpp>
#include <perishell/parallel/reproducible_sum.hpp>
#include <perishell/pd/bond_forces.hpp>
#include <perishell/solvers/explicit/external_actions.hpp>
#include <perishell/solvers/explicit/nodal_inertia.hpp>
#include <perishell/shell/shell_body.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace perishell::solvers {

class ExplicitInstability : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ExplicitOptions {
  double density = 0.0;    // rho [kg/m^3]
  double thickness = 0.0;  // t [m]
  double timeStep = 0.0;   // dt [s]; 0: safetyFactor x the estimated critical step
  double safetyFactor = 0.9;
  double damping = 0.0;    // mass-proportional coefficient c [1/s], force -c m v
  deck::ForceKernel forceKernel = deck::ForceKernel::NodeGather;
  long long monitorEvery = 100;
  // Unstable when kinetic + strain + dissipated energy exceeds (1 + this) times the energy
  // put in; a stable run stays within a few per cent.
  double energyGrowthLimit = 1.0;
  // Stop when the one-point shell elements' hourglass energy exceeds this fraction of the
  // strain energy (docs/explicit.md): the mesh then deforms in modes the element cannot see.
  double hourglassEnergyLimit = 0.1;
  // Fence after each phase of a step and add its wall time to phaseSeconds() (the paper's
  // Table 3 columns). Costs a synchronisation per phase, so it is off for plain runs.
  bool timePhases = false;
  // A distributed step's forces around its halo exchange: the interior while the messages
  // travel, the rest after (docs/parallel.md, "Overlap"). Off, every force waits for the
  // exchange, which the step then finishes at once: for ranks that share a GPU, whose
  // contexts take turns on it, so that nothing overlaps and the split only adds launches.
  bool overlapExchange = true;
};

// Wall time of the phases of the steps taken so far [s], with ExplicitOptions::timePhases.
struct ExplicitPhaseSeconds {
  double forces = 0.0;       // bond and element forces (stress update)
  double integration = 0.0;  // the leapfrog update of every node, supports and loads
  double monitor = 0.0;      // the energy balance check every monitorEvery steps
  double exchange = 0.0;     // the halo exchange of a distributed run
};

// Energies at one step [J]; the balance error is
// (kinetic + strain + fracture + damping - input) / max(input, that sum).
struct EnergyReport {
  long long step = 0;
  double time = 0.0;
  double kinetic = 0.0, strain = 0.0, fracture = 0.0, damping = 0.0;
  double hourglass = 0.0;  // the one-point shell elements' hourglass energy, a part of strain
  double externalWork = 0.0, supportWork = 0.0, initial = 0.0;
  double input() const { return initial + externalWork + supportWork; }
  double stored() const { return kinetic + strain + fracture + damping; }
  double balanceError() const {
    const double scale = std::max(std::abs(input()), stored());
    return scale > 0.0 ? (stored() - input()) / scale : 0.0;
  }
};

template <class ExecutionSpaceT>
class CentralDifferenceSolver {
 public:
  using MemorySpace = typename ExecutionSpaceT::memory_space;
  using NodeList = Kokkos::View<const LocalIndex*, MemorySpace>;
  static_assert(is_execution_space_v<ExecutionSpaceT>);

  CentralDifferenceSolver(const ExecutionSpaceT& space, pd::PdBody<MemorySpace> body,
                          ExternalActions<MemorySpace> actions, const ExplicitOptions& options)
      : CentralDifferenceSolver(space, std::move(body), std::nullopt, std::move(actions), options) {}

  // A mixed model: the PD body indexed by mesh node (pd::indexByMeshNodes; it may have no
  // bonds) and the shell elements (coupling/make_coupled_model.hpp builds both). In a
  // distributed run, the bodies and actions of this rank's nodes and their distribution.
  CentralDifferenceSolver(const ExecutionSpaceT& space, pd::PdBody<MemorySpace> body,
                          std::optional<shell::ShellBody<MemorySpace>> shellBody, ExternalActions<MemorySpace> actions,
                          const ExplicitOptions& options,
                          parallel::NodeDistribution<MemorySpace> distribution = {})
      : space_(space),
        distribution_(std::move(distribution)),
        body_(std::move(body)),
        shell_(std::move(shellBody)),
        actions_(std::move(actions)),
        options_(options),
        state_(body_.numNodes()),
        velocities_("pd velocities", body_.numNodes()),
        forces_("pd forces", body_.numNodes()),
        intact_(pd::makeIntactFlags(body_.bonds, "intact bonds")),
        intactNext_(pd::makeIntactFlags(body_.bonds, "intact bonds next")),
        strainEnergy_("pd strain energy", body_.numNodes()),
        hourglassEnergy_("shell hourglass energy", body_.numNodes()),
        fractureEnergy_("pd fracture energy", body_.numNodes()),
        externalWork_("pd external work", body_.numNodes()),
        supportWork_("pd support work", body_.numNodes()),
        dampingWork_("pd damping work", body_.numNodes()),
        kineticEnergy_("pd kinetic energy", body_.numNodes()) {
    validate();
    stepWork_ = stepWorkOf(body_, shell_);
    inertia_ = computeNodalInertia(space_, body_, shell_, options_.density, options_.thickness);
    assembly::weighInertiaByShare(space_, actions_.mirrorImages, inertia_.mass, inertia_.rotaryInertia);
    applyInitialSupportValues();
    // A halo image whose master lives on another rank takes the owner's initial value.
    distribution_.exchange(space_, state_.displacements, state_.rotations);
    criticalTimeStep_ = estimateCriticalTimeStep();
    timeStep_ = options_.timeStep > 0.0 ? options_.timeStep : options_.safetyFactor * criticalTimeStep_;
  }

  // Sets initial velocities (nodes x 6: translational [m/s] and angular [rad/s]) before the first step.
  void setInitialVelocities(const pd::NodalVectorView<MemorySpace>& velocities) {
    if (step_ != 0) throw std::logic_error("initial velocities must be set before the first step");
    Kokkos::deep_copy(space_, velocities_, velocities);
  }

  // Advances one step; every monitorEvery steps (and on the first) checks the energy
  // balance and throws ExplicitInstability on non-finite or runaway energy. On many ranks the
  // step ends with the halo exchange started, and the next step's interior forces run while
  // its messages travel (docs/parallel.md, "Overlap"): between steps the owned rows are
  // current, the halo rows once finishHaloExchange() has run (energies() runs it).
  void step() {
    const bool monitor = step_ % options_.monitorEvery == 0;
    auto phaseStart = std::chrono::steady_clock::now();
    const pd::BondForceOutputs<MemorySpace> outputs = stepOutputs(monitor);
    addInteriorForces(state_, outputs);
    timePhase(phaseSeconds_.forces, phaseStart);
    finishHaloExchange();
    timePhase(phaseSeconds_.exchange, phaseStart);
    addBoundaryForces(state_, outputs);
    timePhase(phaseSeconds_.forces, phaseStart);
    std::swap(intact_, intactNext_);
    advance(monitor);
    timePhase(phaseSeconds_.integration, phaseStart);
    startHaloExchange();
    if (!options_.overlapExchange) finishHaloExchange();
    timePhase(phaseSeconds_.exchange, phaseStart);
    if (monitor) {
      checkEnergy();
      timePhase(phaseSeconds_.monitor, phaseStart);
    }
    ++step_;
    time_ += timeStep_;
  }

  // The energies between steps (one extra force evaluation into scratch outputs, so no
  // state changes and no bond is counted as breaking twice); kinetic from v_{n-1/2}.
  EnergyReport energies() {
    zeroForces();
    Kokkos::deep_copy(space_, strainEnergy_, 0.0);
    Kokkos::deep_copy(space_, hourglassEnergy_, 0.0);
    if (discardedFracture_.extent(0) == 0) {
      discardedFracture_ = VectorView<MemorySpace>("pd fracture energy scratch", body_.numNodes());
      discardedFlags_ = pd::BondFlagView<MemorySpace>("intact bonds scratch", body_.bonds.numBonds());
    }
    const pd::BondForceOutputs<MemorySpace> outputs{forces_, strainEnergy_, discardedFracture_, discardedFlags_};
    addInteriorForces(state_, outputs);
    finishHaloExchange();
    addBoundaryForces(state_, outputs);
    return reduceEnergies(kineticAtHalfSteps());
  }

  // The monitor's test (step()) made now, between steps, on energies(): finite state and
  // energies, and no stored energy beyond (1 + energyGrowthLimit) x the work done on the body.
  // The run driver calls it before every write and after the last step, so that a blow-up
  // between two monitor steps is never written out as a result.
  struct StateCheck {
    EnergyReport energy;
    bool finite = true;
    bool runaway = false;
    bool healthy() const { return finite && !runaway; }
  };
  StateCheck checkState() {
    StateCheck check;
    check.energy = energies();
    check.finite = !nonFinite_;
    check.runaway = step_ > 0 && check.energy.stored() > 0.0 &&
                    check.energy.stored() > (1.0 + options_.energyGrowthLimit) * std::abs(check.energy.input());
    return check;
  }

  // Switches to new bodies over the same mesh nodes (the adaptive PD zone,
  // coupling/adaptive_zone.hpp). Displacements, rotations, velocities and the energy
  // accumulators carry over; a bond of the new list between two nodes whose old bond was
  // broken stays broken (fracture/carry_broken_bonds.hpp). The stiffness and the rotary
  // inertia change under the current state, and with them the strain and kinetic energy:
  // that jump is booked as input, so the energy balance stays closed. A time step taken
  // from the estimate is lowered to safetyFactor x the new estimate when needed; a fixed one
  // above the new critical step throws ExplicitInstability.
  //
  // changedNodes (per node, 1 where the bodies changed) confines the work to the change: the
  // patch is those nodes and their bond and element neighbours in the old and the new bodies,
  // whose rows of K, inertia and energies changed with them; outside it nothing does. So the
  // new estimate runs on the patch (estimateCriticalTimeStep), the nodal inertia is
  // recomputed there, and the energy jump is the patch's. The critical step is the lower of
  // the old one and the local estimate, so it never rises.
  void replaceBodies(pd::PdBody<MemorySpace> body, std::optional<shell::ShellBody<MemorySpace>> shellBody,
                     const Kokkos::View<const std::uint8_t*, MemorySpace>& changedNodes) {
    requireSingleRank("an adaptive PD zone");
    Kokkos::View<std::uint8_t*, MemorySpace> patchNodes("changed nodes and neighbours", body_.numNodes());
    addNeighbours(changedNodes, body_.bonds, shell_, patchNodes);
    addNeighbours(changedNodes, body.bonds, shellBody, patchNodes);
    const double before = patchEnergy(patchOf(patchNodes), intact_);
    intact_ = fracture::carryBrokenBonds(space_, body_.bonds, intact_, body.bonds);
    intactNext_ = pd::makeIntactFlags(body.bonds, "intact bonds next");
    Kokkos::deep_copy(space_, intactNext_, intact_);
    body_ = std::move(body);
    shell_ = std::move(shellBody);
    discardedFracture_ = VectorView<MemorySpace>();
    discardedFlags_ = pd::BondFlagView<MemorySpace>();
    validate();
    stepWork_ = stepWorkOf(body_, shell_);
    const Patch patch = patchOf(patchNodes);
    updateInertiaOn(patch);
    criticalTimeStep_ = std::min(criticalTimeStep_, estimateCriticalTimeStep(80, &patch));
    initialEnergy_ += patchEnergy(patch, intact_) - before;
    // A step chosen from the estimate follows it down; one the deck fixed must stay below it.
    if (options_.timeStep <= 0.0) timeStep_ = std::min(timeStep_, options_.safetyFactor * criticalTimeStep_);
    if (timeStep_ > criticalTimeStep_) {
      std::ostringstream message;
      message.precision(4);
      message << "explicit solver: after the PD zone grew at step " << step_ << " the critical step is "
              << criticalTimeStep_ << " s, below dt = " << timeStep_ << " s; lower solver.dt or leave it out";
      throw ExplicitInstability(message.str());
    }
  }

  // The state between two steps, for a checkpoint (io/checkpoint.hpp, entries "explicit.*"):
  // displacements, rotations, half-step velocities, the per-node energy accumulators (each in
  // mesh-node order), the broken bonds (mesh-node pairs), and time, step, dt, critical step and
  // initial energy. Everything else (forces, scratch, the monitor's strain and kinetic energy)
  // is recomputed before it is read. The entries are those of a single-rank run on any rank
  // count; the root holds them (parallel/gather_nodes.hpp). Collective.
  void saveTo(io::Checkpoint& checkpoint, const parallel::NodeGather& gather) const {
    parallel::putNodalView(checkpoint, "explicit.displacements", state_.displacements, gather);
    parallel::putNodalView(checkpoint, "explicit.rotations", state_.rotations, gather);
    parallel::putNodalView(checkpoint, "explicit.velocities", velocities_, gather);
    parallel::putNodalView(checkpoint, "explicit.fracture-energy", fractureEnergy_, gather);
    parallel::putNodalView(checkpoint, "explicit.external-work", externalWork_, gather);
    parallel::putNodalView(checkpoint, "explicit.support-work", supportWork_, gather);
    parallel::putNodalView(checkpoint, "explicit.damping-work", dampingWork_, gather);
    checkpoint.putIntegers("explicit.broken-bonds", brokenBondPairs(gather));
    checkpoint.putReals("explicit.clock", {time_, timeStep_, criticalTimeStep_, initialEnergy_});
    checkpoint.putInteger("explicit.step", step_);
  }

  // Continues from saveTo's state: a solver over the same model (with an adaptive zone, the
  // bodies of the zone the checkpoint recorded), on this or any other rank count, then steps on
  // bit for bit as the saved one would have. Every rank reads the checkpoint; a halo node takes
  // its owner's state. Throws io::CheckpointError when the checkpoint is not of this model.
  // Collective.
  void restoreFrom(const io::Checkpoint& checkpoint, const parallel::NodeGather& gather) {
    const std::string mismatch = "the deck's model is not the one the checkpoint's run solved (another mesh, zones or "
                                 "horizon)";
    finishHaloExchange();  // so that no exchange of the old state lands on the restored one
    parallel::takeNodalView(checkpoint, "explicit.displacements", state_.displacements, gather, mismatch);
    parallel::takeNodalView(checkpoint, "explicit.rotations", state_.rotations, gather, mismatch);
    parallel::takeNodalView(checkpoint, "explicit.velocities", velocities_, gather, mismatch);
    parallel::takeNodalView(checkpoint, "explicit.fracture-energy", fractureEnergy_, gather, mismatch);
    parallel::takeNodalView(checkpoint, "explicit.external-work", externalWork_, gather, mismatch);
    parallel::takeNodalView(checkpoint, "explicit.support-work", supportWork_, gather, mismatch);
    parallel::takeNodalView(checkpoint, "explicit.damping-work", dampingWork_, gather, mismatch);
    restoreBrokenBonds(checkpoint, gather, mismatch);
    const auto& clock = checkpoint.reals("explicit.clock");
    if (clock.size() != 4) throw io::CheckpointError(checkpoint.context() + "'explicit.clock' holds " +
                                                     std::to_string(clock.size()) + " values, not 4");
    time_ = clock[0];
    timeStep_ = clock[1];
    criticalTimeStep_ = clock[2];
    initialEnergy_ = clock[3];
    step_ = checkpoint.integer("explicit.step");
    nonFinite_ = false;
  }

  long long stepIndex() const { return step_; }
  double time() const { return time_; }
  double timeStep() const { return timeStep_; }
  double criticalTimeStep() const { return criticalTimeStep_; }
  // Force evaluations the last critical-step estimate took.
  int lanczosProducts() const { return lanczosProducts_; }
  const EnergyReport& lastEnergyReport() const { return lastReport_; }
  const ExplicitPhaseSeconds& phaseSeconds() const { return phaseSeconds_; }
  const pd::PdBody<MemorySpace>& body() const { return body_; }
  LocalIndex numElements() const { return shell_ ? shell_->numElements() : 0; }
  const pd::PdKinematics<MemorySpace>& kinematics() const { return state_; }
  const pd::NodalVectorView<MemorySpace>& velocities() const { return velocities_; }
  const pd::NodalVectorView<MemorySpace>& forces() const { return forces_; }
  const pd::BondFlagView<MemorySpace>& intactBonds() const { return intact_; }

  const parallel::NodeDistribution<MemorySpace>& distribution() const { return distribution_; }
  // What a step's halo exchange sends per node: displacement, rotation and velocity.
  static constexpr int haloDoublesPerNode = 3 + 4 + 6;
  // Completes the exchange the last step started, if any: the halo rows take their owners'
  // state. Collective.
  void finishHaloExchange() {
    distribution_.finishExchange(space_, state_.displacements, state_.rotations, velocities_);
  }

  // Over every rank: a bond counts on the rank that owns its first node.
  long long brokenBonds() const {
    if (!distribution_.distributed()) return fracture::countBrokenBonds(space_, intact_);
    const auto owned = distribution_.owned();
    const auto halfBonds = body_.bonds.halfBonds;
    const auto intact = intact_;
    long long broken = 0;
    Kokkos::parallel_reduce(
        "perishell::solvers::CentralDifferenceSolver::brokenOwnedBonds",
        Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, intact.extent(0)),
        KOKKOS_LAMBDA(const std::size_t b, long long& sum) { sum += !intact(b) && owned(halfBonds(b, 0)) ? 1 : 0; },
        broken);
    return distribution_.communicator().sum(broken);
  }
  // The broken bonds as mesh-node pairs (i < j), ascending, on the root: one list for any rank
  // count, each bond sent by the rank owning its first node. Collective; checkpoints only.
  std::vector<long long> brokenBondPairs(const parallel::NodeGather& gather) const {
    const auto intact = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, intact_);
    const auto halfBonds = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, body_.bonds.halfBonds);
    const auto owned = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, distribution_.owned());
    const bool everyNodeOwned = owned.extent(0) == 0;
    std::vector<long long> mine;
    for (std::size_t b = 0; b < intact.extent(0); ++b)
      if (!intact(b) && (everyNodeOwned || owned(halfBonds(b, 0)))) {
        mine.push_back(gather.meshNode(halfBonds(b, 0)));
        mine.push_back(gather.meshNode(halfBonds(b, 1)));
      }
    const auto all = distribution_.communicator().gather(mine);
    std::vector<std::pair<long long, long long>> pairs;
    for (std::size_t k = 0; k + 1 < all.size(); k += 2)
      pairs.emplace_back(std::min(all[k], all[k + 1]), std::max(all[k], all[k + 1]));
    std::sort(pairs.begin(), pairs.end());
    std::vector<long long> sorted;
    for (const auto& [i, j] : pairs) sorted.insert(sorted.end(), {i, j});
    return sorted;
  }

  // Every local bond intact unless the checkpoint lists its nodes; every listed bond must be
  // one of this model's (counted over the ranks, each on the owner of its first node).
  void restoreBrokenBonds(const io::Checkpoint& checkpoint, const parallel::NodeGather& gather,
                          const std::string& mismatch) {
    const auto& listed = checkpoint.integers("explicit.broken-bonds");
    if (listed.size() % 2 != 0)
      throw io::CheckpointError(checkpoint.context() + "'explicit.broken-bonds' does not hold node pairs");
    std::vector<std::pair<long long, long long>> broken;
    for (std::size_t k = 0; k < listed.size(); k += 2) broken.emplace_back(listed[k], listed[k + 1]);
    std::sort(broken.begin(), broken.end());
    const auto halfBonds = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, body_.bonds.halfBonds);
    const auto owned = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, distribution_.owned());
    auto intact = Kokkos::create_mirror_view(Kokkos::HostSpace{}, intact_);
    long long found = 0;
    for (std::size_t b = 0; b < intact.extent(0); ++b) {
      const long long i = gather.meshNode(halfBonds(b, 0)), j = gather.meshNode(halfBonds(b, 1));
      const bool isBroken =
          std::binary_search(broken.begin(), broken.end(), std::make_pair(std::min(i, j), std::max(i, j)));
      intact(b) = isBroken ? 0 : 1;
      if (isBroken && (owned.extent(0) == 0 || owned(halfBonds(b, 0)))) ++found;
    }
    found = distribution_.communicator().sum(found);
    if (found != static_cast<long long>(broken.size()))
      throw io::CheckpointError(checkpoint.context() + "'explicit.broken-bonds' lists " +
                                std::to_string(broken.size()) + " broken bonds, of which this model has " +
                                std::to_string(found) + ": " + mismatch);
    Kokkos::deep_copy(intact_, intact);
    Kokkos::deep_copy(space_, intactNext_, intact_);
  }

  void computeDamage(const VectorView<MemorySpace>& damage) const {
    fracture::computeDamage(space_, body_, intact_, damage);
  }

 // The steps below launch kernels. They are public only because nvcc rejects extended
 // lambdas in private or protected member functions; callers use the interface above.
  void validate() const {
    if (!(options_.density > 0.0)) throw std::invalid_argument("explicit solver: density must be > 0");
    if (!(options_.thickness > 0.0)) throw std::invalid_argument("explicit solver: thickness must be > 0");
    if (options_.monitorEvery < 1) throw std::invalid_argument("explicit solver: monitorEvery must be >= 1");
    if (actions_.numPatterns() > maxCurvesPerKind ||
        static_cast<int>(actions_.supportCurves.size()) > maxCurvesPerKind)
      throw std::invalid_argument("explicit solver: at most " + std::to_string(maxCurvesPerKind) +
                                  " distinct load curves and support curves each");
    if (body_.bonds.numBonds() == 0 && !shell_)
      throw std::invalid_argument("explicit solver: the model has neither PD bonds nor shell elements");
    double smallestVolume = 0.0;
    const auto volumes = body_.volumes;
    const auto owned = distribution_.owned();
    const bool everyNode = owned.extent(0) == 0;
    Kokkos::parallel_reduce(
        "perishell::solvers::CentralDifferenceSolver::smallestVolume",
        Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, body_.numNodes()),
        KOKKOS_LAMBDA(const LocalIndex node, double& smallest) {
          if ((everyNode || owned(node)) && !(volumes(node) >= smallest)) smallest = volumes(node);
        },
        Kokkos::Min<double>(smallestVolume));
    smallestVolume = distribution_.communicator().min(smallestVolume);
    if (!(smallestVolume > 0.0))
      throw std::invalid_argument("explicit solver: a node has zero (or non-finite) volume");
  }

  // Prescribed values hold from t = 0 on: u_0 = value x curve(0).
  void applyInitialSupportValues() {
    const CurveFactors factors = actions_.supportFactors(0.0);
    const auto constrained = actions_.constrainedDofs;
    const auto value = actions_.prescribedValue;
    const auto curveIndex = actions_.supportCurveIndex;
    const auto displacements = state_.displacements;
    const auto rotations = state_.rotations;
    Kokkos::parallel_for(
        "perishell::solvers::CentralDifferenceSolver::initialSupportValues",
        Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, body_.numNodes()), KOKKOS_LAMBDA(const LocalIndex node) {
          double initial[6];
          for (int d = 0; d < 6; ++d) {
            const int curve = curveIndex(node, d);
            const bool prescribed = (constrained(node) >> d) & 1;
            initial[d] = prescribed ? value(node, d) * (curve < 0 ? 1.0 : factors.values[curve]) : 0.0;
          }
          for (int k = 0; k < 3; ++k) displacements(node, k) = initial[k];
          double q[4] = {1.0, 0.0, 0.0, 0.0};
          rotation::rotateBySpatialIncrement(initial + 3, q);
          for (int k = 0; k < 4; ++k) rotations(node, k) = q[k];
        });
    assembly::imposeMirrorImages(space_, actions_.mirrorImages, displacements, rotations, actions_.prescribedAt(0.0, 1.0));
  }

  // forces_ zeroed for an evaluation that adds into them. The update leaves them zero
  // (advance), so a step launches no fill of its own (docs/explicit.md, "Around the forces").
  void zeroForces() {
    if (!forcesZero_) fillContiguous(space_, forces_, 0.0);
    forcesZero_ = false;
  }

  // A step's outputs, zeroed: forces, and the strain and hourglass energies on a monitor step.
  pd::BondForceOutputs<MemorySpace> stepOutputs(bool withStrainEnergy) {
    zeroForces();
    if (withStrainEnergy) {
      Kokkos::deep_copy(space_, strainEnergy_, 0.0);
      Kokkos::deep_copy(space_, hourglassEnergy_, 0.0);
    }
    return {forces_, withStrainEnergy ? strainEnergy_ : VectorView<MemorySpace>(), fractureEnergy_, intactNext_};
  }

  void startHaloExchange() { distribution_.startExchange(space_, state_.displacements, state_.rotations, velocities_); }

  // The forces bonds and elements exert on the nodes in `state`, added into outputs.forces;
  // their strain energy into outputs.strainEnergy unless it is empty, and then the
  // elements' hourglass energy into hourglassEnergy_. In two calls, with finishHaloExchange()
  // between them: first the work that reads no node the exchange writes (on one rank, all of
  // it), then the rest (stepWorkOf).
  void addInteriorForces(const pd::PdKinematics<MemorySpace>& state,
                         const pd::BondForceOutputs<MemorySpace>& outputs) {
    if (!distribution_.distributed()) {
      addModelForces(state, outputs);
      return;
    }
    if (body_.bonds.numBonds() > 0) {
      updateBondFrames(state);
      if (stepWork_.interiorBonds)
        pd::computeBondForces(space_, options_.forceKernel, *stepWork_.interiorBonds, state, intact_, outputs,
                              pd::NodeFrames::Current);
    }
    if (stepWork_.shell)
      shell::subtractSelectedShellForces(space_, *stepWork_.shell, ElementSelection::only(stepWork_.interiorElements),
                                         state, outputs.forces, outputs.strainEnergy, hourglassOutput(outputs));
  }
  void addBoundaryForces(const pd::PdKinematics<MemorySpace>& state,
                         const pd::BondForceOutputs<MemorySpace>& outputs) {
    if (!distribution_.distributed()) return;
    if (body_.bonds.numBonds() > 0) {
      // The frames are current but for the halo nodes an exchange in flight just wrote.
      if (options_.overlapExchange) pd::updateNodeFrames(space_, body_, state, distribution_.receivedNodes());
      if (stepWork_.boundaryBonds)
        pd::computeBondForces(space_, options_.forceKernel, *stepWork_.boundaryBonds, state, intact_, outputs,
                              pd::NodeFrames::Current);
    }
    if (stepWork_.shell) {
      shell::subtractSelectedShellForces(space_, *stepWork_.shell, ElementSelection::only(stepWork_.boundaryElements),
                                         state, outputs.forces, outputs.strainEnergy, hourglassOutput(outputs));
      shell::gatherShellForces(space_, *stepWork_.shell, outputs.forces, outputs.strainEnergy,
                               hourglassOutput(outputs));
    }
    assembly::condenseImageForces(space_, actions_.mirrorImages, outputs.forces);
  }
  // The frames the bonds read: those of the nodes with bonds (a mixed model's CCM nodes have
  // none).
  void updateBondFrames(const pd::PdKinematics<MemorySpace>& state) {
    if (stepWork_.bondedNodes.extent(0) > 0)
      pd::updateNodeFrames(space_, body_, state, stepWork_.bondedNodes);
    else
      pd::updateNodeFrames(space_, body_, state);
  }
  // One rank's forces: the bonds', then the shell elements'.
  void addModelForces(const pd::PdKinematics<MemorySpace>& state, const pd::BondForceOutputs<MemorySpace>& outputs) {
    if (body_.bonds.numBonds() > 0) {
      updateBondFrames(state);
      pd::computeBondForces(space_, options_.forceKernel, body_, state, intact_, outputs, pd::NodeFrames::Current);
    }
    if (shell_)
      shell::subtractShellForces(space_, *shell_, state, outputs.forces, outputs.strainEnergy, hourglassOutput(outputs));
    assembly::condenseImageForces(space_, actions_.mirrorImages, outputs.forces);
  }
  VectorView<MemorySpace> hourglassOutput(const pd::BondForceOutputs<MemorySpace>& outputs) const {
    return outputs.strainEnergy.extent(0) > 0 ? hourglassEnergy_ : VectorView<MemorySpace>();
  }

  // The same over given bodies (the local critical-step estimate's patch of this model's).
  void addInternalForces(const pd::PdBody<MemorySpace>& body, const std::optional<shell::ShellBody<MemorySpace>>& shell,
                         deck::ForceKernel kernel, const pd::PdKinematics<MemorySpace>& state,
                         const pd::BondForceOutputs<MemorySpace>& outputs) {
    if (body.bonds.numBonds() > 0) pd::computeBondForces(space_, kernel, body, state, intact_, outputs);
    const bool withEnergy = outputs.strainEnergy.extent(0) > 0;
    if (shell)
      shell::subtractShellForces(space_, *shell, state, outputs.forces, outputs.strainEnergy,
                                 withEnergy ? hourglassEnergy_ : VectorView<MemorySpace>());
    assembly::condenseImageForces(space_, actions_.mirrorImages, outputs.forces);
  }

  // The leapfrog update of one node's six DOFs; work and dissipation accumulate per node
  // (no reduction on the hot path) with the trapezoidal displacement dt (v_old + v_new)/2.
  void advance(bool monitor) {
    const bool firstStep = step_ == 0;
    const double dt = timeStep_;
    const double velocityStep = firstStep ? 0.5 * dt : dt;  // v_{1/2} = v_0 + dt/2 a_0
    const double damping = options_.damping;
    const CurveFactors loadFactors = actions_.loadFactors(time_);
    const CurveFactors supportNow = actions_.supportFactors(time_);
    const CurveFactors supportNext = actions_.supportFactors(time_ + dt);
    const int numPatterns = actions_.numPatterns();
    const auto loads = actions_.loadPatterns;
    const auto constrained = actions_.constrainedDofs;
    const auto value = actions_.prescribedValue;
    const auto curveIndex = actions_.supportCurveIndex;
    const auto mass = inertia_.mass, rotaryInertia = inertia_.rotaryInertia;
    const auto forces = forces_, velocities = velocities_;
    const auto displacements = state_.displacements;
    const auto rotations = state_.rotations;
    const auto externalWork = externalWork_, supportWork = supportWork_, dampingWork = dampingWork_;
    const auto kinetic = kineticEnergy_;
    Kokkos::parallel_for(
        "perishell::solvers::CentralDifferenceSolver::advance", queuedRangePolicy(space_, 0, body_.numNodes()),
        KOKKOS_LAMBDA(const LocalIndex node) {
          double external = 0.0, support = 0.0, dissipated = 0.0, kineticNode = 0.0;
          double newVelocity[6];
          for (int d = 0; d < 6; ++d) {
            const double inertiaD = d < 3 ? mass(node) : rotaryInertia(node);
            double loadD = 0.0;
            for (int p = 0; p < numPatterns; ++p) loadD += loadFactors.values[p] * loads(node, 6 * p + d);
            const double oldV = velocities(node, d);
            double newV;
            if ((constrained(node) >> d) & 1) {
              const int curve = curveIndex(node, d);
              const double change = curve < 0 ? 0.0 : supportNext.values[curve] - supportNow.values[curve];
              newV = value(node, d) * change / dt;
              const double reaction = inertiaD * (newV - oldV) / velocityStep - forces(node, d) - loadD;
              support += reaction * 0.5 * dt * (oldV + newV);
            } else {
              newV = oldV + velocityStep * ((forces(node, d) + loadD) / inertiaD - damping * oldV);
              dissipated += damping * inertiaD * oldV * 0.5 * dt * (oldV + newV);
            }
            external += loadD * 0.5 * dt * (oldV + newV);
            // Leapfrog's conserved kinetic energy at step n is m v_{n-1/2} v_{n+1/2} / 2.
            kineticNode += 0.5 * inertiaD * (firstStep ? oldV * oldV : oldV * newV);
            newVelocity[d] = newV;
          }
          for (int d = 0; d < 6; ++d) {
            velocities(node, d) = newVelocity[d];
            forces(node, d) = 0.0;  // for the next step's evaluation (zeroForces)
          }
          for (int k = 0; k < 3; ++k) displacements(node, k) += dt * newVelocity[k];
          const double spin[3] = {dt * newVelocity[3], dt * newVelocity[4], dt * newVelocity[5]};
          double q[4] = {rotations(node, 0), rotations(node, 1), rotations(node, 2), rotations(node, 3)};
          rotation::rotateBySpatialIncrement(spin, q);
          for (int k = 0; k < 4; ++k) rotations(node, k) = q[k];
          // Most nodes are free, unloaded and undamped: leaving their accumulators alone where
          // nothing is added saves a sixth of the update's memory traffic (docs/explicit.md).
          if (external != 0.0) externalWork(node) += external;
          if (support != 0.0) supportWork(node) += support;
          if (dissipated != 0.0) dampingWork(node) += dissipated;
          if (monitor) kinetic(node) = kineticNode;
        });
    forcesZero_ = true;
    assembly::imposeMirrorImages(space_, actions_.mirrorImages, displacements, rotations,
                                 actions_.prescribedAt(time_ + dt, 1.0));
  }

  // Kinetic energy from the stored half-step velocities alone (between steps).
  VectorView<MemorySpace> kineticAtHalfSteps() {
    const auto mass = inertia_.mass, rotaryInertia = inertia_.rotaryInertia;
    const auto velocities = velocities_;
    const auto kinetic = kineticEnergy_;
    Kokkos::parallel_for(
        "perishell::solvers::CentralDifferenceSolver::kineticAtHalfSteps",
        Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, body_.numNodes()), KOKKOS_LAMBDA(const LocalIndex node) {
          double sum = 0.0;
          for (int d = 0; d < 6; ++d)
            sum += 0.5 * (d < 3 ? mass(node) : rotaryInertia(node)) * velocities(node, d) * velocities(node, d);
          kinetic(node) = sum;
        });
    return kinetic;
  }

  EnergyReport reduceEnergies(const VectorView<MemorySpace>& kinetic) {
    EnergyReport report;
    report.step = step_;
    report.time = time_;
    report.initial = initialEnergy_;
    const auto displacements = state_.displacements;
    int nonFinite = 0;
    const auto owned = distribution_.owned();
    const bool everyNode = owned.extent(0) == 0;
    Kokkos::parallel_reduce(
        "perishell::solvers::CentralDifferenceSolver::countNonFinite",
        Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, body_.numNodes()),
        KOKKOS_LAMBDA(const LocalIndex node, int& count) {
          if (everyNode || owned(node))
            for (int k = 0; k < 3; ++k) count += Kokkos::Experimental::isfinite(displacements(node, k)) ? 0 : 1;
        },
        nonFinite);
    nonFinite = distribution_.communicator().any(nonFinite > 0) ? 1 : 0;
    const double sums[7] = {sum(kinetic),      sum(strainEnergy_), sum(fractureEnergy_), sum(externalWork_),
                            sum(supportWork_), sum(dampingWork_),  sum(hourglassEnergy_)};
    report.kinetic = sums[0];
    report.strain = sums[1];
    report.fracture = sums[2];
    report.externalWork = sums[3];
    report.supportWork = sums[4];
    report.damping = sums[5];
    report.hourglass = sums[6];
    nonFinite_ = nonFinite > 0 || !std::isfinite(report.stored()) || !std::isfinite(report.input());
    return report;
  }

  void checkEnergy() {
    lastReport_ = reduceEnergies(kineticEnergy_);
    if (step_ == 0) {
      initialEnergy_ = lastReport_.stored();
      lastReport_.initial = initialEnergy_;
    }
    const bool runaway = lastReport_.stored() > (1.0 + options_.energyGrowthLimit) * std::abs(lastReport_.input()) &&
                         lastReport_.stored() > 0.0 && step_ > 0;
    if (!nonFinite_ && !runaway) {
      checkHourglassEnergy();
      return;
    }
    std::ostringstream message;
    message.precision(4);
    message << "explicit solver: unstable at step " << step_ << " (t = " << time_ << " s): ";
    if (nonFinite_)
      message << "the state is no longer finite";
    else
      message << "the stored energy " << lastReport_.stored() << " J exceeds the work done on the body "
              << lastReport_.input() << " J";
    message << "; dt = " << timeStep_ << " s against an estimated critical step of " << criticalTimeStep_
            << " s (ratio " << timeStep_ / criticalTimeStep_ << "). Reduce solver.dt or leave it out to use "
            << "safety-factor x the estimate.";
    throw ExplicitInstability(message.str());
  }

  // The hourglass share is judged once the strain energy is a visible part of the input
  // (early steps of an impact store little strain energy against much kinetic energy).
  void checkHourglassEnergy() const {
    const EnergyReport& e = lastReport_;
    if (!(e.hourglass > options_.hourglassEnergyLimit * e.strain) || !(e.strain > 1e-3 * std::abs(e.input()))) return;
    std::ostringstream message;
    message.precision(3);
    message << "explicit solver: at step " << step_ << " (t = " << time_ << " s) the shell elements' hourglass energy "
            << e.hourglass << " J is " << 100.0 * e.hourglass / e.strain << " % of the strain energy (limit "
            << 100.0 * options_.hourglassEnergyLimit
            << " %): the one-point elements deform in modes they cannot see. Refine the mesh where loads or "
               "supports act on single nodes, raise solver.hourglass, or set solver.shell-element: mitc4.";
    throw ExplicitInstability(message.str());
  }

  // Part of the model: its nodes (per node, 1 in it), the bond rows of those nodes and the
  // elements touching them, out of the current bodies. Each of its nodes has all its bonds
  // and elements there, in their order, so per-node sums over it (forces, strain energy,
  // nodal stiffness) are the whole model's to the bit; node-gather evaluates only the rows it
  // is given (bond-scatter would visit every bond).
  struct Patch {
    Kokkos::View<const std::uint8_t*, MemorySpace> nodes;
    pd::PdBody<MemorySpace> body;
    std::optional<shell::ShellBody<MemorySpace>> shell;
  };
  // dt_crit = 2 / omega_max, omega_max^2 the largest eigenvalue of A = M^-1/2 K M^-1/2 with K
  // the tangent of the bond and element forces at the reference state. Lanczos: each product
  // A q is a force evaluation at a tiny trial state q/sqrt(M) (amplitude 1e-7 of the horizon).
  // The largest eigenvalue of the Lanczos tridiagonal (a Ritz value) approaches omega_max^2 from
  // below, and never below the power iteration's Rayleigh quotient after as many products (its
  // Krylov space holds the power iterate). It stops when the Ritz value moves less than
  // settledRitzChange between products, at least after 10, at most after 80 (what the power
  // iteration used to take, always). The estimate needs no more: dt = safetyFactor x dt_crit
  // leaves omega_max^2 23 % of room at the default 0.9 (docs/explicit.md, "Critical step").
  //
  // A patch (patchOf; none: every node) confines the estimate to its nodes: after a local
  // change of the bodies the new top of the spectrum, if any, lies there. Lanczos then runs on
  // the patch's block of A (the support's DOFs, the rest held at zero), whose products
  // evaluate only the patch's bonds and elements. By Cauchy interlacing its top is at most the
  // whole model's: the estimate is local, not a bound, as the global one is from below too.
  // The 300 x 120 mm glass plate of perf/decks, shell-dominated, creeps up by 1e-4 per product
  // after 31 products, then 0.17 % more by the 80th; 1e-6 took all 80 there (1 s of its 5.8 s
  // on 2 threads).
  static constexpr double settledRitzChange = 1e-4;
  double estimateCriticalTimeStep(int maxProducts = 80, const Patch* patch = nullptr) {
    const Kokkos::View<const std::uint8_t*, MemorySpace> startSupport =
        patch ? patch->nodes : Kokkos::View<const std::uint8_t*, MemorySpace>();
    const LocalIndex numNodes = body_.numNodes();
    pd::NodalVectorView<MemorySpace> q("lanczos q", numNodes), previous("lanczos previous q", numNodes),
        product("lanczos A q", numNodes);
    TrialScratch scratch{pd::PdKinematics<MemorySpace>(numNodes),
                         VectorView<MemorySpace>("critical step fracture energy", numNodes),
                         pd::makeIntactFlags(body_.bonds, "critical step bonds"),
                         characteristicLength(),
                         body_,
                         shell_,
                         options_.forceKernel,
                         startSupport,
                         {}};
    if (patch) {
      scratch.body = patch->body;
      scratch.shell = patch->shell;
      scratch.kernel = deck::ForceKernel::NodeGather;
      scratch.nodes = productNodes(startSupport);
    }
    const auto constrained = actions_.constrainedDofs;
    const auto globalIds = distribution_.globalIds();
    const bool localIsGlobal = globalIds.extent(0) == 0;
    const bool everywhere = startSupport.extent(0) == 0;
    Kokkos::parallel_for(
        "perishell::solvers::CentralDifferenceSolver::lanczosStart",
        Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, numNodes), KOKKOS_LAMBDA(const LocalIndex node) {
          const long long meshNode = localIsGlobal ? node : globalIds(node);
          for (int d = 0; d < 6; ++d) {
            // A fixed pseudo-random start with components along every mode (by mesh node,
            // so that it is the same on any rank count).
            unsigned hash = 2654435761u * static_cast<unsigned>(6 * meshNode + d + 1);
            hash ^= hash >> 16;
            hash *= 2246822519u;
            hash ^= hash >> 13;
            q(node, d) = ((constrained(node) >> d) & 1) || !(everywhere || startSupport(node))
                             ? 0.0
                             : (hash % 2001u) / 1000.0 - 1.0;
          }
        });
    const auto& nodes = scratch.nodes;
    const double startNorm = std::sqrt(dot(q, q, nodes));
    if (!(startNorm > 0.0)) {
      if (!everywhere) return criticalTimeStep_;  // the change touched prescribed DOFs only
      throw std::invalid_argument("explicit solver: every DOF is prescribed");
    }
    scale(q, 1.0 / startNorm, nodes);
    std::vector<double> diagonal, offDiagonal;
    double beta = 0.0, ritz = 0.0;
    for (int k = 0; k < maxProducts; ++k) {
      applyScaledStiffness(q, product, scratch);
      const double alpha = dot(product, q, nodes);
      // product <- A q - alpha q - beta q_previous, the next Lanczos direction (unnormalised).
      subtractProjections(product, q, alpha, previous, beta, nodes);
      diagonal.push_back(alpha);
      const double last = ritz;
      ritz = largestTridiagonalEigenvalue(diagonal, offDiagonal);
      lanczosProducts_ = k + 1;
      if (k + 1 >= 10 && std::abs(ritz - last) <= settledRitzChange * ritz) break;
      beta = std::sqrt(dot(product, product, nodes));
      if (!(beta > 1e-14 * std::abs(ritz))) break;  // an invariant subspace: the spectrum's top is found
      offDiagonal.push_back(beta);
      std::swap(previous, q);
      std::swap(q, product);
      scale(q, 1.0 / beta, nodes);
    }
    if (!(ritz > 0.0) || !std::isfinite(ritz))
      throw std::runtime_error("explicit solver: the critical time step estimate failed (largest eigenvalue " +
                               std::to_string(ritz) + ")");
    return 2.0 / std::sqrt(ritz);
  }

  // The nodes marked in `nodes` and every node that shares a bond or an element with one.
  Kokkos::View<const std::uint8_t*, MemorySpace> withNeighbours(
      const Kokkos::View<const std::uint8_t*, MemorySpace>& nodes) const {
    Kokkos::View<std::uint8_t*, MemorySpace> grown("changed nodes and neighbours", nodes.extent(0));
    addNeighbours(nodes, body_.bonds, shell_, grown);
    return grown;
  }
  // Marks in `grown` the nodes marked in `nodes` and those sharing a bond of `bonds` or an
  // element of `shell` with one (leaves other marks as they are).
  void addNeighbours(const Kokkos::View<const std::uint8_t*, MemorySpace>& nodes, const pd::BondList<MemorySpace>& bonds,
                     const std::optional<shell::ShellBody<MemorySpace>>& shell,
                     const Kokkos::View<std::uint8_t*, MemorySpace>& grown) const {
    Kokkos::parallel_for(
        "perishell::solvers::CentralDifferenceSolver::bondNeighbours",
        Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, bonds.numNodes()), KOKKOS_LAMBDA(const LocalIndex node) {
          bool near = nodes(node) != 0;
          for (RowOffset entry = bonds.offsets(node); entry < bonds.offsets(node + 1) && !near; ++entry)
            near = nodes(bonds.neighbours(entry)) != 0;
          if (near) grown(node) = 1;
        });
    if (shell) {
      const auto quads = shell->quads;
      Kokkos::parallel_for(
          "perishell::solvers::CentralDifferenceSolver::elementNeighbours",
          Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, shell->numElements()), KOKKOS_LAMBDA(const LocalIndex e) {
            bool touches = false;
            for (int a = 0; a < 4; ++a) touches = touches || nodes(quads(e, a)) != 0;
            if (touches)
              for (int a = 0; a < 4; ++a) Kokkos::atomic_assign(&grown(quads(e, a)), std::uint8_t(1));
          });
    }
  }

  Patch patchOf(const Kokkos::View<const std::uint8_t*, MemorySpace>& nodes) const {
    Patch patch{nodes, body_, std::nullopt};
    patch.body.bonds = pd::restrictRows(space_, body_.bonds, nodes);
    if (shell_) patch.shell = shell::selectElements(space_, *shell_, nodes);
    return patch;
  }

  // The nodal inertia (solvers/explicit/nodal_inertia.hpp) of the patch's nodes, from their
  // bonds and elements; the other nodes keep theirs.
  void updateInertiaOn(const Patch& patch) {
    const auto fresh = computeNodalInertia(space_, patch.body, patch.shell, options_.density, options_.thickness);
    assembly::weighInertiaByShare(space_, actions_.mirrorImages, fresh.mass, fresh.rotaryInertia);
    const auto nodes = patch.nodes;
    const auto mass = inertia_.mass, rotaryInertia = inertia_.rotaryInertia;
    Kokkos::parallel_for(
        "perishell::solvers::CentralDifferenceSolver::updateInertiaOn",
        Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, nodes.extent(0)), KOKKOS_LAMBDA(const LocalIndex node) {
          if (!nodes(node)) return;
          mass(node) = fresh.mass(node);
          rotaryInertia(node) = fresh.rotaryInertia(node);
        });
  }

  // The strain and kinetic energy of the patch's nodes in the current state, with the given
  // bonds intact: the part of energies().stored() a change of bodies inside the patch can
  // change (fracture and damping are accumulated, not evaluated).
  double patchEnergy(const Patch& patch, const pd::BondFlagView<MemorySpace>& intact) {
    const LocalIndex numNodes = body_.numNodes();
    zeroForces();
    Kokkos::deep_copy(space_, strainEnergy_, 0.0);
    const pd::BondForceOutputs<MemorySpace> outputs{
        forces_, strainEnergy_, VectorView<MemorySpace>("patch fracture energy scratch", numNodes),
        pd::BondFlagView<MemorySpace>("patch bonds scratch", intact.extent(0))};
    if (patch.body.bonds.numBonds() > 0)
      pd::computeBondForces(space_, deck::ForceKernel::NodeGather, patch.body, state_, intact, outputs);
    if (patch.shell) shell::subtractShellForces(space_, *patch.shell, state_, forces_, strainEnergy_);
    const auto kinetic = kineticAtHalfSteps();
    const auto nodes = patch.nodes;
    const auto strain = strainEnergy_;
    return parallel::reproducibleSum(
        space_, numNodes, KOKKOS_LAMBDA(const std::size_t i)->double { return nodes(i) ? strain(i) + kinetic(i) : 0.0; },
        distribution_.communicator(), numNodes);
  }

  // What a trial force evaluation writes besides the forces (discarded), and what it
  // evaluates: the whole model, or a patch of it (support: its nodes; empty: every node).
  struct TrialScratch {
    pd::PdKinematics<MemorySpace> state;
    VectorView<MemorySpace> fracture;
    pd::BondFlagView<MemorySpace> intact;
    double length;  // characteristicLength(), the translations' scale
    pd::PdBody<MemorySpace> body;
    std::optional<shell::ShellBody<MemorySpace>> shell;
    deck::ForceKernel kernel;
    Kokkos::View<const std::uint8_t*, MemorySpace> support;
    // The nodes a product can make non-zero (productNodes); empty: every node.
    Kokkos::View<const LocalIndex*, MemorySpace> nodes;
  };

  // product = A v = M^-1/2 K M^-1/2 v at the prescribed DOFs' zero, from the forces at the trial
  // state u = eps M^-1/2 v, scaled so its largest translation is 1e-7 of the horizon (its
  // largest rotation 1e-7): product = -M^-1/2 f / eps.
  void applyScaledStiffness(const pd::NodalVectorView<MemorySpace>& v, const pd::NodalVectorView<MemorySpace>& product,
                            const TrialScratch& scratch) {
    const LocalIndex numNodes = body_.numNodes();
    distribution_.exchange(space_, v);
    const auto trial = scratch.state;
    const auto constrained = actions_.constrainedDofs;
    const auto mass = inertia_.mass, rotaryInertia = inertia_.rotaryInertia;
    const double amplitude = 1e-7;
    const double horizonLength = scratch.length;
    const auto owned = distribution_.owned();
    const bool everyOwned = owned.extent(0) == 0;
    // A local estimate's vectors and trial state change only on its product nodes.
    const NodeList nodes = scratch.nodes;
    const bool everyNode = nodes.extent(0) == 0;
    double largest = 0.0;
    Kokkos::parallel_reduce(
        "perishell::solvers::CentralDifferenceSolver::trialScale", overNodes(nodes),
        KOKKOS_LAMBDA(const LocalIndex k, double& maximum) {
          const LocalIndex node = everyNode ? k : nodes(k);
          if (!everyOwned && !owned(node)) return;
          for (int d = 0; d < 6; ++d) {
            const double physical = Kokkos::Experimental::fabs(v(node, d)) /
                                    Kokkos::Experimental::sqrt(d < 3 ? mass(node) : rotaryInertia(node)) /
                                    (d < 3 ? horizonLength : 1.0);
            if (physical > maximum) maximum = physical;
          }
        },
        Kokkos::Max<double>(largest));
    largest = distribution_.communicator().max(largest);
    if (!(largest > 0.0)) throw std::invalid_argument("explicit solver: every DOF is prescribed");
    const double epsilon = amplitude / largest;
    Kokkos::parallel_for(
        "perishell::solvers::CentralDifferenceSolver::trialState", overNodes(nodes),
        KOKKOS_LAMBDA(const LocalIndex i) {
          const LocalIndex node = everyNode ? i : nodes(i);
          for (int k = 0; k < 3; ++k)
            trial.displacements(node, k) = epsilon * v(node, k) / Kokkos::Experimental::sqrt(mass(node));
          const double spin[3] = {epsilon * v(node, 3) / Kokkos::Experimental::sqrt(rotaryInertia(node)),
                                  epsilon * v(node, 4) / Kokkos::Experimental::sqrt(rotaryInertia(node)),
                                  epsilon * v(node, 5) / Kokkos::Experimental::sqrt(rotaryInertia(node))};
          double quaternion[4] = {1.0, 0.0, 0.0, 0.0};
          rotation::rotateBySpatialIncrement(spin, quaternion);
          for (int k = 0; k < 4; ++k) trial.rotations(node, k) = quaternion[k];
        });
    assembly::imposeMirrorImages(space_, actions_.mirrorImages, trial.displacements, trial.rotations,
                                 assembly::NothingPrescribed{});
    if (everyNode) {
      fillContiguous(space_, product, 0.0);
    } else {
      Kokkos::parallel_for(
          "perishell::solvers::CentralDifferenceSolver::clearProduct", overNodes(nodes),
          KOKKOS_LAMBDA(const LocalIndex k) {
            for (int d = 0; d < 6; ++d) product(nodes(k), d) = 0.0;
          });
    }
    const pd::BondForceOutputs<MemorySpace> outputs{product, VectorView<MemorySpace>(), scratch.fracture, scratch.intact};
    addInternalForces(scratch.body, scratch.shell, scratch.kernel, trial, outputs);
    const auto support = scratch.support;
    const bool wholeModel = support.extent(0) == 0;
    Kokkos::parallel_for(
        "perishell::solvers::CentralDifferenceSolver::scaledProduct", overNodes(nodes),
        KOKKOS_LAMBDA(const LocalIndex k) {
          const LocalIndex node = everyNode ? k : nodes(k);
          for (int d = 0; d < 6; ++d)
            product(node, d) = ((constrained(node) >> d) & 1) || !(wholeModel || support(node))
                                   ? 0.0
                                   : -product(node, d) /
                                         (epsilon * Kokkos::Experimental::sqrt(d < 3 ? mass(node) : rotaryInertia(node)));
        });
  }

  // a <- a - alpha b - beta c.
  void subtractProjections(const pd::NodalVectorView<MemorySpace>& a, const pd::NodalVectorView<MemorySpace>& b,
                           double alpha, const pd::NodalVectorView<MemorySpace>& c, double beta,
                           const NodeList& nodes) const {
    const bool everyNode = nodes.extent(0) == 0;
    Kokkos::parallel_for(
        "perishell::solvers::CentralDifferenceSolver::lanczosProjections", overNodes(nodes),
        KOKKOS_LAMBDA(const LocalIndex k) {
          const LocalIndex node = everyNode ? k : nodes(k);
          for (int d = 0; d < 6; ++d) a(node, d) -= alpha * b(node, d) + beta * c(node, d);
        });
  }

  // a <- factor a.
  void scale(const pd::NodalVectorView<MemorySpace>& a, double factor, const NodeList& nodes) const {
    const bool everyNode = nodes.extent(0) == 0;
    Kokkos::parallel_for(
        "perishell::solvers::CentralDifferenceSolver::lanczosScale", overNodes(nodes),
        KOKKOS_LAMBDA(const LocalIndex k) {
          const LocalIndex node = everyNode ? k : nodes(k);
          for (int d = 0; d < 6; ++d) a(node, d) *= factor;
        });
  }

  // Over the owned nodes of every rank, independent of the order of addition.
  double sum(const VectorView<MemorySpace>& values) const {
    const auto owned = distribution_.owned();
    const bool everyNode = owned.extent(0) == 0;
    return parallel::reproducibleSum(
        space_, values.extent(0),
        KOKKOS_LAMBDA(const std::size_t i)->double { return everyNode || owned(i) ? values(i) : 0.0; },
        distribution_.communicator(), distribution_.meshNodes(values.extent(0)));
  }

  // Over `nodes` (empty: every node), where the vectors' non-zero rows are; the sum is
  // reproducible, so leaving out zero rows changes no bit.
  double dot(const pd::NodalVectorView<MemorySpace>& a, const pd::NodalVectorView<MemorySpace>& b,
             const NodeList& nodes) const {
    const auto owned = distribution_.owned();
    const bool everyOwned = owned.extent(0) == 0;
    const bool everyNode = nodes.extent(0) == 0;
    return parallel::reproducibleSum(
        space_, everyNode ? a.extent(0) : nodes.extent(0),
        KOKKOS_LAMBDA(const std::size_t k)->double {
          const std::size_t node = everyNode ? k : nodes(k);
          double partial = 0.0;
          if (everyOwned || owned(node))
            for (int d = 0; d < 6; ++d) partial += a(node, d) * b(node, d);
          return partial;
        },
        distribution_.communicator(), distribution_.meshNodes(a.extent(0)));
  }

  // k in [0, nodes' count), or every node where `nodes` is empty.
  Kokkos::RangePolicy<ExecutionSpaceT> overNodes(const NodeList& nodes) const {
    return Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, nodes.extent(0) > 0 ? nodes.extent(0) : body_.numNodes());
  }

  // The nodes a product over the patch `support` can make non-zero, ascending: the support's
  // rows (node-gather), the nodes of the elements touching it, which are its neighbours, and
  // the mirror images and their masters (condensed forces). Outside them every Lanczos
  // vector, the trial state's displacement and rotation stay zero and the identity.
  NodeList productNodes(const Kokkos::View<const std::uint8_t*, MemorySpace>& support) const {
    const Kokkos::View<std::uint8_t*, MemorySpace> in("lanczos product node mask", body_.numNodes());
    Kokkos::deep_copy(space_, in, withNeighbours(support));
    const auto images = actions_.mirrorImages.nodes, masters = actions_.mirrorImages.masters;
    Kokkos::parallel_for(
        "perishell::solvers::CentralDifferenceSolver::productNodesImages",
        Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, images.extent(0)), KOKKOS_LAMBDA(const std::size_t k) {
          Kokkos::atomic_assign(&in(images(k)), std::uint8_t(1));
          Kokkos::atomic_assign(&in(masters(k)), std::uint8_t(1));
        });
    const Kokkos::View<LocalIndex*, MemorySpace> nodes("lanczos product nodes", body_.numNodes());
    LocalIndex count = 0;
    Kokkos::parallel_scan(
        "perishell::solvers::CentralDifferenceSolver::productNodes",
        Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, body_.numNodes()),
        KOKKOS_LAMBDA(const LocalIndex node, LocalIndex& sum, const bool final) {
          if (!in(node)) return;
          if (final) nodes(sum) = node;
          ++sum;
        },
        count);
    return Kokkos::subview(nodes, std::make_pair(LocalIndex(0), count));
  }


  // The longest bond, or without bonds the side of the largest node area: the length trial
  // displacements are scaled by.
  double characteristicLength() const {
    double largestVolume = 0.0;
    const auto volumes = body_.volumes;
    Kokkos::parallel_reduce(
        "perishell::solvers::CentralDifferenceSolver::largestVolume",
        Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, volumes.extent(0)),
        KOKKOS_LAMBDA(const LocalIndex node, double& maximum) {
          if (volumes(node) > maximum) maximum = volumes(node);
        },
        Kokkos::Max<double>(largestVolume));
    // Over every local node: a halo node's volume (fewer elements than its owner sees) is at
    // most its owner's, so the maximum is the single-rank one.
    largestVolume = distribution_.communicator().max(largestVolume);
    return std::max(maxReferenceLength(), std::sqrt(largestVolume / options_.thickness));
  }

  double maxReferenceLength() const {
    double longest = 0.0;
    const auto lengths = body_.bonds.referenceLength;
    Kokkos::parallel_reduce(
        "perishell::solvers::CentralDifferenceSolver::longestBond",
        Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, lengths.extent(0)),
        KOKKOS_LAMBDA(const RowOffset b, double& maximum) {
          if (lengths(b) > maximum) maximum = lengths(b);
        },
        Kokkos::Max<double>(longest));
    return distribution_.communicator().max(longest);
  }

 private:
  void requireSingleRank(const char* what) const {
    if (distribution_.distributed())
      throw std::logic_error(std::string("explicit solver: ") + what + " is not supported in a distributed run");
  }

  // On many ranks, what a step evaluates: only what an owned node reads, since the exchange
  // overwrites the halo's state (docs/parallel.md, "Owned rows only"). Read are the owned
  // nodes' forces and those of mirror images whose master is owned (condensed onto it). So:
  // - the shell elements with a read node (shell::selectElements keeps the gather order);
  // - with node-gather, the bond rows of the read nodes and of the lower node of each of their
  //   bonds: that row alone writes the bond's broken flag (pd/bond_forces.hpp). Bond-scatter
  //   visits every bond anyway.
  // Each in two parts (docs/parallel.md, "Overlap"): the interior, bond rows and elements that
  // read no node the exchange writes, runs while the exchange is in flight; the boundary after
  // it. A node's bond row is whole in one part and the gather sums every element of a node
  // after both, so each node's sums are those of one rank, to the bit. Bond-scatter bonds all
  // wait for the exchange. On one rank the step evaluates the whole bodies, and only
  // bondedNodes is set.
  using ElementSelection = shell::ElementSelection<MemorySpace>;
  struct StepWork {
    // The nodes with bonds where some have none (a mixed model), else empty.
    Kokkos::View<const LocalIndex*, MemorySpace> bondedNodes;
    std::optional<pd::PdBody<MemorySpace>> interiorBonds, boundaryBonds;
    std::optional<shell::ShellBody<MemorySpace>> shell;
    Kokkos::View<LocalIndex*, MemorySpace> interiorElements, boundaryElements;  // into *shell
  };
  StepWork stepWorkOf(const pd::PdBody<MemorySpace>& body,
                      const std::optional<shell::ShellBody<MemorySpace>>& shell) const {
    StepWork work;
    if (body.bonds.numBonds() > 0) {
      const auto offsets = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, body.bonds.offsets);
      std::vector<LocalIndex> bonded;
      for (LocalIndex node = 0; node < body.numNodes(); ++node)
        if (offsets(node + 1) > offsets(node)) bonded.push_back(node);
      if (bonded.size() < static_cast<std::size_t>(body.numNodes()))
        work.bondedNodes = viewOf<MemorySpace>(bonded, "nodes with bonds");
    }
    if (!distribution_.distributed()) return work;
    const auto owned = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, distribution_.owned());
    const auto slots = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, distribution_.ownerSlots());
    const auto images = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, actions_.mirrorImages.nodes);
    const auto masters = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, actions_.mirrorImages.masters);
    const LocalIndex numNodes = body.numNodes();
    // Without overlap the exchange is finished before a step begins: nothing waits for it.
    const bool overlap = options_.overlapExchange;
    const auto received = [&slots, overlap](LocalIndex node) { return overlap && slots(node) > 0; };
    Kokkos::View<std::uint8_t*, Kokkos::HostSpace> read("nodes whose forces a step reads", numNodes);
    for (LocalIndex node = 0; node < numNodes; ++node) read(node) = owned(node);
    for (std::size_t k = 0; k < images.extent(0); ++k)
      if (owned(masters(k))) read(images(k)) = 1;
    if (shell) {
      const Kokkos::View<const std::uint8_t*, MemorySpace> readMask =
          Kokkos::create_mirror_view_and_copy(MemorySpace{}, read);
      work.shell = shell::selectElements(space_, *shell, readMask);
      const auto quads = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, work.shell->quads);
      std::vector<LocalIndex> interior, boundary;
      for (LocalIndex e = 0; e < work.shell->numElements(); ++e) {
        bool waits = false;
        for (int a = 0; a < 4; ++a) waits = waits || received(quads(e, a));
        (waits ? boundary : interior).push_back(e);
      }
      work.interiorElements = viewOf<MemorySpace>(interior, "interior shell elements");
      work.boundaryElements = viewOf<MemorySpace>(boundary, "boundary shell elements");
    }
    if (options_.forceKernel != deck::ForceKernel::NodeGather) {
      work.boundaryBonds = body;
      return work;
    }
    const auto offsets = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, body.bonds.offsets);
    const auto neighbours = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, body.bonds.neighbours);
    Kokkos::View<std::uint8_t*, Kokkos::HostSpace> evaluated("bond rows a step evaluates", numNodes);
    for (LocalIndex node = 0; node < numNodes; ++node) {
      if (!read(node)) continue;
      evaluated(node) = 1;
      for (RowOffset entry = offsets(node); entry < offsets(node + 1); ++entry)
        if (neighbours(entry) < node) evaluated(neighbours(entry)) = 1;
    }
    Kokkos::View<std::uint8_t*, Kokkos::HostSpace> interiorRows("interior bond rows", numNodes),
        boundaryRows("boundary bond rows", numNodes);
    for (LocalIndex node = 0; node < numNodes; ++node) {
      if (!evaluated(node)) continue;
      bool waits = received(node);
      for (RowOffset entry = offsets(node); entry < offsets(node + 1); ++entry)
        waits = waits || received(neighbours(entry));
      (waits ? boundaryRows : interiorRows)(node) = 1;
    }
    const auto restricted = [&](const Kokkos::View<std::uint8_t*, Kokkos::HostSpace>& rows) {
      std::optional<pd::PdBody<MemorySpace>> part;
      if (std::none_of(rows.data(), rows.data() + rows.extent(0), [](std::uint8_t row) { return row != 0; }))
        return part;  // no row: no launch
      part = body;
      part->bonds = pd::restrictRows(space_, body.bonds, Kokkos::View<const std::uint8_t*, MemorySpace>(
                                                             Kokkos::create_mirror_view_and_copy(MemorySpace{}, rows)));
      return part;
    };
    work.interiorBonds = restricted(interiorRows);
    work.boundaryBonds = restricted(boundaryRows);
    return work;
  }

  // With timePhases: fences, adds the time since `start` to `total` and restarts `start`.
  void timePhase(double& total, std::chrono::steady_clock::time_point& start) const {
    if (!options_.timePhases) return;
    total += fencedSecondsSince(space_, start);
    start = std::chrono::steady_clock::now();
  }

  ExecutionSpaceT space_;
  parallel::NodeDistribution<MemorySpace> distribution_;
  pd::PdBody<MemorySpace> body_;
  StepWork stepWork_;  // stepWorkOf(body_, shell_)
  std::optional<shell::ShellBody<MemorySpace>> shell_;
  ExternalActions<MemorySpace> actions_;
  ExplicitOptions options_;
  pd::PdKinematics<MemorySpace> state_;
  pd::NodalVectorView<MemorySpace> velocities_;
  pd::NodalVectorView<MemorySpace> forces_;
  pd::BondFlagView<MemorySpace> intact_, intactNext_;
  VectorView<MemorySpace> strainEnergy_, hourglassEnergy_, fractureEnergy_, externalWork_, supportWork_, dampingWork_, kineticEnergy_;
  // Outputs of energies() that must not touch the run's state; allocated on first use.
  VectorView<MemorySpace> discardedFracture_;
  pd::BondFlagView<MemorySpace> discardedFlags_;
  NodalInertia<MemorySpace> inertia_;
  double criticalTimeStep_ = 0.0;
  int lanczosProducts_ = 0;  // of the last critical-step estimate
  double timeStep_ = 0.0;
  double time_ = 0.0;
  long long step_ = 0;
  double initialEnergy_ = 0.0;
  bool nonFinite_ = false;
  bool forcesZero_ = true;  // every entry of forces_ is zero (zeroForces)
  EnergyReport lastReport_;
  ExplicitPhaseSeconds phaseSeconds_;
};

}  // namespace perishell::solvers
