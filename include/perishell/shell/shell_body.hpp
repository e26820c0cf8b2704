#pragma once
// The CCM part of a model on one memory space, and its kernels (paper §3.2.1, element
// mapping): internal forces scattered with atomic_add, and the tangent added into the CRS
// values through the pattern's precomputed slots. One thread per element; the elements
// themselves are shell/mitc4_shell.hpp (both solvers) and shell/one_point_shell.hpp
// (the explicit solver's default).
#include <perishell/mesh/node_incidence.hpp>
#include <perishell/mesh/quad_mesh.hpp>
#include <perishell/pd/pd_body.hpp>
#include <perishell/shell/explicit_triangle.hpp>
#include <perishell/shell/mitc4_shell.hpp>
#include <perishell/shell/one_point_shell.hpp>

#include <algorithm>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace perishell::shell {

// Which element the CCM part uses: the MITC4 element (shell/mitc4_shell.hpp; both solvers;
// its 24 x 24 K_l cached per element) or the one-point element (shell/one_point_shell.hpp;
// explicit only; nothing cached). Triangles of either kind are shell/mitc3_triangle.hpp's:
// from the cached K_l (Mitc4), or with forces written out (OnePoint,
// shell/explicit_triangle.hpp).
enum class ShellElementKind { Mitc4, OnePoint };

// How the one-point element's forces reach the nodes: Scatter, one thread per element adding
// its 24 forces with atomic_add; Gather, one thread per element writing them to a buffer,
// then one thread per node summing its elements' entries (no atomics). Measured in
// perf/explicit_shell.cpp (docs/explicit.md): each backend takes its faster one.
enum class ElementForceAssembly { Scatter, Gather };

template <class MemorySpaceT>
struct ShellBody {
  ShellElementKind kind = ShellElementKind::Mitc4;
  ShellSection section;
  CoordinateView<MemorySpaceT> referencePositions;  // every mesh node [m]
  QuadConnectivityView<MemorySpaceT> quads;          // the CCM elements
  // MITC4 only: K_l of each element in its reference frame (24 x 24, cached: the element is flat).
  Kokkos::View<double* [24][24], Kokkos::LayoutRight, MemorySpaceT> localStiffness;
  // Per element and Gauss point, the factor on the membrane and bending blocks of D that
  // K_l was built with: 1 for a plain CCM element, 1 - alpha_bar in the PD-CCM transition
  // (model.md §4, coupling/morphing.hpp). The one-point element takes their mean.
  Kokkos::View<double* [4], Kokkos::LayoutRight, MemorySpaceT> membraneBendingScale;
  // The node-to-element incidence (mesh/node_incidence.hpp: node n's entries
  // nodeElementOffsets(n) .. (n + 1), each 4 e + a for corner a of element e), for sums over a
  // node's elements in a fixed order.
  Kokkos::View<RowOffset*, MemorySpaceT> nodeElementOffsets;
  Kokkos::View<LocalIndex*, MemorySpaceT> nodeElementEntries;
  // One-point only: the force assembly, and for Gather the elements' forces and energies (24
  // forces, strain, hourglass) between the two kernels.
  ElementForceAssembly assembly = ElementForceAssembly::Scatter;
  Kokkos::View<double* [26], Kokkos::LayoutRight, MemorySpaceT> elementForces;
  // One-point only: each element's ExplicitReference (shell/corotational_projector.hpp), in
  // the memory space's layout (per element contiguous on a host, coalesced on a GPU).
  Kokkos::View<double* [explicitReferenceSize], MemorySpaceT> explicitGeometry;
  // Per element, a triangle's edges with Allman's term (triangleQuadraticEdges): the one-point
  // kind's triangles build their forces with it, and a triangle's strains take it (both kinds).
  Kokkos::View<unsigned*, MemorySpaceT> quadraticEdges;
  // Whether any element is a triangle (a b c c): the one-point kernel is specialised for
  // bodies of quads only.
  bool hasTriangles = false;

  LocalIndex numElements() const { return static_cast<LocalIndex>(quads.extent(0)); }
};

// The elements of `body` with a node where nodeMask != 0, as a body of their own, in their
// order in `body`, with its force assembly and a node incidence of its own (as makeShellBody
// gives every body): a node all of whose elements are selected sums them in the same order,
// to the same bits. Uses: the critical step's local estimate over the elements around a change, and a
// distributed step over the elements whose forces an owned node reads
// (solvers/explicit/central_difference.hpp). Every per-element view of ShellBody is gathered
// here; a new one must be too.
template <class ExecutionSpaceT, class MemorySpaceT>
ShellBody<MemorySpaceT> selectElements(const ExecutionSpaceT& space, const ShellBody<MemorySpaceT>& body,
                                       const Kokkos::View<const std::uint8_t*, MemorySpaceT>& nodeMask) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  const auto quads = body.quads;
  const LocalIndex numElements = body.numElements();
  Kokkos::View<LocalIndex*, MemorySpaceT> selected("selected shell elements", numElements);
  LocalIndex count = 0;
  Kokkos::parallel_scan(
      "perishell::shell::selectElements::list", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, numElements),
      KOKKOS_LAMBDA(const LocalIndex e, LocalIndex& sum, const bool final) {
        bool touches = false;
        for (int a = 0; a < 4; ++a) touches = touches || nodeMask(quads(e, a)) != 0;
        if (!touches) return;
        if (final) selected(sum) = e;
        ++sum;
      },
      count);
  ShellBody<MemorySpaceT> subset;
  subset.kind = body.kind;
  subset.section = body.section;
  subset.referencePositions = body.referencePositions;
  subset.assembly = body.assembly;
  subset.hasTriangles = body.hasTriangles;
  subset.quads = QuadConnectivityView<MemorySpaceT>("selected quads", count);
  subset.membraneBendingScale =
      Kokkos::View<double* [4], Kokkos::LayoutRight, MemorySpaceT>("selected membrane-bending scales", count);
  const bool withStiffness = body.localStiffness.extent(0) > 0, withEdges = body.quadraticEdges.extent(0) > 0;
  if (withStiffness)
    subset.localStiffness =
        Kokkos::View<double* [24][24], Kokkos::LayoutRight, MemorySpaceT>("selected local stiffness", count);
  if (withEdges) subset.quadraticEdges = Kokkos::View<unsigned*, MemorySpaceT>("selected quadratic edges", count);
  const bool withGeometry = body.explicitGeometry.extent(0) > 0;
  if (withGeometry) subset.explicitGeometry = decltype(subset.explicitGeometry)("selected explicit geometry", count);
  const auto to = subset;
  Kokkos::parallel_for(
      "perishell::shell::selectElements::copy", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, count),
      KOKKOS_LAMBDA(const LocalIndex k) {
        const LocalIndex e = selected(k);
        for (int a = 0; a < 4; ++a) {
          to.quads(k, a) = body.quads(e, a);
          to.membraneBendingScale(k, a) = body.membraneBendingScale(e, a);
        }
        if (withStiffness)
          for (int r = 0; r < 24; ++r)
            for (int c = 0; c < 24; ++c) to.localStiffness(k, r, c) = body.localStiffness(e, r, c);
        if (withEdges) to.quadraticEdges(k) = body.quadraticEdges(e);
        if (withGeometry)
          for (int c = 0; c < explicitReferenceSize; ++c) to.explicitGeometry(k, c) = body.explicitGeometry(e, c);
      });
  if (body.nodeElementOffsets.extent(0) > 0) {
    const auto incidence =
        mesh::makeNodeIncidence(space, subset.quads, static_cast<LocalIndex>(body.nodeElementOffsets.extent(0) - 1));
    subset.nodeElementOffsets = incidence.offsets;
    subset.nodeElementEntries = incidence.entries;
  }
  if (body.elementForces.extent(0) > 0)
    subset.elementForces = decltype(subset.elementForces)("selected shell element forces", count);
  return subset;
}

// The faster assembly of the one-point element's forces on each backend (docs/explicit.md,
// "The explicit shell element"): Gather on host backends (no atomics; 1.25x faster on 2
// OpenMP threads), Scatter on a GPU (1.4x faster on the H200).
template <class ExecutionSpaceT>
constexpr ElementForceAssembly defaultElementForceAssembly() {
  return Kokkos::SpaceAccessibility<Kokkos::HostSpace, typename ExecutionSpaceT::memory_space>::accessible
             ? ElementForceAssembly::Gather
             : ElementForceAssembly::Scatter;
}

// Per MITC element, 24 local forces s (a triangle's first 18): the mixed-format Newton's
// independent unknowns (shellLinearizedLocalForces).
template <class MemorySpaceT>
using ElementLocalForcesView = Kokkos::View<double* [24], Kokkos::LayoutRight, MemorySpaceT>;

namespace detail {

// ExplicitReference as ShellBody::explicitGeometry keeps it: local coordinates, then the
// frame's quaternion.
template <class GeometryView>
KOKKOS_INLINE_FUNCTION void storeExplicitReference(const ExplicitReference& reference, const GeometryView& geometry,
                                                   LocalIndex element) {
  for (int a = 0; a < 4; ++a)
    for (int k = 0; k < 3; ++k) geometry(element, 3 * a + k) = reference.local[a][k];
  for (int k = 0; k < 4; ++k) geometry(element, 12 + k) = reference.frameQuaternion[k];
}
template <class GeometryView>
KOKKOS_INLINE_FUNCTION ExplicitReference loadExplicitReference(const GeometryView& geometry, LocalIndex element) {
  ExplicitReference reference;
  for (int a = 0; a < 4; ++a)
    for (int k = 0; k < 3; ++k) reference.local[a][k] = geometry(element, 3 * a + k);
  for (int k = 0; k < 4; ++k) reference.frameQuaternion[k] = geometry(element, 12 + k);
  return reference;
}

// Element e's corners' reference positions.
template <class MemorySpaceT>
KOKKOS_INLINE_FUNCTION void loadReferenceCorners(const ShellBody<MemorySpaceT>& body, LocalIndex element,
                                                 double reference[4][3]) {
  for (int a = 0; a < 4; ++a)
    for (int d = 0; d < 3; ++d) reference[a][d] = body.referencePositions(body.quads(element, a), d);
}

// Element e's reference and current corner positions and its nodes' rotations as unit
// quaternions (the explicit elements read them so).
template <class MemorySpaceT>
KOKKOS_INLINE_FUNCTION void loadExplicitElement(const ShellBody<MemorySpaceT>& body,
                                                const pd::PdKinematics<MemorySpaceT>& state, LocalIndex element,
                                                double reference[4][3], double current[4][3], double quaternions[4][4]) {
  for (int a = 0; a < 4; ++a) {
    const LocalIndex node = body.quads(element, a);
    for (int k = 0; k < 3; ++k) {
      reference[a][k] = body.referencePositions(node, k);
      current[a][k] = reference[a][k] + state.displacements(node, k);
    }
    for (int k = 0; k < 4; ++k) quaternions[a][k] = state.rotations(node, k);
  }
}

// The same with the rotations as matrices (MITC4's).
template <class MemorySpaceT>
KOKKOS_INLINE_FUNCTION void loadElement(const ShellBody<MemorySpaceT>& body, const pd::PdKinematics<MemorySpaceT>& state,
                                        LocalIndex element, double reference[4][3], double current[4][3],
                                        double rotations[4][3][3]) {
  double quaternions[4][4];
  loadExplicitElement(body, state, element, reference, current, quaternions);
  for (int a = 0; a < 4; ++a) rotation::toMatrix(quaternions[a], rotations[a]);
}

// Subtracts the internal force of MITC element e (N = 4 a quad, N = 3 a triangle a b c c)
// from its nodes' forces, and adds its energy, 1/N per node.
template <int N, class MemorySpaceT>
KOKKOS_INLINE_FUNCTION void subtractElementForce(const ShellBody<MemorySpaceT>& body, LocalIndex e,
                                                 const double reference[4][3], const double current[4][3],
                                                 const double rotations[4][3][3],
                                                 const pd::NodalVectorView<MemorySpaceT>& forces,
                                                 const VectorView<MemorySpaceT>& energy) {
  double localStiffness[6 * N][6 * N], force[6 * N];
  for (int r = 0; r < 6 * N; ++r)
    for (int c = 0; c < 6 * N; ++c) localStiffness[r][c] = body.localStiffness(e, r, c);
  const double elementEnergy = shellInternalForce<N>(reference, current, rotations, localStiffness, force);
  for (int a = 0; a < N; ++a) {
    for (int d = 0; d < 6; ++d) Kokkos::atomic_add(&forces(body.quads(e, a), d), -force[6 * a + d]);
    if (energy.extent(0) > 0) Kokkos::atomic_add(&energy(body.quads(e, a)), elementEnergy / N);
  }
}

// Adds the tangent of MITC element e (N as above) into the CRS values; with the mixed-format
// Newton's local forces where mixedLocalForces has rows (shellTangent).
template <int N, class MemorySpaceT, class PatternT>
KOKKOS_INLINE_FUNCTION void addElementTangent(const ShellBody<MemorySpaceT>& body, LocalIndex e,
                                              const double reference[4][3], const double current[4][3],
                                              const double rotations[4][3][3], const PatternT& pattern,
                                              const VectorView<MemorySpaceT>& values, TangentForm form,
                                              const ElementLocalForcesView<MemorySpaceT>& mixedLocalForces) {
  double localStiffness[6 * N][6 * N], force[6 * N], tangent[6 * N][6 * N], mixed[6 * N];
  for (int r = 0; r < 6 * N; ++r)
    for (int c = 0; c < 6 * N; ++c) localStiffness[r][c] = body.localStiffness(e, r, c);
  const bool useMixed = mixedLocalForces.extent(0) > 0;
  if (useMixed)
    for (int i = 0; i < 6 * N; ++i) mixed[i] = mixedLocalForces(e, i);
  shellTangent<N>(reference, current, rotations, localStiffness, force, tangent, useMixed ? mixed : nullptr);
  if (form == TangentForm::Exact) addRotationAsymmetry<N>(force, tangent);
  pattern.template atomicAddElementMatrix<N>(e, tangent, values);
}

// Writes element e's mixed-format local forces after the correction eta dq (N as above).
template <int N, class MemorySpaceT>
KOKKOS_INLINE_FUNCTION void linearizeElementLocalForces(const ShellBody<MemorySpaceT>& body, LocalIndex e,
                                                        const double reference[4][3], const double current[4][3],
                                                        const double rotations[4][3][3],
                                                        const pd::NodalVectorView<MemorySpaceT>& correction, double eta,
                                                        const ElementLocalForcesView<MemorySpaceT>& localForces) {
  double localStiffness[6 * N][6 * N], step[6 * N], forces[6 * N];
  for (int r = 0; r < 6 * N; ++r)
    for (int c = 0; c < 6 * N; ++c) localStiffness[r][c] = body.localStiffness(e, r, c);
  for (int a = 0; a < N; ++a)
    for (int d = 0; d < 6; ++d) step[6 * a + d] = eta * correction(body.quads(e, a), d);
  shellLinearizedLocalForces<N>(reference, current, rotations, localStiffness, step, forces);
  for (int i = 0; i < 6 * N; ++i) localForces(e, i) = forces[i];
}

}  // namespace detail

// The CCM elements of a mesh (body element k is mesh element ccmElements[k]) with their
// section, the membrane and bending blocks of D scaled per element and Gauss point by
// membraneBendingScale (numElements x 4, on the device), as elements of `kind`. Throws
// std::invalid_argument naming the first element the kind cannot represent.
template <class ExecutionSpaceT>
ShellBody<typename ExecutionSpaceT::memory_space> makeShellBody(
    const ExecutionSpaceT& space, const mesh::HostQuadMesh& mesh, const std::vector<LocalIndex>& ccmElements,
    const ShellSection& section,
    const Kokkos::View<double* [4], Kokkos::LayoutRight, typename ExecutionSpaceT::memory_space>& membraneBendingScale,
    ShellElementKind kind = ShellElementKind::Mitc4) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  using MemorySpaceT = typename ExecutionSpaceT::memory_space;
  if (membraneBendingScale.extent(0) != ccmElements.size()) {
    std::ostringstream message;
    message << "makeShellBody: " << membraneBendingScale.extent(0) << " rows of membrane-bending scales for "
            << ccmElements.size() << " elements";
    throw std::invalid_argument(message.str());
  }
  QuadConnectivityView<Kokkos::HostSpace> quads("ccm quads", ccmElements.size());
  bool hasTriangles = false;
  for (std::size_t k = 0; k < ccmElements.size(); ++k) {
    double reference[4][3];
    for (int a = 0; a < 4; ++a) {
      quads(k, a) = mesh.quads(ccmElements[k], a);
      for (int d = 0; d < 3; ++d) reference[a][d] = mesh.coordinates(quads(k, a), d);
    }
    // Two distinct nodes at one point are a defect, not a triangle (a b c c).
    hasTriangles = hasTriangles || mesh::isTriangle(quads, k);
    if (!mesh::isTriangle(quads, k) && isTriangleElement(reference))
      throw std::invalid_argument("shell element " + std::to_string(ccmElements[k]) +
                                  ": zero or negative area: nodes 2 and 3 coincide");
    if (kind == ShellElementKind::OnePoint)
      checkOnePointShellElement(reference, ccmElements[k]);
    else
      checkShellElement(reference, ccmElements[k]);
  }
  ShellBody<MemorySpaceT> body;
  body.kind = kind;
  body.section = section;
  body.hasTriangles = hasTriangles;
  body.referencePositions = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, mesh.coordinates);
  body.quads = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, quads);
  body.membraneBendingScale = membraneBendingScale;
  // A managed host view: on a host memory space the mirror is this view itself.
  const std::vector<unsigned> hostEdges = triangleQuadraticEdges(quads, quads.extent(0));
  Kokkos::View<unsigned*, Kokkos::HostSpace> hostEdgeView("shell triangle quadratic edges", hostEdges.size());
  std::copy(hostEdges.begin(), hostEdges.end(), hostEdgeView.data());
  body.quadraticEdges = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, hostEdgeView);
  const auto quadraticEdges = body.quadraticEdges;
  const auto incidence = mesh::makeNodeIncidence(space, body.quads, mesh.numNodes());
  body.nodeElementOffsets = incidence.offsets;
  body.nodeElementEntries = incidence.entries;
  if (kind == ShellElementKind::OnePoint) {
    body.elementForces = decltype(body.elementForces)("shell element forces", quads.extent(0));
    body.assembly = defaultElementForceAssembly<ExecutionSpaceT>();
    body.explicitGeometry = decltype(body.explicitGeometry)("shell explicit geometry", quads.extent(0));
    const auto b = body;
    Kokkos::parallel_for(
        "perishell::shell::explicitGeometry", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, b.numElements()),
        KOKKOS_LAMBDA(const LocalIndex e) {
          double reference[4][3];
          detail::loadReferenceCorners(b, e, reference);
          detail::storeExplicitReference(explicitReference(shellReference(reference)), b.explicitGeometry, e);
        });
    return body;
  }
  body.localStiffness = decltype(body.localStiffness)("shell local stiffness", ccmElements.size());
  const auto b = body;
  Kokkos::parallel_for(
      "perishell::shell::localStiffness", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, b.numElements()),
      KOKKOS_LAMBDA(const LocalIndex e) {
        double reference[4][3];
        detail::loadReferenceCorners(b, e, reference);
        const double scale[4] = {b.membraneBendingScale(e, 0), b.membraneBendingScale(e, 1),
                                 b.membraneBendingScale(e, 2), b.membraneBendingScale(e, 3)};
        double K[24][24];
        shellLocalStiffness(reference, section, scale, quadraticEdges(e), K);
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

// Which of a body's elements a force kernel evaluates: every one, or those listed (indices
// into the body; a distributed explicit step evaluates its elements in two lists around the
// halo exchange, solvers/explicit/central_difference.hpp).
template <class MemorySpaceT>
struct ElementSelection {
  Kokkos::View<const LocalIndex*, MemorySpaceT> listed;
  bool all = true;

  static ElementSelection every() { return {}; }
  static ElementSelection only(const Kokkos::View<const LocalIndex*, MemorySpaceT>& elements) {
    return {elements, false};
  }
  LocalIndex count(LocalIndex numElements) const {
    return all ? numElements : static_cast<LocalIndex>(listed.extent(0));
  }
  KOKKOS_INLINE_FUNCTION LocalIndex element(LocalIndex k) const { return all ? k : listed(k); }
};

namespace detail {

// The one-point element's forces (OnePoint bodies), one thread per selected element, scattered
// with atomics or written for the gather (ShellBody::assembly). WithTriangles: the body has
// triangles, and each element takes the explicit triangle's branch or the quad's. A body of
// quads only runs without that branch: fewer registers (246 against 254 per thread) and
// 8 % less time per step at 1e6 elements on an H100 (docs/explicit.md).
template <bool WithTriangles, class ExecutionSpaceT, class MemorySpaceT>
void launchOnePointForces(const ExecutionSpaceT& space, const ShellBody<MemorySpaceT>& body,
                          const ElementSelection<MemorySpaceT>& selection, const pd::PdKinematics<MemorySpaceT>& state,
                          const pd::NodalVectorView<MemorySpaceT>& forces, const VectorView<MemorySpaceT>& energy,
                          const VectorView<MemorySpaceT>& hourglassEnergy, bool gather, bool withEnergy,
                          bool withHourglass) {
  Kokkos::parallel_for(
      "perishell::shell::onePointShellForces", queuedRangePolicy(space, 0, selection.count(body.numElements())),
      KOKKOS_LAMBDA(const LocalIndex k) {
        const LocalIndex e = selection.element(k);
        double reference[4][3], current[4][3], quaternions[4][4], force[shellDofCount];
        loadExplicitElement(body, state, e, reference, current, quaternions);
        const ExplicitReference geometry = loadExplicitReference(body.explicitGeometry, e);
        const double scale = 0.25 * (body.membraneBendingScale(e, 0) + body.membraneBendingScale(e, 1) +
                                     body.membraneBendingScale(e, 2) + body.membraneBendingScale(e, 3));
        int corners = 4;
        OnePointEnergies elementEnergy{0.0, 0.0};
        if constexpr (WithTriangles) corners = mesh::cornerCount(body.quads, e);
        if (WithTriangles && corners == 3)
          elementEnergy.strain = explicitTriangleForce(geometry, current, quaternions, body.section, scale,
                                                       body.quadraticEdges(e), force);
        else
          elementEnergy = onePointShellForce(geometry, current, quaternions, body.section, scale, force);
        // Energies go to the nodes in equal shares.
        if (gather) {
          for (int r = 0; r < 6 * corners; ++r) body.elementForces(e, r) = force[r];
          body.elementForces(e, 24) = elementEnergy.strain / corners;
          body.elementForces(e, 25) = elementEnergy.hourglass / corners;
          return;
        }
        for (int a = 0; a < corners; ++a) {
          const LocalIndex node = body.quads(e, a);
          for (int d = 0; d < 6; ++d) Kokkos::atomic_add(&forces(node, d), -force[6 * a + d]);
          if (withEnergy) Kokkos::atomic_add(&energy(node), elementEnergy.strain / corners);
          if (withHourglass) Kokkos::atomic_add(&hourglassEnergy(node), elementEnergy.hourglass / corners);
        }
      });
}

}  // namespace detail

// The first half of subtractShellForces, over the selected elements: forces -= their internal
// forces (and energies added), except for a one-point body that gathers, whose selected
// elements only write their forces for gatherShellForces. A step may call it for several
// selections before the one gather; every element must be selected once.
template <class ExecutionSpaceT, class MemorySpaceT>
void subtractSelectedShellForces(const ExecutionSpaceT& space, const ShellBody<MemorySpaceT>& body,
                                 const ElementSelection<MemorySpaceT>& selection,
                                 const pd::PdKinematics<MemorySpaceT>& state,
                                 const pd::NodalVectorView<MemorySpaceT>& forces,
                                 const VectorView<MemorySpaceT>& energy = {},
                                 const VectorView<MemorySpaceT>& hourglassEnergy = {}) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  const bool withEnergy = energy.extent(0) > 0;
  if (selection.count(body.numElements()) == 0) return;
  if (body.kind == ShellElementKind::OnePoint) {
    const bool withHourglass = hourglassEnergy.extent(0) > 0;
    const bool gather = body.assembly == ElementForceAssembly::Gather;
    if (body.hasTriangles)
      detail::launchOnePointForces<true>(space, body, selection, state, forces, energy, hourglassEnergy, gather,
                                         withEnergy, withHourglass);
    else
      detail::launchOnePointForces<false>(space, body, selection, state, forces, energy, hourglassEnergy, gather,
                                          withEnergy, withHourglass);
    return;
  }
  Kokkos::parallel_for(
      "perishell::shell::subtractShellForces", queuedRangePolicy(space, 0, selection.count(body.numElements())),
      KOKKOS_LAMBDA(const LocalIndex k) {
        const LocalIndex e = selection.element(k);
        double reference[4][3], current[4][3], rotations[4][3][3];
        detail::loadElement(body, state, e, reference, current, rotations);
        // A triangle works on its 3 nodes: 18 DOF, not the collapsed quad's 24.
        if (mesh::isTriangle(body.quads, e))
          detail::subtractElementForce<3>(body, e, reference, current, rotations, forces, energy);
        else
          detail::subtractElementForce<4>(body, e, reference, current, rotations, forces, energy);
      });
}

// The second half: a gathering one-point body's written element forces summed per node, each
// node's elements in incidence order (no atomics), and subtracted; nothing for other bodies.
template <class ExecutionSpaceT, class MemorySpaceT>
void gatherShellForces(const ExecutionSpaceT& space, const ShellBody<MemorySpaceT>& body,
                       const pd::NodalVectorView<MemorySpaceT>& forces, const VectorView<MemorySpaceT>& energy = {},
                       const VectorView<MemorySpaceT>& hourglassEnergy = {}) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  if (body.kind != ShellElementKind::OnePoint || body.assembly != ElementForceAssembly::Gather) return;
  const bool withEnergy = energy.extent(0) > 0, withHourglass = hourglassEnergy.extent(0) > 0;
  Kokkos::parallel_for(
      "perishell::shell::gatherOnePointShellForces",
      queuedRangePolicy(space, 0, static_cast<LocalIndex>(body.nodeElementOffsets.extent(0) - 1)),
      KOKKOS_LAMBDA(const LocalIndex node) {
        const RowOffset begin = body.nodeElementOffsets(node), end = body.nodeElementOffsets(node + 1);
        if (begin == end) return;
        double sum[6] = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0}, strain = 0.0, hourglass = 0.0;
        for (RowOffset k = begin; k < end; ++k) {
          const LocalIndex entry = body.nodeElementEntries(k), e = entry / 4, corner = entry % 4;
          for (int d = 0; d < 6; ++d) sum[d] += body.elementForces(e, 6 * corner + d);
          strain += body.elementForces(e, 24);
          hourglass += body.elementForces(e, 25);
        }
        for (int d = 0; d < 6; ++d) forces(node, d) -= sum[d];
        if (withEnergy) energy(node) += strain;
        if (withHourglass) hourglassEnergy(node) += hourglass;
      });
}

// forces -= internal forces of every element (the caller's forces are the loads acting on
// the nodes, so the result is the out-of-balance force). With a non-empty energy view, each
// element's energy (MITC4: W = 1/2 d^T K_l d) is also added to it, in equal shares per node, and
// with a non-empty hourglassEnergy view the one-point element's hourglass part likewise.
template <class ExecutionSpaceT, class MemorySpaceT>
void subtractShellForces(const ExecutionSpaceT& space, const ShellBody<MemorySpaceT>& body,
                         const pd::PdKinematics<MemorySpaceT>& state, const pd::NodalVectorView<MemorySpaceT>& forces,
                         const VectorView<MemorySpaceT>& energy = {},
                         const VectorView<MemorySpaceT>& hourglassEnergy = {}) {
  subtractSelectedShellForces(space, body, ElementSelection<MemorySpaceT>::every(), state, forces, energy,
                              hourglassEnergy);
  gatherShellForces(space, body, forces, energy, hourglassEnergy);
}

// Per node, the elements' diagonal stiffness: the mean of the three translational and of the
// three rotational diagonal entries of the element's linear stiffness, summed over the
// node's elements (for the explicit solver's rotary-inertia scaling,
// solvers/explicit/nodal_inertia.hpp).
template <class ExecutionSpaceT, class MemorySpaceT>
void addShellNodalStiffness(const ExecutionSpaceT& space, const ShellBody<MemorySpaceT>& body,
                            const VectorView<MemorySpaceT>& translational, const VectorView<MemorySpaceT>& rotational) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  const bool onePoint = body.kind == ShellElementKind::OnePoint;
  // Per element and corner (translational, rotational), then gathered by node in element order.
  const Kokkos::View<double* [4][2], Kokkos::LayoutRight, MemorySpaceT> cornerStiffness("shell corner stiffness",
                                                                                       body.numElements());
  Kokkos::parallel_for(
      "perishell::shell::addShellNodalStiffness", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, body.numElements()),
      KOKKOS_LAMBDA(const LocalIndex e) {
        double moving[4] = {0.0, 0.0, 0.0, 0.0}, turning[4] = {0.0, 0.0, 0.0, 0.0};
        const int corners = mesh::cornerCount(body.quads, e);
        if (onePoint) {
          double reference[4][3];
          detail::loadReferenceCorners(body, e, reference);
          const double scale = 0.25 * (body.membraneBendingScale(e, 0) + body.membraneBendingScale(e, 1) +
                                       body.membraneBendingScale(e, 2) + body.membraneBendingScale(e, 3));
          if (corners == 4) {
            onePointShellNodalStiffness(reference, body.section, scale, moving, turning);
          } else {  // the explicit triangle stores no K_l: build it once here
            double local[3][2], K[triangleDofCount][triangleDofCount];
            detail::triangleCorners(shellReference(reference), local);
            triangleLocalStiffness(local, body.section, scale, body.quadraticEdges(e), K);
            for (int a = 0; a < 3; ++a)
              for (int d = 0; d < 3; ++d) {
                moving[a] += K[6 * a + d][6 * a + d] / 3.0;
                turning[a] += K[6 * a + 3 + d][6 * a + 3 + d] / 3.0;
              }
          }
        } else {
          for (int a = 0; a < 4; ++a)
            for (int d = 0; d < 3; ++d) {
              moving[a] += body.localStiffness(e, 6 * a + d, 6 * a + d) / 3.0;
              turning[a] += body.localStiffness(e, 6 * a + 3 + d, 6 * a + 3 + d) / 3.0;
            }
        }
        for (int a = 0; a < 4; ++a) {
          cornerStiffness(e, a, 0) = a < corners ? moving[a] : 0.0;
          cornerStiffness(e, a, 1) = a < corners ? turning[a] : 0.0;
        }
      });
  const auto offsets = body.nodeElementOffsets;
  const auto entries = body.nodeElementEntries;
  Kokkos::parallel_for(
      "perishell::shell::gatherShellNodalStiffness",
      Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, static_cast<LocalIndex>(offsets.extent(0) - 1)),
      KOKKOS_LAMBDA(const LocalIndex node) {
        double moving = 0.0, turning = 0.0;
        for (RowOffset i = offsets(node); i < offsets(node + 1); ++i) {
          moving += cornerStiffness(entries(i) / 4, entries(i) % 4, 0);
          turning += cornerStiffness(entries(i) / 4, entries(i) % 4, 1);
        }
        translational(node) += moving;
        rotational(node) += turning;
      });
}

// Adds every element's symmetric tangent K_T (the one CG solves with) into the CRS values;
// the pattern's element e is body element e. mixedLocalForces: empty, or one row per element
// (the mixed-format Newton's s, in place of K_l d).
template <class ExecutionSpaceT, class MemorySpaceT, class PatternT>
void assembleShellTangent(const ExecutionSpaceT& space, const ShellBody<MemorySpaceT>& body,
                          const pd::PdKinematics<MemorySpaceT>& state, const PatternT& pattern,
                          const VectorView<MemorySpaceT>& values, TangentForm form = TangentForm::Symmetric,
                          const ElementLocalForcesView<MemorySpaceT>& mixedLocalForces = {}) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  if (body.kind != ShellElementKind::Mitc4)
    throw std::logic_error("assembleShellTangent: the one-point shell element has no tangent; build MITC4 elements");
  Kokkos::parallel_for(
      "perishell::shell::assembleShellTangent", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, body.numElements()),
      KOKKOS_LAMBDA(const LocalIndex e) {
        double reference[4][3], current[4][3], rotations[4][3][3];
        detail::loadElement(body, state, e, reference, current, rotations);
        if (mesh::isTriangle(body.quads, e))
          detail::addElementTangent<3>(body, e, reference, current, rotations, pattern, values, form, mixedLocalForces);
        else
          detail::addElementTangent<4>(body, e, reference, current, rotations, pattern, values, form, mixedLocalForces);
      });
}

// The mixed-format Newton's local forces of every element after the correction eta dq from
// the current state: s = K_l (d + eta B dq) (shellLinearizedLocalForces). dq per node:
// translations, then the spatial rotation increment. Call before the correction is applied.
template <class ExecutionSpaceT, class MemorySpaceT>
void linearizeShellLocalForces(const ExecutionSpaceT& space, const ShellBody<MemorySpaceT>& body,
                               const pd::PdKinematics<MemorySpaceT>& state,
                               const pd::NodalVectorView<MemorySpaceT>& correction, double eta,
                               const ElementLocalForcesView<MemorySpaceT>& localForces) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  Kokkos::parallel_for(
      "perishell::shell::linearizeShellLocalForces", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, body.numElements()),
      KOKKOS_LAMBDA(const LocalIndex e) {
        double reference[4][3], current[4][3], rotations[4][3][3];
        detail::loadElement(body, state, e, reference, current, rotations);
        if (mesh::isTriangle(body.quads, e))
          detail::linearizeElementLocalForces<3>(body, e, reference, current, rotations, correction, eta, localForces);
        else
          detail::linearizeElementLocalForces<4>(body, e, reference, current, rotations, correction, eta, localForces);
      });
}

}  // namespace perishell::shell
