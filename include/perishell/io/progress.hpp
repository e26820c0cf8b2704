#pragma once
// What a long run prints: progress lines (step, simulated time, elapsed wall time, ETA) at
// most once per interval, and a summary table at the end. The clock is injectable so that
// tests see exact numbers.
#include <chrono>
#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

namespace perishell::io {

class ProgressReporter {
 public:
  using Clock = std::function<double()>;  // seconds since any fixed origin

  // totalSteps >= 1; lines go to out, at most one per intervalSeconds (the first and the
  // last step always print).
  ProgressReporter(long long totalSteps, std::ostream& out, double intervalSeconds = 5.0,
                   Clock clock = steadyClock());

  // Reports step (1-based, <= totalSteps) reached at simulated time [s]; prints when due.
  // Returns whether it printed.
  bool update(long long step, double simulatedTime);
  // The same, with the run's own state in place of the simulated time (a static increment's
  // load factor and iterations).
  bool update(long long step, const std::string& state);

  // A continued run (a restart) starts at step `done`: the ETA takes the rate of this run's steps.
  void continueFrom(long long done) { firstStep_ = done; }

  double elapsedSeconds() const;

  static Clock steadyClock();

 private:
  long long totalSteps_;
  std::ostream& out_;
  double intervalSeconds_;
  Clock clock_;
  double start_;
  double lastPrint_;
  long long firstStep_ = 0;
  bool printed_ = false;
};

// "1 h 02 min", "3 min 07 s", "12.3 s": durations as people read them.
std::string formatDuration(double seconds);

// A two-column table (quantity, value) with a title, aligned for a terminal.
class SummaryTable {
 public:
  explicit SummaryTable(std::string title);
  SummaryTable& add(std::string quantity, std::string value);
  void print(std::ostream& out) const;

 private:
  std::string title_;
  std::vector<std::pair<std::string, std::string>> rows_;
};

}  // namespace perishell::io
