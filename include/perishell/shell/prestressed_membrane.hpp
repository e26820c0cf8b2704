#pragma once
// Out-of-plane stiffness of a membrane under uniform isotropic in-plane tension T [N/m]:
// K_ab = T * integral of grad(N_a) . grad(N_b) dA, the initial-stress stiffness of a shell
// with a pure membrane prestress (model.md §5, K_S term). Assembled by element mapping:
// one thread per element, atomic_add into the CRS values through the precomputed slots.
#include <perishell/assembly/quad_crs_pattern.hpp>
#include <perishell/mesh/bilinear_quad.hpp>

#include <cmath>

namespace perishell::shell {

template <class ExecutionSpaceT, class MemorySpaceT>
void assembleMembraneStiffness(const ExecutionSpaceT& space, const mesh::QuadMesh<MemorySpaceT>& mesh,
                               const assembly::QuadCrsPattern<MemorySpaceT>& pattern, double tension,
                               const VectorView<MemorySpaceT>& values) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  const auto coordinates = mesh.coordinates;
  const auto quads = mesh.quads;
  const auto valueSlot = pattern.valueSlot;
  Kokkos::parallel_for(
      "perishell::assembleMembraneStiffness",
      Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, mesh.numElements()),
      KOKKOS_LAMBDA(const int element) {
        double x[4][3];
        mesh::bilinear::gatherNodes(coordinates, quads, element, x);
        double k[4][4] = {};
        for (int q = 0; q < mesh::bilinear::numGaussPoints; ++q) {
          const auto point =
              mesh::bilinear::evaluate(x, mesh::bilinear::gaussXi(q), mesh::bilinear::gaussEta(q));
          for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b) k[a][b] += tension * point.gradientDot(a, b) * point.areaElement;
        }
        for (int a = 0; a < 4; ++a)
          for (int b = 0; b < 4; ++b) Kokkos::atomic_add(&values(valueSlot(element, a, b)), k[a][b]);
      });
}

// Centre deflection of a square membrane of side a, fixed edges, tension T, pressure p:
// the double sine series of T lap(w) = -p, w = 16 p a^2 / (pi^4 T) sum_{m,n odd}
// (-1)^((m+n)/2-1) / (m n (m^2+n^2)) at the centre. Terms fall as 1/(m n (m^2+n^2)):
// 2000 odd indices each way leave < 1e-12 relative error.
inline double squareMembraneCentreDeflection(double pressure, double side, double tension) {
  constexpr double pi = 3.14159265358979323846;
  double sum = 0.0;
  for (int m = 1; m < 4000; m += 2)
    for (int n = 1; n < 4000; n += 2) {
      const double sign = (((m + n) / 2 - 1) % 2 == 0) ? 1.0 : -1.0;
      sum += sign / (double(m) * n * (double(m) * m + double(n) * n));
    }
  return 16.0 * pressure * side * side / (std::pow(pi, 4) * tension) * sum;
}

}  // namespace perishell::shell
