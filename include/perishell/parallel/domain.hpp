#pragma once
// Domain decomposition of a model's mesh nodes over the ranks of a distributed run
// (docs/parallel.md). Every rank reads the deck and builds the host model (mesh, sets,
// support layer); each then builds only its local part of the device model: its owned nodes
// and a halo of the nodes around them, with the bonds and elements among those. Local
// numbering keeps the global order, so a node's bonds and elements are visited in the same
// order on any rank count, and the owned nodes' arithmetic is the single-rank run's.
//
// The halo is every node within haloRadius of an owned node, closed over elements (a halo
// node has its elements). Its radius covers what an owned node's update reads: bonds (delta),
// the bond constants of a neighbour (its own neighbourhood, delta more), the morphing field
// of the transition (its width) and element neighbours. After each step the solver sets the
// state of the halo nodes within stateReadRadius of an owned node to their owners'.
#include <perishell/mesh/quad_mesh.hpp>
#include <perishell/mesh/support_layer.hpp>
#include <perishell/parallel/communicator.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace perishell::model {
struct Model;
}

namespace perishell::parallel {

// The owning rank of every mesh node (the support layer's too): METIS k-way on the node graph
// of the elements, each node weighted by its work (its bonds if PD, its share of CCM
// elements); a mirrored layer node goes with the node it mirrors. Deterministic (METIS'
// default seed); computed on the root and broadcast. Throws std::invalid_argument when there
// are more ranks than the model can give nodes to.
std::vector<int> partitionNodes(const model::Model& model, const Communicator& communicator);

// What an owned node's set-up reads, at most: 3 delta + the transition width + 2 element sizes
// (see the header comment).
double haloRadius(const model::Model& model);
// Whose state an owned node's step reads, at most: its bonds' and elements' nodes, and for a
// mirror image's master the image's bonds (2 delta + 2 element sizes). Only these halo nodes
// are exchanged; the rest of the halo serves the set-up and may drift after it, unread.
double stateReadRadius(const model::Model& model);

struct LocalDomain {
  std::vector<LocalIndex> nodes;     // the mesh node of every local node, ascending
  std::vector<LocalIndex> elements;  // the mesh element of every local element, ascending
  std::vector<std::uint8_t> owned;   // 1 where this rank owns the local node
  mesh::HostQuadMesh mesh;           // local coordinates and connectivity
  Kokkos::View<std::uint8_t*, Kokkos::HostSpace> elementIsPd;  // per local element
  mesh::SupportLayer supportLayer;   // renumbered: first layer node and element, mirror images, shares
  // Halo exchange: for neighbour ranks[k], the local nodes whose state it sends us (ascending
  // global order; those within stateReadRadius of an owned node) and the local nodes we own
  // that it needs.
  std::vector<int> ranks;
  std::vector<std::vector<LocalIndex>> receiveNodes, sendNodes;

  LocalIndex numNodes() const { return static_cast<LocalIndex>(nodes.size()); }
  long long numOwned() const;
};

LocalDomain makeLocalDomain(const model::Model& model, const std::vector<int>& owner, const Communicator& communicator);

// One line per rank on the root (empty elsewhere): owned and halo nodes, elements, bonds, and
// the imbalance of owned work (max over mean). Collective.
struct PartitionRow {
  long long ownedNodes = 0, haloNodes = 0, exchangedNodes = 0, elements = 0, bonds = 0, neighbours = 0;
};
std::vector<PartitionRow> gatherPartitionRows(const PartitionRow& mine, const Communicator& communicator);

}  // namespace perishell::parallel
