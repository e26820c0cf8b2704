#pragma once
// A deck's loads and supports as per-node 6-DOF data (DOF order ux uy uz rx ry rz,
// model.md §1), the form the solvers consume. Host data built once at setup; a solver moves
// what it needs to the device with Kokkos::create_mirror_view_and_copy (the layouts are
// explicit so the mirrors are assignable).
#include <perishell/model/model.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace perishell::model {

using HostNodalValues = Kokkos::View<double* [6], Kokkos::LayoutRight, Kokkos::HostSpace>;

// Fixed-direction loads sharing one load curve, summed into reference nodal forces/moments.
struct LoadPattern {
  std::string curve;       // deck curve name; empty: no curve (factor rules in docs/deck.md)
  HostNodalValues nodal;  // [N, N m], one row per mesh node
};

// A pressure that turns with the deforming element (deck `follower: true`); solvers apply it
// per step from the current geometry.
struct FollowerPressure {
  std::string name;  // deck load name
  std::string curve;
  double pressure = 0.0;  // [Pa], along the current element normal
  std::vector<LocalIndex> elements;
};

struct NodalLoads {
  std::vector<LoadPattern> patterns;  // one per distinct curve (deck order of first use)
  std::vector<FollowerPressure> followerPressures;
};

// Point forces/moments act on every node of their set. Edge tractions act on the edge's
// cross-section (length x thickness) and load each end node with half of it (consistent
// loads of a linear edge): a `vector` traction in its fixed global direction, a `value`
// traction along the outward in-plane edge normal (positive pulls), which is the edge
// direction crossed with the mean of its end nodes' normals (edges run with the shell on
// their left). Fixed-direction pressure: consistent bilinear loads F_a = ∫ N_a p n dA over
// the reference element, 2x2 Gauss (exact: n dA = g_1 x g_2 dξ dη is linear in ξ, η).
// Throws DeckError naming the load's key (e.g. "loads.top.set") for what the deck reader
// cannot see: non-finite nodal values, an edge with no outward normal.
NodalLoads buildNodalLoads(const Model& model);

struct SupportConditions {
  // Bit d set: DOF d of the node is prescribed; one entry per mesh node.
  Kokkos::View<std::uint8_t*, Kokkos::HostSpace> constrainedDofs;
  HostNodalValues prescribedValue;  // [m, rad] at curve factor 1; 0 where free
  // Index into curves, -1: the value holds at all times (also every zero value).
  Kokkos::View<std::int8_t* [6], Kokkos::LayoutRight, Kokkos::HostSpace> curveIndex;
  std::vector<std::string> curves;  // deck curve names used by non-zero supports

  long long numConstrainedDofs() const;
};

// Supports may overlap (two edge sets share a corner node) as long as they prescribe the same
// value on a shared DOF; a zero value is the same whatever its curve. Throws DeckError naming
// both supports when they prescribe different values or curves on one node DOF.
SupportConditions buildSupportConditions(const Model& model);

}  // namespace perishell::model
