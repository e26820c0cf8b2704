#include <perishell/io/progress.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ostream>
#include <stdexcept>

namespace perishell::io {

ProgressReporter::Clock ProgressReporter::steadyClock() {
  return [] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
  };
}

ProgressReporter::ProgressReporter(long long totalSteps, std::ostream& out, double intervalSeconds, Clock clock)
    : totalSteps_(totalSteps), out_(out), intervalSeconds_(intervalSeconds), clock_(std::move(clock)) {
  if (totalSteps_ < 1) throw std::invalid_argument("progress: total steps must be at least 1");
  if (!(intervalSeconds_ >= 0.0)) throw std::invalid_argument("progress: interval must be >= 0 s");
  start_ = lastPrint_ = clock_();
}

double ProgressReporter::elapsedSeconds() const { return clock_() - start_; }

bool ProgressReporter::update(long long step, double simulatedTime) {
  char time[48];
  std::snprintf(time, sizeof time, "t = %.6e s", simulatedTime);
  return update(step, std::string(time));
}

bool ProgressReporter::update(long long step, const std::string& state) {
  if (step < 1 || step > totalSteps_)
    throw std::out_of_range("progress: step " + std::to_string(step) + " outside 1.." + std::to_string(totalSteps_));
  const double now = clock_();
  const bool due = !printed_ || step == totalSteps_ || now - lastPrint_ >= intervalSeconds_;
  if (!due) return false;
  const double elapsed = now - start_;
  // The remaining steps at the mean rate so far: steady for explicit runs, a rough guide
  // for Newton increments of varying cost.
  const double remaining = elapsed * double(totalSteps_ - step) / double(std::max(step - firstStep_, 1LL));
  char line[512];
  std::snprintf(line, sizeof line, "step %lld/%lld (%5.1f %%)  %s  elapsed %s  ETA %s\n", step, totalSteps_,
                100.0 * double(step) / double(totalSteps_), state.c_str(), formatDuration(elapsed).c_str(),
                formatDuration(remaining).c_str());
  out_ << line << std::flush;
  lastPrint_ = now;
  printed_ = true;
  return true;
}

std::string formatDuration(double seconds) {
  if (!std::isfinite(seconds) || seconds < 0.0) return "?";
  char text[64];
  if (seconds < 60.0) {
    std::snprintf(text, sizeof text, "%.1f s", seconds);
  } else if (seconds < 3600.0) {
    const long long whole = std::llround(seconds);
    std::snprintf(text, sizeof text, "%lld min %02lld s", whole / 60, whole % 60);
  } else {
    const long long minutes = std::llround(seconds / 60.0);
    std::snprintf(text, sizeof text, "%lld h %02lld min", minutes / 60, minutes % 60);
  }
  return text;
}

SummaryTable::SummaryTable(std::string title) : title_(std::move(title)) {}

SummaryTable& SummaryTable::add(std::string quantity, std::string value) {
  rows_.emplace_back(std::move(quantity), std::move(value));
  return *this;
}

void SummaryTable::print(std::ostream& out) const {
  std::size_t width = 8;
  for (const auto& row : rows_) width = std::max(width, row.first.size());
  out << title_ << "\n";
  for (const auto& [quantity, value] : rows_)
    out << "  " << quantity << std::string(width - quantity.size() + 2, ' ') << value << "\n";
}

}  // namespace perishell::io
