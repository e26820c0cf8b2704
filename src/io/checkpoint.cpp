#include <perishell/io/checkpoint.hpp>

#include "hdf5_file.hpp"

#include <filesystem>
#include <utility>

namespace perishell::io {

using namespace hdf5;

namespace {

constexpr const char* formatText = "perishell checkpoint 1";

template <class MapT>
const typename MapT::mapped_type* find(const MapT& map, const std::string& name) {
  const auto it = map.find(name);
  return it == map.end() ? nullptr : &it->second;
}

// One group of entries (name -> a vector or a string), one dataset each.
template <class MapT>
void writeEntries(hid_t file, const char* groupName, const MapT& entries, hid_t memoryType, hid_t fileType,
                  const std::string& path) {
  Hdf5Handle group(checkHdf5(H5Gcreate2(file, groupName, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                             std::string("create group '") + groupName + "'", path),
                   H5Gclose);
  for (const auto& [name, values] : entries)
    writeDataset(group.get(), name, memoryType, fileType, {values.size()}, values.data(), path);
}

// Entries of one group, each read whole as memoryType into a vector of ValueT.
template <class ValueT>
std::map<std::string, std::vector<ValueT>> readGroup(hid_t file, const char* groupName, hid_t memoryType,
                                                     const std::string& path) {
  std::map<std::string, std::vector<ValueT>> entries;
  if (!hasLink(file, groupName)) return entries;
  Hdf5Handle group(checkHdf5(H5Gopen2(file, groupName, H5P_DEFAULT), std::string("open group '") + groupName + "'",
                             path),
                   H5Gclose);
  for (const auto& name : linkNames(group.get(), path)) {
    std::size_t size = 1;
    for (const hsize_t extent : datasetExtents(group.get(), name, path)) size *= extent;
    std::vector<ValueT> values(size);
    if (size > 0) readDataset(group.get(), name, memoryType, values.data(), path);
    entries.emplace(name, std::move(values));
  }
  return entries;
}

std::string asText(const std::vector<char>& characters) { return std::string(characters.begin(), characters.end()); }

std::string readText(hid_t location, const std::string& name, const std::string& path) {
  std::size_t size = 1;
  for (const hsize_t extent : datasetExtents(location, name, path)) size *= extent;
  std::vector<char> characters(size);
  if (size > 0) readDataset(location, name, H5T_NATIVE_CHAR, characters.data(), path);
  return asText(characters);
}

}  // namespace

void Checkpoint::putReals(const std::string& name, std::vector<double> values) { reals_[name] = std::move(values); }
void Checkpoint::putIntegers(const std::string& name, std::vector<long long> values) {
  integers_[name] = std::move(values);
}
void Checkpoint::putBytes(const std::string& name, std::vector<std::uint8_t> values) {
  bytes_[name] = std::move(values);
}
void Checkpoint::putText(const std::string& name, std::string text) { texts_[name] = std::move(text); }

bool Checkpoint::has(const std::string& name) const {
  return reals_.count(name) || integers_.count(name) || bytes_.count(name) || texts_.count(name);
}

void Checkpoint::missing(const std::string& name) const {
  throw CheckpointError(context() + "no entry '" + name +
                        "' (written by another version of perishell, or by the run of another deck)");
}

const std::vector<double>& Checkpoint::reals(const std::string& name) const {
  if (const auto* values = find(reals_, name)) return *values;
  missing(name);
}

const std::vector<long long>& Checkpoint::integers(const std::string& name) const {
  if (const auto* values = find(integers_, name)) return *values;
  missing(name);
}

const std::vector<std::uint8_t>& Checkpoint::bytes(const std::string& name) const {
  if (const auto* values = find(bytes_, name)) return *values;
  missing(name);
}

const std::string& Checkpoint::text(const std::string& name) const {
  if (const auto* value = find(texts_, name)) return *value;
  missing(name);
}

double Checkpoint::real(const std::string& name) const {
  const auto& values = reals(name);
  if (values.size() != 1)
    throw CheckpointError(context() + "'" + name + "' holds " + std::to_string(values.size()) + " values, not one");
  return values.front();
}

long long Checkpoint::integer(const std::string& name) const {
  const auto& values = integers(name);
  if (values.size() != 1)
    throw CheckpointError(context() + "'" + name + "' holds " + std::to_string(values.size()) + " values, not one");
  return values.front();
}

void Checkpoint::write(const std::string& path) const {
  writeHdf5FileAtomically(path, [this](hid_t file, const std::string& temporary) {
    const std::string format = formatText;
    writeDataset(file, "format", H5T_NATIVE_CHAR, H5T_STD_I8LE, {format.size()}, format.data(), temporary);
    writeEntries(file, "reals", reals_, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, temporary);
    writeEntries(file, "integers", integers_, H5T_NATIVE_LLONG, H5T_STD_I64LE, temporary);
    writeEntries(file, "bytes", bytes_, H5T_NATIVE_UINT8, H5T_STD_U8LE, temporary);
    writeEntries(file, "texts", texts_, H5T_NATIVE_CHAR, H5T_STD_I8LE, temporary);
  });
}

Checkpoint Checkpoint::read(const std::string& path) {
  if (!std::filesystem::is_regular_file(path))
    throw CheckpointError("checkpoint " + path + ": no such file (a run writes DIR/" + checkpointFileName +
                          " every output.checkpoint-every, when it is stopped, and at its end)");
  Checkpoint checkpoint;
  checkpoint.source_ = path;
  try {
    const QuietHdf5Errors quiet;
    Hdf5Handle file = openForReading(path);
    if (!hasLink(file.get(), "format") || readText(file.get(), "format", path) != formatText)
      throw CheckpointError("checkpoint " + path + ": not a perishell checkpoint (no '" + formatText + "' format)");
    checkpoint.reals_ = readGroup<double>(file.get(), "reals", H5T_NATIVE_DOUBLE, path);
    checkpoint.integers_ = readGroup<long long>(file.get(), "integers", H5T_NATIVE_LLONG, path);
    checkpoint.bytes_ = readGroup<std::uint8_t>(file.get(), "bytes", H5T_NATIVE_UINT8, path);
    for (const auto& [name, characters] : readGroup<char>(file.get(), "texts", H5T_NATIVE_CHAR, path))
      checkpoint.texts_.emplace(name, asText(characters));
  } catch (const CheckpointError&) {
    throw;
  } catch (const std::runtime_error& error) {
    throw CheckpointError("checkpoint " + path + ": cannot be read (" + error.what() + ")");
  }
  return checkpoint;
}

}  // namespace perishell::io
