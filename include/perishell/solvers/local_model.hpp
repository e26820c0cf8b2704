#pragma once
// One rank's part of a model in a distributed run (docs/parallel.md): its nodes and halo
// (parallel/domain.hpp), the coupled bodies among them, the loads and supports on them, and
// the halo exchange. Only this part is on the device: no rank holds the whole bond list.
#include <perishell/coupling/make_coupled_model.hpp>
#include <perishell/parallel/domain.hpp>
#include <perishell/parallel/node_distribution.hpp>
#include <perishell/solvers/model_actions.hpp>

#include <iomanip>
#include <ostream>
#include <sstream>

namespace perishell::solvers {

template <class ExecutionSpaceT>
struct LocalModel {
  using MemorySpace = typename ExecutionSpaceT::memory_space;
  parallel::LocalDomain domain;
  coupling::CoupledBodies<MemorySpace> bodies;
  ExternalActions<MemorySpace> actions;
  parallel::NodeDistribution<MemorySpace> distribution;

  // This rank's line of the partition table: bonds and shell elements count on the rank
  // owning their first node.
  parallel::PartitionRow partitionRow() const {
    parallel::PartitionRow row;
    row.ownedNodes = domain.numOwned();
    row.haloNodes = domain.numNodes() - row.ownedNodes;
    for (const auto& nodes : domain.receiveNodes) row.exchangedNodes += static_cast<long long>(nodes.size());
    for (const LocalIndex e : bodies.ccmElements) row.elements += domain.owned[domain.mesh.quads(e, 0)];
    const auto halfBonds = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, bodies.pdBody.bonds.halfBonds);
    for (std::size_t b = 0; b < halfBonds.extent(0); ++b) row.bonds += domain.owned[halfBonds(b, 0)];
    row.neighbours = static_cast<long long>(domain.ranks.size());
    return row;
  }
};

template <class ExecutionSpaceT>
LocalModel<ExecutionSpaceT> makeLocalModel(const ExecutionSpaceT& space, const model::Model& model,
                                           const parallel::Communicator& communicator) {
  using MemorySpace = typename ExecutionSpaceT::memory_space;
  LocalModel<ExecutionSpaceT> local;
  local.domain = parallel::makeLocalDomain(model, parallel::partitionNodes(model, communicator), communicator);
  auto inputs = coupling::couplingInputs(model);
  inputs.firstHeldNode = local.domain.supportLayer.firstNode;
  inputs.supportLayer = local.domain.supportLayer;
  local.bodies = coupling::makeCoupledBodies(space, local.domain.mesh, local.domain.elementIsPd, inputs);
  local.actions = makeExternalActions<MemorySpace>(model, local.domain.nodes, &local.domain.supportLayer);
  local.distribution = parallel::NodeDistribution<MemorySpace>(local.domain, communicator);
  return local;
}

// The partition table on the root's log: nodes, halo, elements, bonds and neighbours per rank,
// and the imbalance of owned bonds + elements (max over mean); doublesPerNode: what the
// solver's exchange sends per halo node, once per `exchangeEvery` (a step, a Krylov iteration).
// Collective.
inline void printPartition(const parallel::PartitionRow& mine, int doublesPerNode, const parallel::Communicator& communicator,
                           std::ostream& log, const char* exchangeEvery = "step") {
  const auto rows = parallel::gatherPartitionRows(mine, communicator);
  if (!communicator.root()) return;
  log << "partition: " << rows.size() << " ranks (METIS on the node graph, weighted by bonds and elements)\n"
      << "  rank  owned nodes  halo nodes  exchanged  shell elements        bonds  neighbours\n"
      << "        (halo: for the set-up; exchanged: the halo nodes whose state owned nodes read;\n"
      << "         shell elements and bonds: those whose first node it owns)\n";
  double largest = 0.0, total = 0.0;
  long long exchangedNodes = 0;
  for (std::size_t r = 0; r < rows.size(); ++r) {
    const auto& row = rows[r];
    log << std::setw(6) << r << std::setw(13) << row.ownedNodes << std::setw(12) << row.haloNodes << std::setw(11)
        << row.exchangedNodes << std::setw(16)
        << row.elements << std::setw(13) << row.bonds << std::setw(12) << row.neighbours << "\n";
    const double work = double(row.bonds) + 30.0 * double(row.elements) + double(row.ownedNodes);
    largest = std::max(largest, work);
    exchangedNodes += row.exchangedNodes;
    total += work;
  }
  std::ostringstream imbalance;
  imbalance.precision(3);
  imbalance << largest / (total / double(rows.size()));
  log << "  imbalance (max / mean of bonds + 30 x shell elements + nodes): " << imbalance.str() << "\n"
      << "  halo exchange per " << exchangeEvery << ": " << exchangedNodes << " halo nodes x " << doublesPerNode << " doubles = "
      << exchangedNodes * doublesPerNode * 8 << " bytes sent over all ranks\n";
}

}  // namespace perishell::solvers
