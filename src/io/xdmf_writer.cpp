#include <perishell/core/rotation.hpp>
#include <perishell/io/atomic_file.hpp>
#include <perishell/io/xdmf_writer.hpp>

#include "hdf5_file.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <regex>
#include <set>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace perishell::io {

using namespace hdf5;

namespace {

// The .xmf declares the topology as 4-byte Int.
static_assert(std::is_same_v<LocalIndex, int> && sizeof(int) == 4, "topology is written as int32");

// HDF5 writes from one contiguous buffer; a padded host view is copied once.
template <class ViewT>
ViewT contiguous(const ViewT& view) {
  if (view.span_is_contiguous()) return view;
  auto copy = Kokkos::create_mirror(Kokkos::HostSpace{}, view);
  Kokkos::deep_copy(copy, view);
  return copy;
}

// Names end up in file names, HDF5 paths ("file.h5:/fields/<name>") and XML attributes;
// this set is safe in all three without escaping.
bool isSafeName(const std::string& name) {
  if (name.empty() || name.front() == '-' || name.front() == '.') return false;
  for (const char c : name)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.')) return false;
  return true;
}

const char* const kNameRule =
    "must be non-empty, start with a letter, digit or '_', and contain only letters, "
    "digits, '_', '-' and '.'";

std::string formatDouble(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.17g", value);
  return buffer;
}

std::string joinPath(const std::string& directory, const std::string& fileName) {
  return directory.back() == '/' ? directory + fileName : directory + "/" + fileName;
}

template <class ValueT>
NodalField scalarFieldFrom(std::string name, const Kokkos::View<const ValueT*, Kokkos::HostSpace>& values) {
  Kokkos::View<double**, Kokkos::LayoutRight, Kokkos::HostSpace> copy(name, values.extent(0), 1);
  for (std::size_t node = 0; node < values.extent(0); ++node)
    copy(node, 0) = static_cast<double>(values(node));
  return NodalField{std::move(name), 1, copy};
}

}  // namespace

NodalField firstNodes(const NodalField& field, LocalIndex numNodes) {
  return {field.name, field.components,
          Kokkos::subview(field.values, std::make_pair(LocalIndex(0), numNodes), Kokkos::ALL)};
}

NodalField makeScalarField(std::string name, const Kokkos::View<const double*, Kokkos::HostSpace>& values) {
  return scalarFieldFrom(std::move(name), values);
}

NodalField makeScalarField(std::string name, const Kokkos::View<const int*, Kokkos::HostSpace>& values) {
  return scalarFieldFrom(std::move(name), values);
}

NodalField makeRotationVectorField(
    std::string name, const Kokkos::View<const double* [4], Kokkos::LayoutRight, Kokkos::HostSpace>& quaternions) {
  const auto numNodes = quaternions.extent(0);
  Kokkos::View<double**, Kokkos::LayoutRight, Kokkos::HostSpace> rotationVectors(name, numNodes, 3);
  for (std::size_t node = 0; node < numNodes; ++node) {
    const double q[4] = {quaternions(node, 0), quaternions(node, 1), quaternions(node, 2), quaternions(node, 3)};
    double theta[3];
    rotation::rotationVector(q, theta);
    for (int d = 0; d < 3; ++d) rotationVectors(node, d) = theta[d];
  }
  return {std::move(name), 3, rotationVectors};
}

XdmfTimeSeriesWriter::XdmfTimeSeriesWriter(std::string directory, std::string baseName,
                                           const mesh::HostQuadMesh& mesh)
    : directory_(std::move(directory)),
      baseName_(std::move(baseName)),
      numNodes_(mesh.numNodes()),
      numElements_(mesh.numElements()) {
  if (directory_.empty()) throw std::invalid_argument("XDMF output: empty directory");
  if (!isSafeName(baseName_))
    throw std::invalid_argument("XDMF output in '" + directory_ + "': base name '" + baseName_ + "' " +
                                kNameRule);
  if (numNodes_ == 0 || numElements_ == 0)
    throw std::invalid_argument("XDMF output '" + xdmfPath() + "': empty mesh (" + std::to_string(numNodes_) +
                                " nodes, " + std::to_string(numElements_) + " elements)");
  for (LocalIndex element = 0; element < numElements_; ++element)
    for (int corner = 0; corner < 4; ++corner) {
      const LocalIndex node = mesh.quads(element, corner);
      if (node < 0 || node >= numNodes_)
        throw std::invalid_argument("XDMF output '" + xdmfPath() + "': element " + std::to_string(element) +
                                    " corner " + std::to_string(corner) + " refers to node " +
                                    std::to_string(node) + ", outside [0, " + std::to_string(numNodes_) +
                                    ")");
    }

  const auto coordinates = contiguous(mesh.coordinates);
  const auto quads = contiguous(mesh.quads);
  // Triangles (stored a b c c) go out as XDMF triangles, so that viewers see three corners.
  bool hasTriangles = false;
  for (LocalIndex e = 0; e < numElements_ && !hasTriangles; ++e) hasTriangles = mesh::isTriangle(mesh.quads, e);
  std::vector<int> mixed;
  for (LocalIndex e = 0; hasTriangles && e < numElements_; ++e) {
    const int corners = mesh::cornerCount(mesh.quads, e);
    mixed.push_back(corners == 3 ? 4 : 5);  // XDMF's Triangle and Quadrilateral
    for (int corner = 0; corner < corners; ++corner) mixed.push_back(mesh.quads(e, corner));
  }
  mixedTopologyLength_ = mixed.size();
  writeHdf5FileAtomically(meshPath(), [&](hid_t file, const std::string& path) {
    writeDataset(file, "geometry", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, {hsize_t(numNodes_), 3},
                 coordinates.data(), path);
    if (mixed.empty())
      writeDataset(file, "topology", H5T_NATIVE_INT, H5T_STD_I32LE, {hsize_t(numElements_), 4}, quads.data(),
                   path);
    else
      writeDataset(file, "topology", H5T_NATIVE_INT, H5T_STD_I32LE, {hsize_t(mixed.size())}, mixed.data(), path);
  });
}

std::string XdmfTimeSeriesWriter::xdmfPath() const { return joinPath(directory_, baseName_ + ".xmf"); }

std::string XdmfTimeSeriesWriter::meshPath() const { return joinPath(directory_, baseName_ + "_mesh.h5"); }

std::string XdmfTimeSeriesWriter::stepPath(int step) const {
  return joinPath(directory_, stepFileName(step));
}

std::string XdmfTimeSeriesWriter::stepFileName(int step) const {
  char number[16];
  std::snprintf(number, sizeof number, "%06d", step);
  return baseName_ + "_" + number + ".h5";
}

void XdmfTimeSeriesWriter::writeStep(double time, const std::vector<NodalField>& fields) {
  const int step = numSteps();
  const std::string context = "XDMF output '" + xdmfPath() + "' step " + std::to_string(step);
  if (!std::isfinite(time))
    throw std::invalid_argument(context + ": time " + formatDouble(time) + " is not finite");
  if (step > 0 && time < steps_.back().time)
    throw std::invalid_argument(context + ": time " + formatDouble(time) +
                                " s is before the previous step's " + formatDouble(steps_.back().time) +
                                " s");
  StepRecord record{time, {}};
  std::set<std::string> names;
  for (const NodalField& field : fields) {
    if (!isSafeName(field.name))
      throw std::invalid_argument(context + ": field name '" + field.name + "' " + kNameRule);
    if (!names.insert(field.name).second)
      throw std::invalid_argument(context + ": field '" + field.name + "' appears twice");
    if (field.components != 1 && field.components != 3)
      throw std::invalid_argument(context + ": field '" + field.name + "' has " +
                                  std::to_string(field.components) +
                                  " components, expected 1 (scalar) or 3 (vector)");
    if (field.values.extent(0) != std::size_t(numNodes_) ||
        field.values.extent(1) != std::size_t(field.components))
      throw std::invalid_argument(
          context + ": field '" + field.name + "' has " + std::to_string(field.values.extent(0)) + " x " +
          std::to_string(field.values.extent(1)) + " values, expected " + std::to_string(numNodes_) + " x " +
          std::to_string(field.components) + " (nodes x components)");
    record.fields.push_back({field.name, field.components});
  }

  writeHdf5FileAtomically(stepPath(step), [&](hid_t file, const std::string& path) {
    writeDataset(file, "time", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, {1}, &time, path);
    Hdf5Handle group(checkHdf5(H5Gcreate2(file, "fields", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                               "create group 'fields'", path),
                     H5Gclose);
    for (const NodalField& field : fields) {
      std::vector<hsize_t> dimensions{hsize_t(numNodes_)};
      if (field.components > 1) dimensions.push_back(hsize_t(field.components));
      writeDataset(group.get(), field.name, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, dimensions,
                   contiguous(field.values).data(), path);
    }
  });

  // The first step writes the whole .xmf; later ones replace its closing tags by their grid
  // and the closing tags, so each step costs its own grid, and the file is complete XML
  // after every step. A file whose size is not what this writer left (changed by hand) is
  // rewritten whole.
  const std::string closing = xdmfClosing();
  const std::string grid = xdmfGrid(step, record);
  std::error_code sizeError;
  const auto sizeOnDisk = step > 0 ? std::filesystem::file_size(xdmfPath(), sizeError) : 0;
  if (step > 0 && !sizeError && sizeOnDisk == xdmfBytes_) {
    replaceFileTail(xdmfPath(), xdmfBytes_ - closing.size(), closing, grid + closing);
    xdmfBytes_ += grid.size();
  } else {
    std::string text = xdmfHeader();
    for (std::size_t earlier = 0; earlier < steps_.size(); ++earlier)
      text += xdmfGrid(static_cast<int>(earlier), steps_[earlier]);
    text += grid + closing;
    writeFileAtomically(xdmfPath(), text);
    xdmfBytes_ = text.size();
  }
  steps_.push_back(std::move(record));
}

void XdmfTimeSeriesWriter::continueSeries(std::vector<StepRecord> earlier) {
  if (!steps_.empty()) throw std::logic_error("XDMF output '" + xdmfPath() + "': continueSeries after writeStep");
  for (std::size_t step = 0; step < earlier.size(); ++step)
    if (!std::filesystem::is_regular_file(stepPath(static_cast<int>(step))))
      throw std::runtime_error("XDMF output '" + xdmfPath() + "': step " + std::to_string(step) + " of the run to " +
                               "continue is missing (" + stepPath(static_cast<int>(step)) + ")");
  // The steps an interrupted run wrote after its checkpoint are not this run's.
  const std::regex stepFile(baseName_ + R"(_([0-9]{6,})\.h5)");
  for (const auto& entry : std::filesystem::directory_iterator(directory_)) {
    std::smatch match;
    const std::string name = entry.path().filename().string();
    if (std::regex_match(name, match, stepFile) && std::stoull(match[1].str()) >= earlier.size())
      std::filesystem::remove(entry.path());
  }
  steps_ = std::move(earlier);
  std::string text = xdmfHeader();
  for (std::size_t step = 0; step < steps_.size(); ++step) text += xdmfGrid(static_cast<int>(step), steps_[step]);
  text += xdmfClosing();
  writeFileAtomically(xdmfPath(), text);
  xdmfBytes_ = text.size();
}

std::string XdmfTimeSeriesWriter::xdmfHeader() const {
  return "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
         "<Xdmf Version=\"3.0\">\n"
         "  <Domain>\n"
         "    <Grid Name=\"" + baseName_ + "\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
}

std::string XdmfTimeSeriesWriter::xdmfClosing() { return "    </Grid>\n  </Domain>\n</Xdmf>\n"; }

std::string XdmfTimeSeriesWriter::xdmfGrid(int step, const StepRecord& record) const {
  const std::string nodes = std::to_string(numNodes_);
  const std::string elements = std::to_string(numElements_);
  const std::string meshFile = baseName_ + "_mesh.h5";
  const auto dataItem = [](const std::string& dimensions, const char* numberType, const char* precision,
                           const std::string& reference) {
    return "          <DataItem Dimensions=\"" + dimensions + "\" NumberType=\"" + numberType +
           "\" Precision=\"" + precision + "\" Format=\"HDF\">" + reference + "</DataItem>\n";
  };
  const std::string stepFile = stepFileName(step);
  std::string text = "      <Grid Name=\"step_" + std::to_string(step) + "\" GridType=\"Uniform\">\n";
  text += "        <Time Value=\"" + formatDouble(record.time) + "\"/>\n";
  // The mesh's DataItems repeat in every grid (rather than XInclude'd): plain, and the
  // heavy data stay in the one mesh file.
  if (mixedTopologyLength_ == 0) {
    text += "        <Topology TopologyType=\"Quadrilateral\" NumberOfElements=\"" + elements + "\">\n";
    text += dataItem(elements + " 4", "Int", "4", meshFile + ":/topology");
  } else {
    text += "        <Topology TopologyType=\"Mixed\" NumberOfElements=\"" + elements + "\">\n";
    text += dataItem(std::to_string(mixedTopologyLength_), "Int", "4", meshFile + ":/topology");
  }
  text += "        </Topology>\n";
  text += "        <Geometry GeometryType=\"XYZ\">\n";
  text += dataItem(nodes + " 3", "Float", "8", meshFile + ":/geometry");
  text += "        </Geometry>\n";
  for (const FieldRecord& field : record.fields) {
    const bool vector = field.components == 3;
    text += "        <Attribute Name=\"" + field.name + "\" AttributeType=\"" + (vector ? "Vector" : "Scalar") +
            "\" Center=\"Node\">\n";
    text += dataItem(vector ? nodes + " 3" : nodes, "Float", "8", stepFile + ":/fields/" + field.name);
    text += "        </Attribute>\n";
  }
  text += "      </Grid>\n";
  return text;
}

}  // namespace perishell::io
