#pragma once
// The explicit solver's shell element (issue 21, docs/explicit.md "The explicit shell
// element"): a 4-node shell with one-point quadrature and hourglass control, the
// Belytschko-Lin-Tsay design (Belytschko, Lin & Tsay 1984) written in total corotational
// form, so that it is conservative and exactly invariant under rigid motions of any size:
//  - kinematics as the MITC4 element's (shell/mitc4_shell.hpp, model.md §5): the same
//    corotational frame, the deformational DOF d (local translations E (x_a - x_c) - X_a and
//    local rotations log(E R_a E0^T), the force kernel taking them from the nodes'
//    quaternions: shell/corotational_projector.hpp);
//  - generalised strains at the centre from the uniform gradient B of Flanagan & Belytschko
//    (1981): membrane, curvature and the drilling mismatch theta_z - omega, with the section
//    of model.md §4; the transverse shear (gamma = grad w + beta, beta = (theta_y, -theta_x))
//    is MITC4's (covariant shears tied at the edge midpoints), integrated exactly on a
//    parallelogram: its value at the centre plus the differences of the opposite edges'
//    shears, which carry the w-hourglass and the twist of the normals. Every tied shear
//    vanishes for a Kirchhoff field of constant curvature on any quad, so a thin distorted
//    plate neither locks nor fails the bending patch test (the one-point B of w would do
//    both; Belytschko & Leviathan 1994 stabilise the shear the same way);
//  - hourglass control of the membrane, bending and drilling fields by the
//    Flanagan-Belytschko vectors gamma_a = (h_a - (h.x) B_xa - (h.y) B_ya)/4,
//    h = (1, -1, 1, -1), which are orthogonal to every linear field on any quad (so the patch
//    tests stay exact on distorted meshes). Membrane: the BLT element's stiffness r E t A/8 B.B
//    (LS-DYNA theory manual, "Belytschko-Lin-Tsay shell"; full integration would lock in
//    in-plane bending). Bending and drilling: the exact 2x2-point energy of the hourglass
//    mode (MITC4's, on a parallelogram), as in Belytschko & Leviathan's physical
//    stabilisation: the BLT bending scaling r E t^3 A/192 B.B is ~100 x softer, and under the
//    moment of a strongly bent strip the geometric terms of the rotations outweighed it (the
//    hourglass mode grew without bound in Sze 3.1);
//  - W = A (1/2 eps.n + 1/2 kappa.m + 1/2 zeta z) + shear energy + hourglass energy, and the
//    nodal forces are dW/dq exactly: f_local = dW/dd, mapped to the global DOF through the
//    derivative of d, including the frame's spin (the corotational projector; derived in
//    docs/explicit.md). No stiffness matrix, no automatic differentiation: about 600 flops
//    and 60 doubles read per element (positions, displacements, quaternions, section factors,
//    and the reference geometry ShellBody keeps, ExplicitReference).
// The coupling's hybrid section (model.md §4, coupling/morphing.hpp) enters as one factor
// s on the membrane and bending resultants and on their hourglass stiffnesses: the mean of
// the element's four Gauss-point factors, i.e. 1 - alphaBar at the centre, which
// integrates (1 - alphaBar(x)) W exactly on parallelogram elements, as 2x2 Gauss does.
// DOF order and conventions are the MITC4 element's.
#include <perishell/shell/corotational_projector.hpp>
#include <perishell/shell/mitc4_shell.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace perishell::shell {

// The largest warp the flat one-point element accepts: max |z_a| / sqrt(A), z_a the nodes'
// distances from the element's mean plane. A flat facet (any cylinder, cone or sphere
// mesh of lat-long quads) has none; 0.05 is a twist of about 6 degrees across the element.
constexpr double maxOnePointWarp = 0.05;

// The element's reference constants, recomputed on every evaluation from the nodes'
// coordinates in the reference frame (ExplicitReference, kept per element): a few dozen
// flops, cheaper than the memory traffic of storing them.
struct OnePointReference {
  double local[4][3];       // the nodes' coordinates in the reference frame E0 (ShellReference::local)
  double area;              // A of the flat projection
  double dNdx[4], dNdy[4];  // the uniform gradient at the centre
  double hourglass[4];      // Flanagan-Belytschko gamma_a
  // Per shear measure (gamma_xz, gamma_yz at the centre, then the opposite edges' covariant
  // shear differences d_xi, d_eta), its weight in int |gamma|^2 dA: A, A, A |J^-1 e_1|^2 / 12,
  // A |J^-1 e_2|^2 / 12.
  double shearWeight[4];
  // The gradients of the natural coordinates at the centre, (dxi/dx, dxi/dy) and (deta/dx, deta/dy).
  double naturalGradient[2][2];
};

// MITC4's tying edges (model.md §5), as (from, to) corners: the xi-edges 0-1 at eta = -1 and
// 3-2 at eta = +1, then the eta-edges 0-3 at xi = -1 and 1-2 at xi = +1. (Functions: device
// code cannot read a namespace-scope array.)
KOKKOS_INLINE_FUNCTION constexpr int tyingEdgeFrom(int edge) { return edge == 1 ? 3 : (edge == 3 ? 1 : 0); }
KOKKOS_INLINE_FUNCTION constexpr int tyingEdgeTo(int edge) { return edge == 0 ? 1 : (edge == 2 ? 3 : 2); }

KOKKOS_INLINE_FUNCTION OnePointReference onePointReference(const double local[4][3]) {
  OnePointReference r{};
  for (int a = 0; a < 4; ++a)
    for (int k = 0; k < 3; ++k) r.local[a][k] = local[a][k];
  const auto& x = r.local;
  r.area = 0.5 * ((x[2][0] - x[0][0]) * (x[3][1] - x[1][1]) - (x[3][0] - x[1][0]) * (x[2][1] - x[0][1]));
  const double inverseTwiceArea = 0.5 / r.area;  // one division: they cost tens of flops on a GPU
  for (int a = 0; a < 4; ++a) {
    const int next = (a + 1) % 4, previous = (a + 3) % 4;
    r.dNdx[a] = (x[next][1] - x[previous][1]) * inverseTwiceArea;
    r.dNdy[a] = (x[previous][0] - x[next][0]) * inverseTwiceArea;
  }
  double hx = 0.0, hy = 0.0;
  for (int a = 0; a < 4; ++a) {
    const double h = (a % 2 == 0) ? 1.0 : -1.0;
    hx += h * x[a][0];
    hy += h * x[a][1];
  }
  for (int a = 0; a < 4; ++a) {
    const double h = (a % 2 == 0) ? 1.0 : -1.0;
    r.hourglass[a] = 0.25 * (h - hx * r.dNdx[a] - hy * r.dNdy[a]);
  }
  // The centre's Jacobian (rows dx/dxi, dx/deta) and its inverse: gamma = J^-1 (e_xi, e_eta).
  const double jacobian[2][2] = {
      {0.25 * (-x[0][0] + x[1][0] + x[2][0] - x[3][0]), 0.25 * (-x[0][1] + x[1][1] + x[2][1] - x[3][1])},
      {0.25 * (-x[0][0] - x[1][0] + x[2][0] + x[3][0]), 0.25 * (-x[0][1] - x[1][1] + x[2][1] + x[3][1])}};
  const double inverseDeterminant = 1.0 / (jacobian[0][0] * jacobian[1][1] - jacobian[0][1] * jacobian[1][0]);
  const double inverse[2][2] = {{jacobian[1][1] * inverseDeterminant, -jacobian[0][1] * inverseDeterminant},
                                {-jacobian[1][0] * inverseDeterminant, jacobian[0][0] * inverseDeterminant}};
  // With e_xi(eta) = centre + eta/2 d_xi (MITC4's linear interpolation), int |gamma|^2 dA
  // over a parallelogram is A |gamma_centre|^2 + A/12 (|J^-1 e_1|^2 d_xi^2 + |J^-1 e_2|^2 d_eta^2).
  for (int k = 0; k < 2; ++k) {
    r.naturalGradient[0][k] = inverse[k][0];
    r.naturalGradient[1][k] = inverse[k][1];
  }
  r.shearWeight[0] = r.shearWeight[1] = r.area;
  r.shearWeight[2] = r.area / 12.0 * (inverse[0][0] * inverse[0][0] + inverse[1][0] * inverse[1][0]);
  r.shearWeight[3] = r.area / 12.0 * (inverse[0][1] * inverse[0][1] + inverse[1][1] * inverse[1][1]);
  return r;
}

// Rejects what a flat one-point element cannot represent: what checkShellElement rejects,
// and a warp above maxOnePointWarp (a triangle is flat). `element` names it in the message.
inline void checkOnePointShellElement(const double referencePositions[4][3], long element) {
  checkShellElement(referencePositions, element);
  if (isTriangleElement(referencePositions)) return;  // flat; shell/explicit_triangle.hpp
  const OnePointReference r = onePointReference(shellReference(referencePositions).local);
  double warp = 0.0;
  for (int a = 0; a < 4; ++a) warp = std::max(warp, std::abs(r.local[a][2]));
  warp /= std::sqrt(r.area);
  if (warp > maxOnePointWarp) {
    std::ostringstream message;
    message.precision(3);
    message << "shell element " << element << ": warped by " << warp
            << " (largest distance of a node from the mean plane over sqrt(area)); the explicit one-point shell "
               "accepts at most "
            << maxOnePointWarp << ": refine the mesh there or set solver.shell-element: mitc4";
    throw std::invalid_argument(message.str());
  }
}

namespace detail {

// The section's stiffnesses the one-point element needs, for a membrane-bending factor s.
struct OnePointSection {
  double membrane, bending;  // s E t/(1-nu^2), s E t^3/(12 (1-nu^2))
  double poisson, halfOneMinusPoisson;
  double transverseShear;    // kappa G t
  double drilling;           // drillingFactor G t
  double hourglassMembrane, hourglassDrilling;  // per (gamma_h . field)^2
  // The bending hourglass energy 1/2 [a b] H [a b]^T, a and b the hourglass amplitudes of
  // beta_x = theta_y and beta_y = -theta_x: H11, H12, H22.
  double hourglassBending[3];
};

KOKKOS_INLINE_FUNCTION OnePointSection onePointSection(const OnePointReference& r, const ShellSection& section,
                                                       double membraneBendingScale) {
  const double hourglassCoefficient = section.hourglassCoefficient;
  const double E = section.youngModulus, nu = section.poissonRatio, t = section.thickness;
  const double shearModulus = E / (2.0 * (1.0 + nu));
  double gradientSquared = 0.0;
  for (int a = 0; a < 4; ++a) gradientSquared += r.dNdx[a] * r.dNdx[a] + r.dNdy[a] * r.dNdy[a];
  OnePointSection s{};
  s.membrane = membraneBendingScale * E * t / (1.0 - nu * nu);
  s.bending = s.membrane * t * t / 12.0;
  s.poisson = nu;
  s.halfOneMinusPoisson = 0.5 * (1.0 - nu);
  s.transverseShear = section.shearCorrection * shearModulus * t;
  s.drilling = section.drillingFactor * shearModulus * t;
  s.hourglassMembrane = membraneBendingScale * hourglassCoefficient * E * t * r.area / 8.0 * gradientSquared;
  // beta = (a, b) xi eta: kappa = eta K1 + xi K2 with K1 = (a xi_x, b xi_y, a xi_y + b xi_x),
  // K2 likewise with eta's gradient; int eta^2 = int xi^2 = A/3 and int xi eta = 0 on a
  // parallelogram, so W = A/6 (K1.D K1 + K2.D K2).
  for (int k = 0; k < 3; ++k) s.hourglassBending[k] = 0.0;
  for (int g = 0; g < 2; ++g) {
    const double gx = r.naturalGradient[g][0], gy = r.naturalGradient[g][1];
    // K = Ma a + Mb b with Ma = (gx, 0, gy), Mb = (0, gy, gx); D = bending [1 nu 0; nu 1 0; 0 0 (1-nu)/2].
    const double third = r.area / 3.0 * s.bending;
    s.hourglassBending[0] += third * (gx * gx + s.halfOneMinusPoisson * gy * gy);
    s.hourglassBending[1] += third * (s.poisson * gx * gy + s.halfOneMinusPoisson * gy * gx);
    s.hourglassBending[2] += third * (gy * gy + s.halfOneMinusPoisson * gx * gx);
  }
  // The drilling penalty's own energy in the mode theta_z = h_a (zero at the centre),
  // integrated by 2x2 Gauss as the MITC4 element does: drilling A / 9 per (gamma.theta_z)^2.
  s.hourglassDrilling = s.drilling * r.area / 9.0;
  return s;
}

// Generalised strains at the centre and hourglass amplitudes from the deformational DOF.
struct OnePointStrains {
  double membrane[3];   // eps_xx eps_yy gamma_xy
  double curvature[3];  // kappa_xx kappa_yy kappa_xy
  double shear[4];      // gamma_xz gamma_yz at the centre, d_xi, d_eta
  double drilling;      // theta_z - omega
  double hourglass[5];  // gamma_h . (u v theta_x theta_y theta_z)
};

template <class T>
KOKKOS_INLINE_FUNCTION void onePointStrains(const OnePointReference& r, const T d[shellDofCount], T membrane[3],
                                            T curvature[3], T shear[4], T& drilling, T hourglass[5]) {
  for (int k = 0; k < 3; ++k) membrane[k] = curvature[k] = T(0.0);
  drilling = T(0.0);
  for (int k = 0; k < 5; ++k) hourglass[k] = T(0.0);
  for (int a = 0; a < 4; ++a) {
    const T* n = &d[6 * a];  // u v w theta_x theta_y theta_z
    const double bx = r.dNdx[a], by = r.dNdy[a];
    membrane[0] += bx * n[0];
    membrane[1] += by * n[1];
    membrane[2] += by * n[0] + bx * n[1];
    curvature[0] += bx * n[4];                // d beta_x/dx, beta_x = theta_y
    curvature[1] -= by * n[3];                // d beta_y/dy, beta_y = -theta_x
    curvature[2] += by * n[4] - bx * n[3];
    drilling += 0.25 * n[5] - 0.5 * (bx * n[1] - by * n[0]);
    for (int k = 0; k < 5; ++k) hourglass[k] += r.hourglass[a] * n[k < 2 ? k : k + 1];
  }
  // MITC4's covariant shears at the tying edges' midpoints, e = dw/ds + beta . dx/ds along the
  // edge (s its natural coordinate): (w_to - w_from)/2 + (beta_from + beta_to)/2 . (x_to - x_from)/2.
  T covariant[4];
  const auto& x = r.local;
  for (int edge = 0; edge < 4; ++edge) {
    const T* from = &d[6 * tyingEdgeFrom(edge)];
    const T* to = &d[6 * tyingEdgeTo(edge)];
    const double dx = x[tyingEdgeTo(edge)][0] - x[tyingEdgeFrom(edge)][0];
    const double dy = x[tyingEdgeTo(edge)][1] - x[tyingEdgeFrom(edge)][1];
    covariant[edge] = 0.5 * (to[2] - from[2]) + 0.25 * ((from[4] + to[4]) * dx - (from[3] + to[3]) * dy);
  }
  // The centre's (the opposite edges' means, mapped by J^-1), then the edges' differences.
  const T alongXi = 0.5 * (covariant[0] + covariant[1]), alongEta = 0.5 * (covariant[2] + covariant[3]);
  for (int i = 0; i < 2; ++i) shear[i] = r.naturalGradient[0][i] * alongXi + r.naturalGradient[1][i] * alongEta;
  shear[2] = covariant[1] - covariant[0];
  shear[3] = covariant[3] - covariant[2];
}

// The energy of the element's strains, split into the one-point part and the hourglass part.
template <class T>
KOKKOS_INLINE_FUNCTION void onePointEnergy(const OnePointReference& r, const OnePointSection& s, const T d[shellDofCount],
                                           T& pointEnergy, T& hourglassEnergy) {
  T membrane[3], curvature[3], shear[4], drilling, hourglass[5];
  onePointStrains(r, d, membrane, curvature, shear, drilling, hourglass);
  const T membraneEnergy =
      s.membrane * (membrane[0] * membrane[0] + membrane[1] * membrane[1] + 2.0 * s.poisson * membrane[0] * membrane[1] +
                    s.halfOneMinusPoisson * membrane[2] * membrane[2]);
  const T bendingEnergy = s.bending * (curvature[0] * curvature[0] + curvature[1] * curvature[1] +
                                       2.0 * s.poisson * curvature[0] * curvature[1] +
                                       s.halfOneMinusPoisson * curvature[2] * curvature[2]);
  T shearEnergy = T(0.0);
  for (int i = 0; i < 4; ++i) shearEnergy += r.shearWeight[i] * shear[i] * shear[i];
  pointEnergy = 0.5 * (r.area * (membraneEnergy + bendingEnergy + s.drilling * drilling * drilling) +
                       s.transverseShear * shearEnergy);
  hourglassEnergy = 0.5 * (s.hourglassMembrane * (hourglass[0] * hourglass[0] + hourglass[1] * hourglass[1]) +
                           s.hourglassBending[0] * hourglass[3] * hourglass[3] -
                           2.0 * s.hourglassBending[1] * hourglass[3] * hourglass[2] +
                           s.hourglassBending[2] * hourglass[2] * hourglass[2] +
                           s.hourglassDrilling * hourglass[4] * hourglass[4]);
}

// The deformational DOF in a given current frame: E (x_a - x_c) - X_a, log(E R_a E0^T).
template <class T, class RotationT>
KOKKOS_INLINE_FUNCTION void onePointDeformation(const ShellReference& reference, const T frame[3][3],
                                                const T centroid[3], const T x[4][3],
                                                const RotationT rotations[4][3][3], T d[shellDofCount]) {
  for (int a = 0; a < 4; ++a) {
    localTranslation(frame, centroid, x[a], reference.local[a], &d[6 * a]);
    localRotation(frame, rotations[a], reference.frame, &d[6 * a + 3]);
  }
}

}  // namespace detail

// The element's energy for any scalar type (the tests differentiate it with core/dual.hpp
// to check onePointShellForce). `pointEnergy` excludes the hourglass part.
template <class T, class RotationT>
KOKKOS_INLINE_FUNCTION void onePointShellEnergy(const double referencePositions[4][3], const T positions[4][3],
                                                const RotationT rotations[4][3][3], const ShellSection& section,
                                                double membraneBendingScale, T& pointEnergy, T& hourglassEnergy) {
  const ShellReference reference = shellReference(referencePositions);
  const OnePointReference r = onePointReference(reference.local);
  const detail::OnePointSection s = detail::onePointSection(r, section, membraneBendingScale);
  T frame[3][3], centroid[3];
  detail::FrameLengths<T> lengths;
  detail::corotationalFrame(positions, frame, centroid, lengths);
  T d[shellDofCount];
  detail::onePointDeformation(reference, frame, centroid, positions, rotations, d);
  detail::onePointEnergy(r, s, d, pointEnergy, hourglassEnergy);
}

struct OnePointEnergies {
  double strain;  // the whole elastic energy, hourglass terms included [J]
  // The energy of the artificial membrane hourglass stiffness [J]: what the element stores
  // in modes it cannot see. The bending and drilling hourglass terms are MITC4's 2x2-point
  // energies of those modes, physical strain energy (a point load rightly stores a good part
  // of its energy in them: 12 % in the first steps of the MacNeal-Harder hemisphere).
  double hourglass;
};

// Internal force f = dW/dq (global translations, then spatial moments per node, as
// shellInternalForce) and the element's energies; the element's reference geometry as
// explicitReference gives it, the nodes' rotations as unit quaternions.
KOKKOS_INLINE_FUNCTION OnePointEnergies onePointShellForce(const ExplicitReference& reference,
                                                          const double positions[4][3], const double quaternions[4][4],
                                                          const ShellSection& section, double membraneBendingScale,
                                                          double force[shellDofCount]) {
  const OnePointReference r = onePointReference(reference.local);
  const detail::OnePointSection s = detail::onePointSection(r, section, membraneBendingScale);
  double E[3][3], centroid[3], d[shellDofCount];
  detail::FrameLengths<double> lengths;
  detail::explicitDeformation<4>(reference, positions, quaternions, E, centroid, lengths, d);

  double membrane[3], curvature[3], shear[4], drilling, hourglass[5];
  detail::onePointStrains(r, d, membrane, curvature, shear, drilling, hourglass);
  // dW/d(strain): the resultants per unit length (n, m, z) times the area, and the shears'.
  const double A = r.area;
  const double n[3] = {A * s.membrane * (membrane[0] + s.poisson * membrane[1]),
                       A * s.membrane * (membrane[1] + s.poisson * membrane[0]),
                       A * s.membrane * s.halfOneMinusPoisson * membrane[2]};
  const double m[3] = {A * s.bending * (curvature[0] + s.poisson * curvature[1]),
                       A * s.bending * (curvature[1] + s.poisson * curvature[0]),
                       A * s.bending * s.halfOneMinusPoisson * curvature[2]};
  double q[4], shearWork = 0.0;
  for (int i = 0; i < 4; ++i) {
    q[i] = s.transverseShear * r.shearWeight[i] * shear[i];
    shearWork += q[i] * shear[i];
  }
  const double z = A * s.drilling * drilling;
  // Hourglass forces dW/dq for q = (u, v, theta_x, theta_y, theta_z) amplitudes; bending in
  // (a, b) = (q_theta_y, -q_theta_x).
  const double* H = s.hourglassBending;
  const double hourglassForce[5] = {s.hourglassMembrane * hourglass[0], s.hourglassMembrane * hourglass[1],
                                    -(H[1] * hourglass[3] - H[2] * hourglass[2]), H[0] * hourglass[3] - H[1] * hourglass[2],
                                    s.hourglassDrilling * hourglass[4]};
  double stabilisation = 0.0;
  for (int k = 0; k < 5; ++k) stabilisation += 0.5 * hourglassForce[k] * hourglass[k];
  OnePointEnergies energies;
  energies.hourglass = 0.5 * (hourglassForce[0] * hourglass[0] + hourglassForce[1] * hourglass[1]);
  energies.strain = 0.5 * (n[0] * membrane[0] + n[1] * membrane[1] + n[2] * membrane[2] + m[0] * curvature[0] +
                           m[1] * curvature[1] + m[2] * curvature[2] + shearWork + z * drilling) +
                    stabilisation;

  // dW/dd per node (the local forces), then mapped to the global DOF through the derivative
  // of d (shell/corotational_projector.hpp).
  double local[4][6];
  for (int a = 0; a < 4; ++a) {
    const double bx = r.dNdx[a], by = r.dNdy[a], g = r.hourglass[a];
    local[a][0] = bx * n[0] + by * n[2] + 0.5 * by * z + g * hourglassForce[0];
    local[a][1] = by * n[1] + bx * n[2] - 0.5 * bx * z + g * hourglassForce[1];
    local[a][2] = 0.0;
    local[a][3] = -by * m[1] - bx * m[2] + g * hourglassForce[2];
    local[a][4] = bx * m[0] + by * m[2] + g * hourglassForce[3];
    local[a][5] = 0.25 * z + g * hourglassForce[4];
  }
  // The shears' forces back through onePointStrains' tying edges: dW/d(covariant edge shear),
  // then onto the edge's w and beta = (theta_y, -theta_x).
  const double alongXi = r.naturalGradient[0][0] * q[0] + r.naturalGradient[0][1] * q[1];
  const double alongEta = r.naturalGradient[1][0] * q[0] + r.naturalGradient[1][1] * q[1];
  const double covariantForce[4] = {0.5 * alongXi - q[2], 0.5 * alongXi + q[2], 0.5 * alongEta - q[3],
                                    0.5 * alongEta + q[3]};
  const auto& x = r.local;
  for (int edge = 0; edge < 4; ++edge) {
    const int from = tyingEdgeFrom(edge), to = tyingEdgeTo(edge);
    const double f = covariantForce[edge];
    const double betaX = 0.25 * f * (x[to][0] - x[from][0]), betaY = 0.25 * f * (x[to][1] - x[from][1]);
    local[to][2] += 0.5 * f;
    local[from][2] -= 0.5 * f;
    local[from][4] += betaX;
    local[to][4] += betaX;
    local[from][3] -= betaY;
    local[to][3] -= betaY;
  }
  detail::projectLocalForces<4>(E, centroid, lengths, positions, d, local, force);
  return energies;
}

// The same from the four reference positions.
KOKKOS_INLINE_FUNCTION OnePointEnergies onePointShellForce(const double referencePositions[4][3],
                                                          const double positions[4][3], const double quaternions[4][4],
                                                          const ShellSection& section, double membraneBendingScale,
                                                          double force[shellDofCount]) {
  return onePointShellForce(explicitReference(shellReference(referencePositions)), positions, quaternions, section,
                            membraneBendingScale, force);
}

// The diagonal of the element's linear stiffness at its reference state, as means per node:
// of the three translational and of the three rotational entries (the explicit solver's
// rotary-inertia scaling, solvers/explicit/nodal_inertia.hpp). K_jj = 2 W(e_j): the energy is
// quadratic in the deformational DOF, which at the reference state are the nodal DOF.
KOKKOS_INLINE_FUNCTION void onePointShellNodalStiffness(const double referencePositions[4][3],
                                                        const ShellSection& section, double membraneBendingScale,
                                                        double translational[4], double rotational[4]) {
  const OnePointReference r = onePointReference(shellReference(referencePositions).local);
  const detail::OnePointSection s = detail::onePointSection(r, section, membraneBendingScale);
  for (int a = 0; a < 4; ++a) {
    translational[a] = rotational[a] = 0.0;
    for (int k = 0; k < 6; ++k) {
      double unit[shellDofCount] = {};
      unit[6 * a + k] = 1.0;
      double pointEnergy, hourglassEnergy;
      detail::onePointEnergy(r, s, unit, pointEnergy, hourglassEnergy);
      (k < 3 ? translational : rotational)[a] += 2.0 * (pointEnergy + hourglassEnergy) / 3.0;
    }
  }
}

}  // namespace perishell::shell
