// The microbeam bond tangent (pd/bond_tangent.hpp) against central finite differences of the
// bond force, its rigid-body null space, its objectivity, and the same numbers on the device.
#include <perishell/pd/bond_tangent.hpp>

#include <Eigen/Dense>
#include <gtest/gtest.h>

#include <cmath>

namespace {

using perishell::pd::MicrobeamEnd;
using perishell::TangentForm;
using Matrix12 = Eigen::Matrix<double, 12, 12, Eigen::RowMajor>;

const perishell::pd::Micromoduli moduli = perishell::pd::microbeamMicromoduli(70e9, 0.25, 1e-3, 3e-3);
constexpr double referenceLength = 2.2e-3;

void rotationMatrix(const double axisAngle[3], double R[3][3]) {
  double q[4];
  perishell::rotation::exponential(axisAngle, q);
  perishell::rotation::toMatrix(q, R);
}

// A bond stretched by 1 %, bent out of plane and in plane, twisted, with end rotations
// of 0.2-0.5 rad: every mode and the frame terms are active.
void deformedBond(MicrobeamEnd ends[2]) {
  const double referenceI[3] = {0.0, 0.0, 0.0};
  const double direction[3] = {0.8, 0.6, 0.0};
  const double rotationI[3] = {0.31, -0.22, 0.4}, rotationJ[3] = {0.27, -0.18, 0.47};
  const double offsetJ[3] = {0.3e-5, -0.2e-5, 0.5e-3};
  for (int k = 0; k < 3; ++k) {
    ends[0].referencePosition[k] = referenceI[k];
    ends[1].referencePosition[k] = referenceI[k] + referenceLength * direction[k];
    ends[0].referenceNormal[k] = ends[1].referenceNormal[k] = k == 2 ? 1.0 : 0.0;
  }
  rotationMatrix(rotationI, ends[0].rotation);
  rotationMatrix(rotationJ, ends[1].rotation);
  // Current chord: the reference chord rotated like end i, stretched by 1 %, plus an offset.
  double chord[3];
  const double referenceChord[3] = {referenceLength * direction[0], referenceLength * direction[1], 0.0};
  perishell::rotation::apply(ends[0].rotation, referenceChord, chord);
  for (int k = 0; k < 3; ++k) {
    ends[0].position[k] = 1e-4 * (k + 1);
    ends[1].position[k] = ends[0].position[k] + 1.01 * chord[k] + offsetJ[k];
  }
}

// -(forces, moments) of the bond, in the tangent's order.
Eigen::Matrix<double, 12, 1> resistingForce(const MicrobeamEnd ends[2]) {
  perishell::pd::MicrobeamResponse response;
  perishell::pd::evaluateMicrobeam(moduli, ends[0], ends[1], referenceLength, response);
  Eigen::Matrix<double, 12, 1> f;
  for (int end = 0; end < 2; ++end)
    for (int k = 0; k < 3; ++k) {
      f(6 * end + k) = -response.force[end][k];
      f(6 * end + 3 + k) = -response.moment[end][k];
    }
  return f;
}

// Moves DOF `dof` by h: translations add, rotations compose as R <- exp(h e_k) R.
void perturb(MicrobeamEnd ends[2], int dof, double h) {
  MicrobeamEnd& end = ends[dof / 6];
  const int k = dof % 6;
  if (k < 3) {
    end.position[k] += h;
    return;
  }
  double axisAngle[3] = {0.0, 0.0, 0.0}, increment[3][3], updated[3][3];
  axisAngle[k - 3] = h;
  rotationMatrix(axisAngle, increment);
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      updated[a][b] = increment[a][0] * end.rotation[0][b] + increment[a][1] * end.rotation[1][b] +
                      increment[a][2] * end.rotation[2][b];
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) end.rotation[a][b] = updated[a][b];
}

Matrix12 tangentOf(const MicrobeamEnd ends[2], TangentForm form) {
  double K[12][12];
  perishell::pd::microbeamTangent(moduli, ends[0], ends[1], referenceLength, form, K);
  Matrix12 result;
  for (int r = 0; r < 12; ++r)
    for (int s = 0; s < 12; ++s) result(r, s) = K[r][s];
  return result;
}

// The same tangent computed by a kernel on the test's execution space.
Matrix12 tangentOnDevice(const MicrobeamEnd ends[2]) {
  Kokkos::View<MicrobeamEnd[2], TEST_MEMSPACE> deviceEnds("ends");
  auto hostEnds = Kokkos::create_mirror_view(deviceEnds);
  hostEnds(0) = ends[0];
  hostEnds(1) = ends[1];
  Kokkos::deep_copy(deviceEnds, hostEnds);
  Kokkos::View<double[12][12], Kokkos::LayoutRight, TEST_MEMSPACE> deviceTangent("tangent");
  const perishell::pd::Micromoduli bondModuli = moduli;  // a copy the lambda captures (no global on the device)
  Kokkos::parallel_for(
      "bond tangent on the device", Kokkos::RangePolicy<TEST_EXECSPACE>(0, 1), KOKKOS_LAMBDA(const int) {
        double K[12][12];
        perishell::pd::microbeamTangent(bondModuli, deviceEnds(0), deviceEnds(1), referenceLength,
                                        TangentForm::Symmetric, K);
        for (int r = 0; r < 12; ++r)
          for (int s = 0; s < 12; ++s) deviceTangent(r, s) = K[r][s];
      });
  const auto host = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, deviceTangent);
  Matrix12 result;
  for (int r = 0; r < 12; ++r)
    for (int s = 0; s < 12; ++s) result(r, s) = host(r, s);
  return result;
}

double relativeMaxDifference(const Matrix12& a, const Matrix12& b) {
  return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff();
}

}  // namespace

TEST(TEST_CATEGORY, bond_tangent_matches_finite_differences_of_the_bond_force) {
  MicrobeamEnd ends[2];
  deformedBond(ends);
  const Matrix12 exact = tangentOf(ends, TangentForm::Exact);
  Matrix12 finiteDifference;
  for (int dof = 0; dof < 12; ++dof) {
    const double h = dof % 6 < 3 ? 1e-6 * referenceLength : 1e-6;
    MicrobeamEnd plus[2] = {ends[0], ends[1]}, minus[2] = {ends[0], ends[1]};
    perturb(plus, dof, h);
    perturb(minus, dof, -h);
    finiteDifference.col(dof) = (resistingForce(plus) - resistingForce(minus)) / (2.0 * h);
  }
  // Rows and columns mix N/m, N and N m; compare block by block so each unit is judged on its own scale.
  for (int rowBlock = 0; rowBlock < 4; ++rowBlock)
    for (int columnBlock = 0; columnBlock < 4; ++columnBlock) {
      const Eigen::Matrix3d ad = exact.block<3, 3>(3 * rowBlock, 3 * columnBlock);
      const Eigen::Matrix3d fd = finiteDifference.block<3, 3>(3 * rowBlock, 3 * columnBlock);
      const double scale = finiteDifference.block<3, 12>(3 * rowBlock, 0).cwiseAbs().maxCoeff();
      EXPECT_LT((ad - fd).cwiseAbs().maxCoeff(), 1e-5 * scale) << "block " << rowBlock << ", " << columnBlock;
    }
  // The exact tangent is not symmetric away from equilibrium (spatial rotation increments);
  // the symmetric form is its symmetric part.
  const Matrix12 symmetric = tangentOf(ends, TangentForm::Symmetric);
  EXPECT_LT(relativeMaxDifference(symmetric, 0.5 * (exact + exact.transpose())), 1e-14);
  EXPECT_GT(relativeMaxDifference(exact, exact.transpose()), 1e-6);
}

TEST(TEST_CATEGORY, bond_tangent_at_rest_is_symmetric_semidefinite_with_six_rigid_modes) {
  MicrobeamEnd ends[2];
  deformedBond(ends);
  for (int end = 0; end < 2; ++end)
    for (int a = 0; a < 3; ++a) {
      ends[end].position[a] = ends[end].referencePosition[a];
      for (int b = 0; b < 3; ++b) ends[end].rotation[a][b] = a == b ? 1.0 : 0.0;
    }
  const Matrix12 exact = tangentOf(ends, TangentForm::Exact);
  EXPECT_LT(relativeMaxDifference(exact, exact.transpose()), 1e-12);
  // Unit-consistent scaling: rotations times the bond length make every entry N/m.
  Eigen::Matrix<double, 12, 1> scale;
  for (int dof = 0; dof < 12; ++dof) scale(dof) = dof % 6 < 3 ? 1.0 : 1.0 / referenceLength;
  const Matrix12 scaled = scale.asDiagonal() * exact * scale.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Matrix12> eigen(scaled);
  const auto values = eigen.eigenvalues();
  const double largest = values.cwiseAbs().maxCoeff();
  int rigidModes = 0;
  for (int k = 0; k < 12; ++k) {
    EXPECT_GT(values(k), -1e-12 * largest);
    if (std::abs(values(k)) < 1e-10 * largest) ++rigidModes;
  }
  // Three translations and three rotations of the pair; the other six (stretch, twist, and
  // symmetric and antisymmetric bending in two planes) all store energy.
  EXPECT_EQ(rigidModes, 6);
}

TEST(TEST_CATEGORY, bond_tangent_is_objective_and_the_same_on_the_device) {
  MicrobeamEnd ends[2];
  deformedBond(ends);
  const Matrix12 tangent = tangentOf(ends, TangentForm::Symmetric);
  // Rotate the whole deformed state rigidly by 90 degrees about a skew axis.
  const double angle = 1.5707963267948966;
  const double axisAngle[3] = {angle / std::sqrt(3.0), angle / std::sqrt(3.0), angle / std::sqrt(3.0)};
  double Q[3][3];
  rotationMatrix(axisAngle, Q);
  MicrobeamEnd rotated[2] = {ends[0], ends[1]};
  for (int end = 0; end < 2; ++end) {
    perishell::rotation::apply(Q, ends[end].position, rotated[end].position);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        rotated[end].rotation[a][b] =
            Q[a][0] * ends[end].rotation[0][b] + Q[a][1] * ends[end].rotation[1][b] + Q[a][2] * ends[end].rotation[2][b];
  }
  Matrix12 blockQ = Matrix12::Zero();
  for (int block = 0; block < 4; ++block)
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) blockQ(3 * block + a, 3 * block + b) = Q[a][b];
  const Matrix12 rotatedTangent = tangentOf(rotated, TangentForm::Symmetric);
  EXPECT_LT(relativeMaxDifference(rotatedTangent, blockQ * tangent * blockQ.transpose()), 1e-10);

  EXPECT_LT(relativeMaxDifference(tangentOnDevice(ends), tangent), 1e-13);
}
