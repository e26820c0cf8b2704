#pragma once
// Sparse matrix product C = A B and transpose T = P^T for the Galerkin products of smoothed
// aggregation: the patterns once per sparsity pattern on the host (like the aggregates), the
// values on the device at every update, one thread per row or entry and no atomics.
//
// Every matrix of the hierarchy has the nodal block layout of the tangent
// (assembly/nodal_block_crs.hpp): the 6 rows of a node (or aggregate) share one sorted
// column pattern made of whole, aligned groups of 6 columns. The product runs over those
// 6x6 blocks: one search for a block of C per pair of blocks multiplied, where a scalar
// product searched once per scalar term (216 times as often); on the pressed plate 4.2.1
// the Galerkin products were 70-75 % of the set-up (docs/implicit.md).
//
// Kokkos Kernels 3.4's spgemm is not used: on the H100 (sm_90, CUDA 13) every device variant
// (SPGEMM_KK, _KK_MEMORY, _KK_DENSE, _KK_LP, _KK_SPEED, _KK_MEMORY_SORTED) wrote out of bounds
// or returned a wrong product for these matrices, and only its host fallback was right
// (tstSmoothedAggregation's consistency tests, 2026-11-22).
#include <perishell/core/types.hpp>
#include <perishell/solvers/belos/crs_operator.hpp>

#include <Kokkos_Core.hpp>

#include <algorithm>
#include <stdexcept>
#include <string>
#include <vector>

namespace perishell::multigrid {

inline constexpr int dofPerNode = 6;

// Whether a CRS pattern (host views) has the nodal block layout: rows and columns in groups
// of dofPerNode, the rows of a group with one column pattern of whole aligned column groups.
template <class RowMapView, class ColumnView>
bool hasNodalBlockLayout(const RowMapView& rows, const ColumnView& columns, LocalIndex numRows, LocalIndex numCols) {
  if (numRows % dofPerNode != 0 || numCols % dofPerNode != 0) return false;
  for (LocalIndex first = 0; first < numRows; first += dofPerNode) {
    const RowOffset begin = rows(first), length = rows(first + 1) - rows(first);
    if (length % dofPerNode != 0) return false;
    for (RowOffset k = 0; k < length; k += dofPerNode)
      for (int c = 0; c < dofPerNode; ++c)
        if (columns(begin + k + c) != columns(begin + k) + c || (c == 0 && columns(begin + k) % dofPerNode != 0))
          return false;
    for (int r = 1; r < dofPerNode; ++r) {
      const RowOffset other = rows(first + r);
      if (rows(first + r + 1) - other != length) return false;
      for (RowOffset k = 0; k < length; ++k)
        if (columns(other + k) != columns(begin + k)) return false;
    }
  }
  return true;
}

// C's pattern with rows sorted and zero values: column j is in row i when some A(i, k) and
// B(k, j) are both stored (structural, whatever their values).
template <class ExecutionSpaceT>
belos::CrsMatrix<ExecutionSpaceT> productPattern(const belos::CrsMatrix<ExecutionSpaceT>& A,
                                                 const belos::CrsMatrix<ExecutionSpaceT>& B, const std::string& label) {
  using Matrix = belos::CrsMatrix<ExecutionSpaceT>;
  const auto aRows = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, A.graph.row_map);
  const auto aColumns = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, A.graph.entries);
  const auto bRows = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, B.graph.row_map);
  const auto bColumns = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, B.graph.entries);
  const LocalIndex numRows = A.numRows(), numCols = B.numCols();
  if (A.numCols() != B.numRows() || !hasNodalBlockLayout(aRows, aColumns, numRows, A.numCols()) ||
      !hasNodalBlockLayout(bRows, bColumns, B.numRows(), numCols))
    throw std::invalid_argument("perishell::multigrid::productPattern (" + label +
                                "): the factors need matching sizes and the nodal block layout");
  std::vector<RowOffset> rowMap{0};
  rowMap.reserve(numRows + 1);
  std::vector<LocalIndex> columns;
  std::vector<LocalIndex> lastRowWith(numCols, -1);
  for (LocalIndex row = 0; row < numRows; ++row) {
    const std::size_t first = columns.size();
    for (RowOffset a = aRows(row); a < aRows(row + 1); ++a) {
      const LocalIndex k = aColumns(a);
      for (RowOffset b = bRows(k); b < bRows(k + 1); ++b) {
        const LocalIndex column = bColumns(b);
        if (lastRowWith[column] == row) continue;
        lastRowWith[column] = row;
        columns.push_back(column);
      }
    }
    std::sort(columns.begin() + first, columns.end());
    rowMap.push_back(columns.size());
  }
  typename Matrix::row_map_type::non_const_type deviceRowMap(label + " row map", rowMap.size());
  typename Matrix::index_type::non_const_type deviceColumns(label + " entries", columns.size());
  Kokkos::deep_copy(deviceRowMap, Kokkos::View<const RowOffset*, Kokkos::HostSpace, Kokkos::MemoryTraits<Kokkos::Unmanaged>>(
                                      rowMap.data(), rowMap.size()));
  Kokkos::deep_copy(deviceColumns, Kokkos::View<const LocalIndex*, Kokkos::HostSpace, Kokkos::MemoryTraits<Kokkos::Unmanaged>>(
                                       columns.data(), columns.size()));
  typename Matrix::values_type::non_const_type values(label + " values", columns.size());
  return Matrix(label, numRows, numCols, static_cast<RowOffset>(columns.size()), values, deviceRowMap, deviceColumns);
}

// C's values = A B, for C from productPattern(A, B) (the same patterns of A and B), block by
// block: the thread of row r of a block row takes row r of A's blocks times B's blocks.
template <class ExecutionSpaceT>
void multiplyInto(const ExecutionSpaceT& space, const belos::CrsMatrix<ExecutionSpaceT>& A,
                  const belos::CrsMatrix<ExecutionSpaceT>& B, const belos::CrsMatrix<ExecutionSpaceT>& C) {
  const auto aRows = A.graph.row_map;
  const auto aColumns = A.graph.entries;
  const auto aValues = A.values;
  const auto bRows = B.graph.row_map;
  const auto bColumns = B.graph.entries;
  const auto bValues = B.values;
  const auto cRows = C.graph.row_map;
  const auto cColumns = C.graph.entries;
  const auto cValues = C.values;
  Kokkos::parallel_for(
      "perishell::amg::sparse_product", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, C.numRows()),
      KOKKOS_LAMBDA(const LocalIndex row) {
        const RowOffset cFirst = cRows(row);
        const LocalIndex cBlocks = static_cast<LocalIndex>((cRows(row + 1) - cFirst) / dofPerNode);
        for (RowOffset c = cFirst; c < cRows(row + 1); ++c) cValues(c) = 0.0;
        for (RowOffset a = aRows(row); a < aRows(row + 1); a += dofPerNode) {
          double aRow[dofPerNode];
          for (int m = 0; m < dofPerNode; ++m) aRow[m] = aValues(a + m);
          // B's block row k: its dofPerNode rows have one length.
          const LocalIndex k = aColumns(a);
          const RowOffset bFirst = bRows(k), bLength = bRows(k + 1) - bFirst;
          for (RowOffset b = 0; b < bLength; b += dofPerNode) {
            // Binary search of the block in C's sorted row (it is there by construction).
            const LocalIndex column = bColumns(bFirst + b);
            LocalIndex low = 0, high = cBlocks;
            while (high - low > 1) {
              const LocalIndex middle = low + (high - low) / 2;
              if (cColumns(cFirst + dofPerNode * static_cast<RowOffset>(middle)) <= column) low = middle;
              else high = middle;
            }
            double sum[dofPerNode] = {};
            for (int m = 0; m < dofPerNode; ++m)
              for (int c = 0; c < dofPerNode; ++c) sum[c] += aRow[m] * bValues(bFirst + m * bLength + b + c);
            const RowOffset at = cFirst + dofPerNode * static_cast<RowOffset>(low);
            for (int c = 0; c < dofPerNode; ++c) cValues(at + c) += sum[c];
          }
        }
      });
}

// P^T's pattern with rows sorted, and for each of its entries the index of the same entry in
// P's values, so that the transposition at every update is a gather (transposeInto).
template <class ExecutionSpaceT>
struct Transposition {
  belos::CrsMatrix<ExecutionSpaceT> transpose;
  Kokkos::View<RowOffset*, typename belos::CrsMatrix<ExecutionSpaceT>::device_type> sourceEntry;
};

template <class ExecutionSpaceT>
Transposition<ExecutionSpaceT> transposePattern(const belos::CrsMatrix<ExecutionSpaceT>& P, const std::string& label) {
  using Matrix = belos::CrsMatrix<ExecutionSpaceT>;
  const auto pRows = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, P.graph.row_map);
  const auto pColumns = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, P.graph.entries);
  const LocalIndex numRows = P.numCols();
  typename Matrix::row_map_type::non_const_type rowMap(label + " row map", numRows + 1);
  typename Matrix::index_type::non_const_type columns(label + " entries", P.nnz());
  Transposition<ExecutionSpaceT> result;
  result.sourceEntry = decltype(result.sourceEntry)(label + " source entries", P.nnz());
  const auto hostRowMap = Kokkos::create_mirror_view(rowMap);
  const auto hostColumns = Kokkos::create_mirror_view(columns);
  const auto hostSource = Kokkos::create_mirror_view(result.sourceEntry);
  Kokkos::deep_copy(hostRowMap, RowOffset(0));
  for (RowOffset k = 0; k < P.nnz(); ++k) ++hostRowMap(pColumns(k) + 1);
  for (LocalIndex row = 0; row < numRows; ++row) hostRowMap(row + 1) += hostRowMap(row);
  std::vector<RowOffset> next(hostRowMap.data(), hostRowMap.data() + numRows);
  // P's rows in ascending order, so every row of P^T comes out sorted.
  for (LocalIndex pRow = 0; pRow < P.numRows(); ++pRow)
    for (RowOffset k = pRows(pRow); k < pRows(pRow + 1); ++k) {
      const RowOffset slot = next[pColumns(k)]++;
      hostColumns(slot) = pRow;
      hostSource(slot) = k;
    }
  Kokkos::deep_copy(rowMap, hostRowMap);
  Kokkos::deep_copy(columns, hostColumns);
  Kokkos::deep_copy(result.sourceEntry, hostSource);
  typename Matrix::values_type::non_const_type values(label + " values", P.nnz());
  result.transpose = Matrix(label, numRows, P.numRows(), P.nnz(), values, rowMap, columns);
  return result;
}

// T's values = P's, for T from transposePattern(P).
template <class ExecutionSpaceT>
void transposeInto(const ExecutionSpaceT& space, const belos::CrsMatrix<ExecutionSpaceT>& P,
                   const Transposition<ExecutionSpaceT>& T) {
  const auto source = T.sourceEntry;
  const auto from = P.values;
  const auto to = T.transpose.values;
  Kokkos::parallel_for(
      "perishell::amg::transpose", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, source.extent(0)),
      KOKKOS_LAMBDA(const RowOffset k) { to(k) = from(source(k)); });
}

}  // namespace perishell::multigrid
