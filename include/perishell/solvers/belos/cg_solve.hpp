#pragma once
// Conjugate gradients on a Kokkos Kernels CRS matrix through Belos' PseudoBlockCGSolMgr,
// with the vectors living (and all vector work running) on the chosen execution space.
// When CG breaks down (an indefinite tangent near a limit point, or a preconditioner that
// is not SPD) the solve restarts from the initial guess with Belos' BlockGmresSolMgr.
#include <perishell/core/types.hpp>
#include <perishell/solvers/belos/block_jacobi.hpp>
#include <perishell/solvers/belos/crs_operator.hpp>
#include <perishell/solvers/belos/kokkos_multivector.hpp>

#include <BelosBlockGmresSolMgr.hpp>
#include <BelosLinearProblem.hpp>
#include <BelosMultiVec.hpp>
#include <BelosOperator.hpp>
#include <BelosPseudoBlockCGSolMgr.hpp>
#include <BelosStatusTest.hpp>
#include <BelosTypes.hpp>
#include <Teuchos_ParameterList.hpp>
#include <Teuchos_RCP.hpp>

#include <Kokkos_Core.hpp>

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace perishell::belos {

struct CgOptions {
  // Relative to the initial residual: stop when ||b - A x_k|| <= tolerance * ||b - A x_0||
  // (Belos' implicit residual, scaled by "Norm of Initial Residual", its default).
  double tolerance = 1e-10;
  int maxIterations = 1000;
  // Amg (smoothed-aggregation multigrid, solvers/multigrid) needs node positions, so the
  // caller builds it and passes it to solveCg; the others are built from A alone.
  enum class Preconditioner { None, Jacobi, BlockJacobi, Amg } preconditioner = Preconditioner::Jacobi;
  // Rows per diagonal block for BlockJacobi: the DOF of one node (6 for a shell node).
  int blockSize = 6;
  // Cg for a symmetric A; Gmres from the start for a non-symmetric one (the exact tangent
  // under applied moments, TangentForm::Exact).
  enum class Method { Cg, Gmres } method = Method::Cg;
  // On a CG breakdown, restart from the initial guess with GMRES instead of throwing.
  bool fallbackOnBreakdown = true;
  // Krylov vectors GMRES builds before it restarts; it stores that many vectors of length n.
  int gmresRestart = 200;
};

struct CgResult {
  bool converged = false;
  int iterations = 0;  // of the method that produced x
  // Largest relative residual Belos measured at the end (its achievedTol()).
  double achievedTolerance = 0.0;
  std::string method = "CG";  // "CG", or "GMRES" (asked for, or after a CG breakdown)
  std::string breakdown;      // why CG broke down when method is "GMRES", else empty
};

// The preconditioner names of the input deck: "none", "jacobi", "block-jacobi", "amg".
inline CgOptions::Preconditioner preconditionerFromName(const std::string& name) {
  using Preconditioner = CgOptions::Preconditioner;
  if (name == "none") return Preconditioner::None;
  if (name == "jacobi") return Preconditioner::Jacobi;
  if (name == "block-jacobi") return Preconditioner::BlockJacobi;
  if (name == "amg") return Preconditioner::Amg;
  throw std::invalid_argument("perishell::belos: unknown preconditioner '" + name +
                              "'; valid names are none, jacobi, block-jacobi, amg");
}

namespace detail {

// Teuchos exception texts span several lines (file, throw number, test, message).
inline std::string oneLine(const std::string& text) {
  std::string line;
  for (const char c : text) {
    const bool space = c == '\n' || c == ' ';
    if (space && (line.empty() || line.back() == ' ')) continue;
    line += space ? ' ' : c;
  }
  if (!line.empty() && line.back() == ' ') line.pop_back();
  return line;
}

template <class ExecutionSpaceT>
Teuchos::RCP<const Belos::Operator<double>> makePreconditioner(const CrsMatrix<ExecutionSpaceT>& A,
                                                               const CgOptions& options) {
  switch (options.preconditioner) {
    case CgOptions::Preconditioner::None: return Teuchos::null;
    case CgOptions::Preconditioner::Jacobi: return Teuchos::rcp(new JacobiPreconditioner<ExecutionSpaceT>(A));
    case CgOptions::Preconditioner::BlockJacobi:
      return Teuchos::rcp(new BlockJacobiPreconditioner<ExecutionSpaceT>(A, options.blockSize));
    case CgOptions::Preconditioner::Amg:
      throw std::invalid_argument(
          "perishell::belos::solveCg: the amg preconditioner needs the node positions: build a "
          "multigrid::SmoothedAggregationPreconditioner and pass it to solveCg");
  }
  throw std::invalid_argument("perishell::belos::solveCg: unknown preconditioner " +
                              std::to_string(static_cast<int>(options.preconditioner)));
}

using LinearProblem = Belos::LinearProblem<double, Belos::MultiVec<double>, Belos::Operator<double>>;

inline Teuchos::RCP<LinearProblem> makeProblem(const Teuchos::RCP<const Belos::Operator<double>>& A,
                                               const Teuchos::RCP<Belos::MultiVec<double>>& X,
                                               const Teuchos::RCP<const Belos::MultiVec<double>>& B,
                                               const Teuchos::RCP<const Belos::Operator<double>>& preconditioner) {
  const auto problem = Teuchos::rcp(new LinearProblem(A, X, B));
  // Right preconditioning: CG applies whichever M is set in z = M r, and both CG's and
  // GMRES' convergence tests then see unpreconditioned residuals. Left would also make
  // setProblem() compute a preconditioned initial residual that CG never reads, and would
  // make GMRES minimise the preconditioned residual instead of the true one.
  if (!preconditioner.is_null()) problem->setRightPrec(preconditioner);
  if (!problem->setProblem()) {
    throw std::logic_error("perishell::belos::solveCg: Belos::LinearProblem::setProblem() refused the system");
  }
  return problem;
}

// Runs a Belos solver manager; translates its failures except CG's breakdown, which the
// caller handles.
template <class SolverManager>
CgResult runSolver(SolverManager& solver, const std::string& method, const std::string& breakdown) {
  Belos::ReturnType status = Belos::Unconverged;
  try {
    status = solver.solve();
  } catch (const Belos::CGIterateFailure&) {
    throw;
  } catch (const Belos::StatusTestError& e) {
    throw std::runtime_error("perishell::belos::solveCg: " + method +
                             " broke down: the residual became NaN (NaN/Inf in A, b or x, or a singular "
                             "system). Belos: " +
                             oneLine(e.what()));
  } catch (const Belos::BelosError& e) {
    throw std::runtime_error("perishell::belos::solveCg: Belos " + method + " failed: " + oneLine(e.what()) +
                             (breakdown.empty() ? "" : " (after " + breakdown + ")"));
  }
  return CgResult{status == Belos::Converged, solver.getNumIters(), solver.achievedTol(), method, breakdown};
}

// Throws std::invalid_argument for mismatched sizes, bad options or aliased x and b.
template <class ExecutionSpaceT>
void checkCgArguments(const CrsMatrix<ExecutionSpaceT>& A,
                      const Kokkos::View<const double*, typename ExecutionSpaceT::memory_space>& b,
                      const VectorView<typename ExecutionSpaceT::memory_space>& x, const CgOptions& options) {
  const auto n = static_cast<std::size_t>(A.numRows());
  if (A.numRows() != A.numCols() || b.extent(0) != n || x.extent(0) != n) {
    std::ostringstream msg;
    msg << "perishell::belos::solveCg: A is " << A.numRows() << " x " << A.numCols() << ", b has "
        << b.extent(0) << " entries, x has " << x.extent(0);
    throw std::invalid_argument(msg.str());
  }
  if (!(options.tolerance > 0.0) || options.maxIterations < 0) {
    throw std::invalid_argument("perishell::belos::solveCg: need tolerance > 0 and maxIterations >= 0, got " +
                                std::to_string(options.tolerance) + " and " +
                                std::to_string(options.maxIterations));
  }
  if ((options.fallbackOnBreakdown || options.method == CgOptions::Method::Gmres) && options.gmresRestart < 1) {
    throw std::invalid_argument("perishell::belos::solveCg: gmresRestart must be at least 1, got " +
                                std::to_string(options.gmresRestart));
  }
  if (n != 0 && x.data() < b.data() + n && b.data() < x.data() + n) {
    throw std::invalid_argument("perishell::belos::solveCg: x and b share storage");
  }
}

}  // namespace detail

// Solves A x = b, meant for symmetric positive definite A (CG), or for any non-singular A
// with options.method Gmres (then GMRES from the start). x holds the initial guess on
// entry and the solution on return (also when the solver did not converge); b is not
// modified. Both are used in place, without copies. When CG breaks down (A or the
// preconditioner not SPD) and options.fallbackOnBreakdown is set, x is reset to the initial
// guess and GMRES solves instead (result.method, result.breakdown say so); without it,
// std::runtime_error. Throws std::invalid_argument for mismatched sizes or options,
// std::runtime_error for a NaN residual or a preconditioner that cannot be built.
//
// preconditioner: a prebuilt operator (M ~ A^-1, kept across solves, e.g. a multigrid
// hierarchy updated per Newton iteration) used instead of options.preconditioner; null for
// none.
// rows: where A, b and x hold one rank's rows of a system split over ranks (DistributedRows;
// collective then, and the preconditioner must leave the halo rows of its output zero when
// those of its input are); null on a single rank.
template <class ExecutionSpaceT>
CgResult solveCg(const CrsMatrix<ExecutionSpaceT>& A,
                 const Kokkos::View<const double*, typename ExecutionSpaceT::memory_space>& b,
                 const VectorView<typename ExecutionSpaceT::memory_space>& x, const CgOptions& options,
                 const Teuchos::RCP<const Belos::Operator<double>>& preconditioner,
                 const SharedRows<typename ExecutionSpaceT::memory_space>& rows = nullptr) {
  static_assert(Kokkos::is_execution_space<ExecutionSpaceT>::value, "solveCg needs a Kokkos execution space");
  using memory_space = typename ExecutionSpaceT::memory_space;
  using MV = Belos::MultiVec<double>;
  using OP = Belos::Operator<double>;
  using Unmanaged2D = Kokkos::View<double**, Kokkos::LayoutLeft, memory_space, Kokkos::MemoryTraits<Kokkos::Unmanaged>>;

  detail::checkCgArguments(A, b, x, options);
  const auto n = static_cast<std::size_t>(A.numRows());
  // A rank with no rows still takes part in a distributed solve's collectives.
  if (n == 0 && !rows) return CgResult{true, 0, 0.0, "CG", ""};

  // Single-column LayoutLeft views over the caller's memory, so Belos updates x in place.
  // Belos only reads b (LinearProblem takes it as RCP<const MV>), so casting away const is safe.
  const MultiVectorView<memory_space> x2d = Unmanaged2D(x.data(), n, 1);
  const MultiVectorView<memory_space> b2d = Unmanaged2D(const_cast<double*>(b.data()), n, 1);
  const Teuchos::RCP<MV> X = Teuchos::rcp(new KokkosMultiVector<ExecutionSpaceT>(x2d, rows));
  const Teuchos::RCP<const MV> B = Teuchos::rcp(new KokkosMultiVector<ExecutionSpaceT>(b2d, rows));
  const Teuchos::RCP<const OP> op = Teuchos::rcp(new CrsOperator<ExecutionSpaceT>(A, rows));

  std::string breakdown;
  if (options.method == CgOptions::Method::Cg) {
    // CG overwrites x as it goes; the fallback restarts from the caller's guess.
    VectorView<memory_space> initialGuess;
    if (options.fallbackOnBreakdown) {
      initialGuess = VectorView<memory_space>(
          Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::belos::initial_guess"), n);
      Kokkos::deep_copy(initialGuess, x);
    }
    const auto params = Teuchos::parameterList("perishell CG");
    params->set("Convergence Tolerance", options.tolerance);
    params->set("Maximum Iterations", options.maxIterations);
    try {
      Belos::PseudoBlockCGSolMgr<double, MV, OP> cg(detail::makeProblem(op, X, B, preconditioner), params);
      const CgResult result = detail::runSolver(cg, "CG", "");
      // x2d aliases x, and CGIter writes the iterate straight into X; the fence makes the
      // result visible to the caller's next host access.
      ExecutionSpaceT().fence();
      return result;
    } catch (const Belos::CGIterateFailure& e) {
      breakdown =
          "CG broke down: the matrix or the preconditioner is not symmetric positive definite (the step "
          "length r^T M r / p^T A p was not positive). Belos: " +
          detail::oneLine(e.what());
      if (!options.fallbackOnBreakdown) throw std::runtime_error("perishell::belos::solveCg: " + breakdown);
    }
    Kokkos::deep_copy(x, initialGuess);
  }

  const auto gmresParams = Teuchos::parameterList("perishell GMRES");
  gmresParams->set("Convergence Tolerance", options.tolerance);
  gmresParams->set("Maximum Iterations", options.maxIterations);
  gmresParams->set("Num Blocks", options.gmresRestart);
  // Enough restarts that the iteration limit, not the restart count, ends the solve.
  gmresParams->set("Maximum Restarts", options.maxIterations / options.gmresRestart + 1);
  Belos::BlockGmresSolMgr<double, MV, OP> gmres(detail::makeProblem(op, X, B, preconditioner), gmresParams);
  const CgResult result = detail::runSolver(gmres, "GMRES", breakdown);
  ExecutionSpaceT().fence();
  return result;
}

// As above, with the preconditioner options.preconditioner builds from A.
template <class ExecutionSpaceT>
CgResult solveCg(const CrsMatrix<ExecutionSpaceT>& A,
                 const Kokkos::View<const double*, typename ExecutionSpaceT::memory_space>& b,
                 const VectorView<typename ExecutionSpaceT::memory_space>& x, const CgOptions& options = {}) {
  detail::checkCgArguments(A, b, x, options);
  return solveCg<ExecutionSpaceT>(A, b, x, options, detail::makePreconditioner(A, options));
}

}  // namespace perishell::belos
