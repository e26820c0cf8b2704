#pragma once
// Dirichlet conditions by symmetric elimination on a CRS matrix (the pattern must hold the
// diagonal of every constrained row): constrained rows and columns are zeroed except the
// diagonal, so the matrix stays symmetric (CG needs it).
// - eliminateHomogeneousDirichlet: diagonal 1, right-hand side 0; the unknowns solve to 0.
// - eliminateDirichlet: prescribed values u_c (a Newton step's increments, say). The free
//   rows move the known columns to the right-hand side, f_i -= K_ic u_c; a constrained row
//   keeps its assembled diagonal d (so point and block Jacobi stay scaled like the rest of
//   the matrix; 1 where d is 0 or not finite) with right-hand side d u_c, and solves to u_c.
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

namespace detail {
// Keeps a parameter out of template deduction, so any View assignable to it converts
// (View<double*> to View<const double*>, a mirror's explicit LayoutRight to the default).
template <class T>
struct NonDeduced {
  using type = T;
};
}  // namespace detail

template <class ExecutionSpaceT, class MemorySpaceT>
void eliminateDirichlet(
    const ExecutionSpaceT& space, const Kokkos::View<RowOffset*, MemorySpaceT>& rowMap,
    const Kokkos::View<LocalIndex*, MemorySpaceT>& columns, const VectorView<MemorySpaceT>& values,
    const VectorView<MemorySpaceT>& rhs,
    const typename detail::NonDeduced<Kokkos::View<const bool*, MemorySpaceT>>::type& isConstrained,
    const typename detail::NonDeduced<Kokkos::View<const double*, MemorySpaceT>>::type& prescribed) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  const Kokkos::RangePolicy<ExecutionSpaceT> rows(space, 0, static_cast<int>(rhs.extent(0)));
  // Two kernels: every free row reads its constrained columns before any row is zeroed.
  Kokkos::parallel_for(
      "perishell::moveDirichletColumnsToRhs", rows, KOKKOS_LAMBDA(const int row) {
        if (isConstrained(row)) return;
        double known = 0.0;
        for (RowOffset slot = rowMap(row); slot < rowMap(row + 1); ++slot) {
          const LocalIndex column = columns(slot);
          if (isConstrained(column)) known += values(slot) * prescribed(column);
        }
        rhs(row) -= known;
      });
  Kokkos::parallel_for(
      "perishell::eliminateDirichlet", rows, KOKKOS_LAMBDA(const int row) {
        const bool rowConstrained = isConstrained(row);
        for (RowOffset slot = rowMap(row); slot < rowMap(row + 1); ++slot) {
          const LocalIndex column = columns(slot);
          if (column == row && rowConstrained) {
            const double assembled = values(slot);
            const double diagonal = (assembled != 0.0 && Kokkos::Experimental::isfinite(assembled)) ? assembled : 1.0;
            values(slot) = diagonal;
            rhs(row) = diagonal * prescribed(row);
          } else if (rowConstrained || isConstrained(column)) {
            values(slot) = 0.0;
          }
        }
      });
}

}  // namespace perishell::assembly
