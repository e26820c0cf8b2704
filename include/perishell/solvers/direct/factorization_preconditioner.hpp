#pragma once
// M = (L L^T)^{-1} of a recent tangent as a Belos preconditioner (direct/sparse_cholesky.hpp).
// Exact when fresh (PCG converges in one iteration); Newton keeps it across iterations and
// increments while PCG needs few iterations, and refreshes it when they grow
// (solvers/implicit/static_newton.hpp).
//
// On a device build the factor lives where `onDevice` says (solver.factorization):
// - on the device (direct/device_cholesky.hpp): nothing crosses PCIe; a tangent that is not
//   positive definite is factored on the host instead (L D L^T, its inertia), and that
//   factor serves until the next factorization;
// - on the host: the matrix values cross once per factorization and each application moves
//   one vector each way (2 x 8 n bytes per PCG iteration).
// The vectors stay where the execution space keeps them.
#include <perishell/solvers/belos/crs_operator.hpp>
#include <perishell/solvers/belos/kokkos_multivector.hpp>
#include <perishell/solvers/direct/device_cholesky.hpp>
#include <perishell/solvers/direct/sparse_cholesky.hpp>

#include <BelosOperator.hpp>

#include <Kokkos_Core.hpp>

#include <memory>
#include <type_traits>

namespace perishell::direct {

template <class ExecutionSpaceT>
class FactorizationPreconditioner final : public Belos::Operator<double> {
 public:
  using memory_space = typename ExecutionSpaceT::memory_space;
  using matrix_type = belos::CrsMatrix<ExecutionSpaceT>;

  // Takes A's pattern (analysis and fill-reducing ordering once); factorize() before use.
  // onDevice: factor on the GPU where the execution space has one (ignored on host spaces).
  FactorizationPreconditioner(const matrix_type& A, bool onDevice)
      : values_(Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::direct::hostValues"), A.nnz()),
        work_(Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::direct::hostVector"), A.numRows()) {
    const auto rowMap = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, A.graph.row_map);
    const auto columns = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, A.graph.entries);
    cholesky_.setPattern(A.numRows(), rowMap.data(), columns.data());
#if defined(KOKKOS_ENABLE_CUDA)
    if constexpr (std::is_same_v<ExecutionSpaceT, Kokkos::Cuda>) {
      if (onDevice) {
        device_ = std::make_unique<DeviceCholesky>();
        device_->setPattern(A.numRows(), rowMap.data(), columns.data(), cholesky_.fillReducingOrdering());
      }
    }
#endif
    (void)onDevice;
  }

  // Factors A (same pattern as at construction). Throws FactorizationError.
  FactorizationInfo factorize(const matrix_type& A) {
#if defined(KOKKOS_ENABLE_CUDA)
    useDevice_ = false;
    if (device_) {
      if (const auto info = device_->factorize(A.values.data())) {
        useDevice_ = true;
        return *info;
      }
    }
#endif
    Kokkos::deep_copy(values_, A.values);
    return cholesky_.factorize(values_.data());
  }

  // Whether the last factor is the device's (false: the host's, also where onDevice asked for
  // the device and the matrix was not positive definite).
  bool factoredOnDevice() const {
#if defined(KOKKOS_ENABLE_CUDA)
    return useDevice_;
#else
    return false;
#endif
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
      if (factoredOnDevice()) {
#if defined(KOKKOS_ENABLE_CUDA)
        device_->solve(xj.data(), yj.data());
#endif
      } else if constexpr (Kokkos::SpaceAccessibility<Kokkos::HostSpace, memory_space>::accessible) {
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
#if defined(KOKKOS_ENABLE_CUDA)
  std::unique_ptr<DeviceCholesky> device_;
  bool useDevice_ = false;
#endif
};

}  // namespace perishell::direct
