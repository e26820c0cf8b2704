#pragma once
// The largest eigenvalue of a symmetric tridiagonal matrix: the top Ritz value of a Lanczos
// run (the explicit solver's critical step, the multigrid smoother's spectrum bound).
#include <Eigen/Dense>

#include <vector>

namespace perishell {

// diagonal: n values; offDiagonal: the n - 1 values below it (extra values are ignored).
inline double largestTridiagonalEigenvalue(const std::vector<double>& diagonal,
                                           const std::vector<double>& offDiagonal) {
  const auto n = static_cast<Eigen::Index>(diagonal.size());
  if (n == 0) return 0.0;
  const Eigen::VectorXd d = Eigen::Map<const Eigen::VectorXd>(diagonal.data(), n);
  const Eigen::VectorXd e = Eigen::Map<const Eigen::VectorXd>(offDiagonal.data(), n - 1);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver;
  solver.computeFromTridiagonal(d, e, Eigen::EigenvaluesOnly);
  return solver.eigenvalues().maxCoeff();
}

}  // namespace perishell
