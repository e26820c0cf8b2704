#pragma once
// The explicit solver's shell triangle (docs/explicit.md, "The explicit shell element"): the
// triangle of shell/mitc3_triangle.hpp (Allman membrane with drilling rotations, linear
// bending, MITC3 shear) with its forces written out instead of read from a stored K_l:
// W = sum over the 3 points q of 1/2 w_q eps_q . D eps_q, the local forces dW/dd by hand
// (triangleLocalForces below), and the global forces through the corotational projector
// (shell/corotational_projector.hpp). The same energy as the implicit solver's triangle
// (1/2 d^T K_l d), so the same answer; no stored matrix, no automatic differentiation, and no
// hourglass modes to control.
#include <perishell/shell/corotational_projector.hpp>
#include <perishell/shell/mitc3_triangle.hpp>
#include <perishell/shell/mitc4_shell.hpp>

namespace perishell::shell {

namespace detail {

// A tied covariant shear e = w_end - w_0 + sum_a shape_a (theta_y_a g_x - theta_x_a g_y).
KOKKOS_INLINE_FUNCTION double tiedShear(const double d[triangleDofCount], const double shape[3], const double g[2],
                                        int end) {
  double e = d[6 * end + 2] - d[2];
  for (int a = 0; a < 3; ++a) e += shape[a] * (d[6 * a + 4] * g[0] - d[6 * a + 3] * g[1]);
  return e;
}

// The triangle's energy and its local forces dW/dd (6 per corner, d's order), evaluated
// field by field on the nonzero terms only: the membrane through the 3 mid-side displacements
// of Allman's field (the quadratic triangle's gradient then costs 6 products per point), the
// constant curvature once, and MITC3's shear through its 4 tied covariant strains, which do
// not depend on the point. The same W as triangleLocalStiffness's 1/2 d^T K_l d.
KOKKOS_INLINE_FUNCTION double triangleLocalForces(const double x[3][2], const ShellSection& section,
                                                  double membraneBendingScale, unsigned quadraticEdges,
                                                  const double d[triangleDofCount], double local[3][6]) {
  for (int a = 0; a < 3; ++a)
    for (int k = 0; k < 6; ++k) local[a][k] = 0.0;
  const double twiceArea = (x[1][0] - x[0][0]) * (x[2][1] - x[0][1]) - (x[2][0] - x[0][0]) * (x[1][1] - x[0][1]);
  const double area = 0.5 * twiceArea;
  double b[3], c[3];  // dL_a/dx, dL_a/dy
  for (int a = 0; a < 3; ++a) {
    const int next = (a + 1) % 3, last = (a + 2) % 3;
    b[a] = (x[next][1] - x[last][1]) / twiceArea;
    c[a] = (x[last][0] - x[next][0]) / twiceArea;
  }
  const double E = section.youngModulus, nu = section.poissonRatio, t = section.thickness;
  const double membrane = membraneBendingScale * E * t / (1.0 - nu * nu);
  const double bending = membrane * t * t / 12.0;
  const double shearModulus = E / (2.0 * (1.0 + nu));
  const double transverse = section.shearCorrection * shearModulus * t, drilling = section.drillingFactor * shearModulus * t;
  double energy = 0.0;

  // Membrane and drilling: Allman's mid-side displacements of edge (i, j), m = i.
  double normal[3][2], middle[3][2];
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    const bool quadratic = (quadraticEdges >> i) & 1u;
    normal[i][0] = quadratic ? (x[j][1] - x[i][1]) / 8.0 : 0.0;
    normal[i][1] = quadratic ? (x[i][0] - x[j][0]) / 8.0 : 0.0;
    for (int k = 0; k < 2; ++k) middle[i][k] = 0.5 * (d[6 * i + k] + d[6 * j + k]) + (d[6 * j + 5] - d[6 * i + 5]) * normal[i][k];
  }
  const double pointR[3] = {1.0 / 6.0, 2.0 / 3.0, 1.0 / 6.0}, pointS[3] = {1.0 / 6.0, 1.0 / 6.0, 2.0 / 3.0};
  const double weight = area / 3.0;
  double middleForce[3][2] = {{0.0, 0.0}, {0.0, 0.0}, {0.0, 0.0}};
  for (int q = 0; q < 3; ++q) {
    const double L[3] = {1.0 - pointR[q] - pointS[q], pointR[q], pointS[q]};
    double cornerX[3], cornerY[3], middleX[3], middleY[3];  // dN/dx, dN/dy of the 6 nodes
    double gradient[2][2] = {{0.0, 0.0}, {0.0, 0.0}};       // [u or v][x or y]
    for (int a = 0; a < 3; ++a) {
      const int j = (a + 1) % 3;
      cornerX[a] = (4.0 * L[a] - 1.0) * b[a];
      cornerY[a] = (4.0 * L[a] - 1.0) * c[a];
      middleX[a] = 4.0 * (L[a] * b[j] + L[j] * b[a]);
      middleY[a] = 4.0 * (L[a] * c[j] + L[j] * c[a]);
      for (int k = 0; k < 2; ++k) {
        gradient[k][0] += cornerX[a] * d[6 * a + k] + middleX[a] * middle[a][k];
        gradient[k][1] += cornerY[a] * d[6 * a + k] + middleY[a] * middle[a][k];
      }
    }
    const double strain[3] = {gradient[0][0], gradient[1][1], gradient[0][1] + gradient[1][0]};
    const double mismatch = L[0] * d[5] + L[1] * d[11] + L[2] * d[17] - 0.5 * (gradient[1][0] - gradient[0][1]);
    const double n[3] = {weight * membrane * (strain[0] + nu * strain[1]), weight * membrane * (strain[1] + nu * strain[0]),
                         weight * membrane * 0.5 * (1.0 - nu) * strain[2]};
    const double z = weight * drilling * mismatch;
    energy += 0.5 * (n[0] * strain[0] + n[1] * strain[1] + n[2] * strain[2] + z * mismatch);
    // dW/d(gradient): u,x; u,y; v,x; v,y.
    const double dGradient[2][2] = {{n[0], n[2] + 0.5 * z}, {n[2] - 0.5 * z, n[1]}};
    for (int a = 0; a < 3; ++a) {
      local[a][5] += L[a] * z;
      for (int k = 0; k < 2; ++k) {
        local[a][k] += cornerX[a] * dGradient[k][0] + cornerY[a] * dGradient[k][1];
        middleForce[a][k] += middleX[a] * dGradient[k][0] + middleY[a] * dGradient[k][1];
      }
    }
  }
  for (int i = 0; i < 3; ++i) {
    const int j = (i + 1) % 3;
    for (int k = 0; k < 2; ++k) {
      local[i][k] += 0.5 * middleForce[i][k];
      local[j][k] += 0.5 * middleForce[i][k];
      local[j][5] += middleForce[i][k] * normal[i][k];
      local[i][5] -= middleForce[i][k] * normal[i][k];
    }
  }

  // Bending: constant curvature of beta = (theta_y, -theta_x).
  double curvature[3] = {0.0, 0.0, 0.0};
  for (int a = 0; a < 3; ++a) {
    curvature[0] += b[a] * d[6 * a + 4];
    curvature[1] -= c[a] * d[6 * a + 3];
    curvature[2] += c[a] * d[6 * a + 4] - b[a] * d[6 * a + 3];
  }
  const double m[3] = {area * bending * (curvature[0] + nu * curvature[1]),
                       area * bending * (curvature[1] + nu * curvature[0]),
                       area * bending * 0.5 * (1.0 - nu) * curvature[2]};
  energy += 0.5 * (m[0] * curvature[0] + m[1] * curvature[1] + m[2] * curvature[2]);
  for (int a = 0; a < 3; ++a) {
    local[a][4] += b[a] * m[0] + c[a] * m[2];
    local[a][3] += -c[a] * m[1] - b[a] * m[2];
  }

  // MITC3 shear: the tied covariant strains e = dw/dxi + beta . g (mitc3_triangle.hpp).
  const double tangentR[2] = {x[1][0] - x[0][0], x[1][1] - x[0][1]};
  const double tangentS[2] = {x[2][0] - x[0][0], x[2][1] - x[0][1]};
  const double half[3][3] = {{0.5, 0.5, 0.0}, {0.5, 0.0, 0.5}, {0.0, 0.5, 0.5}};  // edges 01, 02, 12
  const double rAt1 = tiedShear(d, half[0], tangentR, 1), sAt2 = tiedShear(d, half[1], tangentS, 2);
  const double rAt3 = tiedShear(d, half[2], tangentR, 1), sAt3 = tiedShear(d, half[2], tangentS, 2);
  const double cross = sAt3 - rAt3 - sAt2 + rAt1;
  double sumR = 0.0, sumS = 0.0, sumCross = 0.0;  // dW/d(e_r), dW/d(e_s) summed, and dW/dc
  for (int q = 0; q < 3; ++q) {
    const double alongR = rAt1 + cross * pointS[q], alongS = sAt2 - cross * pointR[q];
    const double gamma[2] = {(tangentS[1] * alongR - tangentR[1] * alongS) / twiceArea,
                             (-tangentS[0] * alongR + tangentR[0] * alongS) / twiceArea};
    const double tau[2] = {weight * transverse * gamma[0], weight * transverse * gamma[1]};
    energy += 0.5 * (tau[0] * gamma[0] + tau[1] * gamma[1]);
    const double dR = (tangentS[1] * tau[0] - tangentS[0] * tau[1]) / twiceArea;
    const double dS = (-tangentR[1] * tau[0] + tangentR[0] * tau[1]) / twiceArea;
    sumR += dR;
    sumS += dS;
    sumCross += pointS[q] * dR - pointR[q] * dS;
  }
  // dW/d of each tied strain, then through its expression.
  const double dTied[4] = {sumR + sumCross, sumS - sumCross, -sumCross, sumCross};  // rAt1, sAt2, rAt3, sAt3
  const double* shapes[4] = {half[0], half[1], half[2], half[2]};
  const double* tangents[4] = {tangentR, tangentS, tangentR, tangentS};
  const int ends[4] = {1, 2, 1, 2};
  for (int k = 0; k < 4; ++k) {
    local[ends[k]][2] += dTied[k];
    local[0][2] -= dTied[k];
    for (int a = 0; a < 3; ++a) {
      local[a][4] += dTied[k] * shapes[k][a] * tangents[k][0];
      local[a][3] -= dTied[k] * shapes[k][a] * tangents[k][1];
    }
  }
  return energy;
}

}  // namespace detail

// Internal force f = dW/dq of a triangle stored as a b c c (reference: its 4 corners' geometry,
// explicitReference; positions and quaternions: its 3 nodes'; force: 18 entries, the MITC4
// element's order) with its section scaled by membraneBendingScale on the membrane and bending
// blocks and Allman's term on quadraticEdges (mitc3_triangle.hpp). Returns the strain energy W.
KOKKOS_INLINE_FUNCTION double explicitTriangleForce(const ExplicitReference& reference, const double positions[][3],
                                                    const double quaternions[][4], const ShellSection& section,
                                                    double membraneBendingScale, unsigned quadraticEdges,
                                                    double force[triangleDofCount]) {
  double corners[3][2];
  detail::triangleCorners(reference, corners);
  double E[3][3], centroid[3], d[triangleDofCount];
  detail::FrameLengths<double> lengths;
  detail::explicitDeformation<3>(reference, positions, quaternions, E, centroid, lengths, d);
  double local[3][6];
  const double energy = detail::triangleLocalForces(corners, section, membraneBendingScale, quadraticEdges, d, local);
  detail::projectLocalForces<3>(E, centroid, lengths, positions, d, local, force);
  return energy;
}

// The same from the 4 corners' reference positions.
KOKKOS_INLINE_FUNCTION double explicitTriangleForce(const double referencePositions[4][3], const double positions[][3],
                                                    const double quaternions[][4], const ShellSection& section,
                                                    double membraneBendingScale, unsigned quadraticEdges,
                                                    double force[triangleDofCount]) {
  return explicitTriangleForce(explicitReference(shellReference(referencePositions)), positions, quaternions, section,
                               membraneBendingScale, quadraticEdges, force);
}

}  // namespace perishell::shell
