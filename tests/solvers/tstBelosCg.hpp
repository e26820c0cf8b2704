// Belos CG on Kokkos: the MultiVec adapter against hand-computed values, CG on a device-
// assembled 2D Laplacian (plain and badly scaled), and the failure paths (zero diagonal,
// indefinite matrix).
#include <perishell/solvers/belos/cg_solve.hpp>
#include <perishell/solvers/belos/crs_operator.hpp>
#include <perishell/solvers/belos/kokkos_multivector.hpp>

#include <KokkosBlas1_axpby.hpp>
#include <KokkosBlas1_nrm2.hpp>
#include <KokkosBlas1_scal.hpp>
#include <KokkosSparse_spmv.hpp>
#include <Teuchos_RCP.hpp>
#include <Teuchos_SerialDenseMatrix.hpp>

#include <cmath>
#include <iostream>
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
    try {
      perishell::belos::solveCg(A, b, x, cgOptions(preconditioner, 1e-10, 100));
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
