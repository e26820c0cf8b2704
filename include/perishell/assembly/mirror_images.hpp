#pragma once
// Mirrored support-layer nodes on the device (mesh/support_layer.hpp; docs/model-setup.md,
// "Supports on PD regions"). A mirrored layer node L owns no DOF: it moves as the image of its
// master M, u_L = A_u u_M and theta_L = A_theta theta_M (rotation vectors), about what its set
// prescribes (imposeMirrorImages). The layer stands
// for the material beyond a symmetry plane, hinge or diaphragm, whose energy the model does
// not store. The whole structure's energy is the sum over its nodes of half their bonds'
// energies; the model stores each node's part times its share of the structure (1 inside,
// 1/2 on a mirror line, 1/4 where two meet, 0 for an image), so a bond carries the mean share
// of its ends (weighBondsByShare), and likewise a node on a mirror line its share of the mass.
// For the states the images allow, that is exactly the model's part of the whole structure's
// energy. Its gradient gives the masters the images' forces, f_M += A^T f_L
// (condenseImageForces, which leaves each image its reaction), and its Hessian the tangent
// blocks A^T K A (mapBondTangent).
#include <perishell/core/rotation.hpp>
#include <perishell/mesh/support_layer.hpp>
#include <perishell/pd/pd_body.hpp>

#include <map>
#include <string>
#include <vector>

namespace perishell::assembly {

template <class MemorySpaceT>
struct MirrorImages {
  Kokkos::View<LocalIndex*, MemorySpaceT> nodes;    // mirrored layer nodes, ascending
  Kokkos::View<LocalIndex*, MemorySpaceT> masters;  // the node each one images
  Kokkos::View<double* [18], Kokkos::LayoutRight, MemorySpaceT> maps;  // A_u then A_theta, row-major
  Kokkos::View<LocalIndex*, MemorySpaceT> imageOf;  // per mesh node: its index in nodes, or -1
  VectorView<MemorySpaceT> share;      // per mesh node (mesh::SupportLayer::mirrorShare)
  VectorView<MemorySpaceT> massShare;  // per mesh node (mesh::SupportLayer::massShare)
  // The masters with images, and theirs (CSR into nodes), so that condensing gathers per
  // master: no atomics, the same sums in the same order on every backend.
  Kokkos::View<LocalIndex*, MemorySpaceT> gatherMasters;
  Kokkos::View<LocalIndex*, MemorySpaceT> gatherOffsets;
  Kokkos::View<LocalIndex*, MemorySpaceT> gatherImages;

  LocalIndex size() const { return static_cast<LocalIndex>(nodes.extent(0)); }
  bool empty() const { return nodes.extent(0) == 0; }

  // The node that carries node n's DOFs: its master for an image, n itself otherwise.
  KOKKOS_INLINE_FUNCTION LocalIndex carrier(LocalIndex n) const {
    if (imageOf.extent(0) == 0) return n;
    const LocalIndex k = imageOf(n);
    return k < 0 ? n : masters(k);
  }

  // K (12 x 12, ends i and j in 6-DOF blocks) becomes T^T K T with T the block diagonal of
  // each end's maps (identity for a mesh node): the bond's tangent on its carriers' DOFs.
  KOKKOS_INLINE_FUNCTION void mapBondTangent(LocalIndex i, LocalIndex j, double K[12][12]) const {
    if (imageOf.extent(0) == 0) return;
    const LocalIndex ends[2] = {imageOf(i), imageOf(j)};
    for (int e = 0; e < 2; ++e) {
      const LocalIndex k = ends[e];
      if (k < 0) continue;
      for (int part = 0; part < 2; ++part) {
        const int first = 6 * e + 3 * part;
        const auto A = [&](int r, int c) { return maps(k, 9 * part + 3 * r + c); };
        for (int row = 0; row < 12; ++row) {  // columns: K A
          double mapped[3] = {0.0, 0.0, 0.0};
          for (int c = 0; c < 3; ++c)
            for (int m = 0; m < 3; ++m) mapped[c] += K[row][first + m] * A(m, c);
          for (int c = 0; c < 3; ++c) K[row][first + c] = mapped[c];
        }
        for (int column = 0; column < 12; ++column) {  // rows: A^T K
          double mapped[3] = {0.0, 0.0, 0.0};
          for (int r = 0; r < 3; ++r)
            for (int m = 0; m < 3; ++m) mapped[r] += A(m, r) * K[first + m][column];
          for (int r = 0; r < 3; ++r) K[first + r][column] = mapped[r];
        }
      }
    }
  }
};

// A support layer's images and shares (mesh::SupportLayer) on memory space MemorySpaceT
// (empty views when there are none).
template <class MemorySpaceT>
MirrorImages<MemorySpaceT> makeMirrorImages(const mesh::SupportLayer& layer, LocalIndex numNodes) {
  const auto& images = layer.mirrorImages;
  MirrorImages<MemorySpaceT> result;
  const LocalIndex count = static_cast<LocalIndex>(images.size());
  Kokkos::View<LocalIndex*, Kokkos::HostSpace> nodes("mirror image nodes", count), masters("mirror image masters", count);
  Kokkos::View<double* [18], Kokkos::LayoutRight, Kokkos::HostSpace> maps("mirror image maps", count);
  Kokkos::View<LocalIndex*, Kokkos::HostSpace> imageOf("mirror image of node", count > 0 ? numNodes : 0);
  Kokkos::deep_copy(imageOf, LocalIndex(-1));
  Kokkos::View<double*, Kokkos::HostSpace> share("mirror share", count > 0 ? numNodes : 0),
      massShare("mirror mass share", count > 0 ? numNodes : 0);
  Kokkos::deep_copy(share, 1.0);
  Kokkos::deep_copy(massShare, 1.0);
  if (count > 0) {
    for (const auto& [node, value] : layer.mirrorShare) share(node) = value;
    for (const auto& [node, value] : layer.massShare) massShare(node) = value;
  }
  std::vector<std::vector<LocalIndex>> imagesOfMaster(count > 0 ? numNodes : 0);
  for (LocalIndex k = 0; k < count; ++k) {
    nodes(k) = images[k].node;
    masters(k) = images[k].master;
    for (int m = 0; m < 9; ++m) {
      maps(k, m) = images[k].maps.displacement[m];
      maps(k, 9 + m) = images[k].maps.rotation[m];
    }
    imageOf(images[k].node) = k;
    imagesOfMaster[images[k].master].push_back(k);
  }
  std::vector<LocalIndex> gatherMasters, gatherOffsets{0}, gatherImages;
  for (std::size_t master = 0; master < imagesOfMaster.size(); ++master) {
    if (imagesOfMaster[master].empty()) continue;
    gatherMasters.push_back(static_cast<LocalIndex>(master));
    gatherImages.insert(gatherImages.end(), imagesOfMaster[master].begin(), imagesOfMaster[master].end());
    gatherOffsets.push_back(static_cast<LocalIndex>(gatherImages.size()));
  }
  result.nodes = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, nodes);
  result.masters = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, masters);
  result.maps = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, maps);
  result.imageOf = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, imageOf);
  result.share = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, share);
  result.massShare = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, massShare);
  result.gatherMasters = viewOf<MemorySpaceT>(gatherMasters, "mirror gather masters");
  result.gatherOffsets = viewOf<MemorySpaceT>(gatherOffsets, "mirror gather offsets");
  result.gatherImages = viewOf<MemorySpaceT>(gatherImages, "mirror gather images");
  return result;
}

// Moves every image with its master: u_L = A_u u_M + (I - A_u) p_L and theta_L = A_theta
// theta_M + (I - A_theta) p_theta, p = prescribed(L, d) the value its set's supports prescribe
// now (zero where they hold nothing): an odd component is the image about the prescribed
// value (2 p - u_M), a held one the value itself, an even one the master's.
template <class ExecutionSpaceT, class MemorySpaceT, class PrescribedT>
void imposeMirrorImages(const ExecutionSpaceT& space, const MirrorImages<MemorySpaceT>& images,
                        const CoordinateView<MemorySpaceT>& displacements,
                        const pd::RotationView<MemorySpaceT>& rotations, const PrescribedT& prescribed) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  if (images.empty()) return;
  Kokkos::parallel_for(
      "perishell::assembly::imposeMirrorImages", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, images.size()),
      KOKKOS_LAMBDA(const LocalIndex k) {
        const LocalIndex image = images.nodes(k), master = images.masters(k);
        const double q[4] = {rotations(master, 0), rotations(master, 1), rotations(master, 2), rotations(master, 3)};
        double theta[3], held[6];
        rotation::rotationVector(q, theta);
        for (int d = 0; d < 6; ++d) held[d] = prescribed(image, d);
        double u[3], mappedTheta[3];
        for (int r = 0; r < 3; ++r) {
          u[r] = held[r];
          mappedTheta[r] = held[3 + r];
          for (int c = 0; c < 3; ++c) {
            u[r] += images.maps(k, 3 * r + c) * (displacements(master, c) - held[c]);
            mappedTheta[r] += images.maps(k, 9 + 3 * r + c) * (theta[c] - held[3 + c]);
          }
        }
        double mapped[4];
        rotation::exponential(mappedTheta, mapped);
        for (int d = 0; d < 3; ++d) displacements(image, d) = u[d];
        for (int d = 0; d < 4; ++d) rotations(image, d) = mapped[d];
      });
}

// No prescribed motion: the images of a trial state.
struct NothingPrescribed {
  KOKKOS_INLINE_FUNCTION double operator()(LocalIndex, int) const { return 0.0; }
};

// f_M += A^T f_L for every image L of M: the images' forces (and moments) act on the DOFs that
// carry them. What is left at L, f_L - A^T f_L, is the force the layer, as a support, exerts
// beyond what its master takes (an odd image of w carries the edge's shear): the images hold
// all their DOFs, so it is their reaction, and the forces over all nodes still sum to zero.
template <class ExecutionSpaceT, class MemorySpaceT>
void condenseImageForces(const ExecutionSpaceT& space, const MirrorImages<MemorySpaceT>& images,
                         const pd::NodalVectorView<MemorySpaceT>& forces) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  if (images.empty()) return;
  Kokkos::parallel_for(
      "perishell::assembly::condenseImageForces",
      Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, static_cast<LocalIndex>(images.gatherMasters.extent(0))),
      KOKKOS_LAMBDA(const LocalIndex m) {
        const LocalIndex master = images.gatherMasters(m);
        for (LocalIndex slot = images.gatherOffsets(m); slot < images.gatherOffsets(m + 1); ++slot) {
          const LocalIndex k = images.gatherImages(slot), image = images.nodes(k);
          double carried[6];
          for (int part = 0; part < 2; ++part)
            for (int c = 0; c < 3; ++c) {
              double sum = 0.0;
              for (int r = 0; r < 3; ++r) sum += images.maps(k, 9 * part + 3 * r + c) * forces(image, 3 * part + r);
              carried[3 * part + c] = sum;
            }
          for (int d = 0; d < 6; ++d) {
            forces(master, d) += carried[d];
            forces(image, d) -= carried[d];
          }
        }
      });
}

// Scales every bond by the mean share of its ends (and with it its breaking energy,
// pd/bond_forces.hpp); body indexed by mesh node.
template <class ExecutionSpaceT, class MemorySpaceT>
void weighBondsByShare(const ExecutionSpaceT& space, const pd::PdBody<MemorySpaceT>& body,
                       const MirrorImages<MemorySpaceT>& images) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  if (images.empty() || body.bonds.numBonds() == 0) return;
  const auto scale = body.stiffnessScale;
  const auto halfBonds = body.bonds.halfBonds;
  Kokkos::parallel_for(
      "perishell::assembly::weighBondsByShare", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, body.bonds.numBonds()),
      KOKKOS_LAMBDA(const RowOffset b) {
        const double share = 0.5 * (images.share(halfBonds(b, 0)) + images.share(halfBonds(b, 1)));
        scale(b, 0) *= share;
        scale(b, 1) *= share;
      });
}

// Masses and rotary inertias of nodes on mirror lines times their mass share: the deck's
// elements' part of their volume (an image keeps its own: it is held, and the critical step
// estimate divides by it).
template <class ExecutionSpaceT, class MemorySpaceT>
void weighInertiaByShare(const ExecutionSpaceT& space, const MirrorImages<MemorySpaceT>& images,
                         const VectorView<MemorySpaceT>& mass, const VectorView<MemorySpaceT>& rotaryInertia) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  if (images.empty()) return;
  Kokkos::parallel_for(
      "perishell::assembly::weighInertiaByShare",
      Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, static_cast<LocalIndex>(images.massShare.extent(0))),
      KOKKOS_LAMBDA(const LocalIndex node) {
        const double share = images.massShare(node);
        mass(node) *= share;
        rotaryInertia(node) *= share;
      });
}

}  // namespace perishell::assembly
