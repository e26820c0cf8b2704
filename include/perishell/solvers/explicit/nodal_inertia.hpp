#pragma once
// Lumped nodal inertia for explicit dynamics (model.md §6): mass m_i = rho V_i and an
// isotropic rotary inertia I_i. The physical rotary inertia of a thin shell, m t^2/12, makes
// the drilling and bending rotations far stiffer than the translations and would set a
// time step orders of magnitude smaller; like explicit shell codes we scale it so that a
// node's rotational frequency sqrt(k_r/I) does not exceed its translational one
// sqrt(k_t/m), with m t^2/12 as the floor. k_t and k_r are the node's diagonal bond
// stiffnesses: of its bonds (microbeam as an Euler-Bernoulli beam with EI = V_i V_j beta c,
// model.md §2) plus, in a mixed model, the diagonal of its shell elements' K_l.
// This changes only the rotary inertia, a higher-order term for thin-shell motion.
#include <perishell/pd/bond_forces.hpp>
#include <perishell/shell/shell_body.hpp>

#include <optional>

namespace perishell::solvers {

template <class MemorySpaceT>
struct NodalInertia {
  VectorView<MemorySpaceT> mass;           // [kg]
  VectorView<MemorySpaceT> rotaryInertia;  // [kg m^2]
};

template <class ExecutionSpaceT, class MemorySpaceT>
NodalInertia<MemorySpaceT> computeNodalInertia(const ExecutionSpaceT& space, const pd::PdBody<MemorySpaceT>& body,
                                               const std::optional<shell::ShellBody<MemorySpaceT>>& shellBody,
                                               double density, double thickness) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  const LocalIndex numNodes = body.numNodes();
  NodalInertia<MemorySpaceT> inertia{VectorView<MemorySpaceT>("nodal mass", numNodes),
                                     VectorView<MemorySpaceT>("rotary inertia", numNodes)};
  VectorView<MemorySpaceT> translational("nodal translational stiffness", numNodes);
  VectorView<MemorySpaceT> rotational("nodal rotational stiffness", numNodes);
  Kokkos::parallel_for(
      "perishell::solvers::bondNodalStiffness", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, numNodes),
      KOKKOS_LAMBDA(const LocalIndex node) {
        double moving = 0.0, turning = 0.0;
        for (RowOffset entry = body.bonds.offsets(node); entry < body.bonds.offsets(node + 1); ++entry) {
          const RowOffset b = body.bonds.fullToHalf(entry);
          const double xi = body.bonds.referenceLength(b);
          const LocalIndex neighbour = body.bonds.neighbours(entry);
          const double weight = pd::bondVolumeWeight(body, node, neighbour, b);
          const pd::Micromoduli c = pd::bondMicromoduli(body, b);
          const double bending = c.outOfPlaneBending + c.inPlaneBending;
          moving += weight * (c.axial / xi + 12.0 * bending / (xi * xi * xi));
          turning += weight * (4.0 * bending + c.torsion) / xi;
        }
        translational(node) = moving;
        rotational(node) = turning;
      });
  if (shellBody) shell::addShellNodalStiffness(space, *shellBody, translational, rotational);
  const double physicalRadiusSquared = thickness * thickness / 12.0;
  Kokkos::parallel_for(
      "perishell::solvers::computeNodalInertia", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, numNodes),
      KOKKOS_LAMBDA(const LocalIndex node) {
        const double mass = density * body.volumes(node);
        const double scaledRadiusSquared = translational(node) > 0.0 ? rotational(node) / translational(node) : 0.0;
        inertia.mass(node) = mass;
        inertia.rotaryInertia(node) =
            mass * (scaledRadiusSquared > physicalRadiusSquared ? scaledRadiusSquared : physicalRadiusSquared);
      });
  return inertia;
}

}  // namespace perishell::solvers
