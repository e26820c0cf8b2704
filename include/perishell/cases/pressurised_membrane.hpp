#pragma once
// The stack-verification case: a square membrane of side a under uniform tension T and
// pressure p with fixed edges. It runs the whole device pipeline the shell solvers build
// on — mesh on the device, node areas and stiffness by atomic element assembly into a
// Kokkos Kernels CRS matrix, symmetric constraint elimination, Belos PCG through the
// project's Kokkos adapter — and has an exact answer (shell::squareMembraneCentreDeflection).
#include <perishell/assembly/dirichlet.hpp>
#include <perishell/assembly/quad_crs_pattern.hpp>
#include <perishell/mesh/node_areas.hpp>
#include <perishell/shell/prestressed_membrane.hpp>
#include <perishell/solvers/belos/cg_solve.hpp>

#include <cmath>
#include <stdexcept>
#include <string>

namespace perishell::cases {

struct PressurisedMembraneOptions {
  double side = 1.0;         // a [m]
  double tension = 1.0e3;    // T [N/m]
  double pressure = 1.0e2;   // p [Pa]
  int cellsPerSide = 64;     // even, so that a node sits at the centre
  belos::CgOptions solver{};
};

struct PressurisedMembraneResult {
  LocalIndex numNodes = 0;
  LocalIndex numConstrained = 0;
  double meshArea = 0.0;                  // sum of node areas [m^2]
  double centreDeflection = 0.0;          // [m]
  double analyticCentreDeflection = 0.0;  // [m]
  double relativeError = 0.0;
  belos::CgResult solve{};
};

template <class ExecutionSpaceT>
PressurisedMembraneResult runPressurisedMembrane(const ExecutionSpaceT& space,
                                                 const PressurisedMembraneOptions& options) {
  using MemorySpaceT = typename ExecutionSpaceT::memory_space;
  if (options.cellsPerSide < 2 || options.cellsPerSide % 2 != 0)
    throw std::invalid_argument("pressurised membrane: cells per side must be even and >= 2, got " +
                                std::to_string(options.cellsPerSide));
  if (!(options.tension > 0.0 && std::isfinite(options.tension)))
    throw std::invalid_argument("pressurised membrane: tension must be positive and finite");
  if (!std::isfinite(options.pressure))
    throw std::invalid_argument("pressurised membrane: pressure must be finite");

  const int n = options.cellsPerSide;
  const auto hostMesh = mesh::makeRectangularPlate(options.side, options.side, n, n);
  const auto meshOnDevice = mesh::mirrorTo<MemorySpaceT>(hostMesh);
  const auto pattern = assembly::mirrorTo<MemorySpaceT>(assembly::buildQuadCrsPattern(hostMesh));

  PressurisedMembraneResult result;
  result.numNodes = hostMesh.numNodes();

  // Consistent nodal load f_i = p * integral of N_i dA = p * A_i.
  const auto nodeAreas = mesh::computeNodeAreas(space, meshOnDevice);
  VectorView<MemorySpaceT> rhs("membrane load", result.numNodes);
  const double pressure = options.pressure;
  Kokkos::parallel_reduce(
      "perishell::membraneLoad", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, result.numNodes),
      KOKKOS_LAMBDA(const int node, double& area) {
        rhs(node) = pressure * nodeAreas(node);
        area += nodeAreas(node);
      },
      result.meshArea);

  VectorView<MemorySpaceT> values("membrane stiffness", pattern.numEntries());
  shell::assembleMembraneStiffness(space, meshOnDevice, pattern, options.tension, values);

  const auto boundary = mesh::plateBoundaryNodes(n, n);
  result.numConstrained = static_cast<LocalIndex>(boundary.extent(0));
  Kokkos::View<bool*, Kokkos::HostSpace> hostConstrained("constrained", result.numNodes);
  for (LocalIndex i = 0; i < result.numConstrained; ++i) hostConstrained(boundary(i)) = true;
  Kokkos::View<bool*, MemorySpaceT> isConstrained("constrained", result.numNodes);
  Kokkos::deep_copy(isConstrained, hostConstrained);
  assembly::eliminateHomogeneousDirichlet(space, pattern.rowMap, pattern.columns, values, rhs, isConstrained);

  const belos::CrsMatrix<ExecutionSpaceT> stiffness("membrane stiffness", result.numNodes, result.numNodes,
                                                    pattern.numEntries(), values, pattern.rowMap,
                                                    pattern.columns);
  VectorView<MemorySpaceT> deflection("membrane deflection", result.numNodes);
  result.solve = belos::solveCg(stiffness, rhs, deflection, options.solver);

  const LocalIndex centre = (n / 2) * (n + 1) + n / 2;
  double centreDeflection = 0.0;
  Kokkos::deep_copy(centreDeflection, Kokkos::subview(deflection, centre));
  result.centreDeflection = centreDeflection;
  result.analyticCentreDeflection =
      shell::squareMembraneCentreDeflection(options.pressure, options.side, options.tension);
  result.relativeError = std::abs(result.centreDeflection - result.analyticCentreDeflection) /
                         std::abs(result.analyticCentreDeflection);
  return result;
}

// Compiled once per execution space (src/cases/pressurised_membrane_*.cpp): Belos is
// instantiated there, not in every file that runs the case.
#ifdef KOKKOS_ENABLE_OPENMP
extern template PressurisedMembraneResult runPressurisedMembrane(const Kokkos::OpenMP&,
                                                                 const PressurisedMembraneOptions&);
#endif
#ifdef KOKKOS_ENABLE_CUDA
extern template PressurisedMembraneResult runPressurisedMembrane(const Kokkos::Cuda&, const PressurisedMembraneOptions&);
#endif

}  // namespace perishell::cases
