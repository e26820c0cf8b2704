#pragma once
// The microbeam bond (model.md §2, paper eq. 1-16): a two-node beam between PD nodes i and j
// carrying stretch, out-of-plane bending, in-plane bending and torsion. Corotational: the
// bond's frame follows the chord and the mean nodal normal, and each end's rotation is
// measured relative to that frame, so a rigid motion of any size leaves every generalised
// strain at zero (model.md §5). Written once for host and device.
#include <perishell/core/rotation.hpp>

#include <stdexcept>
#include <string>

namespace perishell::pd {

// Micromoduli of paper eq. 16 as checked in model.md §2 (energy forms there).
struct Micromoduli {
  double axial = 0.0;               // c_ax [N/m^6]
  double outOfPlaneBending = 0.0;   // c_by [N/m^4]
  double inPlaneBending = 0.0;      // c_bz [N/m^4]
  double torsion = 0.0;             // c_tor [N/m^4]
};

// Throws std::invalid_argument for parameters the model cannot represent: nu > 1/3 makes
// the in-plane bending and torsion moduli negative (model.md §2).
inline Micromoduli microbeamMicromoduli(double youngModulus, double poissonRatio, double thickness,
                                        double horizon) {
  if (!(youngModulus > 0.0) || !(thickness > 0.0) || !(horizon > 0.0))
    throw std::invalid_argument("microbeam micromoduli need E > 0, t > 0 and delta > 0");
  if (!(poissonRatio > -1.0 && poissonRatio <= 1.0 / 3.0))
    throw std::invalid_argument("microbeam bonds need a Poisson ratio in (-1, 1/3], got " +
                                std::to_string(poissonRatio) +
                                " (above 1/3 the in-plane bending and torsion micromoduli are negative)");
  const double pi = 3.14159265358979323846;
  const double E = youngModulus, nu = poissonRatio, t = thickness, d = horizon;
  Micromoduli c;
  c.axial = 6.0 * E / (pi * t * d * d * d * (1.0 - nu));
  c.outOfPlaneBending = E * t / (2.0 * pi * d * d * d * (1.0 - nu));
  c.inPlaneBending = E * (1.0 - 3.0 * nu) / (6.0 * pi * t * d * (1.0 - nu * nu));
  c.torsion = E * t * (1.0 - 3.0 * nu) / (2.0 * pi * d * d * d * (1.0 - nu * nu));
  return c;
}

// The moduli of one bond: the body's micromoduli times the bond's stiffness scales
// (PdBody::stiffnessScale), one per weighting of the homogeneous-field energy: by xi
// (axial, out-of-plane bending, torsion) and by 1/xi (in-plane bending).
KOKKOS_INLINE_FUNCTION Micromoduli correctedMicromoduli(const Micromoduli& c, double lengthWeightedScale,
                                                        double inverseLengthWeightedScale) {
  return {c.axial * lengthWeightedScale, c.outOfPlaneBending * lengthWeightedScale,
          c.inPlaneBending * inverseLengthWeightedScale, c.torsion * lengthWeightedScale};
}

// A bond breaks when its micropotential reaches w_c = 2 G_c xi / (t delta^4) (model.md §3):
// this is the factor 2 G_c / (t delta^4) that multiplies xi.
inline double criticalMicropotentialPerLength(double fractureEnergy, double thickness, double horizon) {
  return 2.0 * fractureEnergy / (thickness * horizon * horizon * horizon * horizon);
}

// One end of a bond: reference and current position, reference unit normal and the node's
// finite rotation (reference to current). The current state is of scalar type T: double,
// or a dual number when the implicit solver differentiates the bond (pd/bond_tangent.hpp).
template <class T>
struct MicrobeamEndT {
  double referencePosition[3];
  T position[3];
  double referenceNormal[3];
  T rotation[3][3];
};
using MicrobeamEnd = MicrobeamEndT<double>;

// Internal forces and moments on both ends per unit V_i V_j (the caller scales by the
// volumes and the partial-volume factor), and the micropotential w_ij [J/m^6].
template <class T>
struct MicrobeamResponseT {
  T force[2][3];
  T moment[2][3];
  T micropotential;
};
using MicrobeamResponse = MicrobeamResponseT<double>;

namespace detail {
// Scales a to unit length with one division; returns the length it had and its inverse.
template <class T>
KOKKOS_INLINE_FUNCTION T normaliseOnce(T a[3], T& inverseLength) {
  const T length = rotation::norm(a);
  inverseLength = 1.0 / length;
  for (int k = 0; k < 3; ++k) a[k] *= inverseLength;
  return length;
}

// Orthonormal frame (e1 along the chord, e3 the mean normal made orthogonal to e1,
// e2 = e3 x e1), as rows of frame. Returns the chord length and its inverse.
template <class T>
KOKKOS_INLINE_FUNCTION T bondFrame(const T chord[3], const T normalI[3], const T normalJ[3], T frame[3][3],
                                   T& inverseLength) {
  using namespace rotation;
  for (int k = 0; k < 3; ++k) frame[0][k] = chord[k];
  const T length = normaliseOnce(frame[0], inverseLength);
  // The mean normal's factor 1/2 drops out in the normalisation.
  const T along = dot(normalI, frame[0]) + dot(normalJ, frame[0]);
  for (int k = 0; k < 3; ++k) frame[2][k] = normalI[k] + normalJ[k] - along * frame[0][k];
  T unused;
  normaliseOnce(frame[2], unused);
  cross(frame[2], frame[0], frame[1]);
  return length;
}

// Rotation vector, in the current bond frame, of an end's rotation relative to the frame:
// log(E^T R E0) with E, E0 the current and reference frames (columns e1 e2 e3).
template <class T>
KOKKOS_INLINE_FUNCTION void relativeRotation(const T frame[3][3], const T rotationMatrix[3][3],
                                             const double referenceFrame[3][3], T theta[3]) {
  T relative[3][3];
  for (int b = 0; b < 3; ++b) {
    T rotatedAxis[3];
    const T axis[3] = {referenceFrame[b][0], referenceFrame[b][1], referenceFrame[b][2]};
    rotation::apply(rotationMatrix, axis, rotatedAxis);
    for (int a = 0; a < 3; ++a) relative[a][b] = rotation::dot(frame[a], rotatedAxis);
  }
  rotation::logarithm(relative, theta);
}
}  // namespace detail

// Generalised strains: stretch s = (l - xi)/xi; end rotations about e1 (twist), e2
// (out-of-plane bending) and e3 (in-plane bending) relative to the corotated frame. Energy
// (model.md §2): w = 1/2 c_ax s^2 xi + (2 c_by/xi)(a_i^2 + a_i a_j + a_j^2)
//                 + (2 c_bz/xi)(b_i^2 + b_i b_j + b_j^2) + 1/2 c_tor (tau_j - tau_i)^2 / xi.
// Forces are its variation: the chord's spin moves a and b by +-(du_j - du_i).e3/l and
// -+(du_j - du_i).e2/l, so the end shears balance the end moments about the current chord
// and the bond carries no net force or moment (momentum is conserved exactly).
template <class T>
KOKKOS_INLINE_FUNCTION void evaluateMicrobeam(const Micromoduli& c, const MicrobeamEndT<T>& i,
                                              const MicrobeamEndT<T>& j, double referenceLength,
                                              MicrobeamResponseT<T>& out) {
  double referenceChord[3];
  T chord[3], currentNormalI[3], currentNormalJ[3];
  for (int k = 0; k < 3; ++k) {
    referenceChord[k] = j.referencePosition[k] - i.referencePosition[k];
    chord[k] = j.position[k] - i.position[k];
  }
  const T referenceNormalI[3] = {i.referenceNormal[0], i.referenceNormal[1], i.referenceNormal[2]};
  const T referenceNormalJ[3] = {j.referenceNormal[0], j.referenceNormal[1], j.referenceNormal[2]};
  rotation::apply(i.rotation, referenceNormalI, currentNormalI);
  rotation::apply(j.rotation, referenceNormalJ, currentNormalJ);
  double referenceFrame[3][3];
  T frame[3][3];
  double inverseReferenceChord;
  detail::bondFrame(referenceChord, i.referenceNormal, j.referenceNormal, referenceFrame, inverseReferenceChord);
  T inverseLength;
  const T length = detail::bondFrame(chord, currentNormalI, currentNormalJ, frame, inverseLength);
  T thetaI[3], thetaJ[3];
  detail::relativeRotation(frame, i.rotation, referenceFrame, thetaI);
  detail::relativeRotation(frame, j.rotation, referenceFrame, thetaJ);

  const double xi = referenceLength, inverseXi = 1.0 / referenceLength;
  const T stretch = (length - xi) * inverseXi;
  const T twist = thetaJ[0] - thetaI[0];
  const double kBy = 2.0 * c.outOfPlaneBending * inverseXi, kBz = 2.0 * c.inPlaneBending * inverseXi;
  const T axialForce = c.axial * stretch;
  const T torque = c.torsion * twist * inverseXi;
  const T momentByI = kBy * (2.0 * thetaI[1] + thetaJ[1]), momentByJ = kBy * (2.0 * thetaJ[1] + thetaI[1]);
  const T momentBzI = kBz * (2.0 * thetaI[2] + thetaJ[2]), momentBzJ = kBz * (2.0 * thetaJ[2] + thetaI[2]);
  out.micropotential =
      0.5 * c.axial * stretch * stretch * xi +
      kBy * (thetaI[1] * thetaI[1] + thetaI[1] * thetaJ[1] + thetaJ[1] * thetaJ[1]) +
      kBz * (thetaI[2] * thetaI[2] + thetaI[2] * thetaJ[2] + thetaJ[2] * thetaJ[2]) +
      0.5 * c.torsion * twist * twist * inverseXi;

  const T shearAlongE3 = (momentByI + momentByJ) * inverseLength;
  const T shearAlongE2 = -(momentBzI + momentBzJ) * inverseLength;
  for (int k = 0; k < 3; ++k) {
    // dw/dx_j; dw/dx_i is its negative.
    const T gradientJ = axialForce * frame[0][k] + shearAlongE2 * frame[1][k] + shearAlongE3 * frame[2][k];
    out.force[0][k] = gradientJ;
    out.force[1][k] = -gradientJ;
    out.moment[0][k] = -(-torque * frame[0][k] + momentByI * frame[1][k] + momentBzI * frame[2][k]);
    out.moment[1][k] = -(torque * frame[0][k] + momentByJ * frame[1][k] + momentBzJ * frame[2][k]);
  }
}

}  // namespace perishell::pd
