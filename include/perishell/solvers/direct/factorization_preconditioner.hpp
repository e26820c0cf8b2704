#pragma once
// M = (L L^T)^{-1} of a recent tangent as a Belos preconditioner (direct/sparse_cholesky.hpp).
// Exact when fresh (PCG converges in one iteration); Newton keeps it across iterations and
// increments while PCG needs few iterations, and refreshes it when they grow
// (solvers/implicit/static_newton.hpp). The factor lives on the host: on a device build the
// matrix values cross once per factorization and each application moves one vector each way
// (2 x 8 n bytes over PCIe per PCG iteration, against a factorization that is reused for
// many); the vectors stay where the execution space keeps them.
#include <perishell/solvers/belos/crs_operator.hpp>
#include <perishell/solvers/belos/kokkos_multivector.hpp>
#include <perishell/solvers/direct/sparse_cholesky.hpp>

#include <BelosOperator.hpp>

#include <Kokkos_Core.hpp>

#include <type_traits>

namespace perishell::direct {

template <class ExecutionSpaceT>
class FactorizationPreconditioner final : public Belos::Operator<double> {
 public:
  using memory_space = typename ExecutionSpaceT::memory_space;
  using matrix_type = belos::CrsMatrix<ExecutionSpaceT>;

  // Takes A's pattern (analysis and fill-reducing ordering once); factorize() before use.
  explicit FactorizationPreconditioner(const matrix_type& A)
      : values_(Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::direct::hostValues"), A.nnz()),
        work_(Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::direct::hostVector"), A.numRows()) {
    const auto rowMap = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, A.graph.row_map);
    const auto columns = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, A.graph.entries);
    cholesky_.setPattern(A.numRows(), rowMap.data(), columns.data());
  }

  // Factors A (same pattern as at construction). Throws FactorizationError.
  FactorizationInfo factorize(const matrix_type& A) {
    Kokkos::deep_copy(values_, A.values);
    return cholesky_.factorize(values_.data());
  }

  void Apply(const Belos::MultiVec<double>& x, Belos::MultiVec<double>& y,
             Belos::ETrans /*trans: the factor is symmetric*/ = Belos::NOTRANS) const override {
    constexpr const char* who = "perishell::direct::FactorizationPreconditioner::Apply";
    const auto& xk = belos::detail::asKokkos<ExecutionSpaceT>(x, who);
    auto& yk = belos::detail::asKokkos<ExecutionSpaceT>(y, who);
    const auto n = work_.extent(0);
    belos::detail::checkApplyShapes(xk, yk, n, n, who);
    for (std::size_t j = 0; j < xk.view().extent(1); ++j) {
      const auto xj = Kokkos::subview(xk.view(), Kokkos::ALL(), j);
      const auto yj = Kokkos::subview(yk.view(), Kokkos::ALL(), j);
      if constexpr (Kokkos::SpaceAccessibility<Kokkos::HostSpace, memory_space>::accessible) {
        ExecutionSpaceT().fence();  // x may still be written by a kernel
        cholesky_.solve(xj.data(), yj.data());
      } else {
        Kokkos::deep_copy(work_, xj);
        cholesky_.solve(work_.data(), work_.data());
        Kokkos::deep_copy(yj, work_);
      }
    }
  }

  bool HasApplyTranspose() const override { return true; }

 private:
  SparseCholesky cholesky_;
  Kokkos::View<double*, Kokkos::HostSpace> values_;
  Kokkos::View<double*, Kokkos::HostSpace> work_;
};

}  // namespace perishell::direct
