// Per-kernel time of any perishell run, by kernel label: a Kokkos Tools library (the device
// machine has no Nsight Systems, and Nsight Compute serialises and replays every launch).
// CUDA builds: each parallel_for/reduce/scan is bracketed by two CUDA events on the legacy
// default stream, which orders it against the kernels of every blocking stream, so the
// events time the kernel itself; the events are read in batches, off the launch path (a
// short kernel still reads a few microseconds long: the events' own launches). Host builds:
// a host backend's dispatch returns when the kernel is done, so the wall clock between begin
// and end is its time.
// At exit it prints, per label, launches, total and mean time, sorted by total.
//
//   KOKKOS_PROFILE_LIBRARY=build/PRESET/perf/libperishell_kernel_timer.so perishell run DECK
//   (cmake/gpu_bundle.sh packs it as lib/libperishell_kernel_timer.so)
#ifdef PERISHELL_KERNEL_TIMER_CUDA
#include <cuda_runtime.h>
#endif

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <map>
#include <string>
#include <vector>

namespace {

struct Totals {
  long launches = 0;
  double milliseconds = 0.0;
};

std::map<std::string, Totals> totals;

#ifdef PERISHELL_KERNEL_TIMER_CUDA
struct Launch {
  std::string label;
  cudaEvent_t start, stop;
};

std::vector<Launch> pending;
constexpr std::size_t batch = 4096;

void drain() {
  if (pending.empty()) return;
  cudaEventSynchronize(pending.back().stop);
  for (Launch& launch : pending) {
    float milliseconds = 0.0f;
    cudaEventElapsedTime(&milliseconds, launch.start, launch.stop);
    Totals& t = totals[launch.label];
    ++t.launches;
    t.milliseconds += milliseconds;
    cudaEventDestroy(launch.start);
    cudaEventDestroy(launch.stop);
  }
  pending.clear();
}

void begin(const char* label, std::uint64_t* id) {
  if (pending.size() >= batch) drain();
  Launch launch{label, nullptr, nullptr};
  cudaEventCreate(&launch.start);
  cudaEventCreate(&launch.stop);
  cudaEventRecord(launch.start, 0);
  pending.push_back(launch);
  *id = pending.size() - 1;
}

void end(std::uint64_t id) { cudaEventRecord(pending[id].stop, 0); }
#else
std::string running;
std::chrono::steady_clock::time_point started;

void drain() {}

void begin(const char* label, std::uint64_t* id) {
  running = label;
  *id = 0;
  started = std::chrono::steady_clock::now();
}

void end(std::uint64_t) {
  Totals& t = totals[running];
  ++t.launches;
  t.milliseconds += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - started).count();
}
#endif

}  // namespace

extern "C" {
void kokkosp_init_library(int, std::uint64_t, std::uint32_t, void*) {}
void kokkosp_begin_parallel_for(const char* label, std::uint32_t, std::uint64_t* id) { begin(label, id); }
void kokkosp_end_parallel_for(std::uint64_t id) { end(id); }
void kokkosp_begin_parallel_reduce(const char* label, std::uint32_t, std::uint64_t* id) { begin(label, id); }
void kokkosp_end_parallel_reduce(std::uint64_t id) { end(id); }
void kokkosp_begin_parallel_scan(const char* label, std::uint32_t, std::uint64_t* id) { begin(label, id); }
void kokkosp_end_parallel_scan(std::uint64_t id) { end(id); }
void kokkosp_finalize_library() {
  drain();
  std::vector<std::pair<std::string, Totals>> sorted(totals.begin(), totals.end());
  std::sort(sorted.begin(), sorted.end(),
            [](const auto& a, const auto& b) { return a.second.milliseconds > b.second.milliseconds; });
  std::fprintf(stderr, "# kernel timer: %-70s %10s %12s %12s\n", "label", "launches", "total [ms]", "mean [us]");
  for (const auto& [label, t] : sorted)
    std::fprintf(stderr, "# kernel timer: %-70.70s %10ld %12.3f %12.2f\n", label.c_str(), t.launches, t.milliseconds,
                 1e3 * t.milliseconds / t.launches);
}
}
