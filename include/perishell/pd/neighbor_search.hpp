#pragma once
// Builds the PD bond list on the device in O(N) for bounded node density (model.md §1):
// bonds join nodes i != j with 0 < |X_j - X_i| <= delta, except those crossing a pre-crack,
// those crossing a boundary face of the mesh (material the mesh does not connect: a slit's
// faces, a notch) and those between two nodes of a support layer (both held: such a bond
// never acts).
// A uniform cell grid (cells >= delta) bins the nodes (count, scan, fill); each node then
// visits the 27 cells around it twice: once to count its neighbours, once, after a scan to
// row offsets, to write and sort them. The half list and fullToHalf follow from the sorted
// rows by scans and binary searches. No host loop touches nodes or bonds; the host reads
// back only a few totals to size allocations.
#include <perishell/core/types.hpp>
#include <perishell/mesh/crack_segment.hpp>
#include <perishell/pd/bond_list.hpp>
#include <perishell/mesh/boundary_face.hpp>
#include <perishell/pd/detail/boundary_crossing.hpp>
#include <perishell/pd/detail/cell_grid.hpp>
#include <perishell/pd/detail/crack_crossing.hpp>

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

namespace perishell::pd {

// The mesh's boundary faces with material beyond them (mesh/boundary_face.hpp), and per node
// of the bond search its material direction and whether a face lies within the horizon.
// Empty: none.
template <class MemorySpaceT>
struct BoundaryFaces {
  Kokkos::View<const mesh::BoundaryFace*, MemorySpaceT> faces;
  CoordinateView<MemorySpaceT> materialDirections;
  Kokkos::View<const std::uint8_t*, MemorySpaceT> nearFace;
};

namespace detail {

template <class T>
struct NonDeduced {
  using type = T;
};

// Grid points exactly at delta are bonds; round-off in |X_j - X_i| must not decide that.
inline constexpr double relativeHorizonTolerance = 1e-10;

inline void validateBondParameters(const double horizon, const double gridSpacing) {
  const auto fail = [](const std::string& what, const double value) {
    std::ostringstream message;
    message << "buildBondList: " << what << ", got " << value;
    throw std::invalid_argument(message.str());
  };
  if (!std::isfinite(horizon) || horizon <= 0.0) fail("horizon (delta) must be positive and finite", horizon);
  if (!std::isfinite(gridSpacing) || gridSpacing <= 0.0)
    fail("gridSpacing (dx) must be positive and finite", gridSpacing);
  if (horizon < gridSpacing) {
    std::ostringstream what;
    what << "horizon (delta) must be at least gridSpacing (dx = " << gridSpacing << ")";
    fail(what.str(), horizon);
  }
}

// Exclusive scan of counts into offsets (size n + 1, offsets(n) = total); returns the total.
template <class ExecutionSpaceT, class CountView, class OffsetView>
typename OffsetView::non_const_value_type exclusiveScan(const ExecutionSpaceT& space, const char* label,
                                                        const CountView& counts, const OffsetView& offsets) {
  using Offset = typename OffsetView::non_const_value_type;
  const int n = static_cast<int>(counts.extent(0));
  Kokkos::parallel_scan(label, Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, n),
                        KOKKOS_LAMBDA(const int i, Offset& partial, const bool final) {
                          if (final) offsets(i) = partial;
                          partial += static_cast<Offset>(counts(i));
                          if (final && i == n - 1) offsets(n) = partial;
                        });
  Offset total = 0;
  Kokkos::deep_copy(space, Kokkos::View<Offset, Kokkos::HostSpace>(&total), Kokkos::subview(offsets, n));
  space.fence();
  return total;
}

// First position in the ascending range values(begin .. end-1) holding a value > key.
template <class ValuesView>
KOKKOS_INLINE_FUNCTION RowOffset upperBound(const ValuesView& values, RowOffset begin, RowOffset end,
                                            const LocalIndex key) {
  while (begin < end) {
    const RowOffset middle = begin + (end - begin) / 2;
    if (values(middle) <= key)
      begin = middle + 1;
    else
      end = middle;
  }
  return begin;
}

// The neighbours of one node from the binned nodes, for use inside a kernel.
template <class MemorySpaceT>
struct CellNeighbourSearch {
  CoordinateView<MemorySpaceT> positions;
  CellGrid grid;
  Kokkos::View<LocalIndex*, MemorySpaceT> cellOffsets;
  Kokkos::View<LocalIndex*, MemorySpaceT> cellNodes;
  Kokkos::View<const mesh::CrackSegment*, MemorySpaceT> cracks;
  double radiusSquared;
  LocalIndex firstHeldNode;  // nodes from here on are a support layer's
  BoundaryFaces<MemorySpaceT> boundary;
  double coincidentSquared;  // nodes closer than this are one point: never bonded

  KOKKOS_INLINE_FUNCTION bool crossesAnyFace(const LocalIndex i, const LocalIndex j) const {
    if (boundary.faces.extent(0) == 0 || !boundary.nearFace(i) || !boundary.nearFace(j)) return false;
    const LocalIndex first = i < j ? i : j, second = i < j ? j : i;
    const double a[3] = {positions(first, 0), positions(first, 1), positions(first, 2)};
    const double b[3] = {positions(second, 0), positions(second, 1), positions(second, 2)};
    const auto& g = boundary.materialDirections;
    const double gA[3] = {g(first, 0), g(first, 1), g(first, 2)};
    const double gB[3] = {g(second, 0), g(second, 1), g(second, 2)};
    const double reach = Kokkos::Experimental::sqrt(radiusSquared);
    for (std::size_t f = 0; f < boundary.faces.extent(0); ++f)
      if (bondCrossesFace(a, b, gA, gB, boundary.faces(f), reach)) return true;
    return false;
  }

  KOKKOS_INLINE_FUNCTION bool crossesAnyCrack(const LocalIndex i, const LocalIndex j) const {
    const LocalIndex first = i < j ? i : j, second = i < j ? j : i;
    const double a[3] = {positions(first, 0), positions(first, 1), positions(first, 2)};
    const double b[3] = {positions(second, 0), positions(second, 1), positions(second, 2)};
    for (std::size_t c = 0; c < cracks.extent(0); ++c)
      if (bondCrossesCrack(a, b, cracks(c))) return true;
    return false;
  }

  // Calls visit(j) for every bonded j, in cell order (not sorted).
  template <class Visit>
  KOKKOS_INLINE_FUNCTION void forEachNeighbour(const LocalIndex i, Visit&& visit) const {
    const double x[3] = {positions(i, 0), positions(i, 1), positions(i, 2)};
    int lower[3], upper[3];
    for (int d = 0; d < 3; ++d) {
      const int cell = grid.coordinate(x[d], d);
      lower[d] = cell > 0 ? cell - 1 : 0;
      upper[d] = cell < grid.cellsAlong[d] - 1 ? cell + 1 : cell;
    }
    for (int cz = lower[2]; cz <= upper[2]; ++cz)
      for (int cy = lower[1]; cy <= upper[1]; ++cy)
        for (int cx = lower[0]; cx <= upper[0]; ++cx) {
          const int cell = grid.cellIndex(cx, cy, cz);
          for (LocalIndex k = cellOffsets(cell); k < cellOffsets(cell + 1); ++k) {
            const LocalIndex j = cellNodes(k);
            if (j == i) continue;
            const double dx = positions(j, 0) - x[0], dy = positions(j, 1) - x[1], dz = positions(j, 2) - x[2];
            const double distanceSquared = dx * dx + dy * dy + dz * dz;
            if (distanceSquared > radiusSquared || distanceSquared <= coincidentSquared) continue;
            if (i >= firstHeldNode && j >= firstHeldNode) continue;
            if (crossesAnyCrack(i, j) || crossesAnyFace(i, j)) continue;
            visit(j);
          }
        }
  }
};

template <class ExecutionSpaceT, class MemorySpaceT>
CellNeighbourSearch<MemorySpaceT> binNodes(const ExecutionSpaceT& space, const CoordinateView<MemorySpaceT>& positions,
                                           const BoundingBox& box, const double radius,
                                           const Kokkos::View<const mesh::CrackSegment*, MemorySpaceT>& cracks,
                                           const LocalIndex firstHeldNode = std::numeric_limits<LocalIndex>::max(),
                                           const BoundaryFaces<MemorySpaceT>& boundary = {}) {
  using Policy = Kokkos::RangePolicy<ExecutionSpaceT>;
  const LocalIndex numNodes = static_cast<LocalIndex>(positions.extent(0));
  const CellGrid grid = makeCellGrid(box, radius, numNodes);
  const int numCells = grid.numCells();
  Kokkos::View<LocalIndex*, MemorySpaceT> cellFill("perishell::pd::cellFill", numCells);
  Kokkos::View<LocalIndex*, MemorySpaceT> cellOffsets("perishell::pd::cellOffsets", numCells + 1);
  Kokkos::View<LocalIndex*, MemorySpaceT> cellNodes(Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::pd::cellNodes"),
                                                    numNodes);
  Kokkos::parallel_for(
      "perishell::pd::countCellNodes", Policy(space, 0, numNodes),
      KOKKOS_LAMBDA(const int node) {
        Kokkos::atomic_increment(&cellFill(grid.cellOf(positions(node, 0), positions(node, 1), positions(node, 2))));
      });
  exclusiveScan(space, "perishell::pd::cellOffsets", cellFill, cellOffsets);
  // Order inside a cell depends on atomics; node rows are sorted later, so bonds do not.
  Kokkos::deep_copy(space, cellFill, 0);
  Kokkos::parallel_for(
      "perishell::pd::fillCells", Policy(space, 0, numNodes), KOKKOS_LAMBDA(const int node) {
        const int cell = grid.cellOf(positions(node, 0), positions(node, 1), positions(node, 2));
        cellNodes(cellOffsets(cell) + Kokkos::atomic_fetch_add(&cellFill(cell), 1)) = node;
      });
  // A millionth of the horizon apart is one point to any mesh a horizon covers.
  const double coincident = 1e-6 * radius;
  return {positions, grid,          cellOffsets, cellNodes, cracks, radius * radius, firstHeldNode,
          boundary,  coincident * coincident};
}

}  // namespace detail

// The bonds of the nodes `positions` for horizon delta = `horizon` [m] on a grid of spacing
// dx = `gridSpacing` [m] (used for the partial-volume factor), without bonds that cross
// `cracks` (rule: mesh/crack_segment.hpp), those that cross `boundary` (rule:
// pd/detail/boundary_crossing.hpp), those between coincident nodes and those between two
// nodes from firstHeldNode on (a support layer, mesh/support_layer.hpp). Throws std::invalid_argument for a horizon or
// spacing that is not positive and finite, a horizon below the spacing, or non-finite
// positions. No nodes give an empty list.
template <class ExecutionSpaceT, class MemorySpaceT>
BondList<MemorySpaceT> buildBondList(
    const ExecutionSpaceT& space, const CoordinateView<MemorySpaceT>& positions, const double horizon,
    const double gridSpacing,
    const Kokkos::View<const mesh::CrackSegment*, typename detail::NonDeduced<MemorySpaceT>::type>& cracks,
    const LocalIndex firstHeldNode = std::numeric_limits<LocalIndex>::max(),
    const BoundaryFaces<typename detail::NonDeduced<MemorySpaceT>::type>& boundary = {}) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  static_assert(Kokkos::SpaceAccessibility<ExecutionSpaceT, MemorySpaceT>::accessible,
                "buildBondList: the positions must be accessible from the execution space");
  using Policy = Kokkos::RangePolicy<ExecutionSpaceT>;
  detail::validateBondParameters(horizon, gridSpacing);
  const LocalIndex numNodes = static_cast<LocalIndex>(positions.extent(0));

  BondList<MemorySpaceT> bonds;
  bonds.offsets = Kokkos::View<RowOffset*, MemorySpaceT>("perishell::pd::BondList::offsets", numNodes + 1);
  if (numNodes == 0) {
    bonds.neighbours = decltype(bonds.neighbours)("perishell::pd::BondList::neighbours", 0);
    bonds.fullToHalf = decltype(bonds.fullToHalf)("perishell::pd::BondList::fullToHalf", 0);
    bonds.halfBonds = decltype(bonds.halfBonds)("perishell::pd::BondList::halfBonds", 0);
    bonds.referenceLength = decltype(bonds.referenceLength)("perishell::pd::BondList::referenceLength", 0);
    bonds.volumeFactor = decltype(bonds.volumeFactor)("perishell::pd::BondList::volumeFactor", 0);
    return bonds;
  }

  const detail::BoundingBox box = detail::computeBoundingBox(space, positions);
  if (box.nonFiniteCoordinates > 0) {
    std::ostringstream message;
    message << "buildBondList: positions: " << box.nonFiniteCoordinates << " node coordinates are not finite";
    throw std::invalid_argument(message.str());
  }
  for (int d = 0; d < 3; ++d)
    if (!std::isfinite(box.upper[d] - box.lower[d]))
      throw std::invalid_argument("buildBondList: positions: the nodes' bounding box is too large to represent");
  const double radius = horizon * (1.0 + detail::relativeHorizonTolerance);
  const auto search = detail::binNodes(space, positions, box, radius, cracks, firstHeldNode, boundary);

  // Full list: count, scan to row offsets, fill and sort each row.
  Kokkos::View<LocalIndex*, MemorySpaceT> rowCounts(
      Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::pd::rowCounts"), numNodes);
  Kokkos::parallel_for(
      "perishell::pd::countNeighbours", Policy(space, 0, numNodes), KOKKOS_LAMBDA(const int node) {
        LocalIndex count = 0;
        search.forEachNeighbour(node, [&](LocalIndex) { ++count; });
        rowCounts(node) = count;
      });
  const auto offsets = bonds.offsets;
  const RowOffset numFullEntries = detail::exclusiveScan(space, "perishell::pd::rowOffsets", rowCounts, offsets);
  const Kokkos::View<LocalIndex*, MemorySpaceT> neighbours(
      Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::pd::BondList::neighbours"), numFullEntries);
  Kokkos::parallel_for(
      "perishell::pd::fillNeighbours", Policy(space, 0, numNodes), KOKKOS_LAMBDA(const int node) {
        const RowOffset begin = offsets(node), end = offsets(node + 1);
        RowOffset slot = begin;
        search.forEachNeighbour(node, [&](const LocalIndex j) { neighbours(slot++) = j; });
        // Insertion sort: rows hold tens of entries, and sorted rows make the list deterministic.
        for (RowOffset k = begin + 1; k < end; ++k) {
          const LocalIndex value = neighbours(k);
          RowOffset hole = k;
          for (; hole > begin && neighbours(hole - 1) > value; --hole) neighbours(hole) = neighbours(hole - 1);
          neighbours(hole) = value;
        }
      });

  // Half list: the entries j > i of each sorted row, placed by a scan of their counts.
  Kokkos::parallel_for(
      "perishell::pd::countHalfBonds", Policy(space, 0, numNodes), KOKKOS_LAMBDA(const int node) {
        const RowOffset end = offsets(node + 1);
        rowCounts(node) = static_cast<LocalIndex>(end - detail::upperBound(neighbours, offsets(node), end, node));
      });
  Kokkos::View<RowOffset*, MemorySpaceT> halfOffsets("perishell::pd::halfOffsets", numNodes + 1);
  const RowOffset numBonds = detail::exclusiveScan(space, "perishell::pd::halfOffsets", rowCounts, halfOffsets);
  using HalfBondView = decltype(bonds.halfBonds);
  const HalfBondView halfBonds(Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::pd::BondList::halfBonds"),
                               numBonds);
  const Kokkos::View<double*, MemorySpaceT> referenceLength(
      Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::pd::BondList::referenceLength"), numBonds);
  const Kokkos::View<double*, MemorySpaceT> volumeFactor(
      Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::pd::BondList::volumeFactor"), numBonds);
  const Kokkos::View<RowOffset*, MemorySpaceT> fullToHalf(
      Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::pd::BondList::fullToHalf"), numFullEntries);
  Kokkos::parallel_for(
      "perishell::pd::fillHalfBonds", Policy(space, 0, numNodes), KOKKOS_LAMBDA(const int node) {
        const RowOffset begin = offsets(node), end = offsets(node + 1);
        const RowOffset firstAbove = detail::upperBound(neighbours, begin, end, node);
        // Entries j < node: bond (j, node) sits in row j's half segment, found by bisection.
        for (RowOffset k = begin; k < firstAbove; ++k) {
          const LocalIndex j = neighbours(k);
          const RowOffset rowEnd = offsets(j + 1);
          const RowOffset jFirstAbove = detail::upperBound(neighbours, offsets(j), rowEnd, j);
          const RowOffset position = detail::upperBound(neighbours, jFirstAbove, rowEnd, node) - 1;
          fullToHalf(k) = halfOffsets(j) + (position - jFirstAbove);
        }
        for (RowOffset k = firstAbove; k < end; ++k) {
          const LocalIndex j = neighbours(k);
          const RowOffset bond = halfOffsets(node) + (k - firstAbove);
          fullToHalf(k) = bond;
          halfBonds(bond, 0) = node;
          halfBonds(bond, 1) = j;
          double lengthSquared = 0.0;
          for (int d = 0; d < 3; ++d) {
            const double difference = positions(j, d) - positions(node, d);
            lengthSquared += difference * difference;
          }
          const double xi = Kokkos::Experimental::sqrt(lengthSquared);
          referenceLength(bond) = xi;
          // Partial volume (model.md §1 asks for one, stated): the linear "partial area" rule,
          // the fraction of a neighbour's cell of width dx inside the horizon, beta = 1 for
          // xi <= delta - dx/2 and (delta + dx/2 - xi)/dx beyond; bonds admitted by the
          // tolerance count as xi = delta, so beta is in [1/2, 1].
          const double clipped = xi < horizon ? xi : horizon;
          volumeFactor(bond) = clipped <= horizon - 0.5 * gridSpacing
                                   ? 1.0
                                   : (horizon + 0.5 * gridSpacing - clipped) / gridSpacing;
        }
      });
  space.fence();

  bonds.neighbours = neighbours;
  bonds.fullToHalf = fullToHalf;
  bonds.halfBonds = halfBonds;
  bonds.referenceLength = referenceLength;
  bonds.volumeFactor = volumeFactor;
  return bonds;
}

// Without pre-cracks.
template <class ExecutionSpaceT, class MemorySpaceT>
BondList<MemorySpaceT> buildBondList(const ExecutionSpaceT& space, const CoordinateView<MemorySpaceT>& positions,
                                     const double horizon, const double gridSpacing) {
  return buildBondList(space, positions, horizon, gridSpacing,
                       Kokkos::View<mesh::CrackSegment*, MemorySpaceT>("perishell::pd::noCracks", 0));
}

}  // namespace perishell::pd
