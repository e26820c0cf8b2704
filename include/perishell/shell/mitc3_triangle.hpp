#pragma once
// The linear stiffness of a flat 3-node shell triangle in its own frame (model.md §4): the
// triangle counterpart of the MITC4 element's K_l (shell/mitc4_shell.hpp), used for every
// triangle of a mesh (stored as a b c c, mesh/quad_mesh.hpp). The corotational machinery
// (frame, deformational DOF, forces and tangents as exact derivatives of 1/2 d^T K_l d) is
// the quad's, instantiated for 3 corners: the triangle is the quad whose nodes 2 and 3
// coincide, and K_l has zero rows and columns for node 3.
//  - Membrane with drilling rotations: Allman's triangle (D. J. Allman, "A compatible
//    triangular element including vertex rotations for plane elasticity analysis",
//    Computers & Structures 19 (1984) 1-8): the quadratic (6-node) triangle whose mid-side
//    displacements follow from the corners' translations and in-plane rotations,
//    u_m = (u_i + u_j)/2 + L_ij/8 (theta_j - theta_i) n_ij (n_ij the edge's outward normal).
//    The constant-strain triangle alone locks in in-plane bending, as the bilinear quad does.
//    Its one spurious mode (equal theta at the corners) is removed by the drilling penalty
//    theta_z - omega of the section (shell/shell_section.hpp), as on the quad. An edge shared
//    with a quad keeps the linear displacement of the quad's edge (no mid-side term): Allman's
//    quadratic edge against the quad's linear one would leave a gap, and a mixed mesh would
//    fail the patch test (it did: interior error 3 on the MacNeal-Harder patch). Which edges
//    carry the term is a mask, bit i for edge (i, i + 1 mod 3): triangleQuadraticEdges.
//  - Reissner-Mindlin bending with linear w and rotations: constant curvature.
//  - Transverse shear of MITC3 (P. S. Lee & K. J. Bathe, "Development of MITC isotropic
//    triangular shell finite elements", Computers & Structures 82 (2004) 945-962): covariant
//    shear strains tied at the edge midpoints, e_r = e_r(1/2, 0) + c s,
//    e_s = e_s(0, 1/2) - c r, c = e_s(1/2,1/2) - e_r(1/2,1/2) - e_s(0,1/2) + e_r(1/2,0);
//    the plain linear triangle locks in shear.
// Every term is integrated by the 3-point rule at (1/6, 1/6), (2/3, 1/6), (1/6, 2/3), exact
// for the quadratic integrands of a flat triangle.
#include <perishell/mesh/quad_mesh.hpp>
#include <perishell/shell/shell_section.hpp>

#include <set>
#include <utility>
#include <vector>

namespace perishell::shell {

constexpr int triangleDofCount = 18;  // 6 per corner, in the quad's order (u v w theta_x theta_y theta_z)

namespace detail {

// The covariant shear e = dw/dxi + beta . g along tangent g = x_end - x_0 at a point where
// the corners' shape functions are `shape` (beta_x = theta_y, beta_y = -theta_x).
KOKKOS_INLINE_FUNCTION void triangleCovariantShear(const double shape[3], const double tangent[2], int endNode,
                                                   double row[triangleDofCount]) {
  for (int d = 0; d < triangleDofCount; ++d) row[d] = 0.0;
  row[2] = -1.0;
  row[6 * endNode + 2] = 1.0;
  for (int a = 0; a < 3; ++a) {
    row[6 * a + 3] -= shape[a] * tangent[1];
    row[6 * a + 4] += shape[a] * tangent[0];
  }
}

}  // namespace detail

// Generalised strains B d (shell_section.hpp's order) at natural coordinates (r, s) of the
// triangle with corners x[a] = (x, y) in its plane, counter-clockwise, node 0 at r = s = 0,
// node 1 at r = 1, node 2 at s = 1. Returns twice the area.
constexpr unsigned allQuadraticEdges = 7u;

KOKKOS_INLINE_FUNCTION double triangleStrainDisplacement(const double x[3][2], double r, double s,
                                                         double B[shellStrainCount][triangleDofCount],
                                                         unsigned quadraticEdges = allQuadraticEdges) {
  for (int i = 0; i < shellStrainCount; ++i)
    for (int c = 0; c < triangleDofCount; ++c) B[i][c] = 0.0;
  const double twiceArea = (x[1][0] - x[0][0]) * (x[2][1] - x[0][1]) - (x[2][0] - x[0][0]) * (x[1][1] - x[0][1]);
  const double areaCoordinate[3] = {1.0 - r - s, r, s};
  // dL_a/dx = b_a / 2A, dL_a/dy = c_a / 2A.
  double b[3], c[3];
  for (int a = 0; a < 3; ++a) {
    const int next = (a + 1) % 3, last = (a + 2) % 3;
    b[a] = (x[next][1] - x[last][1]) / twiceArea;
    c[a] = (x[last][0] - x[next][0]) / twiceArea;
  }

  // Membrane: gradients of u and v on the 18 DOF. Corners carry L(2L - 1), mid-sides 4 L_i L_j.
  double gradientU[2][triangleDofCount] = {}, gradientV[2][triangleDofCount] = {};
  for (int a = 0; a < 3; ++a) {
    const double factor = 4.0 * areaCoordinate[a] - 1.0;
    gradientU[0][6 * a] += factor * b[a];
    gradientU[1][6 * a] += factor * c[a];
    gradientV[0][6 * a + 1] += factor * b[a];
    gradientV[1][6 * a + 1] += factor * c[a];
  }
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    // L_ij n_ij = (y_j - y_i, x_i - x_j) for a counter-clockwise triangle.
    const bool quadratic = (quadraticEdges >> i) & 1u;
    const double normalX = quadratic ? (x[j][1] - x[i][1]) / 8.0 : 0.0;
    const double normalY = quadratic ? (x[i][0] - x[j][0]) / 8.0 : 0.0;
    const double derivative[2] = {4.0 * (areaCoordinate[i] * b[j] + areaCoordinate[j] * b[i]),
                                  4.0 * (areaCoordinate[i] * c[j] + areaCoordinate[j] * c[i])};
    for (int k = 0; k < 2; ++k) {
      gradientU[k][6 * i] += 0.5 * derivative[k];
      gradientU[k][6 * j] += 0.5 * derivative[k];
      gradientU[k][6 * j + 5] += derivative[k] * normalX;
      gradientU[k][6 * i + 5] -= derivative[k] * normalX;
      gradientV[k][6 * i + 1] += 0.5 * derivative[k];
      gradientV[k][6 * j + 1] += 0.5 * derivative[k];
      gradientV[k][6 * j + 5] += derivative[k] * normalY;
      gradientV[k][6 * i + 5] -= derivative[k] * normalY;
    }
  }
  for (int d = 0; d < triangleDofCount; ++d) {
    B[0][d] = gradientU[0][d];
    B[1][d] = gradientV[1][d];
    B[2][d] = gradientU[1][d] + gradientV[0][d];
    B[8][d] = -0.5 * (gradientV[0][d] - gradientU[1][d]);  // - omega
  }
  for (int a = 0; a < 3; ++a) {
    const int thetaX = 6 * a + 3, thetaY = thetaX + 1;
    B[8][6 * a + 5] += areaCoordinate[a];
    // beta_x = theta_y, beta_y = -theta_x (the quad's convention).
    B[3][thetaY] = b[a];
    B[4][thetaX] = -c[a];
    B[5][thetaY] = c[a];
    B[5][thetaX] = -b[a];
  }

  // MITC3 shear: the covariant strains at the tying points, g_r = x1 - x0, g_s = x2 - x0.
  const double tangentR[2] = {x[1][0] - x[0][0], x[1][1] - x[0][1]};
  const double tangentS[2] = {x[2][0] - x[0][0], x[2][1] - x[0][1]};
  const double atEdge01[3] = {0.5, 0.5, 0.0}, atEdge02[3] = {0.5, 0.0, 0.5}, atEdge12[3] = {0.0, 0.5, 0.5};
  double rAt1[triangleDofCount], sAt2[triangleDofCount], rAt3[triangleDofCount], sAt3[triangleDofCount];
  using detail::triangleCovariantShear;
  triangleCovariantShear(atEdge01, tangentR, 1, rAt1);
  triangleCovariantShear(atEdge02, tangentS, 2, sAt2);
  triangleCovariantShear(atEdge12, tangentR, 1, rAt3);
  triangleCovariantShear(atEdge12, tangentS, 2, sAt3);
  for (int d = 0; d < triangleDofCount; ++d) {
    const double cross = sAt3[d] - rAt3[d] - sAt2[d] + rAt1[d];
    const double alongR = rAt1[d] + cross * s, alongS = sAt2[d] - cross * r;
    // gamma = J^-1 (e_r, e_s), J's rows g_r and g_s, det J = 2A.
    B[6][d] = (tangentS[1] * alongR - tangentR[1] * alongS) / twiceArea;
    B[7][d] = (-tangentS[0] * alongR + tangentR[0] * alongS) / twiceArea;
  }
  return twiceArea;
}

// K_l (18 x 18) of the triangle; membraneBendingScale multiplies the membrane and bending
// blocks of D, as on the quad (the PD-CCM coupling's D_Hb, model.md §4).
KOKKOS_INLINE_FUNCTION void triangleLocalStiffness(const double x[3][2], const ShellSection& section,
                                                   double membraneBendingScale, unsigned quadraticEdges,
                                                   double K[triangleDofCount][triangleDofCount]) {
  double D[shellStrainCount][shellStrainCount];
  shellSectionStiffness(section, D);
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) D[i][j] *= membraneBendingScale;
  for (int i = 0; i < triangleDofCount; ++i)
    for (int j = 0; j < triangleDofCount; ++j) K[i][j] = 0.0;
  const double pointR[3] = {1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0}, pointS[3] = {1.0 / 6.0, 1.0 / 6.0, 2.0 / 3.0};
  for (int q = 0; q < 3; ++q) {
    double B[shellStrainCount][triangleDofCount];
    const double weight = triangleStrainDisplacement(x, pointR[q], pointS[q], B, quadraticEdges) / 6.0;  // A / 3
    for (int col = 0; col < triangleDofCount; ++col) {
      double stress[shellStrainCount];
      for (int i = 0; i < shellStrainCount; ++i) {
        double sum = 0.0;
        for (int k = 0; k < shellStrainCount; ++k) sum += D[i][k] * B[k][col];
        stress[i] = weight * sum;
      }
      for (int row = 0; row <= col; ++row) {
        double sum = 0.0;
        for (int i = 0; i < shellStrainCount; ++i) sum += B[i][row] * stress[i];
        K[row][col] += sum;
      }
    }
  }
  for (int col = 0; col < triangleDofCount; ++col)
    for (int row = col + 1; row < triangleDofCount; ++row) K[row][col] = K[col][row];
}

// Per element of a mesh's connectivity (quads, triangles as a b c c), the mask of its edges
// that carry Allman's mid-side term: a triangle's edges that no quad shares (all 4 bits
// for a quad, which ignores them). Host, at setup.
template <class ConnectivityT>
std::vector<unsigned> triangleQuadraticEdges(const ConnectivityT& elements, std::size_t numElements) {
  const auto key = [](long a, long b) { return std::make_pair(a < b ? a : b, a < b ? b : a); };
  std::set<std::pair<long, long>> quadEdges;
  const auto isTriangle = [&](std::size_t e) { return mesh::isTriangle(elements, static_cast<LocalIndex>(e)); };
  for (std::size_t e = 0; e < numElements; ++e)
    if (!isTriangle(e))
      for (int k = 0; k < 4; ++k) quadEdges.insert(key(elements(e, k), elements(e, (k + 1) % 4)));
  std::vector<unsigned> masks(numElements, 15u);
  for (std::size_t e = 0; e < numElements; ++e) {
    if (!isTriangle(e)) continue;
    masks[e] = 0u;
    for (int k = 0; k < 3; ++k)
      if (quadEdges.count(key(elements(e, k), elements(e, (k + 1) % 3))) == 0) masks[e] |= 1u << k;
  }
  return masks;
}

}  // namespace perishell::shell
