#pragma once
// Built-in meshes of the paper's geometries (SI units) with their named sets, and the
// pre-crack constructor. Spacing-driven generators use cells = round(length / spacing), so
// the actual spacing is length / cells (e.g. 0.09 m at 1 mm gives 90 cells exactly, not 89
// from round-off). Invalid sizes throw std::invalid_argument naming the parameter.
#include <perishell/mesh/crack_segment.hpp>
#include <perishell/mesh/mesh_sets.hpp>

#include <array>

namespace perishell::mesh {

// Flat plate [0, lengthX] x [0, lengthY] at z = 0 (makeRectangularPlate's numbering), normal
// +z. Sets: node and edge sets "left" (x = 0), "right" (x = lengthX), "bottom" (y = 0),
// "top" (y = lengthY); node sets "bottom-left", "bottom-right", "top-right", "top-left"
// (one corner node each) and "boundary".
ShellMesh makePlate(double lengthX, double lengthY, double spacing);
ShellMesh makePlateWithCells(double lengthX, double lengthY, int cellsX, int cellsY);

// Closed cylinder of the given radius about the z axis, z in [0, height]: `around` quads
// round the circumference (round(2 pi radius / spacing), at least 3) by `along` quads
// (round(height / spacing)). The seam shares its nodes, so there are around * (along + 1)
// nodes; node j * around + i sits at angle 2 pi i / around on ring j. Quads are flat facets
// with outward normals. Sets: node and edge sets "bottom" (z = 0) and "top" (z = height).
ShellMesh makeCylinder(double radius, double height, double spacing);

// Hexagonal prism about the z axis, z in [0, length]: six flat faces of width sideLength
// (hexagon vertices at radius sideLength, the first on +x), round(sideLength / spacing)
// quads across each face, round(length / spacing) along; faces share the nodes on the six
// prism edges. Outward normals. Sets: node and edge sets "bottom" and "top" (the end rims);
// element and node sets "face-0".."face-5" (face k between vertices k and k + 1, outward
// normal at angle 60 k + 30 degrees).
ShellMesh makeHexagonalPrism(double sideLength, double length, double spacing);

// A pre-crack from start to end with shell normal `normal` (any length; stored normalised).
// Throws std::invalid_argument for non-finite input, a degenerate segment, a zero normal or
// a normal parallel to the segment (the cut plane would be undefined).
CrackSegment makeCrack(const std::array<double, 3>& start, const std::array<double, 3>& end,
                       const std::array<double, 3>& normal);

}  // namespace perishell::mesh
