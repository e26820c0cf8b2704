#pragma once
// What a PD body is made of, on one memory space: its nodes (reference geometry, volumes),
// its bonds, the microbeam micromoduli and the fracture threshold; and the state that
// changes every step (displacements, finite rotations, intact-bond flags).
#include <perishell/core/types.hpp>
#include <perishell/pd/bond_list.hpp>
#include <perishell/pd/microbeam.hpp>

#include <cstdint>
#include <limits>
#include <string>

namespace perishell::pd {

template <class MemorySpaceT>
using RotationView = Kokkos::View<double* [4], Kokkos::LayoutRight, MemorySpaceT>;  // unit quaternions (w, x, y, z)
template <class MemorySpaceT>
using NodalVectorView = Kokkos::View<double* [6], Kokkos::LayoutRight, MemorySpaceT>;  // ux uy uz rx ry rz (model.md §1)
template <class MemorySpaceT>
using BondFlagView = Kokkos::View<std::uint8_t*, MemorySpaceT>;  // one per half bond

template <class MemorySpaceT>
struct PdBody {
  CoordinateView<MemorySpaceT> referencePositions;  // [m]
  CoordinateView<MemorySpaceT> referenceNormals;    // unit
  VectorView<MemorySpaceT> volumes;                 // V_i = A_i t [m^3]
  BondList<MemorySpaceT> bonds;
  Micromoduli micromoduli;
  // Per half bond, the factors its micromoduli are multiplied by (pd/make_body.hpp,
  // computeStiffnessScales): column 0 scales the moduli whose energy under a homogeneous
  // field weights a bond by xi (c_ax, c_by, c_tor), column 1 the one weighting it by 1/xi
  // (c_bz). Each is the mean of the two ends' quadrature factors, so forces stay equal and
  // opposite. The PD-CCM coupling multiplies both columns by the morphing factor
  // (alpha_i + alpha_j)/2 of model.md §4. The breaking threshold follows column 0
  // (pd/bond_forces.hpp, criticalMicropotential).
  Kokkos::View<double* [2], Kokkos::LayoutRight, MemorySpaceT> stiffnessScale;
  // w_c / xi of model.md §3; infinite when bonds never break.
  double criticalMicropotentialPerLength = std::numeric_limits<double>::infinity();

  LocalIndex numNodes() const { return static_cast<LocalIndex>(referencePositions.extent(0)); }
};

template <class MemorySpaceT>
struct PdKinematics {
  CoordinateView<MemorySpaceT> displacements;  // [m]
  RotationView<MemorySpaceT> rotations;        // reference to current
  // Derived from the two above by the bond force kernel at the start of every evaluation
  // (pd/bond_forces.hpp, updateNodeFrames), so that bonds read each end's current position
  // and rotation matrix instead of rebuilding them per bond: columns 0-2 the current
  // position [m], 3-11 the rotation matrix, row-major.
  Kokkos::View<double* [12], Kokkos::LayoutRight, MemorySpaceT> nodeFrames;

  explicit PdKinematics(LocalIndex numNodes)
      : displacements("pd displacements", numNodes), rotations("pd rotations", numNodes),
        nodeFrames(Kokkos::view_alloc(Kokkos::WithoutInitializing, "pd node frames"), numNodes) {
    Kokkos::deep_copy(Kokkos::subview(rotations, Kokkos::ALL, 0), 1.0);
  }
};

// Intact flags, all 1 for a fresh body.
template <class MemorySpaceT>
BondFlagView<MemorySpaceT> makeIntactFlags(const BondList<MemorySpaceT>& bonds, const std::string& label) {
  BondFlagView<MemorySpaceT> intact(label, bonds.numBonds());
  Kokkos::deep_copy(intact, std::uint8_t(1));
  return intact;
}

}  // namespace perishell::pd
