#include <perishell/solvers/direct/sparse_cholesky.hpp>

#include <cholmod.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

namespace perishell::direct {

namespace {

using Long = SuiteSparse_long;

FactorizationError::Kind kindOf(const cholmod_common& common) {
  return common.status == CHOLMOD_OUT_OF_MEMORY || common.status == CHOLMOD_TOO_LARGE
             ? FactorizationError::Kind::Resources
             : FactorizationError::Kind::Input;
}

std::string statusText(const cholmod_common& common) {
  switch (common.status) {
    case CHOLMOD_OUT_OF_MEMORY:
      return "out of memory (the factor needs about " + std::to_string(static_cast<long long>(common.lnz)) +
             " nonzeros, " + std::to_string(static_cast<long long>(common.lnz * 12.0 / 1048576.0)) + " MiB)";
    case CHOLMOD_TOO_LARGE: return "the factor is too large for CHOLMOD's integer sizes";
    case CHOLMOD_INVALID: return "CHOLMOD refused the matrix (invalid input)";
    case CHOLMOD_NOT_INSTALLED: return "a CHOLMOD module is missing";
    default: return "CHOLMOD status " + std::to_string(common.status);
  }
}

}  // namespace

struct SparseCholesky::Impl {
  cholmod_common common{};
  cholmod_sparse* lower = nullptr;       // (A + A^T) / 2, lower triangle, CSC
  cholmod_factor* supernodal = nullptr;  // L L^T
  cholmod_factor* simplicial = nullptr;  // L D L^T, analysed when first needed
  cholmod_factor* active = nullptr;
  // Per entry of `lower`: the CRS slots of A(j, i) and A(i, j) averaged into it.
  std::vector<RowOffset> slot, transposeSlot;
  mutable cholmod_dense* x = nullptr;
  mutable cholmod_dense* y = nullptr;
  mutable cholmod_dense* e = nullptr;
  LocalIndex n = 0;

  Impl() {
    cholmod_l_start(&common);
    common.print = 0;  // failures are reported through exceptions, in the caller's terms
  }
  ~Impl() {
    freeFactors();
    cholmod_l_free_sparse(&lower, &common);
    cholmod_l_free_dense(&x, &common);
    cholmod_l_free_dense(&y, &common);
    cholmod_l_free_dense(&e, &common);
    cholmod_l_finish(&common);
  }
  void freeFactors() {
    cholmod_l_free_factor(&supernodal, &common);
    cholmod_l_free_factor(&simplicial, &common);
    active = nullptr;
  }

  cholmod_factor* analyse(int method) {
    common.supernodal = method;
    common.final_ll = method == CHOLMOD_SUPERNODAL;
    cholmod_factor* factor = cholmod_l_analyze(lower, &common);
    if (factor == nullptr)
      throw FactorizationError(kindOf(common), "the symbolic analysis failed: " + statusText(common));
    return factor;
  }

  // Returns the column of the first non-positive pivot, or n when the factor is complete.
  Long numeric(cholmod_factor* factor) {
    common.supernodal = factor == supernodal ? CHOLMOD_SUPERNODAL : CHOLMOD_SIMPLICIAL;
    common.final_ll = factor == supernodal;
    if (!cholmod_l_factorize(lower, factor, &common) ||
        (common.status < CHOLMOD_OK && common.status != CHOLMOD_NOT_POSDEF))
      throw FactorizationError(kindOf(common), "the numeric factorization failed: " + statusText(common));
    return common.status == CHOLMOD_NOT_POSDEF ? factor->minor : Long(n);
  }
};

SparseCholesky::SparseCholesky() : impl_(std::make_unique<Impl>()) {}
SparseCholesky::~SparseCholesky() = default;

bool SparseCholesky::hasPattern() const { return impl_->lower != nullptr; }
bool SparseCholesky::hasFactor() const { return impl_->active != nullptr; }

void SparseCholesky::setPattern(LocalIndex n, const RowOffset* rowMap, const LocalIndex* columns) {
  auto& m = *impl_;
  m.freeFactors();
  cholmod_l_free_sparse(&m.lower, &m.common);
  m.slot.clear();
  m.transposeSlot.clear();
  m.n = n;
  // The slot of A(i, j) in row i (rows sorted: binary search).
  auto find = [&](LocalIndex i, LocalIndex j) -> RowOffset {
    const LocalIndex* first = columns + rowMap[i];
    const LocalIndex* last = columns + rowMap[i + 1];
    const LocalIndex* hit = std::lower_bound(first, last, j);
    if (hit == last || *hit != j)
      throw std::invalid_argument("perishell::direct::SparseCholesky: the matrix pattern is not symmetric: entry (" +
                                  std::to_string(j) + ", " + std::to_string(i) + ") has no entry (" +
                                  std::to_string(i) + ", " + std::to_string(j) + ")");
    return rowMap[i] + RowOffset(hit - first);
  };
  std::vector<Long> columnStart(std::size_t(n) + 1, 0);
  for (LocalIndex j = 0; j < n; ++j) {
    if (!std::is_sorted(columns + rowMap[j], columns + rowMap[j + 1]))
      throw std::invalid_argument("perishell::direct::SparseCholesky: row " + std::to_string(j) + " is not sorted");
    find(j, j);  // every diagonal entry is present
    for (RowOffset k = rowMap[j]; k < rowMap[j + 1]; ++k) {
      const LocalIndex i = columns[k];
      if (i < j) continue;
      m.slot.push_back(k);
      m.transposeSlot.push_back(find(i, j));
    }
    columnStart[j + 1] = Long(m.slot.size());
  }
  m.lower = cholmod_l_allocate_sparse(n, n, m.slot.size(), /*sorted*/ 1, /*packed*/ 1, /*stype: lower*/ -1, CHOLMOD_REAL,
                                      &m.common);
  if (m.lower == nullptr) throw FactorizationError(kindOf(m.common), "cannot store the matrix: " + statusText(m.common));
  std::memcpy(m.lower->p, columnStart.data(), columnStart.size() * sizeof(Long));
  auto* rows = static_cast<Long*>(m.lower->i);
  for (std::size_t k = 0; k < m.slot.size(); ++k) rows[k] = columns[m.slot[k]];
}

std::vector<LocalIndex> SparseCholesky::fillReducingOrdering() {
  auto& m = *impl_;
  if (m.lower == nullptr) throw std::logic_error("perishell::direct::SparseCholesky: ordering before setPattern");
  if (m.supernodal == nullptr) m.supernodal = m.analyse(CHOLMOD_SUPERNODAL);
  const auto* perm = static_cast<const Long*>(m.supernodal->Perm);
  return std::vector<LocalIndex>(perm, perm + m.n);
}

FactorizationInfo SparseCholesky::factorize(const double* values) {
  auto& m = *impl_;
  if (m.lower == nullptr) throw std::logic_error("perishell::direct::SparseCholesky: factorize before setPattern");
  const auto start = std::chrono::steady_clock::now();
  auto* x = static_cast<double*>(m.lower->x);
  for (std::size_t k = 0; k < m.slot.size(); ++k) {
    x[k] = 0.5 * (values[m.slot[k]] + values[m.transposeSlot[k]]);
    if (!std::isfinite(x[k]))
      throw FactorizationError(FactorizationError::Kind::Input,
                               "the matrix has a non-finite entry at value slot " + std::to_string(m.slot[k]));
  }
  m.active = nullptr;
  FactorizationInfo info;
  if (m.supernodal == nullptr) m.supernodal = m.analyse(CHOLMOD_SUPERNODAL);
  cholmod_factor* factor = m.supernodal;
  if (m.numeric(m.supernodal) != Long(m.n)) {
    // Not positive definite: L D L^T, simplicial (CHOLMOD's supernodal form is L L^T only).
    if (m.simplicial == nullptr) m.simplicial = m.analyse(CHOLMOD_SIMPLICIAL);
    factor = m.simplicial;
    const Long zeroPivot = m.numeric(m.simplicial);
    if (zeroPivot != Long(m.n))
    {
      const Long row = static_cast<const Long*>(factor->Perm)[zeroPivot];
      throw FactorizationError(FactorizationError::Kind::Singular,
                               "the matrix is singular: zero pivot at row " + std::to_string(row), row);
    }
    info.positiveDefinite = false;
  }
  // Pivots d_j (L L^T: l_jj^2; L D L^T: D(j, j)) of row Perm[j], against that row's diagonal
  // (the first entry of its column in `lower`).
  const auto* perm = static_cast<const Long*>(factor->Perm);
  const auto* lowerStart = static_cast<const Long*>(m.lower->p);
  info.smallestPivotRatio = std::numeric_limits<double>::infinity();
  auto checkPivot = [&](Long j, double pivot) {
    const Long row = perm[j];
    const double ratio = std::abs(pivot) / std::abs(x[lowerStart[row]]);
    if (!std::isfinite(pivot) || pivot == 0.0 || ratio <= singularPivotRatio)
      throw FactorizationError(FactorizationError::Kind::Singular,
                               "the matrix is singular: the pivot of row " + std::to_string(row) + " is " +
                                   std::to_string(ratio) + " times its diagonal",
                               row);
    info.smallestPivotRatio = std::min(info.smallestPivotRatio, ratio);
    if (pivot < 0.0) ++info.negativePivots;
  };
  const auto* factorValues = static_cast<const double*>(factor->x);
  if (factor->is_super) {
    const auto* super = static_cast<const Long*>(factor->super);
    const auto* rowStart = static_cast<const Long*>(factor->pi);
    const auto* valueStart = static_cast<const Long*>(factor->px);
    for (std::size_t s = 0; s < factor->nsuper; ++s) {
      const Long rows = rowStart[s + 1] - rowStart[s];  // a supernode is a dense rows x columns block
      for (Long j = super[s]; j < super[s + 1]; ++j) {
        const double diagonal = factorValues[valueStart[s] + (j - super[s]) * (rows + 1)];
        checkPivot(j, diagonal * diagonal);
      }
    }
  } else {
    const auto* columnStart = static_cast<const Long*>(factor->p);
    for (Long j = 0; j < Long(m.n); ++j) checkPivot(j, factorValues[columnStart[j]]);  // D(j, j) leads column j
  }
  m.active = factor;
  info.factorEntries = m.common.lnz;
  info.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return info;
}

void SparseCholesky::solve(const double* b, double* x) const {
  auto& m = *impl_;
  if (m.active == nullptr) throw std::logic_error("perishell::direct::SparseCholesky: solve without a factor");
  cholmod_dense rhs{};
  rhs.nrow = rhs.d = rhs.nzmax = std::size_t(m.n);
  rhs.ncol = 1;
  rhs.x = const_cast<double*>(b);  // read only
  rhs.xtype = CHOLMOD_REAL;
  rhs.dtype = CHOLMOD_DOUBLE;
  if (!cholmod_l_solve2(CHOLMOD_A, m.active, &rhs, nullptr, &m.x, nullptr, &m.y, &m.e, &m.common))
    throw FactorizationError(kindOf(m.common), "the triangular solves failed: " + statusText(m.common));
  std::memcpy(x, m.x->x, std::size_t(m.n) * sizeof(double));
}

}  // namespace perishell::direct
