#pragma once
// Broken bonds survive a rebuilt bond list (the adaptive PD zone, coupling/adaptive_zone.hpp):
// a half bond of the new list is intact unless the old list held a bond between the same two
// nodes and it was broken (model.md §3: breaking is irreversible). Both lists index the same
// mesh nodes with neighbours ascending per node, so each new bond finds its old twin by a
// binary search in one row. One thread per new half bond.
#include <perishell/pd/pd_body.hpp>

namespace perishell::fracture {

template <class ExecutionSpaceT, class MemorySpaceT>
pd::BondFlagView<MemorySpaceT> carryBrokenBonds(const ExecutionSpaceT& space, const pd::BondList<MemorySpaceT>& from,
                                                const pd::BondFlagView<MemorySpaceT>& intactFrom,
                                                const pd::BondList<MemorySpaceT>& to) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  pd::BondFlagView<MemorySpaceT> intact("intact bonds", to.numBonds());
  const LocalIndex oldNodes = from.numNodes();
  Kokkos::parallel_for(
      "perishell::fracture::carryBrokenBonds", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, to.numBonds()),
      KOKKOS_LAMBDA(const RowOffset b) {
        const LocalIndex i = to.halfBonds(b, 0), j = to.halfBonds(b, 1);
        std::uint8_t flag = 1;
        if (i < oldNodes) {
          RowOffset low = from.offsets(i), high = from.offsets(i + 1);
          while (low < high) {
            const RowOffset middle = low + (high - low) / 2;
            if (from.neighbours(middle) < j)
              low = middle + 1;
            else
              high = middle;
          }
          if (low < from.offsets(i + 1) && from.neighbours(low) == j) flag = intactFrom(from.fullToHalf(low));
        }
        intact(b) = flag;
      });
  return intact;
}

}  // namespace perishell::fracture
