#pragma once
// Conjugate gradients on a Kokkos Kernels CRS matrix through Belos' PseudoBlockCGSolMgr,
// with the vectors living (and all vector work running) on the chosen execution space.
#include <perishell/core/types.hpp>
#include <perishell/solvers/belos/crs_operator.hpp>
#include <perishell/solvers/belos/kokkos_multivector.hpp>

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
  enum class Preconditioner { None, Jacobi } preconditioner = Preconditioner::Jacobi;
};

struct CgResult {
  bool converged = false;
  int iterations = 0;
  // Largest relative residual Belos measured at the end (its achievedTol()).
  double achievedTolerance = 0.0;
};

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

}  // namespace detail

// Solves A x = b for symmetric positive definite A. x holds the initial guess on entry and
// the solution on return (also when CG did not converge); b is not modified. Both are used
// in place, without copies. Throws std::invalid_argument for mismatched sizes and
// std::runtime_error when CG breaks down (A or the preconditioner not SPD, NaN residual).
template <class ExecutionSpaceT>
CgResult solveCg(const CrsMatrix<ExecutionSpaceT>& A,
                 const Kokkos::View<const double*, typename ExecutionSpaceT::memory_space>& b,
                 const VectorView<typename ExecutionSpaceT::memory_space>& x, const CgOptions& options = {}) {
  static_assert(Kokkos::is_execution_space<ExecutionSpaceT>::value, "solveCg needs a Kokkos execution space");
  using memory_space = typename ExecutionSpaceT::memory_space;
  using MV = Belos::MultiVec<double>;
  using OP = Belos::Operator<double>;
  using Unmanaged2D = Kokkos::View<double**, Kokkos::LayoutLeft, memory_space, Kokkos::MemoryTraits<Kokkos::Unmanaged>>;

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
  if (n == 0) return CgResult{true, 0, 0.0};
  if (x.data() < b.data() + n && b.data() < x.data() + n) {
    throw std::invalid_argument("perishell::belos::solveCg: x and b share storage");
  }

  // Single-column LayoutLeft views over the caller's memory, so Belos updates x in place.
  // Belos only reads b (LinearProblem takes it as RCP<const MV>), so casting away const is safe.
  const MultiVectorView<memory_space> x2d = Unmanaged2D(x.data(), n, 1);
  const MultiVectorView<memory_space> b2d = Unmanaged2D(const_cast<double*>(b.data()), n, 1);
  const Teuchos::RCP<MV> X = Teuchos::rcp(new KokkosMultiVector<ExecutionSpaceT>(x2d));
  const Teuchos::RCP<const MV> B = Teuchos::rcp(new KokkosMultiVector<ExecutionSpaceT>(b2d));
  const Teuchos::RCP<const OP> op = Teuchos::rcp(new CrsOperator<ExecutionSpaceT>(A));

  const auto problem = Teuchos::rcp(new Belos::LinearProblem<double, MV, OP>(op, X, B));
  if (options.preconditioner == CgOptions::Preconditioner::Jacobi) {
    // Belos' CG iterations apply whichever preconditioner is set as M in z = M r, and the
    // default convergence test ("Norm of Initial Residual") uses unpreconditioned residuals
    // either way. Left would also make setProblem() compute a preconditioned initial
    // residual that this configuration never reads; right skips that apply.
    problem->setRightPrec(Teuchos::rcp(new JacobiPreconditioner<ExecutionSpaceT>(A)));
  }
  if (!problem->setProblem()) {
    throw std::logic_error("perishell::belos::solveCg: Belos::LinearProblem::setProblem() refused the system");
  }

  const auto params = Teuchos::parameterList("perishell CG");
  params->set("Convergence Tolerance", options.tolerance);
  params->set("Maximum Iterations", options.maxIterations);

  Belos::PseudoBlockCGSolMgr<double, MV, OP> solver(problem, params);
  Belos::ReturnType status = Belos::Unconverged;
  try {
    status = solver.solve();
  } catch (const Belos::CGIterateFailure& e) {
    throw std::runtime_error(
        "perishell::belos::solveCg: CG broke down: the matrix or the preconditioner is not symmetric "
        "positive definite (the step length r^T M r / p^T A p was not positive). Belos: " +
        detail::oneLine(e.what()));
  } catch (const Belos::StatusTestError& e) {
    throw std::runtime_error(
        "perishell::belos::solveCg: CG broke down: the residual became NaN (NaN/Inf in A, b or x, "
        "or a singular system). Belos: " +
        detail::oneLine(e.what()));
  } catch (const Belos::BelosError& e) {
    throw std::runtime_error("perishell::belos::solveCg: Belos CG failed: " +
                             detail::oneLine(e.what()));
  }

  // x2d aliases x, and CGIter writes the iterate straight into X; the fence makes the
  // result visible to the caller's next host access.
  ExecutionSpaceT().fence();
  return CgResult{status == Belos::Converged, solver.getNumIters(), solver.achievedTol()};
}

}  // namespace perishell::belos
