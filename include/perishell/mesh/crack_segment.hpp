#pragma once
// A pre-crack: a straight cut through the shell thickness along the segment start-end on
// the mid-surface (global coordinates, metres). `normal` is the shell normal at the crack;
// the cut is the planar patch {start + s (end - start) + r normal : s in [0, 1]}, so a bond
// crosses it when its end points lie on opposite sides of the plane through start with
// normal (end - start) x normal (a point on the plane counts as the positive side, so a
// crack along a row of nodes cuts that row from the negative side) and the crossing point
// has s in [0, 1]. Exact for flat
// plates; on curved shells it cuts along the local normal. Bonds that cross a pre-crack are
// never created (model.md §1).
namespace perishell::mesh {

struct CrackSegment {
  double start[3];
  double end[3];
  double normal[3];
};

}  // namespace perishell::mesh
