#pragma once
// The CCM part of a model on one memory space, and its two kernels (paper §3.2.1, element
// mapping): internal forces scattered with atomic_add, and the tangent added into the CRS
// values through the pattern's precomputed slots. One thread per element; the element
// itself is shell/mitc4_shell.hpp.
#include <perishell/mesh/quad_mesh.hpp>
#include <perishell/pd/pd_body.hpp>
#include <perishell/shell/mitc4_shell.hpp>

#include <sstream>
#include <stdexcept>
#include <vector>

namespace perishell::shell {

template <class MemorySpaceT>
struct ShellBody {
  CoordinateView<MemorySpaceT> referencePositions;  // every mesh node [m]
  QuadConnectivityView<MemorySpaceT> quads;          // the CCM elements
  // K_l of each element in its reference frame (24 x 24, cached: the element is flat).
  Kokkos::View<double* [24][24], Kokkos::LayoutRight, MemorySpaceT> localStiffness;
  // Per element and Gauss point, the factor on the membrane and bending blocks of D that
  // K_l was built with: 1 for a plain CCM element, 1 - alpha_bar in the PD-CCM transition
  // (model.md §4, coupling/morphing.hpp).
  Kokkos::View<double* [4], Kokkos::LayoutRight, MemorySpaceT> membraneBendingScale;

  LocalIndex numElements() const { return static_cast<LocalIndex>(quads.extent(0)); }
};

namespace detail {

template <class MemorySpaceT>
KOKKOS_INLINE_FUNCTION void loadElement(const ShellBody<MemorySpaceT>& body, const pd::PdKinematics<MemorySpaceT>& state,
                                        LocalIndex element, double reference[4][3], double current[4][3],
                                        double rotations[4][3][3]) {
  for (int a = 0; a < 4; ++a) {
    const LocalIndex node = body.quads(element, a);
    for (int k = 0; k < 3; ++k) {
      reference[a][k] = body.referencePositions(node, k);
      current[a][k] = reference[a][k] + state.displacements(node, k);
    }
    const double q[4] = {state.rotations(node, 0), state.rotations(node, 1), state.rotations(node, 2),
                         state.rotations(node, 3)};
    rotation::toMatrix(q, rotations[a]);
  }
}

}  // namespace detail

// The CCM elements of a mesh (body element k is mesh element ccmElements[k]) with their
// section, the membrane and bending blocks of D scaled per element and Gauss point by
// membraneBendingScale (numElements x 4, on the device). Throws std::invalid_argument
// naming the first degenerate element.
template <class ExecutionSpaceT>
ShellBody<typename ExecutionSpaceT::memory_space> makeShellBody(
    const ExecutionSpaceT& space, const mesh::HostQuadMesh& mesh, const std::vector<LocalIndex>& ccmElements,
    const ShellSection& section,
    const Kokkos::View<double* [4], Kokkos::LayoutRight, typename ExecutionSpaceT::memory_space>& membraneBendingScale) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  using MemorySpaceT = typename ExecutionSpaceT::memory_space;
  if (membraneBendingScale.extent(0) != ccmElements.size()) {
    std::ostringstream message;
    message << "makeShellBody: " << membraneBendingScale.extent(0) << " rows of membrane-bending scales for "
            << ccmElements.size() << " elements";
    throw std::invalid_argument(message.str());
  }
  QuadConnectivityView<Kokkos::HostSpace> quads("ccm quads", ccmElements.size());
  for (std::size_t k = 0; k < ccmElements.size(); ++k) {
    double reference[4][3];
    for (int a = 0; a < 4; ++a) {
      quads(k, a) = mesh.quads(ccmElements[k], a);
      for (int d = 0; d < 3; ++d) reference[a][d] = mesh.coordinates(quads(k, a), d);
    }
    checkShellElement(reference, ccmElements[k]);
  }
  ShellBody<MemorySpaceT> body;
  body.referencePositions = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, mesh.coordinates);
  body.quads = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, quads);
  body.localStiffness = decltype(body.localStiffness)("shell local stiffness", ccmElements.size());
  body.membraneBendingScale = membraneBendingScale;
  const auto b = body;
  Kokkos::parallel_for(
      "perishell::shell::localStiffness", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, b.numElements()),
      KOKKOS_LAMBDA(const LocalIndex e) {
        double reference[4][3];
        for (int a = 0; a < 4; ++a)
          for (int d = 0; d < 3; ++d) reference[a][d] = b.referencePositions(b.quads(e, a), d);
        const double scale[4] = {b.membraneBendingScale(e, 0), b.membraneBendingScale(e, 1),
                                 b.membraneBendingScale(e, 2), b.membraneBendingScale(e, 3)};
        double K[24][24];
        shellLocalStiffness(reference, section, scale, K);
        for (int r = 0; r < 24; ++r)
          for (int s = 0; s < 24; ++s) b.localStiffness(e, r, s) = K[r][s];
      });
  return body;
}

// The same with the full section everywhere (a model without PD-CCM coupling).
template <class ExecutionSpaceT>
ShellBody<typename ExecutionSpaceT::memory_space> makeShellBody(const ExecutionSpaceT& space,
                                                                const mesh::HostQuadMesh& mesh,
                                                                const std::vector<LocalIndex>& ccmElements,
                                                                const ShellSection& section) {
  Kokkos::View<double* [4], Kokkos::LayoutRight, typename ExecutionSpaceT::memory_space> fullSection(
      "shell membrane-bending scale", ccmElements.size());
  Kokkos::deep_copy(space, fullSection, 1.0);
  return makeShellBody(space, mesh, ccmElements, section, fullSection);
}

// forces -= internal forces of every element (the caller's forces are the loads acting on
// the nodes, so the result is the out-of-balance force). With a non-empty energy view, each
// element's energy W = 1/2 d^T K_l d is also added to it, a quarter per node.
template <class ExecutionSpaceT, class MemorySpaceT>
void subtractShellForces(const ExecutionSpaceT& space, const ShellBody<MemorySpaceT>& body,
                         const pd::PdKinematics<MemorySpaceT>& state, const pd::NodalVectorView<MemorySpaceT>& forces,
                         const VectorView<MemorySpaceT>& energy = {}) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  const bool withEnergy = energy.extent(0) > 0;
  Kokkos::parallel_for(
      "perishell::shell::subtractShellForces", queuedRangePolicy(space, 0, body.numElements()),
      KOKKOS_LAMBDA(const LocalIndex e) {
        double reference[4][3], current[4][3], rotations[4][3][3], localStiffness[24][24], force[24];
        detail::loadElement(body, state, e, reference, current, rotations);
        for (int r = 0; r < 24; ++r)
          for (int s = 0; s < 24; ++s) localStiffness[r][s] = body.localStiffness(e, r, s);
        const double elementEnergy = shellInternalForce(reference, current, rotations, localStiffness, force);
        for (int a = 0; a < 4; ++a) {
          for (int d = 0; d < 6; ++d) Kokkos::atomic_add(&forces(body.quads(e, a), d), -force[6 * a + d]);
          if (withEnergy) Kokkos::atomic_add(&energy(body.quads(e, a)), 0.25 * elementEnergy);
        }
      });
}

// Per node, the elements' diagonal stiffness: the mean of the three translational and of the
// three rotational diagonal entries of K_l, summed over the node's elements (for the
// explicit solver's rotary-inertia scaling, solvers/explicit/nodal_inertia.hpp).
template <class ExecutionSpaceT, class MemorySpaceT>
void addShellNodalStiffness(const ExecutionSpaceT& space, const ShellBody<MemorySpaceT>& body,
                            const VectorView<MemorySpaceT>& translational, const VectorView<MemorySpaceT>& rotational) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  Kokkos::parallel_for(
      "perishell::shell::addShellNodalStiffness", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, body.numElements()),
      KOKKOS_LAMBDA(const LocalIndex e) {
        for (int a = 0; a < 4; ++a) {
          double moving = 0.0, turning = 0.0;
          for (int d = 0; d < 3; ++d) {
            moving += body.localStiffness(e, 6 * a + d, 6 * a + d) / 3.0;
            turning += body.localStiffness(e, 6 * a + 3 + d, 6 * a + 3 + d) / 3.0;
          }
          Kokkos::atomic_add(&translational(body.quads(e, a)), moving);
          Kokkos::atomic_add(&rotational(body.quads(e, a)), turning);
        }
      });
}

// Adds every element's symmetric tangent K_T (the one CG solves with) into the CRS values;
// the pattern's element e is body element e.
template <class ExecutionSpaceT, class MemorySpaceT, class PatternT>
void assembleShellTangent(const ExecutionSpaceT& space, const ShellBody<MemorySpaceT>& body,
                          const pd::PdKinematics<MemorySpaceT>& state, const PatternT& pattern,
                          const VectorView<MemorySpaceT>& values, TangentForm form = TangentForm::Symmetric) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  Kokkos::parallel_for(
      "perishell::shell::assembleShellTangent", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, body.numElements()),
      KOKKOS_LAMBDA(const LocalIndex e) {
        double reference[4][3], current[4][3], rotations[4][3][3], localStiffness[24][24], force[24], tangent[24][24];
        detail::loadElement(body, state, e, reference, current, rotations);
        for (int r = 0; r < 24; ++r)
          for (int s = 0; s < 24; ++s) localStiffness[r][s] = body.localStiffness(e, r, s);
        shellTangent(reference, current, rotations, localStiffness, force, tangent);
        if (form == TangentForm::Exact) addRotationAsymmetry(force, tangent);
        pattern.atomicAddElementMatrix(e, tangent, values);
      });
}

}  // namespace perishell::shell
