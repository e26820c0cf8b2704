#pragma once
// Smoothed-aggregation algebraic multigrid (Vanek, Mandel, Brezina 1996; the scheme of
// ML/MueLu) as a Belos preconditioner for the 6-DOF-per-node shell/PD tangent. Thin shells
// are badly conditioned (bending stiffness ~ t^3, model.md §6): nodal block Jacobi needs
// PCG iterations growing like h^-2, one V-cycle of this hierarchy keeps them nearly mesh
// independent.
//
// Per level l (A_0 = the tangent, 6 DOF per node):
// - nodes are aggregated greedily over their strong couplings (aggregation.hpp, host, once
//   per pattern, from the values of the first matrix);
// - the near-null space B_l (6 columns) is, on the finest level, the 6 rigid-body modes of
//   each node in the current configuration (u = t, theta = 0; u = w x (x - x_c), theta = w),
//   zero on constrained DOF (rows holding only their diagonal after eliminateDirichlet);
// - the tentative prolongator P_tent is B_l orthonormalised per aggregate (thin QR, one
//   thread per aggregate), and R of that QR is the next level's near-null space, so
//   P_tent B_{l+1} = B_l and coarse nodes carry 6 DOF again;
// - P = (I - omega M^-1 A) P_tent with M = diag(lambda_r(i)) D, D the 6x6 nodal block
//   diagonal, lambda_r = lambda_max(D^-1 A) on the nodes of region r alone (the caller's
//   regions: PD nodes and shell-only nodes; a coarse node, an aggregate, is in the union of
//   its members' regions), and omega = 4 / (3 lambda_max(M^-1 A)), both by Lanczos
//   (largestEigenvalues): each region of a model that mixes stiffnesses of different spectra (PD
//   bonds and shell elements) is damped and smoothed by its own spectrum, not the stiffest
//   region's. A model of one region gets M = lambda D, the same hierarchy as with D;
// - A_{l+1} = P^T A P (sparse_product.hpp: patterns once on the host, values on the device
//   at every update()).
// The coarsest matrix (up to ~1200 DOF) is inverted densely where the hierarchy lives
// (coarse_inverse.hpp) and applied as a dense matrix-vector product: a rebuild on the GPU
// copies no matrix to the host.
//
// One V-cycle with the same Chebyshev smoother (scaled by M^-1, a polynomial in
// M^-1 A, hence self-adjoint in the A inner product) before and after the coarse correction,
// and R = P^T exactly, so the preconditioner is symmetric, as CG needs. Apply() runs only
// device kernels.
#include <perishell/core/fenced_seconds.hpp>
#include <perishell/core/tridiagonal.hpp>
#include <perishell/core/types.hpp>
#include <perishell/solvers/belos/block_jacobi.hpp>
#include <perishell/solvers/belos/crs_operator.hpp>
#include <perishell/solvers/belos/kokkos_multivector.hpp>
#include <perishell/solvers/multigrid/aggregation.hpp>
#include <perishell/solvers/multigrid/coarse_inverse.hpp>
#include <perishell/solvers/multigrid/sparse_product.hpp>

#include <BelosOperator.hpp>
#include <BelosTypes.hpp>

#include <KokkosBlas1_axpby.hpp>
#include <KokkosBlas2_gemv.hpp>
#include <KokkosSparse_spmv.hpp>
#include <Kokkos_Core.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace perishell::multigrid {

struct SmoothedAggregationOptions {
  // The coarsest level is inverted densely (coarse_inverse.hpp). Coarsening stops at the
  // first level of at most smallCoarseNodes nodes (6 DOF each), or earlier at one of at most
  // maxCoarseNodes whose inverse costs at most denseInverseBudget products with the fine
  // matrix ((6 n)^3 / 2 multiply-adds against nnz(A_0) each). Solved exactly at ~100-200
  // nodes instead of coarsened once more to ~20, the coarsest level cut PCG iterations by
  // 10-20 % on the pressed plate 4.2.1 (docs/implicit.md, "A larger coarsest level"); the
  // budget keeps the inverse a small part of a small model's solve.
  LocalIndex maxCoarseNodes = 200;
  LocalIndex smallCoarseNodes = 80;
  double denseInverseBudget = 200.0;
  int maxLevels = 10;
  // Chebyshev smoothing of [lambda_max / eigenRatio, boost lambda_max] (Ifpack2's defaults).
  int chebyshevDegree = 2;
  double chebyshevEigenRatio = 30.0;
  double chebyshevBoost = 1.1;
  // The spectrum bounds (lambda_max(M^-1 A) for omega and the Chebyshev interval, lambda_r by
  // region; detail::largestEigenvalues): Lanczos steps where A is symmetric, power iterations
  // where it is not (the exact tangent, for GMRES). An underestimated lambda_max makes the
  // Chebyshev polynomial negative on the top of the spectrum and the V-cycle indefinite (CG
  // breaks down): 10 power iterations from a random start did that on the tie plate 4.1.1
  // (tstSmoothedAggregation); 40 are ample. Lanczos gets closer in fewer products
  // (docs/implicit.md, "Spectrum bounds by Lanczos").
  bool symmetric = true;
  int lanczosSteps = 15;
  int powerIterations = 40;
  // Aggregation follows strong couplings only (aggregation.hpp, strongNodeGraphOf). A PD
  // node couples to every node of its horizon (~28 at delta = 3 dx), and aggregating whole
  // horizons coarsened too fast: on the pressed plate 4.2.1 (first increment, 2 OpenMP
  // threads) 0.05 cut PCG per solve from 120 to 55 (100 % PD) and from 149 to 85 (50 % PD) at
  // dx 0.5 mm, from 216 to 125 and 301 to 128 at 0.25 mm; CCM-only stayed at 40 and 39
  // (docs/implicit.md, "Strength of connection"). 0 aggregates over every stored block.
  double dropTolerance = 0.05;
  // Scaling of the smoother's diagonal by region, M = diag(lambda_r(i)) D
  // (detail::largestEigenvalues by region); false: M = D, one damping for the whole level. In a mixed model
  // lambda_max(D^-1 A) is the shell region's (2.40 on the pressed plate 4.2.1, against 1.54
  // for PD alone), which damped and smoothed the PD region with about 0.64 of its own omega
  // (docs/implicit.md, "Scaling by region").
  bool regionScaling = true;
};

// Seconds of each part of the set-up, the construction and every update() together, each
// part fenced: where a rebuild's time goes (perf/implicit_solve.cpp prints them).
struct SmoothedAggregationSetupSeconds {
  double patterns = 0.0;     // aggregation and product patterns (host, at construction)
  double smoother = 0.0;     // fine-matrix copy, rigid-body modes, block inverses, M by region, lambda_max
  double prolongator = 0.0;  // QR of the near-null space, M^-1 A P_tent, smoothing, P^T
  double galerkin = 0.0;     // A P and P^T (A P)
  double coarse = 0.0;       // the coarsest level's dense inverse
  double total() const { return patterns + smoother + prolongator + galerkin + coarse; }
};

namespace detail {

template <class ExecutionSpaceT>
using Matrix = belos::CrsMatrix<ExecutionSpaceT>;
template <class ExecutionSpaceT>
using DeviceOf = typename Matrix<ExecutionSpaceT>::device_type;
template <class ExecutionSpaceT>
using Vector = Kokkos::View<double*, Kokkos::LayoutLeft, DeviceOf<ExecutionSpaceT>>;
// B(6 node + dof, mode)
template <class ExecutionSpaceT>
using NearNullSpace = Kokkos::View<double* [dofPerNode], Kokkos::LayoutRight, DeviceOf<ExecutionSpaceT>>;

// Rigid-body modes about the centroid of positions (the current configuration); a DOF whose
// matrix row holds nothing but its diagonal is constrained and gets zero rows.
template <class ExecutionSpaceT>
void rigidBodyModes(const ExecutionSpaceT& space, const Matrix<ExecutionSpaceT>& A,
                    const CoordinateView<typename ExecutionSpaceT::memory_space>& positions,
                    const NearNullSpace<ExecutionSpaceT>& B) {
  const LocalIndex numNodes = static_cast<LocalIndex>(positions.extent(0));
  double centroid[3];
  for (int k = 0; k < 3; ++k) {
    double sum = 0.0;
    Kokkos::parallel_reduce(
        "perishell::amg::centroid", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, numNodes),
        KOKKOS_LAMBDA(const LocalIndex node, double& partial) { partial += positions(node, k); }, sum);
    centroid[k] = numNodes > 0 ? sum / numNodes : 0.0;
  }
  const double cx = centroid[0], cy = centroid[1], cz = centroid[2];
  const auto rowMap = A.graph.row_map;
  const auto entries = A.graph.entries;
  const auto values = A.values;
  Kokkos::parallel_for(
      "perishell::amg::rigid_body_modes", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, dofPerNode * numNodes),
      KOKKOS_LAMBDA(const LocalIndex row) {
        bool constrained = true;
        for (RowOffset k = rowMap(row); k < rowMap(row + 1); ++k)
          if (entries(k) != row && values(k) != 0.0) constrained = false;
        const LocalIndex node = row / dofPerNode;
        const int dof = row % dofPerNode;
        const double r[3] = {positions(node, 0) - cx, positions(node, 1) - cy, positions(node, 2) - cz};
        for (int mode = 0; mode < dofPerNode; ++mode) {
          double value = 0.0;
          if (mode < 3) {
            value = dof == mode ? 1.0 : 0.0;
          } else if (dof < 3) {
            // (e_w x r)_dof with w = mode - 3
            const int w = mode - 3;
            value = (w + 1) % 3 == dof ? -r[(w + 2) % 3] : ((w + 2) % 3 == dof ? r[(w + 1) % 3] : 0.0);
          } else {
            value = dof == mode ? 1.0 : 0.0;
          }
          B(row, mode) = constrained ? 0.0 : value;
        }
      });
}

// Relative size below which a near-null-space column is taken as a combination of the
// previous ones within an aggregate (its Q column and R row are zeroed).
inline constexpr double dependentColumn = 1e-10;

// Thin QR per aggregate by modified Gram-Schmidt, twice ("twice is enough"): Q goes into the
// tentative prolongator's values (row i holds its 6 entries at 6 i .. 6 i + 5), R into the
// coarse near-null space rows of the aggregate.
template <class ExecutionSpaceT>
void tentativeProlongator(const ExecutionSpaceT& space,
                          const Kokkos::View<RowOffset*, DeviceOf<ExecutionSpaceT>>& offsets,
                          const Kokkos::View<LocalIndex*, DeviceOf<ExecutionSpaceT>>& members,
                          const NearNullSpace<ExecutionSpaceT>& fine, const VectorView<typename ExecutionSpaceT::memory_space>& q,
                          const NearNullSpace<ExecutionSpaceT>& coarse) {
  const LocalIndex numAggregates = static_cast<LocalIndex>(offsets.extent(0) - 1);
  Kokkos::parallel_for(
      "perishell::amg::tentative_prolongator", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, numAggregates),
      KOKKOS_LAMBDA(const LocalIndex aggregate) {
        const RowOffset first = offsets(aggregate), last = offsets(aggregate + 1);
        auto Q = [&](RowOffset member, int dof, int column) -> double& {
          return q(dofPerNode * (dofPerNode * static_cast<RowOffset>(members(member)) + dof) + column);
        };
        double R[dofPerNode][dofPerNode] = {};
        for (RowOffset m = first; m < last; ++m)
          for (int d = 0; d < dofPerNode; ++d)
            for (int j = 0; j < dofPerNode; ++j) Q(m, d, j) = fine(dofPerNode * members(m) + d, j);
        for (int j = 0; j < dofPerNode; ++j) {
          double initial = 0.0;
          for (RowOffset m = first; m < last; ++m)
            for (int d = 0; d < dofPerNode; ++d) initial += Q(m, d, j) * Q(m, d, j);
          for (int pass = 0; pass < 2; ++pass)
            for (int i = 0; i < j; ++i) {
              if (R[i][i] == 0.0) continue;
              double dot = 0.0;
              for (RowOffset m = first; m < last; ++m)
                for (int d = 0; d < dofPerNode; ++d) dot += Q(m, d, i) * Q(m, d, j);
              R[i][j] += dot;
              for (RowOffset m = first; m < last; ++m)
                for (int d = 0; d < dofPerNode; ++d) Q(m, d, j) -= dot * Q(m, d, i);
            }
          double squared = 0.0;
          for (RowOffset m = first; m < last; ++m)
            for (int d = 0; d < dofPerNode; ++d) squared += Q(m, d, j) * Q(m, d, j);
          const bool independent = squared > dependentColumn * dependentColumn * initial && squared > 0.0;
          const double norm = independent ? Kokkos::Experimental::sqrt(squared) : 0.0;
          R[j][j] = norm;
          for (RowOffset m = first; m < last; ++m)
            for (int d = 0; d < dofPerNode; ++d) Q(m, d, j) = independent ? Q(m, d, j) / norm : 0.0;
        }
        for (int i = 0; i < dofPerNode; ++i)
          for (int j = 0; j < dofPerNode; ++j) coarse(dofPerNode * aggregate + i, j) = R[i][j];
      });
}

// values of B A for the block inverses B (of D or of M), where rows of one node share A's
// column pattern (nodal layout, sorted).
template <class ExecutionSpaceT>
void scaleByBlockInverse(const ExecutionSpaceT& space, const belos::detail::BlockInverseView<ExecutionSpaceT>& inverses,
                         const Matrix<ExecutionSpaceT>& A, const VectorView<typename ExecutionSpaceT::memory_space>& scaled) {
  const auto rowMap = A.graph.row_map;
  const auto values = A.values;
  Kokkos::parallel_for(
      "perishell::amg::scale_by_block_inverse", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, A.numRows()),
      KOKKOS_LAMBDA(const LocalIndex row) {
        const LocalIndex node = row / dofPerNode;
        const int dof = row % dofPerNode;
        const RowOffset length = rowMap(row + 1) - rowMap(row);
        for (RowOffset k = 0; k < length; ++k) {
          double sum = 0.0;
          for (int c = 0; c < dofPerNode; ++c) sum += inverses(node, dof, c) * values(rowMap(dofPerNode * node + c) + k);
          scaled(rowMap(row) + k) = sum;
        }
      });
}

// A fixed pseudo-random value in [-1, 1) per row (a hash of the row index, so no random pool
// is built per update): the start of the spectrum estimates below.
KOKKOS_INLINE_FUNCTION double pseudoRandom(LocalIndex row) {
  // splitmix64 finaliser: well-mixed bits, mapped to [-1, 1)
  std::uint64_t z = static_cast<std::uint64_t>(row) + 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  z ^= z >> 31;
  return 2.0 * static_cast<double>(z >> 11) * 0x1.0p-53 - 1.0;
}

// A node's regions as bit flags (SmoothedAggregationPreconditioner's `regions`): a coarse
// node carries the union (bitwise or) of its aggregate's members.
constexpr int regionCount = 4;  // two flags
template <class ExecutionSpaceT>
using RegionView = Kokkos::View<const int*, DeviceOf<ExecutionSpaceT>>;

// One sum per region, reduced in one pass (atomics onto 4 addresses serialise: on 2 OpenMP
// threads they cost the 1 mm pressed plate at 50 % PD 2.5 s more set-up over 117 builds).
struct RegionSums {
  double value[regionCount];
  KOKKOS_INLINE_FUNCTION RegionSums() {
    for (int r = 0; r < regionCount; ++r) value[r] = 0.0;
  }
  KOKKOS_INLINE_FUNCTION RegionSums& operator+=(const RegionSums& other) {
    for (int r = 0; r < regionCount; ++r) value[r] += other.value[r];
    return *this;
  }
  // Kokkos 3.4's reducers join through volatile references.
  KOKKOS_INLINE_FUNCTION void operator+=(const volatile RegionSums& other) volatile {
    for (int r = 0; r < regionCount; ++r) value[r] += other.value[r];
  }
};

}  // namespace detail
}  // namespace perishell::multigrid

template <>
struct Kokkos::reduction_identity<perishell::multigrid::detail::RegionSums> {
  KOKKOS_FORCEINLINE_FUNCTION static perishell::multigrid::detail::RegionSums sum() { return {}; }
};

namespace perishell::multigrid {
namespace detail {

// What largestEigenvalues works in: five vectors of a level's rows, and per step the sums it
// reduces (sized on first use, so a rebuild allocates nothing).
template <class ExecutionSpaceT>
struct SpectrumWork {
  Vector<ExecutionSpaceT> v, previous, mv, previousMv, product;
  Kokkos::View<RegionSums*, DeviceOf<ExecutionSpaceT>> sums;
  SpectrumWork() = default;
  SpectrumWork(LocalIndex rows, const std::string& tag)
      : v("perishell::amg::spectrum_v_" + tag, rows), previous("perishell::amg::spectrum_previous_" + tag, rows),
        mv("perishell::amg::spectrum_mv_" + tag, rows), previousMv("perishell::amg::spectrum_previous_mv_" + tag, rows),
        product("perishell::amg::spectrum_product_" + tag, rows) {}
};

// v (and M v) divided by the root of sums(k) of the row's region: a step of largestEigenvalues.
template <class ExecutionSpaceT>
void normaliseByRegion(const ExecutionSpaceT& space, const SpectrumWork<ExecutionSpaceT>& work,
                       const Kokkos::View<RegionSums*, DeviceOf<ExecutionSpaceT>>& sums, int k,
                       const RegionView<ExecutionSpaceT>& regions, bool symmetric) {
  const bool byRegion = regions.extent(0) > 0;
  Kokkos::parallel_for(
      "perishell::amg::spectrum_normalise", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, work.v.extent(0)),
      KOKKOS_LAMBDA(const LocalIndex row) {
        const double squared = sums(k).value[byRegion ? regions(row / dofPerNode) : 0];
        const double scale = squared > 0.0 ? 1.0 / Kokkos::Experimental::sqrt(squared) : 0.0;
        work.v(row) *= scale;
        if (symmetric) work.mv(row) *= scale;
      });
}

// The largest eigenvalue of M^-1 A_rr for every region r at once, A_rr the rows and columns of
// region r's nodes (no regions: one region, M^-1 A), M given by its nodal block inverses. A
// must hold no couplings between regions (keepCouplingsWithinRegions), so that one product
// serves every region.
// - symmetric A (CG's tangent): Lanczos in the M inner product, in which M^-1 A is
//   self-adjoint (alpha_j = v_j^T A v_j, beta_{j+1}^2 = w^T M w; M v is carried along, so M is
//   never formed). The top Ritz value of `steps` products approaches lambda_max from below,
//   never below the M-Rayleigh quotient of the power iterate from the same start (the Krylov
//   space holds it), and much faster (docs/implicit.md, "Spectrum bounds by Lanczos").
// - non-symmetric A (the exact tangent, GMRES): `steps` power iterations, |M^-1 A x| for unit x.
// Every step's coefficients are reduced where the vectors live and read back once at the end.
template <class ExecutionSpaceT>
RegionSums largestEigenvalues(const ExecutionSpaceT& space, const Matrix<ExecutionSpaceT>& A,
                              const belos::detail::BlockInverseView<ExecutionSpaceT>& inverses,
                              const RegionView<ExecutionSpaceT>& regions, bool symmetric, int steps,
                              SpectrumWork<ExecutionSpaceT>& work) {
  using Memory = typename ExecutionSpaceT::memory_space;
  // sums(0): the start's squared norm; step j: sums(1 + 2j) alpha_j, sums(2 + 2j) beta_{j+1}^2
  // (Lanczos) or |M^-1 A x|^2 (power iterations); per region.
  if (work.sums.extent(0) < static_cast<std::size_t>(2 * steps + 1))
    work.sums = decltype(work.sums)("perishell::amg::spectrum_sums", 2 * steps + 1);
  const auto sums = work.sums;
  const auto into = [&sums](int k) {
    return Kokkos::Sum<RegionSums, Memory>(Kokkos::View<RegionSums, Memory>(sums.data() + k));
  };
  const bool byRegion = regions.extent(0) > 0;
  const LocalIndex numNodes = A.numRows() / dofPerNode;
  const Kokkos::RangePolicy<ExecutionSpaceT> nodes(space, 0, numNodes), rows(space, 0, A.numRows());

  // Start: M v = a pseudo-random vector, v = M^-1 of it (power iterations: v itself).
  Kokkos::parallel_reduce(
      "perishell::amg::spectrum_start", nodes,
      KOKKOS_LAMBDA(const LocalIndex node, RegionSums& partial) {
        const int region = byRegion ? regions(node) : 0;
        double start[dofPerNode];
        for (int a = 0; a < dofPerNode; ++a) start[a] = pseudoRandom(dofPerNode * node + a);
        for (int a = 0; a < dofPerNode; ++a) {
          const LocalIndex row = dofPerNode * node + a;
          double v = start[a];
          if (symmetric) {
            v = 0.0;
            for (int b = 0; b < dofPerNode; ++b) v += inverses(node, a, b) * start[b];
            work.mv(row) = start[a];
          }
          work.v(row) = v;
          partial.value[region] += v * start[a];
        }
      },
      into(0));
  normaliseByRegion(space, work, sums, 0, regions, symmetric);

  for (int j = 0; j < steps; ++j) {
    KokkosSparse::spmv("N", 1.0, A, work.v, 0.0, work.product);
    if (symmetric)
      Kokkos::parallel_reduce(
          "perishell::amg::spectrum_alpha", rows,
          KOKKOS_LAMBDA(const LocalIndex row, RegionSums& partial) {
            partial.value[byRegion ? regions(row / dofPerNode) : 0] += work.v(row) * work.product(row);
          },
          into(1 + 2 * j));
    // Lanczos: w = M^-1 A v_j - alpha_j v_j - beta_j v_{j-1} and M w, into the previous vectors;
    // power iterations: M^-1 A v.
    Kokkos::parallel_reduce(
        "perishell::amg::spectrum_next", nodes,
        KOKKOS_LAMBDA(const LocalIndex node, RegionSums& partial) {
          const int region = byRegion ? regions(node) : 0;
          const double alpha = symmetric ? sums(1 + 2 * j).value[region] : 0.0;
          const double betaSquared = symmetric && j > 0 ? sums(2 * j).value[region] : 0.0;
          const double beta = betaSquared > 0.0 ? Kokkos::Experimental::sqrt(betaSquared) : 0.0;
          for (int a = 0; a < dofPerNode; ++a) {
            const LocalIndex row = dofPerNode * node + a;
            double w = 0.0;
            for (int b = 0; b < dofPerNode; ++b) w += inverses(node, a, b) * work.product(dofPerNode * node + b);
            if (symmetric) {
              w -= alpha * work.v(row) + (beta > 0.0 ? beta * work.previous(row) : 0.0);
              const double mw =
                  work.product(row) - alpha * work.mv(row) - (beta > 0.0 ? beta * work.previousMv(row) : 0.0);
              work.previousMv(row) = mw;
              partial.value[region] += w * mw;
            } else {
              partial.value[region] += w * w;
            }
            work.previous(row) = w;
          }
        },
        into(2 + 2 * j));
    std::swap(work.v, work.previous);
    std::swap(work.mv, work.previousMv);
    normaliseByRegion(space, work, sums, 2 + 2 * j, regions, symmetric);
  }

  const auto host = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, sums);
  RegionSums largest;
  for (int r = 0; r < regionCount; ++r) {
    if (!(host(0).value[r] > 0.0)) continue;  // no node of this region
    if (!symmetric) {
      largest.value[r] = std::sqrt(host(2 * steps).value[r]);
      continue;
    }
    // The tridiagonal up to the first vanishing beta (an invariant subspace: its top is found).
    std::vector<double> alphas, betas;
    double scale = 0.0;
    for (int j = 0; j < steps; ++j) {
      alphas.push_back(host(1 + 2 * j).value[r]);
      scale = std::max(scale, std::abs(alphas.back()));
      const double betaSquared = host(2 + 2 * j).value[r];
      if (!(betaSquared > 1e-24 * scale * scale)) break;
      betas.push_back(std::sqrt(betaSquared));
    }
    largest.value[r] = largestTridiagonalEigenvalue(alphas, betas);
  }
  return largest;
}

// values of A without the couplings between nodes of different regions.
template <class ExecutionSpaceT>
void keepCouplingsWithinRegions(const ExecutionSpaceT& space, const Matrix<ExecutionSpaceT>& A,
                                const RegionView<ExecutionSpaceT>& regions,
                                const VectorView<typename ExecutionSpaceT::memory_space>& within) {
  const auto rowMap = A.graph.row_map;
  const auto entries = A.graph.entries;
  const auto values = A.values;
  Kokkos::parallel_for(
      "perishell::amg::keep_couplings_within_regions", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, A.numRows()),
      KOKKOS_LAMBDA(const LocalIndex row) {
        const int region = regions(row / dofPerNode);
        for (RowOffset e = rowMap(row); e < rowMap(row + 1); ++e)
          within(e) = regions(entries(e) / dofPerNode) == region ? values(e) : 0.0;
      });
}

// D_i^-1 -> (lambda_r D_i)^-1, r node i's region: the block inverses become M's.
template <class ExecutionSpaceT>
void scaleBlockInverses(const ExecutionSpaceT& space, const belos::detail::BlockInverseView<ExecutionSpaceT>& inverses,
                        const RegionView<ExecutionSpaceT>& regions, const RegionSums& lambdas) {
  Kokkos::parallel_for(
      "perishell::amg::scale_block_inverses", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, inverses.extent(0)),
      KOKKOS_LAMBDA(const LocalIndex node) {
        const double lambda = lambdas.value[regions(node)];
        const double scale = lambda > 0.0 ? 1.0 / lambda : 1.0;
        for (int a = 0; a < dofPerNode; ++a)
          for (int b = 0; b < dofPerNode; ++b) inverses(node, a, b) *= scale;
      });
}

// P = P_tent - omega Z, Z = M^-1 A P_tent; P shares Z's graph, and P_tent's 6 entries of row i
// (columns 6 aggregateOf(i / 6) + j) are among Z's.
template <class ExecutionSpaceT>
void smoothProlongator(const ExecutionSpaceT& space, const Kokkos::View<LocalIndex*, DeviceOf<ExecutionSpaceT>>& aggregateOf,
                       const VectorView<typename ExecutionSpaceT::memory_space>& tentative, const Matrix<ExecutionSpaceT>& Z,
                       double omega, const VectorView<typename ExecutionSpaceT::memory_space>& smoothed) {
  const auto rowMap = Z.graph.row_map;
  const auto entries = Z.graph.entries;
  const auto values = Z.values;
  Kokkos::parallel_for(
      "perishell::amg::smooth_prolongator", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, Z.numRows()),
      KOKKOS_LAMBDA(const LocalIndex row) {
        const LocalIndex aggregate = aggregateOf(row / dofPerNode);
        for (RowOffset k = rowMap(row); k < rowMap(row + 1); ++k) {
          const LocalIndex column = entries(k);
          double value = -omega * values(k);
          if (column / dofPerNode == aggregate) value += tentative(dofPerNode * static_cast<RowOffset>(row) + column % dofPerNode);
          smoothed(k) = value;
        }
      });
}

// A coarse DOF whose prolongator column is zero (a dependent mode) has an all-zero row and
// column in P^T A P; a unit diagonal decouples it without changing the coarse correction.
template <class ExecutionSpaceT>
void unitDiagonalOnEmptyRows(const ExecutionSpaceT& space, const Matrix<ExecutionSpaceT>& A) {
  const auto rowMap = A.graph.row_map;
  const auto entries = A.graph.entries;
  const auto values = A.values;
  Kokkos::parallel_for(
      "perishell::amg::unit_diagonal_on_empty_rows", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, A.numRows()),
      KOKKOS_LAMBDA(const LocalIndex row) {
        for (RowOffset k = rowMap(row); k < rowMap(row + 1); ++k)
          if (values(k) != 0.0) return;
        for (RowOffset k = rowMap(row); k < rowMap(row + 1); ++k)
          if (entries(k) == row) values(k) = 1.0;
      });
}

// w = a w + c D^-1 r (w is not read when a is 0).
template <class ExecutionSpaceT, class RView>
void blockJacobiUpdate(const ExecutionSpaceT& space, const belos::detail::BlockInverseView<ExecutionSpaceT>& inverses,
                       const RView& r, double a, const Vector<ExecutionSpaceT>& w, double c) {
  Kokkos::parallel_for(
      "perishell::amg::block_jacobi_update",
      Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, static_cast<LocalIndex>(r.extent(0))),
      KOKKOS_LAMBDA(const LocalIndex row) {
        const LocalIndex node = row / dofPerNode;
        const int dof = row % dofPerNode;
        double sum = 0.0;
        for (int j = 0; j < dofPerNode; ++j) sum += inverses(node, dof, j) * r(dofPerNode * node + j);
        w(row) = (a == 0.0 ? 0.0 : a * w(row)) + c * sum;
      });
}

}  // namespace detail

template <class ExecutionSpaceT>
class SmoothedAggregationPreconditioner final : public Belos::Operator<double> {
  static_assert(Kokkos::is_execution_space<ExecutionSpaceT>::value,
                "SmoothedAggregationPreconditioner needs a Kokkos execution space");

 public:
  using memory_space = typename ExecutionSpaceT::memory_space;
  using matrix_type = belos::CrsMatrix<ExecutionSpaceT>;
  using vector_type = detail::Vector<ExecutionSpaceT>;
  using near_null_space_type = detail::NearNullSpace<ExecutionSpaceT>;
  using positions_type = CoordinateView<memory_space>;

  // A: symmetric for CG (non-symmetric, e.g. the exact tangent, for GMRES: then the V-cycle
  // is not symmetric either, and only Apply without transpose is meaningful), 6 DOF per node in consecutive rows, rows sorted, the rows of one node
  // sharing one column pattern (the NodalBlockPattern layout); supports eliminated.
  // positions: the nodes' current coordinates [m]. regions: per node, bit flags below
  // detail::regionCount naming its part of the model (static Newton's nodeRegions: 1 PD,
  // 2 shell elements only), or empty for one region; fixed with the pattern. Builds the
  // hierarchy (aggregation and product patterns on the host once, numeric parts on the device,
  // again at update()). Throws std::invalid_argument for bad shapes, std::runtime_error for a singular
  // nodal block or a singular coarse problem (a model free to move as a rigid body).
  SmoothedAggregationPreconditioner(const ExecutionSpaceT& space, const matrix_type& A, const positions_type& positions,
                                    const SmoothedAggregationOptions& options = {},
                                    const detail::RegionView<ExecutionSpaceT>& regions = {})
      : space_(space), options_(options) {
    const auto start = std::chrono::steady_clock::now();
    checkInput(A, positions);
    if (regions.extent(0) != 0 && regions.extent(0) != positions.extent(0))
      throw std::invalid_argument(std::string(who) + ": " + std::to_string(regions.extent(0)) +
                                  " node regions for " + std::to_string(positions.extent(0)) + " nodes");
    if (options.maxCoarseNodes < 1 || options.smallCoarseNodes < 1 || !(options.denseInverseBudget >= 0.0) ||
        options.maxLevels < 1 || options.chebyshevDegree < 1 ||
        options.powerIterations < 1 || options.lanczosSteps < 1 || !(options.chebyshevEigenRatio > 1.0) ||
        !(options.dropTolerance >= 0.0 && options.dropTolerance < 1.0))
      throw std::invalid_argument(std::string(who) +
                                  ": options need maxCoarseNodes, smallCoarseNodes, maxLevels, chebyshevDegree, "
                                  "powerIterations, lanczosSteps >= 1, denseInverseBudget >= 0, "
                                  "chebyshevEigenRatio > 1 and 0 <= dropTolerance < 1");
    levels_.emplace_back();
    setRegions(0, regions.extent(0) != 0 ? hostCopy(regions)
                                         : std::vector<int>(positions.extent(0), 0));
    snapshotFineMatrix(A);
    levels_[0].nearNullSpace = near_null_space_type("perishell::amg::near_null_space_0", A.numRows());
    detail::rigidBodyModes(space_, A, positions, levels_[0].nearNullSpace);
    for (std::size_t l = 0;; ++l) {
      const LocalIndex numNodes = levels_[l].A.numRows() / dofPerNode;
      if (coarsestLevelFits(numNodes, A.nnz()) || static_cast<int>(l) + 1 >= options_.maxLevels) break;
      const auto hostRowMap = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), levels_[l].A.graph.row_map);
      const auto hostEntries = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), levels_[l].A.graph.entries);
      const auto hostValues = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), levels_[l].A.values);
      const Aggregates aggregates = aggregateNodes(
          strongNodeGraphOf(hostRowMap, hostEntries, hostValues, dofPerNode, options_.dropTolerance));
      if (aggregates.numAggregates == numNodes) break;  // coarsening stalled
      buildTransfer(l, aggregates);
    }
    factorCoarsest();
    setupSeconds_.patterns = fencedSecondsSince(space_, start) - setupSeconds_.total();
  }

  // Recomputes every numeric part for a new tangent A (same pattern as at construction) and
  // new current positions: near-null space, QR, block inverses, smoothed prolongators,
  // Galerkin products, coarse inverse. The aggregates and product patterns are kept.
  void update(const matrix_type& A, const positions_type& positions) {
    checkInput(A, positions);
    if (A.nnz() != levels_[0].A.nnz())
      throw std::invalid_argument(std::string(who) + "::update: the matrix has " + std::to_string(A.nnz()) +
                                  " entries, the hierarchy was built for " + std::to_string(levels_[0].A.nnz()));
    const auto start = std::chrono::steady_clock::now();
    snapshotFineMatrix(A);
    detail::rigidBodyModes(space_, A, positions, levels_[0].nearNullSpace);
    setupSeconds_.smoother += fencedSecondsSince(space_, start);
    for (std::size_t l = 0; l + 1 < levels_.size(); ++l) computeTransfer(l);
    factorCoarsest();
  }

  int numLevels() const { return static_cast<int>(levels_.size()); }
  const matrix_type& matrix(int level) const { return levels_.at(level).A; }
  // The transfer from level + 1 to level (absent on the coarsest level).
  const matrix_type& prolongator(int level) const { return levels_.at(level).P; }
  const matrix_type& tentativeProlongator(int level) const { return levels_.at(level).Ptent; }
  // The restriction from level to level + 1 (P^T, computed by transposition).
  const matrix_type& restrictor(int level) const { return levels_.at(level).R; }
  const near_null_space_type& nearNullSpace(int level) const { return levels_.at(level).nearNullSpace; }
  const SmoothedAggregationSetupSeconds& setupSeconds() const { return setupSeconds_; }

  void Apply(const Belos::MultiVec<double>& x, Belos::MultiVec<double>& y,
             Belos::ETrans /*trans: the V-cycle is symmetric*/ = Belos::NOTRANS) const override {
    constexpr const char* applyWho = "perishell::multigrid::SmoothedAggregationPreconditioner::Apply";
    const auto& xk = belos::detail::asKokkos<ExecutionSpaceT>(x, applyWho);
    auto& yk = belos::detail::asKokkos<ExecutionSpaceT>(y, applyWho);
    const auto n = static_cast<std::size_t>(levels_[0].A.numRows());
    belos::detail::checkApplyShapes(xk, yk, n, n, applyWho);
    const auto xv = xk.deviceView();
    const auto yv = yk.deviceView();
    for (std::size_t j = 0; j < xv.extent(1); ++j)
      vCycle(0, Kokkos::subview(xv, Kokkos::ALL(), j), Kokkos::subview(yv, Kokkos::ALL(), j));
  }

  bool HasApplyTranspose() const override { return true; }

 private:
  static constexpr const char* who = "perishell::multigrid::SmoothedAggregationPreconditioner";

  struct Level {
    matrix_type A;
    near_null_space_type nearNullSpace;
    // Smoother and transfer to the next level (absent on the coarsest level).
    belos::detail::BlockInverseView<ExecutionSpaceT> blockInverses;
    matrix_type scaledA;  // M^-1 A
    // Each node's regions (bit flags), how many distinct ones the level has, and lambda_r of
    // M = diag(lambda_r) D per node.
    Kokkos::View<int*, detail::DeviceOf<ExecutionSpaceT>> regions;
    std::vector<int> hostRegions;
    int numRegions = 1;
    double lambdaMax = 0.0;
    detail::SpectrumWork<ExecutionSpaceT> spectrum;  // largestEigenvalues' vectors
    Kokkos::View<RowOffset*, detail::DeviceOf<ExecutionSpaceT>> aggregateOffsets;
    Kokkos::View<LocalIndex*, detail::DeviceOf<ExecutionSpaceT>> aggregateMembers, aggregateOf;
    matrix_type Ptent, Z, P, R, AP;
    Transposition<ExecutionSpaceT> restriction;  // R = P^T: its pattern and gather map
    belos::detail::BlockDiagnosisView<ExecutionSpaceT> blockDiagnoses;
    vector_type x, b, r, w;  // work vectors of this level's size
  };

  void checkInput(const matrix_type& A, const positions_type& positions) const {
    if (A.numRows() != A.numCols() || A.numRows() % dofPerNode != 0 ||
        static_cast<std::size_t>(A.numRows()) != dofPerNode * positions.extent(0)) {
      std::ostringstream msg;
      msg << who << ": the matrix is " << A.numRows() << " x " << A.numCols() << " and there are "
          << positions.extent(0) << " node positions; it needs a square matrix of 6 rows per node";
      throw std::invalid_argument(msg.str());
    }
  }

  // Aggregates and product patterns of level l, then its numeric parts; appends level l + 1.
  void buildTransfer(std::size_t l, const Aggregates& aggregates) {
    const LocalIndex numRows = levels_[l].A.numRows();
    const LocalIndex numCoarseRows = dofPerNode * aggregates.numAggregates;
    const std::string tag = std::to_string(l);
    {
      Level& level = levels_[l];
      level.aggregateOffsets = decltype(level.aggregateOffsets)("perishell::amg::aggregate_offsets_" + tag,
                                                                aggregates.offsets.size());
      level.aggregateMembers = decltype(level.aggregateMembers)("perishell::amg::aggregate_members_" + tag,
                                                                aggregates.members.size());
      level.aggregateOf = decltype(level.aggregateOf)("perishell::amg::aggregate_of_" + tag, aggregates.aggregateOf.size());
      copyToDevice(aggregates.offsets, level.aggregateOffsets);
      copyToDevice(aggregates.members, level.aggregateMembers);
      copyToDevice(aggregates.aggregateOf, level.aggregateOf);

      // P_tent: row i has the 6 columns of its node's aggregate.
      const auto hostRowMap = Kokkos::View<RowOffset*, Kokkos::HostSpace>("ptent row map", numRows + 1);
      const auto hostEntries =
          Kokkos::View<LocalIndex*, Kokkos::HostSpace>("ptent entries", dofPerNode * static_cast<std::size_t>(numRows));
      for (LocalIndex row = 0; row <= numRows; ++row) hostRowMap(row) = dofPerNode * static_cast<RowOffset>(row);
      for (LocalIndex row = 0; row < numRows; ++row)
        for (int j = 0; j < dofPerNode; ++j)
          hostEntries(dofPerNode * static_cast<std::size_t>(row) + j) =
              dofPerNode * aggregates.aggregateOf[row / dofPerNode] + j;
      const auto rowMap = Kokkos::create_mirror_view_and_copy(memory_space(), hostRowMap);
      const auto entries = Kokkos::create_mirror_view_and_copy(memory_space(), hostEntries);
      typename matrix_type::values_type::non_const_type values("perishell::amg::ptent_" + tag, entries.extent(0));
      level.Ptent = matrix_type("perishell::amg::ptent_" + tag, numRows, numCoarseRows,
                                static_cast<RowOffset>(entries.extent(0)), values, rowMap, entries);
      level.scaledA = matrix_type("perishell::amg::scaled_a_" + tag, numRows, numRows, level.A.nnz(),
                                  typename matrix_type::values_type::non_const_type("perishell::amg::scaled_a_" + tag,
                                                                                    level.A.nnz()),
                                  level.A.graph.row_map, level.A.graph.entries);
      level.blockInverses = belos::detail::BlockInverseView<ExecutionSpaceT>(
          "perishell::amg::block_inverses_" + tag, numRows / dofPerNode, dofPerNode, dofPerNode);
      level.blockDiagnoses = belos::detail::BlockDiagnosisView<ExecutionSpaceT>("perishell::amg::block_diagnoses_" + tag,
                                                                                numRows / dofPerNode);
      level.r = vector_type("perishell::amg::r_" + tag, numRows);
      level.w = vector_type("perishell::amg::w_" + tag, numRows);
      level.spectrum = detail::SpectrumWork<ExecutionSpaceT>(numRows, tag);
    }
    levels_.emplace_back();
    std::vector<int> coarseRegions(aggregates.numAggregates, 0);
    for (std::size_t node = 0; node < aggregates.aggregateOf.size(); ++node)
      coarseRegions[aggregates.aggregateOf[node]] |= levels_[l].hostRegions[node];
    setRegions(l + 1, std::move(coarseRegions));
    const std::string nextTag = std::to_string(l + 1);
    levels_[l + 1].nearNullSpace = near_null_space_type("perishell::amg::near_null_space_" + nextTag, numCoarseRows);
    levels_[l + 1].x = vector_type("perishell::amg::x_" + nextTag, numCoarseRows);
    levels_[l + 1].b = vector_type("perishell::amg::b_" + nextTag, numCoarseRows);
    Level& level = levels_[l];
    computeFineNumerics(l);
    level.Z = productPattern(level.scaledA, level.Ptent, "perishell::amg::z_" + tag);
    level.P = matrix_type("perishell::amg::p_" + tag, numRows, numCoarseRows, level.Z.nnz(),
                          typename matrix_type::values_type::non_const_type("perishell::amg::p_" + tag, level.Z.nnz()),
                          level.Z.graph.row_map, level.Z.graph.entries);
    level.restriction = transposePattern(level.P, "perishell::amg::r_" + tag);
    level.R = level.restriction.transpose;
    computeProlongator(l);
    level.AP = productPattern(level.A, level.P, "perishell::amg::ap_" + tag);
    levels_[l + 1].A = productPattern(level.R, level.AP, "perishell::amg::a_" + nextTag);
    computeGalerkin(l);
  }

  // The hierarchy keeps its own copy of the fine values: a caller that reassembles A in place
  // and reuses the hierarchy (Newton, static_newton.hpp) would otherwise pair new fine
  // values with the old smoother bounds and coarse levels, which can make the V-cycle
  // indefinite.
  void snapshotFineMatrix(const matrix_type& A) {
    if (fineValues_.extent(0) != A.values.extent(0))
      fineValues_ = typename matrix_type::values_type::non_const_type("perishell::amg::a_0 values", A.values.extent(0));
    Kokkos::deep_copy(space_, fineValues_, A.values);
    levels_[0].A = matrix_type("perishell::amg::a_0", A.numCols(), fineValues_, A.graph);
  }

  static std::vector<int> hostCopy(const detail::RegionView<ExecutionSpaceT>& device) {
    const auto host = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), device);
    return std::vector<int>(host.data(), host.data() + host.extent(0));
  }

  void setRegions(std::size_t l, std::vector<int> regions) {
    Level& level = levels_[l];
    for (const int region : regions)
      if (region < 0 || region >= detail::regionCount)
        throw std::invalid_argument(std::string(who) + ": a node region of " + std::to_string(region) +
                                    " (regions are bit flags below " + std::to_string(detail::regionCount) + ")");
    std::vector<bool> present(detail::regionCount, false);
    for (const int region : regions) present[region] = true;
    level.numRegions = static_cast<int>(std::count(present.begin(), present.end(), true));
    level.regions = decltype(level.regions)("perishell::amg::regions_" + std::to_string(l), regions.size());
    copyToDevice(regions, level.regions);
    level.hostRegions = std::move(regions);
  }

  template <class T, class DeviceView>
  static void copyToDevice(const std::vector<T>& host, const DeviceView& device) {
    const Kokkos::View<const T*, Kokkos::HostSpace, Kokkos::MemoryTraits<Kokkos::Unmanaged>> wrapped(host.data(), host.size());
    Kokkos::deep_copy(device, wrapped);
  }

  void computeTransfer(std::size_t l) {
    computeFineNumerics(l);
    computeProlongator(l);
    computeGalerkin(l);
  }

  // Whether a level of numNodes nodes is inverted densely rather than coarsened again
  // (SmoothedAggregationOptions::maxCoarseNodes).
  bool coarsestLevelFits(LocalIndex numNodes, std::size_t fineEntries) const {
    if (numNodes <= std::min(options_.smallCoarseNodes, options_.maxCoarseNodes)) return true;
    const double dof = static_cast<double>(dofPerNode) * numNodes;
    return numNodes <= options_.maxCoarseNodes &&
           0.5 * dof * dof * dof <= options_.denseInverseBudget * static_cast<double>(fineEntries);
  }

  // Block inverses (M's), M^-1 A, lambda_max and the QR of the near-null space.
  void computeFineNumerics(std::size_t l) {
    auto start = std::chrono::steady_clock::now();
    Level& level = levels_[l];
    const LocalIndex failed =
        belos::detail::invertDiagonalBlocks(level.A, dofPerNode, level.blockInverses, level.blockDiagnoses);
    if (failed >= 0)
      belos::detail::throwFailedBlock<ExecutionSpaceT>(std::string(who) + " (level " + std::to_string(l) + ")", failed,
                                                       dofPerNode, level.blockDiagnoses);
    const bool symmetric = options_.symmetric;
    const int steps = symmetric ? options_.lanczosSteps : options_.powerIterations;
    if (options_.regionScaling && level.numRegions > 1) {
      // scaledA's values hold A without the couplings between regions until M^-1 A is written.
      const detail::RegionView<ExecutionSpaceT> regions(level.regions);
      detail::keepCouplingsWithinRegions(space_, level.A, regions, level.scaledA.values);
      const auto lambdas = detail::largestEigenvalues(space_, level.scaledA, level.blockInverses, regions, symmetric,
                                                      steps, level.spectrum);
      detail::scaleBlockInverses(space_, level.blockInverses, regions, lambdas);
    }
    detail::scaleByBlockInverse(space_, level.blockInverses, level.A, level.scaledA.values);
    level.lambdaMax =
        detail::largestEigenvalues(space_, level.A, level.blockInverses, {}, symmetric, steps, level.spectrum).value[0];
    if (!(level.lambdaMax > 0.0) || !std::isfinite(level.lambdaMax))
      throw std::runtime_error(std::string(who) + ": level " + std::to_string(l) +
                               ": the largest eigenvalue of M^-1 A is " + std::to_string(level.lambdaMax) +
                               " (a zero or non-finite matrix?)");
    setupSeconds_.smoother += fencedSecondsSince(space_, start);
    start = std::chrono::steady_clock::now();
    detail::tentativeProlongator(space_, level.aggregateOffsets, level.aggregateMembers, level.nearNullSpace,
                                 level.Ptent.values, levels_[l + 1].nearNullSpace);
    setupSeconds_.prolongator += fencedSecondsSince(space_, start);
  }

  // Z = M^-1 A P_tent, P = P_tent - omega Z, R = P^T.
  void computeProlongator(std::size_t l) {
    const auto start = std::chrono::steady_clock::now();
    Level& level = levels_[l];
    multiplyInto(space_, level.scaledA, level.Ptent, level.Z);
    const double omega = 4.0 / (3.0 * level.lambdaMax);
    detail::smoothProlongator(space_, level.aggregateOf, level.Ptent.values, level.Z, omega, level.P.values);
    transposeInto(space_, level.P, level.restriction);
    setupSeconds_.prolongator += fencedSecondsSince(space_, start);
  }

  // A_{l+1} = R (A P).
  void computeGalerkin(std::size_t l) {
    const auto start = std::chrono::steady_clock::now();
    Level& level = levels_[l];
    multiplyInto(space_, level.A, level.P, level.AP);
    multiplyInto(space_, level.R, level.AP, levels_[l + 1].A);
    detail::unitDiagonalOnEmptyRows(space_, levels_[l + 1].A);
    setupSeconds_.galerkin += fencedSecondsSince(space_, start);
  }

  void factorCoarsest() {
    const auto start = std::chrono::steady_clock::now();
    coarse_.compute(space_, levels_.back().A, static_cast<int>(levels_.size()) - 1);
    setupSeconds_.coarse += fencedSecondsSince(space_, start);
  }

  // Chebyshev iteration for A x = b scaled by M^-1 (Ifpack2's Chebyshev: Saad, Iterative
  // Methods, alg. 12.1), from x = 0 when xIsZero.
  template <class BView, class XView>
  void chebyshev(const Level& level, const BView& b, const XView& x, bool xIsZero) const {
    const double lambdaMax = options_.chebyshevBoost * level.lambdaMax;
    const double lambdaMin = level.lambdaMax / options_.chebyshevEigenRatio;
    const double theta = 0.5 * (lambdaMax + lambdaMin), delta = 0.5 * (lambdaMax - lambdaMin);
    const double s1 = theta / delta;
    double rho = 1.0 / s1;
    if (xIsZero) {
      detail::blockJacobiUpdate(space_, level.blockInverses, b, 0.0, level.w, 1.0 / theta);
      Kokkos::deep_copy(x, level.w);
    } else {
      residual(level, b, x);
      detail::blockJacobiUpdate(space_, level.blockInverses, level.r, 0.0, level.w, 1.0 / theta);
      KokkosBlas::axpy(1.0, level.w, x);
    }
    for (int k = 1; k < options_.chebyshevDegree; ++k) {
      const double rhoNext = 1.0 / (2.0 * s1 - rho);
      residual(level, b, x);
      detail::blockJacobiUpdate(space_, level.blockInverses, level.r, rhoNext * rho, level.w, 2.0 * rhoNext / delta);
      rho = rhoNext;
      KokkosBlas::axpy(1.0, level.w, x);
    }
  }

  // level.r = b - A x
  template <class BView, class XView>
  void residual(const Level& level, const BView& b, const XView& x) const {
    Kokkos::deep_copy(level.r, b);
    KokkosSparse::spmv("N", -1.0, level.A, x, 1.0, level.r);
  }

  template <class BView, class XView>
  void vCycle(std::size_t l, const BView& b, const XView& x) const {
    if (l + 1 == levels_.size()) {
      KokkosBlas::gemv("N", 1.0, coarse_.inverse(), b, 0.0, x);
      return;
    }
    const Level& level = levels_[l];
    const Level& next = levels_[l + 1];
    chebyshev(level, b, x, true);
    residual(level, b, x);
    KokkosSparse::spmv("N", 1.0, level.R, level.r, 0.0, next.b);
    vCycle(l + 1, next.b, next.x);
    KokkosSparse::spmv("N", 1.0, level.P, next.x, 1.0, x);
    chebyshev(level, b, x, false);
  }

  ExecutionSpaceT space_;
  SmoothedAggregationOptions options_;
  std::vector<Level> levels_;
  typename matrix_type::values_type::non_const_type fineValues_;
  CoarseInverse<ExecutionSpaceT> coarse_;
  SmoothedAggregationSetupSeconds setupSeconds_;
};

}  // namespace perishell::multigrid
