#pragma once
// Nodal block-Jacobi preconditioner: y = blockdiag(A)^{-1} x, where the diagonal blocks are
// the blockSize x blockSize couplings among one node's DOF (6 for a shell node). It undoes
// the scale gap between translational and rotational stiffness inside each node, which
// point Jacobi only does for the diagonal entries.
//
// Each block is inverted on the device by Gauss-Jordan elimination with partial pivoting
// (LU with partial pivoting, carried through to the inverse), after symmetric diagonal
// equilibration. Not Cholesky: near a limit point a nodal block of the tangent can be
// indefinite, and the preconditioner must still build for the GMRES fallback.
#include <perishell/core/types.hpp>
#include <perishell/solvers/belos/crs_operator.hpp>
#include <perishell/solvers/belos/kokkos_multivector.hpp>

#include <BelosOperator.hpp>
#include <BelosTypes.hpp>

#include <Kokkos_Core.hpp>

#include <climits>
#include <cstddef>
#include <cstdint>
#include <sstream>
#include <stdexcept>
#include <string>

namespace perishell::belos {

// Largest block the device kernels hold in registers: the 6 DOF of a shell node.
inline constexpr int maxBlockSize = 6;

namespace detail {

enum BlockCondition : int { BlockInvertible = 0, BlockNotFinite = 1, BlockEmptyRow = 2, BlockSingular = 3 };

// A pivot of the equilibrated block (unit diagonal where the diagonal is nonzero) below this
// means the block's condition number exceeds ~1e12: numerically singular.
inline constexpr double singularPivot = 1e-12;

struct BlockDiagnosis {
  int condition = BlockInvertible;
  int localDof = -1;  // the offending row (not finite, empty) or pivot column (singular)
};

// Sum of A's entries in rows and columns [first, first + size) into block (duplicates summed,
// as spmv would); rows are short (the node's neighbours times the DOF), so one thread scans them.
template <class RowMap, class Entries, class Values>
KOKKOS_INLINE_FUNCTION void extractBlock(const RowMap& rowMap, const Entries& entries, const Values& values,
                                         LocalIndex first, int size, double (&block)[maxBlockSize][maxBlockSize]) {
  for (int i = 0; i < size; ++i)
    for (int j = 0; j < size; ++j) block[i][j] = 0.0;
  for (int i = 0; i < size; ++i)
    for (auto k = rowMap(first + i); k < rowMap(first + i + 1); ++k) {
      const LocalIndex column = entries(k) - first;
      if (column >= 0 && column < size) block[i][column] += values(k);
    }
}

// inverse = block^{-1}; block is overwritten. Equilibrates with s_i = |a_ii|^{-1/2} (the
// largest entry of the row where the diagonal is zero), so that the pivot threshold is
// independent of the stiffness units of each DOF.
KOKKOS_INLINE_FUNCTION BlockDiagnosis invertBlock(double (&block)[maxBlockSize][maxBlockSize], int size,
                                                  double (&inverse)[maxBlockSize][maxBlockSize]) {
  double scale[maxBlockSize];
  for (int i = 0; i < size; ++i) {
    double rowMax = 0.0;
    for (int j = 0; j < size; ++j) {
      if (!Kokkos::Experimental::isfinite(block[i][j])) return {BlockNotFinite, i};
      rowMax = Kokkos::Experimental::fmax(rowMax, Kokkos::Experimental::fabs(block[i][j]));
    }
    if (rowMax == 0.0) return {BlockEmptyRow, i};
    const double diagonal = Kokkos::Experimental::fabs(block[i][i]);
    scale[i] = 1.0 / Kokkos::Experimental::sqrt(diagonal != 0.0 ? diagonal : rowMax);
  }
  for (int i = 0; i < size; ++i)
    for (int j = 0; j < size; ++j) {
      block[i][j] *= scale[i] * scale[j];
      inverse[i][j] = i == j ? 1.0 : 0.0;
    }
  for (int k = 0; k < size; ++k) {
    int pivotRow = k;
    for (int i = k + 1; i < size; ++i)
      if (Kokkos::Experimental::fabs(block[i][k]) > Kokkos::Experimental::fabs(block[pivotRow][k])) pivotRow = i;
    // The negated test also catches a NaN pivot.
    if (!(Kokkos::Experimental::fabs(block[pivotRow][k]) > singularPivot)) return {BlockSingular, k};
    if (pivotRow != k)
      for (int j = 0; j < size; ++j) {
        const double a = block[k][j];
        block[k][j] = block[pivotRow][j];
        block[pivotRow][j] = a;
        const double b = inverse[k][j];
        inverse[k][j] = inverse[pivotRow][j];
        inverse[pivotRow][j] = b;
      }
    const double reciprocal = 1.0 / block[k][k];
    for (int j = 0; j < size; ++j) {
      block[k][j] *= reciprocal;
      inverse[k][j] *= reciprocal;
    }
    for (int i = 0; i < size; ++i) {
      if (i == k) continue;
      const double factor = block[i][k];
      for (int j = 0; j < size; ++j) {
        block[i][j] -= factor * block[k][j];
        inverse[i][j] -= factor * inverse[k][j];
      }
    }
  }
  // (S A S)^{-1} = S^{-1} A^{-1} S^{-1}, so A^{-1} = S (S A S)^{-1} S.
  for (int i = 0; i < size; ++i)
    for (int j = 0; j < size; ++j) inverse[i][j] *= scale[i] * scale[j];
  return {};
}

template <class ExecutionSpaceT>
using DeviceOf = typename CrsMatrix<ExecutionSpaceT>::device_type;
template <class ExecutionSpaceT>
using BlockInverseView = Kokkos::View<double***, Kokkos::LayoutRight, DeviceOf<ExecutionSpaceT>>;
template <class ExecutionSpaceT>
using BlockDiagnosisView = Kokkos::View<int* [2], Kokkos::LayoutRight, DeviceOf<ExecutionSpaceT>>;

// One thread per block: extract, invert, store. Returns the first block that failed, or -1;
// its reason is in diagnoses(block, 0) and the local DOF in diagnoses(block, 1).
template <class ExecutionSpaceT>
LocalIndex invertDiagonalBlocks(const CrsMatrix<ExecutionSpaceT>& A, int blockSize,
                                const BlockInverseView<ExecutionSpaceT>& inverses,
                                const BlockDiagnosisView<ExecutionSpaceT>& diagnoses) {
  const auto rowMap = A.graph.row_map;
  const auto entries = A.graph.entries;
  const auto values = A.values;
  const auto numBlocks = static_cast<LocalIndex>(inverses.extent(0));
  LocalIndex firstFailedBlock = INT_MAX;
  Kokkos::parallel_reduce(
      "perishell::belos::invert_diagonal_blocks", Kokkos::RangePolicy<ExecutionSpaceT>(0, numBlocks),
      KOKKOS_LAMBDA(const LocalIndex blockIndex, LocalIndex& firstFailed) {
        double block[maxBlockSize][maxBlockSize];
        double inverse[maxBlockSize][maxBlockSize];
        extractBlock(rowMap, entries, values, blockIndex * blockSize, blockSize, block);
        const BlockDiagnosis diagnosis = invertBlock(block, blockSize, inverse);
        diagnoses(blockIndex, 0) = diagnosis.condition;
        diagnoses(blockIndex, 1) = diagnosis.localDof;
        for (int i = 0; i < blockSize; ++i)
          for (int j = 0; j < blockSize; ++j)
            inverses(blockIndex, i, j) = diagnosis.condition == BlockInvertible ? inverse[i][j] : 0.0;
        if (diagnosis.condition != BlockInvertible && blockIndex < firstFailed) firstFailed = blockIndex;
      },
      Kokkos::Min<LocalIndex>(firstFailedBlock));
  return firstFailedBlock == INT_MAX ? -1 : firstFailedBlock;
}

// Throws std::runtime_error describing why node's diagonal block could not be inverted.
template <class ExecutionSpaceT>
[[noreturn]] void throwFailedBlock(const std::string& who, LocalIndex node, int blockSize,
                                 const BlockDiagnosisView<ExecutionSpaceT>& diagnoses) {
  const auto diagnosis = Kokkos::create_mirror_view_and_copy(
      Kokkos::HostSpace(), Kokkos::subview(diagnoses, node, Kokkos::ALL()));
  const int dof = diagnosis(1);
  std::ostringstream msg;
  msg << who << ": the diagonal block of node " << node << " (rows " << node * blockSize << " to "
      << (node + 1) * blockSize - 1 << ") ";
  if (diagnosis(0) == BlockNotFinite) {
    msg << "has a NaN or Inf entry in its local DOF " << dof
        << " row: the assembled matrix is not finite there (a degenerate element or a NaN state?)";
  } else {
    msg << (diagnosis(0) == BlockEmptyRow ? "has an all-zero row for its local DOF "
                                          : "is singular (no usable pivot for its local DOF ")
        << dof << (diagnosis(0) == BlockEmptyRow ? "" : ")") << ": node " << node
        << " has no stiffness in some DOF: missing support or a rotation DOF no element touches?";
  }
  throw std::runtime_error(msg.str());
}

// y(row, :) = sum_c B(row / size)(row % size, c) x(first + c, :) with B = inverse or its transpose.
template <class InverseView, class MultiView>
void applyBlockInverse(const InverseView& inverses, bool transposed, const MultiView& x, const MultiView& y) {
  using execution_space = typename InverseView::execution_space;
  const int size = static_cast<int>(inverses.extent(1));
  const int numCols = static_cast<int>(x.extent(1));
  Kokkos::parallel_for(
      "perishell::belos::apply_block_inverse",
      Kokkos::RangePolicy<execution_space>(0, static_cast<std::int64_t>(x.extent(0))),
      KOKKOS_LAMBDA(const std::int64_t row) {
        const auto blockIndex = row / size;
        const int local = static_cast<int>(row % size);
        const auto first = blockIndex * size;
        for (int j = 0; j < numCols; ++j) {
          double sum = 0.0;
          for (int c = 0; c < size; ++c)
            sum += (transposed ? inverses(blockIndex, c, local) : inverses(blockIndex, local, c)) * x(first + c, j);
          y(row, j) = sum;
        }
      });
}

}  // namespace detail

// y = blockdiag(A)^{-1} x for a matrix whose rows come in consecutive groups of blockSize
// (one node's DOF). Applies the transposed block inverses for TRANS, so it also serves a
// nonsymmetric A.
template <class ExecutionSpaceT>
class BlockJacobiPreconditioner final : public Belos::Operator<double> {
  static_assert(Kokkos::is_execution_space<ExecutionSpaceT>::value,
                "BlockJacobiPreconditioner needs a Kokkos execution space");

 public:
  using matrix_type = CrsMatrix<ExecutionSpaceT>;
  using inverse_type = detail::BlockInverseView<ExecutionSpaceT>;

  // Throws std::invalid_argument for a non-square matrix, a block size outside
  // [1, maxBlockSize] or a row count that is not a multiple of it; std::runtime_error naming
  // the node whose diagonal block is singular or not finite.
  BlockJacobiPreconditioner(const matrix_type& A, int blockSize) {
    constexpr const char* who = "perishell::belos::BlockJacobiPreconditioner";
    if (A.numRows() != A.numCols()) {
      throw std::invalid_argument(std::string(who) + ": matrix is " + std::to_string(A.numRows()) + " x " +
                                  std::to_string(A.numCols()) + ", not square");
    }
    if (blockSize < 1 || blockSize > maxBlockSize) {
      throw std::invalid_argument(std::string(who) + ": block size " + std::to_string(blockSize) +
                                  " is outside [1, " + std::to_string(maxBlockSize) + "]");
    }
    if (A.numRows() % blockSize != 0) {
      throw std::invalid_argument(std::string(who) + ": " + std::to_string(A.numRows()) +
                                  " rows are not a whole number of blocks of " + std::to_string(blockSize) +
                                  " DOF per node");
    }
    const auto numBlocks = static_cast<std::size_t>(A.numRows() / blockSize);
    inverses_ = inverse_type(Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::belos::block_inverses"),
                             numBlocks, blockSize, blockSize);
    const detail::BlockDiagnosisView<ExecutionSpaceT> diagnoses(
        Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::belos::block_diagnoses"), numBlocks);
    const LocalIndex failedBlock = detail::invertDiagonalBlocks(A, blockSize, inverses_, diagnoses);
    if (failedBlock >= 0) detail::throwFailedBlock<ExecutionSpaceT>(who, failedBlock, blockSize, diagnoses);
  }

  int blockSize() const { return static_cast<int>(inverses_.extent(1)); }
  // inverses()(node, i, j): entry (i, j) of the inverse of node's diagonal block.
  const inverse_type& inverses() const { return inverses_; }

  void Apply(const Belos::MultiVec<double>& x, Belos::MultiVec<double>& y,
             Belos::ETrans trans = Belos::NOTRANS) const override {
    constexpr const char* who = "perishell::belos::BlockJacobiPreconditioner::Apply";
    const auto& xk = detail::asKokkos<ExecutionSpaceT>(x, who);
    auto& yk = detail::asKokkos<ExecutionSpaceT>(y, who);
    const auto n = inverses_.extent(0) * inverses_.extent(1);
    detail::checkApplyShapes(xk, yk, n, n, who);
    detail::applyBlockInverse(inverses_, trans != Belos::NOTRANS, xk.deviceView(), yk.deviceView());
  }

  bool HasApplyTranspose() const override { return true; }

 private:
  inverse_type inverses_;
};

}  // namespace perishell::belos
