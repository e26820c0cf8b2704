// Output: the XDMF/HDF5 time series read back bit for bit with the HDF5 C API and its .xmf
// parsed as XML; atomic replacement (no temporaries left, failed writes keep the previous
// file byte for byte, bad directories throw naming the path); CSV histories round-trip
// every double exactly through strtod. The I/O is host side; TEST_EXECSPACE only picks the
// binary the test runs in.
#include <perishell/io/atomic_file.hpp>
#include <perishell/io/checkpoint.hpp>
#include <perishell/io/csv_history.hpp>
#include <perishell/io/xdmf_writer.hpp>
#include <perishell/mesh/quad_mesh.hpp>

#include <scratch_directory.hpp>

#include <hdf5.h>
#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cfloat>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace {

namespace fs = std::filesystem;
using perishell::io::NodalField;

// Each test's files go to a fresh /tmp directory.
using TemporaryDirectory = perishell_test::ScratchDirectory;

std::string readFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream contents;
  contents << in.rdbuf();
  return contents.str();
}

std::vector<std::string> filesIn(const std::string& directory) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(directory))
    names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

int countTemporaries(const std::string& directory) {
  int count = 0;
  for (const auto& name : filesIn(directory)) count += name.find(".tmp.") != std::string::npos;
  return count;
}

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }

// ---- HDF5 read-back ----------------------------------------------------------------------

struct Dataset {
  std::vector<hsize_t> dimensions;
  H5T_class_t storedClass;  // as stored in the file, before HDF5 converts on reading
  std::size_t storedBytes;
  std::vector<double> doubles;
  std::vector<int> ints;
};

// Reads a whole dataset as double or int (HDF5 converts from the stored type).
Dataset readDataset(const std::string& file, const std::string& name, bool asInt) {
  Dataset result;
  const hid_t fileId = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (fileId < 0) throw std::runtime_error("cannot open " + file);
  const hid_t dataset = H5Dopen2(fileId, name.c_str(), H5P_DEFAULT);
  if (dataset < 0) {
    H5Fclose(fileId);
    throw std::runtime_error("no dataset " + name + " in " + file);
  }
  const hid_t storedType = H5Dget_type(dataset);
  result.storedClass = H5Tget_class(storedType);
  result.storedBytes = H5Tget_size(storedType);
  H5Tclose(storedType);
  const hid_t space = H5Dget_space(dataset);
  result.dimensions.resize(H5Sget_simple_extent_ndims(space));
  H5Sget_simple_extent_dims(space, result.dimensions.data(), nullptr);
  const auto count = static_cast<std::size_t>(H5Sget_simple_extent_npoints(space));
  herr_t status;
  if (asInt) {
    result.ints.resize(count);
    status = H5Dread(dataset, H5T_NATIVE_INT, H5S_ALL, H5S_ALL, H5P_DEFAULT, result.ints.data());
  } else {
    result.doubles.resize(count);
    status = H5Dread(dataset, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, result.doubles.data());
  }
  H5Sclose(space);
  H5Dclose(dataset);
  H5Fclose(fileId);
  if (status < 0) throw std::runtime_error("cannot read " + name + " in " + file);
  return result;
}

std::string dimensionsText(const std::vector<hsize_t>& dimensions) {
  std::string text;
  for (const auto d : dimensions) text += (text.empty() ? "" : " ") + std::to_string(d);
  return text;
}

// ---- a small XML reader: elements, attributes, text; enough for the .xmf -----------------

struct XmlElement {
  std::string name;
  std::map<std::string, std::string> attributes;
  std::string text;
  std::vector<std::unique_ptr<XmlElement>> children;

  std::vector<const XmlElement*> childrenNamed(const std::string& childName) const {
    std::vector<const XmlElement*> found;
    for (const auto& child : children)
      if (child->name == childName) found.push_back(child.get());
    return found;
  }
  const XmlElement& only(const std::string& childName) const {
    const auto found = childrenNamed(childName);
    if (found.size() != 1)
      throw std::runtime_error("<" + name + "> has " + std::to_string(found.size()) + " <" + childName + ">");
    return *found.front();
  }
  std::string attribute(const std::string& key) const {
    const auto it = attributes.find(key);
    if (it == attributes.end()) throw std::runtime_error("<" + name + "> has no attribute " + key);
    return it->second;
  }
};

class XmlReader {
 public:
  explicit XmlReader(std::string text) : text_(std::move(text)) {}

  // Throws on anything that is not well-formed (for the subset the writer uses).
  std::unique_ptr<XmlElement> document() {
    skipSpace();
    if (text_.compare(position_, 5, "<?xml") == 0) {
      position_ = text_.find("?>", position_);
      if (position_ == std::string::npos) fail("unterminated XML declaration");
      position_ += 2;
    }
    skipSpace();
    auto root = element();
    skipSpace();
    if (position_ != text_.size()) fail("content after the root element");
    return root;
  }

 private:
  [[noreturn]] void fail(const std::string& why) const {
    throw std::runtime_error("XML: " + why + " at offset " + std::to_string(position_));
  }
  void skipSpace() {
    while (position_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[position_])))
      ++position_;
  }
  void expect(char c) {
    if (position_ >= text_.size() || text_[position_] != c) fail(std::string("expected '") + c + "'");
    ++position_;
  }
  std::string nameToken() {
    const std::size_t start = position_;
    while (position_ < text_.size() &&
           (std::isalnum(static_cast<unsigned char>(text_[position_])) || text_[position_] == '_' ||
            text_[position_] == ':' || text_[position_] == '-' || text_[position_] == '.'))
      ++position_;
    if (start == position_) fail("expected a name");
    return text_.substr(start, position_ - start);
  }
  std::unique_ptr<XmlElement> element() {
    auto node = std::make_unique<XmlElement>();
    expect('<');
    node->name = nameToken();
    for (;;) {
      skipSpace();
      if (text_.compare(position_, 2, "/>") == 0) {
        position_ += 2;
        return node;
      }
      if (position_ < text_.size() && text_[position_] == '>') break;
      const std::string key = nameToken();
      skipSpace();
      expect('=');
      skipSpace();
      expect('"');
      const std::size_t end = text_.find('"', position_);
      if (end == std::string::npos) fail("unterminated attribute value");
      const std::string value = text_.substr(position_, end - position_);
      if (value.find_first_of("<&") != std::string::npos) fail("unescaped '<' or '&' in attribute " + key);
      if (!node->attributes.emplace(key, value).second) fail("repeated attribute " + key);
      position_ = end + 1;
    }
    expect('>');
    for (;;) {
      const std::size_t tag = text_.find('<', position_);
      if (tag == std::string::npos) fail("unterminated element <" + node->name + ">");
      const std::string text = text_.substr(position_, tag - position_);
      if (text.find('&') != std::string::npos) fail("entity in text");
      node->text += text;
      position_ = tag;
      if (text_.compare(position_, 2, "</") == 0) {
        position_ += 2;
        if (nameToken() != node->name) fail("mismatched end tag for <" + node->name + ">");
        skipSpace();
        expect('>');
        return node;
      }
      node->children.push_back(element());
    }
  }

  std::string text_;
  std::size_t position_ = 0;
};

std::string trimmed(const std::string& text) {
  const auto first = text.find_first_not_of(" \t\r\n");
  const auto last = text.find_last_not_of(" \t\r\n");
  return first == std::string::npos ? "" : text.substr(first, last - first + 1);
}

// A DataItem: Format HDF, its Dimensions equal to `dimensions`, its "file.h5:/path" naming
// an existing file in `directory` whose dataset has exactly those dimensions and is stored
// with the declared NumberType and Precision.
void expectHdfDataItem(const XmlElement& item, const std::string& directory,
                       const std::string& expectedReference, const std::string& dimensions,
                       const std::string& numberType, const std::string& precision) {
  EXPECT_EQ(item.attribute("Format"), "HDF");
  EXPECT_EQ(item.attribute("Dimensions"), dimensions);
  EXPECT_EQ(item.attribute("NumberType"), numberType);
  EXPECT_EQ(item.attribute("Precision"), precision);
  const std::string reference = trimmed(item.text);
  EXPECT_EQ(reference, expectedReference);
  const auto colon = reference.find(':');
  ASSERT_NE(colon, std::string::npos) << reference;
  const std::string file = directory + "/" + reference.substr(0, colon);
  ASSERT_TRUE(fs::is_regular_file(file)) << file;
  const auto dataset = readDataset(file, reference.substr(colon + 1), numberType == "Int");
  EXPECT_EQ(dimensionsText(dataset.dimensions), dimensions) << reference;
  EXPECT_EQ(dataset.storedClass, numberType == "Int" ? H5T_INTEGER : H5T_FLOAT) << reference;
  EXPECT_EQ(std::to_string(dataset.storedBytes), precision) << reference;
}

// ---- the mesh and fields the tests write ---------------------------------------------------

constexpr int kCellsX = 4, kCellsY = 3;
constexpr int kNodes = (kCellsX + 1) * (kCellsY + 1);  // 20
constexpr int kElements = kCellsX * kCellsY;           // 12

perishell::mesh::HostQuadMesh plate() {
  // Lengths whose node coordinates (i / 3 * 0.7, ...) are not short decimals.
  return perishell::mesh::makeRectangularPlate(1.3, 0.7, kCellsX, kCellsY);
}

Kokkos::View<double**, Kokkos::LayoutRight, Kokkos::HostSpace> nodalValues(int components, double seed) {
  Kokkos::View<double**, Kokkos::LayoutRight, Kokkos::HostSpace> values("values", kNodes, components);
  for (int node = 0; node < kNodes; ++node)
    for (int c = 0; c < components; ++c) values(node, c) = std::sin(seed + 1.7 * node + 0.3 * c) / 3.0;
  return values;
}

TEST(TEST_CATEGORY, output_xdmf_time_series_reads_back_exactly) {
  const TemporaryDirectory directory;
  const auto mesh = plate();
  perishell::io::XdmfTimeSeriesWriter writer(directory.path(), "plate", mesh);

  const double times[2] = {0.0, 2.5e-4 / 3.0};
  const auto damage0 = nodalValues(1, 0.1), displacement0 = nodalValues(3, 0.2);
  const auto damage1 = nodalValues(1, 1.1), displacement1 = nodalValues(3, 1.2);
  Kokkos::View<int*, Kokkos::HostSpace> broken("broken", kNodes);
  for (int node = 0; node < kNodes; ++node) broken(node) = node % 3 == 0 ? 1 : 0;
  writer.writeStep(times[0], {{"damage", 1, damage0}, {"displacement", 3, displacement0}});
  writer.writeStep(times[1], {{"damage", 1, damage1},
                              {"displacement", 3, displacement1},
                              perishell::io::makeScalarField("broken", broken)});
  ASSERT_EQ(writer.numSteps(), 2);

  EXPECT_EQ(filesIn(directory.path()),
            (std::vector<std::string>{"plate.xmf", "plate_000000.h5", "plate_000001.h5", "plate_mesh.h5"}));
  EXPECT_EQ(countTemporaries(directory.path()), 0);

  // Mesh: geometry and topology bit for bit.
  const auto geometry = readDataset(directory / "plate_mesh.h5", "/geometry", false);
  ASSERT_EQ(dimensionsText(geometry.dimensions), std::to_string(kNodes) + " 3");
  int mismatches = 0;
  for (int node = 0; node < kNodes; ++node)
    for (int d = 0; d < 3; ++d)
      mismatches += !sameBits(geometry.doubles[3 * node + d], mesh.coordinates(node, d));
  EXPECT_EQ(mismatches, 0);
  const auto topology = readDataset(directory / "plate_mesh.h5", "/topology", true);
  ASSERT_EQ(dimensionsText(topology.dimensions), std::to_string(kElements) + " 4");
  for (int element = 0; element < kElements; ++element)
    for (int corner = 0; corner < 4; ++corner)
      EXPECT_EQ(topology.ints[4 * element + corner], mesh.quads(element, corner));

  // Steps: time and every field bit for bit, scalars 1-D, vectors nodes x 3.
  const decltype(damage0) damages[2] = {damage0, damage1};
  const decltype(damage0) displacements[2] = {displacement0, displacement1};
  for (int step = 0; step < 2; ++step) {
    const std::string file = writer.stepPath(step);
    const auto time = readDataset(file, "/time", false);
    ASSERT_EQ(time.doubles.size(), 1u);
    EXPECT_TRUE(sameBits(time.doubles[0], times[step])) << step;
    const auto damage = readDataset(file, "/fields/damage", false);
    const auto displacement = readDataset(file, "/fields/displacement", false);
    EXPECT_EQ(dimensionsText(damage.dimensions), std::to_string(kNodes));
    EXPECT_EQ(dimensionsText(displacement.dimensions), std::to_string(kNodes) + " 3");
    mismatches = 0;
    for (int node = 0; node < kNodes; ++node) {
      mismatches += !sameBits(damage.doubles[node], damages[step](node, 0));
      for (int c = 0; c < 3; ++c)
        mismatches += !sameBits(displacement.doubles[3 * node + c], displacements[step](node, c));
    }
    EXPECT_EQ(mismatches, 0) << "step " << step;
  }
  const auto brokenBack = readDataset(writer.stepPath(1), "/fields/broken", false);
  for (int node = 0; node < kNodes; ++node) EXPECT_EQ(brokenBack.doubles[node], double(broken(node)));

  // The .xmf: a well-formed XDMF 3 temporal collection of 2 uniform quad grids.
  const auto root = XmlReader(readFile(writer.xdmfPath())).document();
  ASSERT_EQ(root->name, "Xdmf");
  EXPECT_EQ(root->attribute("Version"), "3.0");
  const XmlElement& collection = root->only("Domain").only("Grid");
  EXPECT_EQ(collection.attribute("GridType"), "Collection");
  EXPECT_EQ(collection.attribute("CollectionType"), "Temporal");
  const auto grids = collection.childrenNamed("Grid");
  ASSERT_EQ(grids.size(), 2u);
  const std::vector<std::vector<std::string>> fieldNames = {{"damage", "displacement"},
                                                            {"damage", "displacement", "broken"}};
  for (int step = 0; step < 2; ++step) {
    const XmlElement& grid = *grids[step];
    EXPECT_EQ(grid.attribute("GridType"), "Uniform");
    EXPECT_TRUE(sameBits(std::strtod(grid.only("Time").attribute("Value").c_str(), nullptr), times[step]));
    const XmlElement& topologyItem = grid.only("Topology");
    EXPECT_EQ(topologyItem.attribute("TopologyType"), "Quadrilateral");
    EXPECT_EQ(topologyItem.attribute("NumberOfElements"), std::to_string(kElements));
    expectHdfDataItem(topologyItem.only("DataItem"), directory.path(), "plate_mesh.h5:/topology",
                      std::to_string(kElements) + " 4", "Int", "4");
    const XmlElement& geometryItem = grid.only("Geometry");
    EXPECT_EQ(geometryItem.attribute("GeometryType"), "XYZ");
    expectHdfDataItem(geometryItem.only("DataItem"), directory.path(), "plate_mesh.h5:/geometry",
                      std::to_string(kNodes) + " 3", "Float", "8");
    const auto attributes = grid.childrenNamed("Attribute");
    ASSERT_EQ(attributes.size(), fieldNames[step].size());
    const std::string stepFile = "plate_00000" + std::to_string(step) + ".h5";
    for (std::size_t i = 0; i < attributes.size(); ++i) {
      const std::string& name = fieldNames[step][i];
      const bool vector = name == "displacement";
      EXPECT_EQ(attributes[i]->attribute("Name"), name);
      EXPECT_EQ(attributes[i]->attribute("Center"), "Node");
      EXPECT_EQ(attributes[i]->attribute("AttributeType"), vector ? "Vector" : "Scalar");
      expectHdfDataItem(attributes[i]->only("DataItem"), directory.path(), stepFile + ":/fields/" + name,
                        std::to_string(kNodes) + (vector ? " 3" : ""), "Float", "8");
    }
  }
}

TEST(TEST_CATEGORY, output_xdmf_writes_triangles_as_a_mixed_topology) {
  const TemporaryDirectory directory;
  auto mesh = plate();
  // Element 0 (nodes 0 1 6 5) becomes the triangle 0 1 6; the others stay quads.
  mesh.quads(0, 3) = mesh.quads(0, 2);
  perishell::io::XdmfTimeSeriesWriter writer(directory.path(), "plate", mesh);
  writer.writeStep(0.0, {{"damage", 1, nodalValues(1, 0.1)}});
  const auto topology = readDataset(directory / "plate_mesh.h5", "/topology", true);
  const std::size_t length = 4 + 5 * (kElements - 1);
  ASSERT_EQ(dimensionsText(topology.dimensions), std::to_string(length));
  std::vector<int> expected = {4, mesh.quads(0, 0), mesh.quads(0, 1), mesh.quads(0, 2)};
  for (int element = 1; element < kElements; ++element) {
    expected.push_back(5);
    for (int corner = 0; corner < 4; ++corner) expected.push_back(mesh.quads(element, corner));
  }
  EXPECT_EQ(std::vector<int>(topology.ints.begin(), topology.ints.end()), expected);
  const auto root = XmlReader(readFile(writer.xdmfPath())).document();
  const XmlElement& topologyItem = root->only("Domain").only("Grid").only("Grid").only("Topology");
  EXPECT_EQ(topologyItem.attribute("TopologyType"), "Mixed");
  EXPECT_EQ(topologyItem.attribute("NumberOfElements"), std::to_string(kElements));
  expectHdfDataItem(topologyItem.only("DataItem"), directory.path(), "plate_mesh.h5:/topology",
                    std::to_string(length), "Int", "4");
}

template <class ExceptionT, class CallT>
std::string messageOf(CallT&& call) {
  try {
    call();
  } catch (const ExceptionT& error) {
    return error.what();
  }
  return "(no exception)";
}

TEST(TEST_CATEGORY, output_xdmf_rejected_or_failed_step_keeps_previous_xmf) {
  const TemporaryDirectory directory;
  perishell::io::XdmfTimeSeriesWriter writer(directory.path(), "plate", plate());
  const auto scalar = nodalValues(1, 0.0);
  const auto vector = nodalValues(3, 0.0);
  writer.writeStep(1.0, {{"damage", 1, scalar}, {"displacement", 3, vector}});
  const std::string before = readFile(writer.xdmfPath());
  const auto filesBefore = filesIn(directory.path());

  const Kokkos::View<double**, Kokkos::LayoutRight, Kokkos::HostSpace> shortVector("short", kNodes - 1, 3);
  const std::string prefix = "XDMF output '" + writer.xdmfPath() + "' step 1: ";
  struct Rejected {
    double time;
    std::vector<NodalField> fields;
    std::string reason;
  };
  const std::vector<Rejected> rejected = {
      {2.0,
       {{"displacement", 3, shortVector}},
       "field 'displacement' has 19 x 3 values, expected 20 x 3 (nodes x components)"},
      {2.0,
       {{"damage", 3, scalar}},
       "field 'damage' has 20 x 1 values, expected 20 x 3 (nodes x components)"},
      {2.0, {{"strain", 2, vector}}, "field 'strain' has 2 components, expected 1"},
      {2.0, {{"damage", 1, scalar}, {"damage", 1, scalar}}, "field 'damage' appears twice"},
      {2.0, {{"", 1, scalar}}, "field name '' must be non-empty"},
      {2.0, {{"a/b", 1, scalar}}, "field name 'a/b' must be non-empty"},
      {0.5, {{"damage", 1, scalar}}, "time 0.5 s is before the previous step's 1 s"},
      {NAN, {{"damage", 1, scalar}}, "time nan is not finite"},
      {INFINITY, {}, "time inf is not finite"},
  };
  for (const auto& [time, fields, reason] : rejected) {
    const std::string message = messageOf<std::invalid_argument>(
        [&, &time = time, &fields = fields] { writer.writeStep(time, fields); });
    EXPECT_NE(message.find(prefix + reason), std::string::npos) << message;
    EXPECT_EQ(readFile(writer.xdmfPath()), before) << reason;
    EXPECT_EQ(filesIn(directory.path()), filesBefore) << reason;
  }
  EXPECT_EQ(writer.numSteps(), 1);

  // An I/O failure after validation: the step file's name is taken by a directory, so the
  // rename fails. The previous .xmf stays byte for byte, and no temporary is left.
  fs::create_directory(writer.stepPath(1));
  const std::string message = messageOf<std::runtime_error>([&] {
    writer.writeStep(2.0, {{"damage", 1, scalar}});
  });
  EXPECT_NE(message.find(writer.stepPath(1)), std::string::npos) << message;
  EXPECT_NE(message.find(std::strerror(EISDIR)), std::string::npos) << message;
  EXPECT_EQ(readFile(writer.xdmfPath()), before);
  EXPECT_EQ(countTemporaries(directory.path()), 0);
  EXPECT_EQ(writer.numSteps(), 1);

  // Once the obstacle is gone the same step goes through as step 1, with an equal time.
  fs::remove(writer.stepPath(1));
  writer.writeStep(1.0, {{"damage", 1, scalar}});
  EXPECT_EQ(writer.numSteps(), 2);
  EXPECT_NE(readFile(writer.xdmfPath()), before);
  EXPECT_TRUE(fs::is_regular_file(writer.stepPath(1)));
}

TEST(TEST_CATEGORY, output_xmf_grows_by_appending_a_step_and_stays_valid_xml) {
  // Issue 22: every step rewrote the whole .xmf (output cost growing with the run). Now a
  // later step replaces only the closing tags: the file keeps its inode, the text before the
  // closing tags stays byte for byte, and the file parses as XDMF with all steps after each.
  const TemporaryDirectory directory;
  perishell::io::XdmfTimeSeriesWriter writer(directory.path(), "plate", plate());
  const std::string closing = "    </Grid>\n  </Domain>\n</Xdmf>\n";
  std::string previous;
  ino_t firstInode = 0;
  for (int step = 0; step < 4; ++step) {
    writer.writeStep(1.0 + step, {{"damage", 1, nodalValues(1, double(step))}});
    const std::string text = readFile(writer.xdmfPath());
    ASSERT_GE(text.size(), closing.size());
    EXPECT_EQ(text.substr(text.size() - closing.size()), closing) << "step " << step;
    const auto root = XmlReader(text).document();
    EXPECT_EQ(root->only("Domain").only("Grid").childrenNamed("Grid").size(), std::size_t(step + 1));
    struct stat status {};
    ASSERT_EQ(::stat(writer.xdmfPath().c_str(), &status), 0);
    if (step == 0) {
      firstInode = status.st_ino;
    } else {
      EXPECT_EQ(status.st_ino, firstInode) << "step " << step << " replaced the .xmf instead of appending";
      const std::string kept = previous.substr(0, previous.size() - closing.size());
      EXPECT_EQ(text.compare(0, kept.size(), kept), 0) << "step " << step;
      // Each appended step costs one grid: the growth is the same for every step.
      EXPECT_EQ(text.size() - previous.size(), std::size_t(686)) << "step " << step;
    }
    previous = text;
  }
  EXPECT_EQ(countTemporaries(directory.path()), 0);

  // A .xmf changed behind the writer's back (not the size it left) is rewritten whole, valid.
  { std::ofstream(writer.xdmfPath(), std::ios::app) << "<!-- edited -->\n"; }
  writer.writeStep(5.0, {{"damage", 1, nodalValues(1, 4.0)}});
  const auto root = XmlReader(readFile(writer.xdmfPath())).document();
  EXPECT_EQ(root->only("Domain").only("Grid").childrenNamed("Grid").size(), 5u);
}

TEST(TEST_CATEGORY, output_xmf_write_failure_leaves_no_xmf) {
  // The .xmf's name is taken by a directory: the step's .h5 is complete, the .xmf rename
  // fails, and the writer does not count the step.
  const TemporaryDirectory directory;
  perishell::io::XdmfTimeSeriesWriter writer(directory.path(), "plate", plate());
  fs::create_directory(writer.xdmfPath());
  const std::string message = messageOf<std::runtime_error>([&] {
    writer.writeStep(0.0, {{"damage", 1, nodalValues(1, 0.0)}});
  });
  EXPECT_NE(message.find("cannot rename '" + writer.xdmfPath() + ".tmp."), std::string::npos) << message;
  EXPECT_NE(message.find(std::strerror(EISDIR)), std::string::npos) << message;
  EXPECT_TRUE(fs::is_directory(writer.xdmfPath()));
  EXPECT_EQ(countTemporaries(directory.path()), 0);
  EXPECT_EQ(writer.numSteps(), 0);
}

TEST(TEST_CATEGORY, output_into_missing_directory_throws_and_writes_nothing) {
  const TemporaryDirectory directory;
  const std::string missing = directory / "missing";
  std::string message = messageOf<std::runtime_error>(
      [&] { perishell::io::XdmfTimeSeriesWriter writer(missing, "plate", plate()); });
  EXPECT_NE(message.find(missing + "/plate_mesh.h5"), std::string::npos) << message;
  EXPECT_NE(message.find(std::strerror(ENOENT)), std::string::npos) << message;

  // A path through a regular file (ENOTDIR): root cannot bypass this one, unlike permissions.
  perishell::io::writeFileAtomically(directory / "file", "x");
  const std::string throughFile = directory / "file/history.csv";
  message =
      messageOf<std::runtime_error>([&] { perishell::io::CsvHistory history(throughFile, {"time [s]"}); });
  EXPECT_NE(message.find(throughFile), std::string::npos) << message;
  EXPECT_NE(message.find(std::strerror(ENOTDIR)), std::string::npos) << message;

  EXPECT_EQ(filesIn(directory.path()), std::vector<std::string>{"file"});
  EXPECT_EQ(readFile(directory / "file"), "x");
}

TEST(TEST_CATEGORY, output_atomic_replace_keeps_old_file_when_writer_throws) {
  const TemporaryDirectory directory;
  const std::string path = directory / "state.txt";
  perishell::io::writeFileAtomically(path, "old contents\n");
  EXPECT_THROW(perishell::io::replaceFileAtomically(path,
                                                    [](const std::string& temporary) {
                                                      std::ofstream(temporary) << "half";
                                                      throw std::runtime_error("disk full (simulated)");
                                                    }),
               std::runtime_error);
  EXPECT_EQ(readFile(path), "old contents\n");
  EXPECT_EQ(filesIn(directory.path()), std::vector<std::string>{"state.txt"});
  perishell::io::writeFileAtomically(path, "new\n");
  EXPECT_EQ(readFile(path), "new\n");
  EXPECT_EQ(filesIn(directory.path()), std::vector<std::string>{"state.txt"});
}

std::vector<std::string> split(const std::string& text, char separator) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  for (;;) {
    const std::size_t end = text.find(separator, start);
    parts.push_back(text.substr(start, end - start));
    if (end == std::string::npos) return parts;
    start = end + 1;
  }
}

TEST(TEST_CATEGORY, output_csv_history_round_trips_every_double) {
  const TemporaryDirectory directory;
  const std::string path = directory / "history.csv";
  const std::vector<std::string> columns = {"time [s]", "strain energy [J]", "crack length [m]"};
  perishell::io::CsvHistory history(path, columns);
  EXPECT_EQ(readFile(path), "time [s],strain energy [J],crack length [m]\n");  // header at construction

  const std::vector<std::vector<double>> rows = {
      {0.0, 0.1, 1.0 / 3.0},
      {-0.0, DBL_MAX, DBL_MIN},
      {4.9406564584124654e-324, -2.0 / 7.0, 123456789012345678.0},
      {1e-300, NAN, INFINITY},
      {-INFINITY, std::nextafter(1.0, 2.0), -1e22},
  };
  // Each row is in the file as soon as it is appended (a running or killed run shows its rows).
  for (std::size_t row = 0; row < rows.size(); ++row) {
    history.append(rows[row]);
    EXPECT_EQ(split(readFile(path), '\n').size(), row + 3);  // header, the rows so far, trailing ""
  }
  EXPECT_EQ(history.numRows(), rows.size());
  EXPECT_EQ(countTemporaries(directory.path()), 0);

  const auto lines = split(readFile(path), '\n');
  ASSERT_EQ(lines.size(), rows.size() + 2);
  EXPECT_EQ(lines.back(), "");
  EXPECT_EQ(split(lines[0], ','), columns);
  EXPECT_EQ(lines[4], "1e-300,nan,inf");  // the shortest %.17g form, literal non-finites
  for (std::size_t row = 0; row < rows.size(); ++row) {
    const auto cells = split(lines[row + 1], ',');
    ASSERT_EQ(cells.size(), columns.size()) << lines[row + 1];
    for (std::size_t column = 0; column < cells.size(); ++column) {
      char* end = nullptr;
      const double value = std::strtod(cells[column].c_str(), &end);
      EXPECT_EQ(*end, '\0') << cells[column];
      const double expected = rows[row][column];
      if (std::isnan(expected))
        EXPECT_TRUE(std::isnan(value)) << cells[column];
      else
        EXPECT_TRUE(sameBits(value, expected))
            << "row " << row << " column " << column << ": " << cells[column];
    }
  }
}

TEST(TEST_CATEGORY, output_csv_history_rejects_bad_rows_and_names) {
  const TemporaryDirectory directory;
  perishell::io::CsvHistory history(directory / "history.csv", {"time [s]", "energy [J]", "force [N]"});
  const std::string message = messageOf<std::invalid_argument>([&] { history.append({1.0, 2.0}); });
  EXPECT_NE(message.find("row 0 has 2 values, expected 3"), std::string::npos) << message;
  EXPECT_NE(message.find(directory / "history.csv"), std::string::npos) << message;
  EXPECT_THROW(history.append({1.0, 2.0, 3.0, 4.0}), std::invalid_argument);
  EXPECT_EQ(history.numRows(), 0u);

  EXPECT_THROW(perishell::io::CsvHistory(directory / "a.csv", {}), std::invalid_argument);
  const std::string badName = messageOf<std::invalid_argument>([&] {
    perishell::io::CsvHistory(directory / "b.csv", {"time [s]", "x,y"});
  });
  EXPECT_NE(badName.find("column 1 name 'x,y'"), std::string::npos) << badName;
  EXPECT_EQ(filesIn(directory.path()), std::vector<std::string>{"history.csv"});
}

// Positions x_(node, d) = node / 7 + d filled on the device (a free function: nvcc refuses
// extended lambdas in a test body).
Kokkos::View<double* [3], Kokkos::LayoutRight, TEST_MEMSPACE> devicePositions(int numNodes) {
  Kokkos::View<double* [3], Kokkos::LayoutRight, TEST_MEMSPACE> positions("positions", numNodes);
  Kokkos::parallel_for(
      "fill positions", Kokkos::RangePolicy<TEST_EXECSPACE>(0, numNodes), KOKKOS_LAMBDA(const int node) {
        for (int d = 0; d < 3; ++d) positions(node, d) = node / 7.0 + d;
      });
  return positions;
}

TEST(TEST_CATEGORY, output_checkpoint_round_trips_every_value_bit_for_bit) {
  const TemporaryDirectory directory;
  const std::string path = directory / "checkpoint.h5";
  const std::vector<double> reals = {0.0, -0.0, DBL_MAX, DBL_MIN, 4.9406564584124654e-324, 1.0 / 3.0, NAN, -INFINITY};
  perishell::io::Checkpoint saved;
  saved.putReals("solver.state", reals);
  saved.putReals("empty", {});
  saved.putInteger("solver.step", 1234567890123LL);
  saved.putIntegers("flags", {-1, 0, 5});
  saved.putBytes("intact-bonds", {0, 1, 255, 1});
  saved.putText("layout", "displacement:3 damage:1\n");
  // A device view in and out, through the host.
  const auto positions = devicePositions(5);
  perishell::io::putView(saved, "positions", positions);
  saved.write(path);
  EXPECT_EQ(countTemporaries(directory.path()), 0);

  const auto read = perishell::io::Checkpoint::read(path);
  EXPECT_EQ(read.source(), path);
  const auto& back = read.reals("solver.state");
  ASSERT_EQ(back.size(), reals.size());
  for (std::size_t k = 0; k < reals.size(); ++k) EXPECT_TRUE(sameBits(back[k], reals[k])) << k;
  EXPECT_TRUE(read.reals("empty").empty());
  EXPECT_EQ(read.integer("solver.step"), 1234567890123LL);
  EXPECT_EQ(read.integers("flags"), (std::vector<long long>{-1, 0, 5}));
  EXPECT_EQ(read.bytes("intact-bonds"), (std::vector<std::uint8_t>{0, 1, 255, 1}));
  EXPECT_EQ(read.text("layout"), "displacement:3 damage:1\n");
  Kokkos::View<double* [3], Kokkos::LayoutRight, TEST_MEMSPACE> restored("restored", 5);
  perishell::io::takeView(read, "positions", restored, "another model");
  const auto host = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, restored);
  for (int node = 0; node < 5; ++node)
    for (int d = 0; d < 3; ++d) EXPECT_TRUE(sameBits(host(node, d), node / 7.0 + d));

  // What does not fit is named with the file and the entry.
  Kokkos::View<double* [3], Kokkos::LayoutRight, TEST_MEMSPACE> larger("larger", 6);
  const std::string sizes = messageOf<perishell::io::CheckpointError>(
      [&] { perishell::io::takeView(read, "positions", larger, "another model"); });
  EXPECT_EQ(sizes, "checkpoint " + path + ": 'positions' holds 15 values where this run has 18: another model");
  const std::string missing = messageOf<perishell::io::CheckpointError>([&] { read.reals("velocities"); });
  EXPECT_EQ(missing, "checkpoint " + path +
                         ": no entry 'velocities' (written by another version of perishell, or by the run of another "
                         "deck)");
  EXPECT_THROW(read.integer("flags"), perishell::io::CheckpointError);  // three values, not one
  // Not a checkpoint, and no file at all.
  std::ofstream(directory / "text.h5") << "not HDF5\n";
  const std::string notHdf5 =
      messageOf<perishell::io::CheckpointError>([&] { perishell::io::Checkpoint::read(directory / "text.h5"); });
  EXPECT_EQ(notHdf5.rfind("checkpoint " + directory / "text.h5" + ": cannot be read (HDF5 file", 0), 0u) << notHdf5;
  const std::string none =
      messageOf<perishell::io::CheckpointError>([&] { perishell::io::Checkpoint::read(directory / "none.h5"); });
  EXPECT_EQ(none.rfind("checkpoint " + directory / "none.h5" + ": no such file", 0), 0u) << none;
}

TEST(TEST_CATEGORY, output_csv_history_continues_an_earlier_run_cutting_its_later_rows) {
  const TemporaryDirectory directory;
  const std::string path = directory / "history.csv";
  const std::vector<std::string> columns = {"step", "energy [J]"};
  {
    perishell::io::CsvHistory earlier(path, columns);
    for (int row = 0; row < 5; ++row) earlier.append({double(row), row / 3.0});
  }
  // Continued after row 3: rows 3 and 4 of the interrupted run go, the new ones follow.
  perishell::io::CsvHistory continued(path, columns, 3);
  EXPECT_EQ(continued.numRows(), 3u);
  continued.append({30.0, 0.5});
  EXPECT_EQ(readFile(path), "step,energy [J]\n0,0\n1,0.33333333333333331\n2,0.66666666666666663\n30,0.5\n");
  EXPECT_EQ(countTemporaries(directory.path()), 0);

  const std::string fewer = messageOf<std::runtime_error>([&] { perishell::io::CsvHistory(path, columns, 9); });
  EXPECT_EQ(fewer, "cannot continue the history '" + path + "': it has 4 whole rows, the checkpoint was written "
                   "after row 9");
  const std::string other =
      messageOf<std::runtime_error>([&] { perishell::io::CsvHistory(path, {"step", "time [s]"}, 1); });
  EXPECT_EQ(other, "cannot continue the history '" + path + "': its header is not this run's columns (step,time [s])");
  EXPECT_THROW(perishell::io::CsvHistory(directory / "none.csv", columns, 0), std::runtime_error);
}

TEST(TEST_CATEGORY, output_xdmf_series_continues_an_earlier_run_dropping_its_later_steps) {
  const TemporaryDirectory directory;
  const auto mesh = plate();
  std::vector<perishell::io::XdmfTimeSeriesWriter::StepRecord> kept;
  std::string xmfAfterTwo;
  {
    perishell::io::XdmfTimeSeriesWriter earlier(directory.path(), "plate", mesh);
    for (int step = 0; step < 4; ++step) {
      earlier.writeStep(0.25 * step, {{"damage", 1, nodalValues(1, step)}, {"displacement", 3, nodalValues(3, step)}});
      if (step == 1) {
        kept = earlier.steps();
        xmfAfterTwo = readFile(earlier.xdmfPath());
      }
    }
  }
  // A restart after step 1: steps 2 and 3 of the interrupted run go, the series goes on from there.
  perishell::io::XdmfTimeSeriesWriter continued(directory.path(), "plate", mesh);
  continued.continueSeries(kept);
  EXPECT_EQ(continued.numSteps(), 2);
  EXPECT_EQ(readFile(continued.xdmfPath()), xmfAfterTwo);
  EXPECT_EQ(filesIn(directory.path()),
            (std::vector<std::string>{"plate.xmf", "plate_000000.h5", "plate_000001.h5", "plate_mesh.h5"}));
  continued.writeStep(0.6, {{"damage", 1, nodalValues(1, 9.0)}, {"displacement", 3, nodalValues(3, 9.0)}});
  const auto damage = readDataset(directory / "plate_000002.h5", "/fields/damage", false);
  EXPECT_TRUE(sameBits(damage.doubles[4], nodalValues(1, 9.0)(4, 0)));
  const auto xmf = readFile(continued.xdmfPath());
  EXPECT_NE(xmf.find("<Time Value=\"0.59999999999999998\"/>"), std::string::npos) << xmf;
  EXPECT_EQ(xmf.find("<Time Value=\"0.75\"/>"), std::string::npos) << xmf;

  // A step the checkpoint lists but the directory lacks is named.
  fs::remove(directory / "plate_000001.h5");
  perishell::io::XdmfTimeSeriesWriter broken(directory.path(), "plate", mesh);
  const std::string message = messageOf<std::runtime_error>([&] { broken.continueSeries(kept); });
  EXPECT_NE(message.find("step 1 of the run to continue is missing (" + directory / "plate_000001.h5" + ")"),
            std::string::npos)
      << message;
}

}  // namespace
