// The sparse Cholesky factorization (solvers/direct) against closed forms: the 5-point
// Laplacian's eigenvalues 4 - 2 cos(j pi/(m+1)) - 2 cos(k pi/(m+1)) give the inertia of the
// shifted matrix, so the count of negative L D L^T pivots is known exactly (Sylvester's law
// of inertia); solves against A x = b; the factor of a non-symmetric matrix is that of its
// symmetric part; a singular matrix and a non-symmetric pattern are refused; and as a Belos
// preconditioner on the backend (on a GPU factored on the device when asked, and on the host
// where the matrix is indefinite), PCG converges in one iteration on a fresh factor.
#include <perishell/solvers/belos/cg_solve.hpp>
#include <perishell/solvers/direct/factorization_preconditioner.hpp>

#include <cmath>
#include <map>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace perishell_test_sparse_cholesky {

using perishell::LocalIndex;
using perishell::RowOffset;

struct HostCrs {
  std::vector<RowOffset> rowMap;
  std::vector<LocalIndex> columns;
  std::vector<double> values;
  LocalIndex numRows() const { return LocalIndex(rowMap.size()) - 1; }
};

HostCrs toCrs(const std::vector<std::map<LocalIndex, double>>& rows) {
  HostCrs crs;
  crs.rowMap.push_back(0);
  for (const auto& row : rows) {
    for (const auto& [column, value] : row) {
      crs.columns.push_back(column);
      crs.values.push_back(value);
    }
    crs.rowMap.push_back(crs.columns.size());
  }
  return crs;
}

// 5-point Laplacian on the m x m interior nodes, diagonal 4 - shift; skew adds +skew above
// and -skew below the diagonal on the x-neighbours (a non-symmetric part, pattern unchanged).
HostCrs shiftedLaplacian(int m, double shift, double skew = 0.0) {
  std::vector<std::map<LocalIndex, double>> rows(std::size_t(m) * m);
  for (int j = 0; j < m; ++j)
    for (int i = 0; i < m; ++i) {
      const LocalIndex row = j * m + i;
      rows[row][row] = 4.0 - shift;
      if (i > 0) rows[row][row - 1] = -1.0 - skew;
      if (i < m - 1) rows[row][row + 1] = -1.0 + skew;
      if (j > 0) rows[row][row - m] = -1.0;
      if (j < m - 1) rows[row][row + m] = -1.0;
    }
  return toCrs(rows);
}

// Eigenvalues of the m x m Laplacian below shift.
long eigenvaluesBelow(int m, double shift) {
  const double pi = 3.14159265358979323846;
  long count = 0;
  for (int j = 1; j <= m; ++j)
    for (int k = 1; k <= m; ++k)
      if (4.0 - 2.0 * std::cos(j * pi / (m + 1)) - 2.0 * std::cos(k * pi / (m + 1)) < shift) ++count;
  return count;
}

std::vector<double> multiply(const HostCrs& A, const std::vector<double>& x) {
  std::vector<double> y(A.numRows(), 0.0);
  for (LocalIndex row = 0; row < A.numRows(); ++row)
    for (RowOffset k = A.rowMap[row]; k < A.rowMap[row + 1]; ++k) y[row] += A.values[k] * x[A.columns[k]];
  return y;
}

std::vector<double> testVector(LocalIndex n) {
  std::vector<double> x(n);
  for (LocalIndex i = 0; i < n; ++i) x[i] = std::sin(0.37 * i) + 0.1 * i / n;
  return x;
}

double relativeDifference(const std::vector<double>& a, const std::vector<double>& b) {
  double difference = 0.0, norm = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    difference += (a[i] - b[i]) * (a[i] - b[i]);
    norm += b[i] * b[i];
  }
  return std::sqrt(difference / norm);
}

// Factors A and solves A x = A x_exact; returns the relative error of x.
double solveError(perishell::direct::SparseCholesky& cholesky, const HostCrs& A,
                  perishell::direct::FactorizationInfo& info) {
  cholesky.setPattern(A.numRows(), A.rowMap.data(), A.columns.data());
  info = cholesky.factorize(A.values.data());
  const auto exact = testVector(A.numRows());
  std::vector<double> x = multiply(A, exact);
  cholesky.solve(x.data(), x.data());
  return relativeDifference(x, exact);
}

template <class ExecutionSpaceT>
perishell::belos::CrsMatrix<ExecutionSpaceT> onBackend(const HostCrs& A) {
  using Memory = typename ExecutionSpaceT::memory_space;
  Kokkos::View<RowOffset*, Memory> rowMap("rowMap", A.rowMap.size());
  Kokkos::View<LocalIndex*, Memory> columns("columns", A.columns.size());
  perishell::VectorView<Memory> values("values", A.values.size());
  Kokkos::deep_copy(rowMap, Kokkos::View<const RowOffset*, Kokkos::HostSpace>(A.rowMap.data(), A.rowMap.size()));
  Kokkos::deep_copy(columns,
                    Kokkos::View<const LocalIndex*, Kokkos::HostSpace>(A.columns.data(), A.columns.size()));
  Kokkos::deep_copy(values, Kokkos::View<const double*, Kokkos::HostSpace>(A.values.data(), A.values.size()));
  return perishell::belos::CrsMatrix<ExecutionSpaceT>("A", A.numRows(), A.numRows(), RowOffset(A.values.size()),
                                                      values, rowMap, columns);
}

}  // namespace perishell_test_sparse_cholesky

TEST(TEST_CATEGORY, sparse_cholesky_solves_a_positive_definite_laplacian) {
  using namespace perishell_test_sparse_cholesky;
  perishell::direct::SparseCholesky cholesky;
  perishell::direct::FactorizationInfo info;
  const double error = solveError(cholesky, shiftedLaplacian(30, 0.0), info);
  EXPECT_TRUE(info.positiveDefinite);
  EXPECT_EQ(info.negativePivots, 0);
  EXPECT_GT(info.factorEntries, 900.0);  // at least the diagonal of L
  EXPECT_LT(error, 1e-12);
}

TEST(TEST_CATEGORY, sparse_cholesky_counts_the_negative_eigenvalues_of_an_indefinite_matrix) {
  using namespace perishell_test_sparse_cholesky;
  perishell::direct::SparseCholesky cholesky;
  // Shifts between eigenvalues (none within 1e-3 of one for m = 30).
  for (const double shift : {0.5, 1.3, 3.1}) {
    perishell::direct::FactorizationInfo info;
    const double error = solveError(cholesky, shiftedLaplacian(30, shift), info);
    const long expected = eigenvaluesBelow(30, shift);
    ASSERT_GT(expected, 0);
    EXPECT_FALSE(info.positiveDefinite) << "shift " << shift;
    EXPECT_EQ(info.negativePivots, expected) << "shift " << shift;
    EXPECT_LT(error, 1e-9) << "shift " << shift;
  }
  // The same object factors a positive definite matrix again with L L^T.
  perishell::direct::FactorizationInfo info;
  EXPECT_LT(solveError(cholesky, shiftedLaplacian(30, 0.0), info), 1e-12);
  EXPECT_TRUE(info.positiveDefinite);
}

TEST(TEST_CATEGORY, sparse_cholesky_factors_the_symmetric_part_of_a_non_symmetric_matrix) {
  using namespace perishell_test_sparse_cholesky;
  const HostCrs nonSymmetric = shiftedLaplacian(12, 0.0, 0.3);
  const HostCrs symmetricPart = shiftedLaplacian(12, 0.0);
  perishell::direct::SparseCholesky cholesky;
  cholesky.setPattern(nonSymmetric.numRows(), nonSymmetric.rowMap.data(), nonSymmetric.columns.data());
  cholesky.factorize(nonSymmetric.values.data());
  const auto exact = testVector(symmetricPart.numRows());
  std::vector<double> x = multiply(symmetricPart, exact);
  cholesky.solve(x.data(), x.data());
  EXPECT_LT(relativeDifference(x, exact), 1e-12);
}

TEST(TEST_CATEGORY, sparse_cholesky_refuses_singular_matrices_and_unsymmetric_patterns) {
  using namespace perishell_test_sparse_cholesky;
  perishell::direct::SparseCholesky cholesky;
  // A row and column of zeros (a DOF nothing holds: a mechanism).
  std::vector<std::map<LocalIndex, double>> rows = {{{0, 2.0}, {1, -1.0}}, {{0, -1.0}, {1, 2.0}}, {{2, 0.0}}};
  const HostCrs singular = toCrs(rows);
  cholesky.setPattern(3, singular.rowMap.data(), singular.columns.data());
  EXPECT_THROW(cholesky.factorize(singular.values.data()), perishell::direct::FactorizationError);
  EXPECT_FALSE(cholesky.hasFactor());

  rows = {{{0, 2.0}, {1, -1.0}}, {{1, 2.0}}};  // (0, 1) without (1, 0)
  const HostCrs unsymmetric = toCrs(rows);
  try {
    cholesky.setPattern(2, unsymmetric.rowMap.data(), unsymmetric.columns.data());
    FAIL() << "an unsymmetric pattern was accepted";
  } catch (const std::invalid_argument& error) {
    EXPECT_NE(std::string(error.what()).find("not symmetric"), std::string::npos) << error.what();
  }
}

// Where the factor lives: on the GPU the device factorization when asked for, else the host's.
template <class ExecutionSpaceT>
bool factorOnDevice(bool asked) {
#if defined(KOKKOS_ENABLE_CUDA)
  return asked && std::is_same_v<ExecutionSpaceT, Kokkos::Cuda>;
#else
  (void)asked;
  return false;
#endif
}

TEST(TEST_CATEGORY, factorization_preconditioned_cg_converges_in_one_iteration) {
  using namespace perishell_test_sparse_cholesky;
  using Memory = TEST_EXECSPACE::memory_space;
  // SPD, condition ~ 800.
  const HostCrs host = shiftedLaplacian(40, -0.01);
  const auto A = onBackend<TEST_EXECSPACE>(host);
  for (const bool onDevice : {false, true}) {
    perishell::direct::FactorizationPreconditioner<TEST_EXECSPACE> factor(A, onDevice);
    const auto info = factor.factorize(A);
    EXPECT_TRUE(info.positiveDefinite);
    EXPECT_EQ(factor.factoredOnDevice(), factorOnDevice<TEST_EXECSPACE>(onDevice));

    const auto exact = testVector(host.numRows());
    const auto rhs = multiply(host, exact);
    perishell::VectorView<Memory> b("b", rhs.size()), x("x", rhs.size());
    Kokkos::deep_copy(b, Kokkos::View<const double*, Kokkos::HostSpace>(rhs.data(), rhs.size()));
    perishell::belos::CgOptions options;
    options.tolerance = 1e-12;
    options.maxIterations = 50;
    const auto result =
        perishell::belos::solveCg<TEST_EXECSPACE>(A, b, x, options, Teuchos::rcp(&factor, false));
    EXPECT_TRUE(result.converged) << "onDevice " << onDevice;
    EXPECT_LE(result.iterations, 2) << "onDevice " << onDevice;
    const auto xHost = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, x);
    EXPECT_LT(relativeDifference(std::vector<double>(xHost.data(), xHost.data() + xHost.extent(0)), exact), 1e-10)
        << "onDevice " << onDevice;
  }
}

// The device factorization (L L^T only) leaves an indefinite matrix to the host's L D L^T,
// which counts its negative eigenvalues; the next positive definite matrix goes back to the
// device. A non-symmetric matrix is factored by its symmetric part on either side.
TEST(TEST_CATEGORY, factorization_preconditioner_factors_indefinite_and_non_symmetric_matrices) {
  using namespace perishell_test_sparse_cholesky;
  const int m = 30;
  const double shift = 1.3;
  const auto indefinite = onBackend<TEST_EXECSPACE>(shiftedLaplacian(m, shift));
  const auto definite = onBackend<TEST_EXECSPACE>(shiftedLaplacian(m, 0.0, 0.3));
  const HostCrs symmetricPart = shiftedLaplacian(m, 0.0);
  for (const bool onDevice : {false, true}) {
    perishell::direct::FactorizationPreconditioner<TEST_EXECSPACE> factor(indefinite, onDevice);
    const auto info = factor.factorize(indefinite);
    EXPECT_FALSE(info.positiveDefinite);
    EXPECT_EQ(info.negativePivots, eigenvaluesBelow(m, shift)) << "onDevice " << onDevice;
    EXPECT_FALSE(factor.factoredOnDevice());

    EXPECT_TRUE(factor.factorize(definite).positiveDefinite);
    EXPECT_EQ(factor.factoredOnDevice(), factorOnDevice<TEST_EXECSPACE>(onDevice));
    // One application of the factor solves the symmetric part exactly.
    const auto exact = testVector(symmetricPart.numRows());
    const auto rhs = multiply(symmetricPart, exact);
    perishell::belos::KokkosMultiVector<TEST_EXECSPACE> b("b", std::ptrdiff_t(rhs.size()), 1),
        x("x", std::ptrdiff_t(rhs.size()), 1);
    Kokkos::deep_copy(Kokkos::subview(b.view(), Kokkos::ALL(), 0),
                      Kokkos::View<const double*, Kokkos::HostSpace>(rhs.data(), rhs.size()));
    factor.Apply(b, x);
    const auto xHost = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, x.view());
    std::vector<double> solution(rhs.size());
    for (std::size_t i = 0; i < solution.size(); ++i) solution[i] = xHost(i, 0);
    EXPECT_LT(relativeDifference(solution, exact), 1e-12) << "onDevice " << onDevice;
  }
}
