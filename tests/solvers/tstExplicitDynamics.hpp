// Central-difference dynamics of PD plates (model.md §6): energy conservation of free
// vibration, the plane-wave speed, a rigid spin, the stability limit (runs below it, is
// caught above it), and the same run on the host and on TEST_EXECSPACE.
#include <perishell/mesh/generators.hpp>
#include <perishell/pd/make_body.hpp>
#include <perishell/solvers/explicit/central_difference.hpp>
#include <solvers/pushed_edge.hpp>

#include <cmath>
#include <functional>

namespace {

using perishell::LocalIndex;
constexpr double pi = 3.14159265358979323846;

struct PlateSetup {
  perishell::mesh::ShellMesh shell;
  perishell::pd::PdMaterial material;
  double density;
  double spacing;
};

PlateSetup makePlate(int cellsX, int cellsY, double poissonRatio) {
  const double spacing = 1e-3;
  return {perishell::mesh::makePlate(cellsX * spacing, cellsY * spacing, spacing),
          {70e9, poissonRatio, 1e-3, std::nullopt}, 2440.0, spacing};
}

template <class ExecutionSpaceT>
perishell::pd::PdBody<typename ExecutionSpaceT::memory_space> makeBody(const PlateSetup& plate) {
  return perishell::pd::makePdBody(ExecutionSpaceT{}, plate.shell.mesh,
                                   perishell::pd::allNodes(plate.shell.mesh.numNodes()), plate.material,
                                   3.0 * plate.spacing, plate.spacing, {});
}

perishell::solvers::ExplicitOptions optionsFor(const PlateSetup& plate, double timeStep = 0.0) {
  perishell::solvers::ExplicitOptions options;
  options.density = plate.density;
  options.thickness = plate.material.thickness;
  options.timeStep = timeStep;
  return options;
}

template <class ExecutionSpaceT>
using Solver = perishell::solvers::CentralDifferenceSolver<ExecutionSpaceT>;
using HostNodal = perishell::pd::NodalVectorView<Kokkos::HostSpace>;
using VelocityField = std::function<void(double x, double y, double v[6])>;

template <class ExecutionSpaceT>
void setVelocities(Solver<ExecutionSpaceT>& solver, const PlateSetup& plate, const VelocityField& field) {
  HostNodal host("initial velocities", plate.shell.mesh.numNodes());
  for (LocalIndex node = 0; node < plate.shell.mesh.numNodes(); ++node) {
    double v[6];
    field(plate.shell.mesh.coordinates(node, 0), plate.shell.mesh.coordinates(node, 1), v);
    for (int d = 0; d < 6; ++d) host(node, d) = v[d];
  }
  solver.setInitialVelocities(Kokkos::create_mirror_view_and_copy(typename ExecutionSpaceT::memory_space{}, host));
}

// A smooth mix of membrane and bending motion.
void vibrationMode(double x, double y, double v[6]) {
  const double L = 16e-3;
  v[0] = 0.05 * std::sin(pi * x / L) * std::cos(pi * y / L);
  v[1] = 0.03 * std::cos(2 * pi * x / L) * std::sin(pi * y / L);
  v[2] = 0.2 * std::sin(pi * x / L) * std::sin(pi * y / L);
  v[3] = v[4] = v[5] = 0.0;
}

template <class ExecutionSpaceT>
perishell::CoordinateView<Kokkos::HostSpace> runVibration(const PlateSetup& plate, perishell::deck::ForceKernel kernel,
                                                           int steps) {
  auto body = makeBody<ExecutionSpaceT>(plate);
  auto options = optionsFor(plate);
  options.forceKernel = kernel;
  using Memory = typename ExecutionSpaceT::memory_space;
  Solver<ExecutionSpaceT> solver(ExecutionSpaceT{}, body,
                                 perishell::solvers::makeFreeActions<Memory>(body.numNodes()), options);
  setVelocities(solver, plate, vibrationMode);
  for (int s = 0; s < steps; ++s) solver.step();
  return Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, solver.kinematics().displacements);
}

}  // namespace

TEST(TEST_CATEGORY, explicit_free_vibration_conserves_energy_over_10000_steps) {
  const auto plate = makePlate(16, 16, 0.2);
  const auto body = makeBody<TEST_EXECSPACE>(plate);
  Solver<TEST_EXECSPACE> solver(TEST_EXECSPACE{}, body, perishell::solvers::makeFreeActions<TEST_MEMSPACE>(body.numNodes()),
                                optionsFor(plate));
  setVelocities(solver, plate, vibrationMode);
  solver.step();
  const auto initial = solver.lastEnergyReport();
  ASSERT_GT(initial.kinetic, 0.0);
  EXPECT_LT(initial.strain, 1e-20 * initial.kinetic);  // at rest in the reference state
  double worstDrift = 0.0, largestStrain = 0.0;
  while (solver.stepIndex() <= 10000) {
    solver.step();
    const auto& report = solver.lastEnergyReport();
    worstDrift = std::max(worstDrift, std::abs(report.stored() / initial.stored() - 1.0));
    largestStrain = std::max(largestStrain, report.strain);
  }
  std::printf("dt = %.4e s (critical %.4e s), worst energy drift over 10,000 steps %.3e\n", solver.timeStep(),
              solver.criticalTimeStep(), worstDrift);
  EXPECT_EQ(solver.lastEnergyReport().step, 10000);
  // Energy really moved between kinetic and strain, so the check is not vacuous.
  EXPECT_GT(largestStrain, 0.3 * initial.kinetic);
  EXPECT_LT(worstDrift, 1e-3);
}

TEST(TEST_CATEGORY, explicit_plane_wave_travels_at_the_plate_wave_speed) {
  const double nu = 0.33;
  const auto plate = makePlate(240, 40, nu);
  const auto body = makeBody<TEST_EXECSPACE>(plate);
  const LocalIndex numNodes = body.numNodes();
  // Uniaxial strain: u_y = 0 everywhere, so the front moves at sqrt(E / (rho (1 - nu^2))).
  // The left edge is pushed at a constant speed v0 (a ramp of its displacement).
  const double pushSpeed = 0.1, rampTime = 1.0;
  const auto actions = pushedEdgeActions<TEST_MEMSPACE>(plate.shell.mesh, 0.5 * plate.spacing, pushSpeed, rampTime);
  Solver<TEST_EXECSPACE> solver(TEST_EXECSPACE{}, body, actions, optionsFor(plate));

  // Arrival time of the front (half the push speed) at two stations on the centre line.
  const double stations[2] = {80e-3, 160e-3};
  LocalIndex probe[2] = {0, 0};
  for (LocalIndex node = 0; node < numNodes; ++node)
    for (int s = 0; s < 2; ++s)
      if (std::abs(plate.shell.mesh.coordinates(node, 0) - stations[s]) < 1e-9 &&
          std::abs(plate.shell.mesh.coordinates(node, 1) - 20e-3) < 1e-9)
        probe[s] = node;
  const double E = plate.material.youngModulus;
  const double expectedSpeed = std::sqrt(E / (plate.density * (1 - nu * nu)));
  double arrival[2] = {0.0, 0.0};
  double previousVelocity[2] = {0.0, 0.0};
  const double endTime = 1.3 * stations[1] / expectedSpeed;
  while (solver.time() < endTime && arrival[1] == 0.0) {
    solver.step();
    const auto velocities = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, solver.velocities());
    for (int s = 0; s < 2; ++s) {
      const double v = velocities(probe[s], 0);
      // Linear interpolation of the crossing; velocities live at half steps.
      if (arrival[s] == 0.0 && v >= 0.5 * pushSpeed)
        arrival[s] = solver.time() - 0.5 * solver.timeStep() -
                     solver.timeStep() * (v - 0.5 * pushSpeed) / (v - previousVelocity[s]);
      previousVelocity[s] = v;
    }
  }
  ASSERT_GT(arrival[0], 0.0);
  ASSERT_GT(arrival[1], 0.0);
  const double measuredSpeed = (stations[1] - stations[0]) / (arrival[1] - arrival[0]);
  std::printf("plane wave: measured %.1f m/s, sqrt(E/(rho(1-nu^2))) = %.1f m/s, ratio - 1 = %+.3e\n", measuredSpeed,
              expectedSpeed, measuredSpeed / expectedSpeed - 1);
  EXPECT_NEAR(measuredSpeed / expectedSpeed, 1.0, 0.02);
}

TEST(TEST_CATEGORY, explicit_rigid_spin_keeps_the_plate_shape) {
  const auto plate = makePlate(10, 10, 0.2);
  const auto body = makeBody<TEST_EXECSPACE>(plate);
  Solver<TEST_EXECSPACE> solver(TEST_EXECSPACE{}, body, perishell::solvers::makeFreeActions<TEST_MEMSPACE>(body.numNodes()),
                                optionsFor(plate));
  // Spin about the x axis through the plate's centre line: v = omega x (X - c).
  const double omega = 2000.0, cy = 5e-3;
  setVelocities(solver, plate, [&](double, double y, double v[6]) {
    v[0] = 0.0;
    v[1] = 0.0;
    v[2] = omega * (y - cy);
    v[3] = omega;
    v[4] = v[5] = 0.0;
  });
  const double quarterTurn = 0.5 * pi / omega;
  while (solver.time() < quarterTurn) solver.step();
  const auto u = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, solver.kinematics().displacements);
  const auto& X = plate.shell.mesh.coordinates;
  // Shape: every distance between the corner nodes and all others is kept.
  double worstStrain = 0.0;
  const LocalIndex last = plate.shell.mesh.numNodes() - 1;
  for (const LocalIndex corner : {LocalIndex(0), last})
    for (LocalIndex node = 0; node < plate.shell.mesh.numNodes(); ++node) {
      if (node == corner) continue;
      double before = 0.0, after = 0.0;
      for (int d = 0; d < 3; ++d) {
        before += std::pow(X(node, d) - X(corner, d), 2);
        after += std::pow(X(node, d) + u(node, d) - X(corner, d) - u(corner, d), 2);
      }
      worstStrain = std::max(worstStrain, std::abs(std::sqrt(after / before) - 1.0));
    }
  // The plate turned: the far edge (y = 10 mm) moved up by about its distance from the axis.
  const double turnedAngle = solver.time() * omega;
  std::printf("rigid spin by %.4f rad: worst relative change of distance %.3e\n", turnedAngle, worstStrain);
  EXPECT_NEAR(X(last, 2) + u(last, 2), (10e-3 - cy) * std::sin(turnedAngle), 2e-3 * (10e-3 - cy));
  // Centrifugal stretching is rho omega^2 R^2 / E ~ 1e-7 here.
  EXPECT_LT(worstStrain, 1e-5);
}

TEST(TEST_CATEGORY, explicit_time_step_below_the_limit_runs_and_above_it_is_caught) {
  const auto plate = makePlate(12, 12, 0.25);
  const auto body = makeBody<TEST_EXECSPACE>(plate);
  const auto actions = perishell::solvers::makeFreeActions<TEST_MEMSPACE>(body.numNodes());
  const double critical = Solver<TEST_EXECSPACE>(TEST_EXECSPACE{}, body, actions, optionsFor(plate)).criticalTimeStep();
  // Hand estimate from the axial bonds alone: dt >= sqrt(2 m / sum k) is the classical
  // PD bound; the full microbeam tangent is stiffer, so the estimate must be smaller.
  EXPECT_GT(critical, 0.0);
  {
    Solver<TEST_EXECSPACE> stable(TEST_EXECSPACE{}, body, actions, optionsFor(plate, 0.9 * critical));
    setVelocities(stable, plate, vibrationMode);
    for (int s = 0; s < 3000; ++s) EXPECT_NO_THROW(stable.step()) << "step " << s;
    EXPECT_LT(std::abs(stable.lastEnergyReport().balanceError()), 1e-3);
  }
  Solver<TEST_EXECSPACE> unstable(TEST_EXECSPACE{}, body, actions, optionsFor(plate, 1.5 * critical));
  setVelocities(unstable, plate, vibrationMode);
  try {
    for (int s = 0; s < 3000; ++s) unstable.step();
    FAIL() << "dt = 1.5 dt_crit ran 3000 steps undetected";
  } catch (const perishell::solvers::ExplicitInstability& error) {
    const std::string message = error.what();
    std::printf("caught at step %lld: %s\n", unstable.stepIndex(), message.c_str());
    EXPECT_NE(message.find("unstable at step"), std::string::npos);
    EXPECT_NE(message.find("ratio 1.5"), std::string::npos);
    EXPECT_LE(unstable.stepIndex(), 300);
  }
}

TEST(TEST_CATEGORY, explicit_host_and_device_runs_agree_and_kernels_agree) {
  const auto plate = makePlate(12, 8, 0.3);
  using Gather = perishell::deck::ForceKernel;
  const auto device = runVibration<TEST_EXECSPACE>(plate, Gather::NodeGather, 400);
  const auto host = runVibration<Kokkos::DefaultHostExecutionSpace>(plate, Gather::NodeGather, 400);
  const auto scatter = runVibration<TEST_EXECSPACE>(plate, Gather::BondScatter, 400);
  double scale = 0.0, hostDifference = 0.0, kernelDifference = 0.0;
  for (std::size_t node = 0; node < device.extent(0); ++node)
    for (int d = 0; d < 3; ++d) {
      scale = std::max(scale, std::abs(device(node, d)));
      hostDifference = std::max(hostDifference, std::abs(device(node, d) - host(node, d)));
      kernelDifference = std::max(kernelDifference, std::abs(device(node, d) - scatter(node, d)));
    }
  std::printf("after 400 steps: |u|max %.4e m, host vs %s %.3e, gather vs scatter %.3e (relative)\n", scale,
              TEST_EXECSPACE::name(), hostDifference / scale, kernelDifference / scale);
  ASSERT_GT(scale, 0.0);
  EXPECT_LT(hostDifference / scale, 1e-10);
  EXPECT_LT(kernelDifference / scale, 1e-10);
}

// The solver zeroes its nodal forces every step with fillContiguous (core/types.hpp): every
// entry of a rank-2 view, and a strided view is refused rather than half filled.
TEST(TEST_CATEGORY, explicit_force_reset_fills_every_entry_and_refuses_strided_views) {
  perishell::pd::NodalVectorView<TEST_MEMSPACE> forces("forces", 1001);
  Kokkos::deep_copy(forces, 7.0);
  perishell::fillContiguous(TEST_EXECSPACE{}, forces, 0.0);
  const auto host = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, forces);
  double largest = 0.0;
  for (std::size_t node = 0; node < host.extent(0); ++node)
    for (int d = 0; d < 6; ++d) largest = std::max(largest, std::abs(host(node, d)));
  EXPECT_EQ(largest, 0.0);
  EXPECT_THROW(perishell::fillContiguous(TEST_EXECSPACE{}, Kokkos::subview(forces, Kokkos::ALL, 2), 1.0),
               std::logic_error);
}
