#pragma once
// The CCM shell element (model.md §4, §5; paper eq. 34-35): a 4-node flat shell with
//  - a bilinear membrane (2x2 Gauss) and a drilling rotation tied to the in-plane rotation
//    by a penalty,
//  - Reissner-Mindlin bending (2x2 Gauss) with the MITC4 assumed transverse shear of
//    Bathe & Dvorkin (1985): covariant shear strains tied at the edge midpoints, so a thin
//    shell does not lock in shear,
//  - isotropic plane stress,
// made geometrically nonlinear by a corotational formulation that is energy-consistent:
// the element energy is W = 1/2 d^T K_l d, with K_l the linear stiffness in the element's
// flat reference frame and d the deformational DOF (rigid motions of any size removed), and
// the internal force and tangent are its exact first and second derivatives, taken by
// forward-mode automatic differentiation (core/dual.hpp). The tangent is B^T K_l B (paper
// K_L) plus sum_i (K_l d)_i d2 d_i/dq dq (paper K_S); there is no separate K_N (eq. 35).
//
// Conventions. Nodes are counter-clockwise about the element normal. Element DOF order:
// node a's ux uy uz (global translations), then its phi_x phi_y phi_z (spatial rotation
// increments: R_a <- exp(phi) R_a, model.md §5), for a = 0..3. Local (element-frame) DOF
// use the same order: u v w theta_x theta_y theta_z. Forces are internal resisting forces
// (equilibrium: f = external load).
//
// Triangles (stored as a b c c, mesh/quad_mesh.hpp) take their K_l from
// shell/mitc3_triangle.hpp (zero for node 3); the corotational part below serves both: its
// functions take the corner count N, and N = 3 evaluates the collapsed quad's frame and
// energy on the triangle's 3 nodes and 18 DOF (the same numbers as N = 4 with node 3 moving
// and turning with node 2, at about half the cost).
//
// All functions are written once for host and device on small fixed arrays. A warped
// reference element (nodes off the flat frame's plane by z_a) gets K_l of its flat
// projection, tied to the true nodes by rigid links (applyWarpingCorrection below); rigid
// motions cost no energy for any element, because d removes them exactly.
#include <perishell/core/dual.hpp>
#include <perishell/core/rotation.hpp>
#include <perishell/mesh/bilinear_quad.hpp>
#include <perishell/mesh/quad_shape.hpp>
#include <perishell/shell/mitc3_triangle.hpp>
#include <perishell/shell/shell_section.hpp>

#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

namespace perishell::shell {

constexpr int shellNodeCount = 4;
constexpr int shellDofCount = 24;

namespace detail {

// What the corotational frame normalised: |n| of the diagonals' cross product n, |P a| of
// the in-plane part of the xi-direction edge sum a, and a . e3 (the explicit element's
// corotational projector needs them, shell/one_point_shell.hpp).
template <class T>
struct FrameLengths {
  T normal, along, alongNormal;
};

// Corotational frame (model.md §5) as rows e1 e2 e3, and the centroid: e3 along the cross
// product of the diagonals, e1 along the mean of the two xi-direction edges made orthogonal
// to e3, e2 = e3 x e1. Built from cross products and lengths only, so it rotates with the
// nodes: a rigid motion leaves the local coordinates unchanged.
// N = 4: a quad; N = 3: a triangle, taken as the quad a b c c (x_3 = x_2), the frame and
// centroid the same functions of its nodes.
template <int N = 4, class T>
KOKKOS_INLINE_FUNCTION void corotationalFrame(const T x[][3], T frame[3][3], T centroid[3], FrameLengths<T>& lengths) {
  static_assert(N == 3 || N == 4, "a shell element has 3 or 4 corners");
  const T* last = x[N - 1];
  T diagonal13[3], diagonal24[3], along[3];
  for (int k = 0; k < 3; ++k) {
    centroid[k] = 0.25 * (x[0][k] + x[1][k] + x[2][k] + last[k]);
    diagonal13[k] = x[2][k] - x[0][k];
    diagonal24[k] = last[k] - x[1][k];
    along[k] = x[1][k] + x[2][k] - x[0][k] - last[k];
  }
  rotation::cross(diagonal13, diagonal24, frame[2]);
  lengths.normal = rotation::normalise(frame[2]);
  lengths.alongNormal = rotation::dot(along, frame[2]);
  for (int k = 0; k < 3; ++k) frame[0][k] = along[k] - lengths.alongNormal * frame[2][k];
  lengths.along = rotation::normalise(frame[0]);
  rotation::cross(frame[2], frame[0], frame[1]);
}

template <int N = 4, class T>
KOKKOS_INLINE_FUNCTION void corotationalFrame(const T x[][3], T frame[3][3], T centroid[3]) {
  FrameLengths<T> lengths;
  corotationalFrame<N>(x, frame, centroid, lengths);
}

}  // namespace detail

// The element's reference geometry: frame E0 (rows) and the nodes' coordinates in it,
// E0^T (X_a - X_c). The third coordinate is the warp; the stiffness uses the projection.
struct ShellReference {
  double frame[3][3];
  double local[4][3];
};

KOKKOS_INLINE_FUNCTION ShellReference shellReference(const double referencePositions[4][3]) {
  ShellReference reference{};
  double centroid[3];
  detail::corotationalFrame(referencePositions, reference.frame, centroid);
  for (int a = 0; a < 4; ++a)
    for (int i = 0; i < 3; ++i) {
      double sum = 0.0;
      for (int k = 0; k < 3; ++k) sum += reference.frame[i][k] * (referencePositions[a][k] - centroid[k]);
      reference.local[a][i] = sum;
    }
  return reference;
}

// Whether the element is a triangle stored as the quad a b c c (mesh/quad_mesh.hpp): its
// nodes 2 and 3 are one node, so their coordinates are bitwise equal.
KOKKOS_INLINE_FUNCTION bool isTriangleElement(const double positions[4][3]) {
  return positions[3][0] == positions[2][0] && positions[3][1] == positions[2][1] && positions[3][2] == positions[2][2];
}

namespace detail {

// A triangle's corners in its flat frame (the frame's plane holds all three), from a
// ShellReference or an ExplicitReference (shell/corotational_projector.hpp).
template <class Reference>
KOKKOS_INLINE_FUNCTION void triangleCorners(const Reference& reference, double corners[3][2]) {
  for (int a = 0; a < 3; ++a)
    for (int k = 0; k < 2; ++k) corners[a][k] = reference.local[a][k];
}

// An 18 x 18 triangle matrix in the quad's 24 x 24 layout (node 3's rows and columns zero).
KOKKOS_INLINE_FUNCTION void embedTriangleMatrix(const double triangle[triangleDofCount][triangleDofCount],
                                                double quad[shellDofCount][shellDofCount]) {
  for (int r = 0; r < shellDofCount; ++r)
    for (int c = 0; c < shellDofCount; ++c)
      quad[r][c] = r < triangleDofCount && c < triangleDofCount ? triangle[r][c] : 0.0;
}

}  // namespace detail

// Area of the flat (projected) quad: half the length of the diagonals' cross product.
KOKKOS_INLINE_FUNCTION double shellReferenceArea(const double referencePositions[4][3]) {
  double diagonal13[3], diagonal24[3], normal[3];
  for (int k = 0; k < 3; ++k) {
    diagonal13[k] = referencePositions[2][k] - referencePositions[0][k];
    diagonal24[k] = referencePositions[3][k] - referencePositions[1][k];
  }
  rotation::cross(diagonal13, diagonal24, normal);
  return 0.5 * rotation::norm(normal);
}

// Rejects an element the formulation cannot represent: non-finite coordinates, or a shape the
// bilinear map cannot carry (mesh/quad_shape.hpp: coincident corners, zero area, a bow-tie, a
// re-entrant or straight corner; either node order is fine). `element` names it in the message.
inline void checkShellElement(const double referencePositions[4][3], long element) {
  const bool triangle = isTriangleElement(referencePositions);
  const std::string name = std::string(triangle ? "shell triangle " : "shell element ") + std::to_string(element) + ": ";
  std::array<std::array<double, 3>, 4> corners;
  for (int a = 0; a < 4; ++a)
    for (int k = 0; k < 3; ++k) {
      if (!std::isfinite(referencePositions[a][k]))
        throw std::invalid_argument(name + "node " + std::to_string(a) + " has a non-finite coordinate");
      corners[a][k] = referencePositions[a][k];
    }
  const mesh::QuadShapeCheck shape =
      triangle ? mesh::checkTriangleShape({corners[0], corners[1], corners[2]}) : mesh::checkQuadShape(corners);
  switch (shape.defect) {
    case mesh::QuadShapeDefect::none:
      return;
    case mesh::QuadShapeDefect::coincidentCorners:
      throw std::invalid_argument(name + "zero or negative area: nodes " + std::to_string(shape.corner) + " and " +
                                  std::to_string(shape.otherCorner) + " coincide");
    case mesh::QuadShapeDefect::zeroArea:
      throw std::invalid_argument(name + "zero or negative area: collinear nodes");
    case mesh::QuadShapeDefect::selfCrossing:
      throw std::invalid_argument(name + "zero or negative area: the outline crosses itself (a bow-tie)");
    case mesh::QuadShapeDefect::reentrantCorner:
      throw std::invalid_argument(name + "zero or negative area at corner " + std::to_string(shape.corner) +
                                  " (a re-entrant or straight corner)");
  }
}

// Generalised strain-displacement matrix at (xi, eta) in the element frame: strains =
// B d_local (shellStrainCount rows, order above). Returns the Jacobian determinant.
// Membrane and bending: bilinear interpolation of u v w and of the rotations. The normal's
// rotation is beta = theta x e3, i.e. beta_x = theta_y, beta_y = -theta_x.
// Transverse shear (MITC4): the covariant strains e_xi = gamma . dx/dxi and
// e_eta = gamma . dx/deta are evaluated at the edge midpoints (0, +-1) and (+-1, 0),
// interpolated linearly across the element, and mapped back by gamma = J^-1 (e_xi, e_eta).
KOKKOS_INLINE_FUNCTION double shellStrainDisplacement(const ShellReference& reference, double xi, double eta,
                                                      double B[shellStrainCount][shellDofCount]) {
  using mesh::bilinear::nodeEta;
  using mesh::bilinear::nodeXi;
  const auto& x = reference.local;
  for (int r = 0; r < shellStrainCount; ++r)
    for (int c = 0; c < shellDofCount; ++c) B[r][c] = 0.0;

  double shape[4], dShapeDxi[4], dShapeDeta[4];
  double jacobian[2][2] = {{0.0, 0.0}, {0.0, 0.0}};  // rows: d(x, y)/dxi, d(x, y)/deta
  for (int a = 0; a < 4; ++a) {
    shape[a] = 0.25 * (1.0 + nodeXi(a) * xi) * (1.0 + nodeEta(a) * eta);
    dShapeDxi[a] = 0.25 * nodeXi(a) * (1.0 + nodeEta(a) * eta);
    dShapeDeta[a] = 0.25 * nodeEta(a) * (1.0 + nodeXi(a) * xi);
    for (int k = 0; k < 2; ++k) {
      jacobian[0][k] += dShapeDxi[a] * x[a][k];
      jacobian[1][k] += dShapeDeta[a] * x[a][k];
    }
  }
  const double determinant = jacobian[0][0] * jacobian[1][1] - jacobian[0][1] * jacobian[1][0];
  const double inverse[2][2] = {{jacobian[1][1] / determinant, -jacobian[0][1] / determinant},
                                {-jacobian[1][0] / determinant, jacobian[0][0] / determinant}};

  // Covariant shear rows at the four tying points: A (0, 1), C (0, -1) give e_xi;
  // B (1, 0), D (-1, 0) give e_eta.
  const double tyingXi[4] = {0.0, 0.0, 1.0, -1.0};
  const double tyingEta[4] = {1.0, -1.0, 0.0, 0.0};
  const double tyingWeight[4] = {0.5 * (1.0 + eta), 0.5 * (1.0 - eta), 0.5 * (1.0 + xi), 0.5 * (1.0 - xi)};
  double covariantShear[2][shellDofCount] = {};
  for (int p = 0; p < 4; ++p) {
    const int direction = p < 2 ? 0 : 1;  // 0: e_xi, 1: e_eta
    double tangent[2] = {0.0, 0.0};
    double pointShape[4], pointDerivative[4];
    for (int a = 0; a < 4; ++a) {
      pointShape[a] = 0.25 * (1.0 + nodeXi(a) * tyingXi[p]) * (1.0 + nodeEta(a) * tyingEta[p]);
      pointDerivative[a] = direction == 0 ? 0.25 * nodeXi(a) * (1.0 + nodeEta(a) * tyingEta[p])
                                          : 0.25 * nodeEta(a) * (1.0 + nodeXi(a) * tyingXi[p]);
      for (int k = 0; k < 2; ++k) tangent[k] += pointDerivative[a] * x[a][k];
    }
    for (int a = 0; a < 4; ++a) {
      // e = dw/ds + beta . dx/ds with beta_x = theta_y, beta_y = -theta_x.
      covariantShear[direction][6 * a + 2] += tyingWeight[p] * pointDerivative[a];
      covariantShear[direction][6 * a + 3] -= tyingWeight[p] * pointShape[a] * tangent[1];
      covariantShear[direction][6 * a + 4] += tyingWeight[p] * pointShape[a] * tangent[0];
    }
  }

  for (int a = 0; a < 4; ++a) {
    const double dx = inverse[0][0] * dShapeDxi[a] + inverse[0][1] * dShapeDeta[a];
    const double dy = inverse[1][0] * dShapeDxi[a] + inverse[1][1] * dShapeDeta[a];
    const int u = 6 * a, v = u + 1, thetaX = u + 3, thetaY = u + 4, thetaZ = u + 5;
    B[0][u] = dx;
    B[1][v] = dy;
    B[2][u] = dy;
    B[2][v] = dx;
    B[3][thetaY] = dx;   // kappa_xx = d beta_x / dx
    B[4][thetaX] = -dy;  // kappa_yy = d beta_y / dy
    B[5][thetaY] = dy;   // kappa_xy = d beta_x / dy + d beta_y / dx
    B[5][thetaX] = -dx;
    B[8][thetaZ] = shape[a];  // theta_z - 1/2 (dv/dx - du/dy)
    B[8][u] = 0.5 * dy;
    B[8][v] = -0.5 * dx;
  }
  for (int c = 0; c < shellDofCount; ++c) {
    B[6][c] = inverse[0][0] * covariantShear[0][c] + inverse[0][1] * covariantShear[1][c];
    B[7][c] = inverse[1][0] * covariantShear[0][c] + inverse[1][1] * covariantShear[1][c];
  }
  return determinant;
}

// B at the element's centre (quad: xi = eta = 0; triangle: its centroid), in the quad's layout.
// quadraticEdges: a triangle's edges with Allman's term (triangleQuadraticEdges), as its K_l.
KOKKOS_INLINE_FUNCTION void shellCentreStrainDisplacement(const ShellReference& reference,
                                                          double B[shellStrainCount][shellDofCount],
                                                          unsigned quadraticEdges = allQuadraticEdges) {
  if (!isTriangleElement(reference.local)) {
    shellStrainDisplacement(reference, 0.0, 0.0, B);
    return;
  }
  double corners[3][2], triangle[shellStrainCount][triangleDofCount];
  detail::triangleCorners(reference, corners);
  triangleStrainDisplacement(corners, 1.0 / 3.0, 1.0 / 3.0, triangle, quadraticEdges);
  for (int r = 0; r < shellStrainCount; ++r)
    for (int c = 0; c < shellDofCount; ++c) B[r][c] = c < triangleDofCount ? triangle[r][c] : 0.0;
}

// Rigid-link warping correction (MacNeal, "A simple quadrilateral shell element", Computers
// & Structures 8 (1978) 175-183; Taylor's flat shell in FEAP does the same): the flat
// element's node p_a = X_a - z_a e3 moves with the true node a as if joined by a rigid link,
// u_p = u_a + theta_a x (p_a - X_a): u_p = u_a - z_a theta_y, v_p = v_a + z_a theta_x, so
// K_l <- W^T K_l W. Without it a flat element takes the membrane motion of the true (warped)
// node for that of its projection (on the MacNeal-Harder twisted beam, 7.5 degrees of twist
// per element at 12 x 2, the links change the tip deflection by 0.4 %). W d in place:
KOKKOS_INLINE_FUNCTION void linkWarpedDofsToFlat(const ShellReference& reference, double d[shellDofCount]) {
  for (int a = 0; a < 4; ++a) {
    const double warp = reference.local[a][2];
    d[6 * a] -= warp * d[6 * a + 4];
    d[6 * a + 1] += warp * d[6 * a + 3];
  }
}

// K_l <- W^T K_l W, the same links applied to the stiffness.
KOKKOS_INLINE_FUNCTION void applyWarpingCorrection(const ShellReference& reference,
                                                   double localStiffness[shellDofCount][shellDofCount]) {
  for (int a = 0; a < 4; ++a) {
    const double warp = reference.local[a][2];
    if (warp == 0.0) continue;
    const int u = 6 * a, v = u + 1, thetaX = u + 3, thetaY = u + 4;
    // K W: columns theta_x, theta_y gain the u, v columns (which W leaves as they are).
    for (int r = 0; r < shellDofCount; ++r) {
      localStiffness[r][thetaY] -= warp * localStiffness[r][u];
      localStiffness[r][thetaX] += warp * localStiffness[r][v];
    }
    // W^T (K W): the same for rows.
    for (int c = 0; c < shellDofCount; ++c) {
      localStiffness[thetaY][c] -= warp * localStiffness[u][c];
      localStiffness[thetaX][c] += warp * localStiffness[v][c];
    }
  }
}

// Enhanced membrane strains, condensed (Simo & Rifai, "A class of mixed assumed strain methods
// and the method of incompatible modes", IJNME 29 (1990) 1595-1638: EAS4, equivalent to
// Wilson's incompatible modes u, v += alpha (1 - xi^2), beta (1 - eta^2) with Taylor's
// correction, QM6): the bilinear membrane alone locks in in-plane bending (a 12 x 2 straight
// cantilever came out 26 % stiff under an in-plane tip force), and in-plane bending is how
// curved and twisted shells carry much of their load (MacNeal-Harder pinched cylinder, twisted
// beam). The four modes' strain, G alpha with G = (j0 / j) J0^-1 dM/dxi, integrates to zero
// over the element, so constant strain is exact (patch test) and the modes never store the
// energy of a homogeneous field. K_l <- K_l - K_da K_aa^-1 K_ad over the membrane rows.
KOKKOS_INLINE_FUNCTION void condenseEnhancedMembrane(const ShellReference& reference, const ShellSection& section,
                                                     double localStiffness[shellDofCount][shellDofCount]) {
  using mesh::bilinear::nodeEta;
  using mesh::bilinear::nodeXi;
  const auto& x = reference.local;
  double centreJacobian[2][2] = {{0.0, 0.0}, {0.0, 0.0}};
  for (int a = 0; a < 4; ++a)
    for (int k = 0; k < 2; ++k) {
      centreJacobian[0][k] += 0.25 * nodeXi(a) * x[a][k];
      centreJacobian[1][k] += 0.25 * nodeEta(a) * x[a][k];
    }
  const double centreDeterminant =
      centreJacobian[0][0] * centreJacobian[1][1] - centreJacobian[0][1] * centreJacobian[1][0];
  const double centreInverse[2][2] = {{centreJacobian[1][1] / centreDeterminant, -centreJacobian[0][1] / centreDeterminant},
                                      {-centreJacobian[1][0] / centreDeterminant, centreJacobian[0][0] / centreDeterminant}};
  double D[shellStrainCount][shellStrainCount];
  shellSectionStiffness(section, D);
  double modes[4][4] = {}, coupling[4][shellDofCount] = {};  // K_aa, K_ad
  for (int q = 0; q < mesh::bilinear::numGaussPoints; ++q) {
    const double xi = mesh::bilinear::gaussXi(q), eta = mesh::bilinear::gaussEta(q);
    double B[shellStrainCount][shellDofCount];
    const double weight = shellStrainDisplacement(reference, xi, eta, B);
    // d/dx, d/dy of (1 - xi^2) and (1 - eta^2) through the centre's Jacobian, times j0 / j.
    const double dModeDxi[2] = {-2.0 * xi, 0.0}, dModeDeta[2] = {0.0, -2.0 * eta};
    double G[3][4] = {};  // eps_xx, eps_yy, gamma_xy per mode (u: 0, 1; v: 2, 3)
    for (int m = 0; m < 2; ++m) {
      const double dx = centreDeterminant / weight * (centreInverse[0][0] * dModeDxi[m] + centreInverse[0][1] * dModeDeta[m]);
      const double dy = centreDeterminant / weight * (centreInverse[1][0] * dModeDxi[m] + centreInverse[1][1] * dModeDeta[m]);
      G[0][m] = dx;
      G[2][m] = dy;
      G[1][2 + m] = dy;
      G[2][2 + m] = dx;
    }
    for (int m = 0; m < 4; ++m) {
      double stress[3];  // D_m G e_m, times the Gauss weight
      for (int s = 0; s < 3; ++s) {
        double sum = 0.0;
        for (int k = 0; k < 3; ++k) sum += D[s][k] * G[k][m];
        stress[s] = weight * sum;
      }
      for (int n = 0; n < 4; ++n) modes[m][n] += G[0][n] * stress[0] + G[1][n] * stress[1] + G[2][n] * stress[2];
      for (int c = 0; c < shellDofCount; ++c) coupling[m][c] += B[0][c] * stress[0] + B[1][c] * stress[1] + B[2][c] * stress[2];
    }
  }
  // K_aa^-1 K_ad by Cholesky of the 4 x 4 K_aa (positive definite for any valid element).
  double lower[4][4] = {};
  for (int j = 0; j < 4; ++j) {
    double diagonal = modes[j][j];
    for (int k = 0; k < j; ++k) diagonal -= lower[j][k] * lower[j][k];
    lower[j][j] = math::sqrt(diagonal);
    for (int i = j + 1; i < 4; ++i) {
      double sum = modes[i][j];
      for (int k = 0; k < j; ++k) sum -= lower[i][k] * lower[j][k];
      lower[i][j] = sum / lower[j][j];
    }
  }
  double solved[4][shellDofCount];  // L^-1 K_ad: K_da K_aa^-1 K_ad = solved^T solved
  for (int c = 0; c < shellDofCount; ++c)
    for (int i = 0; i < 4; ++i) {
      double sum = coupling[i][c];
      for (int k = 0; k < i; ++k) sum -= lower[i][k] * solved[k][c];
      solved[i][c] = sum / lower[i][i];
    }
  for (int r = 0; r < shellDofCount; ++r)
    for (int c = 0; c < shellDofCount; ++c)
      localStiffness[r][c] -= solved[0][r] * solved[0][c] + solved[1][r] * solved[1][c] + solved[2][r] * solved[2][c] +
                              solved[3][r] * solved[3][c];
}

// Linear stiffness K_l (24x24) in the element's flat reference frame, 2x2 Gauss for every
// term, with the enhanced membrane where the element is wholly CCM and the warping
// correction. Depends on the reference geometry only: the caller may cache it per element.
// The enhanced membrane is left out where the coupling scales the membrane point by point
// (a transition element): with unequal scales its modes would see a homogeneous field.
// membraneBendingScale[q] multiplies the membrane and bending blocks of D at Gauss point q
// (mesh::bilinear order): the hybrid D_Hb of the PD-CCM coupling (model.md §4, paper eq.
// 22-23; coupling/morphing.hpp). Transverse shear and drilling keep their full stiffness:
// eq. 22 subtracts only what the bonds carry, membrane and bending.
// quadraticEdges: a triangle's edges with Allman's mid-side term (shell/mitc3_triangle.hpp,
// triangleQuadraticEdges); ignored for a quad.
KOKKOS_INLINE_FUNCTION void shellLocalStiffness(const double referencePositions[4][3], const ShellSection& section,
                                                const double membraneBendingScale[mesh::bilinear::numGaussPoints],
                                                unsigned quadraticEdges,
                                                double localStiffness[shellDofCount][shellDofCount]) {
  const ShellReference reference = shellReference(referencePositions);
  if (isTriangleElement(referencePositions)) {
    // A flat triangle (shell/mitc3_triangle.hpp), its section scaled by the mean of the
    // scales at the collapsed quad's Gauss points (each a mean of its corners' factors).
    double corners[3][2], triangle[triangleDofCount][triangleDofCount];
    detail::triangleCorners(reference, corners);
    const double scale = 0.25 * (membraneBendingScale[0] + membraneBendingScale[1] + membraneBendingScale[2] +
                                 membraneBendingScale[3]);
    triangleLocalStiffness(corners, section, scale, quadraticEdges, triangle);
    detail::embedTriangleMatrix(triangle, localStiffness);
    return;
  }
  double D[shellStrainCount][shellStrainCount];
  shellSectionStiffness(section, D);
  for (int r = 0; r < shellDofCount; ++r)
    for (int c = 0; c < shellDofCount; ++c) localStiffness[r][c] = 0.0;
  for (int q = 0; q < mesh::bilinear::numGaussPoints; ++q) {
    double B[shellStrainCount][shellDofCount];
    const double weight =
        shellStrainDisplacement(reference, mesh::bilinear::gaussXi(q), mesh::bilinear::gaussEta(q), B);
    for (int c = 0; c < shellDofCount; ++c) {
      double stress[shellStrainCount];  // D B e_c, times the Gauss weight
      for (int s = 0; s < shellStrainCount; ++s) {
        double sum = 0.0;
        for (int k = 0; k < shellStrainCount; ++k) sum += D[s][k] * B[k][c];
        // D is block diagonal (membrane, bending | shear, drilling), so scaling rows 0-5 is D_Hb.
        stress[s] = (s < 6 ? membraneBendingScale[q] : 1.0) * weight * sum;
      }
      for (int r = 0; r <= c; ++r) {
        double sum = 0.0;
        for (int s = 0; s < shellStrainCount; ++s) sum += B[s][r] * stress[s];
        localStiffness[r][c] += sum;
      }
    }
  }
  for (int c = 0; c < shellDofCount; ++c)
    for (int r = c + 1; r < shellDofCount; ++r) localStiffness[r][c] = localStiffness[c][r];
  bool wholeMembrane = true;
  for (int q = 0; q < mesh::bilinear::numGaussPoints; ++q) wholeMembrane = wholeMembrane && membraneBendingScale[q] == 1.0;
  if (wholeMembrane) condenseEnhancedMembrane(reference, section, localStiffness);
  applyWarpingCorrection(reference, localStiffness);
}

// The full section, and a triangle's edges all quadratic (no quad beside it).
KOKKOS_INLINE_FUNCTION void shellLocalStiffness(const double referencePositions[4][3], const ShellSection& section,
                                                double localStiffness[shellDofCount][shellDofCount]) {
  const double fullSection[mesh::bilinear::numGaussPoints] = {1.0, 1.0, 1.0, 1.0};
  shellLocalStiffness(referencePositions, section, fullSection, allQuadraticEdges, localStiffness);
}

namespace detail {

// Local translation of node a: E^T (x_a - x_c) - E0^T (X_a - X_c).
template <class T>
KOKKOS_INLINE_FUNCTION void localTranslation(const T frame[3][3], const T centroid[3], const T position[3],
                                             const double referenceLocal[3], T out[3]) {
  for (int i = 0; i < 3; ++i) {
    T sum = frame[i][0] * (position[0] - centroid[0]);
    for (int k = 1; k < 3; ++k) sum += frame[i][k] * (position[k] - centroid[k]);
    out[i] = sum - referenceLocal[i];
  }
}

// Local rotation of a node: log(E^T R E0) (model.md §5).
template <class T, class RotationT>
KOKKOS_INLINE_FUNCTION void localRotation(const T frame[3][3], const RotationT R[3][3],
                                          const double referenceFrame[3][3], T theta[3]) {
  RotationT rotatedAxes[3][3];  // column j: R e0_j
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 3; ++j)
      rotatedAxes[k][j] = R[k][0] * referenceFrame[j][0] + R[k][1] * referenceFrame[j][1] + R[k][2] * referenceFrame[j][2];
  T relative[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      relative[i][j] = frame[i][0] * rotatedAxes[0][j] + frame[i][1] * rotatedAxes[1][j] + frame[i][2] * rotatedAxes[2][j];
  rotation::logarithm(relative, theta);
}

// The 6 N deformational DOF d (local translations and rotations per node) of an element of
// N corners (a triangle's reference is its quad a b c c's).
template <int N = 4, class T, class RotationT>
KOKKOS_INLINE_FUNCTION void deformationalDofs(const ShellReference& reference, const T x[][3],
                                              const RotationT rotations[][3][3], T d[]) {
  T frame[3][3], centroid[3];
  corotationalFrame<N>(x, frame, centroid);
  for (int a = 0; a < N; ++a) {
    localTranslation(frame, centroid, x[a], reference.local[a], &d[6 * a]);
    localRotation(frame, rotations[a], reference.frame, &d[6 * a + 3]);
  }
}

// Column j of B = dd/dq by one forward-mode pass. A translation moves the frame and so
// every entry; a rotation increment of node a changes only theta_a.
template <int N = 4>
KOKKOS_INLINE_FUNCTION void deformationalGradientColumn(const ShellReference& reference, const double x[][3],
                                                        const double rotations[][3][3], const double frame[3][3],
                                                        int j, double column[]) {
  using D = Dual<double>;
  const int node = j / 6, component = j % 6;
  if (component < 3) {
    D seeded[N][3];
    for (int a = 0; a < N; ++a)
      for (int k = 0; k < 3; ++k) seeded[a][k] = D(x[a][k], a == node && k == component ? 1.0 : 0.0);
    D d[6 * N];
    deformationalDofs<N>(reference, seeded, rotations, d);
    for (int i = 0; i < 6 * N; ++i) column[i] = d[i].derivative;
    return;
  }
  for (int i = 0; i < 6 * N; ++i) column[i] = 0.0;
  D phi[3], rotated[3][3], constantFrame[3][3], theta[3];
  for (int k = 0; k < 3; ++k) phi[k] = D(0.0, k == component - 3 ? 1.0 : 0.0);
  rotation::rotateBySpatialIncrementToSecondOrder(phi, rotations[node], rotated);
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) constantFrame[r][k] = frame[r][k];
  localRotation(constantFrame, rotated, reference.frame, theta);
  for (int k = 0; k < 3; ++k) column[6 * node + 3 + k] = theta[k].derivative;
}

// d is unchanged when every node translates by the same vector (the frame and the local
// coordinates are built from differences of positions), so a derivative with respect to node
// 0's translation is minus the sum of the other nodes' (the element's translational forces
// balance): B, f and K_S need forward-mode passes for nodes 1..N-1 only, 45 translation pairs
// of a quad instead of 78. Fills node 0's translation rows and columns of a symmetric matrix
// whose other entries hold those derivatives.
template <int N = 4>
KOKKOS_INLINE_FUNCTION void completeFirstNodeTranslations(double matrix[][6 * N]) {
  for (int k = 0; k < 3; ++k)
    for (int m = 3; m < 6 * N; ++m) {
      double sum = 0.0;
      for (int a = 1; a < N; ++a) sum += matrix[6 * a + k][m];
      matrix[k][m] = -sum;
      matrix[m][k] = -sum;
    }
  for (int k = 0; k < 3; ++k)
    for (int l = 0; l < 3; ++l) {
      double sum = 0.0;
      for (int b = 1; b < N; ++b) sum += matrix[k][6 * b + l];
      matrix[k][l] = -sum;
    }
}

// The same for the columns of B (columns[j] = dd/dq_j) of node 0's translations.
template <int N = 4>
KOKKOS_INLINE_FUNCTION void completeFirstNodeColumns(double columns[][6 * N]) {
  for (int k = 0; k < 3; ++k)
    for (int i = 0; i < 6 * N; ++i) {
      double sum = 0.0;
      for (int a = 1; a < N; ++a) sum += columns[6 * a + k][i];
      columns[k][i] = -sum;
    }
}

// Node 0's translational force balances the others' (completeFirstNodeTranslations).
template <int N = 4>
KOKKOS_INLINE_FUNCTION void balanceFirstNodeForce(double force[]) {
  for (int k = 0; k < 3; ++k) {
    double sum = 0.0;
    for (int a = 1; a < N; ++a) sum += force[6 * a + k];
    force[k] = -sum;
  }
}

template <int N = 4>
KOKKOS_INLINE_FUNCTION void addSymmetricPair(double tangent[][6 * N], int j, int k, double value) {
  tangent[j][k] += value;
  if (j != k) tangent[k][j] += value;
}

// Writes sum_i s_i d2 d_i / dq_j dq_k (paper K_S) for fixed s into a zeroed matrix, as the
// Hessian of the scalar s . d(q), one pair of directions per Dual<Dual> pass (inner
// derivative: q_j, outer: q_k). Pairs of rotations of different nodes vanish; a rotation pair
// of one node changes only that node's theta; a translation-rotation pair needs the seeded
// frame and one theta; node 0's translations follow from the others'.
template <int N = 4>
KOKKOS_INLINE_FUNCTION void initialStressStiffness(const ShellReference& reference, const double x[][3],
                                                      const double rotations[][3][3], const double frame[3][3],
                                                      const double s[], double tangent[][6 * N]) {
  using DD = Dual<Dual<double>>;
  // Node 0's translations come last, from the others' (completeFirstNodeTranslations).
  for (int j = 6; j < 6 * N; ++j) {
    if (j % 6 >= 3) continue;
    for (int k = j; k < 6 * N; ++k) {
      if (k % 6 >= 3) continue;
      DD seeded[N][3];
      for (int a = 0; a < N; ++a)
        for (int c = 0; c < 3; ++c) seeded[a][c] = DD(x[a][c]);
      seeded[j / 6][j % 6].value.derivative = 1.0;
      seeded[k / 6][k % 6].derivative.value = 1.0;
      DD d[6 * N];
      deformationalDofs<N>(reference, seeded, rotations, d);
      double sum = 0.0;
      for (int i = 0; i < 6 * N; ++i) sum += s[i] * d[i].derivative.derivative;
      addSymmetricPair<N>(tangent, j, k, sum);
    }
  }
  for (int j = 6; j < 6 * N; ++j) {
    if (j % 6 >= 3) continue;
    DD seeded[N][3], seededFrame[3][3], centroid[3];
    for (int a = 0; a < N; ++a)
      for (int c = 0; c < 3; ++c) seeded[a][c] = DD(x[a][c]);
    seeded[j / 6][j % 6].derivative.value = 1.0;
    corotationalFrame<N>(seeded, seededFrame, centroid);
    for (int a = 0; a < N; ++a)
      for (int c = 0; c < 3; ++c) {
        DD phi[3] = {DD(0.0), DD(0.0), DD(0.0)};
        phi[c].value.derivative = 1.0;
        DD rotated[3][3], theta[3];
        rotation::rotateBySpatialIncrementToSecondOrder(phi, rotations[a], rotated);
        localRotation(seededFrame, rotated, reference.frame, theta);
        double sum = 0.0;
        for (int m = 0; m < 3; ++m) sum += s[6 * a + 3 + m] * theta[m].derivative.derivative;
        addSymmetricPair<N>(tangent, j, 6 * a + 3 + c, sum);
      }
  }
  DD constantFrame[3][3];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) constantFrame[r][c] = DD(frame[r][c]);
  for (int a = 0; a < N; ++a)
    for (int c = 0; c < 3; ++c)
      for (int e = c; e < 3; ++e) {
        DD phi[3] = {DD(0.0), DD(0.0), DD(0.0)};
        phi[c].value.derivative = 1.0;
        phi[e].derivative.value = 1.0;
        DD rotated[3][3], theta[3];
        rotation::rotateBySpatialIncrementToSecondOrder(phi, rotations[a], rotated);
        localRotation(constantFrame, rotated, reference.frame, theta);
        double sum = 0.0;
        for (int m = 0; m < 3; ++m) sum += s[6 * a + 3 + m] * theta[m].derivative.derivative;
        addSymmetricPair<N>(tangent, 6 * a + 3 + c, 6 * a + 3 + e, sum);
      }
  completeFirstNodeTranslations<N>(tangent);
}

// Everything force and tangent share: reference, current frame, d and s = K_l d.
template <int N>
struct ShellState {
  ShellReference reference;
  double frame[3][3];
  double d[6 * N];
  double s[6 * N];
  double energy;
};

template <int N>
KOKKOS_INLINE_FUNCTION void evaluateState(const double referencePositions[4][3], const double positions[][3],
                                          const double rotations[][3][3], const double localStiffness[][6 * N],
                                          ShellState<N>& state) {
  state.reference = shellReference(referencePositions);
  double centroid[3];
  corotationalFrame<N>(positions, state.frame, centroid);
  deformationalDofs<N>(state.reference, positions, rotations, state.d);
  state.energy = 0.0;
  for (int r = 0; r < 6 * N; ++r) {
    double sum = 0.0;
    for (int c = 0; c < 6 * N; ++c) sum += localStiffness[r][c] * state.d[c];
    state.s[r] = sum;
    state.energy += 0.5 * sum * state.d[r];
  }
}

}  // namespace detail

// Deformational DOF d (local translations and rotations, model.md §5); zero for any rigid
// motion of the reference element. `rotations` are the nodes' finite rotations (reference
// to current).
KOKKOS_INLINE_FUNCTION void shellDeformationalDofs(const double referencePositions[4][3], const double positions[4][3],
                                                   const double rotations[4][3][3], double d[shellDofCount]) {
  const ShellReference reference = shellReference(referencePositions);
  detail::deformationalDofs(reference, positions, rotations, d);
}

// Generalised strains (order: shellStrainCount) at (xi, eta) from local DOF d_local (the
// deformational DOF, or for a linear check E0^T u per node).
KOKKOS_INLINE_FUNCTION void shellLocalStrains(const double referencePositions[4][3], const double localDofs[shellDofCount],
                                              double xi, double eta, double strains[shellStrainCount]) {
  const ShellReference reference = shellReference(referencePositions);
  double B[shellStrainCount][shellDofCount];
  shellStrainDisplacement(reference, xi, eta, B);
  for (int r = 0; r < shellStrainCount; ++r) {
    double sum = 0.0;
    for (int c = 0; c < shellDofCount; ++c) sum += B[r][c] * localDofs[c];
    strains[r] = sum;
  }
}

// Internal force f = dW/dq = B^T K_l d (global translations, then spatial moments per
// node); returns the element energy W = 1/2 d^T K_l d. N = 4 for a quad; N = 3 for a
// triangle (a b c c: referencePositions holds its 4 corners, positions and rotations its 3
// nodes', localStiffness is the 18 x 18 block of its K_l, force has 18 entries).
template <int N = 4>
KOKKOS_INLINE_FUNCTION double shellInternalForce(const double referencePositions[4][3], const double positions[][3],
                                                 const double rotations[][3][3], const double localStiffness[][6 * N],
                                                 double force[]) {
  detail::ShellState<N> state;
  detail::evaluateState<N>(referencePositions, positions, rotations, localStiffness, state);
  for (int j = 3; j < 6 * N; ++j) {
    double column[6 * N];
    detail::deformationalGradientColumn<N>(state.reference, positions, rotations, state.frame, j, column);
    double sum = 0.0;
    for (int i = 0; i < 6 * N; ++i) sum += state.s[i] * column[i];
    force[j] = sum;
  }
  detail::balanceFirstNodeForce<N>(force);
  return state.energy;
}

// Internal force (as shellInternalForce) and the symmetric tangent K_T = d2W/dq2 =
// B^T K_l B + sum_i (K_l d)_i d2 d_i/dq2 (paper K_L + K_S). K_T is the symmetric part of the
// derivative of f under the multiplicative update R <- exp(dphi) R; addRotationAsymmetry
// gives that derivative itself. Returns W. N as for shellInternalForce.
// mixedLocalForces (6 N entries, or null): the mixed-format Newton's independent local forces
// s (shellLinearizedLocalForces below, docs/implicit.md "Mixed-format Newton") take the place
// of K_l d in the initial-stress term and in f = B^T s.
template <int N = 4>
KOKKOS_INLINE_FUNCTION double shellTangent(const double referencePositions[4][3], const double positions[][3],
                                           const double rotations[][3][3], const double localStiffness[][6 * N],
                                           double force[], double tangent[][6 * N],
                                           const double* mixedLocalForces = nullptr) {
  constexpr int dofs = 6 * N;
  detail::ShellState<N> state;
  detail::evaluateState<N>(referencePositions, positions, rotations, localStiffness, state);
  if (mixedLocalForces != nullptr)
    for (int i = 0; i < dofs; ++i) state.s[i] = mixedLocalForces[i];
  double columns[dofs][dofs];  // columns[j] = dd/dq_j
  for (int j = 3; j < dofs; ++j)
    detail::deformationalGradientColumn<N>(state.reference, positions, rotations, state.frame, j, columns[j]);
  detail::completeFirstNodeColumns<N>(columns);
  for (int j = 3; j < dofs; ++j) {
    double sum = 0.0;
    for (int i = 0; i < dofs; ++i) sum += state.s[i] * columns[j][i];
    force[j] = sum;
  }
  detail::balanceFirstNodeForce<N>(force);  // as shellInternalForce, to the bit
  // K_S first: its node-0 translation rows are completed from the others' before K_L joins.
  for (int j = 0; j < dofs; ++j)
    for (int k = 0; k < dofs; ++k) tangent[j][k] = 0.0;
  detail::initialStressStiffness<N>(state.reference, positions, rotations, state.frame, state.s, tangent);
  for (int k = 0; k < dofs; ++k) {
    double stiffnessTimesColumn[dofs];
    for (int r = 0; r < dofs; ++r) {
      double sum = 0.0;
      for (int c = 0; c < dofs; ++c) sum += localStiffness[r][c] * columns[k][c];
      stiffnessTimesColumn[r] = sum;
    }
    for (int j = 0; j <= k; ++j) {
      double sum = 0.0;
      for (int i = 0; i < dofs; ++i) sum += columns[j][i] * stiffnessTimesColumn[i];
      tangent[j][k] += sum;
      if (j != k) tangent[k][j] += sum;
    }
  }
  return state.energy;
}

// The mixed-format Newton's local forces after a correction (Magisano, Leonetti & Garcea,
// "How to improve efficiency and robustness of the Newton method in geometrically nonlinear
// structural problem discretized via displacement-based finite elements", CMAME 313 (2017)
// 986-1005: stresses as independent unknowns, condensed element by element):
// s = K_l (d(q) + B(q) dq), the local forces linearised along the correction dq (per node:
// translations, then the spatial rotation increment) from the state q it is applied to. One
// forward-mode pass gives B dq. N as for shellInternalForce.
template <int N = 4>
KOKKOS_INLINE_FUNCTION void shellLinearizedLocalForces(const double referencePositions[4][3],
                                                       const double positions[][3], const double rotations[][3][3],
                                                       const double localStiffness[][6 * N], const double correction[],
                                                       double localForces[]) {
  using D = Dual<double>;
  const ShellReference reference = shellReference(referencePositions);
  D seeded[N][3], rotated[N][3][3];
  for (int a = 0; a < N; ++a) {
    D phi[3];
    for (int k = 0; k < 3; ++k) {
      seeded[a][k] = D(positions[a][k], correction[6 * a + k]);
      phi[k] = D(0.0, correction[6 * a + 3 + k]);
    }
    rotation::rotateBySpatialIncrementToSecondOrder(phi, rotations[a], rotated[a]);
  }
  D d[6 * N];
  detail::deformationalDofs<N>(reference, seeded, rotated, d);
  for (int r = 0; r < 6 * N; ++r) {
    double sum = 0.0;
    for (int c = 0; c < 6 * N; ++c) sum += localStiffness[r][c] * (d[c].value + d[c].derivative);
    localForces[r] = sum;
  }
}

// Turns the symmetric K_T into the exact derivative of f under R_a <- exp(dphi_a) R_a
// (TangentForm::Exact, core/types.hpp): df_phi_a/dphi_a = K_T - 1/2 skew(m_a), m_a the
// node's moment in f. Non-symmetric; summed over elements at equilibrium the term is
// -1/2 skew(applied moment), so it vanishes where no moment is applied.
template <int N = 4>
KOKKOS_INLINE_FUNCTION void addRotationAsymmetry(const double force[], double tangent[][6 * N]) {
  for (int a = 0; a < N; ++a) {
    const int o = 6 * a + 3;
    const double m[3] = {force[o], force[o + 1], force[o + 2]};
    tangent[o][o + 1] += 0.5 * m[2];
    tangent[o][o + 2] -= 0.5 * m[1];
    tangent[o + 1][o] -= 0.5 * m[2];
    tangent[o + 1][o + 2] += 0.5 * m[0];
    tangent[o + 2][o] += 0.5 * m[1];
    tangent[o + 2][o + 1] -= 0.5 * m[0];
  }
}

}  // namespace perishell::shell
