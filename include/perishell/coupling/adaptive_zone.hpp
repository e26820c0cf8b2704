#pragma once
// The PD zone that grows with the load (issue 6, beyond the paper): a CCM element whose
// largest surface strain reaches strainFraction x the bonds' critical stretch s_c (model.md
// §3: 1/2 c_ax s_c^2 xi = w_c, so s_c = sqrt(2 w_c / (c_ax xi))) turns PD, and with it the
// CCM elements whose centres lie within `margin` of its centre (2 delta by default, as the
// seed around a pre-crack: a crack opens unbridged only beyond the transition, and the
// zone grows in fewer, larger switches, each of which costs a rebuild); the coupled
// bodies are rebuilt around the grown zone (alpha, bonds, hybrid sections;
// coupling/make_coupled_model.hpp) and the solver carries its state over
// (growPdZone below, CentralDifferenceSolver::replaceBodies). Elements only ever turn PD,
// never back.
// The check is one kernel per element and a reduction; the host sees the strains only when
// some element switches, and then rebuilds the bodies (rare, at setup cost).
#include <perishell/coupling/make_coupled_model.hpp>
#include <perishell/shell/surface_strain.hpp>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace perishell::coupling {

template <class ExecutionSpaceT>
class AdaptivePdZone {
 public:
  using Memory = typename ExecutionSpaceT::memory_space;

  // elementIsPd: the starting zone (copied); margin [m]. Throws std::invalid_argument without a
  // fracture energy (there is no critical stretch), with strainFraction outside (0, 1] or a
  // negative margin.
  AdaptivePdZone(const ExecutionSpaceT& space, const mesh::HostQuadMesh& mesh,
                 const Kokkos::View<const std::uint8_t*, Kokkos::HostSpace>& elementIsPd, const CouplingInputs& inputs,
                 double strainFraction, double margin)
      : space_(space), mesh_(mesh), inputs_(inputs), margin_(margin),
        elementIsPd_("adaptive element is pd", elementIsPd.extent(0)) {
    if (!inputs.material.fractureEnergy)
      throw std::invalid_argument("adaptive PD zone: needs material.fracture-energy (the switch compares strains "
                                  "with the bonds' critical stretch)");
    if (!(strainFraction > 0.0 && strainFraction <= 1.0))
      throw std::invalid_argument("adaptive PD zone: the strain fraction must lie in (0, 1], got " +
                                  std::to_string(strainFraction));
    if (!(margin >= 0.0))
      throw std::invalid_argument("adaptive PD zone: the margin must be >= 0 m, got " + std::to_string(margin));
    Kokkos::deep_copy(elementIsPd_, elementIsPd);
    const auto& material = inputs.material;
    const double axial =
        pd::microbeamMicromoduli(material.youngModulus, material.poissonRatio, material.thickness, inputs.horizon).axial;
    criticalStretch_ = std::sqrt(
        2.0 * pd::criticalMicropotentialPerLength(*material.fractureEnergy, material.thickness, inputs.horizon) / axial);
    threshold_ = strainFraction * criticalStretch_;
    rebuild();
    changedNodes_ = Kokkos::View<std::uint8_t*, Memory>("adaptive changed nodes", bodies_.alpha.extent(0));
  }

  const CoupledBodies<Memory>& bodies() const { return bodies_; }
  const Kokkos::View<std::uint8_t*, Kokkos::HostSpace>& elementIsPd() const { return elementIsPd_; }
  LocalIndex numPdElements() const {
    LocalIndex count = 0;
    for (std::size_t e = 0; e < elementIsPd_.extent(0); ++e) count += elementIsPd_(e);
    return count;
  }
  // The nodes of PD elements, ascending (the zone output field).
  Kokkos::View<LocalIndex*, Kokkos::HostSpace> pdElementNodes() const {
    std::vector<std::uint8_t> isPdNode(mesh_.numNodes(), 0);
    for (std::size_t e = 0; e < elementIsPd_.extent(0); ++e)
      if (elementIsPd_(e))
        for (int a = 0; a < 4; ++a) isPdNode[mesh_.quads(e, a)] = 1;
    Kokkos::View<LocalIndex*, Kokkos::HostSpace> nodes("pd element nodes",
                                                       std::count(isPdNode.begin(), isPdNode.end(), 1));
    for (LocalIndex node = 0, k = 0; node < mesh_.numNodes(); ++node)
      if (isPdNode[node]) nodes(k++) = node;
    return nodes;
  }
  // Per mesh node, 1 where the last switch changed alpha or alphaBar, or a switched element has
  // a corner. Only these nodes' neighbours by a bond (whose bonds' morphing (alpha_i +
  // alpha_j)/2 changed) or an element (whose hybrid section 1 - alphaBar, or membership of the
  // shell body, changed) saw their bonds, elements and inertia change: the solver re-estimates
  // its critical step, inertia and energy there (CentralDifferenceSolver::replaceBodies).
  // alphaBar, a bond-weighted mean over a node's bonds, changes a horizon beyond alpha; a
  // corner whose alpha and alphaBar were 1 already still loses the element's shell stiffness.
  const Kokkos::View<std::uint8_t*, Memory>& changedNodes() const { return changedNodes_; }
  double criticalStretch() const { return criticalStretch_; }
  double threshold() const { return threshold_; }

  // Switches every CCM element whose largest surface strain in `state` reaches the threshold,
  // and every CCM element within the margin of one, to PD and rebuilds the bodies; returns how
  // many switched (0: bodies unchanged) and marks changedNodes().
  LocalIndex update(const pd::PdKinematics<Memory>& state) {
    if (bodies_.shellBody.numElements() == 0) return 0;
    shell::computeLargestSurfaceStrain(space_, bodies_.shellBody, state, inputs_.material.thickness, strain_);
    if (countCandidates() == 0) return 0;
    const auto strain = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, strain_);
    std::vector<LocalIndex> reached;  // shell body indices
    for (std::size_t k = 0; k < bodies_.ccmElements.size(); ++k)
      if (!elementIsPd_(bodies_.ccmElements[k]) && strain(k) >= threshold_) reached.push_back(k);
    const auto near = withinMargin(reached);
    LocalIndex switched = 0;
    Kokkos::View<std::uint8_t*, Kokkos::HostSpace> corners("adaptive switched corners", mesh_.numNodes());
    for (std::size_t k = 0; k < bodies_.ccmElements.size(); ++k) {
      const LocalIndex element = bodies_.ccmElements[k];
      if (!elementIsPd_(element) && near(k) > 0.0) {
        elementIsPd_(element) = 1;
        ++switched;
        for (int a = 0; a < 4; ++a) corners(mesh_.quads(element, a)) = 1;
      }
    }
    const auto previousAlpha = bodies_.alpha, previousAlphaBar = bodies_.alphaBar;
    rebuild();
    markChangedNodes(previousAlpha, previousAlphaBar, Kokkos::create_mirror_view_and_copy(Memory{}, corners));
    return switched;
  }

  // Public only because nvcc rejects extended lambdas in private member functions.
  LocalIndex countCandidates() const {
    LocalIndex count = 0;
    const auto strain = strain_;
    const auto isCcm = isCcmElement_;
    const double threshold = threshold_;
    Kokkos::parallel_reduce(
        "perishell::coupling::AdaptivePdZone::countCandidates",
        Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, strain.extent(0)),
        KOKKOS_LAMBDA(const LocalIndex k, LocalIndex& sum) { sum += isCcm(k) && strain(k) >= threshold ? 1 : 0; },
        count);
    return count;
  }

  // Public only because nvcc rejects extended lambdas in private member functions.
  void markChangedNodes(const VectorView<Memory>& previousAlpha, const VectorView<Memory>& previousAlphaBar,
                        const Kokkos::View<std::uint8_t*, Memory>& switchedCorners) {
    const auto alpha = bodies_.alpha, alphaBar = bodies_.alphaBar;
    const auto changed = changedNodes_;
    Kokkos::parallel_for(
        "perishell::coupling::AdaptivePdZone::markChangedNodes",
        Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, alpha.extent(0)), KOKKOS_LAMBDA(const LocalIndex node) {
          const bool morphed = alpha(node) != previousAlpha(node) || alphaBar(node) != previousAlphaBar(node);
          changed(node) = morphed || switchedCorners(node) ? 1 : 0;
        });
  }

 private:
  // Per shell body element, > 0 where its centre lies within margin of the centre of an
  // element in `reached` (which always count): the distance pass of the morphing field
  // (coupling/alpha_field.hpp) with the reached centres as its "PD nodes", linear profile.
  Kokkos::View<double*, Kokkos::HostSpace> withinMargin(const std::vector<LocalIndex>& reached) const {
    const auto& ccm = bodies_.ccmElements;
    CoordinateView<Kokkos::HostSpace> centres("adaptive element centres", ccm.size()),
        reachedCentres("adaptive reached centres", reached.size());
    for (std::size_t k = 0; k < ccm.size(); ++k)
      for (int d = 0; d < 3; ++d) {
        centres(k, d) = 0.0;
        for (int a = 0; a < 4; ++a) centres(k, d) += 0.25 * mesh_.coordinates(mesh_.quads(ccm[k], a), d);
      }
    Kokkos::View<double*, Kokkos::HostSpace> near("adaptive within margin", ccm.size());
    for (std::size_t r = 0; r < reached.size(); ++r) {
      near(reached[r]) = 1.0;
      for (int d = 0; d < 3; ++d) reachedCentres(r, d) = centres(reached[r], d);
    }
    if (margin_ > 0.0 && !reached.empty())
      Kokkos::deep_copy(near, computeAlphaField(space_, Kokkos::create_mirror_view_and_copy(Memory{}, centres),
                                                Kokkos::create_mirror_view_and_copy(Memory{}, reachedCentres),
                                                margin_, deck::TransitionProfile::Linear));
    return near;
  }

  void rebuild() {
    bodies_ = makeCoupledBodies(space_, mesh_, elementIsPd_, inputs_);
    const auto numShell = bodies_.ccmElements.size();
    Kokkos::View<std::uint8_t*, Kokkos::HostSpace> isCcm("adaptive shell element is ccm", numShell);
    for (std::size_t k = 0; k < numShell; ++k) isCcm(k) = elementIsPd_(bodies_.ccmElements[k]) ? 0 : 1;
    isCcmElement_ = Kokkos::create_mirror_view_and_copy(Memory{}, isCcm);
    strain_ = VectorView<Memory>("adaptive surface strain", numShell);
  }

  ExecutionSpaceT space_;
  const mesh::HostQuadMesh& mesh_;
  CouplingInputs inputs_;
  double margin_;  // [m]
  Kokkos::View<std::uint8_t*, Kokkos::HostSpace> elementIsPd_;
  CoupledBodies<Memory> bodies_;
  Kokkos::View<std::uint8_t*, Memory> isCcmElement_;
  Kokkos::View<std::uint8_t*, Memory> changedNodes_;
  VectorView<Memory> strain_;
  double criticalStretch_ = 0.0, threshold_ = 0.0;
};

// One check of the zone against the solver's current state; when elements switched, the
// solver continues on the grown bodies. Returns how many elements switched.
template <class ExecutionSpaceT, class SolverT>
LocalIndex growPdZone(AdaptivePdZone<ExecutionSpaceT>& zone, SolverT& solver) {
  const LocalIndex switched = zone.update(solver.kinematics());
  if (switched > 0) solver.replaceBodies(zone.bodies().pdBody, zone.bodies().shellElements(), zone.changedNodes());
  return switched;
}

}  // namespace perishell::coupling
