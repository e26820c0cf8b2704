#pragma once
// The median wall time of repeated runs of a kernel (fenced before and after), the figure
// every perf/ benchmark reports: medians resist the noise of shared machines.
#include <Kokkos_Core.hpp>

#include <algorithm>
#include <chrono>
#include <vector>

namespace perishell::perf {

// prepare() runs untimed before each repeat (e.g. to free what the previous run built).
template <class Prepare, class Kernel>
double medianSeconds(int repeats, const Prepare& prepare, const Kernel& kernel) {
  std::vector<double> seconds;
  for (int r = 0; r < repeats; ++r) {
    prepare();
    Kokkos::fence();
    const auto start = std::chrono::steady_clock::now();
    kernel();
    Kokkos::fence();
    seconds.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  }
  std::sort(seconds.begin(), seconds.end());
  return seconds[seconds.size() / 2];
}

template <class Kernel>
double medianSeconds(int repeats, const Kernel& kernel) {
  return medianSeconds(repeats, [] {}, kernel);
}

}  // namespace perishell::perf
