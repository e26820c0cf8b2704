#pragma once
// The implicit solver's bond stiffness (issue 5, paper eq. 36-40): the 12x12 tangent of one
// microbeam bond is the exact derivative of the force the explicit kernel applies
// (pd/microbeam.hpp), taken by forward-mode automatic differentiation (core/dual.hpp) with
// respect to the end translations and spatial rotation increments (R <- exp(phi) R, model.md
// §5). It therefore holds the material part (paper K_L) and the initial-stress part (K_S),
// plus the frame-rotation terms the paper drops (K_N). Symmetrised for CG: the asymmetric
// remainder is proportional to the end moments and vanishes with them.
#include <perishell/assembly/mirror_images.hpp>
#include <perishell/pd/bond_forces.hpp>

namespace perishell::pd {

// K = -d(forces, moments)/d(u_i, phi_i, u_j, phi_j) per unit V_i V_j (Exact), or its
// symmetric part (what CG solves with); order of rows and columns: end i's ux uy uz rx ry
// rz, then end j's.
KOKKOS_INLINE_FUNCTION void microbeamTangent(const Micromoduli& c, const MicrobeamEnd& i, const MicrobeamEnd& j,
                                             double referenceLength, TangentForm form, double tangent[12][12]) {
  using D = Dual<double>;
  const MicrobeamEnd* ends[2] = {&i, &j};
  for (int column = 0; column < 12; ++column) {
    const int seededEnd = column / 6, seededDof = column % 6;
    MicrobeamEndT<D> dual[2];
    for (int end = 0; end < 2; ++end) {
      const MicrobeamEnd& source = *ends[end];
      D phi[3];
      for (int k = 0; k < 3; ++k) {
        const bool seeded = end == seededEnd;
        dual[end].referencePosition[k] = source.referencePosition[k];
        dual[end].referenceNormal[k] = source.referenceNormal[k];
        dual[end].position[k] = D(source.position[k], seeded && seededDof == k ? 1.0 : 0.0);
        phi[k] = D(0.0, seeded && seededDof == 3 + k ? 1.0 : 0.0);
      }
      rotation::rotateBySpatialIncrementToSecondOrder(phi, source.rotation, dual[end].rotation);
    }
    MicrobeamResponseT<D> response;
    evaluateMicrobeam(c, dual[0], dual[1], referenceLength, response);
    for (int end = 0; end < 2; ++end)
      for (int k = 0; k < 3; ++k) {
        tangent[6 * end + k][column] = -response.force[end][k].derivative;
        tangent[6 * end + 3 + k][column] = -response.moment[end][k].derivative;
      }
  }
  if (form == TangentForm::Exact) return;
  for (int r = 0; r < 12; ++r)
    for (int s = r + 1; s < 12; ++s) {
      const double mean = 0.5 * (tangent[r][s] + tangent[s][r]);
      tangent[r][s] = mean;
      tangent[s][r] = mean;
    }
}

// Adds every intact bond's tangent in the given form, scaled by its volume weight, into the CRS values through
// the pattern's precomputed slots (one thread per bond, atomic_add: paper §3.2.1). The
// pattern's bond b is the body's half bond b, its ends mapped to the pattern's node numbers:
// the nodes that carry their DOFs, a mirror image's end mapped onto its master's (images).
template <class ExecutionSpaceT, class MemorySpaceT, class PatternT>
void assembleBondTangent(const ExecutionSpaceT& space, const PdBody<MemorySpaceT>& body,
                         const PdKinematics<MemorySpaceT>& state, const BondFlagView<MemorySpaceT>& intact,
                         const PatternT& pattern, const VectorView<MemorySpaceT>& values,
                         TangentForm form = TangentForm::Symmetric,
                         const assembly::MirrorImages<MemorySpaceT>& images = {}) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  Kokkos::parallel_for(
      "perishell::pd::assembleBondTangent", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, body.bonds.numBonds()),
      KOKKOS_LAMBDA(const RowOffset b) {
        if (!intact(b)) return;
        const LocalIndex i = body.bonds.halfBonds(b, 0), j = body.bonds.halfBonds(b, 1);
        MicrobeamEnd ends[2];
        detail::loadBondEnd(body, state, i, ends[0]);
        detail::loadBondEnd(body, state, j, ends[1]);
        double tangent[12][12];
        microbeamTangent(bondMicromoduli(body, b), ends[0], ends[1], body.bonds.referenceLength(b),
                         form, tangent);
        const double weight = bondVolumeWeight(body, i, j, b);
        for (int r = 0; r < 12; ++r)
          for (int s = 0; s < 12; ++s) tangent[r][s] *= weight;
        images.mapBondTangent(i, j, tangent);
        pattern.atomicAddBondMatrix(static_cast<LocalIndex>(b), tangent, values);
      });
}

}  // namespace perishell::pd
