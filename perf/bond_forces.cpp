// Cost of one explicit step (model.md §6) and throughput of the bond force kernel
// (pd/bond_forces.hpp) for both of its mappings, NodeGather and BondScatter, on the build's
// default execution space: square PD plates of ~1e4 to ~1e7 nodes at spacing dx with
// delta = 3 dx (model.md §1), set vibrating by a smooth velocity field (no fracture energy,
// so no bond breaks and every step does the same work).
//
// Per size and kernel: the solver's construction (inertia and the critical-time-step power
// iteration, 80 force evaluations), the force kernel alone and a whole step (each the mean
// over `steps` launches, median over repeats), and a step with the energy monitor (its
// reductions); one warm-up block first. NodeGather evaluates every bond from both ends, so
// its bond evaluations are the full-list entries (2 x half bonds), BondScatter's the half
// bonds; half bonds per second compare the two.
//
// Usage: perishell_perf_bond_forces [--csv] [--steps S] [repeats] [nodes...]
//   defaults: 5 repeats, 20 steps, nodes 1e4 3e4 1e5 3e5 1e6; ask for 1e7 by name: it needs
//   ~13 GB of device memory (48 B per bond, 14 half bonds and ~0.5 kB of solver state per node)
//   OpenMP: OMP_NUM_THREADS=2 OMP_PROC_BIND=false ./perishell_perf_bond_forces 3 1e4 1e5
//           (1e6 on 2 threads: add --steps 2; construction alone is ~6 min per kernel there)
//   CUDA:   ./perishell_perf_bond_forces 5 1e4 3e4 1e5 3e5 1e6 1e7
#include <perishell/mesh/generators.hpp>
#include <perishell/pd/make_body.hpp>
#include <perishell/solvers/explicit/central_difference.hpp>

#include "median_seconds.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

namespace {

using perishell::LocalIndex;
using perishell::deck::ForceKernel;
using perishell::perf::medianSeconds;
using ExecutionSpace = perishell::ExecutionSpace;
using MemorySpace = ExecutionSpace::memory_space;
using Solver = perishell::solvers::CentralDifferenceSolver<ExecutionSpace>;

constexpr double pi = 3.14159265358979323846;
constexpr double spacing = 1.0e-3;     // dx [m]
constexpr double horizonFactor = 3.0;  // delta = 3 dx, as in all the paper's examples (model.md §1)
// The glass of the paper's Y-branching plate (model.md §7, case 4.1.2), without G_c so that
// no bond breaks.
constexpr double density = 2440.0;  // [kg/m^3]
const perishell::pd::PdMaterial glass{72e9, 0.33, 1e-3, std::nullopt};

struct Options {
  bool csv = false;
  int repeats = 5;
  int steps = 20;
  std::vector<double> nodeCounts{1e4, 3e4, 1e5, 3e5, 1e6};
};

Options parseArguments(int argc, char* argv[]) {
  Options options;
  std::vector<double> positional;
  for (int a = 1; a < argc; ++a) {
    if (std::strcmp(argv[a], "--csv") == 0) {
      options.csv = true;
    } else if (std::strcmp(argv[a], "--steps") == 0 && a + 1 < argc) {
      options.steps = std::max(1, std::atoi(argv[++a]));
    } else {
      char* end = nullptr;
      const double value = std::strtod(argv[a], &end);
      if (end == argv[a] || *end != '\0' || !(value >= 1.0)) {
        std::fprintf(stderr, "error: argument %d '%s' is not a positive number (usage: %s [--csv] [--steps S] "
                             "[repeats] [nodes...])\n", a, argv[a], argv[0]);
        std::exit(2);
      }
      positional.push_back(value);
    }
  }
  if (!positional.empty()) options.repeats = static_cast<int>(positional.front());
  if (positional.size() > 1) options.nodeCounts.assign(positional.begin() + 1, positional.end());
  return options;
}

// A smooth mix of membrane and bending motion over the whole plate: every bond stretches,
// bends and twists a little, far below any instability.
void plateVibration(double x, double y, double side, double v[6]) {
  const double sx = std::sin(pi * x / side), cx = std::cos(pi * x / side);
  const double sy = std::sin(pi * y / side), cy = std::cos(pi * y / side);
  v[0] = 0.05 * sx * cy;  // [m/s]
  v[1] = 0.03 * cx * sy;
  v[2] = 0.2 * sx * sy;
  v[3] = v[4] = v[5] = 0.0;
}

perishell::pd::NodalVectorView<MemorySpace> initialVelocities(const perishell::mesh::HostQuadMesh& mesh, double side) {
  perishell::pd::NodalVectorView<Kokkos::HostSpace> host("initial velocities", mesh.numNodes());
  for (LocalIndex node = 0; node < mesh.numNodes(); ++node) {
    double v[6];
    plateVibration(mesh.coordinates(node, 0), mesh.coordinates(node, 1), side, v);
    for (int d = 0; d < 6; ++d) host(node, d) = v[d];
  }
  return Kokkos::create_mirror_view_and_copy(MemorySpace{}, host);
}

double secondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

struct Timings {
  double construction = 0.0;    // [s]
  double kernel = 0.0;          // [s] per launch
  double step = 0.0;            // [s] per unmonitored step
  double monitoredStep = 0.0;   // [s]
  double strainEnergy = 0.0;    // [J] at the last monitored step: proof that bonds were loaded
};

Timings timeKernel(const perishell::pd::PdBody<MemorySpace>& body, const perishell::mesh::HostQuadMesh& mesh,
                   double side, ForceKernel kernel, const Options& options) {
  const ExecutionSpace space;
  perishell::solvers::ExplicitOptions solverOptions;
  solverOptions.density = density;
  solverOptions.thickness = glass.thickness;
  solverOptions.forceKernel = kernel;
  // One monitored step, then `steps` plain ones: each timed block starts right after a
  // monitored step (timed on its own) and contains none.
  solverOptions.monitorEvery = options.steps + 1;

  Timings timings;
  Kokkos::fence();
  const auto start = std::chrono::steady_clock::now();
  Solver solver(space, body, perishell::solvers::makeFreeActions<MemorySpace>(body.numNodes()), solverOptions);
  Kokkos::fence();
  timings.construction = secondsSince(start);
  solver.setInitialVelocities(initialVelocities(mesh, side));

  const auto steps = [&] {
    for (int s = 0; s < options.steps; ++s) solver.step();
  };
  solver.step();  // step 0: the monitored first step (initial energy), then a warm-up block
  steps();
  std::vector<double> monitored;
  timings.step = medianSeconds(
                     options.repeats, [&] { monitored.push_back(medianSeconds(1, [&] { solver.step(); })); }, steps) /
                 options.steps;
  std::sort(monitored.begin(), monitored.end());
  timings.monitoredStep = monitored[monitored.size() / 2];
  timings.strainEnergy = solver.lastEnergyReport().strain;

  // The force kernel alone on the vibrating state; forces accumulate over the launches
  // (the step zeroes them, here that would be timed too), which changes no work.
  const LocalIndex numNodes = body.numNodes();
  const perishell::pd::BondForceOutputs<MemorySpace> outputs{
      perishell::pd::NodalVectorView<MemorySpace>("bench forces", numNodes), perishell::VectorView<MemorySpace>(),
      perishell::VectorView<MemorySpace>("bench fracture energy", numNodes),
      perishell::pd::makeIntactFlags(body.bonds, "bench intact next")};
  const auto launches = [&] {
    for (int s = 0; s < options.steps; ++s)
      perishell::pd::computeBondForces(space, kernel, solver.body(), solver.kinematics(), solver.intactBonds(), outputs);
  };
  launches();  // warm-up
  timings.kernel = medianSeconds(options.repeats, launches) / options.steps;
  return timings;
}

}  // namespace

int main(int argc, char* argv[]) {
  Kokkos::ScopeGuard kokkos(argc, argv);
  const Options options = parseArguments(argc, argv);
  const char* spaceName = ExecutionSpace::name();
  std::printf("# bond forces and explicit steps on %s (concurrency %d), delta = %g dx, mean of %d steps, "
              "median of %d repeats\n",
              spaceName, ExecutionSpace::concurrency(), horizonFactor, options.steps, options.repeats);
  if (options.csv)
    std::printf("nodes,half_bonds,kernel,construction_s,kernel_s,step_s,monitored_step_s,bond_evaluations_per_s,"
                "half_bonds_per_s,step_half_bonds_per_s,space\n");
  else
    std::printf("%10s %11s %12s %11s %11s %11s %11s %12s %12s %12s  %s\n", "nodes", "half bonds", "kernel",
                "setup [s]", "force [s]", "step [s]", "monitor [s]", "bond eval/s", "half bond/s", "step hb/s",
                "space");
  for (const double target : options.nodeCounts) {
    const int cells = std::max(2, static_cast<int>(std::lround(std::sqrt(target)))) - 1;
    const double side = cells * spacing;
    const auto plate = perishell::mesh::makePlateWithCells(side, side, cells, cells);
    const auto body = perishell::pd::makePdBody(ExecutionSpace{}, plate.mesh,
                                                perishell::pd::allNodes(plate.mesh.numNodes()), glass,
                                                horizonFactor * spacing, spacing, {});
    const double halfBonds = static_cast<double>(body.bonds.numBonds());
    for (const ForceKernel kernel : {ForceKernel::NodeGather, ForceKernel::BondScatter}) {
      const Timings t = timeKernel(body, plate.mesh, side, kernel, options);
      if (!(t.strainEnergy > 0.0)) {
        std::fprintf(stderr, "error: no strain energy on %d nodes: the bonds were not loaded\n", body.numNodes());
        return 1;
      }
      const bool gather = kernel == ForceKernel::NodeGather;
      const double evaluations = gather ? 2.0 * halfBonds : halfBonds;
      const char* name = gather ? "node-gather" : "bond-scatter";
      const char* format = options.csv ? "%d,%.0f,%s,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%.6e,%s\n"
                                       : "%10d %11.0f %12s %11.3e %11.3e %11.3e %11.3e %12.4e %12.4e %12.4e  %s\n";
      std::printf(format, body.numNodes(), halfBonds, name, t.construction, t.kernel, t.step, t.monitoredStep,
                  evaluations / t.kernel, halfBonds / t.kernel, halfBonds / t.step, spaceName);
      std::fflush(stdout);
    }
  }
  return 0;
}
