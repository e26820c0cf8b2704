#pragma once
// Uniform cell grid for the O(N) neighbour search: the nodes' bounding box (one device
// reduction) cut into cubic cells no smaller than the search radius, so every neighbour of
// a node lies in its own cell or one of the 26 around it.
#include <perishell/core/types.hpp>

#include <algorithm>
#include <cfloat>
#include <climits>
#include <cmath>

namespace perishell::pd::detail {

struct BoundingBox {
  double lower[3];
  double upper[3];
  LocalIndex nonFiniteCoordinates;
};

// Kokkos reducer (the 3.4 interface, volatile joins included) for BoundingBox.
template <class SpaceT>
struct BoundingBoxReducer {
  using reducer = BoundingBoxReducer;
  using value_type = BoundingBox;
  using result_view_type = Kokkos::View<value_type, SpaceT, Kokkos::MemoryUnmanaged>;

  KOKKOS_INLINE_FUNCTION explicit BoundingBoxReducer(value_type& result) : result_(&result) {}

  KOKKOS_INLINE_FUNCTION void join(value_type& into, const value_type& from) const {
    for (int d = 0; d < 3; ++d) {
      into.lower[d] = from.lower[d] < into.lower[d] ? from.lower[d] : into.lower[d];
      into.upper[d] = from.upper[d] > into.upper[d] ? from.upper[d] : into.upper[d];
    }
    into.nonFiniteCoordinates += from.nonFiniteCoordinates;
  }
  KOKKOS_INLINE_FUNCTION void join(volatile value_type& into, const volatile value_type& from) const {
    for (int d = 0; d < 3; ++d) {
      into.lower[d] = from.lower[d] < into.lower[d] ? from.lower[d] : into.lower[d];
      into.upper[d] = from.upper[d] > into.upper[d] ? from.upper[d] : into.upper[d];
    }
    into.nonFiniteCoordinates += from.nonFiniteCoordinates;
  }
  KOKKOS_INLINE_FUNCTION void init(value_type& value) const {
    for (int d = 0; d < 3; ++d) {
      value.lower[d] = DBL_MAX;
      value.upper[d] = -DBL_MAX;
    }
    value.nonFiniteCoordinates = 0;
  }
  KOKKOS_INLINE_FUNCTION value_type& reference() const { return *result_.data(); }
  KOKKOS_INLINE_FUNCTION result_view_type view() const { return result_; }
  KOKKOS_INLINE_FUNCTION bool references_scalar() const { return true; }

 private:
  result_view_type result_;
};

template <class ExecutionSpaceT, class MemorySpaceT>
BoundingBox computeBoundingBox(const ExecutionSpaceT& space, const CoordinateView<MemorySpaceT>& positions) {
  BoundingBox box;
  Kokkos::parallel_reduce(
      "perishell::pd::boundingBox",
      Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, positions.extent(0)),
      KOKKOS_LAMBDA(const int node, BoundingBox& partial) {
        for (int d = 0; d < 3; ++d) {
          const double x = positions(node, d);
          if (!(Kokkos::Experimental::fabs(x) <= DBL_MAX)) {  // NaN or infinite
            ++partial.nonFiniteCoordinates;
            continue;
          }
          if (x < partial.lower[d]) partial.lower[d] = x;
          if (x > partial.upper[d]) partial.upper[d] = x;
        }
      },
      BoundingBoxReducer<Kokkos::HostSpace>(box));
  return box;
}

struct CellGrid {
  double origin[3];
  double inverseCellSize;
  int cellsAlong[3];

  int numCells() const { return cellsAlong[0] * cellsAlong[1] * cellsAlong[2]; }

  // Clamped, so round-off at the box's upper faces cannot step outside the grid.
  KOKKOS_INLINE_FUNCTION int coordinate(const double x, const int d) const {
    const double scaled = (x - origin[d]) * inverseCellSize;
    if (!(scaled > 0.0)) return 0;
    if (scaled >= double(cellsAlong[d] - 1)) return cellsAlong[d] - 1;
    return static_cast<int>(scaled);
  }
  KOKKOS_INLINE_FUNCTION int cellIndex(const int cx, const int cy, const int cz) const {
    return (cz * cellsAlong[1] + cy) * cellsAlong[0] + cx;
  }
  KOKKOS_INLINE_FUNCTION int cellOf(const double x, const double y, const double z) const {
    return cellIndex(coordinate(x, 0), coordinate(y, 1), coordinate(z, 2));
  }
};

// Cells are at least searchRadius wide (with a 0.1 % margin, so round-off in a cell
// coordinate never puts two nodes within the radius more than one cell apart), and grown
// until there are at most ~2 cells per node: a few far-apart nodes must not allocate a
// huge empty grid. Larger cells only cost more distance checks, never a missed neighbour.
inline CellGrid makeCellGrid(const BoundingBox& box, const double searchRadius, const LocalIndex numNodes) {
  const double maxCells = std::min(2.0 * numNodes + 27.0, double(INT_MAX / 2));
  double cellSize = 1.001 * searchRadius;
  const auto cellsAlong = [&](const int d) { return std::floor((box.upper[d] - box.lower[d]) / cellSize) + 1.0; };
  while (cellsAlong(0) * cellsAlong(1) * cellsAlong(2) > maxCells) cellSize *= 1.25;
  CellGrid grid;
  grid.inverseCellSize = 1.0 / cellSize;
  for (int d = 0; d < 3; ++d) {
    grid.origin[d] = box.lower[d];
    grid.cellsAlong[d] = static_cast<int>(cellsAlong(d));
  }
  return grid;
}

}  // namespace perishell::pd::detail
