// Cost of the implicit path (model.md §6, paper §3.2.1 and Table 4) on the build's default
// execution space, for the pressed plate of example 4.2.1 (90 x 30 x 0.8 mm, left edge
// clamped, 1 MPa pressure; model.md §7) at several grid spacings, CCM-only and 100 % PD:
// - assembly: one tangent (shell elements or bonds into the 6x6-block CRS matrix by
//   atomic_add), median over repeats;
// - the first load increment (1 % of the pressure, as the deck's 100 increments): Newton
//   iterations, and per linear solve the preconditioner set-up, the PCG time and iterations;
//   with amg also the set-up's parts (aggregation and patterns, smoother, prolongator,
//   Galerkin products, coarse inverse);
//   with --newton N only its first N Newton iterations (N = 1: one linear solve, the
//   paper's measure, its AMG set-up built from nothing).
// The paper's Table 4 timed one linear solve of its 50 % PD model: 163 s (259,200 DOF),
// 347 s (1,036,800 DOF) and 11,329 s (6,480,000 DOF) on its GPU; its "DOF" are elements x 24
// (model.md §7), printed beside the true number of free DOF.
//
// Usage: perishell_perf_implicit_solve [--csv] [--repeats R] [--preconditioner NAME]
//                                      [--factorization auto|host|device] [--amg-drop-tolerance T]
//                                      [--amg-coarse-nodes N] [--amg-region-scaling true|false]
//                                      [--models ccm,pd,pd50] [--newton N] [spacing_mm...]
//   models: ccm, pd (100 %) or pdNN (NN % PD, the zone grown from the clamped edge's middle);
//   defaults: 5 repeats, preconditioner amg, models ccm and pd, spacings 0.5 0.25 0.1 mm; with
//   cholesky or direct the increment ends with a factorization of its converged tangent (the
//   stability check, counted in setup per solve)
//   OpenMP: OMP_NUM_THREADS=2 OMP_PROC_BIND=false ./perishell_perf_implicit_solve 1 0.5
#include <perishell/io/deck.hpp>
#include <perishell/solvers/implicit/static_solver_from_model.hpp>

#include "median_seconds.hpp"

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {

using ExecutionSpace = perishell::ExecutionSpace;

struct Options {
  bool csv = false;
  int repeats = 5;
  std::string preconditioner = "amg";
  std::string factorization = "auto";  // solver.factorization: where a GPU run factors
  std::string amgDropTolerance = "0.05";  // solver.amg-drop-tolerance
  std::string amgCoarseNodes = "200";     // solver.amg-coarse-nodes
  std::string amgRegionScaling = "true";   // solver.amg-region-scaling
  std::vector<std::string> models{"ccm", "pd"};
  std::vector<double> spacingsMm{0.5, 0.25, 0.1};
  int newtonIterations = 0;  // 0: the whole first increment
};

// "pd25" -> 25: a mixed model of that PD ratio; -1 for any other name.
int pdRatioPercent(const std::string& model) {
  if (model.size() < 3 || model.compare(0, 2, "pd") != 0) return -1;
  char* end = nullptr;
  const long percent = std::strtol(model.c_str() + 2, &end, 10);
  return *end == '\0' && percent > 0 && percent < 100 ? static_cast<int>(percent) : -1;
}

[[noreturn]] void usage(const char* program, const std::string& problem) {
  std::fprintf(stderr,
               "error: %s\nusage: %s [--csv] [--repeats R] [--preconditioner jacobi|block-jacobi|amg|cholesky|direct|auto] "
               "[--factorization auto|host|device] [--amg-drop-tolerance T] [--amg-coarse-nodes N] [--models ccm,pd,pd50] "
               "[--amg-region-scaling true|false] [--newton N] "
               "[spacing_mm...]\n",
               problem.c_str(), program);
  std::exit(2);
}

Options parseArguments(int argc, char* argv[]) {
  Options options;
  std::vector<double> spacings;
  for (int a = 1; a < argc; ++a) {
    const std::string argument = argv[a];
    const bool hasValue = a + 1 < argc;
    if (argument == "--csv") {
      options.csv = true;
    } else if (argument == "--repeats" && hasValue) {
      options.repeats = std::max(1, std::atoi(argv[++a]));
    } else if (argument == "--newton" && hasValue) {
      options.newtonIterations = std::atoi(argv[++a]);
      if (options.newtonIterations < 1) usage(argv[0], "--newton needs a count of at least 1");
    } else if (argument == "--preconditioner" && hasValue) {
      options.preconditioner = argv[++a];
    } else if (argument == "--factorization" && hasValue) {
      options.factorization = argv[++a];
    } else if (argument == "--amg-drop-tolerance" && hasValue) {
      options.amgDropTolerance = argv[++a];
    } else if (argument == "--amg-coarse-nodes" && hasValue) {
      options.amgCoarseNodes = argv[++a];
    } else if (argument == "--amg-region-scaling" && hasValue) {
      options.amgRegionScaling = argv[++a];
    } else if (argument == "--models" && hasValue) {
      options.models.clear();
      std::string list = argv[++a];
      for (std::size_t start = 0; start <= list.size();) {
        const auto comma = std::min(list.find(',', start), list.size());
        const std::string model = list.substr(start, comma - start);
        if (model != "ccm" && model != "pd" && pdRatioPercent(model) < 0)
          usage(argv[0], "unknown model '" + model + "' (ccm, pd or pdNN: NN % PD)");
        options.models.push_back(model);
        start = comma + 1;
      }
    } else {
      char* end = nullptr;
      const double value = std::strtod(argv[a], &end);
      if (end == argv[a] || *end != '\0' || !(value > 0.0)) usage(argv[0], "'" + argument + "' is not a spacing in mm");
      spacings.push_back(value);
    }
  }
  if (!spacings.empty()) options.spacingsMm = spacings;
  return options;
}

// The deck of example 4.2.1 with the whole plate CCM or PD, or a PD zone of the given ratio grown
// from the middle of the clamped edge as in apps/cases/pressed_plate_4_2_1.yaml (model.md §7).
perishell::model::Model pressedPlate(double spacing, const std::string& zone, const Options& options,
                                     int maxIterations) {
  const int percent = pdRatioPercent(zone);
  const std::string zones = percent < 0 ? "{default: " + zone + "}"
                                        : "{default: ccm, pd-ratio: {target: " + std::to_string(percent / 100.0) +
                                              ", around: {clamped-edge-middle: [0.0, 0.015, 0.0]}}}";
  const std::string text = R"(perishell:
  version: 1
  mesh: {generator: plate, length-x: 0.090, length-y: 0.030, spacing: )" +
                           std::to_string(spacing) + R"(}
  material: {young-modulus: 210.0e9, poisson-ratio: 0.33, density: 2440.0, thickness: 0.8e-3}
  zones: )" + zones + R"(
  supports: {clamp: {set: left, dofs: [ux, uy, uz, rx, ry, rz]}}
  loads: {pressure: {type: pressure, value: 1.0e6}}
  solver: {type: implicit, increments: 100, max-iterations: )" +
                           std::to_string(maxIterations) + R"(, tolerance: 1.0e-8, preconditioner: )" +
                           options.preconditioner +
                           ", factorization: " + options.factorization +
                           ", amg-drop-tolerance: " + options.amgDropTolerance +
                           ", amg-coarse-nodes: " + options.amgCoarseNodes +
                           ", amg-region-scaling: " + options.amgRegionScaling + R"(}
)";
  return perishell::model::buildModel(perishell::parseDeck(text, "pressed_plate.yaml"));
}

// The paper's GPU time for one linear solve (Table 4) at its DOF count, or 0 where it has none.
double paperSolveSeconds(long long paperDof) {
  if (paperDof == 259200) return 163.0;
  if (paperDof == 1036800) return 347.0;
  if (paperDof == 6480000) return 11329.0;
  return 0.0;
}

}  // namespace

int main(int argc, char* argv[]) {
  Kokkos::ScopeGuard kokkos(argc, argv);
  const Options options = parseArguments(argc, argv);
  if (options.csv) {
    std::printf("backend,model,spacing_mm,nodes,elements,paper_dof,free_dof,bonds,preconditioner,assembly_s,"
                "newton_iterations,linear_iterations_per_solve,setup_s_per_solve,solve_s_per_solve,"
                "tip_deflection_m,paper_solve_s\n");
  } else {
    std::printf("# implicit pressed plate 4.2.1 on %s (concurrency %d), first increment (1 %% of 1 MPa)%s, "
                "assembly median of %d, %s preconditioner, amg-drop-tolerance %s, amg-coarse-nodes %s, "
                "amg-region-scaling %s\n",
                ExecutionSpace::name(), ExecutionSpace::concurrency(),
                options.newtonIterations > 0 ? (", its first " + std::to_string(options.newtonIterations) +
                                                " Newton iterations").c_str()
                                             : "",
                options.repeats, options.preconditioner.c_str(), options.amgDropTolerance.c_str(),
                options.amgCoarseNodes.c_str(), options.amgRegionScaling.c_str());
    std::printf("%5s %8s %9s %9s %10s %10s %10s %12s %7s %9s %10s %10s %12s %10s\n", "model", "dx[mm]", "nodes",
                "elements", "paper DOF", "free DOF", "bonds", "assembly[s]", "Newton", "PCG/solve", "setup[s]",
                "solve[s]", "tip w [m]", "paper [s]");
  }
  for (const auto& zone : options.models)
    for (const double spacingMm : options.spacingsMm) {
      const int maxIterations = options.newtonIterations > 0 ? options.newtonIterations : 100;
      const auto model = pressedPlate(spacingMm * 1e-3, zone, options, maxIterations);
      auto solver = perishell::solvers::makeStaticSolver(ExecutionSpace{}, model);
      const double assemblySeconds = perishell::perf::medianSeconds(options.repeats, [&] { solver.assembleTangent(); });
      perishell::solvers::IncrementReport report;
      if (options.newtonIterations > 0)
        solver.iterate(0.01, report);  // stops after N iterations, converged or not
      else
        report = solver.advanceTo(0.01);
      const auto u = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, solver.kinematics().displacements);
      double tip = 0.0;
      for (const auto node : model.shell.sets.nodeSet("right")) tip = std::max(tip, std::abs(u(node, 2)));
      const long long elements = model.shell.mesh.numElements();
      const long long paperDof = 24 * elements;
      const long long freeDof = model.freeDofCount();
      const double solves = std::max(1, report.newtonIterations);
      const double paper = paperSolveSeconds(paperDof);
      if (options.csv) {
        std::printf("%s,%s,%g,%d,%lld,%lld,%lld,%d,%s,%.6e,%d,%.1f,%.6e,%.6e,%.6e,%g\n", ExecutionSpace::name(),
                    zone.c_str(), spacingMm, model.shell.mesh.numNodes(), elements, paperDof, freeDof,
                    static_cast<int>(solver.numBonds()), options.preconditioner.c_str(), assemblySeconds,
                    report.newtonIterations, report.linearIterations / solves, report.seconds.preconditioner / solves,
                    report.seconds.linearSolve / solves, tip, paper);
      } else {
        std::printf("%5s %8.3g %9d %9lld %10lld %10lld %10d %12.4f %7d %9.1f %10.4f %10.4f %12.6e %10s\n",
                    zone.c_str(), spacingMm, model.shell.mesh.numNodes(), elements, paperDof, freeDof,
                    static_cast<int>(solver.numBonds()), assemblySeconds, report.newtonIterations,
                    report.linearIterations / solves, report.seconds.preconditioner / solves,
                    report.seconds.linearSolve / solves, tip,
                    paper > 0.0 ? std::to_string(static_cast<int>(paper)).c_str() : "-");
        const auto setup = solver.multigridSetupSeconds();
        if (setup.total() > 0.0)
          std::printf("#   amg set-up per solve [s]: patterns %.4f, smoother %.4f, prolongator %.4f, galerkin %.4f, "
                      "coarse inverse %.4f (%d builds)\n",
                      setup.patterns / solves, setup.smoother / solves, setup.prolongator / solves,
                      setup.galerkin / solves, setup.coarse / solves, report.preconditionerBuilds);
      }
      std::fflush(stdout);
    }
  return 0;
}
