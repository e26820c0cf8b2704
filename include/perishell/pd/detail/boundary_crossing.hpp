#pragma once
// Whether the bond a-b passes through a boundary face (mesh/boundary_face.hpp) from the
// face's material to the outside. A point off the face's plane is on the side its distance
// says. A point on the plane (a node of either face of a slit, whose two faces coincide) is
// on the side its elements lie: gA, gB are the nodes' material directions
// (mesh/free_edges.hpp, nodeMaterialDirections), and a node whose elements lie on both
// sides (a slit's tip) is on neither, so nothing it touches is cut there. The bond crosses
// when its ends lie on opposite sides and the crossing point, or for a bond in the plane
// its nearer end, lies on the face or its extension over a mouth (-before <= s <= length +
// after, |r| <= reach).
#include <perishell/mesh/boundary_face.hpp>
#include <perishell/pd/detail/crack_crossing.hpp>

#include <Kokkos_Core.hpp>

namespace perishell::pd::detail {

// -1 inside, +1 outside, 0 on neither side.
KOKKOS_INLINE_FUNCTION int faceSide(const double toPoint[3], const double materialDirection[3],
                                    const mesh::BoundaryFace& face) {
  const double distance = dot3(toPoint, face.outward);
  const double onPlane = 1e-9 * face.length;
  if (distance > onPlane) return 1;
  if (distance < -onPlane) return -1;
  constexpr double clearly = 0.1;  // an edge node's direction is ~0.7 long
  const double facing = dot3(materialDirection, face.outward);
  return facing < -clearly ? -1 : (facing > clearly ? 1 : 0);
}

KOKKOS_INLINE_FUNCTION bool bondCrossesFace(const double a[3], const double b[3], const double gA[3],
                                            const double gB[3], const mesh::BoundaryFace& face, double reach) {
  double toA[3], toB[3];
  for (int d = 0; d < 3; ++d) {
    toA[d] = a[d] - face.origin[d];
    toB[d] = b[d] - face.origin[d];
  }
  const int sideA = faceSide(toA, gA, face), sideB = faceSide(toB, gB, face);
  if (sideA * sideB >= 0) return false;
  const double distanceA = dot3(toA, face.outward), distanceB = dot3(toB, face.outward);
  double toCrossing[3];
  if (distanceA != distanceB && (distanceA > 0.0) != (distanceB > 0.0)) {
    const double t = distanceA / (distanceA - distanceB);
    for (int d = 0; d < 3; ++d) toCrossing[d] = toA[d] + t * (toB[d] - toA[d]);
  } else {  // an end on the plane: it is where the bond leaves its side
    const bool aOnPlane = Kokkos::Experimental::fabs(distanceA) <= Kokkos::Experimental::fabs(distanceB);
    for (int d = 0; d < 3; ++d) toCrossing[d] = aOnPlane ? toA[d] : toB[d];
  }
  const double s = dot3(toCrossing, face.tangent);
  const double tolerance = 1e-9 * face.length;
  return s >= -face.before - tolerance && s <= face.length + face.after + tolerance &&
         Kokkos::Experimental::fabs(dot3(toCrossing, face.normal)) <= reach;
}

}  // namespace perishell::pd::detail
