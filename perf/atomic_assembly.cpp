// Throughput of element-mapped atomic assembly (the paper's §3.2.1 pattern) on the build's
// default device: node areas (4 atomics/element) and the membrane stiffness into CRS values
// (16 atomics/element), for plates from 1e4 to ~1e6 nodes. Prints the median of repeated
// runs as elements/s. Usage: perishell_perf_atomic_assembly [repeats] [max cells per side]
#include <perishell/assembly/quad_crs_pattern.hpp>
#include <perishell/core/runtime.hpp>
#include <perishell/mesh/node_areas.hpp>
#include <perishell/shell/prestressed_membrane.hpp>

#include "median_seconds.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>


int main(int argc, char* argv[]) {
  Kokkos::ScopeGuard kokkos(argc, argv);
  const int repeats = argc > 1 ? std::max(1, std::atoi(argv[1])) : 11;
  const int maxCells = argc > 2 ? std::max(100, std::atoi(argv[2])) : 1000;
  using perishell::ExecutionSpace;
  using perishell::MemorySpace;
  using perishell::perf::medianSeconds;
  std::printf("# atomic assembly on %s (concurrency %d), median of %d runs\n", ExecutionSpace::name(),
              ExecutionSpace::concurrency(), repeats);
  std::printf("%10s %10s %16s %16s\n", "nodes", "elements", "areas [elem/s]", "stiffness [elem/s]");
  for (int cells = 100; cells <= maxCells; cells = cells * 10 / 3 + (cells * 10 / 3) % 2) {
    const auto hostMesh = perishell::mesh::makeRectangularPlate(1.0, 1.0, cells, cells);
    const auto mesh = perishell::mesh::mirrorTo<MemorySpace>(hostMesh);
    const auto pattern =
        perishell::assembly::mirrorTo<MemorySpace>(perishell::assembly::buildQuadCrsPattern(hostMesh));
    perishell::VectorView<MemorySpace> values("values", pattern.numEntries());
    const ExecutionSpace space;
    const double areaSeconds =
        medianSeconds(repeats, [&] { perishell::mesh::computeNodeAreas(space, mesh); });
    const double stiffnessSeconds = medianSeconds(repeats, [&] {
      Kokkos::deep_copy(values, 0.0);
      perishell::shell::assembleMembraneStiffness(space, mesh, pattern, 1.0, values);
    });
    const double elements = mesh.numElements();
    std::printf("%10d %10d %16.3e %16.3e\n", mesh.numNodes(), mesh.numElements(), elements / areaSeconds,
                elements / stiffnessSeconds);
  }
  return 0;
}
