#include <perishell/io/atomic_file.hpp>
#include <perishell/io/csv_history.hpp>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <utility>

namespace perishell::io {

CsvHistory::CsvHistory(std::string path, std::vector<std::string> columnNames)
    : path_(std::move(path)), columnNames_(std::move(columnNames)) {
  if (path_.empty()) throw std::invalid_argument("CSV history: empty path");
  if (columnNames_.empty()) throw std::invalid_argument("CSV history '" + path_ + "': no columns");
  for (std::size_t column = 0; column < columnNames_.size(); ++column) {
    const std::string& name = columnNames_[column];
    if (name.empty() || name.find_first_of(",\"\r\n") != std::string::npos)
      throw std::invalid_argument("CSV history '" + path_ + "': column " + std::to_string(column) +
                                  " name '" + name +
                                  "' must be non-empty and free of commas, quotes and line breaks");
  }
  writeFileAtomically(path_, headerLine(columnNames_));
  openToAppend();
}

CsvHistory::CsvHistory(std::string path, std::vector<std::string> columnNames, std::size_t keepRows)
    : path_(std::move(path)), columnNames_(std::move(columnNames)), numRows_(keepRows) {
  std::ifstream in(path_, std::ios::binary);
  if (!in) throw std::runtime_error("cannot continue the history '" + path_ + "': " + std::strerror(errno));
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string header = headerLine(columnNames_);
  if (text.compare(0, header.size(), header) != 0)
    throw std::runtime_error("cannot continue the history '" + path_ + "': its header is not this run's columns (" +
                             header.substr(0, header.size() - 1) + ")");
  std::size_t end = header.size();
  for (std::size_t row = 0; row < keepRows; ++row) {
    const std::size_t newline = text.find('\n', end);
    if (newline == std::string::npos)
      throw std::runtime_error("cannot continue the history '" + path_ + "': it has " + std::to_string(row) +
                               " whole rows, the checkpoint was written after row " + std::to_string(keepRows));
    end = newline + 1;
  }
  if (end < text.size()) writeFileAtomically(path_, text.substr(0, end));
  openToAppend();
}

std::string CsvHistory::headerLine(const std::vector<std::string>& columnNames) {
  std::string header;
  for (std::size_t column = 0; column < columnNames.size(); ++column)
    header += (column == 0 ? "" : ",") + columnNames[column];
  return header + '\n';
}

void CsvHistory::openToAppend() {
  file_.reset(std::fopen(path_.c_str(), "a"));
  if (!file_) throw std::runtime_error("cannot open the history '" + path_ + "' to append: " + std::strerror(errno));
}

void CsvHistory::append(const std::vector<double>& row) {
  if (row.size() != columnNames_.size())
    throw std::invalid_argument("CSV history '" + path_ + "': row " + std::to_string(numRows_) + " has " +
                                std::to_string(row.size()) + " values, expected " +
                                std::to_string(columnNames_.size()));
  std::string line;
  for (std::size_t column = 0; column < row.size(); ++column)
    line += (column == 0 ? "" : ",") + formatCsvValue(row[column]);
  line += '\n';
  if (std::fwrite(line.data(), 1, line.size(), file_.get()) != line.size() || std::fflush(file_.get()) != 0)
    throw std::runtime_error("cannot append to the history '" + path_ + "': " + std::strerror(errno));
  ++numRows_;
}

std::string formatCsvValue(double value) {
  // printf may print "-nan"; one spelling keeps the files diffable.
  if (std::isnan(value)) return "nan";
  if (std::isinf(value)) return value > 0.0 ? "inf" : "-inf";
  char buffer[32];  // %.17g needs at most 24 characters ("-1.2345678901234567e-308")
  std::snprintf(buffer, sizeof buffer, "%.17g", value);
  return buffer;
}

}  // namespace perishell::io
