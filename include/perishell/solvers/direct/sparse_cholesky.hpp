#pragma once
// Sparse Cholesky factorization of a tangent stiffness on the host, through CHOLMOD
// (SuiteSparse, Debian's libsuitesparse-dev; the paper's CPU baseline used the same suite's
// UMFPACK). The factor is of the symmetric part (A + A^T) / 2 of a structurally symmetric
// CRS matrix: for the symmetric tangent that is A itself; for the exact, non-symmetric
// tangent (model.md §5) it is the symmetric tangent, a preconditioner GMRES converges with in
// a few iterations.
//
// The fill-reducing ordering and symbolic analysis are done once per pattern; every
// factorize() is numeric only. CHOLMOD first tries a supernodal L L^T; a non-positive pivot
// (the tangent lost positive definiteness: a limit or bifurcation point, or an unstable
// state away from equilibrium) switches it to a simplicial L D L^T, which factors symmetric
// indefinite matrices without pivoting and gives their inertia (the count of negative
// pivots). CHOLMOD itself stays out of this header (pimpl), so only the library links it.
#include <perishell/core/types.hpp>

#include <cstddef>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace perishell::direct {

// The factorization could not be made. The message names what failed.
class FactorizationError : public std::runtime_error {
 public:
  // Singular: a pivot vanished relative to its row's diagonal (singularPivotRatio): the
  // matrix has a null space, a mechanism in a tangent stiffness. Resources: out of memory, or
  // too large for CHOLMOD's sizes. Input: a non-finite entry, or CHOLMOD refused the matrix.
  enum class Kind { Singular, Resources, Input };
  FactorizationError(Kind kind, const std::string& what, long row = -1)
      : std::runtime_error(what), kind_(kind), row_(row) {}
  Kind kind() const { return kind_; }
  long row() const { return row_; }  // the singular row (0-based), or -1

 private:
  Kind kind_;
  long row_;
};

// A pivot d_j with |d_j| <= singularPivotRatio |a_jj| is round-off of a zero: the matrix is
// singular (the test of Nastran's MAXRATIO, at a bound that the conditioning of thin shells,
// whose bending and membrane stiffnesses differ by (L/h)^2, stays far from).
inline constexpr double singularPivotRatio = 1e-12;

struct FactorizationInfo {
  bool positiveDefinite = true;  // L L^T succeeded; false: L D L^T with negativePivots > 0
  long negativePivots = 0;       // inertia of the factored matrix (0 when positive definite)
  double smallestPivotRatio = 0.0;  // min |d_j| / |a_jj| over the rows
  double seconds = 0.0;          // numeric factorization (and, the first time, the analysis)
  double factorEntries = 0.0;    // nonzeros of L
};

class SparseCholesky {
 public:
  SparseCholesky();
  ~SparseCholesky();
  SparseCholesky(const SparseCholesky&) = delete;
  SparseCholesky& operator=(const SparseCholesky&) = delete;

  // The pattern of an n x n CRS matrix (host arrays, rows sorted, structurally symmetric, every
  // diagonal entry present). Throws std::invalid_argument when it is not.
  void setPattern(LocalIndex n, const RowOffset* rowMap, const LocalIndex* columns);
  bool hasPattern() const;

  // The fill-reducing elimination order CHOLMOD chose for the pattern (entry k: the row
  // eliminated k-th), analysed once and kept for factorize(). For a device factorization.
  std::vector<LocalIndex> fillReducingOrdering();

  // Factors (A + A^T) / 2 with A's values in the pattern's CRS order. Throws
  // FactorizationError when no factor could be made (the previous one is then gone); a
  // singular matrix's message names the row (0-based) whose pivot vanished.
  FactorizationInfo factorize(const double* values);
  bool hasFactor() const;

  // x = (L L^T)^{-1} b or (L D L^T)^{-1} b; x and b hold n entries each and may alias.
  void solve(const double* b, double* x) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace perishell::direct
