#pragma once
// The model a deck describes, before any solver: the shell mesh with its named sets, the
// kind of every element (CCM or PD, model.md §1), the PD nodes, and the checks that tie the
// deck to the mesh (every set a support, load or zone names exists). Host data built once
// at setup; buildPdBonds moves the PD nodes to the device and builds their bonds there.
#include <perishell/io/deck.hpp>
#include <perishell/mesh/mesh_sets.hpp>
#include <perishell/mesh/support_layer.hpp>
#include <perishell/pd/make_body.hpp>

#include <algorithm>
#include <cstdint>
#include <vector>

namespace perishell::model {

struct Model {
  Deck deck;
  // The mesh with the support layer appended (its nodes and elements after the deck's own).
  mesh::ShellMesh shell;
  mesh::SupportLayer supportLayer;
  // 1 where the element is PD, 0 where it is CCM (model.md §1).
  Kokkos::View<std::uint8_t*, Kokkos::HostSpace> elementIsPd;
  LocalIndex numPdElements = 0;
  // Nodes of PD elements, ascending: the nodes that carry bonds (the support layer's too).
  Kokkos::View<LocalIndex*, Kokkos::HostSpace> pdNodes;
  // Distinct (node, DOF) pairs that supports prescribe.
  long long numConstrainedDofs = 0;
  // Distinct nodes of the deck's mesh at one point (a slit's faces, an unmerged seam): no bond
  // joins them or crosses between their faces. The first pair, and how many.
  std::pair<LocalIndex, LocalIndex> firstCoincidentPair{-1, -1};
  long long numCoincidentPairs = 0;

  double gridSpacing() const { return deck.mesh.spacing; }
  double horizon() const { return deck.peridynamics.horizonFactor * deck.mesh.spacing; }
  std::vector<mesh::CrackSegment> preCrackSegments() const {
    std::vector<mesh::CrackSegment> cracks;
    for (const auto& crack : deck.mesh.preCracks) cracks.push_back(crack.segment);
    return cracks;
  }
  // The deck's own mesh, without the support layer: what results are written on.
  LocalIndex numMeshNodes() const { return std::min(supportLayer.firstNode, shell.mesh.numNodes()); }
  LocalIndex numMeshElements() const { return std::min(supportLayer.firstElement, shell.mesh.numElements()); }
  mesh::HostQuadMesh outputMesh() const {
    return {Kokkos::subview(shell.mesh.coordinates, std::make_pair(LocalIndex(0), numMeshNodes()), Kokkos::ALL),
            Kokkos::subview(shell.mesh.quads, std::make_pair(LocalIndex(0), numMeshElements()), Kokkos::ALL)};
  }
  LocalIndex numLayerNodes() const { return shell.mesh.numNodes() - numMeshNodes(); }
  // The nodes a support holds: its set's, and the support layer's beyond the set's edges
  // (held, or mirrored: their reactions are the layer's, assembly/mirror_images.hpp).
  std::vector<LocalIndex> supportNodes(const deck::Support& support) const;
  // The paper's "PD element ratio": PD elements / all elements (of the deck's mesh).
  double pdRatio() const { return numMeshElements() > 0 ? double(numPdElements) / numMeshElements() : 0.0; }
  // The paper counts elements x 4 nodes x 6 DOF (model.md §7); the true count is
  // 6 per node less the prescribed ones.
  long long paperDofCount() const { return 24LL * numMeshElements(); }
  long long freeDofCount() const { return 6LL * shell.mesh.numNodes() - numConstrainedDofs; }
};

// Builds the mesh (generator or Gmsh file), adds the deck's node sets, flags PD elements
// and checks set references. Throws DeckError naming the deck key for every inconsistency
// between deck and mesh (unknown set, empty set, a pre-crack outside the mesh's PD zone).
Model buildModel(const Deck& deck);

// The bonds among the PD nodes (indices into model.pdNodes), built on the device.
template <class ExecutionSpaceT>
pd::BondList<typename ExecutionSpaceT::memory_space> buildPdBonds(const ExecutionSpaceT& space,
                                                                  const Model& model) {
  return pd::buildBondsAmong(space, model.shell.mesh, model.pdNodes, model.horizon(), model.gridSpacing(),
                             model.preCrackSegments(), model.numMeshNodes())
      .bonds;
}

}  // namespace perishell::model
