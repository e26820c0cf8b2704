#pragma once
// Wall time of device work: kernels launch asynchronously, so a phase's time is read only
// after its execution space has finished it.
#include <chrono>

namespace perishell {

// Seconds since start, after the space's work is done.
template <class ExecutionSpaceT>
double fencedSecondsSince(const ExecutionSpaceT& space, std::chrono::steady_clock::time_point start) {
  space.fence();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace perishell
