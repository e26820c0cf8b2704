#include <perishell/io/atomic_file.hpp>
#include <perishell/solvers/run_options.hpp>

#include <cstdio>
#include <filesystem>

namespace perishell::solvers {

std::string writePhaseTimes(const std::string& directory, const PhaseTimes& phases) {
  std::filesystem::create_directories(directory);
  std::string text = "phase,seconds\n";
  for (const auto& [phase, seconds] : phases) {
    char value[32];
    std::snprintf(value, sizeof value, "%.9g", seconds);
    text += phase + "," + value + "\n";
  }
  const std::string path = directory + "/timings.csv";
  io::writeFileAtomically(path, text);
  return path;
}

}  // namespace perishell::solvers
