#pragma once
// Whether the bond a-b crosses a pre-crack, by the rule of mesh/crack_segment.hpp: the end
// points lie on opposite sides of the plane through `start` with normal
// (end - start) x normal, a point on the plane counting as the positive side, and the
// crossing point P = start + s (end - start) + r normal has s in [0, 1]. Callers pass the end points in a
// fixed order (lower node index first) so that the answer is the same from both ends.
#include <perishell/mesh/crack_segment.hpp>

#include <Kokkos_Core.hpp>

namespace perishell::pd::detail {

KOKKOS_INLINE_FUNCTION double dot3(const double u[3], const double v[3]) {
  return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
}

KOKKOS_INLINE_FUNCTION bool bondCrossesCrack(const double a[3], const double b[3], const mesh::CrackSegment& crack) {
  double along[3], toA[3], toB[3];
  for (int d = 0; d < 3; ++d) {
    along[d] = crack.end[d] - crack.start[d];
    toA[d] = a[d] - crack.start[d];
    toB[d] = b[d] - crack.start[d];
  }
  const double* normal = crack.normal;
  const double planeNormal[3] = {along[1] * normal[2] - along[2] * normal[1],
                                 along[2] * normal[0] - along[0] * normal[2],
                                 along[0] * normal[1] - along[1] * normal[0]};
  const double sideA = dot3(toA, planeNormal);
  const double sideB = dot3(toB, planeNormal);
  // A crack laid along a row of nodes must separate them from one side, or that row would
  // bridge the crack; so the plane itself belongs to the positive side.
  if ((sideA >= 0.0) == (sideB >= 0.0)) return false;
  const double t = sideA / (sideA - sideB);
  double toCrossing[3];
  for (int d = 0; d < 3; ++d) toCrossing[d] = toA[d] + t * (toB[d] - toA[d]);
  // toCrossing = s along + r normal: the 2x2 normal equations, determinant |along x normal|^2 > 0.
  const double alongAlong = dot3(along, along), normalNormal = dot3(normal, normal);
  const double alongNormal = dot3(along, normal);
  const double s = (dot3(toCrossing, along) * normalNormal - dot3(toCrossing, normal) * alongNormal) /
                   (alongAlong * normalNormal - alongNormal * alongNormal);
  return s >= 0.0 && s <= 1.0;
}

}  // namespace perishell::pd::detail
