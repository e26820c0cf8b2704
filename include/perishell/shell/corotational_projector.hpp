#pragma once
// The corotational kinematics and projector of the explicit shell elements (docs/explicit.md,
// "The explicit shell element"): the deformational DOF from the nodes' quaternions, and global
// nodal forces f = dW/dq from the local ones dW/dd, for the
// deformational DOF d of shell/mitc4_shell.hpp (local translations E (x_a - x_c) - X_a and
// rotations log(E R_a E0^T)), the frame E built from the diagonals and the edge sum. Exact:
// it is the chain rule through d, the frame's spin included, written out so that no
// stiffness matrix and no automatic differentiation is needed. N = 4 for a quad, N = 3 for a
// triangle (the quad a b c c: node 3's part of the frame's derivative goes to node 2).
#include <perishell/shell/mitc4_shell.hpp>

namespace perishell::shell {

// An explicit element's reference geometry as its force kernel reads it: the nodes'
// coordinates X_a in the reference frame E0 (ShellReference::local) and E0 as a unit
// quaternion. ShellBody keeps it per element (explicitGeometry), so that a step does not
// rebuild the reference frame: a third of the one-point element's work (docs/explicit.md).
struct ExplicitReference {
  double local[4][3];
  double frameQuaternion[4];
};

// How many doubles ExplicitReference packs into (ShellBody::explicitGeometry's columns).
constexpr int explicitReferenceSize = 16;

KOKKOS_INLINE_FUNCTION ExplicitReference explicitReference(const ShellReference& reference) {
  ExplicitReference r{};
  for (int a = 0; a < 4; ++a)
    for (int k = 0; k < 3; ++k) r.local[a][k] = reference.local[a][k];
  rotation::fromMatrix(reference.frame, r.frameQuaternion);
  return r;
}

}  // namespace perishell::shell

namespace perishell::shell::detail {

// The deformational DOF d of an explicit element (6 N entries) from its nodes' positions and
// unit quaternions, and the current frame E (rows), centroid and lengths the projector needs:
// local translations E (x_a - x_c) - X_a (localTranslation) and local rotations
// log(E R_a E0^T), taken as the rotation vector of the quaternion q_E q_a conj(q_E0): two
// quaternion products per node instead of two 3 x 3 matrix products and a matrix logarithm.
template <int N>
KOKKOS_INLINE_FUNCTION void explicitDeformation(const ExplicitReference& reference, const double positions[][3],
                                                const double quaternions[][4], double E[3][3], double centroid[3],
                                                FrameLengths<double>& lengths, double d[]) {
  corotationalFrame<N>(positions, E, centroid, lengths);
  double frameQuaternion[4];
  rotation::fromMatrix(E, frameQuaternion);
  for (int a = 0; a < N; ++a) {
    localTranslation(E, centroid, positions[a], reference.local[a], &d[6 * a]);
    double turned[4], relative[4];
    rotation::multiply(frameQuaternion, quaternions[a], turned);
    rotation::multiplyByConjugate(turned, reference.frameQuaternion, relative);
    rotation::rotationVector(relative, &d[6 * a + 3]);
  }
}

// J_l^-T(theta) m, J_l^-1 = d log(exp(delta) Q) / d delta the inverse left Jacobian of SO(3):
// J_l^-1 = I - 1/2 [theta] + c [theta]^2, c = 1/theta^2 - (1 + cos theta)/(2 theta sin theta),
// so J_l^-T m = m + 1/2 theta x m + c theta x (theta x m).
KOKKOS_INLINE_FUNCTION void applyTransposedInverseLeftJacobian(const double theta[3], const double m[3], double out[3]) {
  const double angleSquared = theta[0] * theta[0] + theta[1] * theta[1] + theta[2] * theta[2];
  double c;
  if (angleSquared < 1e-2) {
    // c = sum_n |B_2n| theta^(2n-2) / (2n)! (Bernoulli numbers), to n = 6: below 0.1 rad, where
    // the local rotations lie, the first term left out is 1e-18 of c, and no sqrt, sin, cos
    // or division is taken.
    const double x = angleSquared;
    c = 1.0 / 12.0 +
        x * (1.0 / 720.0 + x * (1.0 / 30240.0 + x * (1.0 / 1209600.0 +
                                                     x * (1.0 / 47900160.0 + x * (691.0 / 1307674368000.0)))));
  } else {
    const double angle = Kokkos::Experimental::sqrt(angleSquared);
    c = 1.0 / angleSquared -
        (1.0 + Kokkos::Experimental::cos(angle)) / (2.0 * angle * Kokkos::Experimental::sin(angle));
  }
  double once[3], twice[3];
  rotation::cross(theta, m, once);
  rotation::cross(theta, once, twice);
  for (int k = 0; k < 3; ++k) out[k] = m[k] + 0.5 * once[k] + c * twice[k];
}

// force (6 N entries) = dW/dq from local[a] = dW/dd_a (u v w theta_x theta_y theta_z of node
// a), for the frame E (rows), centroid and lengths of corotationalFrame<N>(positions), and d.
template <int N>
KOKKOS_INLINE_FUNCTION void projectLocalForces(const double E[3][3], const double centroid[3],
                                               const FrameLengths<double>& lengths, const double positions[][3],
                                               const double d[], const double local[][6], double force[]) {
  // Global forces of the local ones with the frame held fixed, F_a = E^T f_a and
  // M_a = E^T J^-T f_theta_a, and their total moment about the centroid.
  double moment[3] = {0.0, 0.0, 0.0}, forceSum[3] = {0.0, 0.0, 0.0};
  for (int a = 0; a < N; ++a) {
    double rotational[3];
    applyTransposedInverseLeftJacobian(&d[6 * a + 3], &local[a][3], rotational);
    for (int k = 0; k < 3; ++k) {
      force[6 * a + k] = E[0][k] * local[a][0] + E[1][k] * local[a][1] + E[2][k] * local[a][2];
      force[6 * a + 3 + k] = E[0][k] * rotational[0] + E[1][k] * rotational[1] + E[2][k] * rotational[2];
      moment[k] += force[6 * a + 3 + k];
      forceSum[k] += force[6 * a + k];
    }
    const double arm[3] = {positions[a][0] - centroid[0], positions[a][1] - centroid[1], positions[a][2] - centroid[2]};
    double armMoment[3];
    rotation::cross(arm, &force[6 * a], armMoment);
    for (int k = 0; k < 3; ++k) moment[k] += armMoment[k];
  }
  // The frame turns with the nodes (omega = sum_b G_b dx_b): f_x_b -= G_b^T moment, written
  // through the diagonals and the edge sum that define the frame (docs/explicit.md), and the
  // centroid moves with them (f_x_b -= forceSum / 4, zero up to round-off).
  const double* last = positions[N - 1];
  double mu[3];
  for (int i = 0; i < 3; ++i) mu[i] = E[i][0] * moment[0] + E[i][1] * moment[1] + E[i][2] * moment[2];
  const double inverseAlong = 1.0 / lengths.along, inverseNormal = 1.0 / lengths.normal;
  const double normalSpin = mu[0] + mu[2] * lengths.alongNormal * inverseAlong;
  double lever[3], diagonal13[3], diagonal24[3], toDiagonal13[3], toDiagonal24[3];
  for (int k = 0; k < 3; ++k) {
    lever[k] = mu[1] * E[0][k] - normalSpin * E[1][k];
    diagonal13[k] = positions[2][k] - positions[0][k];
    diagonal24[k] = last[k] - positions[1][k];
  }
  rotation::cross(diagonal24, lever, toDiagonal13);
  rotation::cross(lever, diagonal13, toDiagonal24);
  for (int k = 0; k < 3; ++k) {
    const double g13 = toDiagonal13[k] * inverseNormal, g24 = toDiagonal24[k] * inverseNormal;
    const double gAlong = mu[2] * inverseAlong * E[1][k];
    const double shift = 0.25 * forceSum[k];
    force[k] += g13 + gAlong - shift;
    force[6 + k] += g24 - gAlong - shift;
    force[12 + k] += -g13 - gAlong - shift;
    force[6 * (N - 1) + k] += -g24 + gAlong - shift;  // node 3, or node 2 of a triangle
  }
}

}  // namespace perishell::shell::detail
