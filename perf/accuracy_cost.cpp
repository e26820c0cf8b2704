// Speed against accuracy (issue 7): validation cases with references in model.md §8, swept
// over grid spacing and model parameters; one CSV row per run, wall time against error.
// Every model is built from deck text as a user's deck would be (docs/deck.md), so the
// time covers the whole path: deck -> model -> bodies on the device -> solve -> answer.
//
// Cases (error against the reference):
//   sze31      cantilever under end shear, Sze 3.1 table (model.md §8): worst over the 11
//              levels of max(|-u - ref|, |w - ref|) / 6.698
//   sze32      end moment rolling the strip into a circle, Sze 3.2 (exact): worst / 12.0
//   elastica   tip-loaded cantilever, exact elastica up to alpha = 12: worst relative error
//   ssplate    simply supported square plate, small pressure: |w_max / (0.00406 q a^4/D) - 1|
//   planewave  explicit plane wave in a strip under uniaxial strain: |c / sqrt(E/(rho(1-nu^2))) - 1|
//
// Usage: perishell_perf_accuracy_cost [--backend device|host|both] [--repeats R]
//                                     [--cases a,b,...] [--quick] [--out FILE]
//   OpenMP: OMP_NUM_THREADS=2 OMP_PROC_BIND=false ./perishell_perf_accuracy_cost --out acc.csv
// Wall time: model build to final answer, fenced, median of R repeats. A point that fails
// (Newton gives up, a deck the model rejects, an unstable run) gets error nan and its
// reason in `status`; the sweep goes on.
// Cost (OpenMP, 2 threads, a 2-core machine shared with builds): the full sweep, 37 runs,
// took 508 s and 740 s (one point 0.5 s in one run, 37 s in the other: on a shared machine
// use --repeats 3); the dearest point is PD Sze 3.2 at dx 0.125 (170-212 s). --quick: 22
// runs, about 4 min there (PD Sze 3.2 at dx 0.25 alone ~30 s).
#include <perishell/coupling/make_coupled_model.hpp>
#include <perishell/io/deck.hpp>
#include <perishell/solvers/explicit/central_difference.hpp>
#include <perishell/solvers/implicit/static_solver_from_model.hpp>
#include <perishell/solvers/model_actions.hpp>

#include <Kokkos_Core.hpp>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

namespace {

constexpr const char* program = "perishell_perf_accuracy_cost";
constexpr double pi = 3.14159265358979323846;
constexpr double nan = std::numeric_limits<double>::quiet_NaN();
const std::vector<std::string> allCases = {"sze31", "sze32", "elastica", "ssplate", "planewave"};

// ---------------------------------------------------------------------------------------------
// Command line

struct Options {
  std::string backend = "device";
  int repeats = 1;
  std::vector<std::string> cases = allCases;
  bool quick = false;
  std::string out;  // empty: stdout
};

[[noreturn]] void usage(const std::string& problem) {
  std::fprintf(stderr,
               "%s: error: %s\nusage: %s [--backend device|host|both] [--repeats R] [--cases %s] [--quick] "
               "[--out FILE]\n",
               program, problem.c_str(), program, "sze31,sze32,elastica,ssplate,planewave");
  std::exit(2);
}

std::vector<std::string> splitList(const std::string& list) {
  std::vector<std::string> items;
  for (std::size_t start = 0; start <= list.size();) {
    const auto comma = std::min(list.find(',', start), list.size());
    items.push_back(list.substr(start, comma - start));
    start = comma + 1;
  }
  return items;
}

Options parseArguments(int argc, char* argv[]) {
  Options options;
  for (int a = 1; a < argc; ++a) {
    const std::string argument = argv[a];
    if (argument.rfind("--kokkos-", 0) == 0) continue;  // Kokkos' own, read by Kokkos::initialize
    const auto value = [&]() -> std::string {
      if (a + 1 >= argc) usage(argument + " needs a value");
      return argv[++a];
    };
    if (argument == "--help" || argument == "-h") {
      std::printf("usage: %s [--backend device|host|both] [--repeats R] [--cases a,b,...] [--quick] [--out FILE]\n"
                  "  cases: sze31 sze32 elastica ssplate planewave (default all); CSV on stdout or FILE\n",
                  program);
      std::exit(0);
    } else if (argument == "--backend") {
      options.backend = value();
      if (options.backend != "device" && options.backend != "host" && options.backend != "both")
        usage("--backend: '" + options.backend + "' is not device, host or both");
    } else if (argument == "--repeats") {
      const std::string text = value();
      char* end = nullptr;
      const long repeats = std::strtol(text.c_str(), &end, 10);
      if (end == text.c_str() || *end != '\0' || repeats < 1 || repeats > 1000)
        usage("--repeats: '" + text + "' is not a whole number in [1, 1000]");
      options.repeats = static_cast<int>(repeats);
    } else if (argument == "--cases") {
      options.cases = splitList(value());
      for (const auto& name : options.cases)
        if (std::find(allCases.begin(), allCases.end(), name) == allCases.end())
          usage("--cases: unknown case '" + name + "' (sze31, sze32, elastica, ssplate, planewave)");
    } else if (argument == "--quick") {
      options.quick = true;
    } else if (argument == "--out") {
      options.out = value();
      if (options.out.empty()) usage("--out: empty file name");
    } else {
      usage("unknown option '" + argument + "'");
    }
  }
  return options;
}

// ---------------------------------------------------------------------------------------------
// Sweep points

enum class Kind { Ccm, Pd, Mixed };
const char* kindName(Kind kind) { return kind == Kind::Ccm ? "ccm" : kind == Kind::Pd ? "pd" : "mixed"; }

struct Point {
  Kind kind;
  double spacing;              // dx [m]
  double horizonFactor = 3.0;  // m = delta / dx (not used by CCM)
  double ratioTarget = 0.0;    // Kind::Mixed: zones.pd-ratio.target
  std::string forceKernel;     // explicit cases: node-gather or bond-scatter; empty for implicit ones

  bool operator==(const Point& other) const {
    return kind == other.kind && spacing == other.spacing &&
           (kind == Kind::Ccm || horizonFactor == other.horizonFactor) && ratioTarget == other.ratioTarget &&
           forceKernel == other.forceKernel;
  }
};

// One sweep: points from the cheapest to the dearest (--quick keeps the first two).
using Sweep = std::vector<Point>;

std::vector<Point> spacingSweep(Kind kind, std::vector<double> spacings, double m = 3.0, std::string kernel = "") {
  std::vector<Point> points;
  for (const double dx : spacings) points.push_back({kind, dx, m, 0.0, kernel});
  return points;
}

std::vector<Point> horizonSweep(double dx, std::vector<double> factors, std::string kernel = "") {
  std::vector<Point> points;
  for (const double m : factors) points.push_back({Kind::Pd, dx, m, 0.0, kernel});
  return points;
}

struct CaseSpec {
  std::string name, reference;
  std::vector<Sweep> sweeps;
};

std::vector<CaseSpec> caseSpecs() {
  std::vector<CaseSpec> specs;
  specs.push_back({"sze31",
                   "Sze 3.1 (ABAQUS S4R, Sze et al. 2004)",
                   {spacingSweep(Kind::Ccm, {1.0, 0.5, 0.25, 0.125}), spacingSweep(Kind::Pd, {0.5, 0.25, 0.125}),
                    horizonSweep(0.25, {2.0, 3.0, 4.0})}});
  specs.push_back({"sze32",
                   "Sze 3.2 (exact, Sze et al. 2004)",
                   {spacingSweep(Kind::Ccm, {1.0, 0.5, 0.25}), spacingSweep(Kind::Pd, {0.5, 0.25, 0.125})}});
  specs.push_back({"elastica", "exact elastica", {spacingSweep(Kind::Ccm, {1.0, 0.5, 0.25, 0.125})}});
  Sweep ratios;
  for (const double ratio : {0.0, 0.25, 0.5, 1.0}) ratios.push_back({Kind::Mixed, 0.05, 3.0, ratio, ""});
  specs.push_back({"ssplate",
                   "Kirchhoff 0.00406 q a^4/D",
                   {spacingSweep(Kind::Ccm, {0.1, 0.05, 0.025, 0.0125}), spacingSweep(Kind::Pd, {0.1, 0.05, 0.025, 0.0125}),
                    ratios}});
  // The strip is 240 x 40 mm at every spacing; the stations (80 and 160 mm on y = 20 mm) are grid nodes.
  specs.push_back({"planewave",
                   "sqrt(E/(rho(1-nu^2)))",
                   {spacingSweep(Kind::Pd, {4e-3, 2e-3, 1e-3, 0.5e-3}, 3.0, "node-gather"),
                    spacingSweep(Kind::Pd, {4e-3, 2e-3, 1e-3, 0.5e-3}, 3.0, "bond-scatter"),
                    horizonSweep(1e-3, {2.0, 3.0, 4.0}, "node-gather")}});
  return specs;
}

// ---------------------------------------------------------------------------------------------
// Decks (the patterns of tests/solvers/tstStaticNewton.hpp)

std::string number(double value) {
  char text[40];
  std::snprintf(text, sizeof text, "%.12g", value);
  std::string result = text;
  // A YAML real, not an integer (both are accepted, this only reads better in messages).
  if (result.find_first_of(".e") == std::string::npos) result += ".0";
  return result;
}

std::string zonesOf(const Point& point, const std::string& around) {
  switch (point.kind) {
    case Kind::Ccm: return "{default: ccm}";
    case Kind::Pd: return "{default: pd}";
    case Kind::Mixed:
      return "{default: ccm, pd-ratio: {target: " + number(point.ratioTarget) + ", around: {p: " + around + "}}}";
  }
  return "";
}

std::string peridynamicsOf(const Point& point) {
  return "{horizon-factor: " + number(point.horizonFactor) +
         (point.forceKernel.empty() ? "" : ", force-kernel: " + point.forceKernel) + "}";
}

perishell::model::Model stripModel(const Point& point, double length, const std::string& load,
                                   const std::string& solver) {
  const std::string text = R"(perishell:
  version: 1
  mesh: {generator: plate, length-x: )" + number(length) + R"(, length-y: 1.0, spacing: )" +
                           number(point.spacing) + R"(}
  material: {young-modulus: 1.2e6, poisson-ratio: 0.0, density: 1.0, thickness: 0.1}
  peridynamics: )" + peridynamicsOf(point) + R"(
  zones: )" + zonesOf(point, "[0.0, 0.5, 0.0]") + R"(
  supports: {clamp: {set: left, dofs: [ux, uy, uz, rx, ry, rz]}}
  loads: {tip: )" + load + R"(}
  solver: {type: implicit, )" + solver + R"(}
)";
  return perishell::model::buildModel(perishell::parseDeck(text, "strip.yaml"));
}

// Simply supported a = 1 m square (w = 0 on the edges, in-plane rigid motion held at two corners).
perishell::model::Model simplySupportedPlate(const Point& point) {
  const std::string text = R"(perishell:
  version: 1
  mesh:
    generator: plate
    length-x: 1.0
    length-y: 1.0
    spacing: )" + number(point.spacing) + R"(
    node-sets:
      origin: {box: {min: [-0.001, -0.001, -0.001], max: [0.001, 0.001, 0.001]}}
      corner-x: {box: {min: [0.999, -0.001, -0.001], max: [1.001, 0.001, 0.001]}}
  material: {young-modulus: 70.0e9, poisson-ratio: 0.3, density: 2700.0, thickness: 0.01}
  peridynamics: )" + peridynamicsOf(point) + R"(
  zones: )" + zonesOf(point, "[0.5, 0.5, 0.0]") + R"(
  supports:
    bottom: {set: bottom, dofs: [uz]}
    right: {set: right, dofs: [uz]}
    top: {set: top, dofs: [uz]}
    left: {set: left, dofs: [uz]}
    pin: {set: origin, dofs: [ux, uy]}
    roller: {set: corner-x, dofs: [uy]}
  loads: {pressure: {type: pressure, value: 1000.0}}
  solver: {type: implicit, increments: 1, tolerance: 1.0e-6}
)";
  return perishell::model::buildModel(perishell::parseDeck(text, "plate.yaml"));
}

// The plane wave of tests/solvers/tstExplicitDynamics.hpp as a deck: 240 x 40 x 1 mm, u_y (and
// every DOF but u_x) held everywhere, the left edge pushed at 0.1 m/s (a ramp of 0.1 m over 1 s).
constexpr double waveE = 70e9, waveNu = 0.33, waveRho = 2440.0, pushSpeed = 0.1;
constexpr double waveStations[2] = {80e-3, 160e-3}, waveProbeY = 20e-3;

perishell::model::Model planeWaveStrip(const Point& point, double endTime) {
  const std::string text = R"(perishell:
  version: 1
  mesh:
    generator: plate
    length-x: 0.240
    length-y: 0.040
    spacing: )" + number(point.spacing) + R"(
    node-sets:
      whole-strip: {box: {min: [-1.0, -1.0, -1.0], max: [1.0, 1.0, 1.0]}}
  material: {young-modulus: )" + number(waveE) + R"(, poisson-ratio: )" + number(waveNu) +
                           R"(, density: )" + number(waveRho) + R"(, thickness: 1.0e-3}
  peridynamics: )" + peridynamicsOf(point) + R"(
  zones: {default: pd}
  supports:
    uniaxial-strain: {set: whole-strip, dofs: [uy, uz, rx, ry, rz]}
    push: {set: left, dofs: [ux], value: )" + number(pushSpeed) + R"(, curve: ramp}
  curves: {ramp: {type: ramp, end-time: 1.0}}
  solver: {type: explicit, end-time: )" + number(endTime) + R"(}
)";
  return perishell::model::buildModel(perishell::parseDeck(text, "plane_wave.yaml"));
}

// ---------------------------------------------------------------------------------------------
// Runs

struct Outcome {
  double error = nan;
  long long freeDof = -1;  // -1: the model was not built
  double pdRatio = nan;
  std::string status = "ok";
  // Implicit cases, for the progress line: summed over the load levels.
  int newtonIterations = 0, cuts = 0;
  long long linearIterations = 0;
  void add(const perishell::solvers::IncrementReport& report) {
    newtonIterations += report.newtonIterations;
    cuts += report.cuts;
    linearIterations += report.linearIterations;
  }
};

void describe(const perishell::model::Model& model, Outcome& outcome) {
  outcome.freeDof = model.freeDofCount();
  outcome.pdRatio = model.pdRatio();
}

template <class Solver>
std::array<double, 3> meanDisplacement(const Solver& solver, const perishell::model::Model& model,
                                       const std::string& set) {
  const auto u = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, solver.kinematics().displacements);
  const auto& nodes = model.shell.sets.nodeSet(set);
  std::array<double, 3> mean{0.0, 0.0, 0.0};
  for (const auto node : nodes)
    for (int d = 0; d < 3; ++d) mean[d] += u(node, d) / nodes.size();
  return mean;
}

struct Level {
  double loadFactor, minusU, w;
};

// model.md §8, Sze 3.1 and 3.2 columns.
const std::vector<Level> sze31Levels = {{0.05, 0.026, 0.663}, {0.1, 0.103, 1.309}, {0.2, 0.381, 2.493},
                                        {0.3, 0.763, 3.488},  {0.4, 1.184, 4.292}, {0.5, 1.604, 4.933},
                                        {0.6, 2.002, 5.444},  {0.7, 2.370, 5.855}, {0.8, 2.705, 6.190},
                                        {0.9, 3.010, 6.467},  {1.0, 3.286, 6.698}};
const std::vector<Level> sze32Levels = {{0.05, 0.196, 1.870}, {0.1, 0.774, 3.648},  {0.2, 2.918, 6.598},
                                        {0.3, 5.945, 8.333},  {0.4, 9.194, 8.637},  {0.5, 12.000, 7.639},
                                        {0.6, 13.871, 5.758}, {0.7, 14.595, 3.571}, {0.8, 14.270, 1.650},
                                        {0.9, 13.247, 0.405}, {1.0, 12.000, 0.0}};

template <class Space>
double worstTipError(const perishell::model::Model& model, const std::vector<Level>& levels, double scale,
                     Outcome& outcome) {
  auto solver = perishell::solvers::makeStaticSolver(Space{}, model);
  double worst = 0.0;
  for (const auto& level : levels) {
    outcome.add(solver.advanceTo(level.loadFactor));
    const auto tip = meanDisplacement(solver, model, "right");
    worst = std::max(worst, std::max(std::abs(-tip[0] - level.minusU), std::abs(tip[2] - level.w)) / scale);
  }
  return worst;
}

template <class Space>
void runSze31(const Point& point, Outcome& outcome) {
  // End shear P_max = 4 as an edge traction over the 1 x 0.1 end section; the test's Newton settings.
  const auto model = stripModel(point, 10.0, "{type: edge-traction, set: right, vector: [0.0, 0.0, 40.0]}",
                                "increments: 20, max-iterations: 60, tolerance: 1.0e-9");
  describe(model, outcome);
  outcome.error = worstTipError<Space>(model, sze31Levels, 6.698, outcome);
}

template <class Space>
void runSze32(const Point& point, Outcome& outcome) {
  // M_max = 2 pi E I / L = 50 pi / 3 about -y, shared by the end nodes (one per dx across the 1 m width).
  const int endNodes = static_cast<int>(std::lround(1.0 / point.spacing)) + 1;
  const double momentPerNode = 50.0 * pi / 3.0 / endNodes;
  const auto model = stripModel(point, 12.0,
                                "{type: point-force, set: right, vector: [0.0, 0.0, 0.0], moment: [0.0, " +
                                    number(-momentPerNode) + ", 0.0]}",
                                "increments: 20, max-iterations: 100, tolerance: 1.0e-6");
  describe(model, outcome);
  outcome.error = worstTipError<Space>(model, sze32Levels, 12.0, outcome);
}

template <class Space>
void runElastica(const Point& point, Outcome& outcome) {
  // alpha = P L^2 / (E I) up to 12 (P = 12: 120 Pa over the 1 x 0.1 end); model.md §8 table.
  struct ElasticaLevel {
    double alpha, uOverL, wOverL;
  };
  static const std::vector<ElasticaLevel> levels = {{1, .05643, .30172}, {2, .16064, .49346}, {4, .32894, .66996},
                                                    {6, .43459, .74457}, {8, .50483, .78498}, {12, .59285, .82859}};
  const auto model = stripModel(point, 10.0, "{type: edge-traction, set: right, vector: [0.0, 0.0, 120.0]}",
                                "increments: 20, max-iterations: 60, tolerance: 1.0e-9");
  describe(model, outcome);
  auto solver = perishell::solvers::makeStaticSolver(Space{}, model);
  double worst = 0.0;
  for (const auto& level : levels) {
    outcome.add(solver.advanceTo(level.alpha / 12.0));
    const auto tip = meanDisplacement(solver, model, "right");
    worst = std::max(worst, std::hypot(-tip[0] / 10.0 - level.uOverL, tip[2] / 10.0 - level.wOverL) /
                                std::hypot(level.uOverL, level.wOverL));
  }
  outcome.error = worst;
}

template <class Space>
void runSimplySupportedPlate(const Point& point, Outcome& outcome) {
  const auto model = simplySupportedPlate(point);
  describe(model, outcome);
  auto solver = perishell::solvers::makeStaticSolver(Space{}, model);
  outcome.add(solver.advanceTo(1.0));
  const auto u = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, solver.kinematics().displacements);
  const auto& x = model.shell.mesh.coordinates;
  bool found = false;
  double centre = 0.0;
  for (perishell::LocalIndex node = 0; node < model.shell.mesh.numNodes(); ++node)
    if (std::abs(x(node, 0) - 0.5) < 1e-9 && std::abs(x(node, 1) - 0.5) < 1e-9) {
      centre = u(node, 2);
      found = true;
    }
  if (!found) throw std::runtime_error("no grid node at the plate centre");
  // w_max = 0.00406 q a^4 / D, D = E t^3 / (12 (1 - nu^2)) (model.md §8, b/a = 1).
  const double D = 70.0e9 * 1e-6 / (12.0 * (1.0 - 0.09));
  outcome.error = std::abs(centre / (0.00406 * 1000.0 / D) - 1.0);
}

template <class Space>
void runPlaneWave(const Point& point, Outcome& outcome) {
  using Memory = typename Space::memory_space;
  const Space space;
  const double expectedSpeed = std::sqrt(waveE / (waveRho * (1.0 - waveNu * waveNu)));
  const double endTime = 1.3 * waveStations[1] / expectedSpeed;
  const auto model = planeWaveStrip(point, endTime);
  describe(model, outcome);
  const auto& deck = model.deck;
  const auto bodies = perishell::coupling::makeCoupledBodies(space, model);
  perishell::solvers::ExplicitOptions options;  // as solvers/explicit_run.cpp takes them from the deck
  options.density = deck.material.density;
  options.thickness = deck.material.thickness;
  options.timeStep = deck.solver.explicitSettings.timeStep.value_or(0.0);
  options.safetyFactor = deck.solver.explicitSettings.safetyFactor;
  options.forceKernel = deck.peridynamics.forceKernel;
  perishell::solvers::CentralDifferenceSolver<Space> solver(
      space, bodies.pdBody, bodies.shellElements(), perishell::solvers::makeExternalActions<Memory>(model), options);

  perishell::LocalIndex probe[2] = {-1, -1};
  const auto& x = model.shell.mesh.coordinates;
  for (perishell::LocalIndex node = 0; node < model.shell.mesh.numNodes(); ++node)
    for (int s = 0; s < 2; ++s)
      if (std::abs(x(node, 0) - waveStations[s]) < 1e-9 && std::abs(x(node, 1) - waveProbeY) < 1e-9) probe[s] = node;
  if (probe[0] < 0 || probe[1] < 0) throw std::runtime_error("no grid node at the stations x = 80, 160 mm");

  // Arrival of the front (half the push speed), interpolated between half steps (as the test).
  double arrival[2] = {0.0, 0.0}, previous[2] = {0.0, 0.0};
  while (solver.time() < endTime && arrival[1] == 0.0) {
    solver.step();
    for (int s = 0; s < 2; ++s) {
      double v = 0.0;
      Kokkos::deep_copy(v, Kokkos::subview(solver.velocities(), probe[s], 0));
      if (arrival[s] == 0.0 && v >= 0.5 * pushSpeed)
        arrival[s] = solver.time() - 0.5 * solver.timeStep() -
                     solver.timeStep() * (v - 0.5 * pushSpeed) / (v - previous[s]);
      previous[s] = v;
    }
  }
  if (arrival[0] == 0.0 || arrival[1] == 0.0)
    throw std::runtime_error("the front did not reach x = 160 mm by 1.3 x its expected arrival");
  const double measured = (waveStations[1] - waveStations[0]) / (arrival[1] - arrival[0]);
  outcome.error = std::abs(measured / expectedSpeed - 1.0);
}

template <class Space>
void runPoint(const std::string& caseName, const Point& point, Outcome& outcome) {
  if (caseName == "sze31") runSze31<Space>(point, outcome);
  else if (caseName == "sze32") runSze32<Space>(point, outcome);
  else if (caseName == "elastica") runElastica<Space>(point, outcome);
  else if (caseName == "ssplate") runSimplySupportedPlate<Space>(point, outcome);
  else runPlaneWave<Space>(point, outcome);
}

// One line, without the CSV's separators' worries (csvField quotes it).
std::string oneLine(std::string text, std::size_t limit = 200) {
  std::replace(text.begin(), text.end(), '\n', ' ');
  std::replace(text.begin(), text.end(), '\r', ' ');
  if (text.size() > limit) text = text.substr(0, limit - 3) + "...";
  return text;
}

// ---------------------------------------------------------------------------------------------
// CSV

std::string csvField(const std::string& text) {
  if (text.find_first_of(",\"\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (const char c : text) quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  return quoted + "\"";
}

std::string format(const char* pattern, double value) {
  if (std::isnan(value)) return "nan";
  char text[64];
  std::snprintf(text, sizeof text, pattern, value);
  return text;
}

class CsvOutput {
 public:
  explicit CsvOutput(const std::string& path) : path_(path) {
    if (path_.empty()) {
      file_ = stdout;
    } else {
      file_ = std::fopen((path_ + ".tmp").c_str(), "w");
      if (!file_) {
        std::fprintf(stderr, "%s: error: --out: cannot write %s.tmp: %s\n", program, path_.c_str(),
                     std::strerror(errno));
        std::exit(1);
      }
    }
    std::fputs("case,reference,backend,model,spacing_m,horizon_factor,pd_ratio,force_kernel,free_dof,repeats,"
               "wall_seconds,error,status\n",
               file_);
    std::fflush(file_);
  }
  void row(const std::vector<std::string>& fields) {
    for (std::size_t k = 0; k < fields.size(); ++k) {
      if (k > 0) std::fputc(',', file_);
      std::fputs(csvField(fields[k]).c_str(), file_);
    }
    std::fputc('\n', file_);
    std::fflush(file_);
  }
  // Renames FILE.tmp to FILE: readers never see a half-written FILE.
  void finish() {
    if (path_.empty()) return;
    const bool written = std::fclose(file_) == 0;
    if (!written || std::rename((path_ + ".tmp").c_str(), path_.c_str()) != 0) {
      std::fprintf(stderr, "%s: error: --out: cannot move %s.tmp to %s: %s\n", program, path_.c_str(), path_.c_str(),
                   std::strerror(errno));
      std::exit(1);
    }
    std::fprintf(stderr, "wrote %s\n", path_.c_str());
  }

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
};

struct Job {
  const CaseSpec* spec;
  Point point;
};

std::vector<Job> jobsFor(const Options& options, const std::vector<CaseSpec>& specs) {
  std::vector<Job> jobs;
  for (const auto& name : options.cases)
    for (const auto& spec : specs) {
      if (spec.name != name) continue;
      std::vector<Point> points;
      for (const auto& sweep : spec.sweeps)
        for (std::size_t k = 0; k < sweep.size() && (!options.quick || k < 2); ++k)
          if (std::find(points.begin(), points.end(), sweep[k]) == points.end()) points.push_back(sweep[k]);
      for (const auto& point : points) jobs.push_back({&spec, point});
    }
  return jobs;
}

template <class Space>
void runAll(const std::string& role, const std::vector<Job>& jobs, const Options& options, CsvOutput& csv,
            int& done, int total) {
  const std::string backend = std::string(Space::name()) + " (" + role + ")";
  for (const auto& job : jobs) {
    const auto& point = job.point;
    std::vector<double> seconds;
    Outcome outcome;
    for (int r = 0; r < options.repeats; ++r) {
      outcome = Outcome{};
      Kokkos::fence();
      const auto start = std::chrono::steady_clock::now();
      try {
        runPoint<Space>(job.spec->name, point, outcome);
      } catch (const perishell::solvers::NewtonFailure& failure) {
        outcome.status = "failed: Newton: " + oneLine(failure.what());
      } catch (const perishell::solvers::ExplicitInstability& failure) {
        outcome.status = "failed: unstable: " + oneLine(failure.what());
      } catch (const perishell::DeckError& failure) {
        outcome.status = "failed: deck: " + oneLine(failure.what());
      } catch (const std::exception& failure) {
        outcome.status = "failed: " + oneLine(failure.what());
      }
      Kokkos::fence();
      seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
      if (outcome.status != "ok") {
        outcome.error = nan;
        break;  // deterministic: the other repeats would fail alike; the time is that of the failed run
      }
      if (!std::isfinite(outcome.error)) {
        outcome.status = "failed: non-finite error";
        outcome.error = nan;
        break;
      }
    }
    std::sort(seconds.begin(), seconds.end());
    const double wall = seconds[seconds.size() / 2];
    const bool pd = point.kind != Kind::Ccm;
    csv.row({job.spec->name, job.spec->reference, backend, kindName(point.kind), format("%.6g", point.spacing),
             pd ? format("%g", point.horizonFactor) : "", format("%.4f", outcome.pdRatio), point.forceKernel,
             outcome.freeDof >= 0 ? std::to_string(outcome.freeDof) : "", std::to_string(seconds.size()),
             format("%.6e", wall), format("%.6e", outcome.error), outcome.status});
    ++done;
    const std::string solverNote =
        outcome.newtonIterations > 0
            ? " (" + std::to_string(outcome.newtonIterations) + " Newton, " + std::to_string(outcome.cuts) + " cuts, " +
                  std::to_string(outcome.linearIterations) + " linear iterations)"
            : "";
    std::fprintf(stderr, "[%d/%d] %-9s %-5s dx %-7g%s%s%s on %s: %.3f s%s, error %s%s%s\n", done, total,
                 job.spec->name.c_str(), kindName(point.kind), point.spacing,
                 pd ? (" m " + format("%g", point.horizonFactor)).c_str() : "",
                 point.kind == Kind::Mixed ? (" ratio " + format("%g", point.ratioTarget)).c_str() : "",
                 point.forceKernel.empty() ? "" : (" " + point.forceKernel).c_str(), backend.c_str(), wall,
                 solverNote.c_str(),
                 format("%.3e", outcome.error).c_str(), outcome.status == "ok" ? "" : " -- ",
                 outcome.status == "ok" ? "" : outcome.status.c_str());
  }
}

}  // namespace

int main(int argc, char* argv[]) {
  const Options options = parseArguments(argc, argv);
  Kokkos::ScopeGuard kokkos(argc, argv);
  using Device = Kokkos::DefaultExecutionSpace;
  using Host = Kokkos::DefaultHostExecutionSpace;
  constexpr bool distinct = !std::is_same_v<Device, Host>;
  const bool runDevice = options.backend != "host";
  // One space in an OpenMP-only build: `both` runs it once, as the device.
  const bool runHost = options.backend == "host" || (options.backend == "both" && distinct);

  const auto specs = caseSpecs();
  const auto jobs = jobsFor(options, specs);
  const int total = static_cast<int>(jobs.size()) * (int(runDevice) + int(runHost));
  std::fprintf(stderr, "%s: %d runs (%s%s), %d repeat(s) each%s\n", program, total, runDevice ? Device::name() : "",
               runHost ? (std::string(runDevice ? " and " : "") + Host::name() + " host").c_str() : "",
               options.repeats, options.quick ? ", --quick" : "");
  CsvOutput csv(options.out);
  const auto start = std::chrono::steady_clock::now();
  int done = 0;
  if (runDevice) runAll<Device>("device", jobs, options, csv, done, total);
  if (runHost) runAll<Host>("host", jobs, options, csv, done, total);
  csv.finish();
  std::fprintf(stderr, "%s: %d runs in %.1f s\n", program, total,
               std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  return 0;
}
