#include <perishell/core/rotation.hpp>
#include <perishell/solvers/history_columns.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace perishell::solvers {

namespace {

const char* const axes[3] = {"x", "y", "z"};

std::string formatNumber(double value) {
  std::ostringstream text;
  text.precision(6);
  text << value;
  return text.str();
}

std::string formatPoint(const double x, const double y, const double z) {
  return "[" + formatNumber(x) + ", " + formatNumber(y) + ", " + formatNumber(z) + "]";
}

std::string formatNode(const model::Model& model, LocalIndex node) {
  const auto& x = model.shell.mesh.coordinates;
  return "node " + std::to_string(node) + " at " + formatPoint(x(node, 0), x(node, 1), x(node, 2)) + " m";
}

}  // namespace

double probeReach(const model::Model& model) {
  const auto& mesh = model.shell.mesh;
  double longest = 0.0;
  for (LocalIndex element = 0; element < model.numMeshElements(); ++element)
    for (int a = 0; a < 4; ++a) {
      const LocalIndex from = mesh.quads(element, a), to = mesh.quads(element, (a + 1) % 4);
      longest = std::max(longest, std::hypot(mesh.coordinates(to, 0) - mesh.coordinates(from, 0),
                                             mesh.coordinates(to, 1) - mesh.coordinates(from, 1),
                                             mesh.coordinates(to, 2) - mesh.coordinates(from, 2)));
    }
  return std::max(model.gridSpacing(), longest);
}

std::vector<SnappedProbe> snapProbes(const model::Model& model) {
  const auto& deck = model.deck;
  const auto& x = model.shell.mesh.coordinates;
  std::vector<SnappedProbe> probes;
  if (deck.output.probes.empty()) return probes;
  const double reach = probeReach(model);
  for (const auto& point : deck.output.probes) {
    const auto& p = point.position;
    SnappedProbe probe{point.name, -1, std::numeric_limits<double>::infinity()};
    for (LocalIndex node = 0; node < model.numMeshNodes(); ++node) {  // not the support layer's
      const double distance = std::hypot(x(node, 0) - p[0], x(node, 1) - p[1], x(node, 2) - p[2]);
      if (distance < probe.distance) probe = {point.name, node, distance};
    }
    if (!(probe.distance <= reach))
      throw DeckError(deck.sourceName, "output.probes." + point.name,
                      "the nearest mesh node to " + formatPoint(p[0], p[1], p[2]) + " m, " +
                          formatNode(model, probe.node) + ", is " + formatNumber(probe.distance) +
                          " m away, farther than " + formatNumber(reach) +
                          " m (the larger of mesh.spacing and the longest element edge): a probe must lie on the "
                          "shell");
    // A point on a node to the round-off of its coordinates is on it.
    if (probe.distance <= 1e-9 * reach) probe.distance = 0.0;
    probes.push_back(probe);
  }
  return probes;
}

void printProbes(const model::Model& model, const std::vector<SnappedProbe>& probes, std::ostream& log) {
  for (const auto& probe : probes)
    log << "probe " << probe.name << ": " << formatNode(model, probe.node) << ", " << formatNumber(probe.distance)
        << " m from the deck's point\n";
}

HistoryColumns::HistoryColumns(const model::Model& model) : model_(&model), probes_(snapProbes(model)) {
  const auto& supports = model.deck.supports;
  // How many supports prescribe each translational node DOF.
  std::vector<int> owners(3 * static_cast<std::size_t>(model.shell.mesh.numNodes()), 0);
  auto eachDof = [&](const deck::Support& support, auto&& visit) {
    for (const LocalIndex node : model.supportNodes(support))  // the support layer's too
      for (const auto dof : support.dofs)
        if (static_cast<int>(dof) < 3) visit(node, static_cast<int>(dof));
  };
  for (const auto& support : supports)
    eachDof(support, [&](LocalIndex node, int dof) { ++owners[3 * std::size_t(node) + dof]; });
  for (const auto& support : supports) {
    auto& shares = supportShares_.emplace_back();
    eachDof(support, [&](LocalIndex node, int dof) {
      shares.push_back({node, dof, 1.0 / owners[3 * std::size_t(node) + dof]});
    });
  }
  for (std::size_t k = 0; k < owners.size(); ++k)
    if (owners[k] > 0) prescribed_.push_back({static_cast<LocalIndex>(k / 3), static_cast<int>(k % 3), 1.0});
}

std::vector<std::string> HistoryColumns::reactionColumns() const {
  std::vector<std::string> columns;
  for (const auto& support : model_->deck.supports)
    for (const char* axis : axes) columns.push_back("reaction-" + support.name + "-" + axis);
  for (const char* axis : axes) columns.push_back(std::string("reaction-total-") + axis);
  return columns;
}

void HistoryColumns::appendReactions(const HostNodalForces& outOfBalance, std::vector<double>& row) const {
  auto appendSum = [&](const std::vector<DofShare>& shares) {
    double sum[3] = {0.0, 0.0, 0.0};
    for (const auto& share : shares) sum[share.dof] -= share.weight * outOfBalance(share.node, share.dof);
    row.insert(row.end(), sum, sum + 3);
  };
  for (const auto& shares : supportShares_) appendSum(shares);
  appendSum(prescribed_);
}

std::vector<std::string> HistoryColumns::loadPointColumns() const {
  std::vector<std::string> columns;
  for (const auto& load : model_->deck.loads)
    if (load.type == deck::LoadType::PointForce)
      for (const char* axis : {"ux", "uy", "uz"}) columns.push_back(load.name + "-" + axis);
  return columns;
}

void HistoryColumns::appendLoadPoints(const HostDisplacements& displacements, std::vector<double>& row) const {
  for (const auto& load : model_->deck.loads) {
    if (load.type != deck::LoadType::PointForce) continue;
    const auto& nodes = model_->shell.sets.nodeSet(load.set);
    double mean[3] = {0.0, 0.0, 0.0};
    for (const LocalIndex node : nodes)
      for (int d = 0; d < 3; ++d) mean[d] += displacements(node, d) / nodes.size();
    row.insert(row.end(), mean, mean + 3);
  }
}

std::vector<std::string> HistoryColumns::probeColumns() const {
  std::vector<std::string> columns;
  for (const auto& probe : probes_)
    for (const char* component : {"ux", "uy", "uz", "rx", "ry", "rz"}) columns.push_back(probe.name + "-" + component);
  return columns;
}

void HistoryColumns::appendProbes(const HostDisplacements& displacements, const HostRotations& rotations,
                                  std::vector<double>& row) const {
  for (const auto& probe : probes_) {
    const double q[4] = {rotations(probe.node, 0), rotations(probe.node, 1), rotations(probe.node, 2),
                         rotations(probe.node, 3)};
    double theta[3];
    rotation::rotationVector(q, theta);
    row.insert(row.end(), {displacements(probe.node, 0), displacements(probe.node, 1), displacements(probe.node, 2),
                           theta[0], theta[1], theta[2]});
  }
}

}  // namespace perishell::solvers
