#pragma once
// Builds a PD body on the device from a host shell mesh: node volumes and normals by element
// mapping over the whole mesh, the chosen PD nodes' geometry gathered from them, bonds by
// the device neighbour search (pre-cracks cut), micromoduli and fracture threshold from the
// material (model.md §1-3).
#include <perishell/mesh/node_geometry.hpp>
#include <perishell/pd/neighbor_search.hpp>
#include <perishell/pd/pd_body.hpp>

#include <optional>
#include <vector>

namespace perishell::pd {

struct PdMaterial {
  double youngModulus = 0.0;             // E [Pa]
  double poissonRatio = 0.0;             // nu, in (-1, 1/3] (model.md §2)
  double thickness = 0.0;                // t [m]
  std::optional<double> fractureEnergy;  // G_c [J/m^2]; none: bonds never break
};

// The discrete horizon sums of the energy differ from the continuum integrals that the
// micromoduli were calibrated with (model.md §2): with delta = 3 dx and the partial-volume
// factor, sum_j xi V_j beta falls 13 % short of t * 2 pi delta^3 / 3. Under a homogeneous
// field a bond's energy weights it by xi (stretch, out-of-plane bending, torsion) or by
// 1/xi (in-plane bending), so each node gets the ratio continuum / discrete for both
// moments, t 2 pi delta^3/3 and t 2 pi delta over the sums of xi V_j beta and V_j beta / xi.
// Interior isotropic states then match exactly; nodes near free edges and pre-cracks get
// the same boost (the classical surface correction); pre-crack bonds count as missing.
template <class ExecutionSpaceT, class MemorySpaceT>
void computeQuadratureCorrections(const ExecutionSpaceT& space, PdBody<MemorySpaceT>& body, double horizon,
                                  double thickness) {
  const double pi = 3.14159265358979323846;
  const double lengthWeightedIntegral = thickness * 2.0 * pi * horizon * horizon * horizon / 3.0;
  const double inverseLengthWeightedIntegral = thickness * 2.0 * pi * horizon;
  body.correctionLengthWeighted = VectorView<MemorySpaceT>("pd correction xi", body.numNodes());
  body.correctionInverseLengthWeighted = VectorView<MemorySpaceT>("pd correction 1/xi", body.numNodes());
  const auto bonds = body.bonds;
  const auto volumes = body.volumes;
  const auto lengthWeighted = body.correctionLengthWeighted, inverseLengthWeighted = body.correctionInverseLengthWeighted;
  Kokkos::parallel_for(
      "perishell::pd::computeQuadratureCorrections", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, body.numNodes()),
      KOKKOS_LAMBDA(const LocalIndex node) {
        double lengthSum = 0.0, inverseLengthSum = 0.0;
        for (RowOffset entry = bonds.offsets(node); entry < bonds.offsets(node + 1); ++entry) {
          const RowOffset b = bonds.fullToHalf(entry);
          const double weighted = volumes(bonds.neighbours(entry)) * bonds.volumeFactor(b);
          lengthSum += weighted * bonds.referenceLength(b);
          inverseLengthSum += weighted / bonds.referenceLength(b);
        }
        lengthWeighted(node) = lengthSum > 0.0 ? lengthWeightedIntegral / lengthSum : 1.0;
        inverseLengthWeighted(node) = inverseLengthSum > 0.0 ? inverseLengthWeightedIntegral / inverseLengthSum : 1.0;
      });
}

// The chosen nodes' reference positions on the device and the bonds among them (device
// neighbour search, pre-cracks cut). pdNodes: mesh node indices, ascending; node k of the
// result is mesh node pdNodes(k).
template <class MemorySpaceT>
struct PdNodeBonds {
  CoordinateView<MemorySpaceT> positions;
  BondList<MemorySpaceT> bonds;
};

template <class ExecutionSpaceT>
PdNodeBonds<typename ExecutionSpaceT::memory_space> buildBondsAmong(
    const ExecutionSpaceT& space, const mesh::HostQuadMesh& hostMesh,
    const Kokkos::View<const LocalIndex*, Kokkos::HostSpace>& pdNodes, double horizon, double gridSpacing,
    const std::vector<mesh::CrackSegment>& preCracks) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  using MemorySpaceT = typename ExecutionSpaceT::memory_space;
  const LocalIndex numPdNodes = static_cast<LocalIndex>(pdNodes.extent(0));
  CoordinateView<Kokkos::HostSpace> hostPositions("pd node positions", numPdNodes);
  for (LocalIndex k = 0; k < numPdNodes; ++k)
    for (int d = 0; d < 3; ++d) hostPositions(k, d) = hostMesh.coordinates(pdNodes(k), d);
  Kokkos::View<mesh::CrackSegment*, Kokkos::HostSpace> hostCracks("pre-cracks", preCracks.size());
  for (std::size_t c = 0; c < preCracks.size(); ++c) hostCracks(c) = preCracks[c];
  PdNodeBonds<MemorySpaceT> result;
  result.positions = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, hostPositions);
  const auto cracks = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, hostCracks);
  result.bonds = buildBondList(space, result.positions, horizon, gridSpacing, cracks);
  return result;
}

// The PD body of the nodes pdNodes (as buildBondsAmong). Throws std::invalid_argument on
// parameters the model rejects.
template <class ExecutionSpaceT>
PdBody<typename ExecutionSpaceT::memory_space> makePdBody(
    const ExecutionSpaceT& space, const mesh::HostQuadMesh& hostMesh,
    const Kokkos::View<const LocalIndex*, Kokkos::HostSpace>& pdNodes, const PdMaterial& material, double horizon,
    double gridSpacing, const std::vector<mesh::CrackSegment>& preCracks) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  using MemorySpaceT = typename ExecutionSpaceT::memory_space;
  PdBody<MemorySpaceT> body;
  body.micromoduli = microbeamMicromoduli(material.youngModulus, material.poissonRatio, material.thickness, horizon);
  if (material.fractureEnergy)
    body.criticalMicropotentialPerLength =
        criticalMicropotentialPerLength(*material.fractureEnergy, material.thickness, horizon);
  auto nodeBonds = buildBondsAmong(space, hostMesh, pdNodes, horizon, gridSpacing, preCracks);
  body.referencePositions = nodeBonds.positions;
  body.bonds = nodeBonds.bonds;

  // Volumes and normals need every quad around a node, so they are computed on the whole mesh.
  const auto meshOnDevice = mesh::mirrorTo<MemorySpaceT>(hostMesh);
  const auto allVolumes = mesh::computeNodeVolumes(space, meshOnDevice, material.thickness);
  const auto allNormals = mesh::computeNodeNormals(space, meshOnDevice);
  const auto nodes = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, pdNodes);
  const LocalIndex numPdNodes = static_cast<LocalIndex>(nodes.extent(0));
  body.referenceNormals = CoordinateView<MemorySpaceT>("pd reference normals", numPdNodes);
  body.volumes = VectorView<MemorySpaceT>("pd volumes", numPdNodes);
  const auto normals = body.referenceNormals;
  const auto volumes = body.volumes;
  Kokkos::parallel_for(
      "perishell::pd::makePdBody::gather", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, numPdNodes),
      KOKKOS_LAMBDA(const LocalIndex k) {
        for (int d = 0; d < 3; ++d) normals(k, d) = allNormals(nodes(k), d);
        volumes(k) = allVolumes(nodes(k));
      });
  computeQuadratureCorrections(space, body, horizon, material.thickness);
  return body;
}

// Every node of the mesh, for 100 % PD models.
inline Kokkos::View<LocalIndex*, Kokkos::HostSpace> allNodes(LocalIndex numNodes) {
  Kokkos::View<LocalIndex*, Kokkos::HostSpace> nodes("all nodes", numNodes);
  for (LocalIndex k = 0; k < numNodes; ++k) nodes(k) = k;
  return nodes;
}

}  // namespace perishell::pd
