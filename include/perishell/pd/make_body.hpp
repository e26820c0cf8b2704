#pragma once
// Builds a PD body on the device from a host shell mesh: node volumes and normals by element
// mapping over the whole mesh, the chosen PD nodes' geometry gathered from them, bonds by
// the device neighbour search (pre-cracks cut), micromoduli and fracture threshold from the
// material (model.md §1-3).
#include <perishell/mesh/free_edges.hpp>
#include <perishell/mesh/node_geometry.hpp>
#include <perishell/mesh/support_layer.hpp>
#include <perishell/pd/neighbor_search.hpp>
#include <perishell/core/rotation.hpp>
#include <perishell/pd/pd_body.hpp>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace perishell::pd {

struct PdMaterial {
  double youngModulus = 0.0;             // E [Pa]
  double poissonRatio = 0.0;             // nu, in (-1, 1/3] (model.md §2)
  double thickness = 0.0;                // t [m]
  std::optional<double> fractureEnergy;  // G_c [J/m^2]; none: bonds never break
};

namespace detail {
// An orthonormal basis (t1, t2) of the plane normal to the unit vector n: t1 from the
// coordinate axis least aligned with n. Only the node's own bonds are measured in it.
KOKKOS_INLINE_FUNCTION void tangentBasis(const double n[3], double t1[3], double t2[3]) {
  int axis = 0;
  for (int k = 1; k < 3; ++k)
    if (Kokkos::Experimental::fabs(n[k]) < Kokkos::Experimental::fabs(n[axis])) axis = k;
  for (int k = 0; k < 3; ++k) t1[k] = (k == axis ? 1.0 : 0.0) - n[axis] * n[k];
  rotation::normalise(t1);
  rotation::cross(n, t1, t2);
}

// The angular harmonics cos 2theta, sin 2theta, cos 4theta, sin 4theta of the direction d
// projected on the tangent plane (t1, t2); zero for a direction along the normal. No
// trigonometry: the fourth from the second by the double-angle formulas.
constexpr int numHarmonics = 4;
KOKKOS_INLINE_FUNCTION void angularHarmonics(const double d[3], const double t1[3], const double t2[3],
                                             double harmonics[numHarmonics]) {
  const double u = rotation::dot(d, t1), v = rotation::dot(d, t2);
  const double squared = u * u + v * v;
  if (!(squared > 0.0)) {
    for (int k = 0; k < numHarmonics; ++k) harmonics[k] = 0.0;
    return;
  }
  const double cosine2 = (u * u - v * v) / squared, sine2 = 2.0 * u * v / squared;
  harmonics[0] = cosine2;
  harmonics[1] = sine2;
  harmonics[2] = cosine2 * cosine2 - sine2 * sine2;
  harmonics[3] = 2.0 * sine2 * cosine2;
}

// The quadrature factor one end gives a bond of direction d, g (1 + sum_k a_k h_k(theta)),
// from the node's factors g, g a_1, ..., g a_4.
KOKKOS_INLINE_FUNCTION double endFactor(const double d[3], const double t1[3], const double t2[3],
                                        const double factors[1 + numHarmonics]) {
  double harmonics[numHarmonics];
  angularHarmonics(d, t1, t2, harmonics);
  double factor = factors[0];
  for (int k = 0; k < numHarmonics; ++k) factor += factors[1 + k] * harmonics[k];
  return factor;
}

// Solves the symmetric positive semi-definite n x n system A x = b in place by Cholesky
// with a diagonal shift `regularisation`: directions A cannot see (a node whose bonds miss
// some harmonic altogether) get no weight instead of an unbounded one.
template <int n>
KOKKOS_INLINE_FUNCTION void solveShiftedCholesky(double A[n][n], double b[n], double regularisation) {
  for (int k = 0; k < n; ++k) A[k][k] += regularisation;
  for (int c = 0; c < n; ++c) {
    for (int k = 0; k < c; ++k) A[c][c] -= A[c][k] * A[c][k];
    A[c][c] = Kokkos::Experimental::sqrt(A[c][c]);
    for (int r = c + 1; r < n; ++r) {
      for (int k = 0; k < c; ++k) A[r][c] -= A[r][k] * A[c][k];
      A[r][c] /= A[c][c];
    }
  }
  for (int r = 0; r < n; ++r) {
    for (int k = 0; k < r; ++k) b[r] -= A[r][k] * b[k];
    b[r] /= A[r][r];
  }
  for (int r = n - 1; r >= 0; --r) {
    for (int k = r + 1; k < n; ++k) b[r] -= A[k][r] * b[k];
    b[r] /= A[r][r];
  }
}
}  // namespace detail

// The per-bond stiffness scales of model.md §2's micromoduli (PdBody::stiffnessScale).
// Under a homogeneous membrane strain eps, a bond of unit direction n stores
// 1/2 c_ax xi (n.eps.n)^2 + 6 (c_bz/xi) (t.eps.n)^2 (t the in-plane normal to n; both
// ends turn by the chord's spin), and under a homogeneous curvature kappa
// 1/2 c_by xi (n.kappa.n)^2 + 1/2 c_tor xi (t.kappa.n)^2. In the angle theta of n these are
// c_ax, c_by, c_tor sums weighted by w = xi V_j beta and a c_bz sum weighted by
// w = V_j beta / xi, of 1, cos 2theta, sin 2theta, cos 4theta, sin 4theta. The micromoduli
// were calibrated on continuum integrals, where only the constant moment is non-zero. The
// discrete sums with delta = 3 dx fall 13 % short in the constant moment; a square lattice
// adds a fourth harmonic (bonds along the axes against the diagonals), 7 % in shear at
// nu = 0; and a node within delta of a free edge or pre-crack misses the bonds that point
// out of the body, a second harmonic: boosting its other bonds evenly stiffened a strip
// 8 spacings wide by 6 % in bending along it.
// So each node, for each of the two weightings, weights its bonds by
//   g (1 + a_c cos 2theta + a_s sin 2theta + b_c cos 4theta + b_s sin 4theta),
// theta measured in the node's tangent plane (any flat or curved mesh), the four harmonic
// weights chosen to cancel the weighted harmonics (a 4x4 solve) and g to make the weighted
// constant moment equal its continuum value (t 2 pi delta^3 / 3 for xi, t 2 pi delta for
// 1/xi). Every node's bonds then store the plate energy of any homogeneous strain or
// curvature exactly, edge nodes included; interior nodes of a symmetric lattice need no
// second harmonic. |a| + |b| is capped at 1/2, which keeps every weight at least half of g.
// A bond's scale is the mean of its two ends' factors: the total energy is still the sum
// of the nodes' exact ones, since each bond's energy is shared by both ends.
// nodesAtCcmInterface (per body node; empty: none) marks nodes whose horizon reaches past
// the body into CCM elements (the outer edge of a coupling transition, model.md §4). Their
// missing neighbours are not free surface and the morphing weights them out anyway
// (coupling/morphing.hpp), so they fit no second harmonic: g and the fourth harmonic only.
// quadratureBonds (optional: body.bonds) are the bonds the node weights are fitted to: the
// list before pre-cracks cut it. A pre-crack is a crack, not a free edge: the nodes along it
// keep the weights of the uncut lattice, as nodes along a crack that opens in the run do.
// Fitting the cut bonds made the faces above and below a pre-crack (cut from one side only,
// docs/model-setup.md) differ, and the glass plate 4.1.2 branched lopsidedly.
// images: a mirrored support-layer node (assembly/mirror_images.hpp) stands for its master's
// mirror image, so its end of a bond takes the master's factors for the reflected direction:
// a bond to it and its mirror image then have one scale, that of the whole structure's bond.
// Its own factors, fitted to the layer's outer rim, made a clamped quarter plate with two
// symmetry planes 10 % too stiff.
template <class MemorySpaceT>
struct ImageQuadrature {
  Kokkos::View<LocalIndex*, MemorySpaceT> master;  // per body node: its master's index, or -1
  Kokkos::View<double* [9], Kokkos::LayoutRight, MemorySpaceT> reflection;  // master side to image side
};

template <class ExecutionSpaceT, class MemorySpaceT>
void computeStiffnessScales(const ExecutionSpaceT& space, PdBody<MemorySpaceT>& body, double horizon,
                            double thickness,
                            const Kokkos::View<const std::uint8_t*, MemorySpaceT>& nodesAtCcmInterface = {},
                            const std::optional<BondList<MemorySpaceT>>& quadratureBonds = std::nullopt,
                            const ImageQuadrature<MemorySpaceT>& images = {}) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  using detail::numHarmonics;
  const double pi = 3.14159265358979323846;
  const double continuumMoment[2] = {thickness * 2.0 * pi * horizon * horizon * horizon / 3.0,
                                     thickness * 2.0 * pi * horizon};
  constexpr double largestHarmonicWeight = 0.5;
  // Per node and weighting: g, g a_c, g a_s, g b_c, g b_s.
  Kokkos::View<double* [2][1 + numHarmonics], Kokkos::LayoutRight, MemorySpaceT> nodeFactors(
      "pd node quadrature factors", body.numNodes());
  const auto bonds = quadratureBonds ? *quadratureBonds : body.bonds;
  const auto volumes = body.volumes;
  const auto positions = body.referencePositions;
  const auto normals = body.referenceNormals;
  const bool anyAtInterface = nodesAtCcmInterface.extent(0) > 0;
  if (anyAtInterface && nodesAtCcmInterface.extent(0) != static_cast<std::size_t>(body.numNodes()))
    throw std::invalid_argument("computeStiffnessScales: the CCM interface mask has " +
                                std::to_string(nodesAtCcmInterface.extent(0)) + " entries for " +
                                std::to_string(body.numNodes()) + " nodes");
  Kokkos::parallel_for(
      "perishell::pd::computeStiffnessScales::nodes", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, body.numNodes()),
      KOKKOS_LAMBDA(const LocalIndex node) {
        const double n[3] = {normals(node, 0), normals(node, 1), normals(node, 2)};
        double t1[3], t2[3];
        detail::tangentBasis(n, t1, t2);
        // Per weighting: sum w, sum w h_k, sum w h_k h_l.
        double total[2] = {}, moments[2][numHarmonics] = {}, products[2][numHarmonics][numHarmonics] = {};
        for (RowOffset entry = bonds.offsets(node); entry < bonds.offsets(node + 1); ++entry) {
          const LocalIndex neighbour = bonds.neighbours(entry);
          const RowOffset b = bonds.fullToHalf(entry);
          const double d[3] = {positions(neighbour, 0) - positions(node, 0), positions(neighbour, 1) - positions(node, 1),
                               positions(neighbour, 2) - positions(node, 2)};
          double h[numHarmonics];
          detail::angularHarmonics(d, t1, t2, h);
          const double volume = volumes(neighbour) * bonds.volumeFactor(b), xi = bonds.referenceLength(b);
          const double w[2] = {volume * xi, volume / xi};
          for (int m = 0; m < 2; ++m) {
            total[m] += w[m];
            for (int k = 0; k < numHarmonics; ++k) {
              moments[m][k] += w[m] * h[k];
              for (int l = 0; l < numHarmonics; ++l) products[m][k][l] += w[m] * h[k] * h[l];
            }
          }
        }
        if (anyAtInterface && nodesAtCcmInterface(node))
          for (int m = 0; m < 2; ++m)
            for (int k = 0; k < 2; ++k) {  // the second harmonic's rows: a_k = 0
              moments[m][k] = 0.0;
              for (int l = 0; l < numHarmonics; ++l) products[m][k][l] = products[m][l][k] = 0.0;
              products[m][k][k] = total[m];
            }
        for (int m = 0; m < 2; ++m) {
          // sum w (1 + a.h) h_k = 0 for every k: products a = -moments.
          double a[numHarmonics];
          for (int k = 0; k < numHarmonics; ++k) a[k] = -moments[m][k];
          detail::solveShiftedCholesky<numHarmonics>(products[m], a, 1e-10 * total[m]);
          const double amplitude = Kokkos::Experimental::sqrt(a[0] * a[0] + a[1] * a[1]) +
                                   Kokkos::Experimental::sqrt(a[2] * a[2] + a[3] * a[3]);
          const double cap = amplitude > largestHarmonicWeight ? largestHarmonicWeight / amplitude : 1.0;
          double weighted = total[m];
          for (int k = 0; k < numHarmonics; ++k) {
            a[k] *= cap;
            weighted += a[k] * moments[m][k];
          }
          const double g = weighted > 0.0 ? continuumMoment[m] / weighted : 1.0;
          nodeFactors(node, m, 0) = g;
          for (int k = 0; k < numHarmonics; ++k) nodeFactors(node, m, 1 + k) = g * a[k];
        }
      });
  const auto bodyBonds = body.bonds;
  const bool hasImages = images.master.extent(0) > 0;
  body.stiffnessScale = decltype(body.stiffnessScale)("pd stiffness scale", bodyBonds.numBonds());
  const auto scale = body.stiffnessScale;
  Kokkos::parallel_for(
      "perishell::pd::computeStiffnessScales::bonds", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, bodyBonds.numBonds()),
      KOKKOS_LAMBDA(const RowOffset b) {
        const LocalIndex ends[2] = {bodyBonds.halfBonds(b, 0), bodyBonds.halfBonds(b, 1)};
        // The harmonics are even: they do not change when the direction reverses.
        const double d[3] = {positions(ends[1], 0) - positions(ends[0], 0), positions(ends[1], 1) - positions(ends[0], 1),
                             positions(ends[1], 2) - positions(ends[0], 2)};
        for (int m = 0; m < 2; ++m) {
          double sum = 0.0;
          for (const LocalIndex end : ends) {
            LocalIndex node = end;
            double direction[3] = {d[0], d[1], d[2]};
            if (hasImages && images.master(end) >= 0) {  // the reflected bond at the master
              node = images.master(end);
              for (int r = 0; r < 3; ++r)
                direction[r] = images.reflection(end, r) * d[0] + images.reflection(end, 3 + r) * d[1] +
                               images.reflection(end, 6 + r) * d[2];
            }
            const double n[3] = {normals(node, 0), normals(node, 1), normals(node, 2)};
            double t1[3], t2[3];
            detail::tangentBasis(n, t1, t2);
            double factors[1 + numHarmonics];
            for (int k = 0; k <= numHarmonics; ++k) factors[k] = nodeFactors(node, m, k);
            sum += detail::endFactor(direction, t1, t2, factors);
          }
          scale(b, m) = 0.5 * sum;
        }
      });
}

// The chosen nodes' reference positions on the device and the bonds among them (device
// neighbour search, pre-cracks cut, none between two mesh nodes from firstHeldNode on).
// pdNodes: mesh node indices, ascending; node k of the result is mesh node pdNodes(k).
template <class MemorySpaceT>
struct PdNodeBonds {
  CoordinateView<MemorySpaceT> positions;
  BondList<MemorySpaceT> bonds;
  BoundaryFaces<MemorySpaceT> boundary;  // what the bonds may not cross
};

// The mesh's boundary faces within the horizon of the chosen nodes (none on most meshes:
// only slits and notches have material beyond a free edge), on the device.
template <class MemorySpaceT>
BoundaryFaces<MemorySpaceT> boundaryFacesFor(const mesh::HostQuadMesh& hostMesh,
                                             const Kokkos::View<const LocalIndex*, Kokkos::HostSpace>& pdNodes,
                                             const CoordinateView<Kokkos::HostSpace>& pdPositions, double horizon) {
  BoundaryFaces<MemorySpaceT> boundary;
  const auto faces = mesh::boundaryFaces(hostMesh, horizon);
  if (faces.empty()) return boundary;
  const LocalIndex numPdNodes = static_cast<LocalIndex>(pdNodes.extent(0));
  Kokkos::View<mesh::BoundaryFace*, Kokkos::HostSpace> hostFaces("boundary faces", faces.size());
  for (std::size_t f = 0; f < faces.size(); ++f) hostFaces(f) = faces[f];
  const auto allDirections = mesh::nodeMaterialDirections(hostMesh);
  CoordinateView<Kokkos::HostSpace> directions("pd node material directions", numPdNodes);
  for (LocalIndex k = 0; k < numPdNodes; ++k)
    for (int d = 0; d < 3; ++d) directions(k, d) = allDirections(pdNodes(k), d);
  // A filter only: a margin keeps bonds of length exactly delta in.
  const auto near = mesh::pointsNearFaces(pdPositions, faces, 1.01 * horizon);
  Kokkos::View<std::uint8_t*, Kokkos::HostSpace> hostNear("pd nodes near a boundary face", numPdNodes);
  for (LocalIndex k = 0; k < numPdNodes; ++k) hostNear(k) = near[k];
  boundary.faces = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, hostFaces);
  boundary.materialDirections = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, directions);
  boundary.nearFace = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, hostNear);
  return boundary;
}

template <class ExecutionSpaceT>
PdNodeBonds<typename ExecutionSpaceT::memory_space> buildBondsAmong(
    const ExecutionSpaceT& space, const mesh::HostQuadMesh& hostMesh,
    const Kokkos::View<const LocalIndex*, Kokkos::HostSpace>& pdNodes, double horizon, double gridSpacing,
    const std::vector<mesh::CrackSegment>& preCracks, LocalIndex firstHeldNode = std::numeric_limits<LocalIndex>::max()) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  using MemorySpaceT = typename ExecutionSpaceT::memory_space;
  const LocalIndex numPdNodes = static_cast<LocalIndex>(pdNodes.extent(0));
  // pdNodes ascends, so the held ones are its tail.
  const LocalIndex firstHeld = static_cast<LocalIndex>(
      std::lower_bound(pdNodes.data(), pdNodes.data() + numPdNodes, firstHeldNode) - pdNodes.data());
  CoordinateView<Kokkos::HostSpace> hostPositions("pd node positions", numPdNodes);
  for (LocalIndex k = 0; k < numPdNodes; ++k)
    for (int d = 0; d < 3; ++d) hostPositions(k, d) = hostMesh.coordinates(pdNodes(k), d);
  Kokkos::View<mesh::CrackSegment*, Kokkos::HostSpace> hostCracks("pre-cracks", preCracks.size());
  for (std::size_t c = 0; c < preCracks.size(); ++c) hostCracks(c) = preCracks[c];
  PdNodeBonds<MemorySpaceT> result;
  result.positions = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, hostPositions);
  const auto cracks = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, hostCracks);
  result.boundary = boundaryFacesFor<MemorySpaceT>(hostMesh, pdNodes, hostPositions, horizon);
  result.bonds = buildBondList(space, result.positions, horizon, gridSpacing, cracks,
                               firstHeld < numPdNodes ? firstHeld : std::numeric_limits<LocalIndex>::max(),
                               result.boundary);
  return result;
}

// The images among pdNodes, indexed as they are (computeStiffnessScales); empty views when
// there are none.
template <class MemorySpaceT>
ImageQuadrature<MemorySpaceT> imageQuadrature(const Kokkos::View<const LocalIndex*, Kokkos::HostSpace>& pdNodes,
                                              const std::vector<mesh::MirrorImage>& mirrorImages) {
  ImageQuadrature<MemorySpaceT> result;
  if (mirrorImages.empty()) return result;
  const LocalIndex numPdNodes = static_cast<LocalIndex>(pdNodes.extent(0));
  const auto bodyIndex = [&](LocalIndex meshNode) -> LocalIndex {
    const LocalIndex* at = std::lower_bound(pdNodes.data(), pdNodes.data() + numPdNodes, meshNode);
    return at != pdNodes.data() + numPdNodes && *at == meshNode ? static_cast<LocalIndex>(at - pdNodes.data()) : -1;
  };
  Kokkos::View<LocalIndex*, Kokkos::HostSpace> master("pd image masters", numPdNodes);
  Kokkos::View<double* [9], Kokkos::LayoutRight, Kokkos::HostSpace> reflection("pd image reflections", numPdNodes);
  Kokkos::deep_copy(master, LocalIndex(-1));
  for (const auto& image : mirrorImages) {
    const LocalIndex node = bodyIndex(image.node), source = bodyIndex(image.master);
    if (node < 0 || source < 0) continue;
    master(node) = source;
    for (int k = 0; k < 9; ++k) reflection(node, k) = image.reflection[k];
  }
  result.master = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, master);
  result.reflection = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, reflection);
  return result;
}

// The PD body of the nodes pdNodes (as buildBondsAmong). nodesAtCcmInterface: per entry of
// pdNodes, or empty (computeStiffnessScales). Throws std::invalid_argument on parameters the
// model rejects.
template <class ExecutionSpaceT>
PdBody<typename ExecutionSpaceT::memory_space> makePdBody(
    const ExecutionSpaceT& space, const mesh::HostQuadMesh& hostMesh,
    const Kokkos::View<const LocalIndex*, Kokkos::HostSpace>& pdNodes, const PdMaterial& material, double horizon,
    double gridSpacing, const std::vector<mesh::CrackSegment>& preCracks,
    const Kokkos::View<const std::uint8_t*, Kokkos::HostSpace>& nodesAtCcmInterface = {},
    LocalIndex firstHeldNode = std::numeric_limits<LocalIndex>::max(),
    const std::vector<mesh::MirrorImage>& mirrorImages = {}) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  using MemorySpaceT = typename ExecutionSpaceT::memory_space;
  PdBody<MemorySpaceT> body;
  body.micromoduli = microbeamMicromoduli(material.youngModulus, material.poissonRatio, material.thickness, horizon);
  if (material.fractureEnergy)
    body.criticalMicropotentialPerLength =
        criticalMicropotentialPerLength(*material.fractureEnergy, material.thickness, horizon);
  auto nodeBonds = buildBondsAmong(space, hostMesh, pdNodes, horizon, gridSpacing, preCracks, firstHeldNode);
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
  // The node weights see every neighbour, the held layer's among themselves too.
  std::optional<BondList<MemorySpaceT>> uncutBonds;
  const bool anyHeld = pdNodes.extent(0) > 0 && pdNodes(pdNodes.extent(0) - 1) >= firstHeldNode;
  if (!preCracks.empty() || anyHeld)
    uncutBonds = buildBondList(space, body.referencePositions, horizon, gridSpacing,
                               Kokkos::View<const mesh::CrackSegment*, MemorySpaceT>(),
                               std::numeric_limits<LocalIndex>::max(), nodeBonds.boundary);
  // An image is its master's mirror: the same volume (the layer's outer row would have half).
  const auto images = imageQuadrature<MemorySpaceT>(pdNodes, mirrorImages);
  if (images.master.extent(0) > 0)
    Kokkos::parallel_for(
        "perishell::pd::makePdBody::imageVolumes", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, numPdNodes),
        KOKKOS_LAMBDA(const LocalIndex k) {
          if (images.master(k) >= 0) volumes(k) = volumes(images.master(k));
        });
  computeStiffnessScales(space, body, horizon, material.thickness,
                         Kokkos::View<const std::uint8_t*, MemorySpaceT>(
                             Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, nodesAtCcmInterface)),
                         uncutBonds, images);
  return body;
}

// The same body indexed by mesh node: node k of the result is mesh node k, and the mesh
// nodes outside pdNodes (ascending) hold no bonds but keep their volume and normal. Solvers
// that keep one state per mesh node (mixed PD-CCM models, model.md §4) pass it to the bond
// kernels unchanged. Since pdNodes ascends, the neighbour entries keep their order: only
// node numbers and row offsets change, and the per-bond arrays are shared.
template <class ExecutionSpaceT>
PdBody<typename ExecutionSpaceT::memory_space> indexByMeshNodes(
    const ExecutionSpaceT& space, const PdBody<typename ExecutionSpaceT::memory_space>& body,
    const mesh::HostQuadMesh& hostMesh, const Kokkos::View<const LocalIndex*, Kokkos::HostSpace>& pdNodes,
    double thickness) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  using MemorySpaceT = typename ExecutionSpaceT::memory_space;
  const LocalIndex numMeshNodes = hostMesh.numNodes();
  const auto numPdNodes = static_cast<LocalIndex>(pdNodes.extent(0));
  if (body.numNodes() != numPdNodes)
    throw std::invalid_argument("indexByMeshNodes: the body has " + std::to_string(body.numNodes()) +
                                " nodes, pdNodes " + std::to_string(numPdNodes));
  PdBody<MemorySpaceT> meshBody = body;
  const auto meshOnDevice = mesh::mirrorTo<MemorySpaceT>(hostMesh);
  meshBody.referencePositions = meshOnDevice.coordinates;
  meshBody.referenceNormals = mesh::computeNodeNormals(space, meshOnDevice);
  meshBody.volumes = mesh::computeNodeVolumes(space, meshOnDevice, thickness);

  // Row offsets: mesh node m starts where the first PD node >= m started (setup-time host pass).
  const auto oldOffsets = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, body.bonds.offsets);
  Kokkos::View<RowOffset*, Kokkos::HostSpace> offsets("pd mesh-indexed offsets", numMeshNodes + 1);
  for (LocalIndex m = 0, k = 0; m <= numMeshNodes; ++m) {
    while (k < numPdNodes && pdNodes(k) < m) ++k;
    offsets(m) = oldOffsets(k);
  }
  meshBody.bonds.offsets = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, offsets);

  const auto nodes = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, pdNodes);
  const auto oldNeighbours = body.bonds.neighbours;
  const auto oldHalfBonds = body.bonds.halfBonds;
  const auto neighbours = meshBody.bonds.neighbours =
      Kokkos::View<LocalIndex*, MemorySpaceT>("pd mesh-indexed neighbours", oldNeighbours.extent(0));
  const auto halfBonds = meshBody.bonds.halfBonds = Kokkos::View<LocalIndex* [2], Kokkos::LayoutRight, MemorySpaceT>(
      "pd mesh-indexed half bonds", oldHalfBonds.extent(0));
  Kokkos::parallel_for(
      "perishell::pd::indexByMeshNodes::neighbours", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, neighbours.extent(0)),
      KOKKOS_LAMBDA(const RowOffset entry) { neighbours(entry) = nodes(oldNeighbours(entry)); });
  Kokkos::parallel_for(
      "perishell::pd::indexByMeshNodes::halfBonds", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, halfBonds.extent(0)),
      KOKKOS_LAMBDA(const RowOffset b) {
        halfBonds(b, 0) = nodes(oldHalfBonds(b, 0));
        halfBonds(b, 1) = nodes(oldHalfBonds(b, 1));
      });
  return meshBody;
}

// Every node of the mesh, for 100 % PD models.
inline Kokkos::View<LocalIndex*, Kokkos::HostSpace> allNodes(LocalIndex numNodes) {
  Kokkos::View<LocalIndex*, Kokkos::HostSpace> nodes("all nodes", numNodes);
  for (LocalIndex k = 0; k < numNodes; ++k) nodes(k) = k;
  return nodes;
}

}  // namespace perishell::pd
