#pragma once
// A CSV time history (energies, reaction forces, crack length, ... per step). Rows are kept
// in memory and flush() rewrites the whole file atomically (atomic_file.hpp), so the file on
// disk is always a complete table up to the last flush, even if the run is killed.
//
// Format: one header line with the column names as given (put the unit in the name, e.g.
// "time [s]"), then one line per row, comma separated, no spaces. Values are printed with
// %.17g, which round-trips every finite double exactly through strtod. Non-finite values
// are diagnostics (a diverged step should show, not stop the history) and are written
// literally as "nan", "inf" or "-inf" (strtod reads them back; the sign and payload of a
// NaN are not kept).
#include <cstddef>
#include <string>
#include <vector>

namespace perishell::io {

class CsvHistory {
 public:
  // Writes the header at once, so a bad path fails here rather than at the first output
  // step. Column names must be non-empty and free of commas, quotes and line breaks.
  CsvHistory(std::string path, std::vector<std::string> columnNames);

  // Throws std::invalid_argument naming the expected and actual value counts.
  void append(std::vector<double> row);

  // Rewrites the file with the header and every row appended so far.
  void flush() const;

  const std::string& path() const { return path_; }
  const std::vector<std::string>& columnNames() const { return columnNames_; }
  std::size_t numRows() const { return rows_.size(); }

 private:
  std::string path_;
  std::vector<std::string> columnNames_;
  std::vector<std::vector<double>> rows_;
};

// The text CsvHistory writes for one value.
std::string formatCsvValue(double value);

}  // namespace perishell::io
