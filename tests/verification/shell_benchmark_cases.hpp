#pragma once
// The MacNeal-Harder linear shell benchmarks on curved and warped meshes (docs/verification.md):
// MacNeal & Harder, "A proposed standard set of problems to test finite element accuracy",
// Finite Elements in Analysis and Design 1 (1985) 3-20, whose reference values these are.
// Each case is meshed as a structured Gmsh grid and solved by the implicit solver under a
// load small enough for the geometrically nonlinear model to answer the linear problem; the
// displacement is scaled back by that factor.
#include <harness/scratch_directory.hpp>
#include <harness/structured_gmsh.hpp>
#include <perishell/io/deck.hpp>
#include <perishell/solvers/implicit/static_solver_from_model.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>

namespace shell_benchmarks_test {

constexpr double pi = 3.14159265358979323846;

struct Benchmark {
  std::string name;
  perishell_test::StructuredGmshGrid grid;
  std::string material;   // the deck's material map
  std::string actions;    // supports and loads
  double spacing;         // the deck's nominal mesh.spacing
  std::array<double, 3> probe;
  int component;          // of the displacement at the probe
  double sign, loadScale, reference;
};

// Returns (ours / reference) for the probe's displacement component.
double solve(const Benchmark& benchmark, const std::string& zones = "{default: ccm}") {
  perishell_test::ScratchDirectory directory("perishell_shell_benchmark");
  const std::string mesh = directory / "mesh.msh";
  benchmark.grid.write(mesh);
  const std::string text = "perishell:\n  version: 1\n  mesh: {generator: gmsh, file: " + mesh +
                           ", spacing: " + std::to_string(benchmark.spacing) + "}\n  material: " + benchmark.material +
                           "\n  zones: " + zones + "\n" + benchmark.actions +
                           "  solver: {type: implicit, increments: 1, preconditioner: cholesky}\n";
  const auto model = perishell::model::buildModel(perishell::parseDeck(text, benchmark.name + ".yaml"));
  auto solver = perishell::solvers::makeStaticSolver(TEST_EXECSPACE{}, model);
  solver.advanceTo(1.0);
  const auto u = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, solver.kinematics().displacements);
  const auto& x = model.shell.mesh.coordinates;
  perishell::LocalIndex nearest = 0;
  double nearestDistance = 1e300;
  for (perishell::LocalIndex node = 0; node < model.numMeshNodes(); ++node) {
    double distance = 0.0;
    for (int d = 0; d < 3; ++d) distance += std::pow(x(node, d) - benchmark.probe[d], 2);
    if (distance < nearestDistance) nearestDistance = distance, nearest = node;
  }
  EXPECT_LT(std::sqrt(nearestDistance), 1e-9 * benchmark.spacing) << "the probe is a mesh node";
  const double value = benchmark.sign * u(nearest, benchmark.component) / benchmark.loadScale;
  std::printf("%s (%s): %.6g, reference %.6g, ratio %.4f\n", benchmark.name.c_str(), zones.c_str(), value,
              benchmark.reference, value / benchmark.reference);
  return value / benchmark.reference;
}

// Scordelis-Lo roof: R 25, L 50, 80-degree arc, t 0.25, E 4.32e8, nu 0, self-weight 90 per unit
// area; ends on rigid diaphragms (uy = uz = 0), long edges free. A quarter, n x n: x from the
// diaphragm to midspan, the arc from the crown to the free edge. Reference: the vertical
// deflection at the midspan of the free edge, 0.3024.
// `split` selects cells meshed as two triangles (StructuredGmshGrid::splitIntoTriangles).
Benchmark scordelisLoRoof(int n, std::function<bool(int, int)> split = {}, const std::string& meshing = "") {
  const double angle = 40.0 * pi / 180.0;
  perishell_test::StructuredGmshGrid grid(n, n, [angle](double a, double b) {
    return std::array<double, 3>{25.0 * a, 25.0 * std::sin(angle * b), 25.0 * std::cos(angle * b)};
  });
  if (split) grid.splitIntoTriangles(split);
  grid.addLine("diaphragm", 0, 0, 0, n);
  grid.addLine("midspan", n, 0, n, n);
  grid.addLine("crown", 0, 0, n, 0);
  return {"Scordelis-Lo roof " + std::to_string(n) + "x" + std::to_string(n) + meshing, grid,
          "{young-modulus: 4.32e8, poisson-ratio: 0.0, density: 1.0, thickness: 0.25}",
          "  supports:\n"
          "    diaphragm: {set: diaphragm, dofs: [uy, uz]}\n"
          "    symmetryX: {set: midspan, dofs: [ux, ry, rz]}\n"
          "    symmetryY: {set: crown, dofs: [uy, rx, rz]}\n"
          "  loads: {weight: {type: pressure, vector: [0.0, 0.0, -0.09]}}\n",
          25.0 / n, {25.0, 25.0 * std::sin(angle), 25.0 * std::cos(angle)}, 2, -1.0, 1e-3, 0.3024};
}

// The whole roof, 2n x 2n (a quarter's spacing at n): PD has no mirror image across a symmetry
// plane (docs/verification.md), so its roof is the whole shell; one crown node holds ux.
Benchmark scordelisLoWholeRoof(int n) {
  const double angle = 40.0 * pi / 180.0;
  perishell_test::StructuredGmshGrid grid(2 * n, 2 * n, [angle](double a, double b) {
    return std::array<double, 3>{50.0 * a, 25.0 * std::sin(angle * (2.0 * b - 1.0)),
                                 25.0 * std::cos(angle * (2.0 * b - 1.0))};
  });
  grid.addLine("diaphragm0", 0, 0, 0, 2 * n);
  grid.addLine("diaphragm1", 2 * n, 0, 2 * n, 2 * n);
  grid.addPoint("crown", n, n);
  return {"Scordelis-Lo whole roof " + std::to_string(2 * n) + "x" + std::to_string(2 * n), grid,
          "{young-modulus: 4.32e8, poisson-ratio: 0.0, density: 1.0, thickness: 0.25}",
          "  supports:\n"
          "    diaphragm0: {set: diaphragm0, dofs: [uy, uz]}\n"
          "    diaphragm1: {set: diaphragm1, dofs: [uy, uz]}\n"
          "    axial: {set: crown, dofs: [ux]}\n"
          "  loads: {weight: {type: pressure, vector: [0.0, 0.0, -0.09]}}\n",
          25.0 / n, {25.0, 25.0 * std::sin(angle), 25.0 * std::cos(angle)}, 2, -1.0, 1e-3, 0.3024};
}

// Pinched hemisphere with an 18-degree hole: R 10, t 0.04, E 6.825e7, nu 0.3, radial forces 2
// (alternately out and in) at four points of the equator. A quarter with symmetry planes, the
// force halved on each plane's point. Reference: the radial displacement at the forces, 0.094.
// `split` as for scordelisLoRoof.
Benchmark pinchedHemisphere(int n, std::function<bool(int, int)> split = {}, const std::string& meshing = "") {
  const double hole = 18.0 * pi / 180.0;
  perishell_test::StructuredGmshGrid grid(n, n, [hole](double a, double b) {
    const double polar = hole + a * (0.5 * pi - hole), azimuth = 0.5 * pi * b;
    return std::array<double, 3>{10.0 * std::sin(polar) * std::cos(azimuth), 10.0 * std::sin(polar) * std::sin(azimuth),
                                 10.0 * std::cos(polar)};
  });
  if (split) grid.splitIntoTriangles(split);
  grid.addLine("y0", 0, 0, n, 0);
  grid.addLine("x0", 0, n, n, n);
  grid.addPoint("A", n, 0);
  grid.addPoint("B", n, n);
  grid.addPoint("pin", 0, 0);
  return {"pinched hemisphere " + std::to_string(n) + "x" + std::to_string(n) + meshing, grid,
          "{young-modulus: 6.825e7, poisson-ratio: 0.3, density: 1.0, thickness: 0.04}",
          "  supports:\n"
          "    symmetryY: {set: y0, dofs: [uy, rx, rz]}\n"
          "    symmetryX: {set: x0, dofs: [ux, ry, rz]}\n"
          "    pin: {set: pin, dofs: [uz]}\n"
          "  loads:\n"
          "    pull: {type: point-force, set: A, vector: [1.0e-3, 0.0, 0.0]}\n"
          "    push: {type: point-force, set: B, vector: [0.0, -1.0e-3, 0.0]}\n",
          0.98 * 16 / n, {10.0, 0.0, 0.0}, 0, 1.0, 1e-3, 0.094};
}

// Pinched cylinder with rigid end diaphragms: R 300, L 600, t 3, E 3e6, nu 0.3, two opposite
// radial forces 1 at midspan. One eighth, n x n: x from a diaphragm to midspan, a quarter of
// the circumference; force 1/4. Reference: the radial displacement under the force, 1.8248e-5
// (linear at the full load: 6e-6 of the thickness).
Benchmark pinchedCylinder(int n) {
  perishell_test::StructuredGmshGrid grid(n, n, [](double a, double b) {
    return std::array<double, 3>{300.0 * a, 300.0 * std::sin(0.5 * pi * b), 300.0 * std::cos(0.5 * pi * b)};
  });
  grid.addLine("diaphragm", 0, 0, 0, n);
  grid.addLine("midspan", n, 0, n, n);
  grid.addLine("y0", 0, 0, n, 0);
  grid.addLine("z0", 0, n, n, n);
  grid.addPoint("load", n, 0);
  return {"pinched cylinder " + std::to_string(n) + "x" + std::to_string(n), grid,
          "{young-modulus: 3.0e6, poisson-ratio: 0.3, density: 1.0, thickness: 3.0}",
          "  supports:\n"
          "    diaphragm: {set: diaphragm, dofs: [uy, uz]}\n"
          "    symmetryX: {set: midspan, dofs: [ux, ry, rz]}\n"
          "    symmetryY: {set: y0, dofs: [uy, rx, rz]}\n"
          "    symmetryZ: {set: z0, dofs: [uz, rx, ry]}\n"
          "  loads: {pinch: {type: point-force, set: load, vector: [0.0, 0.0, -0.25]}}\n",
          300.0 / n, {300.0, 0.0, 300.0}, 2, -1.0, 1.0, 1.8248e-5};
}

// Twisted beam: L 12, width 1.1, t 0.32, twisted 90 degrees from root to tip, E 29e6, nu 0.22,
// clamped root, a unit tip force spread over the tip edge (an edge traction over its section).
// 12 x 2. Reference tip deflection along the force: 5.424e-3 for a force along the root's
// normal (z), 1.754e-3 along the root's width (y).
Benchmark twistedBeam(int component) {
  perishell_test::StructuredGmshGrid grid(12, 2, [](double a, double b) {
    const double twist = 0.5 * pi * a;
    return std::array<double, 3>{12.0 * a, 1.1 * (b - 0.5) * std::cos(twist), 1.1 * (b - 0.5) * std::sin(twist)};
  });
  grid.addLine("root", 0, 0, 0, 2);
  grid.addLine("tip", 12, 0, 12, 2);
  const std::string traction = std::to_string(1e-3 / (1.1 * 0.32));
  const std::string vector = component == 2 ? "[0.0, 0.0, " + traction + "]" : "[0.0, " + traction + ", 0.0]";
  return {std::string("twisted beam, tip force along ") + (component == 2 ? "z" : "y"), grid,
          "{young-modulus: 29.0e6, poisson-ratio: 0.22, density: 1.0, thickness: 0.32}",
          "  supports: {root: {set: root, dofs: [ux, uy, uz, rx, ry, rz]}}\n"
          "  loads: {tip: {type: edge-traction, set: tip, vector: " + vector + "}}\n",
          1.0, {12.0, 0.0, 0.0}, component, 1.0, 1e-3, component == 2 ? 5.424e-3 : 1.754e-3};
}

}  // namespace shell_benchmarks_test
