#pragma once
// The largest principal strain on either face of each shell element, at its centre: the
// membrane strain plus or minus t/2 times the curvature, from the corotational
// deformational DOF (shell/mitc4_shell.hpp). The adaptive PD zone compares it with the
// bonds' critical stretch (coupling/adaptive_zone.hpp). One thread per element.
#include <perishell/shell/shell_body.hpp>

namespace perishell::shell {

template <class ExecutionSpaceT, class MemorySpaceT>
void computeLargestSurfaceStrain(const ExecutionSpaceT& space, const ShellBody<MemorySpaceT>& body,
                                 const pd::PdKinematics<MemorySpaceT>& state, double thickness,
                                 const VectorView<MemorySpaceT>& strain) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  Kokkos::parallel_for(
      "perishell::shell::computeLargestSurfaceStrain", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, body.numElements()),
      KOKKOS_LAMBDA(const LocalIndex e) {
        double reference[4][3], current[4][3], rotations[4][3][3];
        detail::loadElement(body, state, e, reference, current, rotations);
        const ShellReference local = shellReference(reference);
        double d[shellDofCount], B[shellStrainCount][shellDofCount], generalised[6] = {0, 0, 0, 0, 0, 0};
        detail::deformationalDofs(local, current, rotations, d);
        linkWarpedDofsToFlat(local, d);  // strains of the flat element K_l stands for
        shellCentreStrainDisplacement(local, B, body.quadraticEdges(e));
        for (int r = 0; r < 6; ++r)  // membrane eps_xx eps_yy gamma_xy, curvatures kappa_xx kappa_yy kappa_xy
          for (int c = 0; c < shellDofCount; ++c) generalised[r] += B[r][c] * d[c];
        double largest = 0.0;
        for (const double z : {-0.5 * thickness, 0.5 * thickness}) {
          const double xx = generalised[0] + z * generalised[3], yy = generalised[1] + z * generalised[4];
          const double halfShear = 0.5 * (generalised[2] + z * generalised[5]);
          const double principal =
              0.5 * (xx + yy) + Kokkos::Experimental::sqrt(0.25 * (xx - yy) * (xx - yy) + halfShear * halfShear);
          if (principal > largest) largest = principal;
        }
        strain(e) = largest;
      });
}

}  // namespace perishell::shell
