// The microbeam bond and the bond force kernel: micromoduli (model.md §2), strain-energy
// equivalence with classical plate theory at interior nodes, objectivity under large rigid
// rotations, the two force mappings against each other, and energy-based breaking (§3).
#include <perishell/mesh/generators.hpp>
#include <perishell/pd/bond_forces.hpp>
#include <perishell/pd/make_body.hpp>

#include <array>
#include <cmath>
#include <functional>
#include <map>
#include <random>

namespace {

using perishell::LocalIndex;
using perishell::deck::ForceKernel;
using Body = perishell::pd::PdBody<TEST_MEMSPACE>;
using HostNodal = perishell::pd::NodalVectorView<Kokkos::HostSpace>;
using Matrix3 = std::array<std::array<double, 3>, 3>;

constexpr double pi = 3.14159265358979323846;

struct PlateBody {
  perishell::mesh::ShellMesh shell;
  Body body;
  perishell::pd::PdMaterial material;
  double spacing;
};

Matrix3 rotationAbout(std::array<double, 3> axis, double angle);

// tilt: a rigid rotation of the whole mesh before the body is built (identity: the x-y plane).
PlateBody makePlateBody(double poissonRatio, std::optional<double> fractureEnergy = {}, int cells = 24,
                        double horizonFactor = 3.0, const Matrix3& tilt = rotationAbout({0, 0, 1}, 0.0)) {
  const double spacing = 1e-3;
  PlateBody plate{perishell::mesh::makePlate(cells * spacing, cells * spacing, spacing), {}, {}, spacing};
  auto& x = plate.shell.mesh.coordinates;
  for (LocalIndex node = 0; node < plate.shell.mesh.numNodes(); ++node) {
    const double X[3] = {x(node, 0), x(node, 1), x(node, 2)};
    for (int r = 0; r < 3; ++r) x(node, r) = tilt[r][0] * X[0] + tilt[r][1] * X[1] + tilt[r][2] * X[2];
  }
  plate.material = {70e9, poissonRatio, 0.4e-3, fractureEnergy};
  const auto nodes = perishell::pd::allNodes(plate.shell.mesh.numNodes());
  plate.body = perishell::pd::makePdBody(TEST_EXECSPACE{}, plate.shell.mesh, nodes, plate.material,
                                         horizonFactor * spacing, spacing, {});
  return plate;
}

// Host kinematics: per node a displacement and a rotation given as a matrix.
struct HostKinematics {
  perishell::CoordinateView<Kokkos::HostSpace> displacements;
  perishell::pd::RotationView<Kokkos::HostSpace> rotations;
};

void quaternionFromMatrix(const Matrix3& R, double q[4]) {
  // Shepperd's method on the largest diagonal combination.
  const double trace = R[0][0] + R[1][1] + R[2][2];
  if (trace > 0.0) {
    const double s = 2.0 * std::sqrt(1.0 + trace);
    q[0] = 0.25 * s;
    q[1] = (R[2][1] - R[1][2]) / s;
    q[2] = (R[0][2] - R[2][0]) / s;
    q[3] = (R[1][0] - R[0][1]) / s;
    return;
  }
  int i = 0;
  if (R[1][1] > R[i][i]) i = 1;
  if (R[2][2] > R[i][i]) i = 2;
  const int j = (i + 1) % 3, k = (i + 2) % 3;
  const double s = 2.0 * std::sqrt(1.0 + R[i][i] - R[j][j] - R[k][k]);
  q[0] = (R[k][j] - R[j][k]) / s;
  q[1 + i] = 0.25 * s;
  q[1 + j] = (R[j][i] + R[i][j]) / s;
  q[1 + k] = (R[k][i] + R[i][k]) / s;
}

Matrix3 rotationAbout(std::array<double, 3> axis, double angle) {
  const double length = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
  for (auto& a : axis) a /= length;
  const double c = std::cos(angle), s = std::sin(angle);
  Matrix3 R;
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) R[r][k] = (r == k ? c : 0.0) + (1.0 - c) * axis[r] * axis[k];
  R[0][1] -= s * axis[2];
  R[0][2] += s * axis[1];
  R[1][0] += s * axis[2];
  R[1][2] -= s * axis[0];
  R[2][0] -= s * axis[1];
  R[2][1] += s * axis[0];
  return R;
}

Matrix3 multiply(const Matrix3& a, const Matrix3& b) {
  Matrix3 out{};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) out[r][c] += a[r][k] * b[k][c];
  return out;
}

// Fills kinematics from a displacement field u(X) and a rotation-vector field theta(X).
using Field = std::function<std::array<double, 3>(const std::array<double, 3>&)>;
using RotationField = std::function<Matrix3(const std::array<double, 3>&)>;

HostKinematics prescribe(const PlateBody& plate, const Field& displacement, const RotationField& rotation) {
  const LocalIndex n = plate.shell.mesh.numNodes();
  HostKinematics k{perishell::CoordinateView<Kokkos::HostSpace>("u", n),
                   perishell::pd::RotationView<Kokkos::HostSpace>("q", n)};
  for (LocalIndex node = 0; node < n; ++node) {
    const std::array<double, 3> X = {plate.shell.mesh.coordinates(node, 0), plate.shell.mesh.coordinates(node, 1),
                                     plate.shell.mesh.coordinates(node, 2)};
    const auto u = displacement(X);
    for (int d = 0; d < 3; ++d) k.displacements(node, d) = u[d];
    double q[4];
    quaternionFromMatrix(rotation(X), q);
    for (int d = 0; d < 4; ++d) k.rotations(node, d) = q[d];
  }
  return k;
}

Matrix3 smallRotation(double thetaX, double thetaY, double thetaZ) {
  const double angle = std::sqrt(thetaX * thetaX + thetaY * thetaY + thetaZ * thetaZ);
  if (angle == 0.0) return rotationAbout({0, 0, 1}, 0.0);
  return rotationAbout({thetaX, thetaY, thetaZ}, angle);
}

struct ForceResult {
  HostNodal forces;
  Kokkos::View<double*, Kokkos::HostSpace> strainEnergy;
  Kokkos::View<std::uint8_t*, Kokkos::HostSpace> intactNext;
};

ForceResult evaluate(const PlateBody& plate, const HostKinematics& host, ForceKernel kernel) {
  const LocalIndex n = plate.body.numNodes();
  perishell::pd::PdKinematics<TEST_MEMSPACE> state(n);
  Kokkos::deep_copy(state.displacements, host.displacements);
  Kokkos::deep_copy(state.rotations, host.rotations);
  const auto intact = perishell::pd::makeIntactFlags(plate.body.bonds, "intact");
  perishell::pd::BondForceOutputs<TEST_MEMSPACE> out{
      perishell::pd::NodalVectorView<TEST_MEMSPACE>("forces", n), perishell::VectorView<TEST_MEMSPACE>("energy", n),
      perishell::VectorView<TEST_MEMSPACE>("fracture", n),
      perishell::pd::BondFlagView<TEST_MEMSPACE>("intact next", plate.body.bonds.numBonds())};
  perishell::pd::computeBondForces(TEST_EXECSPACE{}, kernel, plate.body, state, intact, out);
  return {Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, out.forces),
          Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, out.strainEnergy),
          Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, out.intactNext)};
}

LocalIndex centreNode(const PlateBody& plate) {
  const auto& x = plate.shell.mesh.coordinates;
  const LocalIndex last = plate.shell.mesh.numNodes() - 1;
  const auto distanceToCentre = [&](LocalIndex node) {
    double squared = 0.0;
    for (int d = 0; d < 3; ++d) squared += std::pow(x(node, d) - 0.5 * (x(0, d) + x(last, d)), 2);
    return squared;
  };
  LocalIndex best = 0;
  for (LocalIndex node = 0; node <= last; ++node)
    if (distanceToCentre(node) < distanceToCentre(best)) best = node;
  return best;
}

double nodeVolume(const PlateBody& plate, LocalIndex node) {
  const auto volumes = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, plate.body.volumes);
  return volumes(node);
}

Matrix3 identity() { return rotationAbout({0, 0, 1}, 0.0); }

// PD energy density of the centre node (model.md §2: W_i = 1/2 sum_j w_ij V_j beta).
double centreEnergyDensity(const PlateBody& plate, const HostKinematics& kinematics) {
  const LocalIndex centre = centreNode(plate);
  return evaluate(plate, kinematics, ForceKernel::NodeGather).strainEnergy(centre) / nodeVolume(plate, centre);
}

// Discrete sums differ from the continuum integrals (model.md §2 asks us to measure it; the
// test prints each value). The per-bond stiffness scales (pd/make_body.hpp,
// computeStiffnessScales) match both the constant and the fourth angular moment of the
// square lattice to the continuum's, so an interior node stores the plate energy to
// round-off. Measured: bending within 4e-11 at every nu; membrane within 1.7e-7, which is
// the geometric nonlinearity of a 1e-6 strain (the bond stretch is not exactly n.eps.n).
// Before the fourth-moment weighting shear was off 7.0 % at nu = 0 and 3.8 % at nu = 0.2.
constexpr double membraneTolerance = 1e-6;
constexpr double bendingTolerance = 1e-9;
// A free 48 x 8 strip as a whole: measured worst 1.26e-3 (shear and twist at nu = 0.33);
// 5.3-7.1 % along and across the strip before the second-harmonic edge weights.
constexpr double stripTolerance = 2e-3;

// A small deformation with every mode: random displacements and rotations per node.
HostKinematics randomDeformation(const PlateBody& plate, double amplitude, unsigned seed) {
  std::mt19937 generator(seed);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  return prescribe(
      plate,
      [&](const std::array<double, 3>&) {
        return std::array<double, 3>{amplitude * plate.spacing * uniform(generator),
                                     amplitude * plate.spacing * uniform(generator),
                                     amplitude * plate.spacing * uniform(generator)};
      },
      [&](const std::array<double, 3>&) {
        return smallRotation(amplitude * uniform(generator), amplitude * uniform(generator), amplitude * uniform(generator));
      });
}

// The same configuration after a rigid rotation Q about the origin: x -> Q x, R -> Q R.
HostKinematics rotated(const PlateBody& plate, const HostKinematics& k, const Matrix3& Q) {
  const LocalIndex n = plate.shell.mesh.numNodes();
  HostKinematics out{perishell::CoordinateView<Kokkos::HostSpace>("u", n),
                     perishell::pd::RotationView<Kokkos::HostSpace>("q", n)};
  for (LocalIndex node = 0; node < n; ++node) {
    double x[3];
    for (int d = 0; d < 3; ++d) x[d] = plate.shell.mesh.coordinates(node, d) + k.displacements(node, d);
    for (int r = 0; r < 3; ++r)
      out.displacements(node, r) = Q[r][0] * x[0] + Q[r][1] * x[1] + Q[r][2] * x[2] - plate.shell.mesh.coordinates(node, r);
    double q[4] = {k.rotations(node, 0), k.rotations(node, 1), k.rotations(node, 2), k.rotations(node, 3)};
    double R[3][3];
    perishell::rotation::toMatrix(q, R);
    Matrix3 current;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) current[r][c] = R[r][c];
    quaternionFromMatrix(multiply(Q, current), q);
    for (int d = 0; d < 4; ++d) out.rotations(node, d) = q[d];
  }
  return out;
}

double largestEntry(const HostNodal& values, int firstComponent) {
  double largest = 0.0;
  for (std::size_t node = 0; node < values.extent(0); ++node)
    for (int d = firstComponent; d < firstComponent + 3; ++d) largest = std::max(largest, std::abs(values(node, d)));
  return largest;
}

}  // namespace

TEST(TEST_CATEGORY, microbeam_micromoduli_match_model_md_closed_forms) {
  const double E = 72e9, t = 1e-3, delta = 1.5e-3;
  const auto atOneThird = perishell::pd::microbeamMicromoduli(E, 1.0 / 3.0, t, delta);
  EXPECT_NEAR(atOneThird.axial / (9.0 * E / (pi * t * delta * delta * delta)), 1.0, 1e-14);
  EXPECT_NEAR(atOneThird.inPlaneBending, 0.0, 1e-9 * atOneThird.axial);
  EXPECT_NEAR(atOneThird.torsion, 0.0, 1e-9 * atOneThird.axial);
  const auto atZero = perishell::pd::microbeamMicromoduli(E, 0.0, t, delta);
  EXPECT_NEAR(atZero.outOfPlaneBending / (E * t / (2 * pi * delta * delta * delta)), 1.0, 1e-14);
  EXPECT_NEAR(atZero.inPlaneBending / (E / (6 * pi * t * delta)), 1.0, 1e-14);
  EXPECT_NEAR(atZero.torsion / (E * t / (2 * pi * delta * delta * delta)), 1.0, 1e-14);
  // Pure stretch reaches w_c at s_c = sqrt(2 pi G_c (1 - nu) / (3 E delta)) (model.md §3).
  const double Gc = 135.0, nu = 0.2, xi = 1e-3;
  const auto c = perishell::pd::microbeamMicromoduli(E, nu, t, delta);
  const double sc = std::sqrt(2 * pi * Gc * (1 - nu) / (3 * E * delta));
  EXPECT_NEAR(0.5 * c.axial * sc * sc * xi / (perishell::pd::criticalMicropotentialPerLength(Gc, t, delta) * xi), 1.0,
              1e-14);
  EXPECT_THROW(perishell::pd::microbeamMicromoduli(E, 0.34, t, delta), std::invalid_argument);
  EXPECT_THROW(perishell::pd::microbeamMicromoduli(E, 0.2, 0.0, delta), std::invalid_argument);
}

TEST(TEST_CATEGORY, microbeam_membrane_energy_density_matches_plate_theory) {
  const double strain = 1e-6;
  for (const double nu : {0.0, 0.2, 0.33}) {
    const auto plate = makePlateBody(nu);
    const double E = plate.material.youngModulus;
    struct Case {
      const char* name;
      double exx, eyy, exy;  // tensor components
    };
    for (const Case& strainCase : {Case{"uniaxial x", strain, 0, 0}, Case{"uniaxial y", 0, strain, 0},
                                   Case{"biaxial", strain, strain, 0}, Case{"shear", 0, 0, strain},
                                   Case{"uniaxial at 30 deg", strain * 0.75, strain * 0.25, strain * 0.4330127018922193}}) {
      const auto kinematics = prescribe(
          plate,
          [&](const std::array<double, 3>& X) {
            return std::array<double, 3>{strainCase.exx * X[0] + strainCase.exy * X[1],
                                         strainCase.exy * X[0] + strainCase.eyy * X[1], 0.0};
          },
          [](const std::array<double, 3>&) { return identity(); });
      const double classical =
          0.5 * E / (1 - nu * nu) *
          (strainCase.exx * strainCase.exx + strainCase.eyy * strainCase.eyy + 2 * nu * strainCase.exx * strainCase.eyy +
           2 * (1 - nu) * strainCase.exy * strainCase.exy);
      const double pd = centreEnergyDensity(plate, kinematics);
      std::printf("membrane nu=%.2f %-20s W_pd/W_ccm - 1 = %+.3e\n", nu, strainCase.name, pd / classical - 1);
      EXPECT_NEAR(pd / classical, 1.0, membraneTolerance) << strainCase.name << ", nu = " << nu;
    }
  }
}

TEST(TEST_CATEGORY, microbeam_membrane_energy_is_exact_on_a_tilted_plate) {
  // The stiffness scales measure bond angles in each node's tangent plane, so a plate lying
  // in any plane, its lattice turned within it, stores the same energy.
  const double strain = 1e-6, nu = 0.0;
  const Matrix3 tilt = rotationAbout({1, 2, 3}, 0.7);
  const auto plate = makePlateBody(nu, {}, 24, 3.0, tilt);
  const double E = plate.material.youngModulus;
  const auto kinematics = prescribe(
      plate,
      [&](const std::array<double, 3>& X) {
        // Shear in the plate's own axes: u = Q eps Q^T X.
        double local[3] = {0.0, 0.0, 0.0};
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) local[r] += tilt[c][r] * X[c];
        const double u[3] = {strain * local[1], strain * local[0], 0.0};
        std::array<double, 3> out{};
        for (int r = 0; r < 3; ++r) out[r] = tilt[r][0] * u[0] + tilt[r][1] * u[1] + tilt[r][2] * u[2];
        return out;
      },
      [](const std::array<double, 3>&) { return identity(); });
  const double classical = 0.5 * E / (1 - nu * nu) * 2 * (1 - nu) * strain * strain;
  const double pd = centreEnergyDensity(plate, kinematics);
  std::printf("membrane nu=%.2f tilted shear        W_pd/W_ccm - 1 = %+.3e\n", nu, pd / classical - 1);
  EXPECT_NEAR(pd / classical, 1.0, membraneTolerance);
}

TEST(TEST_CATEGORY, microbeam_bending_energy_density_matches_plate_theory) {
  const double curvature = 1e-3;  // [1/m]
  for (const double nu : {0.0, 0.2, 0.33}) {
    const auto plate = makePlateBody(nu);
    const double E = plate.material.youngModulus, t = plate.material.thickness;
    const double D = E * t * t * t / (12 * (1 - nu * nu));
    const auto& x = plate.shell.mesh.coordinates;
    const LocalIndex centre = centreNode(plate);
    const double cx = x(centre, 0), cy = x(centre, 1);
    struct Case {
      const char* name;
      double kxx, kyy, kxy;
    };
    for (const Case& bending : {Case{"cylindrical x", curvature, 0, 0}, Case{"cylindrical y", 0, curvature, 0},
                                Case{"spherical", curvature, curvature, 0}, Case{"twist", 0, 0, curvature},
                                Case{"saddle", curvature, -curvature, 0}}) {
      // w = 1/2 (kxx x^2 + kyy y^2 + 2 kxy x y); the normal tilts by grad w, so the rotation
      // vector is (dw/dy, -dw/dx, 0).
      const auto w = [&](double X, double Y) {
        return 0.5 * (bending.kxx * X * X + bending.kyy * Y * Y + 2 * bending.kxy * X * Y);
      };
      const auto kinematics = prescribe(
          plate, [&](const std::array<double, 3>& X) { return std::array<double, 3>{0.0, 0.0, w(X[0] - cx, X[1] - cy)}; },
          [&](const std::array<double, 3>& X) {
            const double dx = X[0] - cx, dy = X[1] - cy;
            const double wx = bending.kxx * dx + bending.kxy * dy, wy = bending.kyy * dy + bending.kxy * dx;
            return smallRotation(wy, -wx, 0.0);
          });
      const double classical = 0.5 * D / t *
                               (bending.kxx * bending.kxx + bending.kyy * bending.kyy +
                                2 * nu * bending.kxx * bending.kyy + 2 * (1 - nu) * bending.kxy * bending.kxy);
      const double pd = centreEnergyDensity(plate, kinematics);
      std::printf("bending  nu=%.2f %-20s W_pd/W_ccm - 1 = %+.3e\n", nu, bending.name, pd / classical - 1);
      EXPECT_NEAR(pd / classical, 1.0, bendingTolerance) << bending.name << ", nu = " << nu;
    }
  }
}

namespace {

// A free strip of cellsX x cellsY cells, every node PD: most nodes within delta of an edge.
PlateBody makeStripBody(double poissonRatio, int cellsX, int cellsY) {
  const double spacing = 1e-3;
  PlateBody strip{perishell::mesh::makePlate(cellsX * spacing, cellsY * spacing, spacing), {}, {}, spacing};
  strip.material = {70e9, poissonRatio, 0.4e-3, {}};
  strip.body = perishell::pd::makePdBody(TEST_EXECSPACE{}, strip.shell.mesh,
                                         perishell::pd::allNodes(strip.shell.mesh.numNodes()), strip.material,
                                         3.0 * spacing, spacing, {});
  return strip;
}

double totalEnergy(const PlateBody& plate, const HostKinematics& kinematics) {
  const auto energy = evaluate(plate, kinematics, ForceKernel::NodeGather).strainEnergy;
  double sum = 0.0;
  for (std::size_t node = 0; node < energy.extent(0); ++node) sum += energy(node);
  return sum;
}

}  // namespace

// Free edges: a node within delta of one misses the bonds pointing out of the body, a
// second angular harmonic; the stiffness scales fit it away (pd/make_body.hpp), so the
// whole strip, edge nodes included, stores the plate energy of a homogeneous field. Only
// the corner nodes, where the harmonic weights reach their cap, keep an error. With an
// even boost of the edge nodes this strip stored 5-7 % too much along it and too little
// across (Sze 3.2's PD strip, 8 spacings wide, was 6 % too stiff).
TEST(TEST_CATEGORY, microbeam_free_strip_stores_the_plate_energy_of_homogeneous_fields) {
  const double strain = 1e-6, curvature = 1e-3;
  for (const double nu : {0.0, 0.2, 0.33}) {
    const auto strip = makeStripBody(nu, 48, 8);
    const double E = strip.material.youngModulus, t = strip.material.thickness;
    const double volume = 48e-3 * 8e-3 * t, D = E * t * t * t / (12 * (1 - nu * nu));
    struct Case {
      const char* name;
      double exx, eyy, exy, kxx, kyy, kxy;
    };
    for (const Case& c : {Case{"stretch along", strain, 0, 0, 0, 0, 0}, Case{"stretch across", 0, strain, 0, 0, 0, 0},
                          Case{"shear", 0, 0, strain, 0, 0, 0}, Case{"bending along", 0, 0, 0, curvature, 0, 0},
                          Case{"bending across", 0, 0, 0, 0, curvature, 0}, Case{"twist", 0, 0, 0, 0, 0, curvature}}) {
      const auto kinematics = prescribe(
          strip,
          [&](const std::array<double, 3>& X) {
            return std::array<double, 3>{c.exx * X[0] + c.exy * X[1], c.exy * X[0] + c.eyy * X[1],
                                         0.5 * (c.kxx * X[0] * X[0] + c.kyy * X[1] * X[1]) + c.kxy * X[0] * X[1]};
          },
          [&](const std::array<double, 3>& X) {
            return smallRotation(c.kyy * X[1] + c.kxy * X[0], -(c.kxx * X[0] + c.kxy * X[1]), 0.0);
          });
      const double membrane = 0.5 * E / (1 - nu * nu) *
                              (c.exx * c.exx + c.eyy * c.eyy + 2 * nu * c.exx * c.eyy + 2 * (1 - nu) * c.exy * c.exy);
      const double bending =
          0.5 * D / t * (c.kxx * c.kxx + c.kyy * c.kyy + 2 * nu * c.kxx * c.kyy + 2 * (1 - nu) * c.kxy * c.kxy);
      const double error = totalEnergy(strip, kinematics) / ((membrane + bending) * volume) - 1.0;
      std::printf("free strip 48x8 nu=%.2f %-15s W_pd/W_plate - 1 = %+.3e\n", nu, c.name, error);
      EXPECT_LT(std::abs(error), stripTolerance) << c.name << ", nu = " << nu;
    }
  }
}

// A pre-crack is a crack, not a free edge (pd/make_body.hpp): every bond it leaves keeps the
// stiffness scales it has in the uncut body, so the faces either side of the crack are
// weighted alike, as they would be after the crack opened in the run.
TEST(TEST_CATEGORY, microbeam_pre_crack_keeps_the_uncut_stiffness_scales) {
  const double spacing = 1e-3;
  const auto shell = perishell::mesh::makePlate(24 * spacing, 24 * spacing, spacing);
  const perishell::pd::PdMaterial material{70e9, 0.2, 0.4e-3, {}};
  const auto nodes = perishell::pd::allNodes(shell.mesh.numNodes());
  const perishell::mesh::CrackSegment crack{{6e-3, 12e-3, 0.0}, {18e-3, 12e-3, 0.0}, {0.0, 0.0, 1.0}};
  const auto uncut = perishell::pd::makePdBody(TEST_EXECSPACE{}, shell.mesh, nodes, material, 3 * spacing, spacing, {});
  const auto cut = perishell::pd::makePdBody(TEST_EXECSPACE{}, shell.mesh, nodes, material, 3 * spacing, spacing, {crack});
  const auto host = [](const auto& view) { return Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, view); };
  const auto uncutEnds = host(uncut.bonds.halfBonds), cutEnds = host(cut.bonds.halfBonds);
  const auto uncutScale = host(uncut.stiffnessScale), cutScale = host(cut.stiffnessScale);
  ASSERT_LT(cut.bonds.numBonds(), uncut.bonds.numBonds());  // the crack cut bonds
  std::map<std::pair<LocalIndex, LocalIndex>, std::size_t> uncutIndex;
  for (std::size_t b = 0; b < uncutEnds.extent(0); ++b)
    uncutIndex[std::minmax(uncutEnds(b, 0), uncutEnds(b, 1))] = b;
  double largestDifference = 0.0;
  for (std::size_t b = 0; b < cutEnds.extent(0); ++b) {
    const auto match = uncutIndex.find(std::minmax(cutEnds(b, 0), cutEnds(b, 1)));
    ASSERT_NE(match, uncutIndex.end());
    for (int m = 0; m < 2; ++m)
      largestDifference = std::max(largestDifference, std::abs(cutScale(b, m) - uncutScale(match->second, m)));
  }
  // Equal up to round-off: node normals and volumes are atomic sums over elements, so two
  // builds may differ in the last bits on a GPU (8.9e-16 seen on the H200). Fitting the
  // weights to the cut bonds instead changes scales near the crack by up to 1.03.
  EXPECT_LT(largestDifference, 1e-13);
}

TEST(TEST_CATEGORY, microbeam_rigid_rotations_give_no_force_and_rotate_deformed_forces) {
  const auto plate = makePlateBody(0.2, {}, 12);
  const auto deformed = randomDeformation(plate, 1e-3, 7);
  const auto reference = evaluate(plate, deformed, ForceKernel::NodeGather);
  const double forceScale = largestEntry(reference.forces, 0), momentScale = largestEntry(reference.forces, 3);
  ASSERT_GT(forceScale, 0.0);
  ASSERT_GT(momentScale, 0.0);
  const auto undeformed = prescribe(
      plate, [](const std::array<double, 3>&) { return std::array<double, 3>{0.0, 0.0, 0.0}; },
      [](const std::array<double, 3>&) { return identity(); });
  const std::array<std::pair<const char*, Matrix3>, 4> rotations = {
      std::pair{"90 deg about x", rotationAbout({1, 0, 0}, pi / 2)}, std::pair{"90 deg about y", rotationAbout({0, 1, 0}, pi / 2)},
      std::pair{"90 deg about z", rotationAbout({0, 0, 1}, pi / 2)}, std::pair{"150 deg about (1,2,3)", rotationAbout({1, 2, 3}, 2.6)}};
  for (const auto& [name, Q] : rotations) {
    for (const ForceKernel kernel : {ForceKernel::NodeGather, ForceKernel::BondScatter}) {
      const auto rigid = evaluate(plate, rotated(plate, undeformed, Q), kernel);
      EXPECT_LT(largestEntry(rigid.forces, 0) / forceScale, 1e-10) << name;
      EXPECT_LT(largestEntry(rigid.forces, 3) / momentScale, 1e-10) << name;
      EXPECT_LT(std::abs(rigid.strainEnergy(centreNode(plate))), 1e-20) << name;
      // Deformed then rotated: the same forces, turned by Q.
      const auto turned = evaluate(plate, rotated(plate, deformed, Q), kernel);
      double worst = 0.0;
      for (LocalIndex node = 0; node < plate.body.numNodes(); ++node)
        for (int block = 0; block < 2; ++block)
          for (int r = 0; r < 3; ++r) {
            double expected = 0.0;
            for (int c = 0; c < 3; ++c) expected += Q[r][c] * reference.forces(node, 3 * block + c);
            worst = std::max(worst, std::abs(turned.forces(node, 3 * block + r) - expected) /
                                        (block == 0 ? forceScale : momentScale));
          }
      EXPECT_LT(worst, 1e-9) << name;
    }
  }
}

// The frames pass (one thread per matrix entry) stores X + u and toMatrix(q), to round-off.
TEST(TEST_CATEGORY, microbeam_node_frames_hold_positions_and_rotation_matrices) {
  const auto plate = makePlateBody(0.2, {}, 6);
  const auto deformed = randomDeformation(plate, 0.5, 3);  // rotations up to ~0.5 rad
  const LocalIndex n = plate.body.numNodes();
  perishell::pd::PdKinematics<TEST_MEMSPACE> state(n);
  Kokkos::deep_copy(state.displacements, deformed.displacements);
  Kokkos::deep_copy(state.rotations, deformed.rotations);
  perishell::pd::updateNodeFrames(TEST_EXECSPACE{}, plate.body, state);
  const auto frames = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, state.nodeFrames);
  const auto X = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, plate.body.referencePositions);
  double worst = 0.0;
  for (LocalIndex node = 0; node < n; ++node) {
    const double q[4] = {deformed.rotations(node, 0), deformed.rotations(node, 1), deformed.rotations(node, 2),
                         deformed.rotations(node, 3)};
    double R[3][3];
    perishell::rotation::toMatrix(q, R);
    for (int k = 0; k < 3; ++k)
      worst = std::max(worst, std::abs(frames(node, k) - (X(node, k) + deformed.displacements(node, k))));
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(frames(node, 3 + 3 * r + c) - R[r][c]));
  }
  EXPECT_LT(worst, 1e-15);
}

TEST(TEST_CATEGORY, microbeam_bond_scatter_and_node_gather_agree) {
  const auto plate = makePlateBody(0.25, {}, 16);
  const auto deformed = randomDeformation(plate, 1e-2, 11);
  const auto gather = evaluate(plate, deformed, ForceKernel::NodeGather);
  const auto scatter = evaluate(plate, deformed, ForceKernel::BondScatter);
  const double forceScale = largestEntry(gather.forces, 0), momentScale = largestEntry(gather.forces, 3);
  double worstForce = 0.0, worstMoment = 0.0, worstEnergy = 0.0, totalEnergy = 0.0;
  double netForce[3] = {0.0, 0.0, 0.0};
  for (LocalIndex node = 0; node < plate.body.numNodes(); ++node) {
    for (int d = 0; d < 3; ++d) {
      worstForce = std::max(worstForce, std::abs(gather.forces(node, d) - scatter.forces(node, d)));
      worstMoment = std::max(worstMoment, std::abs(gather.forces(node, 3 + d) - scatter.forces(node, 3 + d)));
      netForce[d] += gather.forces(node, d);
    }
    worstEnergy = std::max(worstEnergy, std::abs(gather.strainEnergy(node) - scatter.strainEnergy(node)));
    totalEnergy += gather.strainEnergy(node);
  }
  EXPECT_LT(worstForce / forceScale, 1e-12);
  EXPECT_LT(worstMoment / momentScale, 1e-12);
  EXPECT_LT(worstEnergy / totalEnergy, 1e-12);
  // Bonds carry no net force (action and reaction along the same bond).
  for (int d = 0; d < 3; ++d) EXPECT_LT(std::abs(netForce[d]) / forceScale, 1e-11);
}

TEST(TEST_CATEGORY, microbeam_bonds_break_at_the_critical_stretch) {
  const double nu = 0.2, Gc = 135.0;
  const auto plate = makePlateBody(nu, Gc, 10);
  const double E = plate.material.youngModulus, delta = 3.0 * plate.spacing;
  const double sc = std::sqrt(2 * pi * Gc * (1 - nu) / (3 * E * delta));
  // Equibiaxial strain stretches every bond by the same s and turns none.
  for (const auto& [factor, expectIntact] : {std::pair{0.99, 1}, std::pair{1.01, 0}}) {
    const double s = factor * sc;
    const auto kinematics = prescribe(
        plate, [&](const std::array<double, 3>& X) { return std::array<double, 3>{s * X[0], s * X[1], 0.0}; },
        [](const std::array<double, 3>&) { return identity(); });
    for (const ForceKernel kernel : {ForceKernel::NodeGather, ForceKernel::BondScatter}) {
      const auto result = evaluate(plate, kinematics, kernel);
      long long intact = 0;
      for (std::size_t b = 0; b < result.intactNext.extent(0); ++b) intact += result.intactNext(b);
      EXPECT_EQ(intact, expectIntact ? static_cast<long long>(result.intactNext.extent(0)) : 0LL) << "s/s_c = " << factor;
    }
  }
}
