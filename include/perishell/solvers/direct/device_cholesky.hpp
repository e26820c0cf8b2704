#pragma once
// Sparse Cholesky L L^T of a tangent stiffness on the GPU, through cuSOLVER's low-level
// csrchol (CUDA toolkit, cusolverSp_LOWLEVEL_PREVIEW.h): symbolic analysis once per pattern,
// numeric factorization and triangular solves on the device, so a factorization-
// preconditioned Krylov iteration moves no vector over PCIe. As the host factorization
// (direct/sparse_cholesky.hpp), it factors the symmetric part (A + A^T) / 2, here permuted by
// a fill-reducing ordering computed once on the host (CHOLMOD's).
//
// csrchol has no L D L^T: a matrix that is not positive definite is reported as such, and
// the caller factors it on the host, which gives its inertia (a limit point) or names the
// singular row (a mechanism). cuSOLVER itself stays out of this header (pimpl).
#include <perishell/core/types.hpp>
#include <perishell/solvers/direct/sparse_cholesky.hpp>

#include <Kokkos_Core.hpp>

#include <memory>
#include <optional>
#include <vector>

#if defined(KOKKOS_ENABLE_CUDA)

namespace perishell::direct {

class DeviceCholesky {
 public:
  DeviceCholesky();
  ~DeviceCholesky();
  DeviceCholesky(const DeviceCholesky&) = delete;
  DeviceCholesky& operator=(const DeviceCholesky&) = delete;

  // The pattern of an n x n CRS matrix (host arrays, as SparseCholesky::setPattern) and the
  // elimination order (ordering[k]: the row eliminated k-th). Throws FactorizationError
  // (Resources) when cuSOLVER's 32-bit indices or the device memory cannot hold it.
  void setPattern(LocalIndex n, const RowOffset* rowMap, const LocalIndex* columns,
                  const std::vector<LocalIndex>& ordering);

  // Factors (A + A^T) / 2, A's values in device memory in the pattern's CRS order. Returns no
  // info (and keeps no factor) when the matrix is not numerically positive definite; throws
  // FactorizationError when the device cannot hold the factor.
  std::optional<FactorizationInfo> factorize(const double* deviceValues);

  // x = (L L^T)^{-1} b on the device; b and x hold n entries each and may alias.
  void solve(const double* deviceB, double* deviceX) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace perishell::direct

#endif
