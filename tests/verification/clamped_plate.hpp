#pragma once
// The clamped square plate under uniform pressure that the plate verification tests solve
// (docs/verification.md): its deck on any mesh of the unit square, and its answer.
#include <perishell/io/deck.hpp>
#include <perishell/solvers/implicit/static_solver_from_model.hpp>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace plate_verification_test {

// Clamped square plate, a = 1 m, t = 10 mm, nu = 0.3, q = 1 kPa: w_max = 0.00126532 q a^4 / D
// (Taylor & Govindjee, "Solution of clamped rectangular plate problems", Commun. Numer.
// Meth. Engng 20 (2004) 757-765; Timoshenko & Woinowsky-Krieger, Table 35: 0.00126). The
// deflection is 0.7 % of t: the linear range.
inline constexpr double youngModulus = 210.0e9, poissonRatio = 0.3, thickness = 0.01, pressure = 1000.0;

inline constexpr const char* fourClamps = R"(
    left: {set: left, dofs: [ux, uy, uz, rx, ry, rz]}
    right: {set: right, dofs: [ux, uy, uz, rx, ry, rz]}
    bottom: {set: bottom, dofs: [ux, uy, uz, rx, ry, rz]}
    top: {set: top, dofs: [ux, uy, uz, rx, ry, rz]})";
// The quarter [0, a/2]^2: clamped at x = 0 and y = 0, symmetry planes at x = a/2 and y = a/2.
inline constexpr const char* quarterSupports = R"(
    left: {set: left, dofs: [ux, uy, uz, rx, ry, rz]}
    bottom: {set: bottom, dofs: [ux, uy, uz, rx, ry, rz]}
    symmetryX: {set: right, dofs: [ux, ry, rz]}
    symmetryY: {set: top, dofs: [uy, rx, rz]})";
// Hinged on all four edges (every displacement held, rotations free): Navier's series,
// w_max = 0.00406235 q a^4 / D (Timoshenko & Woinowsky-Krieger, Table 8).
inline constexpr const char* fourHinges = R"(
    left: {set: left, dofs: [ux, uy, uz]}
    right: {set: right, dofs: [ux, uy, uz]}
    bottom: {set: bottom, dofs: [ux, uy, uz]}
    top: {set: top, dofs: [ux, uy, uz]})";
inline constexpr double hingedCoefficient = 0.00406235;
inline constexpr const char* implicitSolver =
    "{type: implicit, increments: 1, tolerance: 1.0e-10, preconditioner: cholesky}";

// The plate's model on `mesh` (the deck's mesh map, with node and edge sets left, right,
// bottom, top).
inline perishell::model::Model clampedPlateModel(const std::string& mesh, const std::string& zones,
                                                 const std::string& peridynamics = "{}",
                                                 const std::string& supports = fourClamps,
                                                 const std::string& solver = implicitSolver) {
  const std::string text = R"(perishell:
  version: 1
  mesh: )" + mesh + R"(
  material: {young-modulus: 210.0e9, poisson-ratio: 0.3, density: 7850.0, thickness: 0.01}
  peridynamics: )" + peridynamics + R"(
  zones: )" + zones + R"(
  supports:)" + supports + R"(
  loads: {q: {type: pressure, value: 1000.0}}
  solver: )" + solver + R"(
)";
  return perishell::model::buildModel(perishell::parseDeck(text, "clamped_plate.yaml"));
}

// On the plate generator's cells x cells quads.
inline perishell::model::Model clampedPlate(int cells, const std::string& zones, const std::string& peridynamics = "{}") {
  return clampedPlateModel("{generator: plate, length-x: 1.0, length-y: 1.0, spacing: " + std::to_string(1.0 / cells) +
                               "}",
                           zones, peridynamics);
}

// Its quarter at the same spacing (cells / 2 x cells / 2 quads).
inline perishell::model::Model quarterClampedPlate(int cells, const std::string& zones,
                                                   const std::string& solver = implicitSolver) {
  return clampedPlateModel("{generator: plate, length-x: 0.5, length-y: 0.5, spacing: " + std::to_string(1.0 / cells) +
                               "}",
                           zones, "{}", quarterSupports, solver);
}

struct PlateResult {
  double relativeError;  // of the centre deflection
  double reactionZ;      // sum of the z out-of-balance force over the prescribed nodes [N]
};

// w_max against coefficient q a^4 / D (the clamped plate's by default).
inline PlateResult solveClampedPlate(const perishell::model::Model& model, const char* label,
                                     double coefficient = 0.00126532) {
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
  const double reference = coefficient * pressure / D;
  const double error = centre / reference - 1.0;
  std::printf("%s: w_max %.6e m, reference %.6e m, error %+.2f %%, reactions %.6f N\n", label, centre, reference,
              100.0 * error, -reaction);
  return {error, reaction};
}

}  // namespace plate_verification_test
