#pragma once
// The coarsest level of the smoothed-aggregation hierarchy (up to ~1000 DOF) inverted densely
// where the hierarchy lives, so a hierarchy rebuilt on the GPU copies no matrix to the host
// and back (issue 21, item 3). The V-cycle applies the inverse as one dense matrix-vector
// product, which is far faster on a GPU than two triangular solves of hundreds of
// sequential steps.
//
// The matrix is first scaled symmetrically to a unit diagonal, S = s A s with
// s_i = 1 / sqrt(a_ii), so that the singularity test does not depend on units. A symmetric
// matrix (the tangent CG solves with) must be positive definite: it is inverted by the
// symmetric sweep operator, one pivot per device-wide rank-1 update, without pivoting; its
// pivots are those of its Cholesky factorization, all positive exactly when it is. A
// non-symmetric one (the exact tangent under applied moments, solved by GMRES) need only be
// non-singular: Gauss-Jordan with partial pivoting in one team. Either way the inverse is
// accepted only when its reciprocal condition number 1 / (|S|_1 |S^-1|_1), computed exactly
// from the inverse, exceeds belos::detail::singularPivot.
#include <perishell/core/types.hpp>
#include <perishell/solvers/belos/block_jacobi.hpp>
#include <perishell/solvers/belos/crs_operator.hpp>

#include <Kokkos_Core.hpp>

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace perishell::multigrid {

namespace detail {

// The kernels below are free functions: nvcc takes no device lambda in a private member.
template <class ExecutionSpaceT>
using CoarseDense = Kokkos::View<double**, Kokkos::LayoutRight, typename belos::CrsMatrix<ExecutionSpaceT>::device_type>;
template <class ExecutionSpaceT>
using CoarseScale = Kokkos::View<double*, typename belos::CrsMatrix<ExecutionSpaceT>::device_type>;

// work = s A s (dense) with s_i = 1 / sqrt(a_ii) (1 where a_ii <= 0), inverse = I.
template <class ExecutionSpaceT>
void scaleToUnitDiagonal(const ExecutionSpaceT& space, const belos::CrsMatrix<ExecutionSpaceT>& A,
                         const CoarseScale<ExecutionSpaceT>& scale, const CoarseDense<ExecutionSpaceT>& work,
                         const CoarseDense<ExecutionSpaceT>& inverse) {
  const auto rowMap = A.graph.row_map;
  const auto entries = A.graph.entries;
  const auto values = A.values;
  const LocalIndex n = A.numRows();
  Kokkos::parallel_for(
      "perishell::amg::coarse_diagonal_scale", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, n),
      KOKKOS_LAMBDA(const LocalIndex row) {
        double diagonal = 0.0;
        for (RowOffset k = rowMap(row); k < rowMap(row + 1); ++k)
          if (entries(k) == row) diagonal += values(k);
        scale(row) = diagonal > 0.0 ? 1.0 / Kokkos::Experimental::sqrt(diagonal) : 1.0;
      });
  Kokkos::parallel_for(
      "perishell::amg::coarse_densify", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, n),
      KOKKOS_LAMBDA(const LocalIndex row) {
        for (LocalIndex column = 0; column < n; ++column) {
          work(row, column) = 0.0;
          inverse(row, column) = row == column ? 1.0 : 0.0;
        }
        for (RowOffset k = rowMap(row); k < rowMap(row + 1); ++k)
          work(row, entries(k)) += scale(row) * values(k) * scale(entries(k));
      });
}

// |M|_F, or with transposeDifference |M - M^T|_F
template <class ExecutionSpaceT>
double frobeniusNorm(const ExecutionSpaceT& space, const CoarseDense<ExecutionSpaceT>& M, bool transposeDifference) {
  const LocalIndex n = static_cast<LocalIndex>(M.extent(0));
  double sum = 0.0;
  Kokkos::parallel_reduce(
      "perishell::amg::coarse_frobenius_norm", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, n),
      KOKKOS_LAMBDA(const LocalIndex row, double& partial) {
        for (LocalIndex column = 0; column < n; ++column) {
          const double entry = M(row, column) - (transposeDifference ? M(column, row) : 0.0);
          partial += entry * entry;
        }
      },
      sum);
  return std::sqrt(sum);
}

// M = (M + M^T) / 2, so that round-off asymmetry cannot make the V-cycle non-symmetric.
template <class ExecutionSpaceT>
void symmetrize(const ExecutionSpaceT& space, const CoarseDense<ExecutionSpaceT>& M) {
  const LocalIndex n = static_cast<LocalIndex>(M.extent(0));
  Kokkos::parallel_for(
      "perishell::amg::coarse_symmetrize", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, n),
      KOKKOS_LAMBDA(const LocalIndex row) {
        for (LocalIndex column = row + 1; column < n; ++column) {
          const double mean = 0.5 * (M(row, column) + M(column, row));
          M(row, column) = mean;
          M(column, row) = mean;
        }
      });
}

// max_j sum_i |M_ij|; NaN when M holds one.
template <class ExecutionSpaceT>
double oneNorm(const ExecutionSpaceT& space, const CoarseDense<ExecutionSpaceT>& M) {
  const LocalIndex n = static_cast<LocalIndex>(M.extent(0));
  double norm = 0.0;
  Kokkos::parallel_reduce(
      "perishell::amg::coarse_one_norm", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, n),
      KOKKOS_LAMBDA(const LocalIndex column, double& largest) {
        double sum = 0.0;
        for (LocalIndex row = 0; row < n; ++row) sum += Kokkos::Experimental::fabs(M(row, column));
        if (!(sum <= largest)) largest = sum;
      },
      Kokkos::Max<double>(norm));
  return norm;
}

struct EliminationFailure {
  LocalIndex step = -1;  // the elimination step whose pivot failed, -1 for none
  double pivot = 0.0;
};

template <class ExecutionSpaceT>
using EliminationFailureView = Kokkos::View<double[2], typename CoarseDense<ExecutionSpaceT>::device_type>;

// Gauss-Jordan with partial pivoting on [work | inverse] (inverse = I on entry, work^-1 on
// return) in one team, for the non-symmetric coarse matrix of the exact tangent: its threads
// share each step's entries, consecutive threads on consecutive columns of a row (coalesced on
// a GPU), a barrier between steps; a pivot's magnitude must exceed singularPivot. failure:
// where the failed step and its pivot are written (step -1 for none).
template <class ExecutionSpaceT>
EliminationFailure gaussJordan(const ExecutionSpaceT& space, const CoarseDense<ExecutionSpaceT>& work,
                               const CoarseDense<ExecutionSpaceT>& inverse,
                               const EliminationFailureView<ExecutionSpaceT>& failure) {
  using Policy = Kokkos::TeamPolicy<ExecutionSpaceT>;
  using Member = typename Policy::member_type;
  using Location = Kokkos::MaxLoc<double, LocalIndex>;
  const LocalIndex n = static_cast<LocalIndex>(work.extent(0));
  const double tiny = belos::detail::singularPivot;
  const auto kernel = KOKKOS_LAMBDA(const Member& member) {
    for (LocalIndex step = 0; step < n; ++step) {
      {
        typename Location::value_type largest;
        Kokkos::parallel_reduce(
            Kokkos::TeamThreadRange(member, step, n),
            [&](const LocalIndex row, typename Location::value_type& partial) {
              const double magnitude = Kokkos::Experimental::fabs(work(row, step));
              if (magnitude > partial.val) {
                partial.val = magnitude;
                partial.loc = row;
              }
            },
            Location(largest));
        const LocalIndex pivotRow = largest.val > 0.0 ? largest.loc : step;
        if (pivotRow != step)
          Kokkos::parallel_for(Kokkos::TeamThreadRange(member, n), [&](const LocalIndex column) {
            const double w = work(step, column), x = inverse(step, column);
            work(step, column) = work(pivotRow, column);
            inverse(step, column) = inverse(pivotRow, column);
            work(pivotRow, column) = w;
            inverse(pivotRow, column) = x;
          });
        member.team_barrier();
      }
      const double pivot = work(step, step);
      if (!(Kokkos::Experimental::fabs(pivot) > tiny)) {
        Kokkos::single(Kokkos::PerTeam(member), [&]() {
          failure(0) = static_cast<double>(step);
          failure(1) = pivot;
        });
        return;
      }
      // Row `step` divided by the pivot. Work's columns left of the pivot are zero; column
      // `step` of work is never read again.
      const LocalIndex workColumns = n - step - 1;
      const LocalIndex inverseColumns = n;
      const LocalIndex width = workColumns + inverseColumns;
      Kokkos::parallel_for(Kokkos::TeamThreadRange(member, width), [&](const LocalIndex c) {
        if (c < workColumns)
          work(step, step + 1 + c) /= pivot;
        else
          inverse(step, c - workColumns) /= pivot;
      });
      member.team_barrier();
      Kokkos::parallel_for(Kokkos::TeamThreadRange(member, n * width), [&](const LocalIndex index) {
        const LocalIndex row = index / width, c = index % width;
        if (row == step) return;
        const double factor = work(row, step);
        if (c < workColumns)
          work(row, step + 1 + c) -= factor * work(step, step + 1 + c);
        else
          inverse(row, c - workColumns) -= factor * inverse(step, c - workColumns);
      });
      member.team_barrier();
    }
    Kokkos::single(Kokkos::PerTeam(member), [&]() { failure(0) = -1.0; });
  };
  const int teamSize = std::min(Policy(space, 1, 1).team_size_max(kernel, Kokkos::ParallelForTag()), 512);
  Kokkos::parallel_for("perishell::amg::coarse_gauss_jordan", Policy(space, 1, teamSize), kernel);
  const auto host = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), failure);
  EliminationFailure result;
  result.step = static_cast<LocalIndex>(host(0));
  result.pivot = host(1);
  return result;
}

// The symmetric sweep operator (Goodnight 1979; Beaton 1964) on the upper triangle of the
// unit-diagonal scaled S, in place: sweeping pivot k replaces M_ij by M_ij - M_ik M_kj / d for
// i, j != k, row and column k by M_kj / d and M_kk by -1 / d, with d = M_kk; after every
// pivot M = -S^-1. The pivots are those of S's Cholesky factorization, so a positive
// definite S has all of them above singularPivot and an indefinite or singular one fails.
// Each step is a rank-1 update over the whole device (one launch per pivot: a matrix of
// ~1000 rows no longer waits on one team). Column k enters step k as a copy (columns, two
// buffers of n); step k writes column k + 1 into the other buffer, so no entry is read after
// another thread wrote it. A failed step skips every later one.
template <class ExecutionSpaceT>
EliminationFailure sweepSymmetric(const ExecutionSpaceT& space, const CoarseDense<ExecutionSpaceT>& M,
                                  const CoarseDense<ExecutionSpaceT>& columns,
                                  const EliminationFailureView<ExecutionSpaceT>& failure) {
  using Policy = Kokkos::TeamPolicy<ExecutionSpaceT>;
  using Member = typename Policy::member_type;
  const LocalIndex n = static_cast<LocalIndex>(M.extent(0));
  const double tiny = belos::detail::singularPivot;
  Kokkos::parallel_for(
      "perishell::amg::coarse_sweep_start", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, n),
      KOKKOS_LAMBDA(const LocalIndex row) {
        columns(0, row) = M(row, 0);
        if (row == 0) failure(0) = -1.0;
      });
  for (LocalIndex step = 0; step < n; ++step) {
    const int current = step % 2, next = 1 - current;
    Kokkos::parallel_for(
        "perishell::amg::coarse_sweep", Policy(space, n, Kokkos::AUTO),
        KOKKOS_LAMBDA(const Member& member) {
          if (failure(0) >= 0.0) return;
          const double pivot = columns(current, step);
          const LocalIndex row = member.league_rank();
          if (!(pivot > tiny)) {
            Kokkos::single(Kokkos::PerTeam(member), [&]() {
              if (row == 0) {
                failure(0) = static_cast<double>(step);
                failure(1) = pivot;
              }
            });
            return;
          }
          const double reciprocal = 1.0 / pivot;
          if (row == step) {
            Kokkos::parallel_for(Kokkos::TeamThreadRange(member, row + 1, n), [&](const LocalIndex column) {
              M(row, column) = columns(current, column) * reciprocal;
            });
          } else {
            const double factor = columns(current, row) * reciprocal;
            Kokkos::parallel_for(Kokkos::TeamThreadRange(member, row, n), [&](const LocalIndex column) {
              M(row, column) -= factor * columns(current, column);
            });
          }
          member.team_barrier();
          Kokkos::single(Kokkos::PerTeam(member), [&]() {
            if (row == step) M(row, row) = -reciprocal;
            if (row < step) M(row, step) = columns(current, row) * reciprocal;
            if (row <= step + 1 && step + 1 < n) columns(next, row) = M(row, step + 1);
          });
          if (row == step + 1)
            Kokkos::parallel_for(Kokkos::TeamThreadRange(member, row + 1, n),
                                 [&](const LocalIndex column) { columns(next, column) = M(row, column); });
        });
  }
  const auto host = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), failure);
  return {static_cast<LocalIndex>(host(0)), host(1)};
}

// inverse = s X s with X the negated upper triangle of `result`, mirrored, where fromSweep
// (S^-1 from the sweep's -S^-1), else `result` itself (may be `inverse`); s = 1 where scale
// is empty.
template <class ExecutionSpaceT>
void finishInverse(const ExecutionSpaceT& space, const CoarseDense<ExecutionSpaceT>& result, bool fromSweep,
                   const CoarseScale<ExecutionSpaceT>& scale, const CoarseDense<ExecutionSpaceT>& inverse) {
  const LocalIndex n = static_cast<LocalIndex>(result.extent(0));
  const bool scaled = scale.extent(0) > 0;
  Kokkos::parallel_for(
      "perishell::amg::coarse_finish_inverse", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, n),
      KOKKOS_LAMBDA(const LocalIndex row) {
        for (LocalIndex column = 0; column < n; ++column) {
          const double entry =
              fromSweep ? -(column >= row ? result(row, column) : result(column, row)) : result(row, column);
          inverse(row, column) = scaled ? scale(row) * scale(column) * entry : entry;  // symmetric bit for bit
        }
      });
}

}  // namespace detail

template <class ExecutionSpaceT>
class CoarseInverse {
 public:
  using matrix_type = belos::CrsMatrix<ExecutionSpaceT>;
  using dense_type = detail::CoarseDense<ExecutionSpaceT>;

  // A^-1 of the small CRS matrix A (the hierarchy's coarsest level, numbered level in
  // messages). Throws std::runtime_error for NaN/Inf entries, a singular matrix, or a
  // symmetric one that is not positive definite, with a hint to check the supports.
  void compute(const ExecutionSpaceT& space, const matrix_type& A, int level) {
    const LocalIndex n = A.numRows();
    if (inverse_.extent(0) != static_cast<std::size_t>(n)) {
      inverse_ = dense_type("perishell::amg::coarse_inverse", n, n);
      work_ = dense_type("perishell::amg::coarse_work", n, n);
      scale_ = detail::CoarseScale<ExecutionSpaceT>("perishell::amg::coarse_scale", n);
      columns_ = dense_type("perishell::amg::coarse_sweep_columns", 2, n);
    }
    detail::scaleToUnitDiagonal(space, A, scale_, work_, inverse_);
    const double norm = detail::frobeniusNorm(space, work_, false);
    if (!std::isfinite(norm))
      throw std::runtime_error(std::string(who) + ": the coarse matrix (level " + std::to_string(level) +
                               ") has NaN or Inf entries");
    const bool symmetric = detail::frobeniusNorm(space, work_, true) <= 1e-12 * norm;
    if (symmetric) detail::symmetrize(space, work_);
    const double normOfScaled = detail::oneNorm(space, work_);
    detail::EliminationFailure failure;
    if (symmetric) {
      failure = detail::sweepSymmetric(space, work_, columns_, failure_);
      if (failure.step < 0) detail::finishInverse(space, work_, true, {}, inverse_);
    } else {
      failure = detail::gaussJordan(space, work_, inverse_, failure_);
    }
    double rcond = 0.0;
    if (failure.step < 0) {
      const double normOfInverse = detail::oneNorm(space, inverse_);
      rcond = std::isfinite(normOfInverse) && normOfInverse > 0.0 ? 1.0 / (normOfScaled * normOfInverse) : 0.0;
    }
    if (failure.step >= 0 || !(rcond > belos::detail::singularPivot)) {
      std::ostringstream msg;
      msg << who << ": the coarse problem (level " << level << ", " << n << " DOF) is singular"
          << (symmetric ? " or indefinite" : "") << " (";
      if (failure.step >= 0)
        msg << "pivot " << failure.pivot << " at elimination step " << failure.step;
      else
        msg << "reciprocal condition number " << rcond;
      msg << " after diagonal scaling): the model is free to move as a rigid body or is a mechanism; check the "
             "supports";
      throw std::runtime_error(msg.str());
    }
    detail::finishInverse(space, inverse_, false, scale_, inverse_);
  }

  // A^-1 (n x n), valid after compute().
  const dense_type& inverse() const { return inverse_; }

 private:
  static constexpr const char* who = "perishell::multigrid::SmoothedAggregationPreconditioner";

  dense_type inverse_, work_, columns_;
  detail::CoarseScale<ExecutionSpaceT> scale_;
  detail::EliminationFailureView<ExecutionSpaceT> failure_{"perishell::amg::coarse_failure"};
};

}  // namespace perishell::multigrid
