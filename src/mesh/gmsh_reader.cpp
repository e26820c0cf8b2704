#include <perishell/mesh/gmsh_reader.hpp>
#include <perishell/mesh/quad_shape.hpp>

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <unordered_map>
#include <utility>
#include <vector>

namespace perishell::mesh {

namespace {

struct Token {
  std::string_view text;
  int line;
};

// Whitespace-separated tokens with their line numbers; "..." is one token (physical
// names may hold spaces). Reports errors as "<source>:<line>: <reason>".
class Scanner {
 public:
  Scanner(const std::string& text, const std::string& source) : text_(text), source_(source) {}

  bool atEnd() {
    skipWhitespace();
    return position_ == text_.size();
  }

  // The next token; the end of the file here means the current section is cut short.
  Token next(const char* what) {
    if (atEnd())
      fail(lastTokenLine_, "truncated " + section + " section: the file ends while reading " + what);
    const std::size_t begin = position_;
    if (text_[position_] == '"') {
      const std::size_t close = text_.find_first_of("\"\n", position_ + 1);
      if (close == std::string::npos || text_[close] != '"')
        fail(line_, std::string("unterminated quoted string while reading ") + what);
      position_ = close + 1;
    } else {
      while (position_ < text_.size() && !isWhitespace(text_[position_])) ++position_;
    }
    lastTokenLine_ = line_;
    return {std::string_view(text_).substr(begin, position_ - begin), line_};
  }

  long long integer(const char* what) {
    const Token token = next(what);
    long long value = 0;
    const char* end = token.text.data() + token.text.size();
    const auto result = std::from_chars(token.text.data(), end, value);
    if (result.ec != std::errc() || result.ptr != end)
      fail(token.line, std::string("expected ") + what + " (an integer), got '" +
                           std::string(token.text) + "'");
    return value;
  }

  // An integer that must lie in [minimum, maximum].
  long long integerIn(const char* what, long long minimum, long long maximum) {
    const int line = peekLine();
    const long long value = integer(what);
    if (value < minimum || value > maximum)
      fail(line, std::string(what) + " " + std::to_string(value) + " is out of range [" +
                     std::to_string(minimum) + ", " + std::to_string(maximum) + "]");
    return value;
  }

  double real(const char* what) {
    const Token token = next(what);
    // Tokens end at whitespace or at the end of the text, so strtod cannot run past one.
    char* end = nullptr;
    const double value = std::strtod(token.text.data(), &end);
    if (end != token.text.data() + token.text.size() || !std::isfinite(value))
      fail(token.line, std::string("expected ") + what + " (a finite number), got '" +
                           std::string(token.text) + "'");
    return value;
  }

  void expect(const std::string& keyword) {
    const Token token = next(keyword.c_str());
    if (token.text != keyword)
      fail(token.line, "expected " + keyword + ", got '" + std::string(token.text) + "'");
  }

  int peekLine() {
    skipWhitespace();
    return line_;
  }
  int lastTokenLine() const { return lastTokenLine_; }

  [[noreturn]] void fail(int line, const std::string& reason) const {
    throw std::runtime_error(source_ + ":" + std::to_string(line) + ": " + reason);
  }

  // An entity or physical tag. Gmsh writes a tag negative where the entity is used with its
  // orientation reversed (Extrude, Physical Curve{-4}, $Entities' signed physical tags); the
  // sign says nothing about which entity or group is meant, so it is dropped here.
  int unsignedTag(const char* what) {
    const int line = peekLine();
    const long long tag = integerIn(what, -INT32_MAX, INT32_MAX);
    if (tag == 0) fail(line, std::string(what) + " 0 is not a Gmsh tag (tags start at 1)");
    return static_cast<int>(tag < 0 ? -tag : tag);
  }

  std::string section;

 private:
  static bool isWhitespace(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; }
  void skipWhitespace() {
    while (position_ < text_.size() && isWhitespace(text_[position_])) {
      if (text_[position_] == '\n') ++line_;
      ++position_;
    }
  }

  const std::string& text_;
  const std::string& source_;
  std::size_t position_ = 0;
  int line_ = 1;
  int lastTokenLine_ = 1;
};

constexpr long long maxCount = 1LL << 31;

enum GmshType : int { lineType = 1, triangleType = 2, quadType = 3, pointType = 15 };

int nodesPerElement(int type) { return type == quadType ? 4 : type == triangleType ? 3 : type == lineType ? 2 : 1; }
int dimensionOf(int type) { return type == quadType || type == triangleType ? 2 : type == lineType ? 1 : 0; }

[[noreturn]] void rejectElementType(Scanner& scanner, int line, long long type) {
  switch (type) {
    case 8: case 9: case 10: case 16:
      scanner.fail(line, "second-order element type " + std::to_string(type) +
                             " is not supported; mesh with Mesh.ElementOrder = 1");
    case 4: case 5: case 6: case 7:
      scanner.fail(line, "volume element type " + std::to_string(type) +
                             " is not supported: a shell mesh holds quads, triangles, lines and points only");
    default:
      scanner.fail(line, "element type " + std::to_string(type) +
                             " is not supported (quads 3, triangles 2, lines 1 and points 15 only)");
  }
}

struct RawElement {
  long long tag;
  long long nodeTags[4];  // a triangle's fourth repeats its third (mesh/quad_mesh.hpp)
  int corners;            // surface elements: 4 (quad) or 3 (triangle)
  int line;
  int entityTag;
};

struct GmshFile {
  std::map<std::pair<int, int>, std::string> physicalNames;  // (dimension, physical tag)
  bool hasEntities = false;
  std::map<int, std::vector<int>> entityPhysicals[4];  // per dimension: entity tag -> groups
  std::unordered_map<long long, int> nodeOfTag;  // Gmsh node tag -> position in the file
  std::vector<std::array<double, 3>> nodeCoordinates;
  std::vector<RawElement> elements[3];  // by dimension: points, lines, quads and triangles
};

void readMeshFormat(Scanner& scanner) {
  const Token version = scanner.next("the MSH version");
  if (version.text != "4.1")
    scanner.fail(version.line, "MSH version " + std::string(version.text) +
                                   " is not supported; save as MSH 4.1 (Mesh.MshFileVersion = 4.1)");
  const int fileTypeLine = scanner.peekLine();
  const long long fileType = scanner.integer("the file type");
  if (fileType == 1)
    scanner.fail(fileTypeLine, "binary MSH files are not supported; save as ASCII (Mesh.Binary = 0)");
  if (fileType != 0)
    scanner.fail(fileTypeLine, "file type " + std::to_string(fileType) + " is not 0 (ASCII)");
  scanner.integer("the data size");
}

void readPhysicalNames(Scanner& scanner, GmshFile& file) {
  const long long count = scanner.integerIn("the number of physical names", 0, maxCount);
  for (long long i = 0; i < count; ++i) {
    const int dimension = static_cast<int>(scanner.integerIn("a physical group dimension", 0, 3));
    const int line = scanner.peekLine();
    const int tag = scanner.unsignedTag("a physical tag");
    const Token name = scanner.next("a physical name");
    if (name.text.size() < 3 || name.text.front() != '"')
      scanner.fail(name.line, "expected a non-empty quoted physical name, got '" +
                                  std::string(name.text) + "'");
    if (!file.physicalNames.emplace(std::make_pair(dimension, tag),
                                    std::string(name.text.substr(1, name.text.size() - 2))).second)
      scanner.fail(line, "physical tag " + std::to_string(tag) + " of dimension " +
                             std::to_string(dimension) + " is named twice");
  }
}

void readEntities(Scanner& scanner, GmshFile& file) {
  file.hasEntities = true;
  long long counts[4];
  const char* what[4] = {"the number of points", "the number of curves", "the number of surfaces",
                         "the number of volumes"};
  for (int d = 0; d < 4; ++d) counts[d] = scanner.integerIn(what[d], 0, maxCount);
  for (int dimension = 0; dimension < 4; ++dimension)
    for (long long i = 0; i < counts[dimension]; ++i) {
      const int line = scanner.peekLine();
      const int tag = scanner.unsignedTag("an entity tag");
      // A point has its position, the others a bounding box.
      for (int k = 0; k < (dimension == 0 ? 3 : 6); ++k) scanner.real("an entity coordinate");
      // Counts are read, not trusted: containers grow by the items actually present.
      std::vector<int> physicals;
      const long long numPhysicals = scanner.integerIn("the number of physical tags", 0, maxCount);
      for (long long p = 0; p < numPhysicals; ++p) {
        const int physical = scanner.unsignedTag("a physical tag");
        // Listed with both signs, the entity is in the group once.
        if (std::find(physicals.begin(), physicals.end(), physical) == physicals.end()) physicals.push_back(physical);
      }
      if (dimension > 0) {
        const long long bounding = scanner.integerIn("the number of bounding entities", 0, maxCount);
        for (long long b = 0; b < bounding; ++b) scanner.integer("a bounding entity tag");
      }
      if (!file.entityPhysicals[dimension].emplace(tag, std::move(physicals)).second)
        scanner.fail(line, "entity " + std::to_string(tag) + " of dimension " +
                               std::to_string(dimension) + " is listed twice");
    }
}

void readNodes(Scanner& scanner, GmshFile& file) {
  const long long blocks = scanner.integerIn("the number of node blocks", 0, maxCount);
  const int headerLine = scanner.peekLine();
  const long long numNodes = scanner.integerIn("the number of nodes", 0, maxCount);
  scanner.integer("the minimum node tag");
  scanner.integer("the maximum node tag");
  for (long long block = 0; block < blocks; ++block) {
    const int dimension = static_cast<int>(scanner.integerIn("a node block's entity dimension", 0, 3));
    scanner.integer("a node block's entity tag");
    const bool parametric = scanner.integerIn("a node block's parametric flag", 0, 1) == 1;
    const long long count = scanner.integerIn("a node block's node count", 0, maxCount);
    const std::size_t first = file.nodeCoordinates.size();
    if (static_cast<long long>(first) + count > numNodes)
      scanner.fail(scanner.lastTokenLine(), "node blocks hold more than the " +
                                                std::to_string(numNodes) + " nodes of the header");
    for (long long i = 0; i < count; ++i) {
      const int line = scanner.peekLine();
      const long long tag = scanner.integerIn("a node tag", 1, LLONG_MAX);
      if (!file.nodeOfTag.emplace(tag, static_cast<int>(first + i)).second)
        scanner.fail(line, "node tag " + std::to_string(tag) + " appears twice");
    }
    for (long long i = 0; i < count; ++i) {
      std::array<double, 3> x;
      for (auto& component : x) component = scanner.real("a node coordinate");
      file.nodeCoordinates.push_back(x);
      if (parametric)
        for (int k = 0; k < dimension; ++k) scanner.real("a parametric node coordinate");
    }
  }
  if (static_cast<long long>(file.nodeCoordinates.size()) != numNodes)
    scanner.fail(headerLine, "the header announces " + std::to_string(numNodes) +
                                 " nodes but the blocks hold " +
                                 std::to_string(file.nodeCoordinates.size()));
}

void readElements(Scanner& scanner, GmshFile& file) {
  const long long blocks = scanner.integerIn("the number of element blocks", 0, maxCount);
  const int headerLine = scanner.peekLine();
  const long long numElements = scanner.integerIn("the number of elements", 0, maxCount);
  scanner.integer("the minimum element tag");
  scanner.integer("the maximum element tag");
  long long read = 0;
  for (long long block = 0; block < blocks; ++block) {
    const int blockLine = scanner.peekLine();
    const int dimension = static_cast<int>(scanner.integerIn("an element block's entity dimension", 0, 3));
    const int entityTag = scanner.unsignedTag("an element block's entity tag");
    const long long type = scanner.integer("an element type");
    if (type != quadType && type != triangleType && type != lineType && type != pointType)
      rejectElementType(scanner, blockLine, type);
    if (dimensionOf(static_cast<int>(type)) != dimension)
      scanner.fail(blockLine, "element type " + std::to_string(type) + " in a block of dimension " +
                                  std::to_string(dimension));
    const char* entityKind[3] = {"point", "curve", "surface"};
    if (file.hasEntities && file.entityPhysicals[dimension].count(entityTag) == 0)
      scanner.fail(blockLine, std::string("element block on ") + entityKind[dimension] + " " +
                                  std::to_string(entityTag) + ", which $Entities does not list");
    const long long count = scanner.integerIn("an element block's element count", 0, maxCount);
    read += count;
    if (read > numElements)
      scanner.fail(blockLine, "element blocks hold more than the " + std::to_string(numElements) +
                                  " elements of the header");
    auto& elements = file.elements[dimension];
    for (long long i = 0; i < count; ++i) {
      RawElement element{};
      element.line = scanner.peekLine();
      element.entityTag = entityTag;
      element.tag = scanner.integerIn("an element tag", 1, LLONG_MAX);
      element.corners = nodesPerElement(static_cast<int>(type));
      for (int a = 0; a < element.corners; ++a) {
        element.nodeTags[a] = scanner.integer("an element's node tag");
        if (file.nodeOfTag.count(element.nodeTags[a]) == 0)
          scanner.fail(element.line, "element " + std::to_string(element.tag) +
                                         " refers to unknown node tag " +
                                         std::to_string(element.nodeTags[a]));
      }
      if (type == triangleType) element.nodeTags[3] = element.nodeTags[2];
      elements.push_back(element);
    }
  }
  if (read != numElements)
    scanner.fail(headerLine, "the header announces " + std::to_string(numElements) +
                                 " elements but the blocks hold " + std::to_string(read));
}

void skipSection(Scanner& scanner, const std::string& end) {
  while (scanner.next(end.c_str()).text != end) {
  }
}

std::uint64_t edgeKey(LocalIndex a, LocalIndex b) {
  const auto low = static_cast<std::uint64_t>(std::min(a, b));
  const auto high = static_cast<std::uint64_t>(std::max(a, b));
  return (high << 32) | low;
}

struct EdgeUse {
  std::uint64_t key;
  LocalIndex quad;
  int localEdge;
};

// 3 for a triangle (a b c c), 4 for a quad.
int cornersOf(const std::array<LocalIndex, 4>& element) { return element[3] == element[2] ? 3 : 4; }

// One entry per element edge, sorted by edge so the elements sharing an edge are adjacent.
std::vector<EdgeUse> sortedEdgeUses(const std::vector<std::array<LocalIndex, 4>>& quads) {
  std::vector<EdgeUse> uses;
  uses.reserve(4 * quads.size());
  for (std::size_t q = 0; q < quads.size(); ++q)
    for (int k = 0, corners = cornersOf(quads[q]); k < corners; ++k)
      uses.push_back({edgeKey(quads[q][k], quads[q][(k + 1) % corners]), static_cast<LocalIndex>(q), k});
  std::sort(uses.begin(), uses.end(), [](const EdgeUse& a, const EdgeUse& b) {
    return a.key != b.key ? a.key < b.key : a.quad < b.quad;
  });
  return uses;
}

bool traversesUpward(const std::array<LocalIndex, 4>& quad, int localEdge) {
  return quad[localEdge] < quad[(localEdge + 1) % cornersOf(quad)];
}

// Flip quads so that two quads sharing an edge traverse it in opposite directions; each
// connected patch keeps its first quad's orientation. Edges of three or more quads
// (junctions of shell parts) impose nothing.
void orientConsistently(std::vector<std::array<LocalIndex, 4>>& quads, const std::vector<EdgeUse>& uses,
                        const std::vector<RawElement>& rawQuads, const Scanner& scanner) {
  const std::size_t numQuads = quads.size();
  // For each quad and local edge: the neighbour across it, and whether both traverse it alike.
  std::vector<std::array<LocalIndex, 4>> neighbour(numQuads, {-1, -1, -1, -1});
  std::vector<std::array<bool, 4>> sameDirection(numQuads);
  for (std::size_t i = 0; i < uses.size();) {
    std::size_t j = i;
    while (j < uses.size() && uses[j].key == uses[i].key) ++j;
    if (j - i == 2) {
      const EdgeUse& a = uses[i];
      const EdgeUse& b = uses[i + 1];
      const bool alike = traversesUpward(quads[a.quad], a.localEdge) == traversesUpward(quads[b.quad], b.localEdge);
      neighbour[a.quad][a.localEdge] = b.quad;
      neighbour[b.quad][b.localEdge] = a.quad;
      sameDirection[a.quad][a.localEdge] = alike;
      sameDirection[b.quad][b.localEdge] = alike;
    }
    i = j;
  }
  std::vector<signed char> flipped(numQuads, -1);  // -1: not reached yet
  std::vector<LocalIndex> queue;
  for (std::size_t seed = 0; seed < numQuads; ++seed) {
    if (flipped[seed] >= 0) continue;
    flipped[seed] = 0;
    queue.assign(1, static_cast<LocalIndex>(seed));
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const LocalIndex q = queue[head];
      for (int k = 0; k < cornersOf(quads[q]); ++k) {
        const LocalIndex other = neighbour[q][k];
        if (other < 0) continue;
        const signed char required = flipped[q] ^ (sameDirection[q][k] ? 1 : 0);
        if (flipped[other] < 0) {
          flipped[other] = required;
          queue.push_back(other);
        } else if (flipped[other] != required) {
          scanner.fail(rawQuads[other].line,
                       "elements " + std::to_string(rawQuads[q].tag) + " and " +
                           std::to_string(rawQuads[other].tag) +
                           " cannot be oriented consistently: the surface is not orientable");
        }
      }
    }
  }
  for (std::size_t q = 0; q < numQuads; ++q) {
    if (!flipped[q]) continue;
    if (cornersOf(quads[q]) == 3) {
      std::swap(quads[q][1], quads[q][2]);
      quads[q][3] = quads[q][2];
    } else {
      std::swap(quads[q][1], quads[q][3]);
    }
  }
}

// The edge {a, b} in the direction the (possibly flipped) quad traverses it.
MeshEdge asTraversed(const std::array<LocalIndex, 4>& quad, LocalIndex a, LocalIndex b) {
  const int corners = cornersOf(quad);
  for (int k = 0; k < corners; ++k)
    if (quad[k] == b && quad[(k + 1) % corners] == a) return {b, a};
  return {a, b};
}

std::string groupName(const GmshFile& file, int dimension, int physicalTag) {
  const auto found = file.physicalNames.find({dimension, physicalTag});
  if (found != file.physicalNames.end()) return found->second;
  const char* kind[3] = {"point-", "curve-", "surface-"};
  return kind[dimension] + std::to_string(physicalTag);
}

const std::vector<int>& physicalsOf(const GmshFile& file, int dimension, int entityTag) {
  static const std::vector<int> none;
  const auto found = file.entityPhysicals[dimension].find(entityTag);
  return found == file.entityPhysicals[dimension].end() ? none : found->second;
}

// "quad element 12" or "triangle element 12", as the file's element type says.
std::string elementName(const RawElement& element) {
  return std::string(element.corners == 3 ? "triangle" : "quad") + " element " + std::to_string(element.tag);
}

// An element the shell elements and node weights cannot be built on, named by its tags and line.
void checkQuadShapeAt(const GmshFile& file, const RawElement& quad, const Scanner& scanner) {
  QuadShapeCheck shape;
  if (quad.corners == 3) {
    std::array<std::array<double, 3>, 3> corners;
    for (int a = 0; a < 3; ++a) corners[a] = file.nodeCoordinates[file.nodeOfTag.at(quad.nodeTags[a])];
    shape = checkTriangleShape(corners);
  } else {
    std::array<std::array<double, 3>, 4> corners;
    for (int a = 0; a < 4; ++a) corners[a] = file.nodeCoordinates[file.nodeOfTag.at(quad.nodeTags[a])];
    shape = checkQuadShape(corners);
  }
  if (shape.defect == QuadShapeDefect::none) return;
  std::string name = elementName(quad) + " (node tags";
  for (int a = 0; a < quad.corners; ++a) name += " " + std::to_string(quad.nodeTags[a]);
  name += ")";
  const auto tag = [&quad](int corner) { return std::to_string(quad.nodeTags[corner]); };
  switch (shape.defect) {
    case QuadShapeDefect::coincidentCorners:
      scanner.fail(quad.line, name + ": nodes " + tag(shape.corner) + " and " + tag(shape.otherCorner) +
                                  " are at the same point; " +
                                  (quad.corners == 3 ? "a triangle needs three" : "a quad needs four") +
                                  " distinct corners");
    case QuadShapeDefect::zeroArea:
      scanner.fail(quad.line, name + " has zero area: its nodes lie on one line");
    case QuadShapeDefect::selfCrossing:
      scanner.fail(quad.line, name + " crosses itself (a bow-tie): its nodes are not listed in order "
                                     "around its outline");
    case QuadShapeDefect::reentrantCorner:
      scanner.fail(quad.line, name + " is not convex: its corner at node " + tag(shape.corner) +
                                  " points inward or is straight, where the element map folds");
    case QuadShapeDefect::none:
      break;
  }
}

ShellMesh buildShellMesh(const GmshFile& file, const Scanner& scanner) {
  const auto& rawQuads = file.elements[2];
  if (rawQuads.empty())
    scanner.fail(scanner.lastTokenLine(), "the file holds no surface elements (quads, type 3, or triangles, type 2)");

  // Keep the nodes of quads and triangles, numbered in file order.
  std::vector<LocalIndex> indexOfFileNode(file.nodeCoordinates.size(), -1);
  for (const auto& quad : rawQuads)
    for (int a = 0; a < 4; ++a) indexOfFileNode[file.nodeOfTag.at(quad.nodeTags[a])] = 0;
  LocalIndex numNodes = 0;
  for (auto& index : indexOfFileNode)
    if (index == 0) index = numNodes++;
  auto quadNode = [&](const RawElement& element, int a, const char* kind) {
    const LocalIndex index = indexOfFileNode[file.nodeOfTag.at(element.nodeTags[a])];
    if (index < 0)
      scanner.fail(element.line, std::string(kind) + " element " + std::to_string(element.tag) +
                                     ": node tag " + std::to_string(element.nodeTags[a]) +
                                     " is not a node of any quad or triangle");
    return index;
  };

  std::vector<std::array<LocalIndex, 4>> quads(rawQuads.size());
  for (std::size_t q = 0; q < rawQuads.size(); ++q) {
    const char* kind = rawQuads[q].corners == 3 ? "triangle" : "quad";
    for (int a = 0; a < 4; ++a) quads[q][a] = quadNode(rawQuads[q], a, kind);
    for (int a = 0; a < rawQuads[q].corners; ++a)
      for (int b = a + 1; b < rawQuads[q].corners; ++b)
        if (quads[q][a] == quads[q][b])
          scanner.fail(rawQuads[q].line, elementName(rawQuads[q]) + " repeats node tag " +
                                             std::to_string(rawQuads[q].nodeTags[a]));
    checkQuadShapeAt(file, rawQuads[q], scanner);
  }
  const auto uses = sortedEdgeUses(quads);
  orientConsistently(quads, uses, rawQuads, scanner);

  ShellMesh shell;
  MeshSets& sets = shell.sets;
  auto addNodes = [&sets](const std::string& name, const LocalIndex* nodes, int count) {
    auto& set = sets.nodeSets[name];
    set.insert(set.end(), nodes, nodes + count);
  };
  for (std::size_t q = 0; q < rawQuads.size(); ++q)
    for (int physical : physicalsOf(file, 2, rawQuads[q].entityTag)) {
      const std::string name = groupName(file, 2, physical);
      sets.elementSets[name].push_back(static_cast<LocalIndex>(q));
      addNodes(name, quads[q].data(), 4);
    }
  for (const auto& line : file.elements[1]) {
    const auto& physicals = physicalsOf(file, 1, line.entityTag);
    if (physicals.empty()) continue;
    const LocalIndex ends[2] = {quadNode(line, 0, "line"), quadNode(line, 1, "line")};
    const std::uint64_t key = edgeKey(ends[0], ends[1]);
    const auto found = std::lower_bound(uses.begin(), uses.end(), key,
                                        [](const EdgeUse& use, std::uint64_t k) { return use.key < k; });
    if (found == uses.end() || found->key != key)
      scanner.fail(line.line, "line element " + std::to_string(line.tag) + " (node tags " +
                                  std::to_string(line.nodeTags[0]) + " " + std::to_string(line.nodeTags[1]) +
                                  ") is not an edge of any quad or triangle");
    const MeshEdge edge = asTraversed(quads[found->quad], ends[0], ends[1]);
    for (int physical : physicals) {
      const std::string name = groupName(file, 1, physical);
      sets.edgeSets[name].push_back(edge);
      addNodes(name, ends, 2);
    }
  }
  for (const auto& point : file.elements[0]) {
    const auto& physicals = physicalsOf(file, 0, point.entityTag);
    if (physicals.empty()) continue;
    const LocalIndex node = quadNode(point, 0, "point");
    for (int physical : physicals) addNodes(groupName(file, 0, physical), &node, 1);
  }
  for (auto& entry : sets.nodeSets) {
    auto& nodes = entry.second;
    std::sort(nodes.begin(), nodes.end());
    nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  }

  auto& mesh = shell.mesh;
  mesh.coordinates = CoordinateView<Kokkos::HostSpace>("gmsh coordinates", numNodes);
  mesh.quads = QuadConnectivityView<Kokkos::HostSpace>("gmsh quads", quads.size());
  for (std::size_t i = 0; i < indexOfFileNode.size(); ++i)
    if (indexOfFileNode[i] >= 0)
      for (int k = 0; k < 3; ++k) mesh.coordinates(indexOfFileNode[i], k) = file.nodeCoordinates[i][k];
  for (std::size_t q = 0; q < quads.size(); ++q)
    for (int a = 0; a < 4; ++a) mesh.quads(q, a) = quads[q][a];
  return shell;
}

}  // namespace

ShellMesh parseGmsh(const std::string& text, const std::string& sourceName) {
  Scanner scanner(text, sourceName);
  GmshFile file;
  bool seen[3] = {false, false, false};  // $MeshFormat, $Nodes, $Elements
  while (!scanner.atEnd()) {
    const Token header = scanner.next("a section header");
    if (header.text.size() < 2 || header.text[0] != '$')
      scanner.fail(header.line, "expected a section header such as $Nodes, got '" +
                                    std::string(header.text) + "'");
    const std::string name(header.text.substr(1));
    if (!seen[0] && name != "MeshFormat")
      scanner.fail(header.line, "expected $MeshFormat first (is this a Gmsh MSH file?), got '" +
                                    std::string(header.text) + "'");
    scanner.section = "$" + name;
    auto once = [&](int which) {
      if (seen[which]) scanner.fail(header.line, "a second " + scanner.section + " section");
      seen[which] = true;
    };
    if (name == "MeshFormat") {
      once(0);
      readMeshFormat(scanner);
    } else if (name == "PhysicalNames") {
      readPhysicalNames(scanner, file);
    } else if (name == "Entities") {
      readEntities(scanner, file);
    } else if (name == "PartitionedEntities") {
      scanner.fail(header.line, "partitioned meshes are not supported; save the mesh unpartitioned");
    } else if (name == "Nodes") {
      once(1);
      readNodes(scanner, file);
    } else if (name == "Elements") {
      if (!seen[1]) scanner.fail(header.line, "$Elements before $Nodes");
      once(2);
      readElements(scanner, file);
    } else {
      skipSection(scanner, "$End" + name);
      continue;
    }
    scanner.expect("$End" + name);
  }
  if (!seen[0]) scanner.fail(0, "empty file: no $MeshFormat section");
  if (!seen[2])
    scanner.fail(scanner.lastTokenLine(), std::string("the file ends without a ") +
                                              (seen[1] ? "$Elements" : "$Nodes") + " section");
  return buildShellMesh(file, scanner);
}

ShellMesh readGmsh(const std::string& path) {
  std::ifstream stream(path, std::ios::binary);
  if (!stream)
    throw std::runtime_error(path + ":0: cannot open the file (" + std::strerror(errno) + ")");
  std::ostringstream text;
  text << stream.rdbuf();
  if (stream.bad()) throw std::runtime_error(path + ":0: cannot read the file");
  return parseGmsh(text.str(), path);
}

}  // namespace perishell::mesh
