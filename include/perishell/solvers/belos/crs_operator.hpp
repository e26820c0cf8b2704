#pragma once
// Belos::Operator<double> wrappers: a Kokkos Kernels CRS matrix (y = A x through
// KokkosSparse::spmv) and the point-Jacobi preconditioner built from its diagonal.
#include <perishell/core/types.hpp>
#include <perishell/solvers/belos/kokkos_multivector.hpp>

#include <BelosOperator.hpp>
#include <BelosTypes.hpp>

#include <KokkosSparse_CrsMatrix.hpp>
#include <KokkosSparse_spmv.hpp>
#include <Kokkos_Core.hpp>

#include <climits>
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <stdexcept>
#include <string>

namespace perishell::belos {

template <class ExecutionSpaceT>
using CrsMatrix = KokkosSparse::CrsMatrix<double, LocalIndex,
                                          Kokkos::Device<ExecutionSpaceT, typename ExecutionSpaceT::memory_space>,
                                          void, RowOffset>;

namespace detail {

[[noreturn]] inline void throwNotKokkos(const char* who) {
  throw std::invalid_argument(std::string(who) +
                              ": expects KokkosMultiVector arguments on the operator's execution space");
}

template <class ExecutionSpaceT>
const KokkosMultiVector<ExecutionSpaceT>& asKokkos(const Belos::MultiVec<double>& mv, const char* who) {
  const auto* kokkos = dynamic_cast<const KokkosMultiVector<ExecutionSpaceT>*>(&mv);
  if (kokkos == nullptr) throwNotKokkos(who);
  return *kokkos;
}

template <class ExecutionSpaceT>
KokkosMultiVector<ExecutionSpaceT>& asKokkos(Belos::MultiVec<double>& mv, const char* who) {
  auto* kokkos = dynamic_cast<KokkosMultiVector<ExecutionSpaceT>*>(&mv);
  if (kokkos == nullptr) throwNotKokkos(who);
  return *kokkos;
}

template <class ExecutionSpaceT>
void checkApplyShapes(const KokkosMultiVector<ExecutionSpaceT>& x, const KokkosMultiVector<ExecutionSpaceT>& y,
                      std::size_t xRows, std::size_t yRows, const char* who) {
  const auto& xv = x.view();
  const auto& yv = y.view();
  if (xv.extent(0) != xRows || yv.extent(0) != yRows || xv.extent(1) != yv.extent(1)) {
    std::ostringstream msg;
    msg << who << ": shape mismatch, operator is " << yRows << " x " << xRows << ", x is " << xv.extent(0)
        << " x " << xv.extent(1) << ", y is " << yv.extent(0) << " x " << yv.extent(1);
    throw std::invalid_argument(msg.str());
  }
  // Belos promises x and y never alias; the kernels below would race if they did.
  if (xv.span() != 0 && yv.span() != 0 && xv.data() < yv.data() + yv.span() &&
      yv.data() < xv.data() + xv.span()) {
    throw std::invalid_argument(std::string(who) + ": x and y share storage");
  }
}

// Fills inverseDiagonal(i) = 1 / A(i, i) (duplicate diagonal entries summed, as spmv would)
// and returns the first row whose diagonal is zero or not finite, or -1.
template <class ExecutionSpaceT>
LocalIndex invertDiagonal(const CrsMatrix<ExecutionSpaceT>& A,
                          const Kokkos::View<double*, typename CrsMatrix<ExecutionSpaceT>::device_type>& inverseDiagonal) {
  const auto rowMap = A.graph.row_map;
  const auto entries = A.graph.entries;
  const auto values = A.values;
  LocalIndex firstBadRow = INT_MAX;
  Kokkos::parallel_reduce(
      "perishell::belos::invert_diagonal", Kokkos::RangePolicy<ExecutionSpaceT>(0, A.numRows()),
      KOKKOS_LAMBDA(const LocalIndex row, LocalIndex& firstBad) {
        double diagonal = 0.0;
        for (RowOffset k = rowMap(row); k < rowMap(row + 1); ++k)
          if (entries(k) == row) diagonal += values(k);
        const bool usable = diagonal != 0.0 && Kokkos::Experimental::isfinite(diagonal);
        inverseDiagonal(row) = usable ? 1.0 / diagonal : 0.0;
        if (!usable && row < firstBad) firstBad = row;
      },
      Kokkos::Min<LocalIndex>(firstBadRow));
  return firstBadRow == INT_MAX ? -1 : firstBadRow;
}

template <class ExecutionSpaceT>
double diagonalEntry(const CrsMatrix<ExecutionSpaceT>& A, LocalIndex row) {
  const auto rowMap = A.graph.row_map;
  const auto entries = A.graph.entries;
  const auto values = A.values;
  double diagonal = 0.0;
  Kokkos::parallel_reduce(
      "perishell::belos::diagonal_entry", Kokkos::RangePolicy<ExecutionSpaceT>(0, 1),
      KOKKOS_LAMBDA(const int, double& sum) {
        for (RowOffset k = rowMap(row); k < rowMap(row + 1); ++k)
          if (entries(k) == row) sum += values(k);
      },
      diagonal);
  return diagonal;
}

// y(i, j) = d(i) * x(i, j)
template <class DiagonalView, class MultiView>
void scaleRows(const DiagonalView& d, const MultiView& x, const MultiView& y) {
  using execution_space = typename DiagonalView::execution_space;
  const int numCols = static_cast<int>(x.extent(1));
  Kokkos::parallel_for(
      "perishell::belos::scale_rows",
      Kokkos::RangePolicy<execution_space>(0, static_cast<std::int64_t>(x.extent(0))),
      KOKKOS_LAMBDA(const std::int64_t row) {
        for (int j = 0; j < numCols; ++j) y(row, j) = d(row) * x(row, j);
      });
}

// y(:, column) = 0 on the rows this rank does not own (DistributedRows).
template <class ExecutionSpaceT, class OwnedView, class MultiView>
void zeroHaloRows(const OwnedView& owned, const MultiView& y, int column) {
  Kokkos::parallel_for(
      "perishell::belos::zero_halo_rows", Kokkos::RangePolicy<ExecutionSpaceT>(0, std::int64_t(y.extent(0))),
      KOKKOS_LAMBDA(const std::int64_t row) {
        if (!owned(row)) y(row, column) = 0.0;
      });
}

}  // namespace detail

// y = A x (or A^T x) with KokkosSparse::spmv. Holds the matrix by shallow copy. With
// DistributedRows, A holds this rank's rows (owned rows complete, their columns reaching
// into the halo): x's halo rows are filled from their owners into a copy before the product,
// and y's halo rows are zero.
template <class ExecutionSpaceT>
class CrsOperator final : public Belos::Operator<double> {
  static_assert(Kokkos::is_execution_space<ExecutionSpaceT>::value,
                "CrsOperator needs a Kokkos execution space");

 public:
  using matrix_type = CrsMatrix<ExecutionSpaceT>;
  using memory_space = typename ExecutionSpaceT::memory_space;

  explicit CrsOperator(const matrix_type& A, SharedRows<memory_space> rows = nullptr) : A_(A), rows_(std::move(rows)) {}

  const matrix_type& matrix() const { return A_; }

  void Apply(const Belos::MultiVec<double>& x, Belos::MultiVec<double>& y,
             Belos::ETrans trans = Belos::NOTRANS) const override {
    constexpr const char* who = "perishell::belos::CrsOperator::Apply";
    const auto& xk = detail::asKokkos<ExecutionSpaceT>(x, who);
    auto& yk = detail::asKokkos<ExecutionSpaceT>(y, who);
    const auto rows = static_cast<std::size_t>(A_.numRows());
    const auto cols = static_cast<std::size_t>(A_.numCols());
    // spmv implements the transpose as well; for real scalars CONJTRANS is the same thing.
    const bool transposed = trans != Belos::NOTRANS;
    detail::checkApplyShapes(xk, yk, transposed ? rows : cols, transposed ? cols : rows, who);
    if (rows_) {
      if (transposed) throw std::invalid_argument(std::string(who) + ": no transpose for rows split over ranks");
      if (filled_.extent(0) != cols)
        filled_ = Kokkos::View<double*, Kokkos::Device<ExecutionSpaceT, memory_space>>("perishell::belos::halo_filled", cols);
      for (int j = 0; j < xk.GetNumberVecs(); ++j) {
        Kokkos::deep_copy(filled_, Kokkos::subview(xk.deviceView(), Kokkos::ALL(), j));
        ExecutionSpaceT().fence();
        rows_->fillHalo(VectorView<memory_space>(filled_.data(), cols));
        const auto y = Kokkos::subview(yk.deviceView(), Kokkos::ALL(), j);
        KokkosSparse::spmv(KokkosSparse::NoTranspose, 1.0, A_, filled_, 0.0, y);
        detail::zeroHaloRows<ExecutionSpaceT>(rows_->owned, yk.deviceView(), j);
      }
      return;
    }
    KokkosSparse::spmv(transposed ? KokkosSparse::Transpose : KokkosSparse::NoTranspose, 1.0, A_,
                       xk.deviceView(), 0.0, yk.deviceView());
  }

  bool HasApplyTranspose() const override { return !rows_; }

 private:
  matrix_type A_;
  SharedRows<memory_space> rows_;
  mutable Kokkos::View<double*, Kokkos::Device<ExecutionSpaceT, memory_space>> filled_;
};

// Point Jacobi: y = D^{-1} x with D = diag(A). Symmetric, so it serves as left or right
// preconditioner and its transpose is itself.
template <class ExecutionSpaceT>
class JacobiPreconditioner final : public Belos::Operator<double> {
  static_assert(Kokkos::is_execution_space<ExecutionSpaceT>::value,
                "JacobiPreconditioner needs a Kokkos execution space");

 public:
  using matrix_type = CrsMatrix<ExecutionSpaceT>;
  using diagonal_type = Kokkos::View<double*, typename matrix_type::device_type>;

  // Throws std::runtime_error naming the first row whose diagonal is zero, missing or not finite.
  explicit JacobiPreconditioner(const matrix_type& A)
      : inverseDiagonal_(Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::belos::inverse_diagonal"),
                         static_cast<std::size_t>(A.numRows())) {
    if (A.numRows() != A.numCols()) {
      throw std::invalid_argument("perishell::belos::JacobiPreconditioner: matrix is " +
                                  std::to_string(A.numRows()) + " x " + std::to_string(A.numCols()) +
                                  ", not square");
    }
    const LocalIndex badRow = detail::invertDiagonal(A, inverseDiagonal_);
    if (badRow >= 0) {
      std::ostringstream msg;
      msg << "perishell::belos::JacobiPreconditioner: diagonal entry of row " << badRow << " is "
          << detail::diagonalEntry(A, badRow)
          << "; point Jacobi needs a nonzero, finite diagonal (is the row missing its diagonal, or "
             "is a constraint/boundary row left empty?)";
      throw std::runtime_error(msg.str());
    }
  }

  const diagonal_type& inverseDiagonal() const { return inverseDiagonal_; }

  void Apply(const Belos::MultiVec<double>& x, Belos::MultiVec<double>& y,
             Belos::ETrans /*trans: D^{-1} is its own transpose*/ = Belos::NOTRANS) const override {
    constexpr const char* who = "perishell::belos::JacobiPreconditioner::Apply";
    const auto& xk = detail::asKokkos<ExecutionSpaceT>(x, who);
    auto& yk = detail::asKokkos<ExecutionSpaceT>(y, who);
    const auto n = inverseDiagonal_.extent(0);
    detail::checkApplyShapes(xk, yk, n, n, who);
    detail::scaleRows(inverseDiagonal_, xk.deviceView(), yk.deviceView());
  }

  bool HasApplyTranspose() const override { return true; }

 private:
  diagonal_type inverseDiagonal_;
};

}  // namespace perishell::belos
