#pragma once
// Element states and meshes the shell element tests share (tests/shell): rotations, a warped
// reference quad, rigid and strong deformations, perturbations q_j + h, and the MacNeal &
// Harder distorted patch.
#include <perishell/core/rotation.hpp>
#include <perishell/core/types.hpp>
#include <perishell/shell/mitc4_shell.hpp>

// Eigen serves host-side dense solves only: keep it out of nvcc's device annotations.
#ifndef EIGEN_NO_CUDA
#define EIGEN_NO_CUDA
#endif
#include <Eigen/Dense>

#include <array>
#include <cmath>
#include <functional>
#include <vector>

namespace shell_element_test {

namespace shell = perishell::shell;
constexpr int dofs = shell::shellDofCount;

inline void rotationMatrix(const double rotationVector[3], double R[3][3]) {
  double q[4];
  perishell::rotation::exponential(rotationVector, q);
  perishell::rotation::toMatrix(q, R);
}

inline void multiply(const double A[3][3], const double B[3][3], double out[3][3]) {
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) out[i][j] = A[i][0] * B[0][j] + A[i][1] * B[1][j] + A[i][2] * B[2][j];
}

struct ElementState {
  double reference[4][3];
  double positions[4][3];
  double rotations[4][3][3];
};

// An element state's rotations as unit quaternions (the explicit elements read them so).
struct ElementQuaternions {
  double q[4][4];
};

inline ElementQuaternions quaternionsOf(const ElementState& state) {
  ElementQuaternions out;
  for (int a = 0; a < 4; ++a) perishell::rotation::fromMatrix(state.rotations[a], out.q[a]);
  return out;
}

// A warped, distorted reference element of about 1 m.
inline void warpedReference(double X[4][3]) {
  const double nodes[4][3] = {{0.0, 0.0, 0.0}, {1.1, 0.1, 0.03}, {1.0, 0.9, -0.02}, {-0.1, 0.8, 0.04}};
  for (int a = 0; a < 4; ++a)
    for (int k = 0; k < 3; ++k) X[a][k] = nodes[a][k];
}

inline ElementState rigidlyMoved(const double X[4][3], const double rotationVector[3], const double shift[3]) {
  ElementState state;
  double Q[3][3];
  rotationMatrix(rotationVector, Q);
  for (int a = 0; a < 4; ++a) {
    for (int k = 0; k < 3; ++k) state.reference[a][k] = X[a][k];
    for (int i = 0; i < 3; ++i) {
      state.positions[a][i] = shift[i] + Q[i][0] * X[a][0] + Q[i][1] * X[a][1] + Q[i][2] * X[a][2];
      for (int j = 0; j < 3; ++j) state.rotations[a][i][j] = Q[i][j];
    }
  }
  return state;
}

// Stretched and sheared by ~10 %, warped further, rotated by ~1 rad as a whole, and every
// node turned by a further 0.3-0.5 rad of its own.
inline ElementState stronglyDeformed() {
  ElementState state;
  warpedReference(state.reference);
  const double F[3][3] = {{1.1, 0.05, 0.0}, {0.02, 0.95, 0.03}, {0.01, 0.0, 1.02}};
  const double overall[3] = {0.3, -0.8, 0.5};
  double Q[3][3];
  rotationMatrix(overall, Q);
  const double own[4][3] = {{0.3, -0.2, 0.25}, {-0.35, 0.1, 0.2}, {0.15, 0.4, -0.3}, {-0.2, -0.3, -0.25}};
  for (int a = 0; a < 4; ++a) {
    double stretched[3];
    for (int i = 0; i < 3; ++i)
      stretched[i] = F[i][0] * state.reference[a][0] + F[i][1] * state.reference[a][1] +
                     F[i][2] * state.reference[a][2] + 0.02 * std::sin(3.0 * a + i);
    for (int i = 0; i < 3; ++i)
      state.positions[a][i] = 0.4 + Q[i][0] * stretched[0] + Q[i][1] * stretched[1] + Q[i][2] * stretched[2];
    double turn[3][3];
    rotationMatrix(own[a], turn);
    multiply(turn, Q, state.rotations[a]);
  }
  return state;
}

// A reference triangle of about 1 m, not in a coordinate plane, stored as a b c c
// (mesh/quad_mesh.hpp).
inline void triangleReference(double X[4][3]) {
  const double nodes[4][3] = {{0.0, 0.0, 0.0}, {1.1, 0.1, 0.3}, {0.2, 0.9, -0.2}, {0.2, 0.9, -0.2}};
  for (int a = 0; a < 4; ++a)
    for (int k = 0; k < 3; ++k) X[a][k] = nodes[a][k];
}

// stronglyDeformed's motion of nodes 0-2 on that triangle; node 3 moves and turns with node 2.
inline ElementState stronglyDeformedTriangle() {
  ElementState state = stronglyDeformed();
  triangleReference(state.reference);
  for (int k = 0; k < 3; ++k) {
    state.positions[3][k] = state.positions[2][k];
    for (int l = 0; l < 3; ++l) state.rotations[3][k][l] = state.rotations[2][k][l];
  }
  return state;
}

inline shell::ShellSection thickSection() {
  shell::ShellSection section;
  section.youngModulus = 70e9;
  section.poissonRatio = 0.3;
  section.thickness = 0.05;
  return section;
}

// q_j moved by h: a translation, or R_a <- exp(h e_k) R_a.
inline ElementState perturbed(const ElementState& state, int j, double h) {
  ElementState moved = state;
  const int node = j / 6, component = j % 6;
  if (component < 3) {
    moved.positions[node][component] += h;
  } else {
    double vector[3] = {0.0, 0.0, 0.0};
    vector[component - 3] = h;
    double increment[3][3];
    rotationMatrix(vector, increment);
    multiply(increment, state.rotations[node], moved.rotations[node]);
  }
  return moved;
}

inline bool isRotation(int j) { return j % 6 >= 3; }

using Nodes = std::vector<std::array<double, 3>>;
using Quads = std::vector<std::array<int, 4>>;

inline void gather(const Nodes& nodes, const std::array<int, 4>& quad, double X[4][3]) {
  for (int a = 0; a < 4; ++a)
    for (int k = 0; k < 3; ++k) X[a][k] = nodes[quad[a]][k];
}

// MacNeal & Harder (1985) patch: 0.24 x 0.12, four interior nodes off-centre, five quads.
inline Nodes macNealHarderNodes() {
  return {{0.0, 0.0, 0.0},   {0.24, 0.0, 0.0},  {0.24, 0.12, 0.0}, {0.0, 0.12, 0.0},
          {0.04, 0.02, 0.0}, {0.18, 0.03, 0.0}, {0.16, 0.08, 0.0}, {0.08, 0.08, 0.0}};
}
inline Quads macNealHarderQuads() { return {{0, 1, 5, 4}, {1, 2, 6, 5}, {2, 3, 7, 6}, {3, 0, 4, 7}, {4, 5, 6, 7}}; }
// The same patch cut into ten triangles (a b c c), diagonals in both directions, and a mix of
// two quads and six triangles.
inline Quads macNealHarderTriangles() {
  return {{0, 1, 5, 5}, {0, 5, 4, 4}, {1, 2, 6, 6}, {1, 6, 5, 5}, {2, 7, 6, 6},
          {2, 3, 7, 7}, {3, 4, 7, 7}, {3, 0, 4, 4}, {4, 5, 7, 7}, {5, 6, 7, 7}};
}
inline Quads macNealHarderMixed() {
  return {{0, 1, 5, 4}, {1, 2, 6, 6}, {1, 6, 5, 5}, {2, 3, 7, 6}, {3, 4, 7, 7}, {3, 0, 4, 4}, {4, 6, 7, 7}, {4, 5, 6, 6}};
}

// The state turned as a whole by a fixed rotation Q (returned) and shifted.
inline ElementState rigidlyRotated(const ElementState& state, double Q[3][3]) {
  const double vector[3] = {0.9, -1.7, 0.6};
  rotationMatrix(vector, Q);
  ElementState rotated = state;
  for (int a = 0; a < 4; ++a) {
    for (int i = 0; i < 3; ++i)
      rotated.positions[a][i] = -0.7 + Q[i][0] * state.positions[a][0] + Q[i][1] * state.positions[a][1] +
                                Q[i][2] * state.positions[a][2];
    multiply(Q, state.rotations[a], rotated.rotations[a]);
  }
  return rotated;
}

// Tip deflection of a clamped strip (L = 10, b = 1, t = 0.01, E = 1.2e6, nu = 0) of `cells`
// quads under an end shear P, over Euler-Bernoulli's P L^3 / (3 E I). `skew` shifts the
// interior nodes along the strip by that fraction of a cell, alternately on the two sides (a
// distorted mesh). `assemble` gives the global linear stiffness of the element under test.
// With `triangles`, each cell is two triangles (a b c c, mesh/quad_mesh.hpp), the diagonal
// alternating from cell to cell.
using Assembler = std::function<Eigen::MatrixXd(const Nodes&, const Quads&, const shell::ShellSection&)>;
inline double cantileverTipRatio(int cells, double skew, const Assembler& assemble, bool triangles = false) {
  const double length = 10.0, width = 1.0, load = 1e-6;
  shell::ShellSection section;
  section.youngModulus = 1.2e6;
  section.poissonRatio = 0.0;
  section.thickness = 0.01;
  Nodes nodes;
  Quads quads;
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i <= cells; ++i) {
      const double shift = (i > 0 && i < cells) ? (j == 0 ? skew : -skew) * length / cells : 0.0;
      nodes.push_back({length * i / cells + shift, width * j, 0.0});
    }
  for (int i = 0; i < cells; ++i) {
    const int a = i, b = i + 1, c = cells + 2 + i, d = cells + 1 + i;
    if (!triangles) {
      quads.push_back({a, b, c, d});
    } else if (i % 2 == 0) {
      quads.push_back({a, b, c, c});
      quads.push_back({a, c, d, d});
    } else {
      quads.push_back({a, b, d, d});
      quads.push_back({b, c, d, d});
    }
  }
  const Eigen::MatrixXd K = assemble(nodes, quads, section);
  // Clamped: all DOF of nodes 0 and cells + 1. Free DOF are the others, in order.
  std::vector<int> freeDofs;
  for (int node = 0; node < static_cast<int>(nodes.size()); ++node)
    if (node != 0 && node != cells + 1)
      for (int i = 0; i < 6; ++i) freeDofs.push_back(6 * node + i);
  const int n = static_cast<int>(freeDofs.size());
  Eigen::MatrixXd Kff(n, n);
  Eigen::VectorXd loads = Eigen::VectorXd::Zero(n);
  const auto isTip = [&](int dof) { return dof == 6 * cells + 2 || dof == 6 * (2 * cells + 1) + 2; };
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) Kff(r, c) = K(freeDofs[r], freeDofs[c]);
    if (isTip(freeDofs[r])) loads(r) = 0.5 * load;
  }
  const Eigen::VectorXd u = Kff.ldlt().solve(loads);
  double tip = 0.0;
  for (int r = 0; r < n; ++r)
    if (isTip(freeDofs[r])) tip += 0.5 * u(r);
  const double inertia = width * std::pow(section.thickness, 3) / 12.0;
  return tip / (load * std::pow(length, 3) / (3.0 * section.youngModulus * inertia));
}

using HostPositions = Kokkos::View<double* [4][3], Kokkos::LayoutRight, Kokkos::HostSpace>;
using HostRotations = Kokkos::View<double* [4][3][3], Kokkos::LayoutRight, Kokkos::HostSpace>;

// The states the device tests evaluate: a rigid quarter turn of the warped element, the
// strongly deformed state, and that with node 1's x rotation turned by a further 0.2 rad.
inline std::array<ElementState, 3> deviceTestStates() {
  double X[4][3];
  warpedReference(X);
  const double vector[3] = {0.0, 1.5707963267948966, 0.0}, shift[3] = {1.0, 2.0, 3.0};
  return {rigidlyMoved(X, vector, shift), stronglyDeformed(), perturbed(stronglyDeformed(), 9, 0.2)};
}

struct HostStates {
  HostPositions references, positions;
  HostRotations rotations;
};

inline HostStates hostViews(const std::array<ElementState, 3>& states) {
  HostStates views{HostPositions("X", 3), HostPositions("x", 3), HostRotations("R", 3)};
  for (int e = 0; e < 3; ++e)
    for (int a = 0; a < 4; ++a)
      for (int k = 0; k < 3; ++k) {
        views.references(e, a, k) = states[e].reference[a][k];
        views.positions(e, a, k) = states[e].positions[a][k];
        for (int l = 0; l < 3; ++l) views.rotations(e, a, k, l) = states[e].rotations[a][k][l];
      }
  return views;
}

}  // namespace shell_element_test
