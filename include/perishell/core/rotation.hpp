#pragma once
// Small fixed-size 3-vector, 3x3 matrix and unit-quaternion helpers for device code.
// Nodal rotations are finite (model.md §5): each node keeps a unit quaternion, updated
// multiplicatively by the exponential map of an incremental rotation vector. The vector and
// matrix helpers take any scalar (double, or core/dual.hpp's Dual for the implicit tangents).
#include <perishell/core/dual.hpp>

namespace perishell::rotation {

template <class T>
KOKKOS_INLINE_FUNCTION T dot(const T a[3], const T b[3]) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

template <class T>
KOKKOS_INLINE_FUNCTION void cross(const T a[3], const T b[3], T out[3]) {
  out[0] = a[1] * b[2] - a[2] * b[1];
  out[1] = a[2] * b[0] - a[0] * b[2];
  out[2] = a[0] * b[1] - a[1] * b[0];
}

template <class T>
KOKKOS_INLINE_FUNCTION T norm(const T a[3]) {
  return math::sqrt(dot(a, a));
}

// Scales a in place to unit length; returns the length it had.
template <class T>
KOKKOS_INLINE_FUNCTION T normalise(T a[3]) {
  const T length = norm(a);
  for (int k = 0; k < 3; ++k) a[k] /= length;
  return length;
}

// out = R a
template <class T>
KOKKOS_INLINE_FUNCTION void apply(const T R[3][3], const T a[3], T out[3]) {
  for (int r = 0; r < 3; ++r) out[r] = R[r][0] * a[0] + R[r][1] * a[1] + R[r][2] * a[2];
}

// Quaternions are (w, x, y, z) with w the scalar part.
// Entry (r, c) of the rotation matrix of the unit quaternion whose component k is q(k):
// 1 - 2 (v_a^2 + v_b^2) on the diagonal (a, b the other two axes), 2 (v_r v_c - eps_rck w v_k)
// off it. toMatrix takes all nine; kernels that write one entry per thread take one.
template <class ComponentT>
KOKKOS_INLINE_FUNCTION double matrixEntry(const ComponentT& q, int r, int c) {
  if (r == c) {
    const int a = r == 0 ? 1 : 0, b = r == 2 ? 1 : 2;
    return 1.0 - 2.0 * (q(1 + a) * q(1 + a) + q(1 + b) * q(1 + b));
  }
  const int k = 3 - r - c;
  const double sign = (c - r + 3) % 3 == 1 ? 1.0 : -1.0;  // eps_rck: +1 when (r, c, k) is cyclic
  return 2.0 * (q(1 + r) * q(1 + c) - sign * q(0) * q(1 + k));
}

KOKKOS_INLINE_FUNCTION void toMatrix(const double q[4], double R[3][3]) {
  const auto component = [q](int k) { return q[k]; };
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) R[r][c] = matrixEntry(component, r, c);
}

// The unit quaternion of the rotation vector theta (axis times angle).
KOKKOS_INLINE_FUNCTION void exponential(const double theta[3], double q[4]) {
  const double angleSquared = theta[0] * theta[0] + theta[1] * theta[1] + theta[2] * theta[2];
  double halfSincTimesHalf;  // sin(a/2)/a
  if (angleSquared < 1e-4) {
    // Below 0.01 rad (a step's spin in explicit dynamics) from their series, to the a^8 term
    // (the first left out is below 1e-28): no sqrt, sin or cos on the update's hot path.
    const double x = angleSquared;
    q[0] = 1.0 + x * (-1.0 / 8.0 + x * (1.0 / 384.0 + x * (-1.0 / 46080.0 + x * (1.0 / 10321920.0))));
    halfSincTimesHalf = 0.5 + x * (-1.0 / 48.0 + x * (1.0 / 3840.0 + x * (-1.0 / 645120.0 + x * (1.0 / 185794560.0))));
  } else {
    const double angle = Kokkos::Experimental::sqrt(angleSquared);
    q[0] = Kokkos::Experimental::cos(0.5 * angle);
    halfSincTimesHalf = Kokkos::Experimental::sin(0.5 * angle) / angle;
  }
  for (int k = 0; k < 3; ++k) q[k + 1] = halfSincTimesHalf * theta[k];
}

// out = a b (apply b first, then a)
KOKKOS_INLINE_FUNCTION void multiply(const double a[4], const double b[4], double out[4]) {
  out[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
  out[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
  out[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
  out[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
}

// out = a conj(b) (apply b's inverse, then a)
KOKKOS_INLINE_FUNCTION void multiplyByConjugate(const double a[4], const double b[4], double out[4]) {
  out[0] = a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3];
  out[1] = -a[0] * b[1] + a[1] * b[0] - a[2] * b[3] + a[3] * b[2];
  out[2] = -a[0] * b[2] + a[1] * b[3] + a[2] * b[0] - a[3] * b[1];
  out[3] = -a[0] * b[3] - a[1] * b[2] + a[2] * b[1] + a[3] * b[0];
}

// The unit quaternion of a rotation matrix, toMatrix's inverse (Shepperd 1978): the largest
// of 4 w^2, 4 x^2, 4 y^2, 4 z^2 is read off the diagonal and the others divided by it, so no
// division by a small number at any angle.
KOKKOS_INLINE_FUNCTION void fromMatrix(const double R[3][3], double q[4]) {
  const double trace = R[0][0] + R[1][1] + R[2][2];
  // 2 |q_m| for the largest component q_m, and the products 4 q_m q_k.
  double twiceLargest, scaled[4];
  if (trace >= R[0][0] && trace >= R[1][1] && trace >= R[2][2]) {
    twiceLargest = Kokkos::Experimental::sqrt(1.0 + trace);
    scaled[0] = twiceLargest * twiceLargest;
    scaled[1] = R[2][1] - R[1][2];
    scaled[2] = R[0][2] - R[2][0];
    scaled[3] = R[1][0] - R[0][1];
  } else if (R[0][0] >= R[1][1] && R[0][0] >= R[2][2]) {
    twiceLargest = Kokkos::Experimental::sqrt(1.0 + R[0][0] - R[1][1] - R[2][2]);
    scaled[0] = R[2][1] - R[1][2];
    scaled[1] = twiceLargest * twiceLargest;
    scaled[2] = R[0][1] + R[1][0];
    scaled[3] = R[0][2] + R[2][0];
  } else if (R[1][1] >= R[2][2]) {
    twiceLargest = Kokkos::Experimental::sqrt(1.0 - R[0][0] + R[1][1] - R[2][2]);
    scaled[0] = R[0][2] - R[2][0];
    scaled[1] = R[0][1] + R[1][0];
    scaled[2] = twiceLargest * twiceLargest;
    scaled[3] = R[1][2] + R[2][1];
  } else {
    twiceLargest = Kokkos::Experimental::sqrt(1.0 - R[0][0] - R[1][1] + R[2][2]);
    scaled[0] = R[1][0] - R[0][1];
    scaled[1] = R[0][2] + R[2][0];
    scaled[2] = R[1][2] + R[2][1];
    scaled[3] = twiceLargest * twiceLargest;
  }
  const double inverse = 0.5 / twiceLargest;
  for (int k = 0; k < 4; ++k) q[k] = scaled[k] * inverse;
}

// The rotation vector (axis times angle) of the unit quaternion q, its logarithm: what
// output reports as a node's rotation, and the explicit shell elements' local rotations.
// logarithm(toMatrix(q)) for angles below pi: 2 atan(|v|/w) v/|v| with q taken on the
// hemisphere w > 0. Near the identity atan(t)/t comes from its series in t^2, t = |v|/w.
KOKKOS_INLINE_FUNCTION void rotationVector(const double q[4], double theta[3]) {
  const double sign = q[0] < 0.0 ? -1.0 : 1.0;
  const double w = sign * q[0];
  const double sineSquared = q[1] * q[1] + q[2] * q[2] + q[3] * q[3];
  double scale;  // angle / |v|
  if (sineSquared < 1e-2 * w * w) {
    // atan(t)/t = sum (-t^2)^k / (2k + 1), to k = 8: the first term left out is below
    // t^18/19 < 1e-19 for t < 0.1 (angles below 0.2 rad, where the explicit elements' local
    // rotations lie; a polynomial is several times cheaper than atan2, sqrt and a division).
    const double inverseW = 1.0 / w, x = -sineSquared * inverseW * inverseW;
    const double series =
        1.0 + x * (1.0 / 3.0 +
                   x * (1.0 / 5.0 +
                        x * (1.0 / 7.0 +
                             x * (1.0 / 9.0 +
                                  x * (1.0 / 11.0 + x * (1.0 / 13.0 + x * (1.0 / 15.0 + x * (1.0 / 17.0))))))));
    scale = 2.0 * inverseW * series;
  } else {
    const double sine = Kokkos::Experimental::sqrt(sineSquared);
    scale = 2.0 * Kokkos::Experimental::atan2(sine, w) / sine;
  }
  for (int k = 0; k < 3; ++k) theta[k] = sign * scale * q[k + 1];
}

// q <- exp(theta) q, renormalised so that round-off never accumulates into a stretch.
KOKKOS_INLINE_FUNCTION void rotateBySpatialIncrement(const double theta[3], double q[4]) {
  double increment[4], updated[4];
  exponential(theta, increment);
  multiply(increment, q, updated);
  const double length = Kokkos::Experimental::sqrt(updated[0] * updated[0] + updated[1] * updated[1] +
                                                   updated[2] * updated[2] + updated[3] * updated[3]);
  for (int k = 0; k < 4; ++k) q[k] = updated[k] / length;
}

// The rotation vector of a rotation matrix (its logarithm), exact for angles below pi:
// the axial vector of the skew part is sin(angle) axis, the trace gives cos(angle). Near
// the identity angle/sin(angle) comes from its series in sin^2, which keeps the first and
// second derivatives finite at zero rotation (sqrt would not).
template <class T>
KOKKOS_INLINE_FUNCTION void logarithm(const T R[3][3], T theta[3]) {
  const T axial[3] = {0.5 * (R[2][1] - R[1][2]), 0.5 * (R[0][2] - R[2][0]), 0.5 * (R[1][0] - R[0][1])};
  const T sineSquared = dot(axial, axial);
  const T cosine = 0.5 * (R[0][0] + R[1][1] + R[2][2] - 1.0);
  T scale;
  if (math::valueOf(sineSquared) < 1e-6 && math::valueOf(cosine) > 0.0) {
    // asin(s)/s = 1 + s^2/6 + 3 s^4/40 + O(s^6); s^6 < 1e-18 here.
    scale = 1.0 + sineSquared * (1.0 / 6.0 + sineSquared * (3.0 / 40.0));
  } else {
    const T sine = math::sqrt(sineSquared);
    scale = math::atan2(sine, cosine) / sine;
  }
  for (int k = 0; k < 3; ++k) theta[k] = scale * axial[k];
}

// R(phi) = exp(phi) R to second order in phi: (I + Phi + Phi^2/2) R, Phi = skew(phi). The
// implicit tangents seed phi with dual numbers at phi = 0, where only the first two
// derivatives count, so this is exact for them.
template <class T>
KOKKOS_INLINE_FUNCTION void rotateBySpatialIncrementToSecondOrder(const T phi[3], const double R[3][3], T out[3][3]) {
  const T skew[3][3] = {{T(0.0), -phi[2], phi[1]}, {phi[2], T(0.0), -phi[0]}, {-phi[1], phi[0], T(0.0)}};
  T increment[3][3];
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      T square = skew[a][0] * skew[0][b] + skew[a][1] * skew[1][b] + skew[a][2] * skew[2][b];
      increment[a][b] = skew[a][b] + 0.5 * square + (a == b ? 1.0 : 0.0);
    }
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) out[a][b] = increment[a][0] * R[0][b] + increment[a][1] * R[1][b] + increment[a][2] * R[2][b];
}

}  // namespace perishell::rotation
