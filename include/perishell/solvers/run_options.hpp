#pragma once
// What `perishell run` takes besides the deck, for both solvers, and the per-phase wall
// times a run writes to DIR/timings.csv (the paper's Table 3 columns; perf/speedup.py
// reads them).
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace perishell::solvers {

// Where a run executes. In a CUDA build Host is Kokkos' default host space (OpenMP): the
// CPU baseline, from the same kernels, in the same binary. In an OpenMP build both are one.
enum class Backend { Device, Host };

struct RunOptions {
  std::string outputDirectory;  // empty: the deck's output.directory
  Backend backend = Backend::Device;
  // Stop after this many steps (explicit) or increments (implicit); the deck's load
  // schedule is kept, so a truncated run follows the full one up to there.
  std::optional<long long> maxSteps;
  // Fence between the explicit step's phases to time them (implicit phases are always
  // timed); costs a synchronisation per phase.
  bool timePhases = false;
  // A distributed explicit step's forces around its halo exchange (ExplicitOptions::
  // overlapExchange): forced on or off, or (empty) on unless ranks of a node share a GPU.
  std::optional<bool> exchangeOverlap;
  // The longest a long implicit increment goes without a progress line [s].
  double progressEverySeconds = 2.0;
  // Continue the run whose output directory this is, from its checkpoint.h5
  // (solvers/run_checkpoint.hpp); the run writes on into that directory.
  std::string restartDirectory;
};

// (phase, seconds) rows, in the order written.
using PhaseTimes = std::vector<std::pair<std::string, double>>;

// Writes DIR/timings.csv (`phase,seconds`) atomically; returns its path.
std::string writePhaseTimes(const std::string& directory, const PhaseTimes& phases);

}  // namespace perishell::solvers
