#pragma once
// The pieces of a mixed PD-CCM model on the device (model.md §4, docs/coupling.md): the
// morphing field alpha, the PD body over every node with alpha > 0 (the PD nodes and the
// transition) with its bonds scaled by (alpha_i + alpha_j)/2, and the shell body over
// every element that is not pure PD, with the hybrid section D_Hb per Gauss point
// (coupling/morphing.hpp). A 100 % PD model gives every node alpha = 1 and no shell
// element; a 0 % PD model no PD node and every element with the full section.
#include <perishell/assembly/mirror_images.hpp>
#include <perishell/coupling/alpha_field.hpp>
#include <perishell/coupling/morphing.hpp>
#include <perishell/model/model.hpp>
#include <perishell/pd/make_body.hpp>
#include <perishell/shell/shell_body.hpp>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace perishell::coupling {

template <class MemorySpaceT>
pd::PdBody<MemorySpaceT> emptyPdBody() {
  pd::PdBody<MemorySpaceT> body;
  body.referencePositions = CoordinateView<MemorySpaceT>("pd reference positions", 0);
  body.bonds.offsets = Kokkos::View<RowOffset*, MemorySpaceT>("pd offsets", 1);
  body.bonds.neighbours = Kokkos::View<LocalIndex*, MemorySpaceT>("pd neighbours", 0);
  body.bonds.fullToHalf = Kokkos::View<RowOffset*, MemorySpaceT>("pd full to half", 0);
  body.bonds.halfBonds = Kokkos::View<LocalIndex* [2], Kokkos::LayoutRight, MemorySpaceT>("pd half bonds", 0);
  body.bonds.referenceLength = Kokkos::View<double*, MemorySpaceT>("pd reference length", 0);
  body.bonds.volumeFactor = Kokkos::View<double*, MemorySpaceT>("pd volume factor", 0);
  body.stiffnessScale = Kokkos::View<double* [2], Kokkos::LayoutRight, MemorySpaceT>("pd stiffness scale", 0);
  return body;
}

template <class MemorySpaceT>
struct CoupledBodies {
  VectorView<MemorySpaceT> alpha;     // per mesh node
  VectorView<MemorySpaceT> alphaBar;  // per mesh node: the bonds' share of the energy (0 off the PD body)
  // The bond carriers: the mesh nodes with alpha > 0, ascending.
  Kokkos::View<LocalIndex*, Kokkos::HostSpace> pdNodes;
  // Indexed by mesh node (pd::indexByMeshNodes): only pdNodes hold bonds (none at 0 % PD).
  pd::PdBody<MemorySpaceT> pdBody;
  // Shell body element k is mesh element ccmElements[k]: the elements with alphaBar < 1 at some node.
  std::vector<LocalIndex> ccmElements;
  shell::ShellBody<MemorySpaceT> shellBody;

  // The bodies as the solvers take them: none where the model has no element or no bond carrier.
  std::optional<shell::ShellBody<MemorySpaceT>> shellElements() const {
    if (shellBody.numElements() == 0) return std::nullopt;
    return shellBody;
  }
  std::optional<pd::PdBody<MemorySpaceT>> bondCarriers() const {
    if (pdNodes.extent(0) == 0) return std::nullopt;
    return pdBody;
  }
};

struct CouplingInputs {
  pd::PdMaterial material;
  shell::ShellSection section;
  double horizon = 0.0;      // delta [m]
  double gridSpacing = 0.0;  // dx [m]
  std::vector<mesh::CrackSegment> preCracks;
  deck::Transition transition;  // width 0: 2 delta
  LocalIndex firstHeldNode = std::numeric_limits<LocalIndex>::max();  // the support layer's first node
  mesh::SupportLayer supportLayer;  // its mirrored nodes and shares (assembly/mirror_images.hpp)
  // The CCM elements' formulation: MITC4 for both solvers, the one-point element for explicit runs.
  shell::ShellElementKind shellElement = shell::ShellElementKind::Mitc4;
};

// elementIsPd: per mesh element, 1 where PD (model.md §1). Throws std::invalid_argument on
// a transition narrower than 2 delta and on parameters the bodies reject.
template <class ExecutionSpaceT>
CoupledBodies<typename ExecutionSpaceT::memory_space> makeCoupledBodies(
    const ExecutionSpaceT& space, const mesh::HostQuadMesh& hostMesh,
    const Kokkos::View<const std::uint8_t*, Kokkos::HostSpace>& elementIsPd, const CouplingInputs& inputs) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  using MemorySpaceT = typename ExecutionSpaceT::memory_space;
  const double width = inputs.transition.width > 0.0 ? inputs.transition.width : 2.0 * inputs.horizon;
  if (!(width >= 2.0 * inputs.horizon * (1.0 - 1e-12)))
    throw std::invalid_argument("makeCoupledBodies: transition width " + std::to_string(width) +
                                " m is below 2 delta = " + std::to_string(2.0 * inputs.horizon) + " m (model.md §4)");
  const LocalIndex numNodes = hostMesh.numNodes(), numElements = hostMesh.numElements();
  CoupledBodies<MemorySpaceT> bodies;

  // PD nodes: the nodes of PD elements (model.md §1).
  std::vector<std::uint8_t> isPdNode(numNodes, 0);
  for (LocalIndex e = 0; e < numElements; ++e)
    if (elementIsPd(e))
      for (int a = 0; a < 4; ++a) isPdNode[hostMesh.quads(e, a)] = 1;
  CoordinateView<Kokkos::HostSpace> hostPdPositions("pd node positions", std::count(isPdNode.begin(), isPdNode.end(), 1));
  for (LocalIndex node = 0, k = 0; node < numNodes; ++node)
    if (isPdNode[node]) {
      for (int d = 0; d < 3; ++d) hostPdPositions(k, d) = hostMesh.coordinates(node, d);
      ++k;
    }
  const auto positions = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, hostMesh.coordinates);
  const auto pdPositions = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, hostPdPositions);
  bodies.alpha = computeAlphaField(space, positions, pdPositions, width, inputs.transition.profile);

  // Bond carriers: alpha > 0 (setup-time host pass over one scalar per node).
  const auto hostAlpha = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, bodies.alpha);
  LocalIndex numBodyNodes = 0;
  for (LocalIndex node = 0; node < numNodes; ++node) numBodyNodes += hostAlpha(node) > 0.0;
  bodies.pdNodes = Kokkos::View<LocalIndex*, Kokkos::HostSpace>("coupling pd nodes", numBodyNodes);
  for (LocalIndex node = 0, k = 0; node < numNodes; ++node)
    if (hostAlpha(node) > 0.0) bodies.pdNodes(k++) = node;
  // A node nearer than delta to a node with alpha = 0 lies beyond distance L_c - delta from
  // the PD nodes (triangle inequality), where alpha <= profile(1 - delta / L_c).
  Kokkos::View<std::uint8_t*, Kokkos::HostSpace> atCcmInterface("coupling nodes at the ccm interface", numBodyNodes);
  const double interfaceAlpha = transitionProfile(inputs.transition.profile, 1.0 - inputs.horizon / width);
  for (LocalIndex k = 0; k < numBodyNodes; ++k) atCcmInterface(k) = hostAlpha(bodies.pdNodes(k)) <= interfaceAlpha;
  // No bond carrier (0 % PD): an empty body, and no microbeam checks (a pure CCM model may have nu > 1/3).
  if (numBodyNodes > 0)
    bodies.pdBody = pd::makePdBody(space, hostMesh, bodies.pdNodes, inputs.material, inputs.horizon,
                                   inputs.gridSpacing, inputs.preCracks, atCcmInterface, inputs.firstHeldNode,
                                   inputs.supportLayer.mirrorImages);
  else
    bodies.pdBody = emptyPdBody<MemorySpaceT>();

  const auto bodyNodes = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, bodies.pdNodes);
  VectorView<MemorySpaceT> bodyAlpha("coupling pd body alpha", numBodyNodes);
  const auto alpha = bodies.alpha;
  Kokkos::parallel_for(
      "perishell::coupling::gatherAlpha", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, numBodyNodes),
      KOKKOS_LAMBDA(const LocalIndex k) { bodyAlpha(k) = alpha(bodyNodes(k)); });
  bodies.alphaBar = VectorView<MemorySpaceT>("coupling alpha bar", numNodes);
  const auto alphaBar = bodies.alphaBar;
  const auto bodyAlphaBar =
      numBodyNodes > 0 ? morphBonds(space, bodies.pdBody, bodyAlpha) : VectorView<MemorySpaceT>("empty", 0);
  Kokkos::parallel_for(
      "perishell::coupling::scatterAlphaBar", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, numBodyNodes),
      KOKKOS_LAMBDA(const LocalIndex k) { alphaBar(bodyNodes(k)) = bodyAlphaBar(k); });
  bodies.pdBody = pd::indexByMeshNodes(space, bodies.pdBody, hostMesh, bodies.pdNodes, inputs.material.thickness);
  assembly::weighBondsByShare(space, bodies.pdBody,
                              assembly::makeMirrorImages<MemorySpaceT>(inputs.supportLayer, numNodes));

  // CCM elements: all but the pure PD ones (alphaBar = 1 at every node, to round-off) and the
  // support layer's, which only give its nodes their bonds (mesh/support_layer.hpp): near a
  // PD-CCM transition a layer element's alphaBar falls below 1 too, and as a shell element
  // beyond a mirror line it stored energy the model does not own (Newton stalled on a quarter
  // plate whose PD zone met a symmetry plane).
  const auto hostAlphaBar = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, bodies.alphaBar);
  constexpr double purePd = 1.0 - 1e-12;
  for (LocalIndex e = 0; e < std::min(numElements, inputs.supportLayer.firstElement); ++e) {
    bool pure = true;
    for (int a = 0; a < 4; ++a) pure = pure && hostAlphaBar(hostMesh.quads(e, a)) >= purePd;
    if (!pure) bodies.ccmElements.push_back(e);
  }
  QuadConnectivityView<Kokkos::HostSpace> hostCcmQuads("coupling ccm quads", bodies.ccmElements.size());
  for (std::size_t k = 0; k < bodies.ccmElements.size(); ++k)
    for (int a = 0; a < 4; ++a) hostCcmQuads(k, a) = hostMesh.quads(bodies.ccmElements[k], a);
  const auto ccmQuads = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, hostCcmQuads);
  bodies.shellBody = shell::makeShellBody(space, hostMesh, bodies.ccmElements, inputs.section,
                                          hybridSectionScales(space, ccmQuads, bodies.alphaBar), inputs.shellElement);
  return bodies;
}

// A model's coupling inputs: its deck's material, horizon, pre-cracks and zones.transition;
// for an explicit deck, solver.shell-element and solver.hourglass.
inline CouplingInputs couplingInputs(const model::Model& model) {
  const auto& material = model.deck.material;
  CouplingInputs inputs;
  inputs.material = {material.youngModulus, material.poissonRatio, material.thickness, material.fractureEnergy};
  inputs.section.youngModulus = material.youngModulus;
  inputs.section.poissonRatio = material.poissonRatio;
  inputs.section.thickness = material.thickness;
  inputs.horizon = model.horizon();
  inputs.gridSpacing = model.gridSpacing();
  inputs.preCracks = model.preCrackSegments();
  inputs.transition = model.deck.zones.transition;
  inputs.firstHeldNode = model.supportLayer.firstNode;
  inputs.supportLayer = model.supportLayer;
  if (model.deck.solver.type == deck::SolverType::Explicit) {
    const auto& settings = model.deck.solver.explicitSettings;
    using ShellElement = deck::ExplicitSettings::ShellElement;
    inputs.shellElement = settings.shellElement == ShellElement::OnePoint ? shell::ShellElementKind::OnePoint
                                                                          : shell::ShellElementKind::Mitc4;
    inputs.section.hourglassCoefficient = settings.hourglassCoefficient;
  }
  return inputs;
}

template <class ExecutionSpaceT>
CoupledBodies<typename ExecutionSpaceT::memory_space> makeCoupledBodies(const ExecutionSpaceT& space,
                                                                        const model::Model& model) {
  return makeCoupledBodies(space, model.shell.mesh, model.elementIsPd, couplingInputs(model));
}

}  // namespace perishell::coupling
