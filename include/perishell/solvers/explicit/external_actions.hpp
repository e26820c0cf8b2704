#pragma once
// Loads and supports as the explicit solver applies them on the device: fixed-direction
// load patterns scaled by their curve at each step, and prescribed DOFs whose velocity
// follows their value times the change of their curve. Built once from the host data of
// model/nodal_loads.hpp; per step only the curve factors (a few doubles) travel.
#include <perishell/assembly/mirror_images.hpp>
#include <perishell/io/deck.hpp>
#include <perishell/pd/pd_body.hpp>

#include <optional>
#include <vector>

namespace perishell::solvers {

// Curves per kind are capped so that their factors travel in a kernel's arguments.
inline constexpr int maxCurvesPerKind = 8;

struct CurveFactors {
  double values[maxCurvesPerKind] = {};
};

// What the supports prescribe at one time or load factor: value x the curve's factor, or x
// constantFactor for a value without a curve (1 in time, the load factor in statics).
template <class MemorySpaceT>
struct PrescribedTargets {
  pd::NodalVectorView<MemorySpaceT> value;
  Kokkos::View<std::int8_t* [6], Kokkos::LayoutRight, MemorySpaceT> curveIndex;
  CurveFactors factors;
  double constantFactor = 1.0;

  KOKKOS_INLINE_FUNCTION double operator()(LocalIndex node, int d) const {
    const int curve = curveIndex(node, d);
    return value(node, d) * (curve < 0 ? constantFactor : factors.values[curve]);
  }
};

template <class MemorySpaceT>
struct ExternalActions {
  // nodes x (6 per pattern): pattern p's nodal loads in columns 6p .. 6p+5 [N, N m]
  Kokkos::View<double**, Kokkos::LayoutRight, MemorySpaceT> loadPatterns;
  std::vector<std::optional<deck::Curve>> patternCurves;  // none: factor 1 at all times
  Kokkos::View<std::uint8_t*, MemorySpaceT> constrainedDofs;   // bit d: DOF d prescribed
  pd::NodalVectorView<MemorySpaceT> prescribedValue;            // [m, rad]
  Kokkos::View<std::int8_t* [6], Kokkos::LayoutRight, MemorySpaceT> supportCurveIndex;  // -1: constant
  std::vector<deck::Curve> supportCurves;
  // Support-layer nodes that move as images of mesh nodes; constrainedDofs holds all their DOFs.
  assembly::MirrorImages<MemorySpaceT> mirrorImages;

  int numPatterns() const { return static_cast<int>(patternCurves.size()); }

  CurveFactors loadFactors(double time) const {
    CurveFactors factors;
    for (int p = 0; p < numPatterns(); ++p)
      factors.values[p] = patternCurves[p] ? deck::evaluateCurve(*patternCurves[p], time) : 1.0;
    return factors;
  }
  CurveFactors supportFactors(double time) const {
    CurveFactors factors;
    for (std::size_t s = 0; s < supportCurves.size(); ++s) factors.values[s] = deck::evaluateCurve(supportCurves[s], time);
    return factors;
  }
  PrescribedTargets<MemorySpaceT> prescribedAt(double timeOrLoadFactor, double constantFactor) const {
    return {prescribedValue, supportCurveIndex, supportFactors(timeOrLoadFactor), constantFactor};
  }
};

// No loads and no supports, for a body set in motion by initial conditions.
template <class MemorySpaceT>
ExternalActions<MemorySpaceT> makeFreeActions(LocalIndex numNodes) {
  ExternalActions<MemorySpaceT> actions;
  actions.loadPatterns = Kokkos::View<double**, Kokkos::LayoutRight, MemorySpaceT>("load patterns", numNodes, 0);
  actions.constrainedDofs = Kokkos::View<std::uint8_t*, MemorySpaceT>("constrained dofs", numNodes);
  actions.prescribedValue = pd::NodalVectorView<MemorySpaceT>("prescribed values", numNodes);
  actions.supportCurveIndex = Kokkos::View<std::int8_t* [6], Kokkos::LayoutRight, MemorySpaceT>("support curves", numNodes);
  Kokkos::deep_copy(actions.supportCurveIndex, std::int8_t(-1));
  actions.mirrorImages = assembly::makeMirrorImages<MemorySpaceT>(mesh::SupportLayer{}, numNodes);
  return actions;
}

}  // namespace perishell::solvers
