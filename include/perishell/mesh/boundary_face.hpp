#pragma once
// A face of the mesh's boundary that has material beyond it (a slit's face, a notch's
// flank): a free edge (free_edges.hpp) as a through-thickness cut {origin + s tangent +
// r normal : s in [0, length]}, with `outward` the in-plane normal pointing away from its
// element. Bonds never cross one (pd/detail/boundary_crossing.hpp): no bond joins material
// that the mesh does not connect, within the horizon (model.md §1). Where a slit opens onto
// the mesh's boundary (its mouth: an end node shared with a free edge that has void beyond,
// unlike a tip inside the material), the cut goes on beyond that end, over the void: a bond
// from face to face round the mouth (past the inner rim of a slit ring) crosses there.
namespace perishell::mesh {

struct BoundaryFace {
  double origin[3];
  double tangent[3];  // unit
  double outward[3];  // unit, in the element's plane
  double normal[3];   // unit, the element's
  double length;
  double before = 0.0, after = 0.0;  // how far the cut goes on beyond origin and beyond the far end
};

}  // namespace perishell::mesh
