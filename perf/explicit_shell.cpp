// What a CCM element costs against the PD bonds it replaces (issue 21): one explicit step
// (model.md §6) of the same square plate modelled three ways on the build's default
// execution space — every element a one-point shell (shell/one_point_shell.hpp, the explicit
// solver's default), every element MITC4 (its cached 24 x 24 K_l and forward-mode B), and
// 100 % PD (microbeam bonds, delta = 3 dx, node-gather) — set vibrating by one smooth
// velocity field. The one-point element runs with both force assemblies (atomic scatter and
// buffer-then-gather, shell::ElementForceAssembly). Per size: mean step time over `steps`
// unmonitored steps, median over repeats, one warm-up block first; and the ratios to the PD
// step measured in the same run.
//
// Usage: perishell_perf_explicit_shell [--steps S] [--no-mitc4] [repeats] [elements...]
//   defaults: 5 repeats, 20 steps, elements 1e4 1e5 1e6
//   OpenMP: OMP_NUM_THREADS=2 OMP_PROC_BIND=false ./perishell_perf_explicit_shell 3 1e4 1e5
//           (100 % PD's set-up at 1e6 takes minutes on 2 threads: its critical-step estimate is
//           80 force evaluations)
//   CUDA:   ./perishell_perf_explicit_shell 5 1e4 1e5 1e6
#include <perishell/coupling/make_coupled_model.hpp>
#include <perishell/mesh/generators.hpp>
#include <perishell/solvers/explicit/central_difference.hpp>

#include "median_seconds.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {

using perishell::LocalIndex;
using perishell::perf::medianSeconds;
using ExecutionSpace = perishell::ExecutionSpace;
using MemorySpace = ExecutionSpace::memory_space;
using Solver = perishell::solvers::CentralDifferenceSolver<ExecutionSpace>;
using Element = perishell::shell::ShellElementKind;
using Assembly = perishell::shell::ElementForceAssembly;

constexpr double pi = 3.14159265358979323846;
constexpr double spacing = 1.0e-3;  // dx [m]
// The steel of the paper's plate 4.2.2 (model.md §7), without G_c: no bond breaks.
constexpr double youngModulus = 200e9, poissonRatio = 0.3, thickness = 1e-3, density = 7850.0;

struct Options {
  int repeats = 5;
  int steps = 20;
  bool mitc4 = true;
  std::vector<double> elementCounts{1e4, 1e5, 1e6};
};

Options parseArguments(int argc, char* argv[]) {
  Options options;
  std::vector<double> positional;
  for (int a = 1; a < argc; ++a) {
    if (std::strcmp(argv[a], "--steps") == 0 && a + 1 < argc) {
      options.steps = std::max(1, std::atoi(argv[++a]));
    } else if (std::strcmp(argv[a], "--no-mitc4") == 0) {
      options.mitc4 = false;
    } else {
      char* end = nullptr;
      const double value = std::strtod(argv[a], &end);
      if (end == argv[a] || *end != '\0' || !(value >= 1.0)) {
        std::fprintf(stderr, "error: argument %d '%s' is not a positive number (usage: %s [--steps S] [--no-mitc4] "
                             "[repeats] [elements...])\n", a, argv[a], argv[0]);
        std::exit(2);
      }
      positional.push_back(value);
    }
  }
  if (!positional.empty()) options.repeats = static_cast<int>(positional.front());
  if (positional.size() > 1) options.elementCounts.assign(positional.begin() + 1, positional.end());
  return options;
}

perishell::pd::NodalVectorView<MemorySpace> initialVelocities(const perishell::mesh::HostQuadMesh& mesh, double side) {
  perishell::pd::NodalVectorView<Kokkos::HostSpace> host("initial velocities", mesh.numNodes());
  for (LocalIndex node = 0; node < mesh.numNodes(); ++node) {
    const double x = mesh.coordinates(node, 0), y = mesh.coordinates(node, 1);
    const double sx = std::sin(pi * x / side), cx = std::cos(pi * x / side);
    const double sy = std::sin(pi * y / side), cy = std::cos(pi * y / side);
    host(node, 0) = 0.05 * sx * cy;  // [m/s]
    host(node, 1) = 0.03 * cx * sy;
    host(node, 2) = 0.2 * sx * sy;
  }
  return Kokkos::create_mirror_view_and_copy(MemorySpace{}, host);
}

struct Timing {
  double setup = 0.0;   // [s]
  double step = 0.0;    // [s] per unmonitored step
  double strain = 0.0;  // [J] at the last monitored step: proof that the model was loaded
  LocalIndex elements = 0;
  std::size_t bonds = 0;
};

// allPd: every element PD (100 % PD), else every element CCM of `kind`.
Timing timeModel(const perishell::mesh::ShellMesh& plate, double side, bool allPd, Element kind, Assembly assembly,
                 const Options& options) {
  const ExecutionSpace space;
  Kokkos::fence();
  const auto start = std::chrono::steady_clock::now();
  Kokkos::View<std::uint8_t*, Kokkos::HostSpace> elementIsPd("is pd", plate.mesh.numElements());
  Kokkos::deep_copy(elementIsPd, allPd ? 1 : 0);
  perishell::coupling::CouplingInputs inputs;
  inputs.material = {youngModulus, poissonRatio, thickness, std::nullopt};
  inputs.section.youngModulus = youngModulus;
  inputs.section.poissonRatio = poissonRatio;
  inputs.section.thickness = thickness;
  inputs.horizon = 3.0 * spacing;
  inputs.gridSpacing = spacing;
  inputs.shellElement = kind;
  const auto bodies = perishell::coupling::makeCoupledBodies(space, plate.mesh, elementIsPd, inputs);
  perishell::solvers::ExplicitOptions solverOptions;
  solverOptions.density = density;
  solverOptions.thickness = thickness;
  solverOptions.monitorEvery = options.steps + 1;
  auto shellElements = bodies.shellElements();
  if (shellElements) shellElements->assembly = assembly;
  Solver solver(space, bodies.pdBody, shellElements,
                perishell::solvers::makeFreeActions<MemorySpace>(plate.mesh.numNodes()), solverOptions);
  Kokkos::fence();
  Timing timing;
  timing.setup = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  timing.elements = solver.numElements();
  timing.bonds = solver.body().bonds.numBonds();
  solver.setInitialVelocities(initialVelocities(plate.mesh, side));
  const auto steps = [&] {
    for (int s = 0; s < options.steps; ++s) solver.step();
  };
  solver.step();  // the monitored first step, then a warm-up block
  steps();
  timing.step = medianSeconds(options.repeats, [&] { solver.step(); }, steps) / options.steps;
  timing.strain = solver.lastEnergyReport().strain;
  return timing;
}

}  // namespace

int main(int argc, char* argv[]) {
  Kokkos::ScopeGuard kokkos(argc, argv);
  const Options options = parseArguments(argc, argv);
  std::printf("# one explicit step of a square steel plate (dx = 1 mm, t = 1 mm) on %s (concurrency %d): all CCM "
              "one-point, all CCM MITC4, 100 %% PD (delta = 3 dx, node-gather); mean of %d steps, median of %d "
              "repeats\n",
              ExecutionSpace::name(), ExecutionSpace::concurrency(), options.steps, options.repeats);
  std::printf("%10s %10s %12s %12s %12s %12s %12s %12s %12s %12s\n", "elements", "nodes", "bonds", "PD step [s]",
              "1-pt sc [s]", "1-pt ga [s]", "MITC4 [s]", "1-pt / PD", "MITC4 / PD", "1-pt setup");
  for (const double target : options.elementCounts) {
    const int cells = std::max(2, static_cast<int>(std::lround(std::sqrt(target))));
    const double side = cells * spacing;
    const auto plate = perishell::mesh::makePlateWithCells(side, side, cells, cells);
    const Timing pd = timeModel(plate, side, true, Element::OnePoint, Assembly::Scatter, options);
    const Timing scatter = timeModel(plate, side, false, Element::OnePoint, Assembly::Scatter, options);
    const Timing gather = timeModel(plate, side, false, Element::OnePoint, Assembly::Gather, options);
    const Timing mitc4 =
        options.mitc4 ? timeModel(plate, side, false, Element::Mitc4, Assembly::Scatter, options) : Timing{};
    const Timing& onePoint = scatter.step < gather.step ? scatter : gather;
    for (const Timing* t : {&pd, &scatter, &gather})
      if (!(t->strain > 0.0)) {
        std::fprintf(stderr, "error: no strain energy on %d cells: the model was not loaded\n", cells * cells);
        return 1;
      }
    std::printf("%10d %10d %12zu %12.4e %12.4e %12.4e %12.4e %12.4f %12.4f %12.3e\n", onePoint.elements,
                plate.mesh.numNodes(), pd.bonds, pd.step, scatter.step, gather.step, mitc4.step,
                onePoint.step / pd.step, mitc4.step / pd.step, onePoint.setup);
    std::fflush(stdout);
  }
  return 0;
}
