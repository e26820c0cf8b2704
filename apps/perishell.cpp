// The perishell command-line app. Kokkos options (--kokkos-threads=N, --kokkos-device-id=N)
// pass through to Kokkos.
#include <perishell/cases/pressurised_membrane.hpp>
#include <perishell/core/runtime.hpp>
#include <perishell/core/stop_request.hpp>
#include <perishell/io/xdmf_writer.hpp>
#include <perishell/model/model.hpp>
#include <perishell/parallel/communicator.hpp>
#include <perishell/solvers/explicit/central_difference.hpp>
#include <perishell/solvers/explicit/explicit_run.hpp>
#include <perishell/solvers/history_columns.hpp>
#include <perishell/solvers/implicit/implicit_run.hpp>
#include <perishell/solvers/local_model.hpp>
#include <perishell/solvers/state_check.hpp>

#include <algorithm>
#ifdef KOKKOS_ENABLE_CUDA
#include <cuda_runtime_api.h>
#endif
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <map>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

// Set where the ranks of a distributed run work on their own parts: an error there may be one
// rank's alone, and the others would wait for it in a collective (main ends them all).
bool ranksMayDiverge = false;

constexpr const char* usage = R"(usage: perishell [--help] [--version] [--backend-info]
       perishell run DECK.yaml [--output DIR] [--backend device|host] [--max-steps N]
                               [--restart DIR] [--phase-times] [--exchange-overlap auto|on|off]
       perishell check DECK.yaml [--output DIR]
       perishell membrane [options]

Commands:
  run DECK        Run a case deck: build the model, run its solver on the build's default
                  device with progress lines (step, time, ETA), write DIR/results.xmf (+ .h5
                  per output step) and DIR/history.csv, and print a summary table.
                  DIR is output.directory of the deck unless --output DIR is given. Explicit
                  and implicit decks run CCM-only, 100 % PD or mixed models. Also writes
                  DIR/timings.csv (phase,seconds). Exit 1 with the reason on a bad deck, an
                  unstable explicit run or an increment Newton cannot converge. SIGINT
                  (Ctrl-C) or SIGTERM stops the run after its current step or increment,
                  written, with a checkpoint (DIR/checkpoint.h5) and its summary, and exit
                  status 130 or 143; a second one stops it at once. A run also writes a
                  checkpoint every output.checkpoint-every steps or minutes, when
                  --max-steps stops it, and at its end when the deck asks for checkpoints.
      --backend B     device (default): the build's default device (CUDA in a CUDA build);
                      host: its host space (OpenMP), the CPU baseline of the same kernels.
                      In an OpenMP build both are the same.
      --max-steps N   stop after N steps (explicit) or increments (implicit), keeping the
                      deck's load schedule: a truncated run follows the full one
      --restart DIR   continue the run whose output directory is DIR from its checkpoint,
                      writing on into DIR (what that run wrote after its checkpoint is
                      replaced): the continued run equals an uninterrupted one. The deck may
                      extend the run (more steps, a later end time).
      --phase-times   time the explicit step's phases (forces, integration, energy monitor)
                      with a synchronisation after each; implicit phases are always timed
      --exchange-overlap M
                      under mpirun, explicit: whether a step's forces run around its halo
                      exchange (on) or after it (off); auto (default): off where ranks of a
                      node share a GPU, which takes their kernels in turns, on elsewhere.
                      The results are the same either way (docs/parallel.md, "Overlap")
  check DECK      Validate a case deck (docs/deck.md), build its model — mesh, zones, PD
                  nodes and, on the device, the bonds — and print a model summary: nodes,
                  elements, PD ratio, bonds, DOF counts. Exit 1 with the deck key and the
                  reason when the deck is invalid. With --output DIR, also writes
                  DIR/model.xmf (+ .h5) for ParaView: the mesh with the node fields
                  pd-node (1 on PD nodes) and bonds (bonds per node). Under mpirun, also
                  the partition: owned and halo nodes, elements and bonds per rank.

Distributed runs (a build with PERISHELL_ENABLE_MPI, docs/parallel.md):
  mpirun -np N perishell run DECK   runs an explicit deck on N ranks (one per GPU in a
                  CUDA build), each holding its part of the model; the files and the
                  printed summary are those of a one-rank run, bit for bit.
  membrane        The stack-verification self-test: a square membrane with fixed edges
                  under uniform tension and pressure, assembled and solved on the build's
                  default device (atomic element assembly, Kokkos Kernels CRS matrix, Belos
                  PCG). Compares the centre deflection with the exact series solution.
                  (The quick start's default case is a deck: perishell run
                  apps/cases/default_crack_branching.yaml.)
      --cells N       quads per side, even (default 64)
      --side A        side length a [m] (default 1)
      --tension T     membrane tension T [N/m] (default 1000)
      --pressure P    pressure p [Pa] (default 100)
      --tolerance R   PCG relative residual tolerance (default 1e-10)
      --max-iterations K  PCG iteration limit (default 20000)
      --max-error E   exit 1 when the relative error exceeds E (default 0.01)

Options:
  --help          this text
  --version       the version
  --backend-info  the Kokkos configuration and the devices in use
  --kokkos-...    passed to Kokkos (e.g. --kokkos-threads=2, --kokkos-device-id=0)
)";

struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

double parseNumber(const std::string& option, const std::string& text) {
  std::size_t used = 0;
  double value = 0.0;
  try {
    value = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || !std::isfinite(value))
    throw UsageError("option " + option + ": '" + text + "' is not a finite number");
  return value;
}

int parseInteger(const std::string& option, const std::string& text) {
  const double value = parseNumber(option, text);
  if (value != std::floor(value) || std::abs(value) > 1e9)
    throw UsageError("option " + option + ": '" + text + "' is not an integer");
  return static_cast<int>(value);
}

std::string withThousands(long long value) {
  std::string digits = std::to_string(value < 0 ? -value : value);
  for (int at = static_cast<int>(digits.size()) - 3; at > 0; at -= 3) digits.insert(at, ",");
  return (value < 0 ? "-" : "") + digits;
}

// Elements first..last of the mesh by kind: "8 quads", "7 quads and 2 triangles", "200 triangles".
std::string elementCounts(const perishell::mesh::HostQuadMesh& mesh, perishell::LocalIndex first,
                          perishell::LocalIndex last) {
  long long triangles = 0;
  for (perishell::LocalIndex e = first; e < last; ++e) triangles += perishell::mesh::isTriangle(mesh.quads, e);
  const long long quads = last - first - triangles;
  if (triangles == 0) return withThousands(quads) + " quads";
  if (quads == 0) return withThousands(triangles) + " triangles";
  return withThousands(quads) + " quads and " + withThousands(triangles) + " triangles";
}

const char* generatorName(perishell::deck::MeshGenerator generator) {
  switch (generator) {
    case perishell::deck::MeshGenerator::Plate: return "plate";
    case perishell::deck::MeshGenerator::Cylinder: return "cylinder";
    case perishell::deck::MeshGenerator::HexagonalPrism: return "hexagonal prism";
    case perishell::deck::MeshGenerator::Gmsh: return "gmsh file";
  }
  return "?";
}

// The model as ParaView shows it: PD nodes and bonds per node (pre-cracks show as a band
// of nodes with fewer bonds), the support layer included.
template <class BondListT>
std::string writeModelOutput(const std::string& directory, const perishell::model::Model& model,
                             const BondListT& bonds) {
  std::filesystem::create_directories(directory);
  const auto& mesh = model.shell.mesh;
  Kokkos::View<int*, Kokkos::HostSpace> pdNode("pd-node", mesh.numNodes());
  Kokkos::View<int*, Kokkos::HostSpace> bondCount("bonds", mesh.numNodes());
  const auto offsets = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, bonds.offsets);
  for (std::size_t k = 0; k < model.pdNodes.extent(0); ++k) {
    pdNode(model.pdNodes(k)) = 1;
    bondCount(model.pdNodes(k)) = static_cast<int>(offsets(k + 1) - offsets(k));
  }
  perishell::io::XdmfTimeSeriesWriter writer(directory, "model", mesh);
  writer.writeStep(0.0, {perishell::io::makeScalarField("pd-node", pdNode),
                         perishell::io::makeScalarField("bonds", bondCount)});
  return writer.xdmfPath();
}

// Supports on PD nodes that got no layer (symmetry, simply supported and other partial
// supports; every support when the layer is off): PD is soft next to them, as the bonds
// beyond the edge are missing (docs/verification.md: 5 % on the Scordelis-Lo quarter roof).
void printUnlayeredPdSupports(const perishell::model::Model& model) {
  std::vector<std::uint8_t> isPd(model.shell.mesh.numNodes(), 0);
  for (std::size_t k = 0; k < model.pdNodes.extent(0); ++k) isPd[model.pdNodes(k)] = 1;
  std::map<std::string, std::string> supportsOfSet;
  for (const auto& support : model.deck.supports) {
    const auto& layer = model.supportLayer;
    const auto& skipped = layer.skippedSets;
    if (layer.nodesOfSet.count(support.set) || layer.mirroredNodesOfSet.count(support.set) ||
        std::find(skipped.begin(), skipped.end(), support.set) != skipped.end())
      continue;
    const auto nodes = model.supportNodes(support);
    if (std::count_if(nodes.begin(), nodes.end(), [&](perishell::LocalIndex node) { return isPd[node]; }) < 2) continue;
    auto& names = supportsOfSet[support.set];
    names += (names.empty() ? "" : ", ") + support.name;
  }
  for (const auto& [set, names] : supportsOfSet)
    std::printf("  %-10s no support layer beyond set '%s' (supports %s): %s, so PD nodes next to it miss the bonds "
                "beyond the edge and PD is soft there by a few per cent (docs/verification.md); model the whole "
                "shell, or make the region along it CCM\n",
                "layer", set.c_str(), names.c_str(),
                model.deck.peridynamics.supportLayer
                    ? "its DOFs make no mirror image (a layer needs a clamp, a symmetry or antisymmetry plane, a "
                      "diaphragm or a hinge held at zero, docs/model-setup.md; an edge holding w alone keeps the "
                      "free edge's weights, which already leave its moment zero)"
                    : "peridynamics.support-layer is off");
}

// docs/model-setup.md, "Slits" and "Supports on PD regions".
void printMeshNotes(const perishell::model::Model& model) {
  if (model.numCoincidentPairs > 0) {
    const auto [first, second] = model.firstCoincidentPair;
    const auto& x = model.shell.mesh.coordinates;
    std::printf("  %-10s %s pair(s) of distinct nodes at one point, e.g. nodes %d and %d at (%g, %g, %g): the mesh "
                "does not connect them (a slit, or a seam left unmerged), so neither elements nor bonds do\n",
                "note", withThousands(model.numCoincidentPairs).c_str(), static_cast<int>(first),
                static_cast<int>(second), x(first, 0), x(first, 1), x(first, 2));
  }
  if (model.numLayerNodes() > 0) {
    const auto namesAndCount = [](const std::map<std::string, std::vector<perishell::LocalIndex>>& nodesOfSet) {
      std::string sets;
      std::set<perishell::LocalIndex> nodes;
      for (const auto& [set, members] : nodesOfSet) {
        sets += (sets.empty() ? "" : ", ") + set;
        nodes.insert(members.begin(), members.end());
      }
      return std::make_pair(sets, static_cast<long long>(nodes.size()));
    };
    const auto [held, numHeld] = namesAndCount(model.supportLayer.nodesOfSet);
    const auto [mirrored, numMirrored] = namesAndCount(model.supportLayer.mirroredNodesOfSet);
    std::printf("  %-10s %s nodes, %s beyond supported PD edges (peridynamics.support-layer)", "layer",
                withThousands(model.numLayerNodes()).c_str(),
                elementCounts(model.shell.mesh, model.numMeshElements(), model.shell.mesh.numElements()).c_str());
    if (numHeld > 0) std::printf("; %s held beyond the clamps %s", withThousands(numHeld).c_str(), held.c_str());
    if (numMirrored > 0)
      std::printf("; %s moving as mirror images beyond %s", withThousands(numMirrored).c_str(), mirrored.c_str());
    std::printf("\n");
  }
  for (const auto& set : model.supportLayer.narrowSets)
    std::printf("  %-10s the layer beyond set '%s' is shallower than the horizon (%g m): the model is narrower than "
                "the horizon inside that edge, so its PD nodes miss bonds whatever the layer; refine the mesh or "
                "lower peridynamics.horizon-factor\n",
                "layer", set.c_str(), model.horizon());
  for (const auto& set : model.supportLayer.skippedSets)
    std::printf("  %-10s no support layer beyond set '%s': the mesh goes on beyond each of its free edges (a slit "
                "or a fold)\n",
                "layer", set.c_str());
  printUnlayeredPdSupports(model);
}

// DECK [--output DIR] for the run and check commands, and the run's options.
struct DeckArguments {
  std::string deckPath;
  perishell::solvers::RunOptions run;
};

DeckArguments parseDeckArguments(const std::string& command, const std::vector<std::string>& args) {
  DeckArguments parsed;
  const bool isRun = command == "run";
  const auto valueOf = [&](std::size_t& i, const char* what) -> const std::string& {
    if (i + 1 >= args.size()) throw UsageError("option " + args[i] + " needs " + what);
    return args[++i];
  };
  for (std::size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--output") {
      parsed.run.outputDirectory = valueOf(i, "a directory");
    } else if (isRun && args[i] == "--backend") {
      const std::string& backend = valueOf(i, "device or host");
      if (backend == "device") parsed.run.backend = perishell::solvers::Backend::Device;
      else if (backend == "host") parsed.run.backend = perishell::solvers::Backend::Host;
      else throw UsageError("option --backend: '" + backend + "' is not device or host");
    } else if (isRun && args[i] == "--max-steps") {
      const int steps = parseInteger("--max-steps", valueOf(i, "a number of steps"));
      if (steps < 1) throw UsageError("option --max-steps: must be at least 1");
      parsed.run.maxSteps = steps;
    } else if (isRun && args[i] == "--restart") {
      parsed.run.restartDirectory = valueOf(i, "the output directory of the run to continue");
    } else if (isRun && args[i] == "--phase-times") {
      parsed.run.timePhases = true;
    } else if (isRun && args[i] == "--exchange-overlap") {
      const std::string& mode = valueOf(i, "auto, on or off");
      if (mode == "on") parsed.run.exchangeOverlap = true;
      else if (mode == "off") parsed.run.exchangeOverlap = false;
      else if (mode != "auto") throw UsageError("option --exchange-overlap: '" + mode + "' is not auto, on or off");
    } else if (parsed.deckPath.empty() && args[i].rfind("--", 0) != 0) {
      parsed.deckPath = args[i];
    } else {
      throw UsageError("unexpected argument '" + args[i] + "' for '" + command + "'");
    }
  }
  if (parsed.deckPath.empty()) throw UsageError("'" + command + "' needs a deck file");
  if (!parsed.run.restartDirectory.empty() && !parsed.run.outputDirectory.empty())
    throw UsageError("options --restart and --output: a restart writes on into the directory it continues; leave "
                     "out --output");
  return parsed;
}

int runCheck(const std::vector<std::string>& args) {
  const auto parsed = parseDeckArguments("check", args);
  const std::string& deckPath = parsed.deckPath;
  const std::string& outputDirectory = parsed.run.outputDirectory;
  const auto start = std::chrono::steady_clock::now();
  const perishell::Deck deck = perishell::readDeck(deckPath);
  const auto model = perishell::model::buildModel(deck);
  const auto probes = perishell::solvers::snapProbes(model);  // a probe off the shell is a deck error
  const auto bondStart = std::chrono::steady_clock::now();
  const auto world = perishell::parallel::Communicator::world();
  // Under mpirun the root alone builds the whole bond list and writes (the others' output is silenced).
  const auto bonds = world.root() ? perishell::model::buildPdBonds(perishell::ExecutionSpace{}, model)
                                  : perishell::pd::BondList<perishell::MemorySpace>{};
  Kokkos::fence();
  const auto end = std::chrono::steady_clock::now();

  const auto& mesh = model.shell.mesh;
  std::printf("perishell %s: check %s\n", perishell::versionString().c_str(), deckPath.c_str());
  if (!deck.title.empty()) std::printf("  %-10s %s\n", "title", deck.title.c_str());
  std::printf("  %-10s %s, %s nodes, %s, spacing %g m\n", "mesh", generatorName(deck.mesh.generator),
              withThousands(model.numMeshNodes()).c_str(),
              elementCounts(mesh, 0, model.numMeshElements()).c_str(), model.gridSpacing());
  std::printf("  %-10s %s PD elements of %s: PD ratio %.1f %%; %s PD nodes\n", "zones",
              withThousands(model.numPdElements).c_str(), withThousands(model.numMeshElements()).c_str(),
              100.0 * model.pdRatio(), withThousands(model.pdNodes.extent(0) - model.numLayerNodes()).c_str());
  printMeshNotes(model);
  std::printf("  %-10s %s bonds, horizon %g m (%g x spacing), %zu pre-crack(s); built on %s in %.3f s\n",
              "bonds", withThousands(static_cast<long long>(bonds.numBonds())).c_str(), model.horizon(),
              deck.peridynamics.horizonFactor, deck.mesh.preCracks.size(), perishell::ExecutionSpace::name(),
              std::chrono::duration<double>(end - bondStart).count());
  std::printf("  %-10s %s free (6 per node less %s prescribed); the paper's count, elements x 24: %s\n",
              "DOF", withThousands(model.freeDofCount()).c_str(),
              withThousands(model.numConstrainedDofs).c_str(), withThousands(model.paperDofCount()).c_str());
  std::printf("  %-10s %zu supports, %zu loads, %zu curves; %s solver\n", "setup", deck.supports.size(),
              deck.loads.size(), deck.curves.size(),
              deck.solver.type == perishell::deck::SolverType::Explicit ? "explicit" : "implicit");
  for (const auto& probe : probes)
    std::printf("  %-10s %s: node %d, %g m from the deck's point\n", "probe", probe.name.c_str(),
                static_cast<int>(probe.node), probe.distance);
  if (!outputDirectory.empty() && world.root())
    std::printf("  %-10s %s (pd-node, bonds)\n", "output", writeModelOutput(outputDirectory, model, bonds).c_str());
  for (const auto& warning : deck.warnings) std::printf("  warning: %s\n", warning.c_str());
  // Under mpirun: how the run would split the model (each rank builds its part).
  if (world.distributed()) {
    std::fflush(stdout);
    ranksMayDiverge = true;
    const auto local = perishell::solvers::makeLocalModel(perishell::ExecutionSpace{}, model, world);
    const bool isExplicit = deck.solver.type == perishell::deck::SolverType::Explicit;
    // Explicit: the state each step. Implicit, each Krylov iteration: the operator's input (6
    // DOF per node), and with solver.overlap the preconditioner's input and its output's
    // return to the owners (docs/parallel.md, "Coupling the ranks' preconditioners").
    const int implicitDoubles = deck.solver.implicitSettings.overlap ? 18 : 6;
    perishell::solvers::printPartition(
        local.partitionRow(),
        isExplicit ? perishell::solvers::CentralDifferenceSolver<perishell::ExecutionSpace>::haloDoublesPerNode
                   : implicitDoubles,
        world, std::cout, isExplicit ? "step" : "Krylov iteration");
    std::cout.flush();
  }
  std::printf("deck OK (%.3f s)\n", std::chrono::duration<double>(end - start).count());
  return 0;
}

int runDeck(const std::vector<std::string>& args) {
  const auto parsed = parseDeckArguments("run", args);
  const perishell::Deck deck = perishell::readDeck(parsed.deckPath);
  std::printf("perishell %s: run %s\n", perishell::versionString().c_str(), parsed.deckPath.c_str());
  if (!deck.title.empty()) std::printf("  %-10s %s\n", "title", deck.title.c_str());
  for (const auto& warning : deck.warnings) std::printf("  warning: %s\n", warning.c_str());
  const auto model = perishell::model::buildModel(deck);
  std::printf("  %-10s %s nodes, %s, PD ratio %.1f %%, %s free DOF\n", "model",
              withThousands(model.numMeshNodes()).c_str(),
              elementCounts(model.shell.mesh, 0, model.numMeshElements()).c_str(),
              100.0 * model.pdRatio(), withThousands(model.freeDofCount()).c_str());
  printMeshNotes(model);
  std::fflush(stdout);
  perishell::installStopRequestHandlers();
  const bool isExplicit = deck.solver.type == perishell::deck::SolverType::Explicit;
  // Refusals are the same on every rank: before the ranks go their own ways.
  if (isExplicit) perishell::solvers::requireDistributableExplicitRun(model);
  if (!isExplicit) perishell::solvers::requireDistributableImplicitRun(model);
  ranksMayDiverge = perishell::parallel::Communicator::world().distributed();
  const int stoppedBy = deck.solver.type == perishell::deck::SolverType::Explicit
                            ? perishell::solvers::runExplicit(model, parsed.run, std::cout).stoppedBySignal
                            : perishell::solvers::runImplicit(model, parsed.run, std::cout).stoppedBySignal;
  if (stoppedBy != 0 && ranksMayDiverge) {
    std::cout.flush();
    if (perishell::parallel::Communicator::world().root())
      std::fprintf(stderr,
                   "perishell: stopped by %s before the deck's end; the results hold the states up to the last one "
                   "in the summary (a distributed run writes no checkpoint yet)\n",
                   perishell::stopSignalName(stoppedBy));
    return 128 + stoppedBy;
  }
  if (stoppedBy != 0) {
    std::cout.flush();
    std::fprintf(stderr,
                 "perishell: stopped by %s before the deck's end; the results hold the states up to the last one "
                 "in the summary; continue with: perishell run %s --restart %s\n",
                 perishell::stopSignalName(stoppedBy), parsed.deckPath.c_str(),
                 (parsed.run.restartDirectory.empty()
                      ? (parsed.run.outputDirectory.empty() ? deck.output.directory : parsed.run.outputDirectory)
                      : parsed.run.restartDirectory)
                     .c_str());
    return 128 + stoppedBy;
  }
  return 0;
}

int runMembrane(const std::vector<std::string>& args) {
  perishell::cases::PressurisedMembraneOptions options;
  options.solver.maxIterations = 20000;  // Jacobi-PCG needs O(cells) iterations on this problem
  double maxError = 0.01;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& option = args[i];
    if (i + 1 >= args.size()) throw UsageError("option " + option + " needs a value");
    const std::string& value = args[++i];
    if (option == "--cells") options.cellsPerSide = parseInteger(option, value);
    else if (option == "--side") options.side = parseNumber(option, value);
    else if (option == "--tension") options.tension = parseNumber(option, value);
    else if (option == "--pressure") options.pressure = parseNumber(option, value);
    else if (option == "--tolerance") options.solver.tolerance = parseNumber(option, value);
    else if (option == "--max-iterations") options.solver.maxIterations = parseInteger(option, value);
    else if (option == "--max-error") maxError = parseNumber(option, value);
    else throw UsageError("unknown option '" + option + "' for 'membrane'");
  }
  if (!(options.side > 0.0)) throw UsageError("option --side: must be positive");
  if (!(options.solver.tolerance > 0.0)) throw UsageError("option --tolerance: must be positive");
  if (options.solver.maxIterations < 1) throw UsageError("option --max-iterations: must be at least 1");

  std::printf("perishell %s: pressurised square membrane on %s\n", perishell::versionString().c_str(),
              perishell::ExecutionSpace::name());
  std::printf("  a = %g m, T = %g N/m, p = %g Pa, %d x %d quads\n", options.side, options.tension,
              options.pressure, options.cellsPerSide, options.cellsPerSide);
  const auto start = std::chrono::steady_clock::now();
  const auto result = perishell::cases::runPressurisedMembrane(perishell::ExecutionSpace{}, options);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  std::printf("\n  %-34s %s\n", "quantity", "value");
  std::printf("  %-34s %d (%d constrained)\n", "nodes", result.numNodes, result.numConstrained);
  std::printf("  %-34s %.12g m^2\n", "mesh area (sum of node areas)", result.meshArea);
  std::printf("  %-34s %s in %d iterations (residual %.2e)\n", "Belos PCG (Jacobi)",
              result.solve.converged ? "converged" : "NOT converged", result.solve.iterations,
              result.solve.achievedTolerance);
  std::printf("  %-34s %.9e m\n", "centre deflection", result.centreDeflection);
  std::printf("  %-34s %.9e m\n", "exact (series) centre deflection", result.analyticCentreDeflection);
  std::printf("  %-34s %.3e\n", "relative error", result.relativeError);
  std::printf("  %-34s %.3f s\n", "wall time (setup + solve)", seconds);

  if (!result.solve.converged) {
    std::fprintf(stderr, "perishell: error: PCG did not converge in %d iterations (raise --max-iterations)\n",
                 result.solve.iterations);
    return 1;
  }
  if (result.relativeError > maxError) {
    std::fprintf(stderr, "perishell: error: relative error %.3e exceeds --max-error %.3e\n",
                 result.relativeError, maxError);
    return 1;
  }
  return 0;
}

// The GPUs this process may use (none in an OpenMP build). Asked before Kokkos starts.
int visibleGpuCount() {
#ifdef KOKKOS_ENABLE_CUDA
  int count = 0;
  return cudaGetDeviceCount(&count) == cudaSuccess ? count : 0;
#else
  return 0;
#endif
}

// One rank per GPU (docs/parallel.md): in a CUDA build under mpirun, the rank with node-local
// index r takes GPU r mod the node's GPUs, unless the command line picks one
// (--kokkos-device-id, --kokkos-num-devices). Ranks then share GPUs when there are fewer.
std::vector<std::string> withDeviceOfRank(int argc, char* argv[], const perishell::parallel::Communicator& world) {
  std::vector<std::string> arguments(argv, argv + argc);
  if (!world.distributed()) return arguments;
  const int localRank = world.nodeLocalRank();  // collective: every rank calls it
  const int gpus = visibleGpuCount();
  // Where a node has more ranks than GPUs, ranks share GPUs: allowed (a test can run 2 ranks on
  // one GPU), but slower than one rank per GPU, so the root says so.
  if (world.any(gpus > 0 && localRank >= gpus) && world.root())
    std::fprintf(stderr,
                 "perishell: warning: more MPI ranks on a node than its GPUs: ranks share GPUs (one rank per GPU "
                 "is the intended layout, docs/parallel.md)\n");
  const bool chosen = std::any_of(arguments.begin(), arguments.end(), [](const std::string& argument) {
    return argument.rfind("--kokkos-device-id", 0) == 0 || argument.rfind("--kokkos-num-devices", 0) == 0;
  });
  if (!chosen && gpus > 0) arguments.push_back("--kokkos-device-id=" + std::to_string(localRank % gpus));
  return arguments;
}

}  // namespace

int main(int argc, char* argv[]) {
  // Before Kokkos, and finalised after it: a run under mpirun is distributed (docs/parallel.md).
  const perishell::parallel::Environment mpi(argc, argv);
  const auto world = perishell::parallel::Communicator::world();
  // One progress stream and one summary: the root's. Errors stay on every rank's stderr.
  if (!world.root() && !std::freopen("/dev/null", "w", stdout))
    std::fprintf(stderr, "perishell (rank %d): cannot silence stdout\n", world.rank());
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty() || args[0] == "--help" || args[0] == "-h") {
    std::fputs(usage, args.empty() ? stderr : stdout);
    return args.empty() ? 2 : 0;
  }
  if (args[0] == "--version") {
    std::printf("perishell %s\n", perishell::versionString().c_str());
    return 0;
  }
  // libgomp has already read its environment: with OMP_PROC_BIND unset it binds no threads.
  // Saying so to Kokkos keeps its "OMP_PROC_BIND not set" advice off every run; a value the
  // user set is left alone.
  setenv("OMP_PROC_BIND", "false", /*overwrite=*/0);
  const auto kokkosArguments = withDeviceOfRank(argc, argv, world);
  int kokkosArgc = static_cast<int>(kokkosArguments.size());
  std::vector<char*> kokkosArgv;
  for (const auto& argument : kokkosArguments) kokkosArgv.push_back(const_cast<char*>(argument.c_str()));
  kokkosArgv.push_back(nullptr);
  argv = kokkosArgv.data();
  argc = kokkosArgc;
  Kokkos::ScopeGuard kokkos(argc, argv);  // strips the --kokkos-* arguments from argv
  args.assign(argv + 1, argv + argc);
  if (args.empty()) {
    std::fputs(usage, stderr);
    return 2;
  }
  try {
    if (args[0] == "--backend-info") {
      perishell::printBackendInfo(std::cout);
      return 0;
    }
    if (args[0] == "run") return runDeck({args.begin() + 1, args.end()});
    if (args[0] == "check") return runCheck({args.begin() + 1, args.end()});
    if (args[0] == "membrane") return runMembrane({args.begin() + 1, args.end()});
    throw UsageError("unknown command '" + args[0] + "'");
  } catch (const UsageError& error) {
    if (world.root()) std::fprintf(stderr, "perishell: error: %s\n(see perishell --help)\n", error.what());
    return 2;
  } catch (const perishell::solvers::ExplicitInstability& error) {
    // Judged from global sums and the root's verdict: the same on every rank.
    if (world.root()) std::fprintf(stderr, "perishell: error: %s\n", error.what());
    return 1;
  } catch (const perishell::solvers::NewtonFailure& error) {
    if (world.root()) std::fprintf(stderr, "perishell: error: %s\n", error.what());
    return 1;
  } catch (const perishell::solvers::RunStateError& error) {
    if (world.root()) std::fprintf(stderr, "perishell: error: %s\n", error.what());
    return 1;
  } catch (const std::exception& error) {
    // Errors before the solver are the deck's and the same on every rank: the root says it.
    // In the solver, each rank says its own and all end at once.
    if (world.root())
      std::fprintf(stderr, "perishell: error: %s\n", error.what());
    else if (ranksMayDiverge)
      std::fprintf(stderr, "perishell (rank %d of %d): error: %s\n", world.rank(), world.size(), error.what());
    if (ranksMayDiverge) {
      std::fflush(stderr);
      world.abort(1);
    }
    return 1;
  }
}
