// Explicit dynamics of mixed PD-CCM plates (model.md §4, §6): shell elements and morphed bonds
// on one state per mesh node, with the one-point element (the explicit default) and with
// MITC4. Free vibration conserves energy (2,000 steps, to keep the sanitizer build's serial
// run short; 10,000 for a CCM plate) with the zone inside the plate and without any PD, and
// the one-point elements' hourglass energy stays a small part of their strain energy; the
// critical-step estimate covers the elements (0.9 dt_crit runs, 1.5 dt_crit is caught); a
// plane wave runs at the plate wave speed in CCM and across a PD band; the same mixed run
// agrees on the host and on TEST_EXECSPACE.
#include <perishell/coupling/make_coupled_model.hpp>
#include <perishell/mesh/generators.hpp>
#include <perishell/solvers/explicit/central_difference.hpp>
#include <solvers/pushed_edge.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>

namespace coupled_dynamics_test {

using perishell::LocalIndex;
using Element = perishell::shell::ShellElementKind;
constexpr Element elementKinds[2] = {Element::OnePoint, Element::Mitc4};
inline const char* elementName(Element kind) { return kind == Element::OnePoint ? "one-point" : "MITC4"; }
constexpr double pi = 3.14159265358979323846;
constexpr double spacing = 1e-3, youngModulus = 70e9, thickness = 1e-3, density = 2440.0;

enum class Zone { None, Disc, Band };

struct MixedPlate {
  perishell::mesh::ShellMesh shell;
  Kokkos::View<std::uint8_t*, Kokkos::HostSpace> elementIsPd;
  perishell::coupling::CouplingInputs inputs;
};

// Each quad a b c d cut into two triangles (a b c c and a c d d, or across the other diagonal
// in every other cell); the plate's node and edge sets stay valid.
void cutIntoTriangles(perishell::mesh::HostQuadMesh& mesh) {
  const LocalIndex numQuads = mesh.numElements();
  perishell::QuadConnectivityView<Kokkos::HostSpace> triangles("triangles", 2 * numQuads);
  for (LocalIndex e = 0; e < numQuads; ++e) {
    const LocalIndex a = mesh.quads(e, 0), b = mesh.quads(e, 1), c = mesh.quads(e, 2), d = mesh.quads(e, 3);
    const LocalIndex cut[2][3] = {{a, b, e % 2 ? d : c}, {e % 2 ? b : a, c, d}};
    for (int t = 0; t < 2; ++t)
      for (int k = 0; k < 4; ++k) triangles(2 * e + t, k) = cut[t][k < 3 ? k : 2];
  }
  mesh.quads = triangles;
}

// cellsX x cellsY cells of 1 mm (quads, or with `triangles` two triangles each); PD
// elements: none, a disc of radius 4 mm at the centre, or a band 6 mm wide across x at the
// middle. delta = 3 dx, transition 2 delta, cubic.
MixedPlate makeMixedPlate(int cellsX, int cellsY, double poissonRatio, Zone zone, Element kind,
                          bool triangles = false) {
  MixedPlate plate;
  plate.shell = perishell::mesh::makePlate(cellsX * spacing, cellsY * spacing, spacing);
  if (triangles) cutIntoTriangles(plate.shell.mesh);
  const auto& mesh = plate.shell.mesh;
  plate.elementIsPd = Kokkos::View<std::uint8_t*, Kokkos::HostSpace>("is pd", mesh.numElements());
  const double centreX = 0.5 * cellsX * spacing, centreY = 0.5 * cellsY * spacing;
  for (LocalIndex e = 0; e < mesh.numElements(); ++e) {
    double c[2] = {0.0, 0.0};
    const int corners = perishell::mesh::cornerCount(mesh.quads, e);
    for (int a = 0; a < corners; ++a)
      for (int d = 0; d < 2; ++d) c[d] += mesh.coordinates(mesh.quads(e, a), d) / corners;
    switch (zone) {
      case Zone::None: plate.elementIsPd(e) = 0; break;
      case Zone::Disc: plate.elementIsPd(e) = std::hypot(c[0] - centreX, c[1] - centreY) < 4.0 * spacing; break;
      case Zone::Band: plate.elementIsPd(e) = std::abs(c[0] - centreX) < 3.0 * spacing; break;
    }
  }
  auto& inputs = plate.inputs;
  inputs.material = {youngModulus, poissonRatio, thickness, {}};
  inputs.section = {youngModulus, poissonRatio, thickness};
  inputs.horizon = 3.0 * spacing;
  inputs.gridSpacing = spacing;
  inputs.shellElement = kind;
  return plate;
}

template <class ExecutionSpaceT>
using Solver = perishell::solvers::CentralDifferenceSolver<ExecutionSpaceT>;

template <class ExecutionSpaceT>
Solver<ExecutionSpaceT> makeSolver(const MixedPlate& plate,
                                   perishell::solvers::ExternalActions<typename ExecutionSpaceT::memory_space> actions,
                                   double timeStep = 0.0, double hourglassEnergyLimit = 0.1) {
  auto bodies = perishell::coupling::makeCoupledBodies(ExecutionSpaceT{}, plate.shell.mesh, plate.elementIsPd,
                                                       plate.inputs);
  perishell::solvers::ExplicitOptions options;
  options.density = density;
  options.thickness = thickness;
  options.timeStep = timeStep;
  options.hourglassEnergyLimit = hourglassEnergyLimit;
  return Solver<ExecutionSpaceT>(ExecutionSpaceT{}, bodies.pdBody, bodies.shellElements(), std::move(actions), options);
}

// A smooth mix of membrane and bending motion over a 24 mm plate.
template <class ExecutionSpaceT>
void startVibration(Solver<ExecutionSpaceT>& solver, const MixedPlate& plate) {
  const auto& mesh = plate.shell.mesh;
  perishell::pd::NodalVectorView<Kokkos::HostSpace> v("initial velocities", mesh.numNodes());
  const double L = 24e-3;
  for (LocalIndex node = 0; node < mesh.numNodes(); ++node) {
    const double x = mesh.coordinates(node, 0), y = mesh.coordinates(node, 1);
    v(node, 0) = 0.05 * std::sin(pi * x / L) * std::cos(pi * y / L);
    v(node, 1) = 0.03 * std::cos(2 * pi * x / L) * std::sin(pi * y / L);
    v(node, 2) = 0.2 * std::sin(pi * x / L) * std::sin(pi * y / L);
  }
  solver.setInitialVelocities(Kokkos::create_mirror_view_and_copy(typename ExecutionSpaceT::memory_space{}, v));
}

struct VibrationEnergies {
  double worstDrift = 0.0;       // |stored / initial - 1|
  double largestStrain = 0.0;    // strain / initial kinetic
  double largestHourglass = 0.0;  // hourglass / strain energy
};

// Energies over the steps (checked every 100 steps).
VibrationEnergies vibrationEnergies(Solver<TEST_EXECSPACE>& solver, long long steps) {
  solver.step();
  const auto initial = solver.lastEnergyReport();
  EXPECT_GT(initial.kinetic, 0.0);
  VibrationEnergies result;
  while (solver.stepIndex() <= steps) {
    solver.step();
    const auto& report = solver.lastEnergyReport();
    result.worstDrift = std::max(result.worstDrift, std::abs(report.stored() / initial.stored() - 1.0));
    result.largestStrain = std::max(result.largestStrain, report.strain / initial.kinetic);
    if (report.strain > 0.05 * initial.kinetic)
      result.largestHourglass = std::max(result.largestHourglass, report.hourglass / report.strain);
  }
  return result;
}

// The speeds of a plane wave pushed into the 200 x 10 mm strip's left edge, timed between
// stations on the centre line at 40 and 80 mm (CCM) and at 80 and 120 mm (across the band).
struct WaveSpeeds {
  double ccm, acrossBand;
};

WaveSpeeds planeWaveSpeeds(const MixedPlate& plate, double expectedSpeed) {
  const auto& mesh = plate.shell.mesh;
  const double pushSpeed = 0.1, rampTime = 1.0;
  auto solver = makeSolver<TEST_EXECSPACE>(plate, pushedEdgeActions<TEST_MEMSPACE>(mesh, 0.5 * spacing, pushSpeed, rampTime));
  EXPECT_GT(solver.body().bonds.numBonds(), 0u);
  const double stations[3] = {40e-3, 80e-3, 120e-3};
  LocalIndex probe[3] = {0, 0, 0};
  for (LocalIndex node = 0; node < mesh.numNodes(); ++node)
    for (int s = 0; s < 3; ++s)
      if (std::abs(mesh.coordinates(node, 0) - stations[s]) < 1e-9 && std::abs(mesh.coordinates(node, 1) - 5e-3) < 1e-9)
        probe[s] = node;
  double arrival[3] = {0.0, 0.0, 0.0}, previous[3] = {0.0, 0.0, 0.0};
  while (solver.time() < 1.3 * stations[2] / expectedSpeed && arrival[2] == 0.0) {
    solver.step();
    const auto velocities = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, solver.velocities());
    for (int s = 0; s < 3; ++s) {
      const double v = velocities(probe[s], 0);
      if (arrival[s] == 0.0 && v >= 0.5 * pushSpeed)
        arrival[s] = solver.time() - 0.5 * solver.timeStep() - solver.timeStep() * (v - 0.5 * pushSpeed) / (v - previous[s]);
      previous[s] = v;
    }
  }
  for (int s = 0; s < 3; ++s) EXPECT_GT(arrival[s], 0.0) << "station " << s;
  return {(stations[1] - stations[0]) / (arrival[1] - arrival[0]), (stations[2] - stations[1]) / (arrival[2] - arrival[1])};
}

}  // namespace coupled_dynamics_test

TEST(TEST_CATEGORY, coupled_free_vibration_conserves_energy) {
  using namespace coupled_dynamics_test;
  for (const Element kind : elementKinds)
    for (const Zone zone : {Zone::Disc, Zone::None}) {
      const auto plate = makeMixedPlate(24, 24, 0.2, zone, kind);
      auto solver = makeSolver<TEST_EXECSPACE>(plate, perishell::solvers::makeFreeActions<TEST_MEMSPACE>(
                                                          plate.shell.mesh.numNodes()));
      EXPECT_GT(solver.numElements(), 0);
      EXPECT_EQ(solver.body().bonds.numBonds() > 0, zone == Zone::Disc);
      startVibration(solver, plate);
      const long long steps = zone == Zone::None && kind == Element::OnePoint ? 10000 : 2000;
      const VibrationEnergies energies = vibrationEnergies(solver, steps);
      std::printf("%s, %s: dt = %.4e s (critical %.4e s), worst energy drift over %lld steps %.3e, peak strain / "
                  "initial kinetic %.3f, peak hourglass / strain %.2e\n",
                  zone == Zone::Disc ? "PD disc in CCM plate" : "CCM plate", elementName(kind), solver.timeStep(),
                  solver.criticalTimeStep(), steps, energies.worstDrift, energies.largestStrain,
                  energies.largestHourglass);
      // Energy really moved into the elements and bonds, so the check is not vacuous.
      EXPECT_GT(energies.largestStrain, 0.3);
      EXPECT_LT(energies.worstDrift, 1e-3);
      if (kind == Element::OnePoint)
        EXPECT_LT(energies.largestHourglass, 0.01);
      else
        EXPECT_EQ(energies.largestHourglass, 0.0);
    }
}

TEST(TEST_CATEGORY, coupled_time_step_below_the_limit_runs_and_above_it_is_caught) {
  using namespace coupled_dynamics_test;
  for (const Element kind : elementKinds) {
  const auto plate = makeMixedPlate(24, 24, 0.25, Zone::Disc, kind);
  const auto actions = perishell::solvers::makeFreeActions<TEST_MEMSPACE>(plate.shell.mesh.numNodes());
  const double critical = makeSolver<TEST_EXECSPACE>(plate, actions).criticalTimeStep();
  // The elements set the limit as well as the bonds. For lumped-mass membrane elements it is
  // of the order of the wave's transit time across one element, dx / sqrt(E / (rho (1 - nu^2)))
  // (exactly that for a 1D bar); a bending or drilling mode left unscaled by the rotary
  // inertia would make it far smaller.
  const double transit = spacing / std::sqrt(youngModulus / (density * (1.0 - 0.25 * 0.25)));
  std::printf("%s: critical step %.4e s, element transit time %.4e s\n", elementName(kind), critical, transit);
  EXPECT_GT(critical, 0.5 * transit);
  EXPECT_LT(critical, 1.1 * transit);
  {
    auto stable = makeSolver<TEST_EXECSPACE>(plate, actions, 0.9 * critical);
    startVibration(stable, plate);
    for (int s = 0; s < 1000; ++s) ASSERT_NO_THROW(stable.step()) << "step " << s;
    EXPECT_LT(std::abs(stable.lastEnergyReport().balanceError()), 1e-3);
  }
  auto unstable = makeSolver<TEST_EXECSPACE>(plate, actions, 1.5 * critical);
  startVibration(unstable, plate);
  try {
    for (int s = 0; s < 3000; ++s) unstable.step();
    FAIL() << "dt = 1.5 dt_crit ran 3000 steps undetected";
  } catch (const perishell::solvers::ExplicitInstability& error) {
    std::printf("caught at step %lld: %s\n", unstable.stepIndex(), error.what());
    EXPECT_NE(std::string(error.what()).find("ratio 1.5"), std::string::npos);
    EXPECT_LE(unstable.stepIndex(), 300);
  }
  }
}

TEST(TEST_CATEGORY, coupled_plane_wave_crosses_a_pd_band_at_the_plate_wave_speed) {
  using namespace coupled_dynamics_test;
  // A strip 200 x 10 mm, PD band across its middle (x in [97, 103] mm) with transitions out to
  // 91 and 109 mm. Uniaxial strain (u_y = 0, no bending DOF): the front runs at
  // sqrt(E / (rho (1 - nu^2))) in CCM and PD alike; timed over a CCM stretch and across the band.
  const double nu = 0.33;
  for (const Element kind : elementKinds) {
  const auto plate = makeMixedPlate(200, 10, nu, Zone::Band, kind);
  const double expectedSpeed = std::sqrt(youngModulus / (density * (1 - nu * nu)));
  const WaveSpeeds speeds = planeWaveSpeeds(plate, expectedSpeed);
  const double ccmSpeed = speeds.ccm, acrossBand = speeds.acrossBand;
  std::printf("plane wave, %s: CCM %.1f m/s, across the PD band %.1f m/s, sqrt(E/(rho(1-nu^2))) = %.1f m/s\n",
              elementName(kind), ccmSpeed, acrossBand, expectedSpeed);
  EXPECT_NEAR(ccmSpeed / expectedSpeed, 1.0, 0.02);
  EXPECT_NEAR(acrossBand / expectedSpeed, 1.0, 0.02);
  }
}

// Triangles (shell/mitc3_triangle.hpp; with the one-point kind, the explicit triangle of
// shell/explicit_triangle.hpp): the same energy conservation and wave speed as on quads.
TEST(TEST_CATEGORY, coupled_free_vibration_and_plane_wave_on_triangles) {
  using namespace coupled_dynamics_test;
  for (const Element kind : elementKinds) {
  {
    const auto plate = makeMixedPlate(24, 24, 0.2, Zone::Disc, kind, true);
    auto solver = makeSolver<TEST_EXECSPACE>(plate, perishell::solvers::makeFreeActions<TEST_MEMSPACE>(
                                                        plate.shell.mesh.numNodes()));
    EXPECT_GT(solver.numElements(), 24 * 24);  // triangles: twice the cells, less the pure PD ones
    startVibration(solver, plate);
    const VibrationEnergies energies = vibrationEnergies(solver, 2000);
    std::printf("triangles (%s), PD disc: dt = %.4e s, worst energy drift over 2000 steps %.3e, peak strain / "
                "initial kinetic %.3f\n", elementName(kind), solver.timeStep(), energies.worstDrift,
                energies.largestStrain);
    EXPECT_GT(energies.largestStrain, 0.3);
    EXPECT_LT(energies.worstDrift, 1e-3);
  }
  const double nu = 0.33;
  const auto plate = makeMixedPlate(200, 10, nu, Zone::Band, kind, true);
  const double expectedSpeed = std::sqrt(youngModulus / (density * (1 - nu * nu)));
  const WaveSpeeds speeds = planeWaveSpeeds(plate, expectedSpeed);
  const double ccmSpeed = speeds.ccm, acrossBand = speeds.acrossBand;
  std::printf("plane wave, triangles (%s): CCM %.1f m/s, across the PD band %.1f m/s, sqrt(E/(rho(1-nu^2))) = "
              "%.1f m/s\n", elementName(kind), ccmSpeed, acrossBand, expectedSpeed);
  EXPECT_NEAR(ccmSpeed / expectedSpeed, 1.0, 0.02);
  EXPECT_NEAR(acrossBand / expectedSpeed, 1.0, 0.02);
  }
}

namespace coupled_dynamics_test {

template <class ExecutionSpaceT>
perishell::CoordinateView<Kokkos::HostSpace> vibrateMixed(const MixedPlate& plate, double timeStep, int steps) {
  using Memory = typename ExecutionSpaceT::memory_space;
  auto solver = makeSolver<ExecutionSpaceT>(plate, perishell::solvers::makeFreeActions<Memory>(plate.shell.mesh.numNodes()),
                                            timeStep);
  startVibration(solver, plate);
  for (int s = 0; s < steps; ++s) solver.step();
  return Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, solver.kinematics().displacements);
}

}  // namespace coupled_dynamics_test

TEST(TEST_CATEGORY, coupled_host_and_device_runs_agree) {
  using namespace coupled_dynamics_test;
  for (const Element kind : elementKinds) {
  const auto plate = makeMixedPlate(24, 24, 0.2, Zone::Disc, kind);
  const double dt = 0.8 * makeSolver<Kokkos::DefaultHostExecutionSpace>(
                              plate, perishell::solvers::makeFreeActions<Kokkos::HostSpace>(plate.shell.mesh.numNodes()))
                              .criticalTimeStep();
  const auto host = vibrateMixed<Kokkos::DefaultHostExecutionSpace>(plate, dt, 500);
  const auto device = vibrateMixed<TEST_EXECSPACE>(plate, dt, 500);
  double largest = 0.0, difference = 0.0;
  for (std::size_t node = 0; node < host.extent(0); ++node)
    for (int d = 0; d < 3; ++d) {
      largest = std::max(largest, std::abs(host(node, d)));
      difference = std::max(difference, std::abs(host(node, d) - device(node, d)));
    }
  std::printf("%s, %s vs %s, 500 steps: largest displacement %.4e m, largest difference %.3e m (relative %.2e)\n",
              elementName(kind), Kokkos::DefaultHostExecutionSpace::name(), TEST_EXECSPACE::name(), largest,
              difference, difference / largest);
  ASSERT_GT(largest, 0.0);
  EXPECT_LT(difference, 1e-10 * largest);
  }
}

TEST(TEST_CATEGORY, coupled_hourglass_energy_past_its_bound_stops_the_run) {
  using namespace coupled_dynamics_test;
  // The vibrating CCM plate stores ~1e-4 of its strain energy in hourglass modes; a bound
  // below that must stop the run with a message naming the hourglass energy.
  const auto plate = makeMixedPlate(12, 12, 0.2, Zone::None, Element::OnePoint);
  auto solver = makeSolver<TEST_EXECSPACE>(
      plate, perishell::solvers::makeFreeActions<TEST_MEMSPACE>(plate.shell.mesh.numNodes()), 0.0, 1e-9);
  startVibration(solver, plate);
  try {
    for (int s = 0; s < 1000; ++s) solver.step();
    FAIL() << "a hourglass share above 1e-9 ran 1000 steps undetected";
  } catch (const perishell::solvers::ExplicitInstability& error) {
    const std::string message = error.what();
    std::printf("caught at step %lld: %s\n", solver.stepIndex(), message.c_str());
    EXPECT_NE(message.find("hourglass energy"), std::string::npos) << message;
    EXPECT_NE(message.find("solver.shell-element: mitc4"), std::string::npos) << message;
    EXPECT_LE(solver.stepIndex(), 200);
  }
}
