// Meshes a 2 m x 1 m plate and sums the node areas on the default execution space.
#include <perishell/mesh/node_areas.hpp>

#include <cstdio>

int main(int argc, char* argv[]) {
  Kokkos::ScopeGuard kokkos(argc, argv);
  const auto mesh = perishell::mesh::mirrorTo<perishell::MemorySpace>(
      perishell::mesh::makeRectangularPlate(2.0, 1.0, 8, 4));
  const auto areas = perishell::mesh::computeNodeAreas(perishell::ExecutionSpace{}, mesh);
  double total = 0.0;
  Kokkos::parallel_reduce(
      Kokkos::RangePolicy<perishell::ExecutionSpace>(0, mesh.numNodes()),
      KOKKOS_LAMBDA(const int node, double& sum) { sum += areas(node); }, total);
  std::printf("consumer: total area %.6e m^2 on %s\n", total, perishell::ExecutionSpace::name());
  return 0;
}
