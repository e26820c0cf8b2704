#pragma once
// The morphing field alpha of the PD-CCM coupling (model.md §4, paper eq. 19-23, Lubineau
// et al. 2012): per mesh node, 1 on the nodes of PD elements and, elsewhere,
// profile(d / L_c) with d the distance to the nearest PD node, 0 from d = L_c on.
// Computed on the device: the PD nodes are binned in the neighbour search's cell grid with
// cells >= L_c (pd/neighbor_search.hpp), and every mesh node scans the 27 cells around its
// own. Work per node is bounded by the PD nodes within ~2 L_c, so the pass is O(N) like
// the bond search; a brute-force scan would be O(N x N_pd), 10^8 and more on the paper's
// meshes.
#include <perishell/core/types.hpp>
#include <perishell/io/deck.hpp>
#include <perishell/pd/neighbor_search.hpp>

namespace perishell::coupling {

// The transition profile at s = d / L_c (model.md §4): cubic 1 - 3 s^2 + 2 s^3 (zero slope
// at both ends, so alpha and its gradient are continuous), or linear 1 - s; 1 for s <= 0,
// 0 for s >= 1 (to a relative 1e-10, as the bond search's horizon: a node exactly L_c away
// must not carry bonds for a round-off alpha).
KOKKOS_INLINE_FUNCTION double transitionProfile(const deck::TransitionProfile profile, const double s) {
  if (!(s > 0.0)) return 1.0;
  if (s >= 1.0 - 1e-10) return 0.0;
  return profile == deck::TransitionProfile::Cubic ? 1.0 - s * s * (3.0 - 2.0 * s) : 1.0 - s;
}

// alpha at every point of `positions` (the mesh nodes), from the PD nodes' positions
// `pdPositions`, for transition width `width` = L_c > 0 [m].
template <class ExecutionSpaceT, class MemorySpaceT>
VectorView<MemorySpaceT> computeAlphaField(const ExecutionSpaceT& space, const CoordinateView<MemorySpaceT>& positions,
                                           const CoordinateView<MemorySpaceT>& pdPositions, const double width,
                                           const deck::TransitionProfile profile) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  if (!(width > 0.0)) throw std::invalid_argument("computeAlphaField: transition width must be positive");
  const LocalIndex numNodes = static_cast<LocalIndex>(positions.extent(0));
  VectorView<MemorySpaceT> alpha("coupling alpha", numNodes);
  if (pdPositions.extent(0) == 0) return alpha;
  const auto box = pd::detail::computeBoundingBox(space, pdPositions);
  if (box.nonFiniteCoordinates > 0)
    throw std::invalid_argument("computeAlphaField: a PD node has a non-finite coordinate");
  const Kokkos::View<const mesh::CrackSegment*, MemorySpaceT> noCracks =
      Kokkos::View<mesh::CrackSegment*, MemorySpaceT>("no cracks", 0);
  const auto search = pd::detail::binNodes(space, pdPositions, box, width, noCracks);
  Kokkos::parallel_for(
      "perishell::coupling::computeAlphaField", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, numNodes),
      KOKKOS_LAMBDA(const LocalIndex node) {
        const double x[3] = {positions(node, 0), positions(node, 1), positions(node, 2)};
        // The grid clamps coordinates outside the PD nodes' box to its edge cells, whose
        // neighbours still hold every PD node within L_c of x.
        int lower[3], upper[3];
        for (int d = 0; d < 3; ++d) {
          const int cell = search.grid.coordinate(x[d], d);
          lower[d] = cell > 0 ? cell - 1 : 0;
          upper[d] = cell < search.grid.cellsAlong[d] - 1 ? cell + 1 : cell;
        }
        double nearestSquared = width * width;
        for (int cz = lower[2]; cz <= upper[2]; ++cz)
          for (int cy = lower[1]; cy <= upper[1]; ++cy)
            for (int cx = lower[0]; cx <= upper[0]; ++cx) {
              const int cell = search.grid.cellIndex(cx, cy, cz);
              for (LocalIndex k = search.cellOffsets(cell); k < search.cellOffsets(cell + 1); ++k) {
                const LocalIndex j = search.cellNodes(k);
                const double dx = pdPositions(j, 0) - x[0], dy = pdPositions(j, 1) - x[1], dz = pdPositions(j, 2) - x[2];
                const double squared = dx * dx + dy * dy + dz * dz;
                if (squared < nearestSquared) nearestSquared = squared;
              }
            }
        alpha(node) = transitionProfile(profile, Kokkos::Experimental::sqrt(nearestSquared) / width);
      });
  return alpha;
}

}  // namespace perishell::coupling
