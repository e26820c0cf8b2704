#include <perishell/core/rotation.hpp>
#include <perishell/io/atomic_file.hpp>
#include <perishell/io/xdmf_writer.hpp>

#include <hdf5.h>

#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <set>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

namespace perishell::io {

namespace {

// The .xmf declares the topology as 4-byte Int.
static_assert(std::is_same_v<LocalIndex, int> && sizeof(int) == 4, "topology is written as int32");

// HDF5 prints its error stack to stderr by default; while perishell calls it, the stack is
// read into the exception message instead.
class QuietHdf5Errors {
 public:
  QuietHdf5Errors() {
    H5Eget_auto2(H5E_DEFAULT, &savedHandler_, &savedData_);
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  }
  ~QuietHdf5Errors() { H5Eset_auto2(H5E_DEFAULT, savedHandler_, savedData_); }
  QuietHdf5Errors(const QuietHdf5Errors&) = delete;
  QuietHdf5Errors& operator=(const QuietHdf5Errors&) = delete;

 private:
  H5E_auto2_t savedHandler_ = nullptr;
  void* savedData_ = nullptr;
};

// The innermost entry of HDF5's error stack: the most specific reason (for a file that
// cannot be created it carries the errno text, e.g. "No such file or directory").
std::string innermostHdf5Error() {
  std::string description = "no HDF5 error detail";
  const auto takeFirst = [](unsigned entry, const H5E_error2_t* error, void* result) -> herr_t {
    if (entry == 0 && error->desc) *static_cast<std::string*>(result) = error->desc;
    return 0;
  };
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_UPWARD, takeFirst, &description);
  return description;
}

template <class StatusT>
StatusT checkHdf5(StatusT status, const std::string& what, const std::string& path) {
  if (status < 0)
    throw std::runtime_error("HDF5 file '" + path + "': cannot " + what + ": " + innermostHdf5Error());
  return status;
}

// An HDF5 identifier closed on scope exit; closeChecked() for the file, whose close flushes
// the data and so can fail.
class Hdf5Handle {
 public:
  Hdf5Handle(hid_t id, herr_t (*close)(hid_t)) : id_(id), close_(close) {}
  ~Hdf5Handle() {
    if (id_ >= 0) close_(id_);
  }
  Hdf5Handle(const Hdf5Handle&) = delete;
  Hdf5Handle& operator=(const Hdf5Handle&) = delete;

  hid_t get() const { return id_; }
  void closeChecked(const std::string& path) {
    const hid_t id = std::exchange(id_, -1);
    checkHdf5(close_(id), "close the file", path);
  }

 private:
  hid_t id_;
  herr_t (*close_)(hid_t);
};

// Creates the HDF5 file `path` atomically; fill(file, temporaryPath) adds the datasets.
void writeHdf5FileAtomically(const std::string& path,
                             const std::function<void(hid_t, const std::string&)>& fill) {
  replaceFileAtomically(path, [&fill](const std::string& temporary) {
    const QuietHdf5Errors quiet;
    Hdf5Handle file(checkHdf5(H5Fcreate(temporary.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT),
                              "create the file", temporary),
                    H5Fclose);
    fill(file.get(), temporary);
    file.closeChecked(temporary);
  });
}

void writeDataset(hid_t location, const std::string& name, hid_t memoryType, hid_t fileType,
                  const std::vector<hsize_t>& dimensions, const void* data, const std::string& path) {
  Hdf5Handle space(
      checkHdf5(H5Screate_simple(static_cast<int>(dimensions.size()), dimensions.data(), nullptr),
                "create the dataspace of '" + name + "'", path),
      H5Sclose);
  Hdf5Handle dataset(checkHdf5(H5Dcreate2(location, name.c_str(), fileType, space.get(), H5P_DEFAULT,
                                          H5P_DEFAULT, H5P_DEFAULT),
                               "create dataset '" + name + "'", path),
                     H5Dclose);
  checkHdf5(H5Dwrite(dataset.get(), memoryType, H5S_ALL, H5S_ALL, H5P_DEFAULT, data),
            "write dataset '" + name + "'", path);
}

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
