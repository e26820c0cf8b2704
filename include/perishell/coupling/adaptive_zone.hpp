#pragma once
// The PD zone that grows with the load (issue 6, beyond the paper): a CCM element whose
// largest surface strain reaches strainFraction x the bonds' critical stretch s_c (model.md
// §3: 1/2 c_ax s_c^2 xi = w_c, so s_c = sqrt(2 w_c / (c_ax xi))) turns PD; the coupled
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

  // elementIsPd: the starting zone (copied). Throws std::invalid_argument without a fracture
  // energy (there is no critical stretch) or with strainFraction outside (0, 1].
  AdaptivePdZone(const ExecutionSpaceT& space, const mesh::HostQuadMesh& mesh,
                 const Kokkos::View<const std::uint8_t*, Kokkos::HostSpace>& elementIsPd, const CouplingInputs& inputs,
                 double strainFraction)
      : space_(space), mesh_(mesh), inputs_(inputs),
        elementIsPd_("adaptive element is pd", elementIsPd.extent(0)) {
    if (!inputs.material.fractureEnergy)
      throw std::invalid_argument("adaptive PD zone: needs material.fracture-energy (the switch compares strains "
                                  "with the bonds' critical stretch)");
    if (!(strainFraction > 0.0 && strainFraction <= 1.0))
      throw std::invalid_argument("adaptive PD zone: the strain fraction must lie in (0, 1], got " +
                                  std::to_string(strainFraction));
    Kokkos::deep_copy(elementIsPd_, elementIsPd);
    const auto& material = inputs.material;
    const double axial =
        pd::microbeamMicromoduli(material.youngModulus, material.poissonRatio, material.thickness, inputs.horizon).axial;
    criticalStretch_ = std::sqrt(
        2.0 * pd::criticalMicropotentialPerLength(*material.fractureEnergy, material.thickness, inputs.horizon) / axial);
    threshold_ = strainFraction * criticalStretch_;
    rebuild();
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
  double criticalStretch() const { return criticalStretch_; }
  double threshold() const { return threshold_; }

  // Switches every CCM element whose largest surface strain in `state` reaches the threshold
  // to PD and rebuilds the bodies; returns how many switched (0: bodies unchanged).
  LocalIndex update(const pd::PdKinematics<Memory>& state) {
    if (bodies_.shellBody.numElements() == 0) return 0;
    shell::computeLargestSurfaceStrain(space_, bodies_.shellBody, state, inputs_.material.thickness, strain_);
    if (countCandidates() == 0) return 0;
    const auto strain = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, strain_);
    LocalIndex switched = 0;
    for (std::size_t k = 0; k < bodies_.ccmElements.size(); ++k) {
      const LocalIndex element = bodies_.ccmElements[k];
      if (!elementIsPd_(element) && strain(k) >= threshold_) {
        elementIsPd_(element) = 1;
        ++switched;
      }
    }
    rebuild();
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

 private:
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
  Kokkos::View<std::uint8_t*, Kokkos::HostSpace> elementIsPd_;
  CoupledBodies<Memory> bodies_;
  Kokkos::View<std::uint8_t*, Memory> isCcmElement_;
  VectorView<Memory> strain_;
  double criticalStretch_ = 0.0, threshold_ = 0.0;
};

// One check of the zone against the solver's current state; when elements switched, the
// solver continues on the grown bodies. Returns how many elements switched.
template <class ExecutionSpaceT, class SolverT>
LocalIndex growPdZone(AdaptivePdZone<ExecutionSpaceT>& zone, SolverT& solver) {
  const LocalIndex switched = zone.update(solver.kinematics());
  if (switched > 0) solver.replaceBodies(zone.bodies().pdBody, zone.bodies().shellElements());
  return switched;
}

}  // namespace perishell::coupling
