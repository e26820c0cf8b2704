#include <perishell/model/model.hpp>
#include <perishell/parallel/domain.hpp>

#if PERISHELL_HAVE_METIS
#include <metis.h>
#endif

#include <algorithm>
#include <cmath>
#include <numeric>
#include <set>
#include <stdexcept>
#include <unordered_map>

namespace perishell::parallel {

namespace {

// The largest element edge: the element size the halo reaches across.
double largestEdge(const mesh::HostQuadMesh& mesh) {
  double largest = 0.0;
  for (LocalIndex e = 0; e < mesh.numElements(); ++e)
    for (int a = 0; a < 4; ++a) {
      const LocalIndex i = mesh.quads(e, a), j = mesh.quads(e, (a + 1) % 4);
      double squared = 0.0;
      for (int d = 0; d < 3; ++d) squared += std::pow(mesh.coordinates(i, d) - mesh.coordinates(j, d), 2);
      largest = std::max(largest, std::sqrt(squared));
    }
  return largest;
}

#if PERISHELL_HAVE_METIS
std::vector<int> metisParts(const model::Model& model, int parts) {
  const auto& mesh = model.shell.mesh;
  const LocalIndex numNodes = mesh.numNodes();
  std::vector<std::set<LocalIndex>> adjacency(numNodes);
  std::vector<idx_t> weight(numNodes, 1);
  const double ratio = model.horizon() / model.gridSpacing();
  // A PD node's bonds: about pi (delta / dx)^2 on a regular grid; a MITC4 element costs
  // about as much as 30 bonds, spread over its 4 nodes.
  const idx_t bondsPerNode = static_cast<idx_t>(std::lround(M_PI * ratio * ratio));
  std::vector<std::uint8_t> pdNode(numNodes, 0);
  for (std::size_t k = 0; k < model.pdNodes.extent(0); ++k) pdNode[model.pdNodes(k)] = 1;
  for (LocalIndex node = 0; node < numNodes; ++node) weight[node] += pdNode[node] ? bondsPerNode : 0;
  for (LocalIndex e = 0; e < mesh.numElements(); ++e)
    for (int a = 0; a < 4; ++a) {
      const LocalIndex i = mesh.quads(e, a);
      if (!model.elementIsPd(e)) weight[i] += 8;
      for (int b = 0; b < 4; ++b)
        if (mesh.quads(e, b) != i) adjacency[i].insert(mesh.quads(e, b));
    }
  std::vector<idx_t> offsets(numNodes + 1, 0), neighbours;
  for (LocalIndex node = 0; node < numNodes; ++node) {
    neighbours.insert(neighbours.end(), adjacency[node].begin(), adjacency[node].end());
    offsets[node + 1] = static_cast<idx_t>(neighbours.size());
  }
  idx_t vertices = numNodes, constraints = 1, numParts = parts, cut = 0;
  std::vector<idx_t> part(numNodes, 0);
  idx_t options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(options);
  options[METIS_OPTION_CONTIG] = 0;
  const int status = METIS_PartGraphKway(&vertices, &constraints, offsets.data(), neighbours.data(), weight.data(),
                                         nullptr, nullptr, &numParts, nullptr, nullptr, options, &cut, part.data());
  if (status != METIS_OK) throw std::runtime_error("partition: METIS failed (status " + std::to_string(status) + ")");
  return {part.begin(), part.end()};
}
#else
// Without MPI there is one rank, and nothing to partition.
std::vector<int> metisParts(const model::Model&, int) {
  throw std::logic_error("partition: this build has no METIS (configure with PERISHELL_ENABLE_MPI=ON)");
}
#endif

}  // namespace

double stateReadRadius(const model::Model& model) {
  return 2.0 * model.horizon() + 2.0 * largestEdge(model.shell.mesh);
}

double haloRadius(const model::Model& model) {
  const double horizon = model.horizon();
  const double transition =
      model.deck.zones.transition.width > 0.0 ? model.deck.zones.transition.width : 2.0 * horizon;
  return 3.0 * horizon + transition + 2.0 * largestEdge(model.shell.mesh);
}

std::vector<int> partitionNodes(const model::Model& model, const Communicator& communicator) {
  const int parts = communicator.size();
  const LocalIndex numNodes = model.shell.mesh.numNodes();
  if (parts > numNodes)
    throw std::invalid_argument("partition: " + std::to_string(parts) + " ranks for a model of " +
                                std::to_string(numNodes) + " nodes; run on at most as many ranks as nodes");
  std::vector<int> owner(numNodes, 0);
  if (parts == 1) return owner;
  if (communicator.root()) {
    owner = metisParts(model, parts);
    for (const auto& image : model.supportLayer.mirrorImages) owner[image.node] = owner[image.master];
  }
  communicator.broadcast(owner);
  std::vector<long long> counts(parts, 0);
  for (const int rank : owner) ++counts[rank];
  for (int rank = 0; rank < parts; ++rank)
    if (counts[rank] == 0)
      throw std::invalid_argument("partition: rank " + std::to_string(rank) + " of " + std::to_string(parts) +
                                  " owns no node of a model of " + std::to_string(numNodes) +
                                  " nodes; run on fewer ranks");
  return owner;
}

long long LocalDomain::numOwned() const { return std::count(owned.begin(), owned.end(), std::uint8_t(1)); }

LocalDomain makeLocalDomain(const model::Model& model, const std::vector<int>& owner,
                            const Communicator& communicator) {
  const auto& global = model.shell.mesh;
  const LocalIndex numNodes = global.numNodes();
  const int rank = communicator.rank();
  std::vector<std::uint8_t> local(numNodes, 0);
  for (LocalIndex node = 0; node < numNodes; ++node) local[node] = owner[node] == rank;

  // Nodes within the radius of an owned node: a grid of cells of the radius' size.
  const double radius = haloRadius(model);
  double lower[3];
  for (int d = 0; d < 3; ++d) {
    lower[d] = global.coordinates(0, d);
    for (LocalIndex node = 1; node < numNodes; ++node) lower[d] = std::min(lower[d], global.coordinates(node, d));
  }
  auto cellOf = [&](LocalIndex node, int d) {
    return static_cast<long long>(std::floor((global.coordinates(node, d) - lower[d]) / radius));
  };
  auto key = [](long long x, long long y, long long z) { return (x * 1000003LL + y) * 1000033LL + z; };
  std::unordered_map<long long, std::vector<LocalIndex>> cells;
  for (LocalIndex node = 0; node < numNodes; ++node)
    cells[key(cellOf(node, 0), cellOf(node, 1), cellOf(node, 2))].push_back(node);
  std::vector<std::uint8_t> within(local), read(local);
  const double readRadius = stateReadRadius(model);
  for (LocalIndex node = 0; node < numNodes; ++node) {
    if (owner[node] != rank) continue;
    const long long cx = cellOf(node, 0), cy = cellOf(node, 1), cz = cellOf(node, 2);
    for (long long x = cx - 1; x <= cx + 1; ++x)
      for (long long y = cy - 1; y <= cy + 1; ++y)
        for (long long z = cz - 1; z <= cz + 1; ++z) {
          const auto found = cells.find(key(x, y, z));
          if (found == cells.end()) continue;
          for (const LocalIndex other : found->second) {
            if (read[other]) continue;
            double squared = 0.0;
            for (int d = 0; d < 3; ++d)
              squared += std::pow(global.coordinates(other, d) - global.coordinates(node, d), 2);
            if (squared <= radius * radius) within[other] = 1;
            if (squared <= readRadius * readRadius) read[other] = 1;
          }
        }
  }
  // Closed over elements: every node of an element that touches the halo.
  local = within;
  for (LocalIndex e = 0; e < global.numElements(); ++e) {
    bool touches = false;
    for (int a = 0; a < 4; ++a) touches = touches || within[global.quads(e, a)];
    if (touches)
      for (int a = 0; a < 4; ++a) local[global.quads(e, a)] = 1;
  }

  LocalDomain domain;
  std::vector<LocalIndex> localIndex(numNodes, -1);
  for (LocalIndex node = 0; node < numNodes; ++node)
    if (local[node]) {
      localIndex[node] = static_cast<LocalIndex>(domain.nodes.size());
      domain.nodes.push_back(node);
      domain.owned.push_back(owner[node] == rank);
    }
  for (LocalIndex e = 0; e < global.numElements(); ++e) {
    bool inside = true;
    for (int a = 0; a < 4; ++a) inside = inside && local[global.quads(e, a)];
    if (inside) domain.elements.push_back(e);
  }
  const LocalIndex numLocal = domain.numNodes(), numElements = static_cast<LocalIndex>(domain.elements.size());
  domain.mesh.coordinates = CoordinateView<Kokkos::HostSpace>("local coordinates", numLocal);
  for (LocalIndex k = 0; k < numLocal; ++k)
    for (int d = 0; d < 3; ++d) domain.mesh.coordinates(k, d) = global.coordinates(domain.nodes[k], d);
  domain.mesh.quads = QuadConnectivityView<Kokkos::HostSpace>("local quads", numElements);
  domain.elementIsPd = Kokkos::View<std::uint8_t*, Kokkos::HostSpace>("local element is pd", numElements);
  for (LocalIndex k = 0; k < numElements; ++k) {
    for (int a = 0; a < 4; ++a) domain.mesh.quads(k, a) = localIndex[global.quads(domain.elements[k], a)];
    domain.elementIsPd(k) = model.elementIsPd(domain.elements[k]);
  }

  // The support layer in local numbers: its first node and element are the first local ones
  // at or beyond the global ones (the layer comes last in either numbering).
  const auto& layer = model.supportLayer;
  auto& localLayer = domain.supportLayer;
  if (layer.firstNode < numNodes)
    localLayer.firstNode = static_cast<LocalIndex>(
        std::lower_bound(domain.nodes.begin(), domain.nodes.end(), layer.firstNode) - domain.nodes.begin());
  if (layer.firstElement < global.numElements())
    localLayer.firstElement = static_cast<LocalIndex>(
        std::lower_bound(domain.elements.begin(), domain.elements.end(), layer.firstElement) -
        domain.elements.begin());
  // An image whose master is not local is a halo node: its owner moves it and sends it over.
  for (const auto& image : layer.mirrorImages)
    if (localIndex[image.node] >= 0 && localIndex[image.master] >= 0) {
      auto renumbered = image;
      renumbered.node = localIndex[image.node];
      renumbered.master = localIndex[image.master];
      localLayer.mirrorImages.push_back(renumbered);
    }
  for (const auto& [node, share] : layer.mirrorShare)
    if (localIndex[node] >= 0) localLayer.mirrorShare[localIndex[node]] = share;
  for (const auto& [node, share] : layer.massShare)
    if (localIndex[node] >= 0) localLayer.massShare[localIndex[node]] = share;

  // The halo: what each owner sends us; they learn it from our requests.
  std::vector<std::vector<long long>> requests(communicator.size());
  for (LocalIndex k = 0; k < numLocal; ++k)
    if (!domain.owned[k] && read[domain.nodes[k]]) requests[owner[domain.nodes[k]]].push_back(domain.nodes[k]);
  const auto asked = communicator.allToAll(requests);
  for (int other = 0; other < communicator.size(); ++other) {
    if (requests[other].empty() && asked[other].empty()) continue;
    domain.ranks.push_back(other);
    std::vector<LocalIndex> receive, send;
    for (const long long node : requests[other]) receive.push_back(localIndex[node]);
    for (const long long node : asked[other]) {
      if (node < 0 || node >= numNodes || owner[node] != rank || localIndex[node] < 0)
        throw std::logic_error("partition: rank " + std::to_string(other) + " asked for node " +
                               std::to_string(node) + ", which rank " + std::to_string(rank) + " does not own");
      send.push_back(localIndex[node]);
    }
    domain.receiveNodes.push_back(std::move(receive));
    domain.sendNodes.push_back(std::move(send));
  }
  return domain;
}

std::vector<PartitionRow> gatherPartitionRows(const PartitionRow& mine, const Communicator& communicator) {
  const auto all = communicator.gather(std::vector<long long>{mine.ownedNodes, mine.haloNodes, mine.exchangedNodes,
                                                              mine.elements, mine.bonds, mine.neighbours});
  std::vector<PartitionRow> rows;
  for (std::size_t k = 0; k + 5 < all.size(); k += 6)
    rows.push_back({all[k], all[k + 1], all[k + 2], all[k + 3], all[k + 4], all[k + 5]});
  return rows;
}

}  // namespace perishell::parallel
