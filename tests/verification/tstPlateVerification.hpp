// Verification against analytic plate solutions where supports act on PD regions
// (docs/verification.md): the clamped square plate under uniform pressure, 100 % PD and
// with a PD zone around the centre, with and without the support layer
// (mesh/support_layer.hpp), and the sum of reactions against the applied load.
#include <perishell/io/deck.hpp>
#include <perishell/solvers/implicit/static_solver_from_model.hpp>

#include <cmath>
#include <cstdio>
#include <string>

namespace plate_verification_test {

// Clamped square plate, a = 1 m, t = 10 mm, nu = 0.3, q = 1 kPa: w_max = 0.00126532 q a^4 / D
// (Taylor & Govindjee, "Solution of clamped rectangular plate problems", Commun. Numer.
// Meth. Engng 20 (2004) 757-765; Timoshenko & Woinowsky-Krieger, Table 35: 0.00126). The
// deflection is 0.7 % of t: the linear range.
constexpr double youngModulus = 210.0e9, poissonRatio = 0.3, thickness = 0.01, pressure = 1000.0;

perishell::model::Model clampedPlate(int cells, const std::string& zones, const std::string& peridynamics = "{}") {
  const std::string text = R"(perishell:
  version: 1
  mesh: {generator: plate, length-x: 1.0, length-y: 1.0, spacing: )" +
                           std::to_string(1.0 / cells) + R"(}
  material: {young-modulus: 210.0e9, poisson-ratio: 0.3, density: 7850.0, thickness: 0.01}
  peridynamics: )" + peridynamics + R"(
  zones: )" + zones + R"(
  supports:
    left: {set: left, dofs: [ux, uy, uz, rx, ry, rz]}
    right: {set: right, dofs: [ux, uy, uz, rx, ry, rz]}
    bottom: {set: bottom, dofs: [ux, uy, uz, rx, ry, rz]}
    top: {set: top, dofs: [ux, uy, uz, rx, ry, rz]}
  loads: {q: {type: pressure, value: 1000.0}}
  solver: {type: implicit, increments: 1, tolerance: 1.0e-10, preconditioner: cholesky}
)";
  return perishell::model::buildModel(perishell::parseDeck(text, "clamped_plate.yaml"));
}

struct PlateResult {
  double relativeError;  // of the centre deflection
  double reactionZ;      // sum of the z out-of-balance force over the prescribed nodes [N]
};

PlateResult solveClampedPlate(const perishell::model::Model& model, const char* label) {
  auto solver = perishell::solvers::makeStaticSolver(TEST_EXECSPACE{}, model);
  solver.advanceTo(1.0);
  const auto u = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, solver.kinematics().displacements);
  const auto r = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, solver.outOfBalance());
  const auto& x = model.shell.mesh.coordinates;
  double centre = 0.0, reaction = 0.0;
  for (perishell::LocalIndex node = 0; node < model.numMeshNodes(); ++node)
    if (std::abs(x(node, 0) - 0.5) < 1e-9 && std::abs(x(node, 1) - 0.5) < 1e-9) centre = u(node, 2);
  std::vector<std::uint8_t> held(model.shell.mesh.numNodes(), 0);
  for (const auto& support : model.deck.supports)
    for (const auto node : model.supportNodes(support)) held[node] = 1;
  for (perishell::LocalIndex node = 0; node < model.shell.mesh.numNodes(); ++node)
    if (held[node]) reaction -= r(node, 2);
  const double D = youngModulus * thickness * thickness * thickness / (12.0 * (1.0 - poissonRatio * poissonRatio));
  const double reference = 0.00126532 * pressure / D;
  const double error = centre / reference - 1.0;
  std::printf("%s: w_max %.6e m, reference %.6e m, error %+.2f %%, reactions %.6f N of %.1f N\n", label, centre,
              reference, 100.0 * error, -reaction, pressure);
  return {error, reaction};
}

}  // namespace plate_verification_test

TEST(TEST_CATEGORY, clamped_plate_pd_converges_with_the_support_layer) {
  using namespace plate_verification_test;
  const auto coarse = solveClampedPlate(clampedPlate(20, "{default: pd}"), "clamped plate 100 % PD a/20");
  const auto fine = solveClampedPlate(clampedPlate(40, "{default: pd}"), "clamped plate 100 % PD a/40");
  EXPECT_LT(std::abs(coarse.relativeError), 0.03);
  EXPECT_LT(std::abs(fine.relativeError), 0.01);
  EXPECT_LT(std::abs(fine.relativeError), 0.5 * std::abs(coarse.relativeError));  // converging
  // Every newton of the pressure reaches a support, the layer's included.
  EXPECT_NEAR(-coarse.reactionZ, pressure, 1e-8 * pressure);
  EXPECT_NEAR(-fine.reactionZ, pressure, 1e-8 * pressure);
}

TEST(TEST_CATEGORY, clamped_plate_pd_without_the_layer_is_soft) {
  using namespace plate_verification_test;
  // The edge row alone held: the PD nodes near the clamp see a free surface (first order in
  // delta / a; 23 % at a/20). The layer is what the previous test measures.
  const auto result = solveClampedPlate(clampedPlate(20, "{default: pd}", "{support-layer: false}"),
                                        "clamped plate 100 % PD a/20, no support layer");
  EXPECT_GT(result.relativeError, 0.15);
  EXPECT_NEAR(-result.reactionZ, pressure, 1e-8 * pressure);
}

TEST(TEST_CATEGORY, clamped_plate_with_a_pd_centre) {
  using namespace plate_verification_test;
  // Half the elements PD around the centre, CCM at the clamps.
  const auto result = solveClampedPlate(
      clampedPlate(40, "{default: ccm, pd-regions: {centre: {box: {min: [0.1464, 0.1464, -1.0], max: [0.8536, 0.8536, 1.0]}}}}"),
      "clamped plate 50 % PD around the centre a/40");
  EXPECT_LT(std::abs(result.relativeError), 0.03);
  EXPECT_NEAR(-result.reactionZ, pressure, 1e-8 * pressure);
}

TEST(TEST_CATEGORY, clamped_plate_ccm) {
  using namespace plate_verification_test;
  const auto result = solveClampedPlate(clampedPlate(20, "{default: ccm}"), "clamped plate CCM a/20");
  EXPECT_LT(std::abs(result.relativeError), 0.01);
  EXPECT_NEAR(-result.reactionZ, pressure, 1e-8 * pressure);
}
