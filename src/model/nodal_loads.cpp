#include <perishell/mesh/bilinear_quad.hpp>
#include <perishell/mesh/node_geometry.hpp>
#include <perishell/model/nodal_loads.hpp>

#include <algorithm>
#include <bitset>
#include <cmath>
#include <limits>
#include <numeric>
#include <set>
#include <sstream>

namespace perishell::model {

namespace {

using Vector3 = deck::Vector3;

[[noreturn]] void fail(const Deck& deck, const std::string& keyPath, const std::string& reason) {
  throw DeckError(deck.sourceName, keyPath, reason);
}

std::string loadKey(const deck::Load& load, const std::string& key) { return "loads." + load.name + "." + key; }

Vector3 cross(const Vector3& a, const Vector3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

double norm(const Vector3& v) { return std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]); }


std::vector<LocalIndex> pressureElements(const Model& model, const deck::Load& load) {
  if (!load.set.empty()) return model.shell.sets.elementSet(load.set);
  std::vector<LocalIndex> all(model.numMeshElements());  // not the support layer's
  std::iota(all.begin(), all.end(), 0);
  return all;
}

void addToNode(const HostNodalValues& nodal, LocalIndex node, int firstDof, const Vector3& value) {
  for (int d = 0; d < 3; ++d) nodal(node, firstDof + d) += value[d];
}

void addPointForce(const Model& model, const deck::Load& load, const HostNodalValues& nodal) {
  for (const LocalIndex node : model.shell.sets.nodesOfNodeOrEdgeSet(load.set)) {
    if (load.vector) addToNode(nodal, node, 0, *load.vector);
    if (load.moment) addToNode(nodal, node, 3, *load.moment);
  }
}

// Outward in-plane unit normal of an edge: the edge runs with the shell on its left seen
// against the node normal, so edge direction x normal points away from the shell.
Vector3 outwardEdgeNormal(const Model& model, const deck::Load& load, const mesh::MeshEdge& edge,
                          const CoordinateView<Kokkos::HostSpace>& nodeNormals) {
  const auto& x = model.shell.mesh.coordinates;
  Vector3 direction{}, surfaceNormal{};
  for (int d = 0; d < 3; ++d) {
    direction[d] = x(edge.second, d) - x(edge.first, d);
    surfaceNormal[d] = nodeNormals(edge.first, d) + nodeNormals(edge.second, d);
  }
  Vector3 outward = cross(direction, surfaceNormal);
  const double length = norm(outward);
  // Relative to |direction| |surfaceNormal|: rejects a zero-length edge, opposite end normals
  // and an edge along the normal alike.
  if (!(length > 1e-8 * norm(direction) * norm(surfaceNormal)))
    fail(model.deck, loadKey(load, "set"),
         "edge (" + std::to_string(edge.first) + ", " + std::to_string(edge.second) +
             ") has no outward in-plane normal (zero length, or along the shell normal)");
  for (double& component : outward) component /= length;
  return outward;
}

void addEdgeTraction(const Model& model, const deck::Load& load, const HostNodalValues& nodal,
                     const CoordinateView<Kokkos::HostSpace>& nodeNormals) {
  const auto& x = model.shell.mesh.coordinates;
  const double thickness = model.deck.material.thickness;
  for (const auto& edge : model.shell.sets.edgeSet(load.set)) {
    Vector3 direction{};
    for (int d = 0; d < 3; ++d) direction[d] = x(edge.second, d) - x(edge.first, d);
    const double length = norm(direction);
    Vector3 traction = load.vector ? *load.vector : outwardEdgeNormal(model, load, edge, nodeNormals);
    if (load.value)
      for (double& component : traction) component *= *load.value;
    Vector3 endForce{};
    for (int d = 0; d < 3; ++d) endForce[d] = 0.5 * traction[d] * length * thickness;
    addToNode(nodal, edge.first, 0, endForce);
    addToNode(nodal, edge.second, 0, endForce);
  }
}

// F_a = sum over Gauss points of N_a p (g_1 x g_2), or N_a |g_1 x g_2| t for a traction vector
// t; the Gauss weights are 1.
void addPressure(const Model& model, const deck::Load& load, const HostNodalValues& nodal) {
  const auto& mesh = model.shell.mesh;
  for (const LocalIndex element : pressureElements(model, load)) {
    double x[4][3];
    mesh::bilinear::gatherNodes(mesh.coordinates, mesh.quads, element, x);
    for (int q = 0; q < mesh::bilinear::numGaussPoints; ++q) {
      const auto point =
          mesh::bilinear::evaluate(x, mesh::bilinear::gaussXi(q), mesh::bilinear::gaussEta(q));
      Vector3 g1{}, g2{};
      for (int a = 0; a < 4; ++a)
        for (int d = 0; d < 3; ++d) {
          g1[d] += point.dShapeDxi[a] * x[a][d];
          g2[d] += point.dShapeDeta[a] * x[a][d];
        }
      const Vector3 areaVector = cross(g1, g2);
      Vector3 traction{};
      for (int d = 0; d < 3; ++d)
        traction[d] = load.vector ? (*load.vector)[d] * norm(areaVector) : *load.value * areaVector[d];
      for (int a = 0; a < 4; ++a) {
        Vector3 force{};
        for (int d = 0; d < 3; ++d) force[d] = point.shape[a] * traction[d];
        addToNode(nodal, mesh.quads(element, a), 0, force);
      }
    }
  }
}

// The deck key whose size made a nodal value non-finite.
std::string magnitudeKey(const deck::Load& load, int dof) {
  if (load.type == deck::LoadType::PointForce) return loadKey(load, dof < 3 ? "vector" : "moment");
  return loadKey(load, load.vector ? "vector" : "value");
}

void requireFinite(const Model& model, const deck::Load& load, const HostNodalValues& nodal) {
  for (LocalIndex node = 0; node < static_cast<LocalIndex>(nodal.extent(0)); ++node)
    for (int dof = 0; dof < 6; ++dof)
      if (!std::isfinite(nodal(node, dof))) {
        std::ostringstream reason;
        reason << "gives a non-finite nodal load (DOF " << dof << " of node " << node
               << "): the value is too large for this mesh and thickness";
        fail(model.deck, magnitudeKey(load, dof), reason.str());
      }
}

LoadPattern& patternFor(std::vector<LoadPattern>& patterns, const std::string& curve, LocalIndex numNodes) {
  const auto found = std::find_if(patterns.begin(), patterns.end(),
                                  [&](const LoadPattern& pattern) { return pattern.curve == curve; });
  if (found != patterns.end()) return *found;
  const std::string label = "load pattern " + (curve.empty() ? std::string("(no curve)") : curve);
  patterns.push_back({curve, HostNodalValues(label, numNodes)});
  return patterns.back();
}

double referenceArea(const Model& model, const std::vector<LocalIndex>& elements) {
  const auto& mesh = model.shell.mesh;
  double area = 0.0;
  for (const LocalIndex element : elements) {
    double x[4][3];
    mesh::bilinear::gatherNodes(mesh.coordinates, mesh.quads, element, x);
    for (int q = 0; q < mesh::bilinear::numGaussPoints; ++q)
      area += mesh::bilinear::evaluate(x, mesh::bilinear::gaussXi(q), mesh::bilinear::gaussEta(q)).areaElement;
  }
  return area;
}

FollowerPressure followerPressure(const Model& model, const deck::Load& load) {
  FollowerPressure follower{load.name, load.curve, *load.value, pressureElements(model, load)};
  if (!std::isfinite(follower.pressure * referenceArea(model, follower.elements)))
    fail(model.deck, loadKey(load, "value"), "gives a non-finite total force: too large for this mesh");
  return follower;
}

// Only value tractions need node normals, and computeNodeNormals rejects degenerate meshes.
CoordinateView<Kokkos::HostSpace> nodeNormalsFor(const Model& model) {
  const auto& loads = model.deck.loads;
  const auto byValue = std::find_if(loads.begin(), loads.end(), [](const deck::Load& load) {
    return load.type == deck::LoadType::EdgeTraction && load.value;
  });
  if (byValue == loads.end()) return {};
  try {
    return mesh::computeNodeNormals(Kokkos::DefaultHostExecutionSpace{}, model.shell.mesh);
  } catch (const std::runtime_error& error) {
    fail(model.deck, loadKey(*byValue, "set"),
         std::string("outward edge normals need node normals: ") + error.what());
  }
}

}  // namespace

NodalLoads buildNodalLoads(const Model& model) {
  NodalLoads loads;
  const LocalIndex numNodes = model.shell.mesh.numNodes();
  const auto nodeNormals = nodeNormalsFor(model);
  for (const auto& load : model.deck.loads) {
    if (load.type == deck::LoadType::Pressure && load.follower) {
      loads.followerPressures.push_back(followerPressure(model, load));
      continue;
    }
    const HostNodalValues nodal = patternFor(loads.patterns, load.curve, numNodes).nodal;
    switch (load.type) {
      case deck::LoadType::PointForce: addPointForce(model, load, nodal); break;
      case deck::LoadType::EdgeTraction: addEdgeTraction(model, load, nodal, nodeNormals); break;
      case deck::LoadType::Pressure: addPressure(model, load, nodal); break;
    }
    requireFinite(model, load, nodal);
  }
  return loads;
}

namespace {

constexpr const char* dofNames[6] = {"ux", "uy", "uz", "rx", "ry", "rz"};

// A prescribed DOF as a function of time: value x curve factor, or the constant value.
struct Prescription {
  double value = 0.0;
  int curve = -1;
  bool operator==(const Prescription& other) const { return value == other.value && curve == other.curve; }
};

std::string describe(const Prescription& prescription, const SupportConditions& conditions) {
  std::ostringstream text;
  text << prescription.value;
  if (prescription.curve >= 0) text << " x curve '" << conditions.curves[prescription.curve] << "'";
  return text.str();
}

// A zero value stays zero under any curve, so it is stored as constant: a fixed DOF then
// agrees with every other fixed DOF.
Prescription prescriptionOf(const Model& model, const deck::Support& support, SupportConditions& conditions) {
  if (support.value == 0.0 || support.curve.empty()) return {support.value, -1};
  auto& curves = conditions.curves;
  const auto found = std::find(curves.begin(), curves.end(), support.curve);
  if (found != curves.end()) return {support.value, static_cast<int>(found - curves.begin())};
  if (curves.size() > static_cast<std::size_t>(std::numeric_limits<std::int8_t>::max()))
    fail(model.deck, "supports." + support.name + ".curve", "more than 128 distinct support curves");
  curves.push_back(support.curve);
  return {support.value, static_cast<int>(curves.size()) - 1};
}

[[noreturn]] void failConflict(const Model& model, const deck::Support& later, const deck::Support& earlier,
                               LocalIndex node, int dof, const Prescription& laterValue,
                               const Prescription& earlierValue, const SupportConditions& conditions) {
  const auto& x = model.shell.mesh.coordinates;
  std::ostringstream reason;
  reason << "prescribes " << dofNames[dof] << " = " << describe(laterValue, conditions) << " at node " << node
         << " (" << x(node, 0) << ", " << x(node, 1) << ", " << x(node, 2) << "), where supports."
         << earlier.name << " prescribes " << describe(earlierValue, conditions);
  fail(model.deck, "supports." + later.name, reason.str());
}

}  // namespace

SupportConditions buildSupportConditions(const Model& model) {
  const LocalIndex numNodes = model.shell.mesh.numNodes();
  SupportConditions conditions;
  conditions.constrainedDofs = decltype(conditions.constrainedDofs)("constrained dofs", numNodes);
  conditions.prescribedValue = HostNodalValues("prescribed values", numNodes);
  conditions.curveIndex = decltype(conditions.curveIndex)("support curve index", numNodes);
  Kokkos::deep_copy(conditions.curveIndex, std::int8_t(-1));
  // Which support set each node DOF first, to name both in a conflict.
  std::vector<int> setBy(6 * static_cast<std::size_t>(numNodes), -1);
  const auto& supports = model.deck.supports;
  for (std::size_t s = 0; s < supports.size(); ++s) {
    const Prescription prescription = prescriptionOf(model, supports[s], conditions);
    for (const LocalIndex node : model.supportNodes(supports[s]))
      for (const auto dofName : supports[s].dofs) {
        const int dof = static_cast<int>(dofName);
        int& owner = setBy[6 * std::size_t(node) + dof];
        const Prescription existing{conditions.prescribedValue(node, dof), conditions.curveIndex(node, dof)};
        if (owner >= 0 && !(existing == prescription))
          failConflict(model, supports[s], supports[owner], node, dof, prescription, existing, conditions);
        owner = static_cast<int>(s);
        conditions.constrainedDofs(node) |= std::uint8_t(1u << dof);
        conditions.prescribedValue(node, dof) = prescription.value;
        conditions.curveIndex(node, dof) = static_cast<std::int8_t>(prescription.curve);
      }
  }
  // A mirrored layer node has no DOF of its own: it follows its master
  // (solvers/mirror_constraints.hpp), so the solvers take it as held.
  for (const auto& image : model.supportLayer.mirrorImages) conditions.constrainedDofs(image.node) = 0b111111;
  return conditions;
}

long long SupportConditions::numConstrainedDofs() const {
  long long count = 0;
  for (std::size_t node = 0; node < constrainedDofs.extent(0); ++node)
    count += static_cast<long long>(std::bitset<6>(constrainedDofs(node)).count());
  return count;
}

}  // namespace perishell::model
