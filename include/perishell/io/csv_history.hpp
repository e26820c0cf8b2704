#pragma once
// A CSV time history (energies, reaction forces, crack length, ... per step). The header is
// written atomically when the history is made (atomic_file.hpp); each row is then appended to
// the file as it comes, in one write, so a running or killed run's history.csv holds every row
// so far, and a row costs its own line whatever the run's length. A kill inside that one write
// can leave a partial last line; the rows before it stay whole.
//
// Format: one header line with the column names as given (put the unit in the name, e.g.
// "time [s]"), then one line per row, comma separated, no spaces. Values are printed with
// %.17g, which round-trips every finite double exactly through strtod. Non-finite values
// are diagnostics (a diverged step should show, not stop the history) and are written
// literally as "nan", "inf" or "-inf" (strtod reads them back; the sign and payload of a
// NaN are not kept).
#include <cstddef>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

namespace perishell::io {

class CsvHistory {
 public:
  // Writes the header at once, so a bad path fails here rather than at the first output
  // step. Column names must be non-empty and free of commas, quotes and line breaks.
  CsvHistory(std::string path, std::vector<std::string> columnNames);

  // Continues the history an earlier run left at `path` (a restart, io/checkpoint.hpp): its
  // header must name the same columns and its first keepRows rows stay; rows after them (the
  // interrupted run's beyond its checkpoint) are cut off, atomically. Throws
  // std::runtime_error naming the file when it is missing, has other columns or fewer rows.
  CsvHistory(std::string path, std::vector<std::string> columnNames, std::size_t keepRows);

  // Appends the row to the file. Throws std::invalid_argument naming the expected and actual
  // value counts, std::runtime_error naming the file when the write fails (a full disk).
  void append(const std::vector<double>& row);

  const std::string& path() const { return path_; }
  const std::vector<std::string>& columnNames() const { return columnNames_; }
  std::size_t numRows() const { return numRows_; }

 private:
  static std::string headerLine(const std::vector<std::string>& columnNames);
  void openToAppend();

  struct CloseFile {
    void operator()(std::FILE* file) const { std::fclose(file); }
  };
  std::string path_;
  std::vector<std::string> columnNames_;
  std::size_t numRows_ = 0;
  std::unique_ptr<std::FILE, CloseFile> file_;
};

// The text CsvHistory writes for one value.
std::string formatCsvValue(double value);

}  // namespace perishell::io
