#pragma once
// Lumped nodal inertia for explicit dynamics (model.md §6): mass m_i = rho V_i and an
// isotropic rotary inertia I_i. The physical rotary inertia of a thin shell, m t^2/12, makes
// the drilling and bending rotations far stiffer than the translations and would set a
// time step orders of magnitude smaller; like explicit shell codes we scale it so that a
// node's rotational frequency sqrt(k_r/I) does not exceed its translational one
// sqrt(k_t/m), with m t^2/12 as the floor. k_t and k_r are the node's diagonal bond
// stiffnesses (microbeam as an Euler-Bernoulli beam with EI = V_i V_j beta c, model.md §2).
// This changes only the rotary inertia, a higher-order term for thin-shell motion.
#include <perishell/pd/bond_forces.hpp>

namespace perishell::solvers {

template <class MemorySpaceT>
struct NodalInertia {
  VectorView<MemorySpaceT> mass;           // [kg]
  VectorView<MemorySpaceT> rotaryInertia;  // [kg m^2]
};

template <class ExecutionSpaceT, class MemorySpaceT>
NodalInertia<MemorySpaceT> computeNodalInertia(const ExecutionSpaceT& space, const pd::PdBody<MemorySpaceT>& body,
                                               double density, double thickness) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  NodalInertia<MemorySpaceT> inertia{VectorView<MemorySpaceT>("pd nodal mass", body.numNodes()),
                                     VectorView<MemorySpaceT>("pd rotary inertia", body.numNodes())};
  const double physicalRadiusSquared = thickness * thickness / 12.0;
  Kokkos::parallel_for(
      "perishell::solvers::computeNodalInertia", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, body.numNodes()),
      KOKKOS_LAMBDA(const LocalIndex node) {
        double translational = 0.0, rotational = 0.0;
        for (RowOffset entry = body.bonds.offsets(node); entry < body.bonds.offsets(node + 1); ++entry) {
          const RowOffset b = body.bonds.fullToHalf(entry);
          const double xi = body.bonds.referenceLength(b);
          const LocalIndex neighbour = body.bonds.neighbours(entry);
          const double weight = pd::bondVolumeWeight(body, node, neighbour, b);
          const pd::Micromoduli c = pd::bondMicromoduli(body, b);
          const double bending = c.outOfPlaneBending + c.inPlaneBending;
          translational += weight * (c.axial / xi + 12.0 * bending / (xi * xi * xi));
          rotational += weight * (4.0 * bending + c.torsion) / xi;
        }
        const double mass = density * body.volumes(node);
        const double scaledRadiusSquared = translational > 0.0 ? rotational / translational : 0.0;
        inertia.mass(node) = mass;
        inertia.rotaryInertia(node) =
            mass * (scaledRadiusSquared > physicalRadiusSquared ? scaledRadiusSquared : physicalRadiusSquared);
      });
  return inertia;
}

}  // namespace perishell::solvers
