#include <perishell/mesh/generators.hpp>
#include <perishell/mesh/free_edges.hpp>
#include <perishell/mesh/gmsh_reader.hpp>
#include <perishell/mesh/node_geometry.hpp>
#include <perishell/model/model.hpp>

#include <algorithm>
#include <array>
#include <map>
#include <cmath>
#include <numeric>
#include <set>
#include <sstream>
#include <string>
#include <utility>

namespace perishell::model {

namespace {

using Vector3 = deck::Vector3;
using mesh::HostQuadMesh;

[[noreturn]] void fail(const Deck& deck, const std::string& keyPath, const std::string& reason) {
  throw DeckError(deck.sourceName, keyPath, reason);
}

mesh::ShellMesh buildMesh(const Deck& deck) {
  const auto& spec = deck.mesh;
  try {
    switch (spec.generator) {
      case deck::MeshGenerator::Plate: return mesh::makePlate(spec.lengthX, spec.lengthY, spec.spacing);
      case deck::MeshGenerator::Cylinder: return mesh::makeCylinder(spec.radius, spec.height, spec.spacing);
      case deck::MeshGenerator::HexagonalPrism:
        return mesh::makeHexagonalPrism(spec.side, spec.length, spec.spacing);
      case deck::MeshGenerator::Gmsh: return mesh::readGmsh(spec.file);
    }
  } catch (const std::exception& error) {
    fail(deck, "mesh", error.what());
  }
  fail(deck, "mesh.generator", "unknown generator");
}

Vector3 nodePosition(const HostQuadMesh& mesh, LocalIndex node) { return mesh::nodePoint(mesh, node); }
using mesh::elementCentroid;

bool inBox(const Vector3& p, const Vector3& min, const Vector3& max) {
  for (int d = 0; d < 3; ++d)
    if (p[d] < min[d] || p[d] > max[d]) return false;
  return true;
}

bool inCylinder(const Vector3& p, const deck::PdRegion& region) {
  Vector3 offset{};
  double along = 0.0;
  for (int d = 0; d < 3; ++d) {
    offset[d] = p[d] - region.center[d];
    along += offset[d] * region.axis[d];
  }
  double radialSquared = 0.0;
  for (int d = 0; d < 3; ++d) {
    const double radial = offset[d] - along * region.axis[d];
    radialSquared += radial * radial;
  }
  return std::abs(along) <= region.halfLength && radialSquared <= region.radius * region.radius;
}

double distanceSquared(const Vector3& a, const Vector3& b) {
  double sum = 0.0;
  for (int d = 0; d < 3; ++d) sum += (a[d] - b[d]) * (a[d] - b[d]);
  return sum;
}

void addDeckNodeSets(const Deck& deck, mesh::ShellMesh& shell) {
  for (const auto& boxSet : deck.mesh.nodeSets) {
    const std::string key = "mesh.node-sets." + boxSet.name;
    if (shell.sets.nodeSets.count(boxSet.name) || shell.sets.edgeSets.count(boxSet.name))
      fail(deck, key, "the mesh already has a set named '" + boxSet.name + "'");
    std::vector<LocalIndex> nodes;
    for (LocalIndex node = 0; node < shell.mesh.numNodes(); ++node)
      if (inBox(nodePosition(shell.mesh, node), boxSet.min, boxSet.max)) nodes.push_back(node);
    if (nodes.empty()) fail(deck, key + ".box", "contains no node of the mesh");
    shell.sets.nodeSets[boxSet.name] = std::move(nodes);
  }
}

// Nodes of a support's or load's set: a node set, or the nodes of an edge set.
std::vector<LocalIndex> nodesOfSet(const Deck& deck, const mesh::MeshSets& sets, const std::string& name,
                                   const std::string& keyPath) {
  try {
    return sets.nodesOfNodeOrEdgeSet(name);
  } catch (const std::invalid_argument& error) {
    fail(deck, keyPath, error.what());
  }
}

void checkSetReferences(const Deck& deck, const mesh::MeshSets& sets, long long& constrainedDofs) {
  std::set<std::pair<LocalIndex, int>> constrained;
  for (const auto& support : deck.supports) {
    const auto nodes = nodesOfSet(deck, sets, support.set, "supports." + support.name + ".set");
    for (const LocalIndex node : nodes)
      for (const auto dof : support.dofs) constrained.insert({node, static_cast<int>(dof)});
  }
  constrainedDofs = static_cast<long long>(constrained.size());
  for (const auto& load : deck.loads) {
    const std::string key = "loads." + load.name + ".set";
    try {
      switch (load.type) {
        case deck::LoadType::PointForce: nodesOfSet(deck, sets, load.set, key); break;
        case deck::LoadType::EdgeTraction: sets.edgeSet(load.set); break;
        case deck::LoadType::Pressure:
          if (!load.set.empty()) sets.elementSet(load.set);
          break;
      }
    } catch (const std::invalid_argument& error) {
      fail(deck, load.type == deck::LoadType::Pressure ? "loads." + load.name + ".element-set" : key,
           error.what());
    }
  }
}

// Closest distance from p to the segment a-b.
double distanceToSegment(const Vector3& p, const double a[3], const double b[3]) {
  double ab[3], ap[3], lengthSquared = 0.0, projection = 0.0;
  for (int d = 0; d < 3; ++d) {
    ab[d] = b[d] - a[d];
    ap[d] = p[d] - a[d];
    lengthSquared += ab[d] * ab[d];
    projection += ab[d] * ap[d];
  }
  const double s = std::clamp(projection / lengthSquared, 0.0, 1.0);
  double sum = 0.0;
  for (int d = 0; d < 3; ++d) sum += (ap[d] - s * ab[d]) * (ap[d] - s * ab[d]);
  return std::sqrt(sum);
}

// PD flags per element from zones (docs/deck.md "zones").
LocalIndex flagPdElements(const Deck& deck, const mesh::ShellMesh& shell,
                          Kokkos::View<std::uint8_t*, Kokkos::HostSpace>& isPd) {
  const auto& zones = deck.zones;
  const HostQuadMesh& mesh = shell.mesh;
  const LocalIndex numElements = mesh.numElements();
  isPd = Kokkos::View<std::uint8_t*, Kokkos::HostSpace>("element is pd", numElements);
  Kokkos::deep_copy(isPd, zones.defaultKind == deck::ZoneKind::Pd ? 1 : 0);

  for (const auto& region : zones.pdRegions) {
    if (region.shape == deck::RegionShape::ElementSet) {
      try {
        for (const LocalIndex element : shell.sets.elementSet(region.elementSet)) isPd(element) = 1;
      } catch (const std::invalid_argument& error) {
        fail(deck, "zones.pd-regions." + region.name + ".element-set.name", error.what());
      }
      continue;
    }
    LocalIndex selected = 0;
    for (LocalIndex element = 0; element < numElements; ++element) {
      const Vector3 centroid = elementCentroid(mesh, element);
      const bool inside = region.shape == deck::RegionShape::Box
                              ? inBox(centroid, region.boxMin, region.boxMax)
                              : inCylinder(centroid, region);
      if (inside) {
        isPd(element) = 1;
        ++selected;
      }
    }
    if (selected == 0)
      fail(deck, "zones.pd-regions." + region.name, "contains no element centroid of the mesh");
  }

  if (zones.pdRatio) {
    // The paper's PD ratio: the round(target N) elements nearest to the given points.
    std::vector<std::pair<double, LocalIndex>> byDistance(numElements);
    for (LocalIndex element = 0; element < numElements; ++element) {
      const Vector3 centroid = elementCentroid(mesh, element);
      double nearest = INFINITY;
      for (const auto& point : zones.pdRatio->around)
        nearest = std::min(nearest, distanceSquared(centroid, point.position));
      byDistance[element] = {nearest, element};
    }
    std::sort(byDistance.begin(), byDistance.end());
    const auto count = static_cast<LocalIndex>(std::llround(zones.pdRatio->target * numElements));
    for (LocalIndex k = 0; k < count; ++k) isPd(byDistance[k].second) = 1;
  }

  if (zones.adaptive) {
    // A pre-crack exists only in bonds (model.md §3): the elements within two horizons of it
    // start PD, and the adaptive zone grows from them. Two, because a PD node within one
    // horizon of the zone's edge still bonds to transition nodes and keeps a CCM share that
    // bridges a crack (docs/coupling.md): the crack line and its tips need pure PD around them.
    const double seedRadius = 2.0 * deck.peridynamics.horizonFactor * deck.mesh.spacing;
    for (const auto& crack : deck.mesh.preCracks)
      for (LocalIndex element = 0; element < numElements; ++element)
        if (distanceToSegment(elementCentroid(mesh, element), crack.segment.start, crack.segment.end) <= seedRadius)
          isPd(element) = 1;
  }

  LocalIndex numPd = 0;
  for (LocalIndex element = 0; element < numElements; ++element) numPd += isPd(element);
  return numPd;
}

// A crack lives only where bonds do (model.md §3): some PD node must lie within δ of it.
void checkPreCracksInPd(const Model& model) {
  for (const auto& crack : model.deck.mesh.preCracks) {
    bool nearPd = false;
    for (std::size_t k = 0; k < model.pdNodes.extent(0) && !nearPd; ++k)
      nearPd = distanceToSegment(nodePosition(model.shell.mesh, model.pdNodes(k)), crack.segment.start,
                                 crack.segment.end) <= model.horizon();
    if (!nearPd)
      fail(model.deck, "mesh.pre-cracks." + crack.name,
           "lies outside every PD zone (no PD node within the horizon of it); a crack can only live "
           "in PD elements (model.md §3)");
  }
}

// Extreme but finite material values make the stiffnesses, masses or bond moduli built from
// them overflow or underflow, and the solvers then report symptoms (a non-finite critical step,
// every DOF prescribed, zero displacement) instead of the cause. Each derived scale must lie
// where its square and its inverse are still ordinary doubles.
void checkMaterialScales(const Model& model) {
  const deck::Material& material = model.deck.material;
  const double E = material.youngModulus, nu = material.poissonRatio, rho = material.density, t = material.thickness;
  const double dx = model.gridSpacing(), delta = model.horizon();
  constexpr double smallest = 1e-100, largest = 1e100;
  constexpr double pi = 3.14159265358979323846;
  struct Scale {
    const char* keys;
    const char* what;
    const char* unit;
    double value;
  };
  std::vector<Scale> scales = {
      {"material.young-modulus and material.thickness", "the membrane stiffness E t", "N/m", E * t},
      {"material.young-modulus and material.thickness", "the bending stiffness E t^3 / (12 (1 - nu^2))", "N m",
       E * t * t * t / (12.0 * (1.0 - nu * nu))},
      {"material.density, material.thickness and mesh.spacing", "a node's mass rho t dx^2", "kg", rho * t * dx * dx},
      {"material.young-modulus and material.density", "the wave speed sqrt(E / rho)", "m/s", std::sqrt(E / rho)}};
  if (model.numPdElements > 0) {
    scales.push_back({"material.young-modulus, material.thickness and mesh.spacing",
                      "the axial micromodulus 6 E / (pi t delta^3 (1 - nu)) (model.md §2)", "N/m^6",
                      6.0 * E / (pi * t * delta * delta * delta * (1.0 - nu))});
    if (material.fractureEnergy && *material.fractureEnergy > 0.0)
      scales.push_back({"material.fracture-energy, material.thickness and mesh.spacing",
                        "the critical micropotential per length 2 G_c / (t delta^4) (model.md §3)", "J/m^7",
                        2.0 * *material.fractureEnergy / (t * delta * delta * delta * delta)});
  }
  for (const Scale& scale : scales)
    if (!(std::abs(scale.value) >= smallest && std::abs(scale.value) <= largest)) {
      std::ostringstream reason;
      reason << "these values make " << scale.what << " = " << scale.value << " " << scale.unit
             << ", outside what the solvers can carry in double precision (" << smallest << " to " << largest
             << " in SI units); check their values and units (SI: Pa, kg/m^3, m)";
      fail(model.deck, scale.keys, reason.str());
    }
}

// A load so small or so large that the nodal forces it makes (its value times dx^2 for a
// pressure, dx t for an edge traction, itself for a point force) leave the range the solvers
// carry would show only as a symptom: a zero or non-finite answer. Zero loads are fine (a
// zero point force is a probe).
void checkLoadScales(const Model& model) {
  constexpr double smallest = 1e-100, largest = 1e100;
  const double dx = model.gridSpacing(), t = model.deck.material.thickness;
  for (const auto& load : model.deck.loads) {
    const double area = load.type == deck::LoadType::Pressure       ? dx * dx
                        : load.type == deck::LoadType::EdgeTraction ? dx * t
                                                                     : 1.0;
    const char* unit = load.type == deck::LoadType::PointForce ? "N" : "Pa";
    auto check = [&](const char* key, double magnitude, const char* magnitudeUnit, double nodalScale) {
      if (magnitude == 0.0) return;
      const double nodal = magnitude * nodalScale;
      if (magnitude >= smallest && magnitude <= largest && nodal >= smallest && nodal <= largest) return;
      std::ostringstream reason;
      reason << "has magnitude " << magnitude << " " << magnitudeUnit << ", which makes nodal forces of about "
             << nodal << (key[0] == 'm' ? " N m" : " N") << ", outside what the solvers can carry in double precision ("
             << smallest << " to " << largest << " in SI units); check the value and its units";
      fail(model.deck, "loads." + load.name + "." + key, reason.str());
    };
    const auto norm = [](const deck::Vector3& v) { return std::hypot(v[0], v[1], v[2]); };  // no overflow of the squares
    if (load.value) check("value", std::abs(*load.value), unit, area);
    if (load.vector) check("vector", norm(*load.vector), unit, area);
    if (load.moment) check("moment", norm(*load.moment), "N m", 1.0);
  }
}

// A pre-crack cuts through the thickness along its normal (mesh/crack_segment.hpp); a normal
// in the shell's plane makes the cut the shell's own surface, which separates no bond. The
// shell normal is taken at the mesh node nearest the crack's midpoint.
void checkPreCrackNormals(const Model& model) {
  if (model.deck.mesh.preCracks.empty()) return;
  const HostQuadMesh& mesh = model.shell.mesh;
  const auto normals = mesh::computeNodeNormals(Kokkos::DefaultHostExecutionSpace{}, mesh);
  for (const auto& crack : model.deck.mesh.preCracks) {
    const auto& segment = crack.segment;
    const Vector3 middle = {0.5 * (segment.start[0] + segment.end[0]), 0.5 * (segment.start[1] + segment.end[1]),
                            0.5 * (segment.start[2] + segment.end[2])};
    LocalIndex nearest = 0;
    for (LocalIndex node = 1; node < mesh.numNodes(); ++node)
      if (distanceSquared(middle, nodePosition(mesh, node)) < distanceSquared(middle, nodePosition(mesh, nearest)))
        nearest = node;
    double cosine = 0.0;
    for (int k = 0; k < 3; ++k) cosine += segment.normal[k] * normals(nearest, k);
    // More than 60 degrees off the shell normal: the cut lies closer to the shell's plane than
    // across it (a curved shell turns a straight crack's normal by far less along its length).
    if (std::abs(cosine) < 0.5) {
      const Vector3 at = nodePosition(mesh, nearest);
      std::ostringstream reason;
      reason << "[" << segment.normal[0] << ", " << segment.normal[1] << ", " << segment.normal[2]
             << "] (unit) is " << std::lround(std::acos(std::abs(cosine)) * 180.0 / 3.14159265358979323846)
             << " degrees from the shell normal [" << normals(nearest, 0) << ", " << normals(nearest, 1) << ", "
             << normals(nearest, 2) << "] at the node nearest the crack's middle ([" << at[0] << ", " << at[1]
             << ", " << at[2] << "] m): the crack would cut along the shell's surface and separate nothing; "
             << "give the shell normal at the crack";
      fail(model.deck, "mesh.pre-cracks." + crack.name + ".normal", reason.str());
    }
  }
}

// The supports' sets that get a support layer (docs/model-setup.md, "Supports on PD regions"):
// held where their DOFs clamp a PD edge (all three displacements and every rotation but, at
// most, the drilling one about the shell normal at each of the set's nodes); mirrored where
// they hold other DOFs, each edge then imaged as mesh::mirrorMaps says (about the prescribed
// values, assembly/mirror_images.hpp).
std::vector<mesh::SupportLayerRequest> layerRequests(const Model& model) {
  std::map<std::string, std::uint8_t> dofsOfSet;
  for (const auto& support : model.deck.supports)
    for (const auto dof : support.dofs) dofsOfSet[support.set] |= std::uint8_t(1u << static_cast<int>(dof));
  const auto normals = mesh::computeNodeNormals(Kokkos::DefaultHostExecutionSpace{}, model.shell.mesh);
  std::vector<mesh::SupportLayerRequest> requests;
  for (const auto& [set, dofs] : dofsOfSet) {
    auto nodes = model.shell.sets.nodesOfNodeOrEdgeSet(set);
    bool clamped = (dofs & 0b111) == 0b111;
    for (int axis = 0; axis < 3 && clamped; ++axis) {
      if (dofs & (1u << (3 + axis))) continue;
      constexpr double drillingOnly = 1.0 - 1e-6;  // the free rotation axis is the normal
      for (const LocalIndex node : nodes) clamped = clamped && std::abs(normals(node, axis)) >= drillingOnly;
    }
    requests.push_back({set, std::move(nodes), clamped ? mesh::LayerMotion::Held : mesh::LayerMotion::Mirrored, dofs});
  }
  return requests;
}

// Distinct nodes at one point: the mesh leaves them unconnected on purpose (a slit) or by
// mistake (a seam Gmsh did not merge); `check` and `run` say so either way.
void findCoincidentNodes(Model& model) {
  const HostQuadMesh& mesh = model.shell.mesh;
  const double tolerance = 1e-6 * model.gridSpacing();
  const auto grid = mesh::makeNodeGrid(mesh, model.gridSpacing());
  for (LocalIndex node = 0; node < mesh.numNodes(); ++node) {
    const Vector3 x = nodePosition(mesh, node);
    grid.forEachIn({x[0] - tolerance, x[1] - tolerance, x[2] - tolerance},
                   {x[0] + tolerance, x[1] + tolerance, x[2] + tolerance}, [&](LocalIndex other) {
                     if (other <= node || distanceSquared(x, nodePosition(mesh, other)) > tolerance * tolerance)
                       return;
                     if (model.numCoincidentPairs++ == 0) model.firstCoincidentPair = {node, other};
                   });
  }
}

// docs/model-setup.md, "Supports on PD regions".
void addSupportLayer(Model& model) {
  const LocalIndex numElements = model.shell.mesh.numElements();
  std::vector<std::uint8_t> isPd(model.elementIsPd.data(), model.elementIsPd.data() + numElements);
  const bool wanted = model.deck.peridynamics.supportLayer && model.numPdElements > 0;
  model.supportLayer = mesh::addSupportLayer(model.shell.mesh, wanted ? layerRequests(model) : std::vector<mesh::SupportLayerRequest>{},
                                             isPd, model.horizon(), model.gridSpacing());
  const LocalIndex numAll = model.shell.mesh.numElements();
  if (!model.supportLayer.mirrorShare.empty()) {
    const Kokkos::DefaultHostExecutionSpace host;
    const HostQuadMesh& mesh = model.shell.mesh;
    const auto withLayer = mesh::computeNodeAreas(host, mesh);
    const HostQuadMesh deckOnly{mesh.coordinates,
                                Kokkos::subview(mesh.quads, std::make_pair(LocalIndex(0), numElements), Kokkos::ALL)};
    const auto deckAreas = mesh::computeNodeAreas(host, deckOnly);
    for (const auto& [node, share] : model.supportLayer.mirrorShare)
      if (node < model.supportLayer.firstNode && share > 0.0 && withLayer(node) > 0.0)
        model.supportLayer.massShare[node] = deckAreas(node) / withLayer(node);
  }
  Kokkos::resize(model.elementIsPd, numAll);
  for (LocalIndex element = numElements; element < numAll; ++element) model.elementIsPd(element) = 1;
  std::set<std::pair<LocalIndex, int>> constrained;
  for (const auto& support : model.deck.supports)
    for (const LocalIndex node : model.supportNodes(support))
      for (const auto dof : support.dofs) constrained.insert({node, static_cast<int>(dof)});
  for (const auto& image : model.supportLayer.mirrorImages)
    for (int dof = 0; dof < 6; ++dof) constrained.insert({image.node, dof});
  model.numConstrainedDofs = static_cast<long long>(constrained.size());
}

}  // namespace

std::vector<LocalIndex> Model::supportNodes(const deck::Support& support) const {
  auto nodes = shell.sets.nodesOfNodeOrEdgeSet(support.set);
  for (const auto* layerNodes : {&supportLayer.nodesOfSet, &supportLayer.mirroredNodesOfSet}) {
    const auto layer = layerNodes->find(support.set);
    if (layer != layerNodes->end()) nodes.insert(nodes.end(), layer->second.begin(), layer->second.end());
  }
  return nodes;
}

Model buildModel(const Deck& deck) {
  Model model;
  model.deck = deck;
  model.shell = buildMesh(deck);
  addDeckNodeSets(deck, model.shell);
  checkSetReferences(deck, model.shell.sets, model.numConstrainedDofs);
  model.numPdElements = flagPdElements(deck, model.shell, model.elementIsPd);
  findCoincidentNodes(model);
  addSupportLayer(model);

  const HostQuadMesh& mesh = model.shell.mesh;
  std::vector<std::uint8_t> isPdNode(mesh.numNodes(), 0);
  for (LocalIndex element = 0; element < mesh.numElements(); ++element)
    if (model.elementIsPd(element))
      for (int a = 0; a < 4; ++a) isPdNode[mesh.quads(element, a)] = 1;
  const auto numPdNodes = std::count(isPdNode.begin(), isPdNode.end(), 1);
  model.pdNodes = Kokkos::View<LocalIndex*, Kokkos::HostSpace>("pd nodes", numPdNodes);
  LocalIndex next = 0;
  for (LocalIndex node = 0; node < mesh.numNodes(); ++node)
    if (isPdNode[node]) model.pdNodes(next++) = node;
  checkMaterialScales(model);
  checkLoadScales(model);
  checkPreCracksInPd(model);
  checkPreCrackNormals(model);
  return model;
}

}  // namespace perishell::model
