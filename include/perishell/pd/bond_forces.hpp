#pragma once
// The bond force kernel: internal forces and moments of all intact microbeam bonds
// (model.md §2), energy-based breaking (model.md §3, paper eq. 24-28) and the strain and
// fracture energies per node. Two mappings of the same physics, selected in the deck
// (peridynamics.force-kernel), both written once for every Kokkos backend:
// - BondScatter, the paper's bond mapping: one thread per half bond, both ends' forces
//   scattered with atomic_add;
// - NodeGather: one thread per node over its full neighbour row, no atomics; every bond is
//   evaluated twice, always as (lower, higher) node so both ends see bit-identical results.
// A bond whose micropotential reaches w_c still acts in this step and is written as broken
// into intactNext, by exactly one thread (the bond's thread, or the lower node's).
#include <perishell/io/deck.hpp>
#include <perishell/pd/pd_body.hpp>

namespace perishell::pd {

// Per-node outputs; forces, strainEnergy and fractureEnergy are accumulated into (the
// caller zeroes them), strainEnergy may be empty to skip it.
template <class MemorySpaceT>
struct BondForceOutputs {
  NodalVectorView<MemorySpaceT> forces;      // [N, N m]
  VectorView<MemorySpaceT> strainEnergy;     // [J]; optional
  VectorView<MemorySpaceT> fractureEnergy;   // [J] released by bonds breaking
  BondFlagView<MemorySpaceT> intactNext;     // written for every bond
};

// The micromoduli of half bond b: the body's times the bond's stiffness scales (pd_body.hpp).
template <class MemorySpaceT>
KOKKOS_INLINE_FUNCTION Micromoduli bondMicromoduli(const PdBody<MemorySpaceT>& body, RowOffset halfBond) {
  return correctedMicromoduli(body.micromoduli, body.stiffnessScale(halfBond, 0), body.stiffnessScale(halfBond, 1));
}

// w_c of model.md §3 times the bond's stretch scale, the factor on c_ax: pure stretch then
// still breaks a bond at exactly s_c of model.md §3 (both sides of 1/2 c_ax s^2 xi = w_c
// carry the same factor), and a broken bond releases its scaled share of G_c.
template <class MemorySpaceT>
KOKKOS_INLINE_FUNCTION double criticalMicropotential(const PdBody<MemorySpaceT>& body, RowOffset halfBond,
                                                     double referenceLength) {
  return body.criticalMicropotentialPerLength * referenceLength * body.stiffnessScale(halfBond, 0);
}

// V_i V_j beta: the bond's share of the double volume integral (model.md §1-2).
template <class MemorySpaceT>
KOKKOS_INLINE_FUNCTION double bondVolumeWeight(const PdBody<MemorySpaceT>& body, LocalIndex i, LocalIndex j,
                                               RowOffset halfBond) {
  return body.volumes(i) * body.volumes(j) * body.bonds.volumeFactor(halfBond);
}

namespace detail {

// One end from the kinematics itself (used where no node-frame pass ran: the tangent).
template <class MemorySpaceT>
KOKKOS_INLINE_FUNCTION void loadBondEnd(const PdBody<MemorySpaceT>& body, const PdKinematics<MemorySpaceT>& state,
                                        LocalIndex node, MicrobeamEnd& end) {
  for (int k = 0; k < 3; ++k) {
    end.referencePosition[k] = body.referencePositions(node, k);
    end.position[k] = end.referencePosition[k] + state.displacements(node, k);
    end.referenceNormal[k] = body.referenceNormals(node, k);
  }
  const double q[4] = {state.rotations(node, 0), state.rotations(node, 1), state.rotations(node, 2),
                       state.rotations(node, 3)};
  rotation::toMatrix(q, end.rotation);
}

// One end from the node frames of this evaluation (updateNodeFrames): the same numbers.
template <class MemorySpaceT>
KOKKOS_INLINE_FUNCTION void loadFramedBondEnd(const PdBody<MemorySpaceT>& body, const PdKinematics<MemorySpaceT>& state,
                                              LocalIndex node, MicrobeamEnd& end) {
  for (int k = 0; k < 3; ++k) {
    end.referencePosition[k] = body.referencePositions(node, k);
    end.position[k] = state.nodeFrames(node, k);
    end.referenceNormal[k] = body.referenceNormals(node, k);
  }
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) end.rotation[r][k] = state.nodeFrames(node, 3 + 3 * r + k);
}

}  // namespace detail

// Every node's current position and rotation matrix, once per evaluation, into
// state.nodeFrames: a bond then reads them instead of rebuilding both ends (the quaternion
// to matrix conversion and X + u were repeated for each of a node's ~28 bonds, twice in
// node-gather). One thread per entry, so that a warp writes 32 consecutive doubles: one
// thread per node wrote 12 doubles 96 bytes apart per instruction (1e6 nodes on the H200,
// ncu: 167 us per node, 118 us per entry).
template <class ExecutionSpaceT, class MemorySpaceT>
void updateNodeFrames(const ExecutionSpaceT& space, const PdBody<MemorySpaceT>& body,
                      const PdKinematics<MemorySpaceT>& state) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  constexpr RowOffset entriesPerNode = 12;
  Kokkos::parallel_for(
      "perishell::pd::updateNodeFrames",
      queuedRangePolicy(space, RowOffset(0), entriesPerNode * body.numNodes()),
      KOKKOS_LAMBDA(const RowOffset index) {
        const auto node = static_cast<LocalIndex>(index / entriesPerNode);
        const int entry = static_cast<int>(index % entriesPerNode);
        state.nodeFrames(node, entry) =
            entry < 3 ? body.referencePositions(node, entry) + state.displacements(node, entry)
                      : rotation::matrixEntry([&](int k) { return state.rotations(node, k); }, (entry - 3) / 3,
                                               (entry - 3) % 3);
      });
}

// The same for the listed nodes only (the others' frames are current): a distributed step
// refreshes the halo nodes its exchange just wrote (solvers/explicit/central_difference.hpp).
template <class ExecutionSpaceT, class MemorySpaceT>
void updateNodeFrames(const ExecutionSpaceT& space, const PdBody<MemorySpaceT>& body,
                      const PdKinematics<MemorySpaceT>& state, const Kokkos::View<const LocalIndex*, MemorySpaceT>& nodes) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  constexpr RowOffset entriesPerNode = 12;
  Kokkos::parallel_for(
      "perishell::pd::updateListedNodeFrames",
      queuedRangePolicy(space, RowOffset(0), entriesPerNode * static_cast<RowOffset>(nodes.extent(0))),
      KOKKOS_LAMBDA(const RowOffset index) {
        const LocalIndex node = nodes(static_cast<std::size_t>(index / entriesPerNode));
        const int entry = static_cast<int>(index % entriesPerNode);
        state.nodeFrames(node, entry) =
            entry < 3 ? body.referencePositions(node, entry) + state.displacements(node, entry)
                      : rotation::matrixEntry([&](int k) { return state.rotations(node, k); }, (entry - 3) / 3,
                                               (entry - 3) % 3);
      });
}

// Whether computeBondForces first brings every node's frame up to date (updateNodeFrames), or
// the caller did (a step evaluating its bonds in parts, or only the frames its bonds read).
enum class NodeFrames { Update, Current };

template <class ExecutionSpaceT, class MemorySpaceT>
void computeBondForces(const ExecutionSpaceT& space, deck::ForceKernel kernel, const PdBody<MemorySpaceT>& body,
                       const PdKinematics<MemorySpaceT>& state, const BondFlagView<MemorySpaceT>& intact,
                       const BondForceOutputs<MemorySpaceT>& out, NodeFrames frames = NodeFrames::Update) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  const bool withStrainEnergy = out.strainEnergy.extent(0) > 0;
  if (frames == NodeFrames::Update) updateNodeFrames(space, body, state);
  if (kernel == deck::ForceKernel::BondScatter) {
    Kokkos::parallel_for(
        "perishell::pd::computeBondForces::bondScatter",
        queuedRangePolicy(space, RowOffset(0), body.bonds.numBonds()), KOKKOS_LAMBDA(const RowOffset b) {
          const LocalIndex nodes[2] = {body.bonds.halfBonds(b, 0), body.bonds.halfBonds(b, 1)};
          if (!intact(b)) {
            out.intactNext(b) = 0;
            return;
          }
          MicrobeamEnd ends[2];
          detail::loadFramedBondEnd(body, state, nodes[0], ends[0]);
          detail::loadFramedBondEnd(body, state, nodes[1], ends[1]);
          const double xi = body.bonds.referenceLength(b);
          MicrobeamResponse response;
          evaluateMicrobeam(bondMicromoduli(body, b), ends[0], ends[1], xi, response);
          const double weight = bondVolumeWeight(body, nodes[0], nodes[1], b);
          const bool breaks = response.micropotential >= criticalMicropotential(body, b, xi);
          out.intactNext(b) = breaks ? 0 : 1;
          const double halfEnergy = 0.5 * weight * response.micropotential;
          for (int end = 0; end < 2; ++end) {
            for (int k = 0; k < 3; ++k) {
              Kokkos::atomic_add(&out.forces(nodes[end], k), weight * response.force[end][k]);
              Kokkos::atomic_add(&out.forces(nodes[end], 3 + k), weight * response.moment[end][k]);
            }
            if (withStrainEnergy) Kokkos::atomic_add(&out.strainEnergy(nodes[end]), halfEnergy);
            if (breaks) Kokkos::atomic_add(&out.fractureEnergy(nodes[end]), halfEnergy);
          }
        });
    return;
  }
  // The default launch, not queuedRangePolicy: the functor as a kernel argument raised this
  // kernel from 164 to 173 registers per thread on sm_90, and the 1e6-node step from 2.40 to
  // 2.49 ms on the H200 (perf/bond_forces); the kernels around it still queue.
  Kokkos::parallel_for(
      "perishell::pd::computeBondForces::nodeGather",
      Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, body.numNodes()), KOKKOS_LAMBDA(const LocalIndex node) {
        // A row left out (pd::restrictRows) adds nothing: skip loading its node.
        if (body.bonds.offsets(node) == body.bonds.offsets(node + 1)) return;
        MicrobeamEnd self, other;
        detail::loadFramedBondEnd(body, state, node, self);
        double sum[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
        double strainEnergy = 0.0, fractureEnergy = 0.0;
        for (RowOffset entry = body.bonds.offsets(node); entry < body.bonds.offsets(node + 1); ++entry) {
          const LocalIndex neighbour = body.bonds.neighbours(entry);
          const RowOffset b = body.bonds.fullToHalf(entry);
          const bool owner = node < neighbour;
          if (!intact(b)) {
            if (owner) out.intactNext(b) = 0;
            continue;
          }
          detail::loadFramedBondEnd(body, state, neighbour, other);
          const double xi = body.bonds.referenceLength(b);
          MicrobeamResponse response;
          const LocalIndex lower = owner ? node : neighbour, higher = owner ? neighbour : node;
          const Micromoduli c = bondMicromoduli(body, b);
          if (owner)
            evaluateMicrobeam(c, self, other, xi, response);
          else
            evaluateMicrobeam(c, other, self, xi, response);
          const int selfEnd = owner ? 0 : 1;
          const double weight = bondVolumeWeight(body, lower, higher, b);
          for (int k = 0; k < 3; ++k) {
            sum[k] += weight * response.force[selfEnd][k];
            sum[3 + k] += weight * response.moment[selfEnd][k];
          }
          const bool breaks = response.micropotential >= criticalMicropotential(body, b, xi);
          if (owner) out.intactNext(b) = breaks ? 0 : 1;
          strainEnergy += 0.5 * weight * response.micropotential;
          if (breaks) fractureEnergy += 0.5 * weight * response.micropotential;
        }
        for (int k = 0; k < 6; ++k) out.forces(node, k) += sum[k];
        if (withStrainEnergy) out.strainEnergy(node) += strainEnergy;
        if (fractureEnergy > 0.0) out.fractureEnergy(node) += fractureEnergy;
      });
}

}  // namespace perishell::pd
