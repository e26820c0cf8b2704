// The stack-verification case end to end on the device: atomic assembly into a Kokkos
// Kernels CRS matrix, constraint elimination, Belos PCG, against the exact series solution.
#include <perishell/cases/pressurised_membrane.hpp>

namespace {

TEST(TEST_CATEGORY, pressurised_membrane_matches_series_solution_with_second_order_convergence) {
  perishell::cases::PressurisedMembraneOptions options;
  options.side = 2.0;
  options.tension = 5.0e3;
  options.pressure = 3.0e2;
  options.solver.tolerance = 1e-12;

  options.cellsPerSide = 16;
  const auto coarse = perishell::cases::runPressurisedMembrane(TEST_EXECSPACE{}, options);
  options.cellsPerSide = 32;
  const auto fine = perishell::cases::runPressurisedMembrane(TEST_EXECSPACE{}, options);

  // 16 p a^2 / (pi^4 T) * 0.4545... = 0.07367135 p a^2 / T (the series, evaluated independently).
  EXPECT_NEAR(fine.analyticCentreDeflection, 0.0736713532794 * 3.0e2 * 4.0 / 5.0e3, 1e-12);
  EXPECT_TRUE(fine.solve.converged);
  EXPECT_NEAR(fine.meshArea, 4.0, 1e-12);
  EXPECT_EQ(fine.numNodes, 33 * 33);
  EXPECT_EQ(fine.numConstrained, 4 * 32);
  EXPECT_LT(fine.relativeError, 2e-3);
  // Bilinear elements converge at O(h^2) in nodal values: halving h divides the error by ~4.
  const double order = std::log2(coarse.relativeError / fine.relativeError);
  EXPECT_GT(order, 1.8);
  EXPECT_LT(order, 2.2);
}

TEST(TEST_CATEGORY, pressurised_membrane_rejects_odd_mesh_and_bad_tension) {
  perishell::cases::PressurisedMembraneOptions options;
  options.cellsPerSide = 7;
  EXPECT_THROW(perishell::cases::runPressurisedMembrane(TEST_EXECSPACE{}, options), std::invalid_argument);
  options.cellsPerSide = 8;
  options.tension = -1.0;
  EXPECT_THROW(perishell::cases::runPressurisedMembrane(TEST_EXECSPACE{}, options), std::invalid_argument);
}

}  // namespace
