#pragma once
// Homogeneous Dirichlet conditions by symmetric elimination: constrained rows and columns
// are zeroed, their diagonal set to 1 and their right-hand side to 0, so the matrix stays
// symmetric (CG needs it) and the constrained unknowns solve to exactly 0.
#include <perishell/core/types.hpp>

namespace perishell::assembly {

template <class ExecutionSpaceT, class MemorySpaceT>
void eliminateHomogeneousDirichlet(const ExecutionSpaceT& space,
                                   const Kokkos::View<RowOffset*, MemorySpaceT>& rowMap,
                                   const Kokkos::View<LocalIndex*, MemorySpaceT>& columns,
                                   const VectorView<MemorySpaceT>& values,
                                   const VectorView<MemorySpaceT>& rhs,
                                   const Kokkos::View<bool*, MemorySpaceT>& isConstrained) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  Kokkos::parallel_for(
      "perishell::eliminateHomogeneousDirichlet",
      Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, static_cast<int>(rhs.extent(0))),
      KOKKOS_LAMBDA(const int row) {
        const bool rowConstrained = isConstrained(row);
        for (RowOffset slot = rowMap(row); slot < rowMap(row + 1); ++slot) {
          const LocalIndex column = columns(slot);
          if (rowConstrained)
            values(slot) = (column == row) ? 1.0 : 0.0;
          else if (isConstrained(column))
            values(slot) = 0.0;
        }
        if (rowConstrained) rhs(row) = 0.0;
      });
}

}  // namespace perishell::assembly
