#pragma once
// What the run-driver tests share: the run's backend for the test's execution space, and
// history.csv read back by column name.
#include <perishell/solvers/run_options.hpp>

#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

namespace perishell_test_run_files {

inline std::vector<std::string> splitCsv(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream stream(line);
  for (std::string cell; std::getline(stream, cell, ',');) cells.push_back(cell);
  return cells;
}

// The run driver's backend that runs on ExecutionSpaceT.
template <class ExecutionSpaceT>
perishell::solvers::Backend backendOf() {
  return std::is_same_v<ExecutionSpaceT, perishell::ExecutionSpace> ? perishell::solvers::Backend::Device
                                                                     : perishell::solvers::Backend::Host;
}

// history.csv: its column names and its rows, each row by column name.
struct History {
  std::vector<std::string> columns;
  std::vector<std::map<std::string, double>> rows;
};

inline History readHistory(const std::string& path) {
  History history;
  std::ifstream file(path);
  std::string line;
  if (!std::getline(file, line)) return history;
  history.columns = splitCsv(line);
  while (std::getline(file, line)) {
    const auto cells = splitCsv(line);
    auto& row = history.rows.emplace_back();
    for (std::size_t k = 0; k < cells.size() && k < history.columns.size(); ++k)
      row[history.columns[k]] = std::stod(cells[k]);
  }
  return history;
}

}  // namespace perishell_test_run_files
