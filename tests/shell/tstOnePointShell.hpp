// The explicit one-point shell element (shell/one_point_shell.hpp): its force is the exact
// gradient of its energy (checked against forward-mode derivatives), rigid motions of any
// size cost nothing, the force turns with the element, membrane and bending patch tests on
// the distorted MacNeal-Harder patch are exact, a thin cantilever does not lock, hourglass
// modes are resisted while linear fields are not, the nodal stiffness diagonal matches the
// Hessian's, the device gives the host's numbers, and warped elements are refused. The
// explicit triangle (shell/explicit_triangle.hpp) gives the MITC3 triangle's force and energy.
#include <perishell/core/dual.hpp>
#include <perishell/core/types.hpp>
#include <perishell/shell/explicit_triangle.hpp>
#include <perishell/shell/one_point_shell.hpp>
#include <perishell/shell/shell_body.hpp>
#include <shell/element_states.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <iostream>
#include <string>
#include <vector>

namespace one_point_shell_test {

using namespace shell_element_test;
using D = perishell::Dual<double>;
using DD = perishell::Dual<perishell::Dual<double>>;

inline double force(const ElementState& state, const shell::ShellSection& section, double f[dofs],
                    double membraneBendingScale = 1.0) {
  return shell::onePointShellForce(state.reference, state.positions, quaternionsOf(state).q, section,
                                   membraneBendingScale, f)
      .strain;
}

// d/de W(q + e v), v = (translations, spatial rotation increments) per node: forward mode,
// the rotations as exp(e phi) R to second order (exact for the first two derivatives).
template <class T>
T energyAlong(const ElementState& state, const shell::ShellSection& section, const double direction[dofs],
              const double secondDirection[dofs]) {
  T x[4][3], R[4][3][3];
  for (int a = 0; a < 4; ++a) {
    T phi[3];
    for (int k = 0; k < 3; ++k) {
      x[a][k] = T(state.positions[a][k]);
      phi[k] = T(0.0);
      if constexpr (std::is_same_v<T, D>) {
        x[a][k].derivative = direction[6 * a + k];
        phi[k].derivative = direction[6 * a + 3 + k];
      } else {
        x[a][k].value.derivative = direction[6 * a + k];
        x[a][k].derivative.value = secondDirection[6 * a + k];
        phi[k].value.derivative = direction[6 * a + 3 + k];
        phi[k].derivative.value = secondDirection[6 * a + 3 + k];
      }
    }
    perishell::rotation::rotateBySpatialIncrementToSecondOrder(phi, state.rotations[a], R[a]);
  }
  T point, hourglass;
  shell::onePointShellEnergy(state.reference, x, R, section, 1.0, point, hourglass);
  return point + hourglass;
}

// The element's linear stiffness at its reference state: the Hessian of W.
inline Eigen::MatrixXd referenceStiffness(const double X[4][3], const shell::ShellSection& section) {
  ElementState state;
  for (int a = 0; a < 4; ++a)
    for (int k = 0; k < 3; ++k) {
      state.reference[a][k] = state.positions[a][k] = X[a][k];
      for (int l = 0; l < 3; ++l) state.rotations[a][k][l] = k == l ? 1.0 : 0.0;
    }
  Eigen::MatrixXd K(dofs, dofs);
  for (int i = 0; i < dofs; ++i)
    for (int j = 0; j <= i; ++j) {
      double first[dofs] = {}, second[dofs] = {};
      first[i] = 1.0;
      second[j] = 1.0;
      K(i, j) = K(j, i) = energyAlong<DD>(state, section, first, second).derivative.derivative;
    }
  return K;
}

inline Eigen::MatrixXd assemble(const Nodes& nodes, const Quads& quads, const shell::ShellSection& section) {
  const int n = 6 * static_cast<int>(nodes.size());
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(n, n);
  for (const auto& quad : quads) {
    double X[4][3];
    gather(nodes, quad, X);
    const Eigen::MatrixXd element = referenceStiffness(X, section);
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) K.block<6, 6>(6 * quad[a], 6 * quad[b]) += element.block<6, 6>(6 * a, 6 * b);
  }
  return K;
}

using Field = std::array<double, 6>;  // ux uy uz theta_x theta_y theta_z

// Boundary nodes (0-3) take the exact linear field, the interior is solved: the largest
// interior DOF error over the largest exact interior value.
template <class FieldT>
double patchError(const FieldT& exact) {
  const Nodes nodes = macNealHarderNodes();
  shell::ShellSection section;
  section.youngModulus = 1e6;
  section.poissonRatio = 0.25;
  section.thickness = 0.001;
  const Eigen::MatrixXd K = assemble(nodes, macNealHarderQuads(), section);
  Eigen::VectorXd prescribed(24), exactInterior(24);
  for (int node = 0; node < 8; ++node) {
    const Field value = exact(nodes[node][0], nodes[node][1]);
    for (int i = 0; i < 6; ++i) (node < 4 ? prescribed(6 * node + i) : exactInterior(6 * (node - 4) + i)) = value[i];
  }
  const Eigen::VectorXd solved = K.block(24, 24, 24, 24).ldlt().solve(-K.block(24, 0, 24, 24) * prescribed);
  return (solved - exactInterior).cwiseAbs().maxCoeff() / exactInterior.cwiseAbs().maxCoeff();
}

using HostForces = Kokkos::View<double* [dofs + 2], Kokkos::LayoutRight, Kokkos::HostSpace>;

// One thread per element: the force, then the strain and hourglass energies.
template <class ExecutionSpaceT>
HostForces evaluateOnDevice(const HostPositions& referenceHost, const HostPositions& positionsHost,
                            const HostRotations& rotationsHost, const shell::ShellSection section) {
  using MemorySpace = typename ExecutionSpaceT::memory_space;
  const auto references = Kokkos::create_mirror_view_and_copy(MemorySpace{}, referenceHost);
  const auto positions = Kokkos::create_mirror_view_and_copy(MemorySpace{}, positionsHost);
  const auto rotations = Kokkos::create_mirror_view_and_copy(MemorySpace{}, rotationsHost);
  Kokkos::View<double* [dofs + 2], Kokkos::LayoutRight, MemorySpace> out("one-point forces", referenceHost.extent(0));
  Kokkos::parallel_for(
      "one_point_shell_test::evaluate", Kokkos::RangePolicy<ExecutionSpaceT>(0, referenceHost.extent(0)),
      KOKKOS_LAMBDA(const int e) {
        double X[4][3], x[4][3], R[4][3][3], q[4][4], f[dofs];
        for (int a = 0; a < 4; ++a) {
          for (int k = 0; k < 3; ++k) {
            X[a][k] = references(e, a, k);
            x[a][k] = positions(e, a, k);
            for (int l = 0; l < 3; ++l) R[a][k][l] = rotations(e, a, k, l);
          }
          perishell::rotation::fromMatrix(R[a], q[a]);
        }
        const shell::OnePointEnergies energies = shell::onePointShellForce(X, x, q, section, 0.7, f);
        // Literal columns: a namespace-scope constexpr bound by reference is not visible in device code.
        for (int r = 0; r < 24; ++r) out(e, r) = f[r];
        out(e, 24) = energies.strain;
        out(e, 25) = energies.hourglass;
      });
  return Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, out);
}

}  // namespace one_point_shell_test

namespace {

using namespace one_point_shell_test;

TEST(TEST_CATEGORY, one_point_force_is_the_exact_energy_gradient) {
  const ElementState state = stronglyDeformed();
  const shell::ShellSection section = thickSection();
  double f[dofs];
  const double energy = force(state, section, f);
  EXPECT_GT(energy, 0.0);
  // Unit directions, then mixed ones.
  double worst[2] = {0.0, 0.0}, scale[2] = {0.0, 0.0};
  for (int j = 0; j < dofs; ++j) {
    double direction[dofs] = {}, unused[dofs] = {};
    direction[j] = 1.0;
    const double derivative = energyAlong<D>(state, section, direction, unused).derivative;
    worst[isRotation(j)] = std::max(worst[isRotation(j)], std::abs(derivative - f[j]));
    scale[isRotation(j)] = std::max(scale[isRotation(j)], std::abs(f[j]));
  }
  double mixedError = 0.0, mixedScale = 0.0;
  for (int trial = 0; trial < 5; ++trial) {
    double direction[dofs], unused[dofs] = {}, work = 0.0;
    for (int j = 0; j < dofs; ++j) {
      direction[j] = std::sin(1.7 * j + 2.3 * trial);
      work += f[j] * direction[j];
    }
    mixedError = std::max(mixedError, std::abs(energyAlong<D>(state, section, direction, unused).derivative - work));
    mixedScale = std::max(mixedScale, std::abs(work));
  }
  std::cout << "one-point f vs dW/dq (forward mode): relative error forces " << worst[0] / scale[0] << ", moments "
            << worst[1] / scale[1] << ", mixed directions " << mixedError / mixedScale << "\n";
  EXPECT_LE(worst[0], 1e-11 * scale[0]);
  EXPECT_LE(worst[1], 1e-11 * scale[1]);
  EXPECT_LE(mixedError, 1e-11 * mixedScale);
}

TEST(TEST_CATEGORY, one_point_rigid_motions_give_zero_force_and_the_force_turns_with_the_element) {
  const shell::ShellSection section = thickSection();
  double X[4][3];
  warpedReference(X);
  const double length = 1.0, forceScale = section.youngModulus * section.thickness * length;
  const double halfPi = 1.5707963267948966, skew = halfPi / std::sqrt(14.0);
  const double rotations[5][3] = {
      {halfPi, 0, 0}, {0, halfPi, 0}, {0, 0, halfPi}, {skew, 2 * skew, 3 * skew}, {-1.2, 2.0, 0.9}};
  const double shift[3] = {0.3, -1.2, 2.0};
  double worst = 0.0;
  for (const auto& rotationVector : rotations) {
    double f[dofs];
    const double energy = force(rigidlyMoved(X, rotationVector, shift), section, f);
    for (int i = 0; i < dofs; ++i) worst = std::max(worst, std::abs(f[i]) / forceScale);
    EXPECT_LE(energy, 1e-20 * forceScale * length);
  }
  std::cout << "one-point rigid motions: max |f| / (E t L) " << worst << "\n";
  EXPECT_LE(worst, 1e-10);

  const ElementState state = stronglyDeformed();
  double f[dofs], rotatedForce[dofs];
  const double energy = force(state, section, f);
  double Q[3][3];
  const ElementState rotated = rigidlyRotated(state, Q);
  EXPECT_NEAR(force(rotated, section, rotatedForce), energy, 1e-12 * energy);
  double error = 0.0, largest = 0.0;
  for (int j = 0; j < dofs; j += 3)
    for (int i = 0; i < 3; ++i) {
      error = std::max(error, std::abs(rotatedForce[j + i] - (Q[i][0] * f[j] + Q[i][1] * f[j + 1] + Q[i][2] * f[j + 2])));
      largest = std::max(largest, std::abs(f[j + i]));
    }
  EXPECT_LE(error, 1e-10 * largest);
}

TEST(TEST_CATEGORY, one_point_patch_tests_are_exact_on_a_distorted_mesh) {
  // Membrane: a linear in-plane field with theta_z its rigid rotation part.
  const double membraneError = patchError([](double x, double y) -> Field {
    const double u = 1e-5 + 1e-3 * (2.0 * x + 0.3 * y), v = -2e-5 + 1e-3 * (0.2 * x - y);
    return {u, v, 0.0, 0.0, 0.0, 0.5 * 1e-3 * (0.2 - 0.3)};
  });
  // Bending: w quadratic, rotations its exact slopes (Kirchhoff): constant curvature.
  const double a = 1e-3, b = 2e-3, c = 0.5e-3;
  const double bendingError = patchError([=](double x, double y) -> Field {
    const double w = 1e-4 + 2e-3 * x - 1e-3 * y + 0.5 * (a * x * x + 2.0 * c * x * y + b * y * y);
    const double dwdx = 2e-3 + a * x + c * y, dwdy = -1e-3 + c * x + b * y;
    return {0.0, 0.0, w, dwdy, -dwdx, 0.0};
  });
  std::cout << "one-point patch tests (MacNeal-Harder): membrane error " << membraneError << ", bending error "
            << bendingError << "\n";
  EXPECT_LT(membraneError, 1e-9);
  EXPECT_LT(bendingError, 1e-8);
}

TEST(TEST_CATEGORY, one_point_thin_cantilever_has_no_shear_locking) {
  // L/t = 1000, regular and distorted (interior nodes shifted by 30 % of a cell).
  const double regular = cantileverTipRatio(16, 0.0, assemble), fine = cantileverTipRatio(64, 0.0, assemble);
  const double distorted = cantileverTipRatio(16, 0.3, assemble);
  std::cout << "one-point cantilever tip / (P L^3 / 3EI): 16 x 1 " << regular << ", 64 x 1 " << fine
            << ", 16 x 1 distorted " << distorted << "\n";
  EXPECT_NEAR(regular, 1.0, 0.01);
  EXPECT_NEAR(fine, 1.0, 0.01);
  EXPECT_NEAR(distorted, 1.0, 0.03);
}

TEST(TEST_CATEGORY, one_point_hourglass_modes_are_resisted_and_the_nodal_stiffness_is_the_hessian_diagonal) {
  double X[4][3];
  warpedReference(X);
  for (int a = 0; a < 4; ++a) X[a][2] = 0.0;  // flat: the nodal stiffness is the flat element's
  const shell::ShellSection section = thickSection();
  const Eigen::MatrixXd K = referenceStiffness(X, section);
  // A lone element keeps two zero-energy modes besides the rigid ones: theta_z linear with
  // zero mean (the drilling penalty is tied at the centre and in the hourglass mode). A mesh
  // has none: a 3 x 3 patch of distorted elements, free, has exactly the 6 rigid modes.
  const auto zeroModes = [](const Eigen::MatrixXd& matrix) {
    const Eigen::VectorXd eigenvalues = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(matrix).eigenvalues();
    int zeros = 0;
    // Rigid modes come out at ~1e-17 of the largest eigenvalue; the softest deformation modes
    // (the drilling penalty's, 1e-3 G t) at ~1e-10.
    for (int i = 0; i < eigenvalues.size(); ++i) zeros += std::abs(eigenvalues(i)) < 1e-14 * eigenvalues.maxCoeff();
    return zeros;
  };
  Nodes nodes;
  Quads quads;
  for (int j = 0; j <= 3; ++j)
    for (int i = 0; i <= 3; ++i) {
      const bool interior = i > 0 && i < 3 && j > 0 && j < 3;
      nodes.push_back({0.1 * i + (interior ? 0.02 * std::sin(3.0 * i + j) : 0.0),
                       0.1 * j + (interior ? 0.02 * std::cos(2.0 * i - j) : 0.0), 0.0});
    }
  for (int j = 0; j < 3; ++j)
    for (int i = 0; i < 3; ++i) quads.push_back({4 * j + i, 4 * j + i + 1, 4 * (j + 1) + i + 1, 4 * (j + 1) + i});
  const int elementZeros = zeroModes(K), patchZeros = zeroModes(assemble(nodes, quads, section));
  std::cout << "one-point zero-energy modes: lone element " << elementZeros << ", free 3 x 3 patch " << patchZeros
            << "\n";
  EXPECT_EQ(elementZeros, 8);
  EXPECT_EQ(patchZeros, 6);
  double translational[4], rotational[4];
  shell::onePointShellNodalStiffness(X, section, 1.0, translational, rotational);
  for (int a = 0; a < 4; ++a) {
    const double moving = (K(6 * a, 6 * a) + K(6 * a + 1, 6 * a + 1) + K(6 * a + 2, 6 * a + 2)) / 3.0;
    const double turning = (K(6 * a + 3, 6 * a + 3) + K(6 * a + 4, 6 * a + 4) + K(6 * a + 5, 6 * a + 5)) / 3.0;
    EXPECT_NEAR(translational[a], moving, 1e-10 * moving) << "node " << a;
    EXPECT_NEAR(rotational[a], turning, 1e-10 * turning) << "node " << a;
  }
}

TEST(TEST_CATEGORY, one_point_device_evaluation_matches_host) {
  const shell::ShellSection section = thickSection();
  const std::array<ElementState, 3> states = deviceTestStates();
  const auto [references, positions, rotations] = hostViews(states);
  const HostForces device = evaluateOnDevice<TEST_EXECSPACE>(references, positions, rotations, section);
  for (int e = 0; e < 3; ++e) {
    double f[dofs];
    const shell::OnePointEnergies energies =
        shell::onePointShellForce(states[e].reference, states[e].positions, quaternionsOf(states[e]).q, section, 0.7, f);
    const double forceScale = section.youngModulus * section.thickness;
    for (int r = 0; r < dofs; ++r) EXPECT_NEAR(device(e, r), f[r], 1e-12 * forceScale) << "element " << e << " row " << r;
    EXPECT_NEAR(device(e, dofs), energies.strain, 1e-12 * std::max(energies.strain, forceScale * 1e-12));
    EXPECT_NEAR(device(e, dofs + 1), energies.hourglass, 1e-12 * std::max(energies.hourglass, forceScale * 1e-12));
  }
}

TEST(TEST_CATEGORY, explicit_triangle_force_is_the_mitc3_triangles) {
  // The written-out force of the explicit triangle and the stored-K_l force of the implicit
  // solver's triangle (shell/mitc4_shell.hpp, N = 3) are the derivative of one energy; also for
  // a scaled section and a triangle with one linear (quad-side) edge, and after a rigid motion.
  const ElementState state = stronglyDeformedTriangle();
  const auto& X = state.reference;
  const shell::ShellSection section = thickSection();
  const double forceScale = section.youngModulus * section.thickness;
  for (const unsigned edges : {7u, 5u})
    for (const double scale : {1.0, 0.4}) {
      const double fullScales[4] = {scale, scale, scale, scale};
      double K4[dofs][dofs], K3[18][18], stored[18], written[18];
      shell::shellLocalStiffness(X, section, fullScales, edges, K4);
      for (int r = 0; r < 18; ++r)
        for (int c = 0; c < 18; ++c) K3[r][c] = K4[r][c];
      const double storedEnergy = shell::shellInternalForce<3>(X, state.positions, state.rotations, K3, stored);
      const double writtenEnergy =
          shell::explicitTriangleForce(X, state.positions, quaternionsOf(state).q, section, scale, edges, written);
      EXPECT_GT(storedEnergy, 0.0);
      EXPECT_NEAR(writtenEnergy, storedEnergy, 1e-12 * storedEnergy) << "edges " << edges << " scale " << scale;
      double error = 0.0;
      for (int i = 0; i < 18; ++i) error = std::max(error, std::abs(written[i] - stored[i]));
      std::cout << "explicit triangle, edges " << edges << ", scale " << scale << ": energy " << writtenEnergy
                << ", max force difference / (E t) " << error / forceScale << "\n";
      EXPECT_LE(error, 1e-10 * forceScale);
    }
  // A rigid motion of the reference costs nothing.
  const double turn[3] = {0.3, -1.1, 0.7}, shift[3] = {0.3, -1.2, 2.0};
  const ElementState moved = rigidlyMoved(X, turn, shift);
  double rigid[18];
  EXPECT_LE(shell::explicitTriangleForce(X, moved.positions, quaternionsOf(moved).q, section, 1.0, 7u, rigid),
            1e-20 * forceScale);
  for (int i = 0; i < 18; ++i) EXPECT_LE(std::abs(rigid[i]), 1e-10 * forceScale) << i;
}

// A body's nodes turned by the rotation vector turn(node) and moved by move(node, k), on the
// host, and the same state on the test's memory space.
template <class TurnT, class MoveT>
perishell::pd::PdKinematics<Kokkos::HostSpace> turnedAndMovedNodes(int numNodes, TurnT turn, MoveT move) {
  perishell::pd::PdKinematics<Kokkos::HostSpace> state(numNodes);
  for (int node = 0; node < numNodes; ++node) {
    const std::array<double, 3> theta = turn(node);
    double q[4];
    perishell::rotation::exponential(theta.data(), q);
    for (int k = 0; k < 4; ++k) state.rotations(node, k) = q[k];
    for (int k = 0; k < 3; ++k) state.displacements(node, k) = move(node, k);
  }
  return state;
}

template <class MemorySpaceT>
perishell::pd::PdKinematics<MemorySpaceT> copiedTo(const perishell::pd::PdKinematics<Kokkos::HostSpace>& host) {
  perishell::pd::PdKinematics<MemorySpaceT> state(static_cast<perishell::LocalIndex>(host.displacements.extent(0)));
  Kokkos::deep_copy(state.displacements, host.displacements);
  Kokkos::deep_copy(state.rotations, host.rotations);
  return state;
}

TEST(TEST_CATEGORY, one_point_body_forces_are_the_elements_with_and_without_triangles) {
  // subtractShellForces runs a kernel specialised for bodies of quads only, and one that takes
  // each element's triangle or quad branch: both give the sum of the element forces evaluated
  // one by one on the host, with either assembly.
  using MemorySpace = TEST_EXECSPACE::memory_space;
  perishell::mesh::HostQuadMesh plate;
  plate.coordinates = perishell::CoordinateView<Kokkos::HostSpace>("nodes", 6);
  for (int node = 0; node < 6; ++node) {
    plate.coordinates(node, 0) = 0.01 * (node % 3) + 0.001 * (node == 4);
    plate.coordinates(node, 1) = 0.01 * (node / 3);
  }
  plate.quads = perishell::QuadConnectivityView<Kokkos::HostSpace>("elements", 3);
  const perishell::LocalIndex corners[3][4] = {{0, 1, 4, 3}, {1, 2, 5, 5}, {1, 5, 4, 4}};
  for (int e = 0; e < 3; ++e)
    for (int a = 0; a < 4; ++a) plate.quads(e, a) = corners[e][a];
  const auto hostState = turnedAndMovedNodes(
      6, [](int node) { return std::array<double, 3>{0.02 * node - 0.05, 0.03 - 0.01 * node, 0.015 * (node % 2)}; },
      [](int node, int k) { return 1e-4 * std::sin(1.0 + node + 2.0 * k); });
  const auto state = copiedTo<MemorySpace>(hostState);
  const shell::ShellSection section = thickSection();
  const double forceScale = section.youngModulus * section.thickness;
  for (const std::vector<perishell::LocalIndex>& elements : {std::vector<perishell::LocalIndex>{0}, std::vector<perishell::LocalIndex>{0, 1, 2}}) {
    auto body = shell::makeShellBody(TEST_EXECSPACE{}, plate, elements, section,
                                     Kokkos::View<double* [4], Kokkos::LayoutRight, MemorySpace>("scale", elements.size()),
                                     shell::ShellElementKind::OnePoint);
    Kokkos::deep_copy(body.membraneBendingScale, 1.0);
    EXPECT_EQ(body.hasTriangles, elements.size() == 3);
    // A triangle's edge shared with the quad has no Allman term (triangleQuadraticEdges).
    const auto quadraticEdges = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, body.quadraticEdges);
    double expected[6][6] = {};
    for (const perishell::LocalIndex e : elements) {
      double X[4][3], x[4][3], q[4][4], f[dofs];
      for (int a = 0; a < 4; ++a)
        for (int k = 0; k < 3; ++k) {
          X[a][k] = plate.coordinates(plate.quads(e, a), k);
          x[a][k] = X[a][k] + hostState.displacements(plate.quads(e, a), k);
          for (int l = 0; l < 4; ++l) q[a][l] = hostState.rotations(plate.quads(e, a), l);
        }
      const int count = e == 0 ? 4 : 3;
      if (count == 4)
        shell::onePointShellForce(X, x, q, section, 1.0, f);
      else
        shell::explicitTriangleForce(X, x, q, section, 1.0, quadraticEdges(e), f);
      for (int a = 0; a < count; ++a)
        for (int d = 0; d < 6; ++d) expected[plate.quads(e, a)][d] -= f[6 * a + d];
    }
    for (const auto assembly : {shell::ElementForceAssembly::Scatter, shell::ElementForceAssembly::Gather}) {
      body.assembly = assembly;
      perishell::pd::NodalVectorView<MemorySpace> forces("forces", 6);
      shell::subtractShellForces(TEST_EXECSPACE{}, body, state, forces);
      const auto result = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, forces);
      double largest = 0.0;
      for (int node = 0; node < 6; ++node)
        for (int d = 0; d < 6; ++d) {
          EXPECT_NEAR(result(node, d), expected[node][d], 1e-12 * forceScale) << "node " << node << " dof " << d;
          largest = std::max(largest, std::abs(expected[node][d]));
        }
      EXPECT_GT(largest, 1e-6 * forceScale);
    }
  }
}

// A distorted 3 x 3 quad plate (16 nodes, 9 elements) and a state that moves and turns it.
perishell::mesh::HostQuadMesh distortedNineElementPlate() {
  perishell::mesh::HostQuadMesh plate;
  plate.coordinates = perishell::CoordinateView<Kokkos::HostSpace>("nodes", 16);
  for (int node = 0; node < 16; ++node) {
    plate.coordinates(node, 0) = 0.01 * (node % 4) + 0.0007 * (node % 3);
    plate.coordinates(node, 1) = 0.01 * (node / 4) - 0.0005 * (node % 2);
  }
  plate.quads = perishell::QuadConnectivityView<Kokkos::HostSpace>("elements", 9);
  for (int e = 0; e < 9; ++e) {
    const int first = 4 * (e / 3) + e % 3;
    const perishell::LocalIndex corners[4] = {first, first + 1, first + 5, first + 4};
    for (int a = 0; a < 4; ++a) plate.quads(e, a) = corners[a];
  }
  return plate;
}
template <class MemorySpace>
perishell::pd::PdKinematics<MemorySpace> nineElementPlateState() {
  return copiedTo<MemorySpace>(turnedAndMovedNodes(
      16, [](int node) { return std::array<double, 3>{0.01 * node - 0.07, 0.04 - 0.005 * node, 0.02 * (node % 3)}; },
      [](int node, int k) { return 2e-4 * std::sin(0.5 + 1.3 * node + 2.0 * k); }));
}

TEST(TEST_CATEGORY, selected_elements_give_a_fully_selected_node_the_same_forces_bit_for_bit) {
  // A distributed step evaluates only the elements with a node whose force is read
  // (solvers/explicit/central_difference.hpp, stepWorkOf); shell::selectElements keeps the
  // gather assembly and each node's element order, so a node all of whose elements are
  // selected gets the whole body's forces to the bit. A 3 x 3 quad plate, moved and turned;
  // the mask is interior node 5, whose four elements are selected out of nine.
  using MemorySpace = TEST_EXECSPACE::memory_space;
  const perishell::mesh::HostQuadMesh plate = distortedNineElementPlate();
  const std::vector<perishell::LocalIndex> elements = {0, 1, 2, 3, 4, 5, 6, 7, 8};
  const auto state = nineElementPlateState<MemorySpace>();
  auto body = shell::makeShellBody(TEST_EXECSPACE{}, plate, elements, thickSection(),
                                   Kokkos::View<double* [4], Kokkos::LayoutRight, MemorySpace>("scale", 9),
                                   shell::ShellElementKind::OnePoint);
  Kokkos::deep_copy(body.membraneBendingScale, 1.0);
  body.assembly = shell::ElementForceAssembly::Gather;
  Kokkos::View<std::uint8_t*, Kokkos::HostSpace> hostMask("mask", 16);
  hostMask(5) = 1;
  const Kokkos::View<const std::uint8_t*, MemorySpace> mask =
      Kokkos::create_mirror_view_and_copy(MemorySpace{}, hostMask);
  const auto selected = shell::selectElements(TEST_EXECSPACE{}, body, mask);
  EXPECT_EQ(selected.numElements(), 4);
  EXPECT_EQ(selected.assembly, shell::ElementForceAssembly::Gather);
  perishell::pd::NodalVectorView<MemorySpace> whole("whole", 16), part("part", 16);
  shell::subtractShellForces(TEST_EXECSPACE{}, body, state, whole);
  shell::subtractShellForces(TEST_EXECSPACE{}, selected, state, part);
  const auto a = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, whole);
  const auto b = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, part);
  double largest = 0.0;
  for (int d = 0; d < 6; ++d) {
    EXPECT_EQ(std::memcmp(&a(5, d), &b(5, d), sizeof(double)), 0) << "dof " << d << ": " << a(5, d) << " " << b(5, d);
    largest = std::max(largest, std::abs(a(5, d)));
    EXPECT_EQ(b(15, d), 0.0);  // the far corner's element is not selected
  }
  EXPECT_GT(largest, 1e-3);
}

TEST(TEST_CATEGORY, elements_evaluated_in_two_selections_give_the_whole_bodys_forces) {
  // A distributed explicit step evaluates its elements in two lists around the halo exchange
  // (solvers/explicit/central_difference.hpp, stepWorkOf) and gathers once after both. For
  // each element kind and assembly, a 3 x 3 plate, moved and turned, in two interleaved lists
  // (one of them out of order) must give the whole body's forces and energies: to the bit where
  // the one-point element gathers, to round-off where atomics add in any order. A list that is
  // empty evaluates nothing.
  using MemorySpace = TEST_EXECSPACE::memory_space;
  const perishell::mesh::HostQuadMesh plate = distortedNineElementPlate();
  const std::vector<perishell::LocalIndex> elements = {0, 1, 2, 3, 4, 5, 6, 7, 8};
  const auto state = nineElementPlateState<MemorySpace>();
  const auto listed = [](std::vector<perishell::LocalIndex> values) {
    Kokkos::View<perishell::LocalIndex*, MemorySpace> view("listed elements", values.size());
    Kokkos::deep_copy(view, Kokkos::View<const perishell::LocalIndex*, Kokkos::HostSpace, Kokkos::MemoryUnmanaged>(
                                values.data(), values.size()));
    return shell::ElementSelection<MemorySpace>::only(view);
  };
  const auto first = listed({7, 1, 3, 5}), second = listed({0, 2, 4, 6, 8}), none = listed({});
  struct Case {
    shell::ShellElementKind kind;
    shell::ElementForceAssembly assembly;
  };
  for (const Case c : {Case{shell::ShellElementKind::OnePoint, shell::ElementForceAssembly::Gather},
                       Case{shell::ShellElementKind::OnePoint, shell::ElementForceAssembly::Scatter},
                       Case{shell::ShellElementKind::Mitc4, shell::ElementForceAssembly::Scatter}}) {
    auto body = shell::makeShellBody(TEST_EXECSPACE{}, plate, elements, thickSection(),
                                     Kokkos::View<double* [4], Kokkos::LayoutRight, MemorySpace>("scale", 9), c.kind);
    Kokkos::deep_copy(body.membraneBendingScale, 1.0);
    if (c.kind == shell::ShellElementKind::OnePoint) body.assembly = c.assembly;
    perishell::pd::NodalVectorView<MemorySpace> whole("whole", 16), split("split", 16);
    perishell::VectorView<MemorySpace> wholeEnergy("whole energy", 16), splitEnergy("split energy", 16);
    shell::subtractShellForces(TEST_EXECSPACE{}, body, state, whole, wholeEnergy);
    shell::subtractSelectedShellForces(TEST_EXECSPACE{}, body, first, state, split, splitEnergy);
    shell::subtractSelectedShellForces(TEST_EXECSPACE{}, body, none, state, split, splitEnergy);
    shell::subtractSelectedShellForces(TEST_EXECSPACE{}, body, second, state, split, splitEnergy);
    shell::gatherShellForces(TEST_EXECSPACE{}, body, split, splitEnergy);
    const auto a = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, whole);
    const auto b = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, split);
    const auto ea = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, wholeEnergy);
    const auto eb = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, splitEnergy);
    const bool bitwise = c.assembly == shell::ElementForceAssembly::Gather;
    double largest = 0.0, largestEnergy = 0.0;
    for (int node = 0; node < 16; ++node) {
      for (int d = 0; d < 6; ++d) largest = std::max(largest, std::abs(a(node, d)));
      largestEnergy = std::max(largestEnergy, std::abs(ea(node)));
    }
    for (int node = 0; node < 16; ++node) {
      for (int d = 0; d < 6; ++d) {
        if (bitwise)
          EXPECT_EQ(std::memcmp(&a(node, d), &b(node, d), sizeof(double)), 0) << "node " << node << " dof " << d;
        else
          EXPECT_NEAR(b(node, d), a(node, d), 1e-13 * largest) << "node " << node << " dof " << d;
      }
      EXPECT_NEAR(eb(node), ea(node), (bitwise ? 0.0 : 1e-13) * largestEnergy) << "node " << node;
    }
    EXPECT_GT(largest, 1e-3);
    EXPECT_GT(largestEnergy, 0.0);
  }
}

TEST(TEST_CATEGORY, quaternion_of_a_matrix_and_its_logarithm_invert_the_exponential) {
  // The explicit elements' local rotations (shell/corotational_projector.hpp) go through
  // fromMatrix and the quaternion logarithm. Angles from 1e-9 to near pi about skew axes, and
  // near-half turns about each axis (each of Shepperd's four branches); q and -q alike.
  const double axes[4][3] = {{0.6, -0.48, 0.64}, {1.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, {0.0, 0.0, 1.0}};
  for (const auto& axis : axes)
    for (const double angle : {1e-9, 1e-4, 0.02, 0.5, 2.0, 3.0, 3.14}) {
      const double theta[3] = {angle * axis[0], angle * axis[1], angle * axis[2]};
      double q[4], R[3][3], back[4], fromQuaternion[3], fromMatrix[3];
      perishell::rotation::exponential(theta, q);
      perishell::rotation::toMatrix(q, R);
      perishell::rotation::fromMatrix(R, back);
      EXPECT_NEAR(std::abs(q[0] * back[0] + q[1] * back[1] + q[2] * back[2] + q[3] * back[3]), 1.0, 1e-15);
      perishell::rotation::logarithm(R, fromMatrix);
      for (const double sign : {1.0, -1.0}) {
        const double signed_[4] = {sign * back[0], sign * back[1], sign * back[2], sign * back[3]};
        perishell::rotation::rotationVector(signed_, fromQuaternion);
        for (int k = 0; k < 3; ++k) {
          EXPECT_NEAR(fromQuaternion[k], theta[k], 4e-16 * std::max(1.0, angle / (M_PI - angle)) + 1e-24)
              << "angle " << angle << " component " << k;
          EXPECT_NEAR(fromQuaternion[k], fromMatrix[k], 1e-14 * std::max(1.0, angle / (M_PI - angle)) + 1e-24);
        }
      }
    }
}

TEST(TEST_CATEGORY, rotation_series_match_the_closed_forms_on_both_sides_of_their_thresholds) {
  // exponential, rotationVector and c(theta) of J_l^-T switch from their power series to the
  // closed forms at 0.01 rad, tan(theta/2) = 0.1 and 0.1 rad (core/rotation.hpp,
  // shell/corotational_projector.hpp): each agrees with the closed form in long double to
  // round-off on both sides.
  const double axis[3] = {0.6, -0.48, 0.64};
  for (const double angle : {1e-6, 0.0099, 0.0101, 0.05, 0.0999, 0.1001, 0.199, 0.2, 0.3}) {
    const double theta[3] = {angle * axis[0], angle * axis[1], angle * axis[2]};
    const long double a = angle, half = a / 2;
    double q[4];
    perishell::rotation::exponential(theta, q);
    EXPECT_NEAR(q[0], static_cast<double>(std::cos(half)), 2e-16) << "angle " << angle;
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(q[k + 1], static_cast<double>(std::sin(half) / a * theta[k]), 2e-16 * angle) << "angle " << angle;
    const double exact[4] = {static_cast<double>(std::cos(half)), static_cast<double>(std::sin(half) * axis[0]),
                             static_cast<double>(std::sin(half) * axis[1]),
                             static_cast<double>(std::sin(half) * axis[2])};
    double back[3];
    perishell::rotation::rotationVector(exact, back);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(back[k], theta[k], 4e-16 * angle) << "angle " << angle;
    const double moment[3] = {0.3, -0.2, 0.9};
    double mapped[3];
    perishell::shell::detail::applyTransposedInverseLeftJacobian(theta, moment, mapped);
    const long double c = 1.0L / (a * a) - (1.0L + std::cos(a)) / (2.0L * a * std::sin(a));
    const long double once[3] = {theta[1] * (long double)moment[2] - theta[2] * (long double)moment[1],
                                 theta[2] * (long double)moment[0] - theta[0] * (long double)moment[2],
                                 theta[0] * (long double)moment[1] - theta[1] * (long double)moment[0]};
    const long double twice[3] = {theta[1] * once[2] - theta[2] * once[1], theta[2] * once[0] - theta[0] * once[2],
                                  theta[0] * once[1] - theta[1] * once[0]};
    for (int k = 0; k < 3; ++k)
      EXPECT_NEAR(mapped[k], static_cast<double>(moment[k] + 0.5L * once[k] + c * twice[k]), 4e-16)
          << "angle " << angle;
  }
}

TEST(TEST_CATEGORY, one_point_warped_and_degenerate_elements_are_refused) {
  const double twisted[4][3] = {{0, 0, 0}, {1, 0, 0.2}, {1, 1, 0}, {0, 1, 0.2}};  // warp ~0.1
  try {
    shell::checkOnePointShellElement(twisted, 12);
    ADD_FAILURE() << "accepted a warped element";
  } catch (const std::invalid_argument& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("shell element 12: warped by 0.1 "), std::string::npos) << message;
    EXPECT_NE(message.find("solver.shell-element: mitc4"), std::string::npos) << message;
  }
  const double slightlyTwisted[4][3] = {{0, 0, 0}, {1, 0, 0.04}, {1, 1, 0}, {0, 1, 0.04}};
  EXPECT_NO_THROW(shell::checkOnePointShellElement(slightlyTwisted, 12));
  const double bowTie[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  EXPECT_THROW(shell::checkOnePointShellElement(bowTie, 12), std::invalid_argument);
}

}  // namespace
