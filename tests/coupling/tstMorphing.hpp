// The PD-CCM morphing coupling (model.md §4, paper eq. 19-23; coupling/*.hpp): the alpha
// field and its profiles; a PD band or disc inside a CCM plate stores the classical plate
// energy under homogeneous membrane strains, uniform curvature and twist (bonds plus
// elements, each through its own energy routine); the ghost forces at interior nodes under
// those exact fields, cubic against linear profile; the builder from a deck's model.
#include <perishell/coupling/make_coupled_model.hpp>
#include <perishell/mesh/generators.hpp>
#include <perishell/pd/bond_forces.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <string>

namespace morphing_test {

using perishell::LocalIndex;
using perishell::deck::TransitionProfile;
using MemorySpace = TEST_MEMSPACE;
using Bodies = perishell::coupling::CoupledBodies<MemorySpace>;
using HostNodal = perishell::pd::NodalVectorView<Kokkos::HostSpace>;

constexpr double spacing = 1e-3, horizonFactor = 3.0, youngModulus = 70e9, thickness = 0.4e-3;
constexpr int cells = 36;

enum class Zone { Band, Disc };

struct CoupledPlate {
  perishell::mesh::ShellMesh shell;
  Kokkos::View<std::uint8_t*, Kokkos::HostSpace> elementIsPd;
  perishell::coupling::CouplingInputs inputs;
  Bodies bodies;
};

// A 36 x 36 mm plate, dx = 1 mm, delta = 3 mm; PD elements: a band 6 mm wide across the
// middle (centroid x in [15, 21] mm) or a disc of radius 4 mm at the centre.
CoupledPlate makeCoupledPlate(double poissonRatio, TransitionProfile profile, Zone zone, double width = 0.0,
                              double bandHalfWidth = 3.0 * spacing,
                              perishell::shell::ShellElementKind kind = perishell::shell::ShellElementKind::Mitc4) {
  CoupledPlate plate;
  plate.shell = perishell::mesh::makePlate(cells * spacing, cells * spacing, spacing);
  const auto& mesh = plate.shell.mesh;
  plate.elementIsPd = Kokkos::View<std::uint8_t*, Kokkos::HostSpace>("is pd", mesh.numElements());
  const double centre = 0.5 * cells * spacing;
  for (LocalIndex e = 0; e < mesh.numElements(); ++e) {
    double c[2] = {0.0, 0.0};
    for (int a = 0; a < 4; ++a)
      for (int d = 0; d < 2; ++d) c[d] += 0.25 * mesh.coordinates(mesh.quads(e, a), d);
    plate.elementIsPd(e) = zone == Zone::Band ? std::abs(c[0] - centre) < bandHalfWidth
                                              : std::hypot(c[0] - centre, c[1] - centre) < 4.0 * spacing;
  }
  auto& inputs = plate.inputs;
  inputs.material = {youngModulus, poissonRatio, thickness, {}};
  inputs.section.youngModulus = youngModulus;
  inputs.section.poissonRatio = poissonRatio;
  inputs.section.thickness = thickness;
  inputs.horizon = horizonFactor * spacing;
  inputs.gridSpacing = spacing;
  inputs.transition = {width, profile};
  inputs.shellElement = kind;
  plate.bodies = perishell::coupling::makeCoupledBodies(TEST_EXECSPACE{}, mesh, plate.elementIsPd, inputs);
  return plate;
}

// A small-amplitude field: displacement and rotation vector per point (x, y).
struct Field {
  std::function<std::array<double, 3>(double, double)> displacement, rotation;
};

// Shell energy (sum of element energies) and internal forces (of either element kind): the
// solvers' kernel subtracts them from the zeroed `forces`.
double shellEnergyAndForces(const perishell::shell::ShellBody<MemorySpace>& body,
                            const perishell::pd::PdKinematics<MemorySpace>& state,
                            const perishell::pd::NodalVectorView<MemorySpace>& forces) {
  perishell::VectorView<MemorySpace> energies("shell energy per node", forces.extent(0));
  perishell::shell::subtractShellForces(TEST_EXECSPACE{}, body, state, forces, energies);
  double energy = 0.0;
  Kokkos::parallel_reduce(
      "morphing_test::shellEnergy", Kokkos::RangePolicy<TEST_EXECSPACE>(0, forces.extent(0)),
      KOKKOS_LAMBDA(const int node, double& sum) {
        sum += energies(node);
        for (int d = 0; d < 6; ++d) forces(node, d) = -forces(node, d);
      },
      energy);
  return energy;
}

struct Evaluation {
  double pdEnergy = 0.0, shellEnergy = 0.0;
  HostNodal internalForces;  // dW/dq of bonds + elements, per mesh node
};

Evaluation evaluate(const CoupledPlate& plate, const Field& field) {
  const auto& mesh = plate.shell.mesh;
  const LocalIndex numNodes = mesh.numNodes();
  perishell::CoordinateView<Kokkos::HostSpace> u("u", numNodes);
  perishell::pd::RotationView<Kokkos::HostSpace> q("q", numNodes);
  for (LocalIndex node = 0; node < numNodes; ++node) {
    const double x = mesh.coordinates(node, 0), y = mesh.coordinates(node, 1);
    const auto displacement = field.displacement(x, y);
    const auto rotationVector = field.rotation(x, y);
    double quaternion[4];
    perishell::rotation::exponential(rotationVector.data(), quaternion);
    for (int d = 0; d < 3; ++d) u(node, d) = displacement[d];
    for (int d = 0; d < 4; ++d) q(node, d) = quaternion[d];
  }
  // One state per mesh node serves both bodies (the PD body is indexed by mesh node).
  perishell::pd::PdKinematics<MemorySpace> state(numNodes);
  Kokkos::deep_copy(state.displacements, u);
  Kokkos::deep_copy(state.rotations, q);
  perishell::pd::NodalVectorView<MemorySpace> shellForces("shell forces", numNodes);
  Evaluation result;
  result.shellEnergy = shellEnergyAndForces(plate.bodies.shellBody, state, shellForces);
  result.internalForces = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, shellForces);
  const auto& body = plate.bodies.pdBody;
  if (body.bonds.numBonds() == 0) return result;

  const auto intact = perishell::pd::makeIntactFlags(body.bonds, "intact");
  perishell::pd::BondForceOutputs<MemorySpace> out{
      perishell::pd::NodalVectorView<MemorySpace>("pd forces", numNodes),
      perishell::VectorView<MemorySpace>("pd energy", numNodes),
      perishell::VectorView<MemorySpace>("pd fracture", numNodes),
      perishell::pd::BondFlagView<MemorySpace>("intact next", body.bonds.numBonds())};
  perishell::pd::computeBondForces(TEST_EXECSPACE{}, perishell::deck::ForceKernel::NodeGather, body, state, intact,
                                   out);
  const auto pdForces = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, out.forces);
  const auto pdEnergy = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, out.strainEnergy);
  for (LocalIndex node = 0; node < numNodes; ++node) {
    result.pdEnergy += pdEnergy(node);
    // The bond kernel returns the forces bonds exert on the nodes: minus their internal forces.
    for (int d = 0; d < 6; ++d) result.internalForces(node, d) -= pdForces(node, d);
  }
  return result;
}

struct State {
  const char* name;
  bool bending;
  double exx, eyy, exy;  // membrane strain tensor, or curvatures kxx kyy kxy
};

constexpr double strain = 1e-6, curvature = 1e-3;  // [-], [1/m]: small enough to stay linear
const State states[] = {{"uniaxial", false, strain, 0.0, 0.0},
                        {"shear", false, 0.0, 0.0, strain},
                        {"curvature", true, curvature, 0.0, 0.0},
                        {"twist", true, 0.0, 0.0, curvature}};

Field fieldOf(const State& state) {
  if (!state.bending)
    return {[=](double x, double y) {
              return std::array<double, 3>{state.exx * x + state.exy * y, state.exy * x + state.eyy * y, 0.0};
            },
            [](double, double) { return std::array<double, 3>{0.0, 0.0, 0.0}; }};
  // w = 1/2 (kxx x^2 + kyy y^2 + 2 kxy x y); the normal tilts by grad w: rotation (dw/dy, -dw/dx, 0).
  return {[=](double x, double y) {
            return std::array<double, 3>{0.0, 0.0, 0.5 * (state.exx * x * x + state.eyy * y * y + 2 * state.exy * x * y)};
          },
          [=](double x, double y) {
            return std::array<double, 3>{state.eyy * y + state.exy * x, -(state.exx * x + state.exy * y), 0.0};
          }};
}

// Classical plate energy of the whole plate (model.md §2: membrane E t/(1-nu^2), bending D).
double classicalEnergy(const State& state, double nu) {
  const double area = cells * spacing * cells * spacing;
  const double stiffness = state.bending ? youngModulus * thickness * thickness * thickness / (12 * (1 - nu * nu))
                                         : youngModulus * thickness / (1 - nu * nu);
  // Membrane strains are tensor components, curvatures engineering (kxy = w,xy: 2 kxy^2 (1-nu) both ways).
  return 0.5 * stiffness * area *
         (state.exx * state.exx + state.eyy * state.eyy + 2 * nu * state.exx * state.eyy +
          2 * (1 - nu) * state.exy * state.exy);
}

// Within one horizon of the plate's edge: the free edge's own PD surface effect (a band
// meets the edge), not the coupling's ghost force, and the edge nodes' tractions.
bool nearPlateEdge(const CoupledPlate& plate, LocalIndex node) {
  const double x = plate.shell.mesh.coordinates(node, 0), y = plate.shell.mesh.coordinates(node, 1);
  const double edge = cells * spacing, margin = horizonFactor * spacing * (1.0 + 1e-9);
  return x < margin || y < margin || x > edge - margin || y > edge - margin;
}

struct Ghost {
  double force, moment;  // max over interior nodes, relative to the state's nodal scales
};

// Max over the nodes off the plate's edge band (the transition's, in practice: elsewhere the
// homogeneous field is balanced exactly). Nodal scales: membrane, the force sigma t dx on a node's share of an edge; bending, the
// moment D kappa dx and the force D kappa.
Ghost ghostForces(const CoupledPlate& plate, const State& state, const Evaluation& evaluation, double nu) {
  const double amplitude = std::max({std::abs(state.exx), std::abs(state.eyy), std::abs(state.exy)});
  const double membrane = youngModulus * thickness / (1 - nu * nu);
  const double bending = membrane * thickness * thickness / 12.0;
  const double forceScale = state.bending ? bending * amplitude : membrane * amplitude * spacing;
  const double momentScale = state.bending ? bending * amplitude * spacing : membrane * amplitude * spacing * spacing;
  Ghost ghost{0.0, 0.0};
  for (LocalIndex node = 0; node < plate.shell.mesh.numNodes(); ++node) {
    if (nearPlateEdge(plate, node)) continue;
    for (int d = 0; d < 3; ++d) {
      ghost.force = std::max(ghost.force, std::abs(evaluation.internalForces(node, d)) / forceScale);
      ghost.moment = std::max(ghost.moment, std::abs(evaluation.internalForces(node, 3 + d)) / momentScale);
    }
  }
  return ghost;
}

const char* profileName(TransitionProfile profile) {
  return profile == TransitionProfile::Cubic ? "cubic" : "linear";
}

}  // namespace morphing_test

TEST(TEST_CATEGORY, morphing_alpha_field_follows_the_profile) {
  using namespace morphing_test;
  // L_c = 8 dx: nodes 2, 4, 6 dx from the band sit at s = 0.25, 0.5, 0.75.
  const double width = 8.0 * spacing;
  for (const auto profile : {TransitionProfile::Cubic, TransitionProfile::Linear}) {
    const auto plate = makeCoupledPlate(0.2, profile, Zone::Band, width);
    const auto alpha = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, plate.bodies.alpha);
    const auto& mesh = plate.shell.mesh;
    // Band of PD elements: nodes at x in [15, 21] mm.
    const double bandLow = 15 * spacing, bandHigh = 21 * spacing;
    const std::array<double, 3> expected = profile == TransitionProfile::Cubic
                                               ? std::array<double, 3>{0.84375, 0.5, 0.15625}
                                               : std::array<double, 3>{0.75, 0.5, 0.25};
    for (LocalIndex node = 0; node < mesh.numNodes(); ++node) {
      const double x = mesh.coordinates(node, 0);
      const double distance = std::max({bandLow - x, x - bandHigh, 0.0});
      const double s = distance / width;
      if (s == 0.0) {
        EXPECT_EQ(alpha(node), 1.0) << "node " << node;
      }
      if (s >= 1.0 - 1e-9) {
        EXPECT_EQ(alpha(node), 0.0) << "node " << node;
      }
      for (int k = 0; k < 3; ++k) {
        if (std::abs(s - 0.25 * (k + 1)) < 1e-9) {
          EXPECT_NEAR(alpha(node), expected[k], 1e-12) << "s = " << s;
        }
      }
      // Monotone: the next node away from the band never has a larger alpha.
      if (node + 1 < mesh.numNodes() && x > bandHigh && mesh.coordinates(node + 1, 0) > x) {
        EXPECT_LE(alpha(node + 1), alpha(node));
      }
      if (node > 0 && x < bandLow && mesh.coordinates(node - 1, 0) < x) {
        EXPECT_LE(alpha(node - 1), alpha(node));
      }
    }
    EXPECT_DOUBLE_EQ(perishell::coupling::transitionProfile(profile, 0.0), 1.0);
    EXPECT_DOUBLE_EQ(perishell::coupling::transitionProfile(profile, 1.0), 0.0);
  }
  // The bond carriers are the nodes with alpha > 0. A band 10 elements wide (x in [13, 23] mm):
  // its nodes at least delta = 3 mm inside (x = 16..20 mm) bond only to alpha = 1 nodes, so
  // alphaBar = 1 there and the 4 x 36 elements between them are pure PD, without a shell element.
  const auto plate = makeCoupledPlate(0.2, TransitionProfile::Cubic, Zone::Band, 0.0, 5.0 * spacing);
  const auto alpha = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, plate.bodies.alpha);
  LocalIndex positive = 0;
  for (std::size_t node = 0; node < alpha.extent(0); ++node) positive += alpha(node) > 0.0;
  EXPECT_EQ(LocalIndex(plate.bodies.pdNodes.extent(0)), positive);
  // Band nodes x = 13..23 mm (11 columns) and the transition out to < 6 mm each side (5 columns each).
  EXPECT_EQ(positive, 37 * (11 + 2 * 5));
  for (LocalIndex k = 0; k < positive; ++k) EXPECT_GT(alpha(plate.bodies.pdNodes(k)), 0.0);
  // The body is indexed by mesh node: exactly the nodes with alpha > 0 hold bonds, every
  // bond joins two of them, and each node's geometry is its mesh node's.
  const auto& body = plate.bodies.pdBody;
  ASSERT_EQ(body.numNodes(), plate.shell.mesh.numNodes());
  const auto offsets = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, body.bonds.offsets);
  const auto neighbours = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, body.bonds.neighbours);
  const auto halfBonds = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, body.bonds.halfBonds);
  const auto positions = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, body.referencePositions);
  const auto length = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, body.bonds.referenceLength);
  for (LocalIndex node = 0; node < body.numNodes(); ++node) {
    EXPECT_EQ(offsets(node + 1) > offsets(node), alpha(node) > 0.0) << "node " << node;
    for (int d = 0; d < 3; ++d) EXPECT_EQ(positions(node, d), plate.shell.mesh.coordinates(node, d));
    for (auto entry = offsets(node); entry < offsets(node + 1); ++entry) EXPECT_GT(alpha(neighbours(entry)), 0.0);
  }
  for (std::size_t b = 0; b < halfBonds.extent(0); ++b) {
    double squared = 0.0;
    for (int d = 0; d < 3; ++d)
      squared += std::pow(positions(halfBonds(b, 1), d) - positions(halfBonds(b, 0), d), 2);
    EXPECT_NEAR(std::sqrt(squared), length(b), 1e-12 * spacing) << "bond " << b;
  }
  EXPECT_EQ(plate.bodies.ccmElements.size(), std::size_t(cells * cells - 4 * cells));
  EXPECT_EQ(plate.bodies.shellBody.numElements(), LocalIndex(plate.bodies.ccmElements.size()));
}

TEST(TEST_CATEGORY, morphing_degenerates_to_pure_models) {
  using namespace morphing_test;
  // 100 % PD: alpha = 1 everywhere, every node bonded, no shell element.
  CoupledPlate pd = makeCoupledPlate(0.2, TransitionProfile::Cubic, Zone::Band, 0.0, 1.0);
  EXPECT_EQ(pd.bodies.pdBody.numNodes(), pd.shell.mesh.numNodes());
  EXPECT_TRUE(pd.bodies.ccmElements.empty());
  // 0 % PD, nu > 1/3 (legal without PD): no bond carrier, every element with the full section.
  CoupledPlate ccm = makeCoupledPlate(0.4, TransitionProfile::Cubic, Zone::Band, 0.0, 0.0);
  EXPECT_EQ(ccm.bodies.pdNodes.extent(0), 0u);
  EXPECT_EQ(ccm.bodies.pdBody.numNodes(), ccm.shell.mesh.numNodes());
  EXPECT_EQ(ccm.bodies.pdBody.bonds.numBonds(), 0u);
  EXPECT_EQ(ccm.bodies.ccmElements.size(), std::size_t(cells * cells));
  const auto scale = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, ccm.bodies.shellBody.membraneBendingScale);
  for (std::size_t e = 0; e < scale.extent(0); ++e)
    for (int q = 0; q < 4; ++q) EXPECT_EQ(scale(e, q), 1.0);
  // A transition narrower than 2 delta is refused.
  EXPECT_THROW(makeCoupledPlate(0.2, TransitionProfile::Cubic, Zone::Band, 5.9 * spacing), std::invalid_argument);
}

TEST(TEST_CATEGORY, morphing_stores_the_classical_energy_and_cubic_beats_linear_on_ghost_forces) {
  using namespace morphing_test;
  using Element = perishell::shell::ShellElementKind;
  for (const Element kind : {Element::Mitc4, Element::OnePoint})
  for (const Zone zone : {Zone::Band, Zone::Disc})
    for (const double nu : {0.2, 0.33}) {
      Ghost worst[2] = {{0, 0}, {0, 0}};
      for (const auto profile : {TransitionProfile::Cubic, TransitionProfile::Linear}) {
        const auto plate = makeCoupledPlate(nu, profile, zone, 0.0, 3.0 * spacing, kind);
        for (const State& state : states) {
          const auto evaluation = evaluate(plate, fieldOf(state));
          const double classical = classicalEnergy(state, nu);
          const double error = (evaluation.pdEnergy + evaluation.shellEnergy) / classical - 1.0;
          const Ghost ghost = ghostForces(plate, state, evaluation, nu);
          std::printf("%s %s nu=%.2f %-6s %-9s W_pd/W=%.4f (W_pd+W_ccm)/W_classical-1=%+.3e ghost force %.3e moment "
                      "%.3e\n",
                      kind == Element::Mitc4 ? "MITC4" : "one-point", zone == Zone::Band ? "band" : "disc", nu,
                      profileName(profile), state.name,
                      evaluation.pdEnergy / classical, error, ghost.force, ghost.moment);
          EXPECT_LT(std::abs(error), 0.01) << state.name << " " << profileName(profile) << " nu " << nu;
          const int p = profile == TransitionProfile::Cubic ? 0 : 1;
          worst[p].force = std::max(worst[p].force, ghost.force);
          worst[p].moment = std::max(worst[p].moment, ghost.moment);
        }
      }
      // Measured (36 mm plate, L_c = 2 delta): forces 0.11 / 0.13, moments 0.11 / 0.13 (cubic / linear).
      EXPECT_LT(worst[0].force, worst[1].force) << "nu " << nu;
      EXPECT_LT(worst[0].moment, worst[1].moment) << "nu " << nu;
      EXPECT_LT(worst[0].force, 0.15) << "nu " << nu;
      EXPECT_LT(worst[0].moment, 0.15) << "nu " << nu;
    }
}
