#pragma once
// The model a deck describes, before any solver: the shell mesh with its named sets, the
// kind of every element (CCM or PD, model.md §1), the PD nodes, and the checks that tie the
// deck to the mesh (every set a support, load or zone names exists). Host data built once
// at setup; buildPdBonds moves the PD nodes to the device and builds their bonds there.
#include <perishell/io/deck.hpp>
#include <perishell/mesh/mesh_sets.hpp>
#include <perishell/pd/make_body.hpp>

#include <cstdint>
#include <vector>

namespace perishell::model {

struct Model {
  Deck deck;
  mesh::ShellMesh shell;
  // 1 where the element is PD, 0 where it is CCM (model.md §1).
  Kokkos::View<std::uint8_t*, Kokkos::HostSpace> elementIsPd;
  LocalIndex numPdElements = 0;
  // Nodes of PD elements, ascending: the nodes that carry bonds.
  Kokkos::View<LocalIndex*, Kokkos::HostSpace> pdNodes;
  // Distinct (node, DOF) pairs that supports prescribe.
  long long numConstrainedDofs = 0;

  double gridSpacing() const { return deck.mesh.spacing; }
  double horizon() const { return deck.peridynamics.horizonFactor * deck.mesh.spacing; }
  std::vector<mesh::CrackSegment> preCrackSegments() const {
    std::vector<mesh::CrackSegment> cracks;
    for (const auto& crack : deck.mesh.preCracks) cracks.push_back(crack.segment);
    return cracks;
  }
  // The paper's "PD element ratio": PD elements / all elements.
  double pdRatio() const {
    return shell.mesh.numElements() > 0 ? double(numPdElements) / shell.mesh.numElements() : 0.0;
  }
  // The paper counts elements x 4 nodes x 6 DOF (model.md §7); the true count is
  // 6 per node less the prescribed ones.
  long long paperDofCount() const { return 24LL * shell.mesh.numElements(); }
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
                             model.preCrackSegments())
      .bonds;
}

}  // namespace perishell::model
