#pragma once
// The CRS sparsity of a one-DOF-per-node field on a quad mesh (node adjacency through
// elements), plus the scatter map from each element matrix entry to its CRS value slot, so
// that assembly is a parallel_for over elements with atomic_add (paper §3.2.1).
#include <perishell/mesh/quad_mesh.hpp>

namespace perishell::assembly {

template <class MemorySpaceT>
struct QuadCrsPattern {
  Kokkos::View<RowOffset*, MemorySpaceT> rowMap;
  Kokkos::View<LocalIndex*, MemorySpaceT> columns;
  // valueSlot(e, a, b): index into the CRS values of K(quads(e, a), quads(e, b)).
  Kokkos::View<RowOffset* [4][4], Kokkos::LayoutRight, MemorySpaceT> valueSlot;

  LocalIndex numRows() const { return static_cast<LocalIndex>(rowMap.extent(0)) - 1; }
  RowOffset numEntries() const { return columns.extent(0); }
};

// Built on the host at setup (sorted columns per row), returned in MemorySpaceT.
QuadCrsPattern<Kokkos::HostSpace> buildQuadCrsPattern(const mesh::HostQuadMesh& mesh);

template <class MemorySpaceT>
QuadCrsPattern<MemorySpaceT> mirrorTo(const QuadCrsPattern<Kokkos::HostSpace>& host) {
  return {Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, host.rowMap),
          Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, host.columns),
          Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, host.valueSlot)};
}

}  // namespace perishell::assembly
