#pragma once
// Damage bookkeeping on the device (model.md §3): a node's damage is
// 1 - (intact neighbour volume) / (initial neighbour volume), volumes weighted by the
// partial-volume factor; the broken-bond count is a reduction over the half list.
#include <perishell/pd/pd_body.hpp>

namespace perishell::fracture {

template <class ExecutionSpaceT, class MemorySpaceT>
void computeDamage(const ExecutionSpaceT& space, const pd::PdBody<MemorySpaceT>& body,
                   const pd::BondFlagView<MemorySpaceT>& intact, const VectorView<MemorySpaceT>& damage) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  Kokkos::parallel_for(
      "perishell::fracture::computeDamage", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, body.numNodes()),
      KOKKOS_LAMBDA(const LocalIndex node) {
        double initial = 0.0, remaining = 0.0;
        for (RowOffset entry = body.bonds.offsets(node); entry < body.bonds.offsets(node + 1); ++entry) {
          const RowOffset b = body.bonds.fullToHalf(entry);
          const double weighted = body.volumes(body.bonds.neighbours(entry)) * body.bonds.volumeFactor(b);
          initial += weighted;
          if (intact(b)) remaining += weighted;
        }
        damage(node) = initial > 0.0 ? 1.0 - remaining / initial : 0.0;
      });
}

template <class ExecutionSpaceT, class MemorySpaceT>
long long countBrokenBonds(const ExecutionSpaceT& space, const pd::BondFlagView<MemorySpaceT>& intact) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  long long broken = 0;
  Kokkos::parallel_reduce(
      "perishell::fracture::countBrokenBonds", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, intact.extent(0)),
      KOKKOS_LAMBDA(const std::size_t b, long long& sum) { sum += intact(b) ? 0 : 1; }, broken);
  return broken;
}

}  // namespace perishell::fracture
