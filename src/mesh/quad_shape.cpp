#include <perishell/mesh/quad_shape.hpp>

#include <algorithm>
#include <cmath>

namespace perishell::mesh {

namespace {

using Vector = std::array<double, 3>;

Vector difference(const Vector& a, const Vector& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }

Vector cross(const Vector& a, const Vector& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

double dot(const Vector& a, const Vector& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

double length(const Vector& a) { return std::sqrt(dot(a, a)); }

}  // namespace

QuadShapeCheck checkQuadShape(const std::array<std::array<double, 3>, 4>& corners) {
  double longestEdge = 0.0;
  for (int a = 0; a < 4; ++a) longestEdge = std::max(longestEdge, length(difference(corners[(a + 1) % 4], corners[a])));
  // Relative tolerances: below them a length or an area is round-off of the coordinates.
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b)
      if (!(length(difference(corners[b], corners[a])) > 1e-9 * longestEdge))
        return {QuadShapeDefect::coincidentCorners, a, b};
  // The diagonals' cross product: twice the (signed) area, along the quad's mean normal.
  const Vector normal = cross(difference(corners[2], corners[0]), difference(corners[3], corners[1]));
  const double twiceArea = length(normal);
  double largestCorner = 0.0;
  for (int a = 0; a < 4; ++a)
    largestCorner = std::max(largestCorner, length(cross(difference(corners[(a + 1) % 4], corners[a]),
                                                         difference(corners[(a + 3) % 4], corners[a]))));
  if (!(largestCorner > 1e-12 * longestEdge * longestEdge)) return {QuadShapeDefect::zeroArea};
  // Corners that span an area whose signed sum vanishes: a figure eight.
  if (!(twiceArea > 1e-8 * largestCorner)) return {QuadShapeDefect::selfCrossing};
  // Twice each corner triangle's area along the normal: all positive for a convex outline of
  // either orientation; two negative for a bow-tie, one negative (or ~0) at a re-entrant or
  // straight corner.
  int negative = 0, firstBad = -1;
  for (int a = 0; a < 4; ++a) {
    const Vector toNext = difference(corners[(a + 1) % 4], corners[a]);
    const Vector toPrevious = difference(corners[(a + 3) % 4], corners[a]);
    const double cornerArea = dot(cross(toNext, toPrevious), normal) / twiceArea;
    if (cornerArea < 0.0) ++negative;
    if (!(cornerArea > 1e-8 * twiceArea) && firstBad < 0) firstBad = a;
  }
  if (negative >= 2) return {QuadShapeDefect::selfCrossing};
  if (firstBad >= 0) return {QuadShapeDefect::reentrantCorner, firstBad};
  return {};
}

QuadShapeCheck checkTriangleShape(const std::array<std::array<double, 3>, 3>& corners) {
  double longestEdge = 0.0;
  for (int a = 0; a < 3; ++a) longestEdge = std::max(longestEdge, length(difference(corners[(a + 1) % 3], corners[a])));
  for (int a = 0; a < 3; ++a)
    for (int b = a + 1; b < 3; ++b)
      if (!(length(difference(corners[b], corners[a])) > 1e-9 * longestEdge))
        return {QuadShapeDefect::coincidentCorners, a, b};
  const double twiceArea = length(cross(difference(corners[1], corners[0]), difference(corners[2], corners[0])));
  if (!(twiceArea > 1e-8 * longestEdge * longestEdge)) return {QuadShapeDefect::zeroArea};
  return {};
}

}  // namespace perishell::mesh
