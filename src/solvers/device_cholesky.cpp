#include <perishell/solvers/direct/device_cholesky.hpp>

// csrchol is deprecated in CUDA 13 in favour of cuDSS, which the toolkit does not ship.
#define DISABLE_CUSOLVER_DEPRECATED
#include <cusolverSp.h>
#include <cusolverSp_LOWLEVEL_PREVIEW.h>
#include <cusparse.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>

namespace perishell::direct {

namespace {

using Exec = Kokkos::Cuda;
using Memory = Kokkos::CudaSpace;

std::string statusName(cusolverStatus_t status) {
  switch (status) {
    case CUSOLVER_STATUS_ALLOC_FAILED: return "out of device memory";
    case CUSOLVER_STATUS_INVALID_VALUE: return "an invalid value";
    case CUSOLVER_STATUS_ARCH_MISMATCH: return "an unsupported GPU";
    case CUSOLVER_STATUS_EXECUTION_FAILED: return "a failed kernel launch";
    case CUSOLVER_STATUS_INTERNAL_ERROR: return "an internal error";
    default: return "status " + std::to_string(static_cast<int>(status));
  }
}

void check(cusolverStatus_t status, const char* step) {
  if (status == CUSOLVER_STATUS_SUCCESS) return;
  throw FactorizationError(
      status == CUSOLVER_STATUS_ALLOC_FAILED ? FactorizationError::Kind::Resources : FactorizationError::Kind::Input,
      std::string("the device factorization failed in ") + step + " (cuSOLVER: " + statusName(status) + ")");
}

// Device views, an allocation failure reported as the factorization's resources.
template <class T>
Kokkos::View<T*, Memory> deviceArray(const char* label, std::size_t n) {
  try {
    return Kokkos::View<T*, Memory>(Kokkos::view_alloc(Kokkos::WithoutInitializing, std::string(label)), n);
  } catch (const std::runtime_error& error) {
    throw FactorizationError(FactorizationError::Kind::Resources,
                             std::string("the device cannot hold the factorization's ") + label + " (" +
                                 std::to_string(n * sizeof(T) / 1048576) + " MiB): " + error.what());
  }
}

}  // namespace

struct DeviceCholesky::Impl {
  cusolverSpHandle_t handle = nullptr;
  cusparseMatDescr_t descriptor = nullptr;
  csrcholInfo_t info = nullptr;
  int n = 0;
  int nnz = 0;
  // B = P (A + A^T)/2 P^T in CRS, both triangles; per entry the slots of A averaged into it.
  Kokkos::View<int*, Memory> rowMap, columns;
  Kokkos::View<RowOffset*, Memory> slot, transposeSlot;
  Kokkos::View<double*, Memory> values;
  Kokkos::View<LocalIndex*, Memory> ordering;  // row of A eliminated k-th
  Kokkos::View<char*, Memory> buffer;
  mutable Kokkos::View<double*, Memory> permutedB, permutedX;
  double internalBytes = 0.0;
  bool factored = false;

  Impl() {
    check(cusolverSpCreate(&handle), "cusolverSpCreate");
    check(cusolverSpSetStream(handle, Exec().cuda_stream()), "cusolverSpSetStream");
    if (cusparseCreateMatDescr(&descriptor) != CUSPARSE_STATUS_SUCCESS)
      throw FactorizationError(FactorizationError::Kind::Resources, "cannot create a cuSPARSE matrix descriptor");
    cusparseSetMatType(descriptor, CUSPARSE_MATRIX_TYPE_GENERAL);
    cusparseSetMatIndexBase(descriptor, CUSPARSE_INDEX_BASE_ZERO);
  }
  ~Impl() {
    if (info != nullptr) cusolverSpDestroyCsrcholInfo(info);
    if (descriptor != nullptr) cusparseDestroyMatDescr(descriptor);
    if (handle != nullptr) cusolverSpDestroy(handle);
  }
};

DeviceCholesky::DeviceCholesky() : impl_(std::make_unique<Impl>()) {}
DeviceCholesky::~DeviceCholesky() = default;

void DeviceCholesky::setPattern(LocalIndex n, const RowOffset* rowMap, const LocalIndex* columns,
                                const std::vector<LocalIndex>& ordering) {
  auto& m = *impl_;
  m.factored = false;
  if (rowMap[n] > RowOffset(std::numeric_limits<int>::max()))
    throw FactorizationError(FactorizationError::Kind::Resources,
                             "the matrix has " + std::to_string(rowMap[n]) +
                                 " entries, more than cuSOLVER's 32-bit indices address");
  std::vector<LocalIndex> position(n);  // where row i of A is eliminated
  for (LocalIndex k = 0; k < n; ++k) position[ordering[k]] = k;
  auto find = [&](LocalIndex i, LocalIndex j) {
    return rowMap[i] + RowOffset(std::lower_bound(columns + rowMap[i], columns + rowMap[i + 1], j) - (columns + rowMap[i]));
  };
  // Row k of B is row ordering[k] of A with its columns renumbered and sorted.
  std::vector<int> hostRowMap(std::size_t(n) + 1, 0);
  std::vector<int> hostColumns(rowMap[n]);
  std::vector<RowOffset> hostSlot(rowMap[n]), hostTransposeSlot(rowMap[n]);
  std::vector<std::pair<int, RowOffset>> row;
  for (LocalIndex k = 0; k < n; ++k) {
    const LocalIndex i = ordering[k];
    row.clear();
    for (RowOffset s = rowMap[i]; s < rowMap[i + 1]; ++s) row.emplace_back(position[columns[s]], s);
    std::sort(row.begin(), row.end());
    int at = hostRowMap[k];
    for (const auto& [column, s] : row) {
      hostColumns[at] = column;
      hostSlot[at] = s;
      hostTransposeSlot[at] = find(columns[s], i);
      ++at;
    }
    hostRowMap[k + 1] = at;
  }
  m.n = n;
  m.nnz = static_cast<int>(rowMap[n]);
  m.rowMap = deviceArray<int>("perishell::direct::DeviceCholesky::rowMap", hostRowMap.size());
  m.columns = deviceArray<int>("perishell::direct::DeviceCholesky::columns", hostColumns.size());
  m.slot = deviceArray<RowOffset>("perishell::direct::DeviceCholesky::slot", hostSlot.size());
  m.transposeSlot = deviceArray<RowOffset>("perishell::direct::DeviceCholesky::transposeSlot", hostSlot.size());
  m.values = deviceArray<double>("perishell::direct::DeviceCholesky::values", hostSlot.size());
  m.ordering = deviceArray<LocalIndex>("perishell::direct::DeviceCholesky::ordering", std::size_t(n));
  m.permutedB = deviceArray<double>("perishell::direct::DeviceCholesky::permutedB", std::size_t(n));
  m.permutedX = deviceArray<double>("perishell::direct::DeviceCholesky::permutedX", std::size_t(n));
  using Unmanaged = Kokkos::MemoryTraits<Kokkos::Unmanaged>;
  Kokkos::deep_copy(m.rowMap, Kokkos::View<const int*, Kokkos::HostSpace, Unmanaged>(hostRowMap.data(), hostRowMap.size()));
  Kokkos::deep_copy(m.columns, Kokkos::View<const int*, Kokkos::HostSpace, Unmanaged>(hostColumns.data(), hostColumns.size()));
  Kokkos::deep_copy(m.slot, Kokkos::View<const RowOffset*, Kokkos::HostSpace, Unmanaged>(hostSlot.data(), hostSlot.size()));
  Kokkos::deep_copy(m.transposeSlot,
                    Kokkos::View<const RowOffset*, Kokkos::HostSpace, Unmanaged>(hostTransposeSlot.data(), hostSlot.size()));
  Kokkos::deep_copy(m.ordering, Kokkos::View<const LocalIndex*, Kokkos::HostSpace, Unmanaged>(ordering.data(), ordering.size()));

  if (m.info != nullptr) cusolverSpDestroyCsrcholInfo(m.info);
  m.info = nullptr;
  check(cusolverSpCreateCsrcholInfo(&m.info), "cusolverSpCreateCsrcholInfo");
  check(cusolverSpXcsrcholAnalysis(m.handle, m.n, m.nnz, m.descriptor, m.rowMap.data(), m.columns.data(), m.info),
        "the symbolic analysis");
  std::size_t internalBytes = 0, workBytes = 0;
  check(cusolverSpDcsrcholBufferInfo(m.handle, m.n, m.nnz, m.descriptor, m.values.data(), m.rowMap.data(),
                                     m.columns.data(), m.info, &internalBytes, &workBytes),
        "sizing its workspace");
  m.internalBytes = double(internalBytes);
  m.buffer = deviceArray<char>("perishell::direct::DeviceCholesky::workspace", std::max<std::size_t>(workBytes, 1));
}

std::optional<FactorizationInfo> DeviceCholesky::factorize(const double* deviceValues) {
  auto& m = *impl_;
  if (m.info == nullptr) throw std::logic_error("perishell::direct::DeviceCholesky: factorize before setPattern");
  const auto start = std::chrono::steady_clock::now();
  m.factored = false;
  {
    const auto values = m.values;
    const auto slot = m.slot;
    const auto transposeSlot = m.transposeSlot;
    Kokkos::parallel_for(
        "perishell::direct::DeviceCholesky::symmetricPart", Kokkos::RangePolicy<Exec>(0, values.extent(0)),
        KOKKOS_LAMBDA(const std::size_t k) { values(k) = 0.5 * (deviceValues[slot(k)] + deviceValues[transposeSlot(k)]); });
  }
  // Any failure but memory leaves the matrix to the host factorization, which says what is wrong.
  const cusolverStatus_t factored = cusolverSpDcsrcholFactor(m.handle, m.n, m.nnz, m.descriptor, m.values.data(),
                                                             m.rowMap.data(), m.columns.data(), m.info, m.buffer.data());
  if (factored == CUSOLVER_STATUS_ALLOC_FAILED) check(factored, "the numeric factorization");
  if (factored != CUSOLVER_STATUS_SUCCESS) return std::nullopt;
  int zeroPivot = -1;
  check(cusolverSpDcsrcholZeroPivot(m.handle, m.info, 0.0, &zeroPivot), "its pivot check");
  if (zeroPivot >= 0) return std::nullopt;
  // A negative pivot leaves a non-finite factor (csrchol takes its square root): a solve with a
  // probe vector shows it, where 1^T (L L^T)^{-1} 1 > 0 for any finite factor.
  m.factored = true;
  Kokkos::deep_copy(m.permutedB, 1.0);
  check(cusolverSpDcsrcholSolve(m.handle, m.n, m.permutedB.data(), m.permutedX.data(), m.info, m.buffer.data()),
        "the probe solve");
  double probe = 0.0;
  const auto x = m.permutedX;
  Kokkos::parallel_reduce(
      "perishell::direct::DeviceCholesky::probe", Kokkos::RangePolicy<Exec>(0, x.extent(0)),
      KOKKOS_LAMBDA(const int i, double& sum) { sum += x(i); }, probe);
  if (!std::isfinite(probe) || probe <= 0.0) {
    m.factored = false;
    return std::nullopt;
  }
  FactorizationInfo info;
  info.positiveDefinite = true;
  info.negativePivots = 0;
  info.smallestPivotRatio = std::numeric_limits<double>::quiet_NaN();  // csrchol does not expose its pivots
  info.factorEntries = m.internalBytes / sizeof(double);                 // its storage, an upper bound on L's entries
  info.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return info;
}

void DeviceCholesky::solve(const double* deviceB, double* deviceX) const {
  auto& m = *impl_;
  if (!m.factored) throw std::logic_error("perishell::direct::DeviceCholesky: solve without a factor");
  const auto ordering = m.ordering;
  const auto b = m.permutedB;
  const auto x = m.permutedX;
  Kokkos::parallel_for(
      "perishell::direct::DeviceCholesky::permute", Kokkos::RangePolicy<Exec>(0, m.n),
      KOKKOS_LAMBDA(const int k) { b(k) = deviceB[ordering(k)]; });
  check(cusolverSpDcsrcholSolve(m.handle, m.n, b.data(), x.data(), m.info, m.buffer.data()), "the triangular solves");
  Kokkos::parallel_for(
      "perishell::direct::DeviceCholesky::unpermute", Kokkos::RangePolicy<Exec>(0, m.n),
      KOKKOS_LAMBDA(const int k) { deviceX[ordering(k)] = x(k); });
}

}  // namespace perishell::direct
