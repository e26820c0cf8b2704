// Verification against analytic plate solutions where supports act on PD regions
// (docs/verification.md): the clamped square plate under uniform pressure, 100 % PD and
// with a PD zone around the centre, with and without the support layer
// (mesh/support_layer.hpp), and the sum of reactions against the applied load; and a slit
// ring (two coincident mesh edges) where PD must agree with CCM.
#include <perishell/coupling/make_coupled_model.hpp>
#include <perishell/solvers/explicit/central_difference.hpp>
#include <perishell/solvers/model_actions.hpp>
#include <verification/clamped_plate.hpp>

#include <algorithm>
#include <utility>
#include <vector>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <array>
#include <string>

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

// The quarter with two symmetry planes: their mirrored layers (assembly/mirror_images.hpp)
// give the PD nodes next to the planes the bonds of the material beyond them, so the quarter
// answers as the whole plate does at the same spacing.
TEST(TEST_CATEGORY, quarter_clamped_plate_pd_mirrors_the_whole_plate) {
  using namespace plate_verification_test;
  const auto whole = solveClampedPlate(clampedPlate(40, "{default: pd}"), "clamped plate 100 % PD a/40");
  const auto quarterModel = quarterClampedPlate(40, "{default: pd}");
  ASSERT_EQ(quarterModel.supportLayer.mirroredNodesOfSet.size(), 2u);
  const auto quarter = solveClampedPlate(quarterModel, "its quarter, two symmetry planes mirrored");
  EXPECT_NEAR(quarter.relativeError, whole.relativeError, 0.003);
  EXPECT_LT(std::abs(quarter.relativeError), 0.01);
  // The images carry no z force of their own (w is even across a symmetry plane): a quarter of
  // the load reaches the clamps.
  EXPECT_NEAR(-quarter.reactionZ, 0.25 * pressure, 1e-8 * pressure);
}

// The same quarter, explicit: under a suddenly applied pressure its centre follows the whole
// plate's over the first swing, and the energy balance holds with the images' forces
// condensed onto their masters.
TEST(TEST_CATEGORY, quarter_clamped_plate_pd_explicit_follows_the_whole_plate) {
  using namespace plate_verification_test;
  using Memory = TEST_EXECSPACE::memory_space;
  const auto centreHistory = [](const perishell::model::Model& model, double timeStep, int steps, double& balance) {
    const auto bodies = perishell::coupling::makeCoupledBodies(TEST_EXECSPACE{}, model);
    perishell::solvers::ExplicitOptions options;
    options.density = model.deck.material.density;
    options.thickness = model.deck.material.thickness;
    options.timeStep = timeStep;
    perishell::solvers::CentralDifferenceSolver<TEST_EXECSPACE> solver(
        TEST_EXECSPACE{}, bodies.pdBody, bodies.shellElements(), perishell::solvers::makeExternalActions<Memory>(model),
        options);
    const auto& x = model.shell.mesh.coordinates;
    perishell::LocalIndex centre = -1;
    for (perishell::LocalIndex node = 0; node < model.numMeshNodes(); ++node)
      if (std::abs(x(node, 0) - 0.5) < 1e-9 && std::abs(x(node, 1) - 0.5) < 1e-9) centre = node;
    std::vector<double> history;
    for (int step = 1; step <= steps; ++step) {
      solver.step();
      if (step % (steps / 4) == 0) {
        const auto u = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, solver.kinematics().displacements);
        history.push_back(u(centre, 2));
      }
    }
    const auto energies = solver.energies();
    balance = energies.balanceError();
    return std::make_pair(history, solver.criticalTimeStep());
  };
  const std::string solver = "{type: explicit, steps: 1}";
  double wholeBalance = 0.0, quarterBalance = 0.0;
  // First bending period of the clamped plate: 2 pi / (35.99 / a^2 sqrt(D / rho t)) = 11 ms.
  const double timeStep = 1.0e-6;
  const int steps = 6000;  // the first half period and a little more
  const auto whole = centreHistory(clampedPlateModel("{generator: plate, length-x: 1.0, length-y: 1.0, spacing: 0.05}",
                                                     "{default: pd}", "{}", fourClamps, solver),
                                   timeStep, steps, wholeBalance);
  const auto quarter = centreHistory(quarterClampedPlate(20, "{default: pd}", solver), timeStep, steps, quarterBalance);
  ASSERT_LT(timeStep, 0.8 * std::min(whole.second, quarter.second));
  ASSERT_EQ(whole.first.size(), quarter.first.size());
  const double peak = *std::max_element(whole.first.begin(), whole.first.end());
  for (std::size_t k = 0; k < whole.first.size(); ++k) {
    std::printf("t = %.1f ms: centre w whole %.6e m, quarter %.6e m\n", 1e3 * timeStep * steps * (k + 1) / 4.0,
                whole.first[k], quarter.first[k]);
    EXPECT_NEAR(quarter.first[k], whole.first[k], 0.005 * peak);
  }
  std::printf("energy balance error: whole %.2e, quarter %.2e\n", wholeBalance, quarterBalance);
  EXPECT_LT(std::abs(quarterBalance), 1e-3);
}

// Hinged edges (every displacement held): their layers move as odd images in w (the
// membrane held), so the moment vanishes at the edge as it must.
TEST(TEST_CATEGORY, hinged_plate_pd_with_odd_images) {
  using namespace plate_verification_test;
  const auto hinged = [](int cells, const std::string& peridynamics) {
    return clampedPlateModel("{generator: plate, length-x: 1.0, length-y: 1.0, spacing: " + std::to_string(1.0 / cells) + "}",
                             "{default: pd}", peridynamics, fourHinges);
  };
  const auto coarse = solveClampedPlate(hinged(20, "{}"), "hinged plate 100 % PD a/20", hingedCoefficient);
  const auto fine = solveClampedPlate(hinged(40, "{}"), "hinged plate 100 % PD a/40", hingedCoefficient);
  const auto bare = solveClampedPlate(hinged(20, "{support-layer: false}"), "hinged plate 100 % PD a/20, no layer",
                                      hingedCoefficient);
  EXPECT_LT(std::abs(coarse.relativeError), 0.01);
  EXPECT_LT(std::abs(fine.relativeError), 0.01);
  EXPECT_LT(std::abs(coarse.relativeError), 0.2 * std::abs(bare.relativeError));  // measured -0.06 % and +1.17 %
  // The odd images carry the edges' shear: their reactions (assembly/mirror_images.hpp) and
  // the edge nodes' together balance the load.
  EXPECT_NEAR(-coarse.reactionZ, pressure, 1e-8 * pressure);
  EXPECT_NEAR(-fine.reactionZ, pressure, 1e-8 * pressure);
}

// A moving symmetry plane: a 100 mm x 20 mm strip, 100 % PD, whose end x = L is pulled by a
// prescribed u_x = c with the rotations about y and z held (the symmetry plane of a strip
// twice as long, pulled at both ends). Its layer moves as the even image about the plane's
// prescribed place, u_x -> 2 c - u_x (assembly/mirror_images.hpp), so the strip stretches
// uniformly: the reaction is E t W c / L, and the end moves as the prescription says.
TEST(TEST_CATEGORY, strip_pulled_by_a_moving_symmetry_plane) {
  using namespace plate_verification_test;
  const double length = 0.1, width = 0.02, stretch = 1.0e-5, E = 70.0e9, t = 1.0e-3;
  std::vector<double> errors;
  for (const std::string layer : {"true", "false"}) {
    const std::string text = R"(perishell:
  version: 1
  mesh:
    generator: plate
    length-x: 0.1
    length-y: 0.02
    spacing: 0.0025
  material: {young-modulus: 70.0e9, poisson-ratio: 0.3, density: 2700.0, thickness: 1.0e-3}
  peridynamics: {support-layer: )" + layer + R"(}
  zones: {default: pd}
  supports:
    fixed: {set: left, dofs: [ux, uz, ry, rz]}
    pulled: {set: right, dofs: [ux, ry, rz], value: 1.0e-5}
    pin: {set: bottom-left, dofs: [uy]}
  loads: {}
  solver: {type: implicit, increments: 1, tolerance: 1.0e-10, preconditioner: cholesky}
)";
    const auto model = perishell::model::buildModel(perishell::parseDeck(text, "strip.yaml"));
    auto solver = perishell::solvers::makeStaticSolver(TEST_EXECSPACE{}, model);
    solver.advanceTo(1.0);
    const auto r = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, solver.outOfBalance());
    double pull = 0.0;
    for (const auto& support : model.deck.supports)
      if (support.name == "pulled")
        for (const auto node : model.supportNodes(support)) pull -= r(node, 0);
    const double reference = E * t * width * stretch / length;
    errors.push_back(pull / reference - 1.0);
    std::printf("strip pulled by a moving symmetry plane, support-layer %s: %zu mirrored sets, reaction %.6f N, "
                "E t W c / L = %.6f N, error %+.3f %%\n",
                layer.c_str(), model.supportLayer.mirroredNodesOfSet.size(), pull, reference,
                100.0 * errors.back());
    EXPECT_EQ(model.supportLayer.mirroredNodesOfSet.size(), layer == "true" ? 2u : 0u);
  }
  EXPECT_LT(std::abs(errors[0]), 0.005);  // measured -0.24 %
  EXPECT_LT(std::abs(errors[0]), 0.2 * std::abs(errors[1]));  // -3.9 % without the layer
}

// The quarter of the plate with the PD centre: the PD zone meets both symmetry planes, CCM the
// rest. Only PD elements are mirrored, and the layer's elements stay PD next to the
// transition (coupling/make_coupled_model.hpp): as shell elements they stalled Newton.
TEST(TEST_CATEGORY, quarter_clamped_plate_with_a_pd_centre_mirrors_the_whole_plate) {
  using namespace plate_verification_test;
  const std::string zones =
      "{default: ccm, pd-regions: {centre: {box: {min: [0.1464, 0.1464, -1.0], max: [0.8536, 0.8536, 1.0]}}}}";
  const auto whole = solveClampedPlate(clampedPlate(40, zones), "clamped plate 50 % PD around the centre a/40");
  const auto quarter = solveClampedPlate(quarterClampedPlate(40, zones), "its quarter, two symmetry planes mirrored");
  EXPECT_NEAR(quarter.relativeError, whole.relativeError, 0.005);
  EXPECT_NEAR(-quarter.reactionZ, 0.25 * pressure, 1e-8 * pressure);
}

TEST(TEST_CATEGORY, clamped_plate_ccm) {
  using namespace plate_verification_test;
  const auto result = solveClampedPlate(clampedPlate(20, "{default: ccm}"), "clamped plate CCM a/20");
  EXPECT_LT(std::abs(result.relativeError), 0.01);
  EXPECT_NEAR(-result.reactionZ, pressure, 1e-8 * pressure);
}

namespace plate_verification_test {

// Sze 3.3's slit annular plate (R_i 6, R_o 10, E 21e6, nu 0, h 0.03): nr x nt quads in
// polar rows, its faces at theta = 0 ("clamped") and 2 pi ("loaded") coincident, node
// tags 1 + j (nr + 1) + i; written as Gmsh 4.1 ASCII.
std::string writeSlitRing(int nr, int nt) {
  const auto path = std::filesystem::temp_directory_path() / ("perishell_slit_ring_" + std::to_string(nr) + ".msh");
  const auto tag = [nr](int i, int j) { return 1 + j * (nr + 1) + i; };
  const int numNodes = (nr + 1) * (nt + 1);
  std::ofstream out(path);
  out.precision(17);
  out << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n3\n1 1 \"clamped\"\n1 2 \"loaded\"\n"
      << "2 3 \"ring\"\n$EndPhysicalNames\n$Entities\n0 2 1 0\n1 0 0 0 0 0 0 1 1 0\n2 0 0 0 0 0 0 1 2 0\n"
      << "1 0 0 0 0 0 0 1 3 0\n$EndEntities\n$Nodes\n1 " << numNodes << " 1 " << numNodes << "\n2 1 0 "
      << numNodes << "\n";
  for (int n = 1; n <= numNodes; ++n) out << n << "\n";
  const double pi = 3.14159265358979323846;
  for (int j = 0; j <= nt; ++j)
    for (int i = 0; i <= nr; ++i) {
      const double r = 6.0 + 4.0 * i / nr, theta = 2.0 * pi * j / nt;
      out << r * std::cos(theta) << " " << r * std::sin(theta) << " 0\n";
    }
  const int numElements = 2 * nr + nr * nt;
  out << "$EndNodes\n$Elements\n3 " << numElements << " 1 " << numElements << "\n";
  int element = 1;
  for (const int curve : {1, 2}) {
    out << "1 " << curve << " 1 " << nr << "\n";
    const int j = curve == 1 ? 0 : nt;
    for (int i = 0; i < nr; ++i) out << element++ << " " << tag(i, j) << " " << tag(i + 1, j) << "\n";
  }
  out << "2 1 3 " << nr * nt << "\n";
  for (int j = 0; j < nt; ++j)
    for (int i = 0; i < nr; ++i)
      out << element++ << " " << tag(i, j) << " " << tag(i + 1, j) << " " << tag(i + 1, j + 1) << " " << tag(i, j + 1)
          << "\n";
  out << "$EndElements\n";
  return path.string();
}

struct SlitRingResult {
  double wA = 0.0, wB = 0.0;  // the loaded face's inner and outer corners (Sze's A and B)
  int newtonIterations = 0;
};

// The slit ring under a line force q (Sze's q_max = 0.8 N/m), reached in `increments` equal
// steps, with the deck's solver keys `solverKeys` besides type, increments and tolerance.
SlitRingResult slitRingUnderLineForce(const std::string& mesh, int nr, int nt, const std::string& zone, double q,
                                      int increments, const std::string& solverKeys) {
  char load[64];
  std::snprintf(load, sizeof load, "%.15g", q / 0.03);
  const std::string text = R"(perishell:
  version: 1
  mesh: {generator: gmsh, file: )" + mesh + R"(, spacing: )" + std::to_string(4.0 / nr) + R"(}
  material: {young-modulus: 21.0e6, poisson-ratio: 0.0, density: 1.0, thickness: 0.03}
  zones: {default: )" + zone + R"(}
  supports: {clamp: {set: clamped, dofs: [ux, uy, uz, rx, ry, rz]}}
  loads: {line: {type: edge-traction, set: loaded, vector: [0.0, 0.0, )" + load + R"(]}}
  solver: {type: implicit, increments: )" + std::to_string(increments) + ", tolerance: 1.0e-8, " + solverKeys + R"(}
)";
  const auto model = perishell::model::buildModel(perishell::parseDeck(text, "slit_ring.yaml"));
  EXPECT_EQ(model.numCoincidentPairs, nr + 1);  // the two faces' nodes
  auto solver = perishell::solvers::makeStaticSolver(TEST_EXECSPACE{}, model);
  SlitRingResult result;
  for (int k = 1; k <= increments; ++k) result.newtonIterations += solver.advanceTo(double(k) / increments).newtonIterations;
  const auto u = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, solver.kinematics().displacements);
  const int a = nt * (nr + 1), b = nt * (nr + 1) + nr;  // 0-based: tag - 1
  result.wA = u(a, 2);
  result.wB = u(b, 2);
  std::printf("slit ring %d x %d %s, q %g, %s: w_A %.6f, w_B %.6f, %d Newton iterations\n", nr, nt, zone.c_str(), q,
              solverKeys.c_str(), result.wA, result.wB, result.newtonIterations);
  return result;
}

// Under 0.1 % of q_max (w ~ 2 h: mildly nonlinear), in one increment.
std::array<double, 2> slitRingDeflections(const std::string& mesh, int nr, int nt, const std::string& zone) {
  const auto result = slitRingUnderLineForce(mesh, nr, nt, zone, 0.0008, 1, "preconditioner: cholesky");
  return {result.wA, result.wB};
}

}  // namespace plate_verification_test

TEST(TEST_CATEGORY, slit_ring_pd_agrees_with_ccm) {
  using namespace plate_verification_test;
  // Bonds never cross the slit (pd/detail/boundary_crossing.hpp): with one bond from face to
  // face the loaded face hung on the clamp and PD came out 30 times too stiff.
  const int nr = 20, nt = 160;
  const auto mesh = writeSlitRing(nr, nt);
  const auto ccm = slitRingDeflections(mesh, nr, nt, "ccm");
  const auto pd = slitRingDeflections(mesh, nr, nt, "pd");
  for (int k = 0; k < 2; ++k) EXPECT_NEAR(pd[k], ccm[k], 0.03 * ccm[k]) << (k == 0 ? "A" : "B");
}

TEST(TEST_CATEGORY, slit_ring_mixed_format_newton_reaches_the_same_state_in_fewer_iterations) {
  using namespace plate_verification_test;
  // Sze 3.3 at 0.2 q_max, Sze's own 10 x 80 mesh, 4 increments: w_B ~ 300 h. Sze, Liu & Lo
  // (2004), as transcribed in MBDyn's sze33_ref.dat: w_A 6.725, w_B 9.160.
  const int nr = 10, nt = 80;
  const auto mesh = writeSlitRing(nr, nt);
  const auto mixed = slitRingUnderLineForce(mesh, nr, nt, "ccm", 0.16, 4, "preconditioner: cholesky, newton: mixed");
  const auto classical =
      slitRingUnderLineForce(mesh, nr, nt, "ccm", 0.16, 4, "preconditioner: cholesky, newton: displacement");
  EXPECT_NEAR(mixed.wA, 6.725, 0.01 * 6.725);
  EXPECT_NEAR(mixed.wB, 9.160, 0.01 * 9.160);
  // The same equilibrium (to Newton's tolerance), in well under half the iterations.
  EXPECT_NEAR(mixed.wA, classical.wA, 1e-6 * classical.wA);
  EXPECT_NEAR(mixed.wB, classical.wB, 1e-6 * classical.wB);
  EXPECT_LT(mixed.newtonIterations, classical.newtonIterations / 2);
}
