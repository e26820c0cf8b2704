#pragma once
// The PD bonds of a set of nodes (model.md §1), stored twice:
// - a full CSR list: the neighbours of node i are neighbours(offsets(i) .. offsets(i+1)-1),
//   ascending, so node-mapped kernels (forces, damage) read one contiguous row;
// - a half list: every bond once as (i, j) with i < j, sorted by (i, j), carrying the bond's
//   reference length and partial-volume factor; per-bond state (broken flags, energies)
//   lives once per half bond, and fullToHalf takes a full-list entry to its half bond.
// Memory: 48 bytes per bond (full list 2 x 4 B neighbours + 2 x 8 B fullToHalf; half list
// 8 B node pair + 8 B length + 8 B factor) plus 8 bytes per node of row offsets.
#include <perishell/core/types.hpp>

namespace perishell::pd {

template <class MemorySpaceT>
struct BondList {
  Kokkos::View<RowOffset*, MemorySpaceT> offsets;        // numNodes + 1
  Kokkos::View<LocalIndex*, MemorySpaceT> neighbours;    // 2 numBonds, ascending per node
  Kokkos::View<RowOffset*, MemorySpaceT> fullToHalf;     // 2 numBonds
  Kokkos::View<LocalIndex* [2], Kokkos::LayoutRight, MemorySpaceT> halfBonds;  // numBonds
  Kokkos::View<double*, MemorySpaceT> referenceLength;  // xi = |X_j - X_i| [m], numBonds
  Kokkos::View<double*, MemorySpaceT> volumeFactor;     // partial-volume beta in (0, 1]

  LocalIndex numNodes() const { return static_cast<LocalIndex>(offsets.extent(0)) - 1; }
  RowOffset numBonds() const { return halfBonds.extent(0); }
  RowOffset numFullEntries() const { return neighbours.extent(0); }
  // Bytes the list holds, for capacity planning (see the header comment).
  std::size_t bytes() const {
    return offsets.span() * sizeof(RowOffset) + neighbours.span() * sizeof(LocalIndex) +
           fullToHalf.span() * sizeof(RowOffset) + halfBonds.span() * sizeof(LocalIndex) +
           referenceLength.span() * sizeof(double) + volumeFactor.span() * sizeof(double);
  }
};

template <class TargetMemorySpaceT, class SourceMemorySpaceT>
BondList<TargetMemorySpaceT> mirrorTo(const BondList<SourceMemorySpaceT>& source) {
  const TargetMemorySpaceT target;
  return {Kokkos::create_mirror_view_and_copy(target, source.offsets),
          Kokkos::create_mirror_view_and_copy(target, source.neighbours),
          Kokkos::create_mirror_view_and_copy(target, source.fullToHalf),
          Kokkos::create_mirror_view_and_copy(target, source.halfBonds),
          Kokkos::create_mirror_view_and_copy(target, source.referenceLength),
          Kokkos::create_mirror_view_and_copy(target, source.volumeFactor)};
}

// The rows of the nodes with nodeMask(i) != 0, the other rows empty: a node-mapped kernel over
// the result evaluates only the masked nodes' bonds. The half list and its per-bond data are
// shared, not copied (fullToHalf still indexes them), so per-bond state views stay valid.
template <class ExecutionSpaceT, class MemorySpaceT>
BondList<MemorySpaceT> restrictRows(const ExecutionSpaceT& space, const BondList<MemorySpaceT>& bonds,
                                    const Kokkos::View<const std::uint8_t*, MemorySpaceT>& nodeMask) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  const LocalIndex numNodes = bonds.numNodes();
  BondList<MemorySpaceT> rows = bonds;
  rows.offsets = Kokkos::View<RowOffset*, MemorySpaceT>("restricted bond offsets", numNodes + 1);
  const auto offsets = rows.offsets, fullOffsets = bonds.offsets;
  RowOffset entries = 0;
  Kokkos::parallel_scan(
      "perishell::pd::restrictRows::offsets", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, numNodes + 1),
      KOKKOS_LAMBDA(const LocalIndex node, RowOffset& sum, const bool final) {
        if (final) offsets(node) = sum;
        if (node < numNodes && nodeMask(node)) sum += fullOffsets(node + 1) - fullOffsets(node);
      },
      entries);
  rows.neighbours = Kokkos::View<LocalIndex*, MemorySpaceT>("restricted bond neighbours", entries);
  rows.fullToHalf = Kokkos::View<RowOffset*, MemorySpaceT>("restricted bond full to half", entries);
  const auto neighbours = rows.neighbours;
  const auto fullToHalf = rows.fullToHalf;
  const auto fullNeighbours = bonds.neighbours;
  const auto fullFullToHalf = bonds.fullToHalf;
  Kokkos::parallel_for(
      "perishell::pd::restrictRows::copy", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, numNodes),
      KOKKOS_LAMBDA(const LocalIndex node) {
        for (RowOffset k = 0; k < offsets(node + 1) - offsets(node); ++k) {
          neighbours(offsets(node) + k) = fullNeighbours(fullOffsets(node) + k);
          fullToHalf(offsets(node) + k) = fullFullToHalf(fullOffsets(node) + k);
        }
      });
  return rows;
}

}  // namespace perishell::pd
