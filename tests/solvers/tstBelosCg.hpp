// Belos CG on Kokkos: the MultiVec adapter against hand-computed values, CG on a device-
// assembled 2D Laplacian (plain and badly scaled), the nodal block-Jacobi preconditioner on
// host-built 6-DOF-per-node systems, the GMRES fallback on an indefinite matrix, and the
// failure paths (zero diagonal, singular block, indefinite matrix without fallback).
#include <perishell/solvers/belos/block_jacobi.hpp>
#include <perishell/solvers/belos/cg_solve.hpp>
#include <perishell/solvers/belos/crs_operator.hpp>
#include <perishell/solvers/belos/kokkos_multivector.hpp>

#include <KokkosBlas1_axpby.hpp>
#include <KokkosBlas1_nrm2.hpp>
#include <KokkosBlas1_scal.hpp>
#include <KokkosSparse_spmv.hpp>
#include <Teuchos_RCP.hpp>
#include <Teuchos_SerialDenseMatrix.hpp>

#include <array>
#include <cmath>
#include <iostream>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

// Device code sits in free functions of a named namespace: nvcc rejects KOKKOS_LAMBDA inside
// a TEST body, which gtest makes a private member function.
namespace perishell_test_belos_cg {

using perishell::LocalIndex;
using perishell::RowOffset;

template <class ExecutionSpaceT>
using MultiVector = perishell::belos::KokkosMultiVector<ExecutionSpaceT>;
template <class ExecutionSpaceT>
using Matrix = perishell::belos::CrsMatrix<ExecutionSpaceT>;
template <class ExecutionSpaceT>
using Vector = perishell::VectorView<typename ExecutionSpaceT::memory_space>;

// Host values (row-major literal, rows x cols) into a new device multivector.
template <class ExecutionSpaceT>
std::unique_ptr<MultiVector<ExecutionSpaceT>> makeMultiVector(int rows, int cols, const std::vector<double>& rowMajor) {
  auto mv = std::make_unique<MultiVector<ExecutionSpaceT>>("test_mv", rows, cols);
  auto host = Kokkos::create_mirror_view(mv->view());
  for (int i = 0; i < rows; ++i)
    for (int j = 0; j < cols; ++j) host(i, j) = rowMajor.at(static_cast<std::size_t>(i * cols + j));
  Kokkos::deep_copy(mv->view(), host);
  return mv;
}

template <class ExecutionSpaceT>
auto onHost(const Belos::MultiVec<double>& mv) {
  const auto& kokkos = dynamic_cast<const MultiVector<ExecutionSpaceT>&>(mv);
  return Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), kokkos.view());
}

template <class HostView>
void expectColumn(const HostView& host, int col, const std::vector<double>& expected, const char* what) {
  for (std::size_t i = 0; i < expected.size(); ++i)
    EXPECT_DOUBLE_EQ(host(i, col), expected[i]) << what << ": row " << i << ", column " << col;
}

// 5-point Laplacian on the n x n interior nodes of a grid with Dirichlet boundary, scaled
// symmetrically as D A D with d = scale; `diagonal` other than 4 shifts the spectrum.
// Assembled entirely on the device.
template <class ExecutionSpaceT>
Matrix<ExecutionSpaceT> assembleScaledLaplacian(int n, const Vector<ExecutionSpaceT>& scale, double diagonal = 4.0) {
  using memory_space = typename ExecutionSpaceT::memory_space;
  using policy = Kokkos::RangePolicy<ExecutionSpaceT>;
  const LocalIndex numRows = n * n;
  Kokkos::View<RowOffset*, memory_space> rowMap("laplacian_row_map", numRows + 1);
  Kokkos::parallel_for(
      "count", policy(0, numRows), KOKKOS_LAMBDA(const LocalIndex row) {
        const int i = row % n, j = row / n;
        rowMap(row + 1) = 1 + (i > 0) + (i < n - 1) + (j > 0) + (j < n - 1);
      });
  Kokkos::parallel_scan(
      "offsets", policy(0, numRows + 1), KOKKOS_LAMBDA(const LocalIndex row, RowOffset& partial, const bool final) {
        partial += rowMap(row);
        if (final) rowMap(row) = partial;
      });
  RowOffset nnz = 0;
  Kokkos::deep_copy(nnz, Kokkos::subview(rowMap, numRows));
  Kokkos::View<LocalIndex*, memory_space> entries("laplacian_entries", nnz);
  Kokkos::View<double*, memory_space> values("laplacian_values", nnz);
  Kokkos::parallel_for(
      "fill", policy(0, numRows), KOKKOS_LAMBDA(const LocalIndex row) {
        const int i = row % n, j = row / n;
        RowOffset k = rowMap(row);
        const auto put = [&](LocalIndex col, double a) {
          entries(k) = col;
          values(k) = scale(row) * a * scale(col);
          ++k;
        };
        if (j > 0) put(row - n, -1.0);
        if (i > 0) put(row - 1, -1.0);
        put(row, diagonal);
        if (i < n - 1) put(row + 1, -1.0);
        if (j < n - 1) put(row + n, -1.0);
      });
  return Matrix<ExecutionSpaceT>("laplacian", numRows, numRows, nnz, values, rowMap, entries);
}

template <class ExecutionSpaceT>
Vector<ExecutionSpaceT> ones(LocalIndex size) {
  Vector<ExecutionSpaceT> v("ones", size);
  Kokkos::deep_copy(v, 1.0);
  return v;
}

// d_k = 10^sin(0.7 k): entries spread over two decades, in no order; cond(D A D) grows ~1e4-fold.
template <class ExecutionSpaceT>
Vector<ExecutionSpaceT> badScaling(LocalIndex size) {
  Vector<ExecutionSpaceT> d("bad_scaling", size);
  Kokkos::parallel_for(
      "bad_scaling", Kokkos::RangePolicy<ExecutionSpaceT>(0, size), KOKKOS_LAMBDA(const LocalIndex k) {
        d(k) = Kokkos::Experimental::pow(10.0, Kokkos::Experimental::sin(0.7 * k));
      });
  return d;
}

// A smooth field plus a ramp, divided by d so that it is the solution of the scaled system.
template <class ExecutionSpaceT>
Vector<ExecutionSpaceT> knownSolution(const Vector<ExecutionSpaceT>& scale) {
  Vector<ExecutionSpaceT> x("x_true", scale.extent(0));
  Kokkos::parallel_for(
      "x_true", Kokkos::RangePolicy<ExecutionSpaceT>(0, scale.extent(0)), KOKKOS_LAMBDA(const LocalIndex k) {
        x(k) = (1.0 + 0.5 * Kokkos::Experimental::sin(0.37 * k) + 1e-3 * k) / scale(k);
      });
  return x;
}

template <class ExecutionSpaceT>
Vector<ExecutionSpaceT> multiply(const Matrix<ExecutionSpaceT>& A, const Vector<ExecutionSpaceT>& x) {
  Vector<ExecutionSpaceT> y("A_x", static_cast<std::size_t>(A.numRows()));
  KokkosSparse::spmv("N", 1.0, A, x, 0.0, y);
  return y;
}

template <class VectorT>
double relativeError(const VectorT& x, const VectorT& exact) {
  VectorT e("error", x.extent(0));
  KokkosBlas::update(1.0, x, -1.0, exact, 0.0, e);
  return KokkosBlas::nrm2(e) / KokkosBlas::nrm2(exact);
}

template <class ExecutionSpaceT>
void setDiagonal(const Matrix<ExecutionSpaceT>& A, LocalIndex row, double value) {
  const auto rowMap = A.graph.row_map;
  const auto entries = A.graph.entries;
  const auto values = A.values;
  Kokkos::parallel_for(
      "set_diagonal", Kokkos::RangePolicy<ExecutionSpaceT>(0, 1), KOKKOS_LAMBDA(const int) {
        for (RowOffset k = rowMap(row); k < rowMap(row + 1); ++k)
          if (entries(k) == row) values(k) = value;
      });
}

struct Solve {
  perishell::belos::CgResult result;
  double relativeError;
};

template <class ExecutionSpaceT>
Solve solveFromZero(const Matrix<ExecutionSpaceT>& A, const Vector<ExecutionSpaceT>& exact,
                    const perishell::belos::CgOptions& options) {
  const auto b = multiply(A, exact);
  Vector<ExecutionSpaceT> x("x", exact.extent(0));
  const auto result = perishell::belos::solveCg(A, b, x, options);
  return {result, relativeError(x, exact)};
}

inline perishell::belos::CgOptions cgOptions(perishell::belos::CgOptions::Preconditioner preconditioner,
                                      double tolerance, int maxIterations) {
  perishell::belos::CgOptions options;
  options.preconditioner = preconditioner;
  options.tolerance = tolerance;
  options.maxIterations = maxIterations;
  return options;
}

// ---------------------------------------------------------------- host-built block systems
using Block = std::array<std::array<double, 6>, 6>;
using HostRows = std::vector<std::map<LocalIndex, double>>;  // row -> (column -> value)

// Host rows into a new device CRS matrix (columns sorted, as std::map keeps them).
template <class ExecutionSpaceT>
Matrix<ExecutionSpaceT> matrixOnDevice(const HostRows& rows) {
  using memory_space = typename ExecutionSpaceT::memory_space;
  const auto numRows = static_cast<LocalIndex>(rows.size());
  Kokkos::View<RowOffset*, Kokkos::HostSpace> rowMap("host_row_map", rows.size() + 1);
  for (std::size_t i = 0; i < rows.size(); ++i) rowMap(i + 1) = rowMap(i) + rows[i].size();
  const RowOffset nnz = rowMap(rows.size());
  Kokkos::View<LocalIndex*, Kokkos::HostSpace> entries("host_entries", nnz);
  Kokkos::View<double*, Kokkos::HostSpace> values("host_values", nnz);
  RowOffset k = 0;
  for (const auto& row : rows)
    for (const auto& [column, value] : row) {
      entries(k) = column;
      values(k) = value;
      ++k;
    }
  return Matrix<ExecutionSpaceT>("host_built", numRows, numRows, nnz,
                                 Kokkos::create_mirror_view_and_copy(memory_space(), values),
                                 Kokkos::create_mirror_view_and_copy(memory_space(), rowMap),
                                 Kokkos::create_mirror_view_and_copy(memory_space(), entries));
}

template <class ExecutionSpaceT>
Vector<ExecutionSpaceT> vectorOnDevice(const std::vector<double>& host) {
  Vector<ExecutionSpaceT> v("from_host", host.size());
  const auto mirror = Kokkos::create_mirror_view(v);
  for (std::size_t i = 0; i < host.size(); ++i) mirror(i) = host[i];
  Kokkos::deep_copy(v, mirror);
  return v;
}

template <class VectorT>
std::vector<double> vectorOnHost(const VectorT& v) {
  const auto mirror = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), v);
  return std::vector<double>(mirror.data(), mirror.data() + mirror.extent(0));
}

// rows(rowNode block) += sign * block (columns of colNode); DOF `skippedDof` of any node is
// left out entirely (an untouched DOF: an empty row and column).
inline void addBlock(HostRows& rows, int rowNode, int colNode, const Block& block, double sign, int skippedDof = -1) {
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) {
      const LocalIndex row = 6 * rowNode + i, col = 6 * colNode + j;
      if (row == skippedDof || col == skippedDof) continue;
      rows[row][col] += sign * block[i][j];
    }
}

// A thin-plate-like stiffness scale: translations ~1e6 N/m, rotations ~1e-3 N m/rad.
inline std::array<double, 6> plateScales() {
  const double translation = std::sqrt(1e6), rotation = std::sqrt(1e-3);
  return {translation, translation, translation, rotation, rotation, rotation};
}

// S C S with C(i, j) = rho^|i - j| (Kac-Murdock-Szego: SPD for |rho| < 1), so translations
// and rotations are strongly coupled inside the block; rho varies with the element.
inline Block coupledBlock(double rho) {
  const auto s = plateScales();
  Block block{};
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) block[i][j] = s[i] * std::pow(rho, std::abs(i - j)) * s[j];
  return block;
}

// 1-D chain of numNodes 6-DOF nodes, element e joining nodes e and e + 1 with stiffness
// k_e = coupledBlock(rho_e) on (u_e - u_{e+1}); node 0 sits on a spring k_0 to ground.
// A sum of PSD terms with a grounded, connected chain: SPD.
inline HostRows plateChain(int numNodes, int skippedDof = -1) {
  HostRows rows(static_cast<std::size_t>(6 * numNodes));
  addBlock(rows, 0, 0, coupledBlock(0.9), 1.0, skippedDof);
  for (int e = 0; e + 1 < numNodes; ++e) {
    const Block k = coupledBlock(0.9 + 0.08 * std::sin(0.9 * e));
    addBlock(rows, e, e, k, 1.0, skippedDof);
    addBlock(rows, e + 1, e + 1, k, 1.0, skippedDof);
    addBlock(rows, e, e + 1, k, -1.0, skippedDof);
    addBlock(rows, e + 1, e, k, -1.0, skippedDof);
  }
  return rows;
}

// Solution of the chain in natural units: O(1) after scaling by S, so that translations and
// rotations weigh alike in the error.
inline std::vector<double> plateSolution(int numNodes) {
  const auto s = plateScales();
  std::vector<double> x(static_cast<std::size_t>(6 * numNodes));
  for (std::size_t k = 0; k < x.size(); ++k) x[k] = (1.0 + 0.5 * std::sin(0.37 * k)) / s[k % 6];
  return x;
}

// ||S (x - exact)|| / ||S exact||
inline double scaledRelativeError(const std::vector<double>& x, const std::vector<double>& exact) {
  const auto s = plateScales();
  double error = 0.0, norm = 0.0;
  for (std::size_t k = 0; k < x.size(); ++k) {
    error += std::pow(s[k % 6] * (x[k] - exact[k]), 2);
    norm += std::pow(s[k % 6] * exact[k], 2);
  }
  return std::sqrt(error / norm);
}

// ||b - A x|| / ||b||
template <class ExecutionSpaceT>
double relativeResidual(const Matrix<ExecutionSpaceT>& A, const Vector<ExecutionSpaceT>& x,
                        const Vector<ExecutionSpaceT>& b) {
  Vector<ExecutionSpaceT> r("residual", b.extent(0));
  Kokkos::deep_copy(r, b);
  KokkosSparse::spmv("N", -1.0, A, x, 1.0, r);
  return KokkosBlas::nrm2(r) / KokkosBlas::nrm2(b);
}

// Node p's block: S (M^T M + I) S with M(i, j) = sin(1.3 (i + 1)(j + 1) + p): dense, SPD,
// badly scaled. rankTwoNode gets u u^T + v v^T instead: no empty row, but singular.
inline Block denseSpdBlock(int node) {
  const auto s = plateScales();
  Block m{}, block{};
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) m[i][j] = std::sin(1.3 * (i + 1) * (j + 1) + node);
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) {
      double mtm = i == j ? 1.0 : 0.0;
      for (int k = 0; k < 6; ++k) mtm += m[k][i] * m[k][j];
      block[i][j] = s[i] * mtm * s[j];
    }
  return block;
}

inline Block rankTwoBlock() {
  const double u[6] = {1, 2, 0, -1, 0.5, 3}, v[6] = {0, 1, 1, 2, -2, 1};
  Block block{};
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) block[i][j] = u[i] * u[j] + v[i] * v[j];
  return block;
}

inline HostRows blockDiagonal(int numNodes, int rankTwoNode = -1) {
  HostRows rows(static_cast<std::size_t>(6 * numNodes));
  for (int p = 0; p < numNodes; ++p) addBlock(rows, p, p, p == rankTwoNode ? rankTwoBlock() : denseSpdBlock(p), 1.0);
  return rows;
}

// A (4 x 2) has columns a0 = (1, 2, 3, 4), a1 = (0, 1, 0, -1); row-major below.
inline std::vector<double> entriesOfA() { return {1, 0, 2, 1, 3, 0, 4, -1}; }
// X (4 x 3) has columns x0 = (1, 1, 1, 1), x1 = (2, 0, -1, 0), x2 = (0, 0, 0, 5).
inline std::vector<double> entriesOfX() { return {1, 2, 0, 1, 0, 0, 1, -1, 0, 1, 0, 5}; }

}  // namespace perishell_test_belos_cg

// ---------------------------------------------------------------- the MultiVec adapter

TEST(TEST_CATEGORY, belos_cg_multivector_trans_mv_into_strided_view) {
  using namespace perishell_test_belos_cg;
  const auto A = makeMultiVector<TEST_EXECSPACE>(4, 2, entriesOfA());
  const auto X = makeMultiVector<TEST_EXECSPACE>(4, 3, entriesOfX());
  // The 2 x 3 result goes into a view at (1, 1) of a 5 x 4 matrix: stride 5, not 2.
  Teuchos::SerialDenseMatrix<int, double> big(5, 4);
  big.putScalar(7.0);
  Teuchos::SerialDenseMatrix<int, double> B(Teuchos::View, big, 2, 3, 1, 1);
  X->MvTransMv(2.0, *A, B);
  // 2 A^T X: a0.x0 = 10, a0.x1 = 2 - 3 = -1, a0.x2 = 20, a1.x0 = 0, a1.x1 = 0, a1.x2 = -5.
  const double expected[2][3] = {{20.0, -2.0, 40.0}, {0.0, 0.0, -10.0}};
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 4; ++j) {
      const bool inside = i >= 1 && i < 3 && j >= 1 && j < 4;
      EXPECT_DOUBLE_EQ(big(i, j), inside ? expected[i - 1][j - 1] : 7.0) << "big(" << i << ", " << j << ")";
    }
}

TEST(TEST_CATEGORY, belos_cg_multivector_times_mat_add_mv_from_strided_view) {
  using namespace perishell_test_belos_cg;
  const auto A = makeMultiVector<TEST_EXECSPACE>(4, 2, entriesOfA());
  const auto Y = makeMultiVector<TEST_EXECSPACE>(4, 3, entriesOfX());
  // C = [[1, 0, 2], [3, -1, 0]] read from inside a larger matrix full of NaN.
  Teuchos::SerialDenseMatrix<int, double> big(4, 5);
  big.putScalar(std::nan(""));
  Teuchos::SerialDenseMatrix<int, double> C(Teuchos::View, big, 2, 3, 2, 1);
  C(0, 0) = 1.0; C(0, 1) = 0.0; C(0, 2) = 2.0;
  C(1, 0) = 3.0; C(1, 1) = -1.0; C(1, 2) = 0.0;
  Y->MvTimesMatAddMv(0.5, *A, C, 2.0);
  // A C = [a0 + 3 a1, -a1, 2 a0] = [(1,5,3,1), (0,-1,0,1), (2,4,6,8)]; Y = 0.5 A C + 2 X.
  const auto y = onHost<TEST_EXECSPACE>(*Y);
  expectColumn(y, 0, {2.5, 4.5, 3.5, 2.5}, "0.5 A C + 2 X");
  expectColumn(y, 1, {4.0, -0.5, -2.0, 0.5}, "0.5 A C + 2 X");
  expectColumn(y, 2, {1.0, 2.0, 3.0, 14.0}, "0.5 A C + 2 X");
}

TEST(TEST_CATEGORY, belos_cg_multivector_dot_and_norms) {
  using namespace perishell_test_belos_cg;
  const auto X = makeMultiVector<TEST_EXECSPACE>(4, 3, entriesOfX());
  const auto Y = makeMultiVector<TEST_EXECSPACE>(4, 3, {3, 1, 1, 4, 1, 1, 0, 1, 1, 0, 1, 1});
  std::vector<double> dots(3, -1.0);
  X->MvDot(*Y, dots);  // x0.y0 = 7, x1.y1 = 2 - 1 = 1, x2.y2 = 5
  EXPECT_DOUBLE_EQ(dots[0], 7.0);
  EXPECT_DOUBLE_EQ(dots[1], 1.0);
  EXPECT_DOUBLE_EQ(dots[2], 5.0);
  std::vector<double> norms(3, -1.0);
  X->MvNorm(norms, Belos::TwoNorm);
  EXPECT_DOUBLE_EQ(norms[0], 2.0);
  EXPECT_DOUBLE_EQ(norms[1], std::sqrt(5.0));
  EXPECT_DOUBLE_EQ(norms[2], 5.0);
  X->MvNorm(norms, Belos::OneNorm);
  EXPECT_DOUBLE_EQ(norms[0], 4.0);
  EXPECT_DOUBLE_EQ(norms[1], 3.0);
  EXPECT_DOUBLE_EQ(norms[2], 5.0);
  X->MvNorm(norms, Belos::InfNorm);
  EXPECT_DOUBLE_EQ(norms[0], 1.0);
  EXPECT_DOUBLE_EQ(norms[1], 2.0);
  EXPECT_DOUBLE_EQ(norms[2], 5.0);
  std::vector<double> longer(5, -1.0);  // Belos passes vectors that may be longer: never shrink them.
  Y->MvNorm(longer, Belos::TwoNorm);
  ASSERT_EQ(longer.size(), 5u);
  EXPECT_DOUBLE_EQ(longer[0], 5.0);  // y0 = (3, 4, 0, 0)
  EXPECT_DOUBLE_EQ(longer[3], -1.0);
}

TEST(TEST_CATEGORY, belos_cg_multivector_set_block) {
  using namespace perishell_test_belos_cg;
  const auto A = makeMultiVector<TEST_EXECSPACE>(4, 2, entriesOfA());
  const auto X = makeMultiVector<TEST_EXECSPACE>(4, 3, entriesOfX());
  perishell::belos::KokkosMultiVector<TEST_EXECSPACE> Z("Z", 4, 4);
  Z.SetBlock(*X, {1, 2, 3});  // contiguous target
  auto z = onHost<TEST_EXECSPACE>(Z);
  expectColumn(z, 0, {0, 0, 0, 0}, "untouched");
  expectColumn(z, 1, {1, 1, 1, 1}, "x0");
  expectColumn(z, 2, {2, 0, -1, 0}, "x1");
  expectColumn(z, 3, {0, 0, 0, 5}, "x2");
  Z.SetBlock(*A, {3, 0});  // scattered target, reversed order
  z = onHost<TEST_EXECSPACE>(Z);
  expectColumn(z, 0, {0, 1, 0, -1}, "a1");
  expectColumn(z, 1, {1, 1, 1, 1}, "x0 kept");
  expectColumn(z, 2, {2, 0, -1, 0}, "x1 kept");
  expectColumn(z, 3, {1, 2, 3, 4}, "a0");
  // Source is a view of the target itself, overlapping it: columns 1..2 move to 2..3.
  const Teuchos::RCP<const Belos::MultiVec<double>> source = Teuchos::rcp(Z.CloneView({1, 2}));
  Z.SetBlock(*source, {2, 3});
  z = onHost<TEST_EXECSPACE>(Z);
  expectColumn(z, 2, {1, 1, 1, 1}, "x0 moved");
  expectColumn(z, 3, {2, 0, -1, 0}, "x1 moved");
}

TEST(TEST_CATEGORY, belos_cg_multivector_views_alias_the_parent) {
  using namespace perishell_test_belos_cg;
  const auto X = makeMultiVector<TEST_EXECSPACE>(4, 3, entriesOfX());
  const Teuchos::RCP<Belos::MultiVec<double>> tail = Teuchos::rcp(X->CloneViewNonConst({1, 2}));
  ASSERT_EQ(tail->GetNumberVecs(), 2);
  ASSERT_EQ(tail->GetGlobalLength(), 4);
  const auto& tailView = dynamic_cast<const MultiVector<TEST_EXECSPACE>&>(*tail).view();
  EXPECT_EQ(tailView.data(), X->view().data() + X->view().stride(1));
  tail->MvScale(std::vector<double>{10.0, -1.0});
  auto x = onHost<TEST_EXECSPACE>(*X);
  expectColumn(x, 0, {1, 1, 1, 1}, "outside the view");
  expectColumn(x, 1, {20, 0, -10, 0}, "scaled through the view");
  expectColumn(x, 2, {0, 0, 0, -5}, "scaled through the view");
  // CG's pattern: p = z + beta p with p a one-column view of the parent.
  const Teuchos::RCP<Belos::MultiVec<double>> p = Teuchos::rcp(X->CloneViewNonConst({0}));
  const Teuchos::RCP<const Belos::MultiVec<double>> z = Teuchos::rcp(X->CloneView({2}));
  p->MvAddMv(1.0, *z, 3.0, *p);
  x = onHost<TEST_EXECSPACE>(*X);
  expectColumn(x, 0, {3, 3, 3, -2}, "z + 3 p written into the parent");
  // Copies must not alias.
  const Teuchos::RCP<Belos::MultiVec<double>> copy = Teuchos::rcp(X->CloneCopy({0}));
  copy->MvInit(42.0);
  x = onHost<TEST_EXECSPACE>(*X);
  expectColumn(x, 0, {3, 3, 3, -2}, "parent after writing the copy");
}

TEST(TEST_CATEGORY, belos_cg_multivector_scattered_indices) {
  using namespace perishell_test_belos_cg;
  const auto X = makeMultiVector<TEST_EXECSPACE>(4, 3, entriesOfX());
  try {
    delete X->CloneViewNonConst({0, 2});
    FAIL() << "CloneViewNonConst accepted scattered columns";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("{0, 2}"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("not contiguous"), std::string::npos) << e.what();
  }
  const Teuchos::RCP<const Belos::MultiVec<double>> view = Teuchos::rcp(X->CloneView({2, 0}));
  const auto v = onHost<TEST_EXECSPACE>(*view);
  expectColumn(v, 0, {0, 0, 0, 5}, "x2");
  expectColumn(v, 1, {1, 1, 1, 1}, "x0");
  const Teuchos::RCP<Belos::MultiVec<double>> copy = Teuchos::rcp(X->CloneCopy({1, 1}));
  const auto c = onHost<TEST_EXECSPACE>(*copy);
  expectColumn(c, 0, {2, 0, -1, 0}, "x1");
  expectColumn(c, 1, {2, 0, -1, 0}, "x1 again");
  EXPECT_THROW(delete X->CloneCopy({3}), std::invalid_argument);
}

TEST(TEST_CATEGORY, belos_cg_multivector_random_and_init) {
  using namespace perishell_test_belos_cg;
  MultiVector<TEST_EXECSPACE> R("R", 1000, 2);
  R.MvRandom();
  std::vector<double> first(2), second(2);
  R.MvNorm(first);
  R.MvRandom();
  R.MvNorm(second);
  // Uniform on [-1, 1]: ||column||^2 ~ 1000 / 3, far from 0; two calls must differ.
  EXPECT_GT(first[0], 10.0);
  EXPECT_GT(first[1], 10.0);
  EXPECT_NE(first[0], first[1]);
  EXPECT_NE(first[0], second[0]);
  R.MvInit(-0.5);
  R.MvNorm(first, Belos::OneNorm);
  EXPECT_DOUBLE_EQ(first[0], 500.0);
  EXPECT_DOUBLE_EQ(first[1], 500.0);
}

// ---------------------------------------------------------------- operators
TEST(TEST_CATEGORY, belos_cg_operators_apply) {
  using namespace perishell_test_belos_cg;
  const int n = 3;  // 9 x 9 Laplacian
  const auto A = assembleScaledLaplacian<TEST_EXECSPACE>(n, ones<TEST_EXECSPACE>(n * n));
  const auto X = makeMultiVector<TEST_EXECSPACE>(9, 1, {1, 2, 3, 4, 5, 6, 7, 8, 9});
  MultiVector<TEST_EXECSPACE> Y("Y", 9, 1);
  perishell::belos::CrsOperator<TEST_EXECSPACE> op(A);
  op.Apply(*X, Y);
  // Row 4 (centre): 4*5 - (2 + 4 + 6 + 8) = 0; row 0: 4*1 - 2 - 4 = -2; row 8: 36 - 8 - 6 = 22.
  auto y = onHost<TEST_EXECSPACE>(Y);
  EXPECT_DOUBLE_EQ(y(0, 0), -2.0);
  EXPECT_DOUBLE_EQ(y(4, 0), 0.0);
  EXPECT_DOUBLE_EQ(y(8, 0), 22.0);
  ASSERT_TRUE(op.HasApplyTranspose());
  op.Apply(*X, Y, Belos::TRANS);  // symmetric: same result
  y = onHost<TEST_EXECSPACE>(Y);
  EXPECT_DOUBLE_EQ(y(8, 0), 22.0);
  perishell::belos::JacobiPreconditioner<TEST_EXECSPACE> jacobi(A);
  jacobi.Apply(*X, Y);
  y = onHost<TEST_EXECSPACE>(Y);
  EXPECT_DOUBLE_EQ(y(0, 0), 0.25);
  EXPECT_DOUBLE_EQ(y(8, 0), 2.25);
  EXPECT_THROW(op.Apply(*X, *X), std::invalid_argument);  // Belos forbids aliasing x and y
}

// ---------------------------------------------------------------- CG solves
TEST(TEST_CATEGORY, belos_cg_solves_laplacian_2d) {
  using namespace perishell_test_belos_cg;
  using Preconditioner = perishell::belos::CgOptions::Preconditioner;
  const int n = 40;
  const auto unit = ones<TEST_EXECSPACE>(n * n);
  const auto A = assembleScaledLaplacian<TEST_EXECSPACE>(n, unit);
  ASSERT_EQ(A.nnz(), RowOffset(5 * n * n - 4 * n));
  const auto exact = knownSolution<TEST_EXECSPACE>(unit);
  // cond(A) ~ 700, so a relative residual of 1e-12 bounds the relative error by ~1e-9.
  for (const auto preconditioner : {Preconditioner::None, Preconditioner::Jacobi}) {
    const auto solve = solveFromZero(A, exact, cgOptions(preconditioner, 1e-12, 1000));
    const char* name = preconditioner == Preconditioner::None ? "none" : "jacobi";
    std::cout << "[ belos cg ] laplacian 40x40, preconditioner " << name << ": "
              << solve.result.iterations << " iterations, achieved tolerance "
              << solve.result.achievedTolerance << ", relative error " << solve.relativeError << "\n";
    EXPECT_TRUE(solve.result.converged) << name;
    EXPECT_LE(solve.result.achievedTolerance, 1e-12) << name;
    EXPECT_GT(solve.result.iterations, 10) << name;
    EXPECT_LT(solve.result.iterations, 1000) << name;
    EXPECT_LE(solve.relativeError, 1e-8) << name;
  }
}

TEST(TEST_CATEGORY, belos_cg_uses_initial_guess) {
  using namespace perishell_test_belos_cg;
  const int n = 40;
  const auto unit = ones<TEST_EXECSPACE>(n * n);
  const auto A = assembleScaledLaplacian<TEST_EXECSPACE>(n, unit);
  const auto exact = knownSolution<TEST_EXECSPACE>(unit);
  const auto b = multiply(A, exact);
  Vector<TEST_EXECSPACE> x("x", exact.extent(0));
  Kokkos::deep_copy(x, exact);  // exact start: zero initial residual
  const Kokkos::View<const double*, TEST_EXECSPACE::memory_space> constB = b;
  const auto result = perishell::belos::solveCg(A, constB, x, perishell::belos::CgOptions{});
  EXPECT_TRUE(result.converged);
  EXPECT_EQ(result.iterations, 0);
  EXPECT_EQ(relativeError(x, exact), 0.0);
}

TEST(TEST_CATEGORY, belos_cg_jacobi_fixes_bad_scaling) {
  using namespace perishell_test_belos_cg;
  using Preconditioner = perishell::belos::CgOptions::Preconditioner;
  const int n = 40;
  const auto d = badScaling<TEST_EXECSPACE>(n * n);
  const auto A = assembleScaledLaplacian<TEST_EXECSPACE>(n, d);  // D A D: still SPD
  const auto exact = knownSolution<TEST_EXECSPACE>(d);
  const int maxIterations = 20000;
  const auto plain = solveFromZero(A, exact, cgOptions(Preconditioner::None, 1e-12, maxIterations));
  const auto jacobi = solveFromZero(A, exact, cgOptions(Preconditioner::Jacobi, 1e-12, maxIterations));
  std::cout << "[ belos cg ] D A D, d in [0.1, 10]: none " << plain.result.iterations
            << " iterations (converged " << plain.result.converged << ", relative error "
            << plain.relativeError << "), jacobi " << jacobi.result.iterations << " iterations (relative error "
            << jacobi.relativeError << ")\n";
  EXPECT_TRUE(plain.result.converged);
  EXPECT_TRUE(jacobi.result.converged);
  EXPECT_LE(jacobi.relativeError, 1e-8);
  EXPECT_LE(jacobi.result.iterations, plain.result.iterations);
  // Jacobi undoes D exactly here (diag(D A D) = 4 D^2), so it should need far fewer iterations.
  EXPECT_LT(2 * jacobi.result.iterations, plain.result.iterations);
}

// ---------------------------------------------------------------- failures
TEST(TEST_CATEGORY, belos_cg_jacobi_rejects_zero_diagonal) {
  using namespace perishell_test_belos_cg;
  const int n = 10;
  const auto unit = ones<TEST_EXECSPACE>(n * n);
  const auto A = assembleScaledLaplacian<TEST_EXECSPACE>(n, unit);
  setDiagonal(A, 17, 0.0);
  try {
    perishell::belos::JacobiPreconditioner<TEST_EXECSPACE> jacobi(A);
    FAIL() << "JacobiPreconditioner accepted a zero diagonal";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("row 17 "), std::string::npos) << e.what();
  }
  setDiagonal(A, 17, 4.0);
  setDiagonal(A, 63, std::nan(""));
  EXPECT_THROW(perishell::belos::JacobiPreconditioner<TEST_EXECSPACE>{A}, std::runtime_error);
  // solveCg builds the same preconditioner, so it fails the same way before iterating.
  const auto b = ones<TEST_EXECSPACE>(n * n);
  Vector<TEST_EXECSPACE> x("x", n * n);
  try {
    perishell::belos::solveCg(A, b, x, perishell::belos::CgOptions{});
    FAIL() << "solveCg accepted a NaN diagonal with Jacobi";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("row 63 "), std::string::npos) << e.what();
  }
}

TEST(TEST_CATEGORY, belos_cg_reports_breakdown_on_indefinite_matrix) {
  using namespace perishell_test_belos_cg;
  using Preconditioner = perishell::belos::CgOptions::Preconditioner;
  const int n = 10;
  // Laplacian - 2 I: eigenvalues in (-2, 6), positive diagonal (so Jacobi builds). With b = 1
  // the first step already has p^T A p < 0: interior rows sum to -2, edge rows to -1.
  // (Negating A would not do: -A with Jacobi is CG on A with M = diag(A)^-1 in disguise.)
  const auto A = assembleScaledLaplacian<TEST_EXECSPACE>(n, ones<TEST_EXECSPACE>(n * n), 2.0);
  const auto b = ones<TEST_EXECSPACE>(n * n);
  for (const auto preconditioner : {Preconditioner::None, Preconditioner::Jacobi}) {
    Vector<TEST_EXECSPACE> x("x", n * n);
    auto options = cgOptions(preconditioner, 1e-10, 100);
    options.fallbackOnBreakdown = false;
    try {
      perishell::belos::solveCg(A, b, x, options);
      FAIL() << "CG did not report a breakdown";
    } catch (const std::runtime_error& e) {
      std::cout << "[ belos cg ] indefinite: " << e.what() << "\n";
      EXPECT_NE(std::string(e.what()).find("CG broke down"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("not symmetric positive definite"), std::string::npos) << e.what();
    }
  }
}

TEST(TEST_CATEGORY, belos_cg_reports_nan_residual) {
  using namespace perishell_test_belos_cg;
  const int n = 10;
  const auto A = assembleScaledLaplacian<TEST_EXECSPACE>(n, ones<TEST_EXECSPACE>(n * n));
  const auto b = ones<TEST_EXECSPACE>(n * n);
  Kokkos::deep_copy(Kokkos::subview(b, 37), std::nan(""));
  Vector<TEST_EXECSPACE> x("x", n * n);
  try {
    perishell::belos::solveCg(A, b, x, perishell::belos::CgOptions{});
    FAIL() << "CG accepted a NaN right-hand side";
  } catch (const std::runtime_error& e) {
    std::cout << "[ belos cg ] NaN: " << e.what() << "\n";
    EXPECT_NE(std::string(e.what()).find("NaN"), std::string::npos) << e.what();
  }
}

TEST(TEST_CATEGORY, belos_cg_rejects_mismatched_sizes) {
  using namespace perishell_test_belos_cg;
  const int n = 5;
  const auto A = assembleScaledLaplacian<TEST_EXECSPACE>(n, ones<TEST_EXECSPACE>(n * n));
  const auto b = ones<TEST_EXECSPACE>(n * n);
  Vector<TEST_EXECSPACE> x("x", n * n - 1);
  EXPECT_THROW(perishell::belos::solveCg(A, b, x), std::invalid_argument);
}

// ---------------------------------------------------------------- block Jacobi
TEST(TEST_CATEGORY, belos_cg_block_jacobi_solves_block_diagonal_in_one_iteration) {
  using namespace perishell_test_belos_cg;
  const int numNodes = 5;
  const auto A = matrixOnDevice<TEST_EXECSPACE>(blockDiagonal(numNodes));
  const auto exactHost = plateSolution(numNodes);
  const auto exact = vectorOnDevice<TEST_EXECSPACE>(exactHost);
  const auto b = multiply(A, exact);
  // The preconditioner alone is the exact inverse here.
  perishell::belos::BlockJacobiPreconditioner<TEST_EXECSPACE> blockJacobi(A, 6);
  ASSERT_EQ(blockJacobi.blockSize(), 6);
  const auto B = makeMultiVector<TEST_EXECSPACE>(6 * numNodes, 1, vectorOnHost(b));
  MultiVector<TEST_EXECSPACE> Y("Y", 6 * numNodes, 1);
  blockJacobi.Apply(*B, Y);
  const auto y = onHost<TEST_EXECSPACE>(Y);
  const double applyError = scaledRelativeError(std::vector<double>(y.data(), y.data() + y.extent(0)), exactHost);
  EXPECT_LE(applyError, 1e-13);

  Vector<TEST_EXECSPACE> x("x", exact.extent(0));
  const auto result = perishell::belos::solveCg(
      A, b, x, cgOptions(perishell::belos::CgOptions::Preconditioner::BlockJacobi, 1e-10, 100));
  const double error = scaledRelativeError(vectorOnHost(x), exactHost);
  std::cout << "[ belos cg ] block-diagonal 30 x 30, block Jacobi: " << result.iterations
            << " iteration(s), achieved tolerance " << result.achievedTolerance << ", scaled error " << error
            << " (apply alone: " << applyError << ")\n";
  EXPECT_TRUE(result.converged);
  EXPECT_EQ(result.iterations, 1);
  EXPECT_EQ(result.method, "CG");
  EXPECT_TRUE(result.breakdown.empty());
  EXPECT_LE(error, 1e-13);
}

TEST(TEST_CATEGORY, belos_cg_block_jacobi_pivots_nonsymmetric_blocks) {
  using namespace perishell_test_belos_cg;
  // Two 3 x 3 blocks; the first has zeros on its diagonal (det -7), so the elimination must pivot.
  const double blocks[2][3][3] = {{{0, 2, 1}, {1, 0, 0}, {3, 1, 4}}, {{4, 1, 0}, {2, 5, 1}, {0, 1, 3}}};
  HostRows rows(6);
  for (int p = 0; p < 2; ++p)
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        if (blocks[p][i][j] != 0.0) rows[3 * p + i][3 * p + j] = blocks[p][i][j];
  const auto A = matrixOnDevice<TEST_EXECSPACE>(rows);
  const std::vector<double> exact = {1, -2, 3, 0.5, 4, -1};
  const auto X = makeMultiVector<TEST_EXECSPACE>(6, 1, exact);
  MultiVector<TEST_EXECSPACE> AX("AX", 6, 1), Y("Y", 6, 1);
  perishell::belos::CrsOperator<TEST_EXECSPACE> op(A);
  perishell::belos::BlockJacobiPreconditioner<TEST_EXECSPACE> blockJacobi(A, 3);
  for (const auto trans : {Belos::NOTRANS, Belos::TRANS}) {
    op.Apply(*X, AX, trans);
    blockJacobi.Apply(AX, Y, trans);  // (A^T)^{-1} A^T x = x as well
    const auto y = onHost<TEST_EXECSPACE>(Y);
    for (int i = 0; i < 6; ++i) EXPECT_NEAR(y(i, 0), exact[i], 1e-14) << "row " << i << ", trans " << trans;
  }
  // The first block's second row is e_0^T, so row 0 of its inverse is e_1^T.
  const auto inverses = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), blockJacobi.inverses());
  EXPECT_NEAR(inverses(0, 0, 0), 0.0, 1e-15);
  EXPECT_NEAR(inverses(0, 0, 1), 1.0, 1e-15);
  EXPECT_NEAR(inverses(0, 0, 2), 0.0, 1e-15);
}

TEST(TEST_CATEGORY, belos_cg_block_jacobi_beats_jacobi_on_plate_chain) {
  using namespace perishell_test_belos_cg;
  using Preconditioner = perishell::belos::CgOptions::Preconditioner;
  const int numNodes = 40;
  const auto A = matrixOnDevice<TEST_EXECSPACE>(plateChain(numNodes));
  const auto exactHost = plateSolution(numNodes);
  const auto exact = vectorOnDevice<TEST_EXECSPACE>(exactHost);
  const auto b = multiply(A, exact);
  const double tolerance = 1e-10;
  int iterations[3] = {};
  double errors[3] = {};
  const char* names[3] = {"none", "jacobi", "block-jacobi"};
  for (int p = 0; p < 3; ++p) {
    Vector<TEST_EXECSPACE> x("x", exact.extent(0));
    const auto preconditioner = perishell::belos::preconditionerFromName(names[p]);
    const auto result = perishell::belos::solveCg(A, b, x, cgOptions(preconditioner, tolerance, 2000));
    iterations[p] = result.iterations;
    errors[p] = scaledRelativeError(vectorOnHost(x), exactHost);
    const double residual = relativeResidual(A, x, b);
    std::cout << "[ belos cg ] plate chain 240 DOF, " << names[p] << ": " << result.iterations
              << " iterations, converged " << result.converged << ", relative residual " << residual
              << ", scaled error " << errors[p] << "\n";
    if (preconditioner == Preconditioner::None) {
      // The 1e9 scale gap leaves plain CG far from the tolerance (measured: residual 2e-7).
      EXPECT_FALSE(result.converged);
      continue;
    }
    EXPECT_TRUE(result.converged) << names[p];
    EXPECT_EQ(result.method, "CG") << names[p];
    EXPECT_LE(residual, tolerance) << names[p];
    EXPECT_LE(errors[p], 1e-5) << names[p];
  }
  // Measured on OpenMP: point Jacobi 979, block Jacobi 191 (point Jacobi leaves the coupling
  // inside each node, cond(C) ~ (1 + rho) / (1 - rho) per block, to CG).
  EXPECT_LT(2 * iterations[2], iterations[1]);
  EXPECT_LT(iterations[2], 300);
}

TEST(TEST_CATEGORY, belos_cg_falls_back_to_gmres_on_indefinite_matrix) {
  using namespace perishell_test_belos_cg;
  const int n = 12;  // 144 rows: 24 blocks of 6
  // Laplacian - 2 I (see belos_cg_reports_breakdown_on_indefinite_matrix); its 6 x 6 diagonal
  // blocks are tridiag(-1, 2, -1), SPD, so block Jacobi builds and CG still breaks down.
  const auto unit = ones<TEST_EXECSPACE>(n * n);
  const auto A = assembleScaledLaplacian<TEST_EXECSPACE>(n, unit, 2.0);
  const auto exact = knownSolution<TEST_EXECSPACE>(unit);
  const auto b = multiply(A, exact);
  const double tolerance = 1e-10;
  for (const char* name : {"none", "jacobi", "block-jacobi"}) {
    Vector<TEST_EXECSPACE> x("x", n * n);
    const auto result = perishell::belos::solveCg(
        A, b, x, cgOptions(perishell::belos::preconditionerFromName(name), tolerance, 500));
    const double residual = relativeResidual(A, x, b);
    const double error = relativeError(x, exact);
    std::cout << "[ belos cg ] indefinite 144 x 144, " << name << ": " << result.method << " in "
              << result.iterations << " iterations, relative residual " << residual << ", relative error "
              << error << "\n";
    EXPECT_EQ(result.method, "GMRES") << name;
    EXPECT_NE(result.breakdown.find("CG broke down"), std::string::npos) << result.breakdown;
    EXPECT_TRUE(result.converged) << name;
    EXPECT_GT(result.iterations, 0) << name;
    EXPECT_LE(result.iterations, 144) << name;  // GMRES is exact after n steps
    EXPECT_LE(result.achievedTolerance, tolerance) << name;
    EXPECT_LE(residual, tolerance) << name;
    EXPECT_LE(error, 1e-7) << name;
  }
}

// Method::Gmres (the exact, non-symmetric Newton tangent) solves with GMRES from the start:
// a convection-diffusion-like tridiagonal matrix, far from symmetric.
TEST(TEST_CATEGORY, belos_cg_gmres_method_solves_a_non_symmetric_matrix) {
  using namespace perishell_test_belos_cg;
  const int n = 120;
  HostRows rows(n);
  std::vector<double> exact(n);
  for (int i = 0; i < n; ++i) {
    rows[i][i] = 4.0;
    if (i > 0) rows[i][i - 1] = -2.5;
    if (i + 1 < n) rows[i][i + 1] = 0.5;
    exact[i] = std::sin(0.1 * i) + 1.0;
  }
  const auto A = matrixOnDevice<TEST_EXECSPACE>(rows);
  const auto exactOnDevice = vectorOnDevice<TEST_EXECSPACE>(exact);
  const auto b = multiply(A, exactOnDevice);
  auto options = cgOptions(perishell::belos::CgOptions::Preconditioner::Jacobi, 1e-10, 500);
  options.method = perishell::belos::CgOptions::Method::Gmres;
  Vector<TEST_EXECSPACE> x("x", n);
  const auto result = perishell::belos::solveCg(A, b, x, options);
  const double residual = relativeResidual(A, x, b);
  std::cout << "[ belos cg ] non-symmetric 120 x 120: " << result.method << " in " << result.iterations
            << " iterations, relative residual " << residual << ", relative error " << relativeError(x, exactOnDevice)
            << "\n";
  EXPECT_EQ(result.method, "GMRES");
  EXPECT_TRUE(result.breakdown.empty()) << result.breakdown;
  EXPECT_TRUE(result.converged);
  EXPECT_LE(residual, 1e-10);
  EXPECT_LE(relativeError(x, exactOnDevice), 1e-8);
}

TEST(TEST_CATEGORY, belos_cg_block_jacobi_rejects_singular_blocks) {
  using namespace perishell_test_belos_cg;
  const auto expectFailure = [](const Matrix<TEST_EXECSPACE>& A, const std::vector<std::string>& needles) {
    try {
      perishell::belos::BlockJacobiPreconditioner<TEST_EXECSPACE> blockJacobi(A, 6);
      ADD_FAILURE() << "BlockJacobiPreconditioner accepted a bad block";
    } catch (const std::runtime_error& e) {
      std::cout << "[ belos cg ] " << e.what() << "\n";
      for (const auto& needle : needles)
        EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
    }
  };
  // Rotation DOF 4 of node 3 belongs to no element: empty row and column.
  const auto untouched = matrixOnDevice<TEST_EXECSPACE>(plateChain(8, 6 * 3 + 4));
  expectFailure(untouched, {"node 3 ", "rows 18 to 23", "local DOF 4", "no stiffness in some DOF"});
  // solveCg builds the same preconditioner before iterating.
  const auto b = ones<TEST_EXECSPACE>(6 * 8);
  Vector<TEST_EXECSPACE> x("x", 6 * 8);
  try {
    perishell::belos::solveCg(untouched, b, x,
                              cgOptions(perishell::belos::CgOptions::Preconditioner::BlockJacobi, 1e-10, 100));
    FAIL() << "solveCg accepted a singular block";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("node 3 "), std::string::npos) << e.what();
  }
  // Rank 2 with no empty row: found by the pivot, not by the row scan.
  expectFailure(matrixOnDevice<TEST_EXECSPACE>(blockDiagonal(4, 1)), {"node 1 ", "is singular", "no stiffness"});
  // A NaN entry in node 5.
  auto withNan = plateChain(8);
  withNan[6 * 5 + 2][6 * 5 + 3] = std::nan("");
  expectFailure(matrixOnDevice<TEST_EXECSPACE>(withNan), {"node 5 ", "NaN", "local DOF 2"});
  // 100 rows are no whole number of 6-DOF nodes; block sizes outside [1, 6].
  const auto laplacian = assembleScaledLaplacian<TEST_EXECSPACE>(10, ones<TEST_EXECSPACE>(100));
  try {
    perishell::belos::BlockJacobiPreconditioner<TEST_EXECSPACE> blockJacobi(laplacian, 6);
    FAIL() << "BlockJacobiPreconditioner accepted 100 rows in blocks of 6";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("100 rows"), std::string::npos) << e.what();
  }
  EXPECT_THROW(perishell::belos::BlockJacobiPreconditioner<TEST_EXECSPACE>(laplacian, 0), std::invalid_argument);
  EXPECT_THROW(perishell::belos::BlockJacobiPreconditioner<TEST_EXECSPACE>(laplacian, 10), std::invalid_argument);
  // Block size 4 fits 100 rows: the 2 x 2 grid rows of the Laplacian give SPD blocks.
  EXPECT_NO_THROW(perishell::belos::BlockJacobiPreconditioner<TEST_EXECSPACE>(laplacian, 4));
}

TEST(TEST_CATEGORY, belos_cg_preconditioner_names) {
  using perishell::belos::preconditionerFromName;
  using Preconditioner = perishell::belos::CgOptions::Preconditioner;
  EXPECT_EQ(preconditionerFromName("none"), Preconditioner::None);
  EXPECT_EQ(preconditionerFromName("jacobi"), Preconditioner::Jacobi);
  EXPECT_EQ(preconditionerFromName("block-jacobi"), Preconditioner::BlockJacobi);
  try {
    preconditionerFromName("ilu");
    FAIL() << "preconditionerFromName accepted 'ilu'";
  } catch (const std::invalid_argument& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("'ilu'"), std::string::npos) << what;
    EXPECT_NE(what.find("none, jacobi, block-jacobi"), std::string::npos) << what;
  }
}
