// The MITC4 corotational shell element (shell/mitc4_shell.hpp): membrane and bending patch
// tests on a distorted patch, a thin cantilever free of shear locking, objectivity under
// large rigid rotations, force = energy gradient and tangent = force derivative by finite
// differences in a strongly deformed state, the same numbers on the device, and rejected
// degenerate input.
#include <perishell/core/types.hpp>
#include <perishell/shell/mitc4_shell.hpp>
#include <shell/element_states.hpp>

// Eigen serves host-side dense solves only: keep it out of nvcc's device annotations.
#ifndef EIGEN_NO_CUDA
#define EIGEN_NO_CUDA
#endif
#include <Eigen/Dense>

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <string>
#include <vector>

namespace shell_element_test {

inline double internalForce(const ElementState& state, const double localStiffness[dofs][dofs], double force[dofs]) {
  return shell::shellInternalForce(state.reference, state.positions, state.rotations, localStiffness, force);
}

// Largest |entry| of the block (translation or rotation rows) x (translation or rotation
// columns): the blocks differ by orders of magnitude (t^2 / L^2), so each is compared
// with its own scale.
template <class MatrixT>
double blockMax(const MatrixT& matrix, bool rotationRows, bool rotationColumns) {
  double largest = 0.0;
  for (int r = 0; r < dofs; ++r)
    for (int c = 0; c < dofs; ++c)
      if (isRotation(r) == rotationRows && isRotation(c) == rotationColumns)
        largest = std::max(largest, std::abs(matrix[r][c]));
  return largest;
}

// Global small-displacement stiffness: the tangent at the reference state.
inline Eigen::MatrixXd assembleLinearStiffness(const Nodes& nodes, const Quads& quads,
                                               const shell::ShellSection& section) {
  const int n = 6 * static_cast<int>(nodes.size());
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(n, n);
  const auto connectivity = [&quads](std::size_t e, int a) { return quads[e][a]; };
  const std::vector<unsigned> quadraticEdges = shell::triangleQuadraticEdges(connectivity, quads.size());
  const double fullSection[4] = {1.0, 1.0, 1.0, 1.0};
  for (std::size_t e = 0; e < quads.size(); ++e) {
    const auto& quad = quads[e];
    double X[4][3], R[4][3][3] = {}, localStiffness[dofs][dofs], force[dofs], tangent[dofs][dofs];
    gather(nodes, quad, X);
    for (int a = 0; a < 4; ++a)
      for (int k = 0; k < 3; ++k) R[a][k][k] = 1.0;
    shell::checkShellElement(X, 0);
    shell::shellLocalStiffness(X, section, fullSection, quadraticEdges[e], localStiffness);
    shell::shellTangent(X, X, R, localStiffness, force, tangent);
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        for (int i = 0; i < 6; ++i)
          for (int j = 0; j < 6; ++j) K(6 * quad[a] + i, 6 * quad[b] + j) += tangent[6 * a + i][6 * b + j];
  }
  return K;
}

using Field = std::array<double, 6>;  // ux uy uz theta_x theta_y theta_z

struct PatchResult {
  double interiorError;        // max |u - exact| over interior DOF / max |exact| there
  double strainError;          // max |strain - exact| over elements and points / strain scale
  double rotationStrainError;  // transverse shear and drilling mismatch / max |rotation|
};

// Boundary nodes (0-3) take the exact field, the interior is solved; the strains of every
// element at its Gauss points and centre are compared with the exact local strains.
// exactMembrane: global eps_xx eps_yy gamma_xy; exactCurvature: kappa_xx kappa_yy kappa_xy.
// elements: quads, or triangles as a b c c.
template <class FieldT>
PatchResult runPatchTest(const FieldT& exact, const double exactMembrane[3], const double exactCurvature[3],
                         const Quads& quads = macNealHarderQuads()) {
  const Nodes nodes = macNealHarderNodes();
  shell::ShellSection section;
  section.youngModulus = 1e6;
  section.poissonRatio = 0.25;
  section.thickness = 0.001;
  const Eigen::MatrixXd K = assembleLinearStiffness(nodes, quads, section);
  const int boundary = 24, interior = 24;
  Eigen::VectorXd prescribed(boundary), exactInterior(interior);
  for (int node = 0; node < 8; ++node) {
    const Field value = exact(nodes[node][0], nodes[node][1]);
    for (int i = 0; i < 6; ++i) (node < 4 ? prescribed(6 * node + i) : exactInterior(6 * (node - 4) + i)) = value[i];
  }
  const Eigen::VectorXd solved =
      K.block(boundary, boundary, interior, interior).ldlt().solve(-K.block(boundary, 0, interior, boundary) * prescribed);
  PatchResult result{};
  result.interiorError = (solved - exactInterior).cwiseAbs().maxCoeff() / exactInterior.cwiseAbs().maxCoeff();

  Eigen::VectorXd u(48);
  u << prescribed, solved;
  double strainScale = 0.0, rotationScale = 0.0;
  for (int i = 0; i < 3; ++i) strainScale = std::max({strainScale, std::abs(exactMembrane[i]), std::abs(exactCurvature[i])});
  for (int i = 0; i < 48; ++i)
    if (i % 6 >= 3) rotationScale = std::max(rotationScale, std::abs(u(i)));
  for (const auto& quad : quads) {
    double X[4][3];
    gather(nodes, quad, X);
    const shell::ShellReference reference = shell::shellReference(X);
    // Small displacements: local DOF = E0^T (translation, rotation) per node.
    double localDofs[dofs];
    for (int a = 0; a < 4; ++a)
      for (int part = 0; part < 2; ++part)
        for (int i = 0; i < 3; ++i) {
          double sum = 0.0;
          for (int k = 0; k < 3; ++k) sum += reference.frame[i][k] * u(6 * quad[a] + 3 * part + k);
          localDofs[6 * a + 3 * part + i] = sum;
        }
    // Exact strains in the element frame: F eps F^T, F the in-plane rows of E0^T.
    double exactLocal[6];
    for (int kind = 0; kind < 2; ++kind) {
      const double* global = kind == 0 ? exactMembrane : exactCurvature;
      const double tensor[2][2] = {{global[0], 0.5 * global[2]}, {0.5 * global[2], global[1]}};
      double rotated[2][2];
      for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j) {
          double sum = 0.0;
          for (int k = 0; k < 2; ++k)
            for (int l = 0; l < 2; ++l) sum += reference.frame[i][k] * tensor[k][l] * reference.frame[j][l];
          rotated[i][j] = sum;
        }
      exactLocal[3 * kind] = rotated[0][0];
      exactLocal[3 * kind + 1] = rotated[1][1];
      exactLocal[3 * kind + 2] = 2.0 * rotated[0][1];
    }
    const double points[5][2] = {{-0.57735026918962576, -0.57735026918962576},
                                 {0.57735026918962576, -0.57735026918962576},
                                 {0.57735026918962576, 0.57735026918962576},
                                 {-0.57735026918962576, 0.57735026918962576},
                                 {0.0, 0.0}};
    const bool triangle = quad[3] == quad[2];
    for (const auto& point : points) {
      double strains[shell::shellStrainCount];
      if (triangle) {  // at the centroid, once
        if (&point != &points[4]) continue;
        double B[shell::shellStrainCount][dofs];
        shell::shellCentreStrainDisplacement(reference, B);
        for (int i = 0; i < shell::shellStrainCount; ++i) {
          strains[i] = 0.0;
          for (int c = 0; c < dofs; ++c) strains[i] += B[i][c] * localDofs[c];
        }
      } else {
        shell::shellLocalStrains(X, localDofs, point[0], point[1], strains);
      }
      for (int i = 0; i < 6; ++i)
        result.strainError = std::max(result.strainError, std::abs(strains[i] - exactLocal[i]) / strainScale);
      for (int i = 6; i < 9; ++i)
        result.rotationStrainError = std::max(result.rotationStrainError, std::abs(strains[i]) / rotationScale);
    }
  }
  return result;
}

// Sze, Liu & Lo (2004) 3.2 (model.md §8): a strip L = 12, b = 1, t = 0.1, E = 1.2e6, nu = 0,
// clamped, an end moment about -y growing to M_max = 2 pi E I / L in `steps` increments,
// solved by Newton with the exact Jacobian (K_T plus the rotation asymmetry; the applied
// moment is a fixed spatial vector). Returns the tip (u, w) at each step's end and the
// most Newton iterations any step took.
struct RollUpResult {
  std::vector<std::array<double, 2>> tip;  // (u, w) per step
  std::vector<double> loadFactor;
  int mostIterations = 0;
  bool converged = true;
};

struct ElementMatrix {
  double values[dofs][dofs];
};

inline RollUpResult rollUpCantilever(int cells, int steps) {
  // A 200-DOF dense solve gains nothing from Eigen's own OpenMP threads, which only
  // contend with Kokkos' on the test machine's two cores.
  Eigen::setNbThreads(1);
  const double length = 12.0, width = 1.0;
  shell::ShellSection section;
  section.youngModulus = 1.2e6;
  section.poissonRatio = 0.0;
  section.thickness = 0.1;
  const double inertia = width * std::pow(section.thickness, 3) / 12.0;
  const double maximumMoment = 2.0 * 3.14159265358979323846 * section.youngModulus * inertia / length;
  Nodes nodes;
  Quads quads;
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i <= cells; ++i) nodes.push_back({length * i / cells, width * j, 0.0});
  for (int i = 0; i < cells; ++i) quads.push_back({i, i + 1, cells + 2 + i, cells + 1 + i});
  const int nodeCount = static_cast<int>(nodes.size());
  std::vector<ElementMatrix> localStiffness(quads.size());
  for (std::size_t e = 0; e < quads.size(); ++e) {
    double X[4][3];
    gather(nodes, quads[e], X);
    shell::shellLocalStiffness(X, section, localStiffness[e].values);
  }
  Nodes positions = nodes;
  std::vector<std::array<double, 9>> rotations(nodeCount, {1, 0, 0, 0, 1, 0, 0, 0, 1});
  std::vector<int> freeDofs;
  for (int node = 0; node < nodeCount; ++node)
    if (node != 0 && node != cells + 1)
      for (int i = 0; i < 6; ++i) freeDofs.push_back(6 * node + i);
  const int n = static_cast<int>(freeDofs.size());
  const int tipNodes[2] = {cells, 2 * cells + 1};

  RollUpResult result;
  for (int step = 1; step <= steps; ++step) {
    const double factor = double(step) / steps;
    Eigen::VectorXd external = Eigen::VectorXd::Zero(6 * nodeCount);
    for (int tip : tipNodes) external(6 * tip + 4) = -0.5 * factor * maximumMoment;
    int iteration = 0;
    for (;; ++iteration) {
      Eigen::VectorXd residual = -external;
      Eigen::MatrixXd jacobian = Eigen::MatrixXd::Zero(6 * nodeCount, 6 * nodeCount);
      for (std::size_t e = 0; e < quads.size(); ++e) {
        double X[4][3], x[4][3], R[4][3][3], force[dofs], tangent[dofs][dofs];
        gather(nodes, quads[e], X);
        gather(positions, quads[e], x);
        for (int a = 0; a < 4; ++a)
          for (int k = 0; k < 9; ++k) R[a][k / 3][k % 3] = rotations[quads[e][a]][k];
        shell::shellTangent(X, x, R, localStiffness[e].values, force, tangent);
        shell::addRotationAsymmetry(force, tangent);
        for (int a = 0; a < 4; ++a)
          for (int i = 0; i < 6; ++i) {
            residual(6 * quads[e][a] + i) += force[6 * a + i];
            for (int b = 0; b < 4; ++b)
              for (int j = 0; j < 6; ++j) jacobian(6 * quads[e][a] + i, 6 * quads[e][b] + j) += tangent[6 * a + i][6 * b + j];
          }
      }
      Eigen::VectorXd freeResidual(n);
      Eigen::MatrixXd freeJacobian(n, n);
      for (int r = 0; r < n; ++r) {
        freeResidual(r) = residual(freeDofs[r]);
        for (int c = 0; c < n; ++c) freeJacobian(r, c) = jacobian(freeDofs[r], freeDofs[c]);
      }
      if (freeResidual.cwiseAbs().maxCoeff() <= 1e-9 * maximumMoment) break;
      if (iteration == 30) {
        result.converged = false;
        return result;
      }
      const Eigen::VectorXd correction = freeJacobian.partialPivLu().solve(-freeResidual);
      for (int r = 0; r < n; ++r) {
        const int node = freeDofs[r] / 6, component = freeDofs[r] % 6;
        if (component < 3) positions[node][component] += correction(r);
        if (component != 5) continue;
        // Multiplicative rotation update (model.md §5): R <- exp(dphi) R.
        const double increment[3] = {correction(r - 2), correction(r - 1), correction(r)};
        double Q[3][3], R[3][3], updated[3][3];
        rotationMatrix(increment, Q);
        for (int k = 0; k < 9; ++k) R[k / 3][k % 3] = rotations[node][k];
        multiply(Q, R, updated);
        for (int k = 0; k < 9; ++k) rotations[node][k] = updated[k / 3][k % 3];
      }
    }
    result.mostIterations = std::max(result.mostIterations, iteration);
    std::array<double, 2> tip = {0.0, 0.0};
    for (int node : tipNodes) {
      tip[0] += 0.5 * (positions[node][0] - nodes[node][0]);
      tip[1] += 0.5 * (positions[node][2] - nodes[node][2]);
    }
    result.tip.push_back(tip);
    result.loadFactor.push_back(factor);
  }
  return result;
}

// Device evaluation: one thread per element computes K_l, f (shellInternalForce) and K_T
// with its force (shellTangent).
struct DeviceResults {
  Kokkos::View<double* [dofs][dofs], Kokkos::LayoutRight, Kokkos::HostSpace> localStiffness, tangent;
  Kokkos::View<double* [dofs], Kokkos::LayoutRight, Kokkos::HostSpace> force, tangentForce;
  Kokkos::View<double* [2], Kokkos::LayoutRight, Kokkos::HostSpace> energy;
};

template <class ExecutionSpaceT>
DeviceResults evaluateOnDevice(const ExecutionSpaceT& space, const HostPositions& referenceHost,
                               const HostPositions& positionsHost, const HostRotations& rotationsHost,
                               const shell::ShellSection section) {
  static_assert(perishell::is_execution_space_v<ExecutionSpaceT>);
  using MemorySpace = typename ExecutionSpaceT::memory_space;
  const auto references = Kokkos::create_mirror_view_and_copy(MemorySpace{}, referenceHost);
  const auto positions = Kokkos::create_mirror_view_and_copy(MemorySpace{}, positionsHost);
  const auto rotations = Kokkos::create_mirror_view_and_copy(MemorySpace{}, rotationsHost);
  const int count = static_cast<int>(referenceHost.extent(0));
  Kokkos::View<double* [dofs][dofs], Kokkos::LayoutRight, MemorySpace> localStiffnessOut("K_l", count),
      tangentOut("K_T", count);
  Kokkos::View<double* [dofs], Kokkos::LayoutRight, MemorySpace> forceOut("f", count), tangentForceOut("f_T", count);
  Kokkos::View<double* [2], Kokkos::LayoutRight, MemorySpace> energyOut("W", count);
  Kokkos::parallel_for(
      "shell_element_test::evaluate", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, count),
      KOKKOS_LAMBDA(const int e) {
        double X[4][3], x[4][3], R[4][3][3];
        for (int a = 0; a < 4; ++a)
          for (int k = 0; k < 3; ++k) {
            X[a][k] = references(e, a, k);
            x[a][k] = positions(e, a, k);
            for (int l = 0; l < 3; ++l) R[a][k][l] = rotations(e, a, k, l);
          }
        double localStiffness[dofs][dofs], force[dofs], tangentForce[dofs], tangent[dofs][dofs];
        shell::shellLocalStiffness(X, section, localStiffness);
        energyOut(e, 0) = shell::shellInternalForce(X, x, R, localStiffness, force);
        energyOut(e, 1) = shell::shellTangent(X, x, R, localStiffness, tangentForce, tangent);
        for (int r = 0; r < dofs; ++r) {
          forceOut(e, r) = force[r];
          tangentForceOut(e, r) = tangentForce[r];
          for (int c = 0; c < dofs; ++c) {
            localStiffnessOut(e, r, c) = localStiffness[r][c];
            tangentOut(e, r, c) = tangent[r][c];
          }
        }
      });
  return {Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, localStiffnessOut),
          Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, tangentOut),
          Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, forceOut),
          Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, tangentForceOut),
          Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, energyOut)};
}

}  // namespace shell_element_test

namespace {

using namespace shell_element_test;

TEST(TEST_CATEGORY, shell_membrane_patch_test_is_exact) {
  // Linear in-plane field with a rigid rotation part: theta_z = omega = 1/2 (v,x - u,y).
  const auto exact = [](double x, double y) -> Field {
    const double u = 1e-5 + 1e-3 * (2.0 * x + 0.3 * y), v = -2e-5 + 1e-3 * (0.2 * x - y);
    return {u, v, 0.0, 0.0, 0.0, 0.5 * 1e-3 * (0.2 - 0.3)};
  };
  const double membrane[3] = {2e-3, -1e-3, 0.5e-3}, curvature[3] = {0.0, 0.0, 0.0};
  const PatchResult result = runPatchTest(exact, membrane, curvature);
  std::cout << "membrane patch: interior error " << result.interiorError << ", strain error " << result.strainError
            << ", shear/drilling " << result.rotationStrainError << "\n";
  EXPECT_LT(result.interiorError, 1e-10);
  EXPECT_LT(result.strainError, 1e-10);
  EXPECT_LT(result.rotationStrainError, 1e-10);
}

TEST(TEST_CATEGORY, shell_bending_patch_test_is_exact) {
  // w quadratic, rotations its exact slopes (theta_x = w,y, theta_y = -w,x): constant
  // curvature kappa = (-a, -b, -2c), zero transverse shear.
  const double a = 1e-3, b = 2e-3, c = 0.5e-3;
  const auto exact = [=](double x, double y) -> Field {
    const double w = 1e-4 + 2e-3 * x - 1e-3 * y + 0.5 * (a * x * x + 2.0 * c * x * y + b * y * y);
    const double dwdx = 2e-3 + a * x + c * y, dwdy = -1e-3 + c * x + b * y;
    return {0.0, 0.0, w, dwdy, -dwdx, 0.0};
  };
  const double membrane[3] = {0.0, 0.0, 0.0}, curvature[3] = {-a, -b, -2.0 * c};
  const PatchResult result = runPatchTest(exact, membrane, curvature);
  std::cout << "bending patch: interior error " << result.interiorError << ", strain error " << result.strainError
            << ", shear/drilling " << result.rotationStrainError << "\n";
  EXPECT_LT(result.interiorError, 1e-8);
  EXPECT_LT(result.strainError, 1e-8);
  EXPECT_LT(result.rotationStrainError, 1e-8);
}

TEST(TEST_CATEGORY, shell_thin_cantilever_has_no_shear_locking) {
  // L/t = 1000: a locking element would be orders of magnitude too stiff.
  const double ratio16 = cantileverTipRatio(16, 0.0, assembleLinearStiffness),
               ratio64 = cantileverTipRatio(64, 0.0, assembleLinearStiffness);
  std::cout << "cantilever tip / (P L^3 / 3EI): 16 x 1 " << ratio16 << ", 64 x 1 " << ratio64 << "\n";
  EXPECT_NEAR(ratio16, 1.0, 0.01);
  EXPECT_NEAR(ratio64, 1.0, 0.01);
  EXPECT_LT(std::abs(ratio64 - 1.0), std::abs(ratio16 - 1.0) + 1e-12);
}

TEST(TEST_CATEGORY, shell_cantilever_end_moment_rolls_into_a_circle) {
  // Exact (model.md §8): theta = M L / (E I), -u = L (1 - sin(theta)/theta),
  // w = L (1 - cos(theta)) / theta; at M_max the strip closes into a full circle.
  const int steps = 20;
  const RollUpResult result = rollUpCantilever(16, steps);
  ASSERT_TRUE(result.converged);
  const double length = 12.0, pi = 3.14159265358979323846;
  double worst = 0.0;
  for (int step = 0; step < steps; ++step) {
    const double theta = 2.0 * pi * result.loadFactor[step];
    const double u = -length * (1.0 - std::sin(theta) / theta), w = length * (1.0 - std::cos(theta)) / theta;
    worst = std::max({worst, std::abs(result.tip[step][0] - u) / length, std::abs(result.tip[step][1] - w) / length});
  }
  std::cout << "end moment 16 x 1, " << steps << " steps: tip at M_max (" << result.tip.back()[0] << ", "
            << result.tip.back()[1] << "), exact (-12, 0); max tip error / L " << worst << "; most Newton iterations "
            << result.mostIterations << "\n";
  EXPECT_LT(worst, 0.01);
  EXPECT_LE(result.mostIterations, 8);
}

TEST(TEST_CATEGORY, shell_rigid_motions_give_zero_force) {
  const shell::ShellSection section = thickSection();
  double X[4][3], localStiffness[dofs][dofs];
  warpedReference(X);
  shell::shellLocalStiffness(X, section, localStiffness);
  const double length = std::sqrt(shell::shellReferenceArea(X));
  const double forceScale = section.youngModulus * section.thickness * length;
  const double halfPi = 1.5707963267948966;
  const double skew = halfPi / std::sqrt(14.0);
  const double rotations[5][3] = {
      {halfPi, 0, 0}, {0, halfPi, 0}, {0, 0, halfPi}, {skew, 2 * skew, 3 * skew}, {-1.2, 2.0, 0.9}};
  const double shift[3] = {0.3, -1.2, 2.0};
  double worst = 0.0;
  for (const auto& rotationVector : rotations) {
    const ElementState state = rigidlyMoved(X, rotationVector, shift);
    double force[dofs], d[dofs];
    shell::shellDeformationalDofs(state.reference, state.positions, state.rotations, d);
    const double energy = internalForce(state, localStiffness, force);
    for (int i = 0; i < dofs; ++i) {
      EXPECT_LE(std::abs(d[i]), 1e-14 * (isRotation(i) ? 1.0 : length));
      // Moments carry one more length than forces.
      worst = std::max(worst, std::abs(force[i]) / (forceScale * (isRotation(i) ? length : 1.0)));
    }
    EXPECT_LE(energy, 1e-20 * forceScale * length);
  }
  std::cout << "rigid motions: max |f| / (E t L) " << worst << "\n";
  EXPECT_LE(worst, 1e-10);
}

TEST(TEST_CATEGORY, shell_force_rotates_with_a_rigid_rotation) {
  const ElementState state = stronglyDeformed();
  double localStiffness[dofs][dofs], force[dofs], rotatedForce[dofs];
  shell::shellLocalStiffness(state.reference, thickSection(), localStiffness);
  const double energy = internalForce(state, localStiffness, force);
  double Q[3][3];
  const ElementState rotated = rigidlyRotated(state, Q);
  const double rotatedEnergy = internalForce(rotated, localStiffness, rotatedForce);
  EXPECT_NEAR(rotatedEnergy, energy, 1e-12 * energy);
  EXPECT_GT(energy, 0.0);
  double worst[2] = {0.0, 0.0}, scale[2] = {0.0, 0.0};
  for (int j = 0; j < dofs; j += 3) {
    const int part = isRotation(j) ? 1 : 0;
    for (int i = 0; i < 3; ++i) {
      const double expected = Q[i][0] * force[j] + Q[i][1] * force[j + 1] + Q[i][2] * force[j + 2];
      worst[part] = std::max(worst[part], std::abs(rotatedForce[j + i] - expected));
      scale[part] = std::max(scale[part], std::abs(force[j + i]));
    }
  }
  std::cout << "rotated force: relative error forces " << worst[0] / scale[0] << ", moments " << worst[1] / scale[1]
            << "\n";
  EXPECT_LE(worst[0], 1e-10 * scale[0]);
  EXPECT_LE(worst[1], 1e-10 * scale[1]);
}

TEST(TEST_CATEGORY, shell_force_is_the_energy_gradient) {
  const ElementState state = stronglyDeformed();
  double localStiffness[dofs][dofs], force[dofs], ignored[dofs];
  shell::shellLocalStiffness(state.reference, thickSection(), localStiffness);
  internalForce(state, localStiffness, force);
  const double h = 1e-5;
  double error[2] = {0.0, 0.0}, scale[2] = {0.0, 0.0};
  for (int j = 0; j < dofs; ++j) {
    const double difference = (internalForce(perturbed(state, j, h), localStiffness, ignored) -
                               internalForce(perturbed(state, j, -h), localStiffness, ignored)) / (2.0 * h);
    error[isRotation(j)] = std::max(error[isRotation(j)], std::abs(difference - force[j]));
    scale[isRotation(j)] = std::max(scale[isRotation(j)], std::abs(force[j]));
  }
  std::cout << "f vs dW/dq: relative error forces " << error[0] / scale[0] << ", moments " << error[1] / scale[1]
            << "\n";
  EXPECT_LE(error[0], 1e-6 * scale[0]);
  EXPECT_LE(error[1], 1e-6 * scale[1]);
}

TEST(TEST_CATEGORY, shell_tangent_is_the_force_derivative) {
  const ElementState state = stronglyDeformed();
  double localStiffness[dofs][dofs], force[dofs], tangent[dofs][dofs], forceOnly[dofs];
  shell::shellLocalStiffness(state.reference, thickSection(), localStiffness);
  const double energy = shell::shellTangent(state.reference, state.positions, state.rotations, localStiffness, force,
                                            tangent);
  EXPECT_DOUBLE_EQ(energy, internalForce(state, localStiffness, forceOnly));
  for (int i = 0; i < dofs; ++i) EXPECT_EQ(force[i], forceOnly[i]);
  double asymmetry = 0.0, largest = 0.0;
  for (int r = 0; r < dofs; ++r)
    for (int c = 0; c < dofs; ++c) {
      asymmetry = std::max(asymmetry, std::abs(tangent[r][c] - tangent[c][r]));
      largest = std::max(largest, std::abs(tangent[r][c]));
    }
  EXPECT_LE(asymmetry, 1e-14 * largest);

  // Column j of the finite difference of f under the multiplicative update.
  const double h = 1e-5;
  double difference[dofs][dofs], plus[dofs], minus[dofs];
  for (int j = 0; j < dofs; ++j) {
    internalForce(perturbed(state, j, h), localStiffness, plus);
    internalForce(perturbed(state, j, -h), localStiffness, minus);
    for (int i = 0; i < dofs; ++i) difference[i][j] = (plus[i] - minus[i]) / (2.0 * h);
  }
  double exact[dofs][dofs];
  for (int r = 0; r < dofs; ++r)
    for (int c = 0; c < dofs; ++c) exact[r][c] = tangent[r][c];
  shell::addRotationAsymmetry(force, exact);
  for (int rowBlock = 0; rowBlock < 2; ++rowBlock)
    for (int columnBlock = 0; columnBlock < 2; ++columnBlock) {
      double exactError = 0.0, symmetricError = 0.0;
      for (int r = 0; r < dofs; ++r)
        for (int c = 0; c < dofs; ++c)
          if (isRotation(r) == bool(rowBlock) && isRotation(c) == bool(columnBlock)) {
            exactError = std::max(exactError, std::abs(exact[r][c] - difference[r][c]));
            symmetricError = std::max(symmetricError, std::abs(tangent[r][c] - difference[r][c]));
          }
      const double scale = blockMax(tangent, rowBlock, columnBlock);
      std::cout << "K_T block (" << (rowBlock ? "rot" : "trans") << ", " << (columnBlock ? "rot" : "trans")
                << "): max " << scale << ", exact-Jacobian error " << exactError / scale
                << ", symmetric K_T vs df error " << symmetricError / scale << "\n";
      EXPECT_LE(exactError, 1e-5 * scale);
      // Only the rotation-rotation block carries the -1/2 skew(m) part, and here it is large
      // enough for the check to tell the two apart.
      if (rowBlock == 1 && columnBlock == 1) EXPECT_GT(symmetricError, 1e-3 * scale);
      else EXPECT_LE(symmetricError, 1e-5 * scale);
    }
}

TEST(TEST_CATEGORY, shell_device_evaluation_matches_host) {
  const shell::ShellSection section = thickSection();
  const std::array<ElementState, 3> states = deviceTestStates();
  const auto [references, positions, rotations] = hostViews(states);
  const DeviceResults device = evaluateOnDevice(TEST_EXECSPACE{}, references, positions, rotations, section);
  for (int e = 0; e < 3; ++e) {
    double localStiffness[dofs][dofs], force[dofs], tangentForce[dofs], tangent[dofs][dofs];
    shell::shellLocalStiffness(states[e].reference, section, localStiffness);
    const double energy = internalForce(states[e], localStiffness, force);
    shell::shellTangent(states[e].reference, states[e].positions, states[e].rotations, localStiffness, tangentForce,
                        tangent);
    double stiffnessScale = 0.0, tangentScale = 0.0, forceScale = 1e-300;
    for (int r = 0; r < dofs; ++r) {
      forceScale = std::max(forceScale, std::abs(force[r]));
      for (int c = 0; c < dofs; ++c) {
        stiffnessScale = std::max(stiffnessScale, std::abs(localStiffness[r][c]));
        tangentScale = std::max(tangentScale, std::abs(tangent[r][c]));
      }
    }
    // Rigidly moved: the force and the energy are round-off (d ~ 1e-16 of the coordinates, which
    // each backend's own rounding and contractions make differently); compare them on the
    // stiffness scale instead.
    double size = 0.0;
    for (int a = 0; a < 4; ++a)
      for (int k = 0; k < 3; ++k) size = std::max(size, std::abs(states[e].positions[a][k]));
    const double energyTolerance =
        e == 0 ? stiffnessScale * (1e-14 * size) * (1e-14 * size) : 1e-11 * std::max(energy, 1e-300) + 1e-30;
    if (e == 0) forceScale = stiffnessScale;
    EXPECT_NEAR(device.energy(e, 0), energy, energyTolerance);
    EXPECT_NEAR(device.energy(e, 1), energy, energyTolerance);
    for (int r = 0; r < dofs; ++r) {
      EXPECT_NEAR(device.force(e, r), force[r], 1e-11 * forceScale) << "element " << e << " row " << r;
      EXPECT_NEAR(device.tangentForce(e, r), force[r], 1e-11 * forceScale) << "element " << e << " row " << r;
      for (int c = 0; c < dofs; ++c) {
        EXPECT_NEAR(device.localStiffness(e, r, c), localStiffness[r][c], 1e-12 * stiffnessScale);
        EXPECT_NEAR(device.tangent(e, r, c), tangent[r][c], 1e-11 * tangentScale);
      }
    }
  }
}

// The message names the element and the reason.
void expectRejected(const double X[4][3], const std::string& reason) {
  try {
    shell::checkShellElement(X, 7);
    ADD_FAILURE() << "accepted a degenerate element (" << reason << ")";
  } catch (const std::invalid_argument& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("shell element 7: "), std::string::npos) << message;
    EXPECT_NE(message.find(reason), std::string::npos) << message;
  }
}

TEST(TEST_CATEGORY, shell_degenerate_input_is_rejected) {
  const double collinear[4][3] = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
  const double coincident[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 0, 0}, {0, 1, 0}};
  const double bowTie[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  const double reEntrant[4][3] = {{0, 0, 0}, {2, 0, 0}, {0.5, 0.5, 0}, {0, 2, 0}};
  const double notFinite[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, NAN, 0}, {0, 1, 0}};
  expectRejected(collinear, "zero or negative area");
  expectRejected(coincident, "zero or negative area");
  expectRejected(bowTie, "zero or negative area");
  expectRejected(reEntrant, "corner 2");
  expectRejected(notFinite, "node 2 has a non-finite coordinate");
  // Clockwise numbering only flips the element normal: a valid element.
  const double clockwise[4][3] = {{0, 0, 0}, {0, 1, 0}, {1, 1, 0}, {1, 0, 0}};
  EXPECT_NO_THROW(shell::checkShellElement(clockwise, 7));
  double warped[4][3];
  warpedReference(warped);
  EXPECT_NO_THROW(shell::checkShellElement(warped, 7));

  shell::ShellSection section = thickSection();
  EXPECT_NO_THROW(shell::checkShellSection(section));
  section.thickness = 0.0;
  EXPECT_THROW(shell::checkShellSection(section), std::invalid_argument);
  section = thickSection();
  section.poissonRatio = 0.5;
  try {
    shell::checkShellSection(section);
    ADD_FAILURE() << "accepted nu = 0.5";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("poisson ratio must lie in (-1, 0.5)"), std::string::npos);
  }
}

// Triangles (a b c c): the element's K_l is shell/mitc3_triangle.hpp's, the rest is shared.

TEST(TEST_CATEGORY, shell_triangle_patch_tests_are_exact) {
  const auto membraneField = [](double x, double y) -> Field {
    const double u = 1e-5 + 1e-3 * (2.0 * x + 0.3 * y), v = -2e-5 + 1e-3 * (0.2 * x - y);
    return {u, v, 0.0, 0.0, 0.0, 0.5 * 1e-3 * (0.2 - 0.3)};
  };
  const double a = 1e-3, b = 2e-3, c = 0.5e-3;
  const auto bendingField = [=](double x, double y) -> Field {
    const double w = 1e-4 + 2e-3 * x - 1e-3 * y + 0.5 * (a * x * x + 2.0 * c * x * y + b * y * y);
    const double dwdx = 2e-3 + a * x + c * y, dwdy = -1e-3 + c * x + b * y;
    return {0.0, 0.0, w, dwdy, -dwdx, 0.0};
  };
  const double membrane[3] = {2e-3, -1e-3, 0.5e-3}, noCurvature[3] = {0.0, 0.0, 0.0};
  const double noMembrane[3] = {0.0, 0.0, 0.0}, curvature[3] = {-a, -b, -2.0 * c};
  for (const auto& [name, elements] : {std::make_pair("triangles", macNealHarderTriangles()),
                                       std::make_pair("quads and triangles", macNealHarderMixed())}) {
    const PatchResult stretched = runPatchTest(membraneField, membrane, noCurvature, elements);
    const PatchResult bent = runPatchTest(bendingField, noMembrane, curvature, elements);
    std::cout << name << ": membrane patch interior error " << stretched.interiorError << ", strain error "
              << stretched.strainError << "; bending patch " << bent.interiorError << ", " << bent.strainError
              << ", shear/drilling " << bent.rotationStrainError << "\n";
    EXPECT_LT(stretched.interiorError, 1e-10) << name;
    EXPECT_LT(stretched.strainError, 1e-10) << name;
    EXPECT_LT(stretched.rotationStrainError, 1e-10) << name;
    EXPECT_LT(bent.interiorError, 1e-8) << name;
    EXPECT_LT(bent.strainError, 1e-8) << name;
    EXPECT_LT(bent.rotationStrainError, 1e-8) << name;
  }
}

TEST(TEST_CATEGORY, shell_thin_triangle_cantilever_has_no_shear_locking) {
  // L/t = 1000, each cell two triangles. MITC3 ties the shear along the edges: a plain linear
  // triangle would be orders of magnitude too stiff here.
  const double ratio16 = cantileverTipRatio(16, 0.0, assembleLinearStiffness, true),
               ratio64 = cantileverTipRatio(64, 0.0, assembleLinearStiffness, true);
  std::cout << "triangle cantilever tip / (P L^3 / 3EI): 16 x 1 " << ratio16 << ", 64 x 1 " << ratio64 << "\n";
  EXPECT_NEAR(ratio16, 1.0, 0.05);
  EXPECT_NEAR(ratio64, 1.0, 0.01);
  EXPECT_LT(std::abs(ratio64 - 1.0), std::abs(ratio16 - 1.0));
}

TEST(TEST_CATEGORY, shell_triangle_rigid_motions_and_energy_gradient) {
  const shell::ShellSection section = thickSection();
  double X[4][3];
  triangleReference(X);
  ASSERT_TRUE(shell::isTriangleElement(X));
  double localStiffness[dofs][dofs];
  shell::shellLocalStiffness(X, section, localStiffness);
  for (int i = 0; i < dofs; ++i) {
    EXPECT_EQ(localStiffness[i][18], 0.0);
    EXPECT_EQ(localStiffness[18][i], 0.0);
  }
  const double length = 1.0, forceScale = section.youngModulus * section.thickness * length;
  const double rotations[3][3] = {{1.5707963267948966, 0, 0}, {0.3, -1.1, 0.7}, {-1.2, 2.0, 0.9}};
  const double shift[3] = {0.3, -1.2, 2.0};
  double worst = 0.0;
  for (const auto& rotationVector : rotations) {
    const ElementState state = rigidlyMoved(X, rotationVector, shift);
    double force[dofs];
    const double energy = internalForce(state, localStiffness, force);
    for (int i = 0; i < dofs; ++i)
      worst = std::max(worst, std::abs(force[i]) / (forceScale * (isRotation(i) ? length : 1.0)));
    EXPECT_LE(energy, 1e-20 * forceScale * length);
  }
  std::cout << "triangle rigid motions: max |f| / (E t L) " << worst << "\n";
  EXPECT_LE(worst, 1e-10);

  // A strong deformation: f = dW/dq, with node 3 moving and turning with node 2.
  const ElementState state = stronglyDeformedTriangle();
  double force[dofs], ignored[dofs];
  internalForce(state, localStiffness, force);
  double error = 0.0, scale = 0.0;
  const double h = 1e-5;
  for (int j = 0; j < 18; ++j) {  // node 2's DOF move node 3 too
    ElementState plus = perturbed(state, j, h), minus = perturbed(state, j, -h);
    if (j >= 12) {
      plus = perturbed(plus, j + 6, h);
      minus = perturbed(minus, j + 6, -h);
    }
    const double difference =
        (internalForce(plus, localStiffness, ignored) - internalForce(minus, localStiffness, ignored)) / (2.0 * h);
    const double assembled = j >= 12 ? force[j] + force[j + 6] : force[j];
    error = std::max(error, std::abs(difference - assembled));
    scale = std::max(scale, std::abs(assembled));
  }
  std::cout << "triangle f vs dW/dq: relative error " << error / scale << "\n";
  EXPECT_GT(scale, 0.0);
  EXPECT_LE(error, 1e-6 * scale);
}

TEST(TEST_CATEGORY, shell_triangle_on_three_nodes_equals_the_collapsed_quad) {
  // The solvers evaluate a triangle with N = 3 (18 DOF); it must be the collapsed quad (N = 4,
  // node 3 moving and turning with node 2) exactly: f_3 = P^T f_4, K_3 = P^T K_4 P, P the
  // 24 x 18 map that copies node 2's DOF to node 3.
  const ElementState state = stronglyDeformedTriangle();
  const auto& X = state.reference;
  double K4[dofs][dofs], K3[18][18], f4[dofs], f3[18], T4[dofs][dofs], T3[18][18];
  shell::shellLocalStiffness(X, thickSection(), K4);
  for (int r = 0; r < 18; ++r)
    for (int c = 0; c < 18; ++c) K3[r][c] = K4[r][c];
  const double W4 = shell::shellTangent(state.reference, state.positions, state.rotations, K4, f4, T4);
  shell::addRotationAsymmetry(f4, T4);
  const double W3 = shell::shellTangent<3>(state.reference, state.positions, state.rotations, K3, f3, T3);
  shell::addRotationAsymmetry<3>(f3, T3);
  EXPECT_NEAR(W3, W4, 1e-12 * W4);
  const auto collapsed = [](int i) { return i < 12 ? std::vector<int>{i} : std::vector<int>{i, i + 6}; };
  double forceError = 0.0, forceScale = 0.0, tangentError = 0.0, tangentScale = 0.0;
  for (int i = 0; i < 18; ++i) {
    double sum = 0.0;
    for (const int k : collapsed(i)) sum += f4[k];
    forceError = std::max(forceError, std::abs(f3[i] - sum));
    forceScale = std::max(forceScale, std::abs(sum));
    for (int j = 0; j < 18; ++j) {
      double block = 0.0;
      for (const int k : collapsed(i))
        for (const int l : collapsed(j)) block += T4[k][l];
      tangentError = std::max(tangentError, std::abs(T3[i][j] - block));
      tangentScale = std::max(tangentScale, std::abs(block));
    }
  }
  double forceOnly[18];
  EXPECT_DOUBLE_EQ(shell::shellInternalForce<3>(state.reference, state.positions, state.rotations, K3, forceOnly), W3);
  for (int i = 0; i < 18; ++i) EXPECT_EQ(forceOnly[i], f3[i]);
  std::cout << "triangle N = 3 vs collapsed quad: force error " << forceError / forceScale << ", tangent error "
            << tangentError / tangentScale << "\n";
  EXPECT_LE(forceError, 1e-12 * forceScale);
  EXPECT_LE(tangentError, 1e-12 * tangentScale);
}

TEST(TEST_CATEGORY, shell_degenerate_triangles_are_rejected) {
  const double collinear[4][3] = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {2, 0, 0}};
  const double coincident[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 0, 0}, {0, 0, 0}};
  for (const auto* X : {collinear, coincident}) {
    try {
      shell::checkShellElement(X, 7);
      ADD_FAILURE() << "accepted a degenerate triangle";
    } catch (const std::invalid_argument& error) {
      EXPECT_NE(std::string(error.what()).find("shell triangle 7: zero or negative area"), std::string::npos)
          << error.what();
    }
  }
  const double clockwise[4][3] = {{0, 0, 0}, {0, 1, 0}, {1, 0, 0}, {1, 0, 0}};
  EXPECT_NO_THROW(shell::checkShellElement(clockwise, 7));
}

}  // namespace
