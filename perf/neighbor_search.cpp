// Throughput of the device bond-list build (cell list, O(N)) on the build's default
// execution space: square plates of n x n nodes at spacing dx with delta = 3 dx (model.md
// §1), from ~1e4 bonds up to a maximum. Each size is built once untimed, then timed over
// repeats (median). The bond count is checked against the exact lattice count.
// Usage: perishell_perf_neighbor_search [repeats] [max bonds]
#include <perishell/pd/neighbor_search.hpp>

#include "median_seconds.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>

namespace {

constexpr int horizonInSpacings = 3;
constexpr double spacing = 1.0e-3;  // [m]

// Bonds of an n x n lattice: every lattice offset (a, b) within m spacings, once per pair.
long long latticeBonds(const long long n) {
  long long twice = 0;
  const int m = horizonInSpacings;
  for (int a = -m; a <= m; ++a)
    for (int b = -m; b <= m; ++b)
      if (!(a == 0 && b == 0) && a * a + b * b <= m * m) twice += (n - std::abs(a)) * (n - std::abs(b));
  return twice / 2;
}

template <class ExecutionSpaceT>
perishell::CoordinateView<typename ExecutionSpaceT::memory_space> makePlate(const ExecutionSpaceT& space,
                                                                           const int nodesPerSide) {
  perishell::CoordinateView<typename ExecutionSpaceT::memory_space> positions("plate nodes",
                                                                             nodesPerSide * nodesPerSide);
  const double dx = spacing;
  Kokkos::parallel_for(
      "plate nodes", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, nodesPerSide * nodesPerSide),
      KOKKOS_LAMBDA(const int node) {
        positions(node, 0) = (node % nodesPerSide) * dx;
        positions(node, 1) = (node / nodesPerSide) * dx;
        positions(node, 2) = 0.0;
      });
  return positions;
}

}  // namespace

int main(int argc, char* argv[]) {
  Kokkos::ScopeGuard kokkos(argc, argv);
  const int repeats = argc > 1 ? std::max(1, std::atoi(argv[1])) : 7;
  const double maxBonds = argc > 2 ? std::max(1.0e4, std::atof(argv[2])) : 1.0e7;
  using perishell::ExecutionSpace;
  const ExecutionSpace space;
  std::printf("# bond list build on %s (concurrency %d), delta = %d dx, median of %d runs\n", ExecutionSpace::name(),
              ExecutionSpace::concurrency(), horizonInSpacings, repeats);
  std::printf("%10s %12s %12s %14s %12s\n", "nodes", "bonds", "time [s]", "bonds/s", "bytes/bond");
  for (double target = 1.0e4; target <= maxBonds * 1.0001; target *= 3.1623) {
    int nodesPerSide = 4;
    while (latticeBonds(nodesPerSide) < static_cast<long long>(target)) ++nodesPerSide;
    const auto positions = makePlate(space, nodesPerSide);
    const double horizon = horizonInSpacings * spacing;
    auto bonds = perishell::pd::buildBondList(space, positions, horizon, spacing);
    if (static_cast<long long>(bonds.numBonds()) != latticeBonds(nodesPerSide)) {
      std::fprintf(stderr, "error: %zu bonds on a %d x %d lattice, expected %lld\n", bonds.numBonds(),
                   nodesPerSide, nodesPerSide, latticeBonds(nodesPerSide));
      return 1;
    }
    const double median = perishell::perf::medianSeconds(
        repeats, [&] { bonds = {}; },  // free the previous list, as a fresh build would find the memory
        [&] { bonds = perishell::pd::buildBondList(space, positions, horizon, spacing); });
    const double numBonds = static_cast<double>(bonds.numBonds());
    std::printf("%10d %12zu %12.4e %14.4e %12.1f\n", bonds.numNodes(), bonds.numBonds(), median,
                numBonds / median, static_cast<double>(bonds.bytes()) / numBonds);
  }
  return 0;
}
