#pragma once
// The shape checks a 4-node quad (and a triangle) must pass before any element or node
// weight is built on it: no two corners at one point, a non-zero area, and an outline that
// neither crosses itself (a bow-tie: corners listed out of order) nor folds inward (a
// re-entrant or straight corner, where the bilinear map's Jacobian vanishes or changes
// sign). Either orientation of a valid quad passes. Used where meshes enter (the Gmsh reader), so a bad element is named
// by the user's tags and file line instead of failing later by an internal index.
#include <array>

namespace perishell::mesh {

enum class QuadShapeDefect { none, coincidentCorners, zeroArea, selfCrossing, reentrantCorner };

struct QuadShapeCheck {
  QuadShapeDefect defect = QuadShapeDefect::none;
  int corner = -1;       // coincidentCorners: the first of the two; reentrantCorner: the corner
  int otherCorner = -1;  // coincidentCorners: the second
};

// corners: the quad's corner coordinates [m] in its node order.
QuadShapeCheck checkQuadShape(const std::array<std::array<double, 3>, 4>& corners);

// A triangle's checks: three distinct corners and a non-zero area (coincidentCorners or
// zeroArea; a triangle cannot cross itself or fold).
QuadShapeCheck checkTriangleShape(const std::array<std::array<double, 3>, 3>& corners);

}  // namespace perishell::mesh
