#pragma once
// A run's state at one step or increment, to continue the run from (`perishell run DECK
// --restart DIR`, docs/reliability.md §9): named arrays of doubles, integers and bytes, and
// texts, held on the host and written as one HDF5 file, atomically (io/atomic_file.hpp), so
// a reader, or a run killed while writing, sees the previous checkpoint or the complete new
// one. Doubles are stored as IEEE float64: a restored state is, bit for bit, the one saved,
// whichever backend saved or restores it.
//
// File: "/format" (the text "perishell checkpoint 1"), and groups "/reals", "/integers",
// "/bytes" and "/texts" with one dataset per entry. Entry names are letters, digits, '-',
// '_' and '.'.
#include <Kokkos_Core.hpp>

#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace perishell::io {

// A checkpoint that cannot be read, lacks an entry, or does not fit the model restored into;
// the message names the file and the entry.
class CheckpointError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// The file a run keeps its checkpoint in, inside its output directory.
constexpr const char* checkpointFileName = "checkpoint.h5";

class Checkpoint {
 public:
  void putReals(const std::string& name, std::vector<double> values);
  void putIntegers(const std::string& name, std::vector<long long> values);
  void putBytes(const std::string& name, std::vector<std::uint8_t> values);
  void putText(const std::string& name, std::string text);
  void putReal(const std::string& name, double value) { putReals(name, {value}); }
  void putInteger(const std::string& name, long long value) { putIntegers(name, {value}); }

  bool has(const std::string& name) const;
  // Each throws CheckpointError naming the file and the entry when it is missing, or when a
  // single value is asked of an entry that holds another number of them.
  const std::vector<double>& reals(const std::string& name) const;
  const std::vector<long long>& integers(const std::string& name) const;
  const std::vector<std::uint8_t>& bytes(const std::string& name) const;
  const std::string& text(const std::string& name) const;
  double real(const std::string& name) const;
  long long integer(const std::string& name) const;

  // Writes the file atomically; throws std::runtime_error naming the path and the reason.
  void write(const std::string& path) const;
  // Throws CheckpointError naming the path: missing, unreadable, or not a perishell checkpoint.
  static Checkpoint read(const std::string& path);
  // The file read from ("" for one made in memory), for messages.
  const std::string& source() const { return source_; }

  // "checkpoint <file>: " for messages about its entries.
  std::string context() const { return "checkpoint " + (source_.empty() ? std::string("(in memory)") : source_) + ": "; }

 private:
  [[noreturn]] void missing(const std::string& name) const;

  std::map<std::string, std::vector<double>> reals_;
  std::map<std::string, std::vector<long long>> integers_;
  std::map<std::string, std::vector<std::uint8_t>> bytes_;
  std::map<std::string, std::string> texts_;
  std::string source_;
};

// A contiguous view (device or host) into a checkpoint entry, through a host copy (output
// steps only, never the hot path): doubles as reals, bytes as bytes, other integers as integers.
template <class ViewT>
void putView(Checkpoint& checkpoint, const std::string& name, const ViewT& view) {
  using Value = typename ViewT::non_const_value_type;
  const auto host = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, view);
  const Value* data = host.data();
  const std::size_t size = host.span();
  if constexpr (std::is_same_v<Value, double>)
    checkpoint.putReals(name, std::vector<double>(data, data + size));
  else if constexpr (std::is_same_v<Value, std::uint8_t>)
    checkpoint.putBytes(name, std::vector<std::uint8_t>(data, data + size));
  else
    checkpoint.putIntegers(name, std::vector<long long>(data, data + size));
}

// The entry back into `view`, which must have as many values; throws CheckpointError naming
// the entry, both lengths and `mismatch` (what a different length means) otherwise.
template <class ViewT>
void takeView(const Checkpoint& checkpoint, const std::string& name, const ViewT& view, const std::string& mismatch) {
  using Value = typename ViewT::non_const_value_type;
  auto host = Kokkos::create_mirror_view(Kokkos::HostSpace{}, view);
  const auto copyFrom = [&](const auto& values) {
    if (values.size() != host.span())
      throw CheckpointError(checkpoint.context() + "'" + name + "' holds " + std::to_string(values.size()) +
                            " values where this run has " + std::to_string(host.span()) + ": " + mismatch);
    for (std::size_t k = 0; k < values.size(); ++k) host.data()[k] = static_cast<Value>(values[k]);
  };
  if constexpr (std::is_same_v<Value, double>)
    copyFrom(checkpoint.reals(name));
  else if constexpr (std::is_same_v<Value, std::uint8_t>)
    copyFrom(checkpoint.bytes(name));
  else
    copyFrom(checkpoint.integers(name));
  Kokkos::deep_copy(view, host);
}

}  // namespace perishell::io
