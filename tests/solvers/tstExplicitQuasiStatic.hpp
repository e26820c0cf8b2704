// Explicit statics by slow loading with damping (docs/explicit.md): Sze, Liu & Lo's
// cantilever under end shear (3.1, model.md §8) with the explicit solver's one-point shell
// element, the load ramped to P_max/2 and to P_max with holds in between, against the
// reference tip displacements; the same deck with MITC4 elements for comparison.
#include <perishell/coupling/make_coupled_model.hpp>
#include <perishell/io/deck.hpp>
#include <perishell/solvers/explicit/central_difference.hpp>
#include <perishell/solvers/model_actions.hpp>

#include <cmath>
#include <cstdio>
#include <string>

namespace explicit_quasi_static_test {

using perishell::LocalIndex;

// The strip L = 10, b = 1, t = 0.1, E = 1.2e6, nu = 0, clamped at x = 0, end shear P_max = 4
// as an edge traction over the 1 x 0.1 end section. The load factor ramps 0 -> 0.5 over 8 s,
// holds 6 s, ramps to 1 over 8 s and holds 6 s; the first bending period is 5.6 s and the
// damping 2 /s is about critical for it, so each hold ends at rest.
perishell::model::Model sze31Model(const std::string& shellElement) {
  const std::string text = R"(perishell:
  version: 1
  mesh: {generator: plate, length-x: 10.0, length-y: 1.0, spacing: 0.5}
  material: {young-modulus: 1.2e6, poisson-ratio: 0.0, density: 1.0, thickness: 0.1}
  zones: {default: ccm}
  supports: {clamp: {set: left, dofs: [ux, uy, uz, rx, ry, rz]}}
  loads: {tip: {type: edge-traction, set: right, vector: [0.0, 0.0, 40.0], curve: slow}}
  curves: {slow: {type: table, time: [0.0, 8.0, 14.0, 22.0, 28.0], value: [0.0, 0.5, 0.5, 1.0, 1.0]}}
  solver: {type: explicit, end-time: 28.0, damping: 2.0, shell-element: )" +
                           shellElement + R"(}
)";
  return perishell::model::buildModel(perishell::parseDeck(text, "sze31-explicit.yaml"));
}

struct TipAtHolds {
  double half[2], full[2];  // (-u, w) of the loaded end at the end of each hold
  double largestHourglassShare = 0.0;
};

TipAtHolds runSze31(const std::string& shellElement) {
  using Memory = TEST_EXECSPACE::memory_space;
  const auto model = sze31Model(shellElement);
  const auto bodies = perishell::coupling::makeCoupledBodies(TEST_EXECSPACE{}, model);
  perishell::solvers::ExplicitOptions options;
  options.density = model.deck.material.density;
  options.thickness = model.deck.material.thickness;
  options.damping = model.deck.solver.explicitSettings.damping;
  perishell::solvers::CentralDifferenceSolver<TEST_EXECSPACE> solver(
      TEST_EXECSPACE{}, bodies.pdBody, bodies.shellElements(), perishell::solvers::makeExternalActions<Memory>(model),
      options);
  const auto& tipNodes = model.shell.sets.nodeSet("right");
  const auto tip = [&](double out[2]) {
    const auto u = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, solver.kinematics().displacements);
    out[0] = out[1] = 0.0;
    for (const auto node : tipNodes) {
      out[0] -= u(node, 0) / tipNodes.size();
      out[1] += u(node, 2) / tipNodes.size();
    }
  };
  TipAtHolds result{};
  while (solver.time() < 14.0) {
    solver.step();
    const auto& e = solver.lastEnergyReport();
    if (e.strain > 0.0) result.largestHourglassShare = std::max(result.largestHourglassShare, e.hourglass / e.strain);
  }
  tip(result.half);
  while (solver.time() < 28.0) solver.step();
  tip(result.full);
  std::printf("Sze 3.1 explicit, %s elements, %lld steps of %.3e s: P/Pmax 0.5: -u %.4f (ref 1.604), w %.4f (ref "
              "4.933); 1.0: -u %.4f (ref 3.286), w %.4f (ref 6.698); peak hourglass / strain %.2e\n",
              shellElement.c_str(), solver.stepIndex(), solver.timeStep(), result.half[0], result.half[1],
              result.full[0], result.full[1], result.largestHourglassShare);
  return result;
}

}  // namespace explicit_quasi_static_test

TEST(TEST_CATEGORY, explicit_quasi_static_sze_cantilever_under_end_shear) {
  using namespace explicit_quasi_static_test;
  for (const std::string element : {"one-point", "mitc4"}) {
    const TipAtHolds tip = runSze31(element);
    // 2 % of the final tip deflection, as the implicit test of the same table.
    const double scale = 6.698;
    EXPECT_NEAR(tip.half[0], 1.604, 0.02 * scale) << element;
    EXPECT_NEAR(tip.half[1], 4.933, 0.02 * scale) << element;
    EXPECT_NEAR(tip.full[0], 3.286, 0.02 * scale) << element;
    EXPECT_NEAR(tip.full[1], 6.698, 0.02 * scale) << element;
    if (element == "one-point") EXPECT_LT(tip.largestHourglassShare, 0.01);
  }
}
