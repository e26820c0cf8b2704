// Case decks: Teuchos' YAML parser turns the text into a ParameterList; the schema below
// (documented key by key in docs/deck.md) checks every key and fills the plain Deck struct.
#include <perishell/io/deck.hpp>

#include <Teuchos_ParameterList.hpp>
#include <Teuchos_TwoDArray.hpp>
#include <Teuchos_YamlParser_decl.hpp>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <limits>
#include <regex>
#include <sstream>
#include <tuple>
#include <utility>

namespace perishell {

namespace {

std::string composeMessage(const std::string& sourceName, const std::string& keyPath,
                           const std::string& reason) {
  return sourceName + ": " + (keyPath.empty() ? "" : keyPath + ": ") + reason;
}

}  // namespace

DeckError::DeckError(const std::string& sourceName, const std::string& keyPath,
                     const std::string& reason, int line)
    : std::runtime_error(composeMessage(sourceName, keyPath, reason)),
      sourceName_(sourceName),
      keyPath_(keyPath),
      reason_(reason),
      line_(line) {}

namespace deck {

double evaluateCurve(const Curve& curve, double time) {
  switch (curve.type) {
    case CurveType::Ramp:
      return std::clamp(time / curve.endTime, 0.0, 1.0);
    case CurveType::Step:
      return time < curve.stepTime ? 0.0 : 1.0;
    case CurveType::Table: {
      if (time <= curve.times.front()) return curve.values.front();
      if (time >= curve.times.back()) return curve.values.back();
      const auto upper = std::upper_bound(curve.times.begin(), curve.times.end(), time);
      const auto i = std::size_t(upper - curve.times.begin());
      const double weight = (time - curve.times[i - 1]) / (curve.times[i] - curve.times[i - 1]);
      return curve.values[i - 1] + weight * (curve.values[i] - curve.values[i - 1]);
    }
  }
  return 0.0;
}

}  // namespace deck

const deck::Curve* Deck::findCurve(const std::string& name) const {
  for (const auto& curve : curves)
    if (curve.name == name) return &curve;
  return nullptr;
}

namespace {

using Teuchos::ParameterEntry;
using Teuchos::ParameterList;
using deck::Vector3;

constexpr const char* rootKey = "perishell";

std::string formatNumber(double value) {
  std::ostringstream out;
  out << std::setprecision(6) << value;
  return out.str();
}

std::string joinWords(const std::vector<std::string>& words) {
  std::string joined;
  for (const auto& word : words) joined += (joined.empty() ? "" : ", ") + word;
  return joined;
}

std::string joinPath(const std::string& parent, const std::string& key) {
  return parent.empty() ? key : parent + "." + key;
}

std::string lowerCase(std::string text) {
  for (auto& c : text) c = char(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

template <class T>
bool holds(const ParameterEntry& entry) {
  return !entry.isList() && entry.getAny(false).type() == typeid(T);
}

template <class T>
const T& valueOf(const ParameterEntry& entry) {
  return Teuchos::any_cast<T>(entry.getAny(false));
}

// Teuchos stores what its own number syntax cannot hold (nan, .inf, 1e400) as a string.
bool spellsNonFiniteNumber(const std::string& text) {
  std::string word = lowerCase(text);
  if (!word.empty() && (word[0] == '+' || word[0] == '-')) word.erase(0, 1);
  if (word == "nan" || word == ".nan" || word == "inf" || word == ".inf" || word == "infinity")
    return true;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  return !text.empty() && end == text.c_str() + text.size() && !std::isfinite(value);
}

// What a value is, for "expected X, got Y" messages.
std::string describe(const ParameterEntry& entry) {
  if (entry.isList())
    return valueOf<ParameterList>(entry).numParams() == 0 ? "an empty value" : "a map";
  if (holds<std::string>(entry)) return "the string '" + valueOf<std::string>(entry) + "'";
  if (holds<bool>(entry)) return valueOf<bool>(entry) ? "true" : "false";
  if (holds<int>(entry)) return "the number " + std::to_string(valueOf<int>(entry));
  if (holds<long long>(entry)) return "the number " + std::to_string(valueOf<long long>(entry));
  if (holds<double>(entry)) return "the number " + formatNumber(valueOf<double>(entry));
  if (entry.isArray()) return "a list";
  if (entry.isTwoDArray()) return "a nested list";
  return "a value of another type";
}

// One map of the deck, with its key path for messages.
class Section {
 public:
  Section(const ParameterList& list, std::string path, const std::string& source)
      : list_(&list), path_(std::move(path)), source_(&source) {}

  std::string pathOf(const std::string& key) const { return joinPath(path_, key); }

  [[noreturn]] void fail(const std::string& key, const std::string& reason) const {
    throw DeckError(*source_, key.empty() ? path_ : pathOf(key), reason);
  }

  // Unknown keys are errors everywhere, so that a typo never silently falls back to a default.
  void allowOnly(const std::vector<std::string>& allowed, const std::string& context = "") const {
    for (auto it = list_->begin(); it != list_->end(); ++it) {
      const std::string& key = list_->name(it);
      if (std::find(allowed.begin(), allowed.end(), key) == allowed.end())
        fail(key, (context.empty() ? "unknown key" : "key not allowed " + context) +
                      "; allowed keys here: " + joinWords(allowed));
    }
  }

  bool has(const std::string& key) const { return list_->isParameter(key); }

  std::vector<std::string> keys() const {
    std::vector<std::string> names;
    for (auto it = list_->begin(); it != list_->end(); ++it) names.push_back(list_->name(it));
    return names;
  }

  const ParameterEntry& entry(const std::string& key) const {
    if (!has(key)) fail(key, "missing required key");
    return list_->getEntry(key);
  }

  double number(const std::string& key) const { return toNumber(entry(key), pathOf(key)); }
  double number(const std::string& key, double fallback) const {
    return has(key) ? number(key) : fallback;
  }
  std::optional<double> optionalNumber(const std::string& key) const {
    return has(key) ? std::optional<double>(number(key)) : std::nullopt;
  }

  // Counts; an integral double (5e4) is accepted.
  long long integer(const std::string& key) const {
    const ParameterEntry& value = entry(key);
    if (holds<int>(value)) return valueOf<int>(value);
    if (holds<long long>(value)) return valueOf<long long>(value);
    if (holds<double>(value)) {
      const double real = valueOf<double>(value);
      if (std::isfinite(real) && real == std::floor(real) && std::fabs(real) < 9.0e15)
        return static_cast<long long>(real);
    }
    fail(key, "expected a whole number, got " + describe(value));
  }
  long long integer(const std::string& key, long long fallback) const {
    return has(key) ? integer(key) : fallback;
  }

  std::string text(const std::string& key) const {
    const ParameterEntry& value = entry(key);
    if (!holds<std::string>(value)) fail(key, "expected a string, got " + describe(value));
    const auto& result = valueOf<std::string>(value);
    if (result.empty()) fail(key, "must not be empty");
    return result;
  }
  std::string text(const std::string& key, const std::string& fallback) const {
    return has(key) ? text(key) : fallback;
  }

  bool flag(const std::string& key, bool fallback) const {
    if (!has(key)) return fallback;
    const ParameterEntry& value = entry(key);
    if (!holds<bool>(value)) fail(key, "expected true or false, got " + describe(value));
    return valueOf<bool>(value);
  }

  std::vector<double> numbers(const std::string& key) const {
    return toNumbers(entry(key), pathOf(key));
  }

  Vector3 vector3(const std::string& key) const { return toVector3(entry(key), pathOf(key)); }

  // A list of words; a single word is a list of one.
  std::vector<std::string> words(const std::string& key) const {
    const ParameterEntry& value = entry(key);
    if (holds<std::string>(value)) return {valueOf<std::string>(value)};
    if (holds<Teuchos::Array<std::string>>(value)) {
      const auto& array = valueOf<Teuchos::Array<std::string>>(value);
      return std::vector<std::string>(array.begin(), array.end());
    }
    fail(key, "expected a list of names, got " + describe(value));
  }

  template <class Enum>
  Enum choice(const std::string& key, const std::vector<std::pair<std::string, Enum>>& options) const {
    return choose(text(key), key, options);
  }
  template <class Enum>
  Enum choice(const std::string& key, const std::vector<std::pair<std::string, Enum>>& options,
              Enum fallback) const {
    return has(key) ? choice(key, options) : fallback;
  }
  template <class Enum>
  Enum choose(const std::string& word, const std::string& key,
              const std::vector<std::pair<std::string, Enum>>& options) const {
    std::vector<std::string> names;
    for (const auto& [name, value] : options) {
      if (name == word) return value;
      names.push_back(name);
    }
    fail(key, "'" + word + "' is not one of " + joinWords(names));
  }

  Section sublist(const std::string& key) const {
    const ParameterEntry& value = entry(key);
    if (!value.isList()) fail(key, "expected a map (indented keys below it), got " + describe(value));
    return Section(valueOf<ParameterList>(value), pathOf(key), *source_);
  }
  // An optional map; absent reads as empty.
  Section sublistOrEmpty(const std::string& key) const {
    static const ParameterList empty;
    return has(key) ? sublist(key) : Section(empty, pathOf(key), *source_);
  }
  // Repeated items are named maps (Teuchos holds no lists of maps): every key here is one item.
  std::vector<std::pair<std::string, Section>> namedItems() const {
    std::vector<std::pair<std::string, Section>> items;
    for (const auto& key : keys()) items.emplace_back(key, sublist(key));
    return items;
  }

  double toNumber(const ParameterEntry& value, const std::string& path) const {
    double result = 0.0;
    if (holds<double>(value))
      result = valueOf<double>(value);
    else if (holds<int>(value))
      result = valueOf<int>(value);
    else if (holds<long long>(value))
      result = double(valueOf<long long>(value));
    else if (holds<std::string>(value) && spellsNonFiniteNumber(valueOf<std::string>(value)))
      throw DeckError(*source_, path, "not a finite number ('" + valueOf<std::string>(value) + "')");
    else
      throw DeckError(*source_, path, "expected a number, got " + describe(value));
    if (!std::isfinite(result))
      throw DeckError(*source_, path, "not a finite number (" + formatNumber(result) + ")");
    return result;
  }

  std::vector<double> toNumbers(const ParameterEntry& value, const std::string& path) const {
    std::vector<double> result;
    if (holds<Teuchos::Array<double>>(value)) {
      for (double x : valueOf<Teuchos::Array<double>>(value)) result.push_back(x);
    } else if (holds<Teuchos::Array<int>>(value)) {
      for (int x : valueOf<Teuchos::Array<int>>(value)) result.push_back(x);
    } else if (holds<Teuchos::Array<long long>>(value)) {
      for (long long x : valueOf<Teuchos::Array<long long>>(value)) result.push_back(double(x));
    } else if (holds<Teuchos::Array<std::string>>(value)) {
      // One non-number turns the whole list into strings: name the culprit.
      const auto& array = valueOf<Teuchos::Array<std::string>>(value);
      for (Teuchos::Ordinal i = 0; i < array.size(); ++i) {
        const std::string itemPath = path + "[" + std::to_string(i) + "]";
        char* end = nullptr;
        const double x = std::strtod(array[i].c_str(), &end);
        if (spellsNonFiniteNumber(array[i]))
          throw DeckError(*source_, itemPath, "not a finite number ('" + array[i] + "')");
        if (array[i].empty() || end != array[i].c_str() + array[i].size())
          throw DeckError(*source_, itemPath, "expected a number, got the string '" + array[i] + "'");
        result.push_back(x);
      }
    } else {
      throw DeckError(*source_, path, "expected a list of numbers like [1, 2.5], got " + describe(value));
    }
    return result;
  }

  Vector3 toVector3(const ParameterEntry& value, const std::string& path) const {
    const auto components = toNumbers(value, path);
    if (components.size() != 3)
      throw DeckError(*source_, path, "expected 3 numbers [x, y, z], got " +
                                          std::to_string(components.size()));
    return {components[0], components[1], components[2]};
  }

 private:
  const ParameterList* list_;
  std::string path_;
  const std::string* source_;
};

double norm(const Vector3& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }

Vector3 cross(const Vector3& a, const Vector3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

void requirePositive(const Section& section, const std::string& key, double value) {
  if (!(value > 0.0)) section.fail(key, "must be positive, got " + formatNumber(value));
}

std::string resolveAgainst(const std::filesystem::path& baseDirectory, const std::string& path) {
  const std::filesystem::path relative(path);
  if (relative.is_absolute() || baseDirectory.empty()) return path;
  return (baseDirectory / relative).lexically_normal().string();
}

// ---------------------------------------------------------------- sections

// An axis-aligned box {min, max} (PD regions, deck node sets).
std::pair<Vector3, Vector3> readBox(const Section& box) {
  box.allowOnly({"min", "max"});
  const Vector3 min = box.vector3("min"), max = box.vector3("max");
  for (int d = 0; d < 3; ++d)
    if (max[d] < min[d])
      box.fail("max", "every component must be >= min's; component " + std::to_string(d) + " is " +
                          formatNumber(max[d]) + " < " + formatNumber(min[d]));
  return {min, max};
}

// A map of named points ({tip: [x, y, z], ...}), at least one (zones.pd-ratio.around, output.probes).
std::vector<deck::NamedPoint> readNamedPoints(const Section& parent, const std::string& key, const char* example) {
  const Section points = parent.sublist(key);
  std::vector<deck::NamedPoint> result;
  for (const auto& name : points.keys()) result.push_back({name, points.vector3(name)});
  if (result.empty()) parent.fail(key, std::string("needs at least one named point, e.g. ") + example);
  return result;
}

deck::Mesh readMesh(const Section& section, const std::filesystem::path& baseDirectory) {
  using deck::MeshGenerator;
  const std::vector<std::string> common{"generator", "spacing", "pre-cracks", "node-sets"};
  const std::vector<std::pair<std::string, std::vector<std::string>>> generatorKeys{
      {"plate", {"length-x", "length-y"}},
      {"cylinder", {"radius", "height"}},
      {"hexagonal-prism", {"side", "length"}},
      {"gmsh", {"file"}}};
  std::vector<std::string> allKeys = common;
  for (const auto& [name, keys] : generatorKeys) allKeys.insert(allKeys.end(), keys.begin(), keys.end());
  section.allowOnly(allKeys);

  deck::Mesh mesh;
  mesh.generator = section.choice<MeshGenerator>(
      "generator", {{"plate", MeshGenerator::Plate},
                    {"cylinder", MeshGenerator::Cylinder},
                    {"hexagonal-prism", MeshGenerator::HexagonalPrism},
                    {"gmsh", MeshGenerator::Gmsh}});
  const std::string generatorName = section.text("generator");
  std::vector<std::string> allowed = common;
  for (const auto& [name, keys] : generatorKeys)
    if (name == generatorName) allowed.insert(allowed.end(), keys.begin(), keys.end());
  section.allowOnly(allowed, "for generator " + generatorName);

  auto positive = [&](const std::string& key) {
    const double value = section.number(key);
    requirePositive(section, key, value);
    return value;
  };
  switch (mesh.generator) {
    case MeshGenerator::Plate:
      mesh.lengthX = positive("length-x");
      mesh.lengthY = positive("length-y");
      break;
    case MeshGenerator::Cylinder:
      mesh.radius = positive("radius");
      mesh.height = positive("height");
      break;
    case MeshGenerator::HexagonalPrism:
      mesh.side = positive("side");
      mesh.length = positive("length");
      break;
    case MeshGenerator::Gmsh:
      mesh.file = resolveAgainst(baseDirectory, section.text("file"));
      break;
  }
  mesh.spacing = section.number("spacing");
  if (!(mesh.spacing > 0.0))
    section.fail("spacing", "the grid spacing Δx must be positive, got " + formatNumber(mesh.spacing));

  for (const auto& [name, crack] : section.sublistOrEmpty("pre-cracks").namedItems()) {
    crack.allowOnly({"start", "end", "normal"});
    const Vector3 start = crack.vector3("start"), end = crack.vector3("end");
    const Vector3 normal = crack.vector3("normal");
    const Vector3 along{end[0] - start[0], end[1] - start[1], end[2] - start[2]};
    if (!(norm(along) > 0.0)) crack.fail("end", "must differ from start (a crack needs a length)");
    if (!(norm(cross(along, normal)) > 1e-12 * norm(along) * norm(normal)))
      crack.fail("normal", "must be a non-zero vector not parallel to end - start (the shell normal at the crack)");
    deck::PreCrack preCrack{name, {}};
    for (int d = 0; d < 3; ++d) {
      preCrack.segment.start[d] = start[d];
      preCrack.segment.end[d] = end[d];
      preCrack.segment.normal[d] = normal[d] / norm(normal);
    }
    mesh.preCracks.push_back(preCrack);
  }

  for (const auto& [name, nodeSet] : section.sublistOrEmpty("node-sets").namedItems()) {
    nodeSet.allowOnly({"box"});
    const auto [min, max] = readBox(nodeSet.sublist("box"));
    mesh.nodeSets.push_back({name, min, max});
  }
  return mesh;
}

deck::Material readMaterial(const Section& section) {
  section.allowOnly({"young-modulus", "poisson-ratio", "density", "thickness", "fracture-energy"});
  deck::Material material;
  material.youngModulus = section.number("young-modulus");
  material.poissonRatio = section.number("poisson-ratio");
  material.density = section.number("density");
  material.thickness = section.number("thickness");
  material.fractureEnergy = section.optionalNumber("fracture-energy");
  requirePositive(section, "young-modulus", material.youngModulus);
  // Strain energy stays positive definite only for -1 < ν < 1/2.
  if (!(material.poissonRatio > -1.0 && material.poissonRatio < 0.5))
    section.fail("poisson-ratio",
                 "must lie in (-1, 0.5), got " + formatNumber(material.poissonRatio));
  requirePositive(section, "density", material.density);
  requirePositive(section, "thickness", material.thickness);
  if (material.fractureEnergy && *material.fractureEnergy < 0.0)
    section.fail("fracture-energy",
                 "must be >= 0 (G_c [J/m^2]), got " + formatNumber(*material.fractureEnergy));
  return material;
}

deck::Peridynamics readPeridynamics(const Section& section) {
  section.allowOnly({"horizon-factor", "force-kernel", "support-layer"});
  deck::Peridynamics pd;
  pd.horizonFactor = section.number("horizon-factor", pd.horizonFactor);
  if (pd.horizonFactor < 1.0)
    section.fail("horizon-factor",
                 "must be >= 1 so that the horizon reaches the nearest neighbours "
                 "(δ = m Δx >= Δx), got " + formatNumber(pd.horizonFactor));
  pd.forceKernel = section.choice<deck::ForceKernel>(
      "force-kernel",
      {{"bond-scatter", deck::ForceKernel::BondScatter}, {"node-gather", deck::ForceKernel::NodeGather}},
      pd.forceKernel);
  pd.supportLayer = section.flag("support-layer", pd.supportLayer);
  return pd;
}

deck::PdRegion readPdRegion(const std::string& name, const Section& region) {
  const std::vector<std::string> shapes{"box", "cylinder", "element-set"};
  region.allowOnly(shapes);
  const auto present = region.keys();
  if (present.size() != 1)
    region.fail("", "needs exactly one of box, cylinder, element-set; got " +
                        (present.empty() ? std::string("none") : joinWords(present)));
  deck::PdRegion result;
  result.name = name;
  const Section shape = region.sublist(present.front());
  if (present.front() == "box") {
    result.shape = deck::RegionShape::Box;
    std::tie(result.boxMin, result.boxMax) = readBox(shape);
  } else if (present.front() == "cylinder") {
    shape.allowOnly({"center", "axis", "radius", "half-length"});
    result.shape = deck::RegionShape::Cylinder;
    result.center = shape.vector3("center");
    const Vector3 axis = shape.vector3("axis");
    if (!(norm(axis) > 0.0)) shape.fail("axis", "must be a non-zero vector");
    for (int d = 0; d < 3; ++d) result.axis[d] = axis[d] / norm(axis);
    result.radius = shape.number("radius");
    requirePositive(shape, "radius", result.radius);
    result.halfLength = shape.number("half-length");
    requirePositive(shape, "half-length", result.halfLength);
  } else {
    shape.allowOnly({"name"});
    result.shape = deck::RegionShape::ElementSet;
    result.elementSet = shape.text("name");
  }
  return result;
}

// zones.transition (model.md §4: L_c >= 2 delta). horizon: delta of the deck.
deck::Transition readTransition(const Section& section, const deck::Zones& zones, double horizon) {
  deck::Transition transition;
  transition.width = 2.0 * horizon;
  if (!section.has("transition")) return transition;
  // An explicit transition where it cannot act is a deck mistake, not a no-op to ignore.
  if (!zones.hasPd())
    section.fail("transition", "needs a PD zone to blend into the CCM (zones.default is ccm and there are no "
                               "pd-regions and no pd-ratio above 0)");
  if (zones.defaultKind == deck::ZoneKind::Pd)
    section.fail("transition", "needs default: ccm (with default: pd every element is PD and there is no CCM "
                               "to blend into)");
  const Section block = section.sublist("transition");
  block.allowOnly({"width", "profile"});
  transition.width = block.number("width", transition.width);
  // Relative slack: 2 delta written out in the deck must pass despite round-off.
  if (!(transition.width >= 2.0 * horizon * (1.0 - 1e-12)))
    block.fail("width", "must be >= 2 delta = " + formatNumber(2.0 * horizon) +
                            " m (model.md §4: a transition narrower than two horizons leaves large ghost "
                            "forces), got " + formatNumber(transition.width));
  transition.profile = block.choice<deck::TransitionProfile>(
      "profile", {{"cubic", deck::TransitionProfile::Cubic}, {"linear", deck::TransitionProfile::Linear}},
      transition.profile);
  return transition;
}

deck::Zones readZones(const Section& section, double horizon) {
  section.allowOnly({"default", "pd-regions", "pd-ratio", "transition", "adaptive"});
  deck::Zones zones;
  zones.defaultKind = section.choice<deck::ZoneKind>(
      "default", {{"pd", deck::ZoneKind::Pd}, {"ccm", deck::ZoneKind::Ccm}}, zones.defaultKind);
  if (section.has("pd-regions") && section.has("pd-ratio"))
    section.fail("pd-ratio", "give either pd-regions or pd-ratio, not both");
  if (zones.defaultKind == deck::ZoneKind::Pd)
    for (const char* key : {"pd-regions", "pd-ratio"})
      if (section.has(key))
        section.fail(key, "needs default: ccm (with default: pd every element is already PD)");
  for (const auto& [name, region] : section.sublistOrEmpty("pd-regions").namedItems())
    zones.pdRegions.push_back(readPdRegion(name, region));
  if (section.has("pd-ratio")) {
    const Section ratio = section.sublist("pd-ratio");
    ratio.allowOnly({"target", "around"});
    deck::PdRatio pdRatio;
    pdRatio.target = ratio.number("target");
    if (!(pdRatio.target >= 0.0 && pdRatio.target <= 1.0))
      ratio.fail("target", "must lie in [0, 1] (the fraction of elements flagged PD), got " +
                               formatNumber(pdRatio.target));
    pdRatio.around = readNamedPoints(ratio, "around", "{tip: [0.1, 0, 0]}");
    zones.pdRatio = pdRatio;
  }
  if (section.has("adaptive")) {
    if (zones.defaultKind == deck::ZoneKind::Pd)
      section.fail("adaptive", "needs default: ccm (with default: pd every element is already PD)");
    const Section block = section.sublist("adaptive");
    block.allowOnly({"strain-fraction", "check-every", "margin"});
    deck::AdaptiveZone adaptive;
    adaptive.margin = block.number("margin", 2.0 * horizon);
    if (!(adaptive.margin >= 0.0))
      block.fail("margin", "must be >= 0 (the distance [m] around an element that turns PD within which the CCM "
                           "elements turn PD with it), got " + formatNumber(adaptive.margin));
    adaptive.strainFraction = block.number("strain-fraction", adaptive.strainFraction);
    if (!(adaptive.strainFraction > 0.0 && adaptive.strainFraction <= 1.0))
      block.fail("strain-fraction", "must lie in (0, 1] (the share of the bonds' critical stretch s_c at which a "
                                    "CCM element turns PD), got " + formatNumber(adaptive.strainFraction));
    adaptive.checkEvery = block.integer("check-every", adaptive.checkEvery);
    if (adaptive.checkEvery < 1)
      block.fail("check-every", "must be >= 1 (steps between checks), got " + std::to_string(adaptive.checkEvery));
    zones.adaptive = adaptive;
  }
  zones.transition = readTransition(section, zones, horizon);
  return zones;
}

const std::vector<std::pair<std::string, deck::Dof>> dofNames{
    {"ux", deck::Dof::Ux}, {"uy", deck::Dof::Uy}, {"uz", deck::Dof::Uz},
    {"rx", deck::Dof::Rx}, {"ry", deck::Dof::Ry}, {"rz", deck::Dof::Rz}};

template <class Enum>
std::vector<Enum> readDistinct(const Section& section, const std::string& key,
                               const std::vector<std::pair<std::string, Enum>>& options) {
  std::vector<Enum> result;
  for (const auto& word : section.words(key)) {
    const Enum value = section.choose(word, key, options);
    if (std::find(result.begin(), result.end(), value) != result.end())
      section.fail(key, "'" + word + "' is listed twice");
    result.push_back(value);
  }
  return result;
}

std::vector<deck::Support> readSupports(const Section& section) {
  std::vector<deck::Support> supports;
  for (const auto& [name, item] : section.namedItems()) {
    item.allowOnly({"set", "dofs", "value", "curve"});
    deck::Support support;
    support.name = name;
    support.set = item.text("set");
    support.dofs = readDistinct(item, "dofs", dofNames);
    support.value = item.number("value", 0.0);
    support.curve = item.text("curve", "");
    supports.push_back(support);
  }
  return supports;
}

std::vector<deck::Load> readLoads(const Section& section) {
  using deck::LoadType;
  std::vector<deck::Load> loads;
  for (const auto& [name, item] : section.namedItems()) {
    item.allowOnly({"type", "set", "element-set", "vector", "moment", "value", "follower", "curve"});
    deck::Load load;
    load.name = name;
    load.type = item.choice<LoadType>("type", {{"point-force", LoadType::PointForce},
                                                {"edge-traction", LoadType::EdgeTraction},
                                                {"pressure", LoadType::Pressure}});
    const std::string typeName = item.text("type");
    switch (load.type) {
      case LoadType::PointForce:
        item.allowOnly({"type", "set", "vector", "moment", "curve"}, "for type point-force");
        load.set = item.text("set");
        if (!item.has("vector") && !item.has("moment"))
          item.fail("", "needs a vector (force [N]), a moment (moment [N m]) or both");
        if (item.has("vector")) load.vector = item.vector3("vector");
        if (item.has("moment")) load.moment = item.vector3("moment");
        break;
      case LoadType::EdgeTraction:
        item.allowOnly({"type", "set", "vector", "value", "curve"}, "for type edge-traction");
        load.set = item.text("set");
        if (item.has("vector") == item.has("value"))
          item.fail("", "needs exactly one of vector (traction [Pa], global direction) or value "
                        "(normal traction [Pa], positive pulls outward)");
        if (item.has("vector")) load.vector = item.vector3("vector");
        if (item.has("value")) load.value = item.number("value");
        break;
      case LoadType::Pressure:
        item.allowOnly({"type", "element-set", "vector", "value", "follower", "curve"}, "for type pressure");
        load.set = item.text("element-set", "");
        if (item.has("vector") == item.has("value"))
          item.fail("", "needs exactly one of value (pressure [Pa] along the element normal) or vector "
                        "(traction [Pa] in a fixed global direction, e.g. self-weight)");
        if (item.has("vector")) load.vector = item.vector3("vector");
        if (item.has("value")) load.value = item.number("value");
        load.follower = item.flag("follower", false);
        if (load.follower && load.vector)
          item.fail("follower", "applies to value only: a vector traction keeps its global direction");
        break;
    }
    load.curve = item.text("curve", "");
    loads.push_back(load);
  }
  return loads;
}

std::vector<deck::Curve> readCurves(const Section& section) {
  using deck::CurveType;
  std::vector<deck::Curve> curves;
  for (const auto& [name, item] : section.namedItems()) {
    item.allowOnly({"type", "end-time", "time", "value"});
    deck::Curve curve;
    curve.name = name;
    curve.type = item.choice<CurveType>(
        "type", {{"ramp", CurveType::Ramp}, {"step", CurveType::Step}, {"table", CurveType::Table}});
    switch (curve.type) {
      case CurveType::Ramp:
        item.allowOnly({"type", "end-time"}, "for type ramp");
        curve.endTime = item.number("end-time");
        requirePositive(item, "end-time", curve.endTime);
        break;
      case CurveType::Step:
        item.allowOnly({"type", "time"}, "for type step");
        curve.stepTime = item.number("time", 0.0);
        if (curve.stepTime < 0.0)
          item.fail("time", "must be >= 0, got " + formatNumber(curve.stepTime));
        break;
      case CurveType::Table:
        item.allowOnly({"type", "time", "value"}, "for type table");
        curve.times = item.numbers("time");
        curve.values = item.numbers("value");
        if (curve.times.size() < 2) item.fail("time", "a table needs at least 2 points");
        if (curve.values.size() != curve.times.size())
          item.fail("value", "has " + std::to_string(curve.values.size()) + " entries but time has " +
                                 std::to_string(curve.times.size()));
        for (std::size_t i = 1; i < curve.times.size(); ++i)
          if (!(curve.times[i] > curve.times[i - 1]))
            item.fail("time", "must be strictly increasing: time[" + std::to_string(i) + "] = " +
                                  formatNumber(curve.times[i]) + " is not greater than time[" +
                                  std::to_string(i - 1) + "] = " + formatNumber(curve.times[i - 1]));
        break;
    }
    curves.push_back(curve);
  }
  return curves;
}

deck::Solver readSolver(const Section& section) {
  using deck::SolverType;
  const std::vector<std::string> explicitKeys{"type",    "end-time",      "steps",    "dt", "safety-factor",
                                              "damping", "shell-element", "hourglass"};
  const std::vector<std::string> implicitKeys{"type", "increments", "max-iterations", "tolerance",
                                              "preconditioner", "max-cuts", "tangent", "amg-reuse",
                                              "amg-drop-tolerance", "amg-coarse-nodes", "amg-region-scaling",
                                              "coarse-space", "overlap",
                                              "line-search", "control", "max-increments", "newton", "factorization"};
  std::vector<std::string> allKeys = explicitKeys;
  allKeys.insert(allKeys.end(), implicitKeys.begin() + 1, implicitKeys.end());
  section.allowOnly(allKeys);

  deck::Solver solver;
  solver.type = section.choice<SolverType>(
      "type", {{"explicit", SolverType::Explicit}, {"implicit", SolverType::Implicit}});
  if (solver.type == SolverType::Explicit) {
    section.allowOnly(explicitKeys, "for solver type explicit");
    auto& settings = solver.explicitSettings;
    if (section.has("end-time") == section.has("steps"))
      section.fail("", "an explicit run needs exactly one of end-time [s] or steps");
    if (section.has("end-time")) {
      settings.endTime = section.number("end-time");
      requirePositive(section, "end-time", *settings.endTime);
    } else {
      settings.steps = section.integer("steps");
      if (*settings.steps < 1) section.fail("steps", "must be >= 1, got " + std::to_string(*settings.steps));
    }
    settings.timeStep = section.optionalNumber("dt");
    if (settings.timeStep) requirePositive(section, "dt", *settings.timeStep);
    settings.safetyFactor = section.number("safety-factor", settings.safetyFactor);
    if (!(settings.safetyFactor > 0.0 && settings.safetyFactor <= 1.0))
      section.fail("safety-factor", "must lie in (0, 1] (a fraction of the stable time step), got " +
                                        formatNumber(settings.safetyFactor));
    settings.damping = section.number("damping", settings.damping);
    if (settings.damping < 0.0)
      section.fail("damping", "must be >= 0 [1/s], got " + formatNumber(settings.damping));
    using ShellElement = deck::ExplicitSettings::ShellElement;
    settings.shellElement = section.choice<ShellElement>(
        "shell-element", {{"one-point", ShellElement::OnePoint}, {"mitc4", ShellElement::Mitc4}}, settings.shellElement);
    settings.hourglassCoefficient = section.number("hourglass", settings.hourglassCoefficient);
    if (!(settings.hourglassCoefficient > 0.0 && settings.hourglassCoefficient <= 1.0))
      section.fail("hourglass", "must lie in (0, 1] (the hourglass stiffness coefficient), got " +
                                    formatNumber(settings.hourglassCoefficient));
  } else {
    section.allowOnly(implicitKeys, "for solver type implicit");
    auto& settings = solver.implicitSettings;
    auto count = [&](const std::string& key, int fallback) {
      const long long value = section.integer(key, fallback);
      if (value < 1 || value > std::numeric_limits<int>::max())
        section.fail(key, "must be a whole number >= 1, got " + std::to_string(value));
      return int(value);
    };
    settings.increments = count("increments", settings.increments);
    settings.maxIterations = count("max-iterations", settings.maxIterations);
    settings.tolerance = section.number("tolerance", settings.tolerance);
    if (!(settings.tolerance > 0.0 && settings.tolerance < 1.0))
      section.fail("tolerance", "must lie in (0, 1) (relative residual norm), got " +
                                    formatNumber(settings.tolerance));
    settings.preconditioner = section.choice<deck::Preconditioner>(
        "preconditioner",
        {{"jacobi", deck::Preconditioner::Jacobi},
         {"block-jacobi", deck::Preconditioner::BlockJacobi},
         {"amg", deck::Preconditioner::Amg},
         {"cholesky", deck::Preconditioner::Cholesky},
         {"direct", deck::Preconditioner::Direct},
         {"auto", deck::Preconditioner::Auto}},
        settings.preconditioner);
    settings.factorization = section.choice<deck::Factorization>(
        "factorization",
        {{"auto", deck::Factorization::Auto}, {"host", deck::Factorization::Host}, {"device", deck::Factorization::Device}},
        settings.factorization);
    settings.tangent = section.choice<deck::Tangent>(
        "tangent",
        {{"auto", deck::Tangent::Auto}, {"symmetric", deck::Tangent::Symmetric}, {"exact", deck::Tangent::Exact}},
        settings.tangent);
    if (section.has("max-cuts")) {
      const double cuts = section.number("max-cuts");
      if (!(cuts >= 0 && cuts <= 30 && cuts == std::floor(cuts)))
        section.fail("max-cuts", "must be a whole number in [0, 30], got " + formatNumber(cuts));
      settings.maxCuts = int(cuts);
    }
    settings.lineSearch = section.flag("line-search", settings.lineSearch);
    using Newton = deck::ImplicitSettings::Newton;
    settings.newton = section.choice<Newton>("newton", {{"mixed", Newton::Mixed}, {"displacement", Newton::Displacement}},
                                             settings.newton);
    using Control = deck::ImplicitSettings::Control;
    settings.control = section.choice<Control>("control", {{"load", Control::Load}, {"arc-length", Control::ArcLength}},
                                               settings.control);
    settings.maxIncrements = count("max-increments", 10 * settings.increments);
    if (section.has("max-increments") && settings.control != Control::ArcLength)
      section.fail("max-increments", "applies to control: arc-length only (under load control the run takes "
                                     "exactly `increments` increments)");
    settings.amgReuse = section.number("amg-reuse", settings.amgReuse);
    if (!(settings.amgReuse == 0.0 || (settings.amgReuse >= 1.0 && settings.amgReuse <= 100.0)))
      section.fail("amg-reuse", "must be 0 (rebuild the multigrid hierarchy at every Newton iteration) or a growth "
                                "factor in [1, 100], got " + formatNumber(settings.amgReuse));
    settings.amgDropTolerance = section.number("amg-drop-tolerance", settings.amgDropTolerance);
    if (!(settings.amgDropTolerance >= 0.0 && settings.amgDropTolerance < 1.0))
      section.fail("amg-drop-tolerance", "must be in [0, 1) (0 aggregates over every coupling), got " +
                                             formatNumber(settings.amgDropTolerance));
    const long long coarseNodes = section.integer("amg-coarse-nodes", settings.amgCoarseNodes);
    if (coarseNodes < 1 || coarseNodes > 2000)
      section.fail("amg-coarse-nodes", "must be a whole number in [1, 2000] (nodes of the densely inverted coarsest "
                                       "level), got " + std::to_string(coarseNodes));
    settings.amgCoarseNodes = static_cast<int>(coarseNodes);
    settings.amgRegionScaling = section.flag("amg-region-scaling", settings.amgRegionScaling);
    settings.coarseSpace = section.flag("coarse-space", settings.coarseSpace);
    settings.overlap = section.flag("overlap", settings.overlap);
  }
  return solver;
}

// checkpoint-every: a number of steps (increments), "<minutes> min" of wall time, or a list of both.
void readCheckpointEvery(const Section& section, deck::Output& output) {
  const std::string usage = "expected a number of steps (increments), a wall time such as '30 min', or a list of "
                            "both ([5000, 30 min])";
  std::vector<std::string> items;
  const ParameterEntry& value = section.entry("checkpoint-every");
  if (holds<Teuchos::Array<std::string>>(value)) {
    const auto& array = valueOf<Teuchos::Array<std::string>>(value);
    items.assign(array.begin(), array.end());
  } else if (holds<std::string>(value)) {
    items.push_back(valueOf<std::string>(value));
  } else if (holds<Teuchos::Array<int>>(value) || holds<Teuchos::Array<double>>(value)) {
    section.fail("checkpoint-every", usage + ", got a list of numbers");
  } else {
    output.checkpointEvery = section.integer("checkpoint-every");
    if (output.checkpointEvery < 1)
      section.fail("checkpoint-every", "must be >= 1 step, got " + std::to_string(output.checkpointEvery));
    return;
  }
  if (items.empty() || items.size() > 2) section.fail("checkpoint-every", usage);
  for (const auto& item : items) {
    std::istringstream words(item);
    double number = 0.0;
    std::string unit, rest;
    if (!(words >> number) || (words >> unit && words >> rest)) section.fail("checkpoint-every", usage + ", got '" + item + "'");
    if (unit.empty()) {
      if (!(number >= 1.0 && number == std::floor(number) && number < 9.0e15))
        section.fail("checkpoint-every", "a number of steps must be a whole number >= 1, got '" + item + "'");
      output.checkpointEvery = static_cast<long long>(number);
    } else if (unit == "min") {
      if (!(number > 0.0 && std::isfinite(number)))
        section.fail("checkpoint-every", "a wall time must be > 0 minutes, got '" + item + "'");
      output.checkpointMinutes = number;
    } else {
      section.fail("checkpoint-every", "unknown unit '" + unit + "' (only 'min'); " + usage);
    }
  }
}

deck::Output readOutput(const Section& section, const std::filesystem::path& baseDirectory) {
  section.allowOnly({"directory", "every", "history-every", "fields", "history", "probes", "checkpoint-every"});
  deck::Output output;
  output.directory = resolveAgainst(baseDirectory, section.text("directory", output.directory));
  output.every = section.integer("every", output.every);
  if (output.every < 0)
    section.fail("every", "must be >= 0 (0 writes the final state only), got " + std::to_string(output.every));
  output.historyEvery = section.integer("history-every", output.every > 0 ? output.every : 100);
  if (output.historyEvery < 1)
    section.fail("history-every", "must be >= 1, got " + std::to_string(output.historyEvery));
  if (section.has("checkpoint-every")) readCheckpointEvery(section, output);
  if (section.has("fields"))
    output.fields = readDistinct<deck::OutputField>(
        section, "fields",
        {{"displacement", deck::OutputField::Displacement}, {"rotation", deck::OutputField::Rotation},
         {"velocity", deck::OutputField::Velocity}, {"damage", deck::OutputField::Damage},
         {"zone", deck::OutputField::Zone}});
  if (section.has("history"))
    output.history = readDistinct<deck::HistoryQuantity>(
        section, "history",
        {{"energy", deck::HistoryQuantity::Energy}, {"reactions", deck::HistoryQuantity::Reactions},
         {"broken-bonds", deck::HistoryQuantity::BrokenBonds},
         {"crack-tip", deck::HistoryQuantity::CrackTip}, {"load-points", deck::HistoryQuantity::LoadPoints}});
  if (section.has("probes")) {
    output.probes = readNamedPoints(section, "probes", "{tip: [0.1, 0, 0]}");
    // The name heads history.csv columns, which hold no commas, quotes or line breaks.
    for (const auto& probe : output.probes)
      if (probe.name.find_first_of(",\"\r\n") != std::string::npos)
        section.fail("probes." + probe.name, "a probe's name heads its history.csv columns (<name>-ux ...) and may not "
                                             "hold commas, quotes or line breaks");
  }
  return output;
}

// Rules that tie sections together.
void checkCrossReferences(Deck& deck, const Section& root) {
  const auto& material = deck.material;
  if (deck.zones.hasPd() && material.poissonRatio > 1.0 / 3.0) {
    const std::string where = deck.zones.defaultKind == deck::ZoneKind::Pd ? "zones.default is pd"
                              : !deck.zones.pdRegions.empty()              ? "zones.pd-regions is set"
                              : deck.zones.pdRatio                         ? "zones.pd-ratio is set"
                                                                           : "zones.adaptive is set";
    root.fail("material.poisson-ratio",
              "microbeam PD needs nu <= 1/3 (model.md §2): c_bz and c_tor turn negative; got " +
                  formatNumber(material.poissonRatio) + " and " + where);
  }
  auto checkCurve = [&](const std::string& path, const std::string& curve) {
    if (curve.empty() || deck.findCurve(curve)) return;
    std::vector<std::string> names;
    for (const auto& defined : deck.curves) names.push_back(defined.name);
    root.fail(path, "unknown curve '" + curve + "'; " +
                        (names.empty() ? std::string("no curves are defined") : "defined curves: " + joinWords(names)));
  };
  for (const auto& support : deck.supports) checkCurve("supports." + support.name + ".curve", support.curve);
  for (const auto& load : deck.loads) checkCurve("loads." + load.name + ".curve", load.curve);

  if (deck.supports.empty()) {
    if (deck.solver.type == deck::SolverType::Implicit)
      root.fail("supports", "an unsupported model is singular: the implicit solver needs at least one support");
    deck.warnings.push_back(
        "supports: none given: the model flies free (rigid-body motion is possible); "
        "allowed for the explicit solver");
  }
  const auto& fields = deck.output.fields;
  if (deck.solver.type == deck::SolverType::Implicit &&
      std::find(fields.begin(), fields.end(), deck::OutputField::Velocity) != fields.end())
    root.fail("output.fields", "velocity exists only for the explicit solver");
  const auto& history = deck.output.history;
  if (std::find(history.begin(), history.end(), deck::HistoryQuantity::LoadPoints) != history.end())
    for (const auto& probe : deck.output.probes)
      for (const auto& load : deck.loads)
        if (load.type == deck::LoadType::PointForce && load.name == probe.name)
          root.fail("output.probes." + probe.name, "the probe's columns " + probe.name + "-ux, -uy, -uz would repeat "
                    "the load-points columns of loads." + load.name + "; rename the probe");
  if (deck.zones.adaptive) {
    if (deck.solver.type != deck::SolverType::Explicit)
      root.fail("zones.adaptive", "the PD zone grows only in explicit runs (solver.type: explicit)");
    if (!material.fractureEnergy)
      root.fail("zones.adaptive", "needs material.fracture-energy: elements turn PD at a share of the bonds' "
                                  "critical stretch, which G_c sets (model.md §3)");
  }
  if (material.fractureEnergy && !deck.zones.hasPd())
    deck.warnings.push_back(
        "material.fracture-energy: the model has no PD zone, and only PD bonds fracture (model.md §3)");
}

// ---------------------------------------------------------------- text level

// Teuchos' YAML reader takes time that grows faster than linearly with the length of a line
// (one line of 300,000 characters: 1.1 s, of 1,000,000: 17 s), with nesting (flow maps 3,000
// deep: 6.5 s) and with the number of entries at depth (46,000 lines 14 levels deep: 1.6 s),
// measured with `perishell check` on 2 CPU threads (docs/reliability.md). One pass over the
// text refuses decks beyond these bounds before parsing; the paper's decks stay far below
// them (lines <= 113 characters, depth <= 5, < 100 entries), and the worst deck within them
// parses in well under a second.
constexpr std::size_t maxLineCharacters = 4096;
constexpr int maxNestingDepth = 12;
constexpr std::size_t maxEntries = 20000;

void checkShapeBeforeParsing(const std::string& text, const std::string& source) {
  std::vector<std::size_t> indents;  // of the enclosing block maps and lists
  std::size_t entries = 0;
  int flowDepth = 0, lineNumber = 0;
  auto refuse = [&](const std::string& reason) {
    throw DeckError(source, "", "line " + std::to_string(lineNumber) + ": " + reason, lineNumber);
  };
  for (std::size_t lineStart = 0; lineStart < text.size();) {
    ++lineNumber;
    const std::size_t newline = text.find('\n', lineStart);
    const std::size_t lineEnd = newline == std::string::npos ? text.size() : newline;
    if (lineEnd - lineStart > maxLineCharacters)
      refuse("the line is " + std::to_string(lineEnd - lineStart) + " characters long, over the limit of " +
             std::to_string(maxLineCharacters) + " characters of a deck line");
    const std::size_t first = text.find_first_not_of(" \t\r", lineStart);
    if (first < lineEnd && text[first] != '#') {
      ++entries;
      if (flowDepth == 0) {  // a line of a multi-line flow list does not open a block level
        const std::size_t indent = first - lineStart;
        while (!indents.empty() && indents.back() >= indent) indents.pop_back();
        indents.push_back(indent);
      }
      int deepestFlow = flowDepth;
      char quote = 0;
      for (std::size_t i = first; i < lineEnd; ++i) {
        const char c = text[i];
        if (quote) {
          if (c == '\\' && quote == '"') ++i;
          else if (c == quote) quote = 0;
        } else if ((c == '"' || c == '\'') && (i == first || std::strchr(" \t[{,:", text[i - 1]))) {
          quote = c;
        } else if (c == '#' && (text[i - 1] == ' ' || text[i - 1] == '\t')) {
          break;
        } else if (c == '[' || c == '{') {
          deepestFlow = std::max(deepestFlow, ++flowDepth);
        } else if (c == ']' || c == '}') {
          flowDepth = std::max(0, flowDepth - 1);
        } else if (flowDepth > 0 && (c == ',' || c == ':')) {
          ++entries;
        }
      }
      if (int(indents.size()) + deepestFlow > maxNestingDepth)
        refuse("maps and lists nest more than " + std::to_string(maxNestingDepth) + " levels deep");
      if (entries > maxEntries)
        refuse("the deck has more than " + std::to_string(maxEntries) +
               " entries (keys, list items and lines); a deck holds settings, and a large mesh goes in its own "
               "file (mesh.file)");
    }
    lineStart = lineEnd + 1;
  }
}

std::string deckTooLarge(std::size_t bytes) {
  return "the deck is " + std::to_string(bytes) + " bytes, over the limit of " + std::to_string(maxDeckBytes) +
         " bytes (1 MiB); a deck holds settings, and a large mesh goes in its own file (mesh.file)";
}

// Teuchos' reader takes one top-level map and asserts on anything else; say so plainly.
void checkSingleRootKey(const std::string& text, const std::string& source) {
  std::istringstream lines(text);
  std::string line;
  int lineNumber = 0;
  bool rootSeen = false;
  while (std::getline(lines, line)) {
    ++lineNumber;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty() || std::isspace(static_cast<unsigned char>(line[0])) || line[0] == '#' ||
        line[0] == '%' || line.rfind("---", 0) == 0 || line.rfind("...", 0) == 0)
      continue;
    const std::string key = line.substr(0, line.find(':'));
    if (rootSeen)
      throw DeckError(source, "",
                      "line " + std::to_string(lineNumber) + ": a second top-level key '" + key +
                          "'; every key goes under the single root key '" + rootKey + ":' (indent it)",
                      lineNumber);
    std::string rest = line.find(':') == std::string::npos ? "" : line.substr(line.find(':') + 1);
    rest = rest.substr(0, rest.find('#'));
    rest.erase(0, rest.find_first_not_of(' '));
    if (key != rootKey || line.find(':') == std::string::npos || !(rest.empty() || rest[0] == '{'))
      throw DeckError(source, "",
                      "line " + std::to_string(lineNumber) + ": a deck is one map under the root key '" +
                          rootKey + ":' (the deck reader reads a single top-level map), found '" + line + "'",
                      lineNumber);
    rootSeen = true;
  }
  if (!rootSeen)
    throw DeckError(source, "", std::string("empty deck: expected the root key '") + rootKey + ":'");
}

// Teuchos' lexer takes ASCII only. Comments may hold anything (units like m², Δx), so their
// non-ASCII bytes become spaces; elsewhere a non-ASCII character is an error with its place.
std::string blankNonAsciiInComments(const std::string& text, const std::string& source) {
  std::string result = text;
  int lineNumber = 1;
  std::size_t lineStart = 0;
  char quote = 0;
  bool comment = false;
  for (std::size_t i = 0; i < result.size(); ++i) {
    const char c = result[i];
    if (c == '\n') {
      ++lineNumber;
      lineStart = i + 1;
      comment = false;
      quote = 0;  // flow scalars spanning lines are not used in decks
      continue;
    }
    if (comment) {
      if (static_cast<unsigned char>(c) >= 0x80) result[i] = ' ';
      continue;
    }
    if (static_cast<unsigned char>(c) >= 0x80) {
      int column = 1;  // in characters: count UTF-8 lead bytes before it
      for (std::size_t j = lineStart; j < i; ++j)
        if ((static_cast<unsigned char>(text[j]) & 0xC0) != 0x80) ++column;
      throw DeckError(source, "",
                      "line " + std::to_string(lineNumber) + ", column " + std::to_string(column) +
                          ": non-ASCII character; the deck reader takes ASCII only outside "
                          "comments (write dx for Δx, m^2 for m²)",
                      lineNumber);
    }
    if (quote) {
      if (c == '\\' && quote == '"') ++i;
      else if (c == quote) quote = 0;
    } else if ((c == '"' || c == '\'') &&
               (i == lineStart || std::strchr(" \t[{,", result[i - 1]) != nullptr)) {
      quote = c;  // a quote opens a scalar only where a scalar can start (not in "Bobaru's")
    } else if (c == '#' && (i == lineStart || result[i - 1] == ' ' || result[i - 1] == '\t')) {
      comment = true;
    }
  }
  return result;
}

// Teuchos' parser messages carry its source location and parser state; keep the location in
// the deck and what was expected.
DeckError translateParserError(const std::string& message, const std::string& text,
                               const std::string& source) {
  int lineNumber = 0;
  std::string where;
  std::smatch match;
  if (std::regex_search(message, match, std::regex(R"(line (\d+)(?: column (\d+))?)"))) {
    lineNumber = std::stoi(match[1]);
    where = " at line " + match[1].str() + (match[2].matched ? ", column " + match[2].str() : "");
  }
  std::vector<std::string> lines;
  {
    std::istringstream stream(message.substr(0, message.find("Lexer text:")));
    for (std::string text; std::getline(stream, text);) lines.push_back(text);
  }
  auto isCaret = [](const std::string& text) {
    return !text.empty() && text.find_first_not_of(" ^") == std::string::npos;
  };
  // lines[0] is "error: <what> at line L column C of <source>" or "error: Parser failure ...".
  std::string detail = lines.empty() ? "" : lines[0];
  if (detail.rfind("error: ", 0) == 0) detail.erase(0, 7);
  detail = std::regex_replace(detail, std::regex(R"(\s*\(?(at )?line \d+.*$)"), "");
  if (detail == "Parser failure") detail.clear();
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const std::string& line = lines[i];
    // Skipped: Teuchos' own source location, the echoed deck line above its caret, the caret.
    const bool echoedLine = i + 1 < lines.size() && isCaret(lines[i + 1]);
    if (line.empty() || isCaret(line) || echoedLine || line.find(".cpp:") != std::string::npos ||
        line.rfind("Throw ", 0) == 0)
      continue;
    detail += (detail.empty() ? "" : line[0] == '(' ? " " : "; ") + line;
  }
  std::smatch duplicate;
  if (std::regex_search(message, duplicate, std::regex(R"re(Parameter "([^"]*)" already exists)re")))
    detail = "duplicate key '" + duplicate[1].str() + "'";
  // The reader's own words for lists it cannot hold, in the deck's terms; any other message
  // that shows its internals (class names, source paths) becomes a plain statement.
  const std::pair<const char*, const char*> listProblems[] = {
      {"bug in YAMLParameterList::Reader",
       "a list may hold numbers or words, or lists of them, but no deeper lists and no maps"},
      {"any_cast", "a list mixes single values and lists; a list holds numbers or words, or lists of them"},
      {"implicitly typed arrays can't be empty", "a list cannot be empty"},
      {"implicitly typed 2D arrays can't have empty rows", "a list of lists cannot have an empty row"},
      {"2D array: sub-arrays are different sizes", "the rows of a list of lists differ in length"},
      {"Can't interpret a map inside a sequence", "a list cannot hold maps; write repeated items as named maps"}};
  for (const auto& [teuchosWords, deckWords] : listProblems)
    if (message.find(teuchosWords) != std::string::npos) detail = deckWords;
  if (std::regex_search(detail, std::regex(R"(Teuchos|::|\.[ch]pp|any_cast|typeid|Throw|bug in)")))
    detail = "the deck reader cannot read this construct";
  if (lineNumber > 0) {
    std::istringstream stream(text);
    std::string offending;
    int current = 0;
    while (current < lineNumber && std::getline(stream, offending)) ++current;
    const auto first = offending.find_first_not_of(' ');
    if (first != std::string::npos && offending.compare(first, 2, "- ") == 0 &&
        offending.find(':') != std::string::npos)
      detail += " (a list of maps: decks hold none, write repeated items as named maps)";
  }
  return DeckError(source, "", "YAML error" + where + (detail.empty() ? "" : ": " + detail), lineNumber);
}

}  // namespace

Deck parseDeck(const std::string& yamlText, const std::string& sourceName) {
  if (yamlText.size() > maxDeckBytes) throw DeckError(sourceName, "", deckTooLarge(yamlText.size()));
  checkShapeBeforeParsing(yamlText, sourceName);
  checkSingleRootKey(yamlText, sourceName);
  // The YAML reader needs a final line break: without one the last value or comment ends in
  // "Got: EOF".
  const std::string asciiText =
      blankNonAsciiInComments(yamlText.empty() || yamlText.back() == '\n' ? yamlText : yamlText + '\n', sourceName);
  Teuchos::RCP<ParameterList> parsed;
  try {
    parsed = Teuchos::YAMLParameterList::parseYamlText(asciiText, sourceName);
  } catch (const std::exception& error) {
    throw translateParserError(error.what(), asciiText, sourceName);
  }
  const Section root(*parsed, "", sourceName);
  root.allowOnly({"version", "title", "mesh", "material", "peridynamics", "zones", "supports",
                  "loads", "curves", "solver", "output"});
  const std::filesystem::path baseDirectory = std::filesystem::path(sourceName).parent_path();

  Deck deck;
  deck.sourceName = sourceName;
  const long long version = root.integer("version");
  if (version != 1)
    root.fail("version", "unsupported deck version " + std::to_string(version) + "; this perishell reads version 1");
  deck.version = int(version);
  deck.title = root.text("title", "");
  deck.mesh = readMesh(root.sublist("mesh"), baseDirectory);
  deck.material = readMaterial(root.sublist("material"));
  deck.peridynamics = readPeridynamics(root.sublistOrEmpty("peridynamics"));
  deck.zones = readZones(root.sublistOrEmpty("zones"), deck.peridynamics.horizonFactor * deck.mesh.spacing);
  deck.supports = readSupports(root.sublistOrEmpty("supports"));
  deck.loads = readLoads(root.sublistOrEmpty("loads"));
  deck.curves = readCurves(root.sublistOrEmpty("curves"));
  deck.solver = readSolver(root.sublist("solver"));
  deck.output = readOutput(root.sublistOrEmpty("output"), baseDirectory);
  checkCrossReferences(deck, root);
  return deck;
}

Deck readDeck(const std::string& path) {
  std::error_code error;
  const auto status = std::filesystem::status(path, error);
  if (!std::filesystem::exists(status))
    throw DeckError(path, "", "cannot read the deck: no such file");
  if (std::filesystem::is_directory(status))
    throw DeckError(path, "", "cannot read the deck: it is a directory");
  std::ifstream file(path, std::ios::binary);
  if (!file) throw DeckError(path, "", std::string("cannot read the deck: ") + std::strerror(errno));
  // At most one byte past the limit is read, whatever the file (a device, a pipe) holds.
  std::string text(maxDeckBytes + 1, '\0');
  file.read(text.data(), std::streamsize(text.size()));
  if (file.bad()) throw DeckError(path, "", "cannot read the deck: read error");
  text.resize(std::size_t(file.gcount()));
  if (text.size() > maxDeckBytes) {
    const auto size = std::filesystem::file_size(path, error);
    throw DeckError(path, "", deckTooLarge(error ? text.size() : std::size_t(size)));
  }
  return parseDeck(text, path);
}

}  // namespace perishell
