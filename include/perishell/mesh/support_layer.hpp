#pragma once
// The support layer of PD regions (docs/model-setup.md, "Supports on PD regions"): beyond a
// supported mesh edge, the mirror image of the PD elements within one horizon of it, appended
// to the mesh as extra nodes and elements. Beyond a clamped edge the edge's supports hold the
// layer like the edge itself; beyond a symmetry plane, a hinge or a diaphragm each layer node
// moves as the mirror image (even or odd per component) of the node it images. A PD node near
// such an edge then bonds across it as it would inside the material, instead of seeing a free
// surface: without the layer a clamped square plate under pressure was 23 % too soft at a/20
// (first order in delta/a); with it, 2.2 % (docs/verification.md). Host data, built once at setup.
#include <perishell/mesh/free_edges.hpp>
#include <perishell/mesh/quad_mesh.hpp>

#include <array>
#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace perishell::mesh {

enum class LayerMotion {
  Held,     // the set's supports hold the layer's nodes as the set's (values and curves too)
  Mirrored  // each layer node follows the image of its master (MirrorMaps) about the set's values
};

struct SupportLayerRequest {
  std::string setName;
  std::vector<LocalIndex> nodes;  // the set's nodes, sorted: layers grow beyond its free edges
  LayerMotion motion = LayerMotion::Held;
  std::uint8_t heldDofs = 0;  // Mirrored: bit d for DOF d (ux uy uz rx ry rz) the set holds
};

// How an image node's displacement and rotation vector follow its master's (row-major 3 x 3,
// global axes): u_image = displacement u_master, theta_image = rotation theta_master.
struct MirrorMaps {
  std::array<double, 9> displacement, rotation;
};

// The maps across a free edge (frame, mirrorPlaneEdge's: n the mirror plane's normal, t the
// tangent, z normal to both) of a set holding heldDofs; none where the held DOFs make neither
// part of the motion a mirror image. Per part, in the edge frame (model-setup.md):
// membrane (u_n, u_t, theta_z): u_n and u_t held -> held (map 0); u_n held -> even image
// (u_n odd, u_t even, theta_z odd); u_t held -> odd image; bending (w, theta_n, theta_t):
// w and theta_t held -> held; theta_t held -> even image (w even, theta_n even, theta_t odd);
// w held -> odd image. Even-even is the reflection of a symmetry plane, odd-odd its
// antisymmetric counterpart (a rigid diaphragm), membrane-even with bending-odd a hinge.
std::optional<MirrorMaps> mirrorMaps(const FreeEdge& edge, std::uint8_t heldDofs);

// The edge in its mirror plane's frame: outward the plane's normal, taken from the held
// translations (a symmetry plane holds the displacement across it) or else the free ones (a
// diaphragm leaves free the one along the shell's generator) where the element's outward
// normal lies within 30 degrees of them, so that a curved shell's image across its symmetry
// plane is the shell itself; else the element's frame.
FreeEdge mirrorPlaneEdge(const FreeEdge& edge, std::uint8_t heldDofs);

// A layer node that moves as the image of a node of the deck's mesh. It lies at
// reflection (x_master - o) + o, o a point of its mirror line (row-major 3 x 3: one
// reflection, or two at a corner).
struct MirrorImage {
  LocalIndex node, master;
  MirrorMaps maps;
  std::array<double, 9> reflection;
};

struct SupportLayer {
  // Mesh nodes from here on belong to the layer (no layer: beyond every index).
  LocalIndex firstNode = std::numeric_limits<LocalIndex>::max();
  LocalIndex firstElement = std::numeric_limits<LocalIndex>::max();  // likewise elements
  std::map<std::string, std::vector<LocalIndex>> nodesOfSet;  // held layer nodes per request, sorted
  std::map<std::string, std::vector<LocalIndex>> mirroredNodesOfSet;  // mirrored layer nodes per request, sorted
  std::vector<MirrorImage> mirrorImages;  // every mirrored layer node once, by node
  // The share of each node's neighbourhood that the model holds (assembly/mirror_images.hpp):
  // 0 for a mirrored layer node and a held one beyond a mirror line, 1/2 on one mirror line,
  // 1/4 where two meet; nodes not listed hold all of theirs.
  std::map<LocalIndex, double> mirrorShare;
  // On mirror lines: the node's area in the deck's elements over its area with the layer's,
  // the share of its mass that the model holds.
  std::map<LocalIndex, double> massShare;
  std::vector<std::string> skippedSets;  // requested sets with free edges, the mesh going on beyond each
  std::vector<std::string> narrowSets;   // sets with an edge where the model is narrower than depth

  bool contains(LocalIndex node) const { return node >= firstNode; }
};

// Appends the layer to mesh (its nodes and elements after the existing ones) for every
// request: beyond each free edge of the mesh whose two nodes lie in the set (for a Mirrored
// request, where mirrorMaps gives maps), the mirror image of the elements that `mayMirror`
// marks and whose centroids lie within `depth` of the edge, across the edge's line in the
// plane of its element (Held) or in its mirror plane (Mirrored, mirrorPlaneEdge); at convex
// corners between two such edges, the image across both, where it lies within `depth` of
// both. Images closer than `spacing` / 4 to a node of the set or of the layer share that node;
// a node that a Held request holds is not mirrored. An edge where mesh nodes lie within
// `depth` beyond it (a slit, a fold) gets no layer. Without requests the mesh is unchanged.
SupportLayer addSupportLayer(HostQuadMesh& mesh, const std::vector<SupportLayerRequest>& requests,
                             const std::vector<std::uint8_t>& mayMirror, double depth, double spacing);

}  // namespace perishell::mesh
