#pragma once
// The isotropic plane-stress shell section shared by the shell elements (model.md §4): its
// parameters, the generalised strains' order and the section stiffness D on them.
#include <Kokkos_Core.hpp>

#include <cmath>
#include <stdexcept>
#include <string>

namespace perishell::shell {

// Isotropic plane-stress section.
struct ShellSection {
  double youngModulus = 0.0;          // E [Pa]
  double poissonRatio = 0.0;          // nu [-]
  double thickness = 0.0;             // t [m]
  double shearCorrection = 5.0 / 6.0;  // kappa of the transverse shear stiffness kappa G t
  // Drilling penalty: energy 1/2 (drillingFactor G t) * integral of (theta_z - omega)^2 dA,
  // omega = 1/2 (dv/dx - du/dy), integrated at the 2x2 Gauss points: at the centre alone
  // the four theta_z would share one constraint and a checkerboard of theta_z would cost
  // no energy on a regular mesh (a singular tangent). Where facets meet at an angle (curved
  // and twisted shells) it is also what ties one facet's in-plane rotation to its
  // neighbour's bending: too weak a tie converges to a too flexible shell (the MacNeal-Harder
  // twisted beam, refined to 48 x 8: 1.32 of the reference at 1e-3, 1.03 at 1e-2, 1.001 at
  // 0.1), too strong a one stiffens the membrane (pinched hemisphere 16 x 16: 0.987 at 0.1,
  // 0.962 at 1; Hughes & Brezzi's gamma = G is the factor 1). The patch tests stay exact for
  // any factor (theta_z = omega there). Measured in docs/verification.md.
  double drillingFactor = 0.1;
  // Membrane hourglass stiffness coefficient r of the explicit one-point element
  // (shell/one_point_shell.hpp; LS-DYNA's default QM is 0.1). MITC4 has no hourglass modes.
  double hourglassCoefficient = 0.1;
};

// Generalised strains at a point, in the element frame: membrane eps_xx eps_yy gamma_xy;
// curvatures kappa_xx kappa_yy kappa_xy (engineering); transverse shear gamma_xz gamma_yz;
// drilling mismatch theta_z - omega.
constexpr int shellStrainCount = 9;

// Host checks (bad input gets a message naming the item and the reason).
inline void checkShellSection(const ShellSection& section) {
  if (!(section.youngModulus > 0.0) || !std::isfinite(section.youngModulus))
    throw std::invalid_argument("shell section: young modulus must be positive, got " +
                                std::to_string(section.youngModulus));
  if (!(section.poissonRatio > -1.0 && section.poissonRatio < 0.5))
    throw std::invalid_argument("shell section: poisson ratio must lie in (-1, 0.5), got " +
                                std::to_string(section.poissonRatio));
  if (!(section.thickness > 0.0) || !std::isfinite(section.thickness))
    throw std::invalid_argument("shell section: thickness must be positive, got " +
                                std::to_string(section.thickness));
  if (!(section.shearCorrection > 0.0) || !std::isfinite(section.shearCorrection))
    throw std::invalid_argument("shell section: shear correction must be positive, got " +
                                std::to_string(section.shearCorrection));
  if (!(section.drillingFactor > 0.0) || !std::isfinite(section.drillingFactor))
    throw std::invalid_argument("shell section: drilling factor must be positive, got " +
                                std::to_string(section.drillingFactor));
  if (!(section.hourglassCoefficient > 0.0) || !std::isfinite(section.hourglassCoefficient))
    throw std::invalid_argument("shell section: hourglass coefficient must be positive, got " +
                                std::to_string(section.hourglassCoefficient));
}

// Section stiffness on the generalised strains (diagonal blocks): membrane E t/(1-nu^2)
// [1 nu 0; nu 1 0; 0 0 (1-nu)/2], bending the same times t^2/12, shear kappa G t, drilling
// drillingFactor G t (model.md §4).
KOKKOS_INLINE_FUNCTION void shellSectionStiffness(const ShellSection& section,
                                                  double D[shellStrainCount][shellStrainCount]) {
  const double E = section.youngModulus, nu = section.poissonRatio, t = section.thickness;
  const double membrane = E * t / (1.0 - nu * nu);
  const double bending = membrane * t * t / 12.0;
  const double shearModulus = E / (2.0 * (1.0 + nu));
  for (int r = 0; r < shellStrainCount; ++r)
    for (int c = 0; c < shellStrainCount; ++c) D[r][c] = 0.0;
  for (int block = 0; block < 2; ++block) {
    const int o = 3 * block;
    const double scale = block == 0 ? membrane : bending;
    D[o][o] = D[o + 1][o + 1] = scale;
    D[o][o + 1] = D[o + 1][o] = scale * nu;
    D[o + 2][o + 2] = scale * 0.5 * (1.0 - nu);
  }
  D[6][6] = D[7][7] = section.shearCorrection * shearModulus * t;
  D[8][8] = section.drillingFactor * shearModulus * t;
}

}  // namespace perishell::shell
