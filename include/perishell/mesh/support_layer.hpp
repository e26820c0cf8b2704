#pragma once
// The support layer of PD regions (docs/model-setup.md, "Supports on PD regions"): beyond a
// clamped mesh edge, the mirror image of the PD elements within one horizon of it, appended
// to the mesh as extra nodes and elements that the edge's supports hold like the edge itself.
// A PD node near a clamped edge then bonds across the edge as it would inside the material,
// instead of seeing a free surface: without the layer a clamped square plate under pressure
// was 23 % too soft at a/20 (first order in delta/a); with it, 2.6 % (docs/verification.md).
// Host data, built once at setup.
#include <perishell/mesh/quad_mesh.hpp>

#include <cstdint>
#include <limits>
#include <map>
#include <string>
#include <vector>

namespace perishell::mesh {

struct SupportLayerRequest {
  std::string setName;            // the layer's nodes are held as this set's nodes
  std::vector<LocalIndex> nodes;  // the set's nodes, sorted: layers grow beyond its free edges
};

struct SupportLayer {
  // Mesh nodes from here on belong to the layer (no layer: beyond every index).
  LocalIndex firstNode = std::numeric_limits<LocalIndex>::max();
  LocalIndex firstElement = std::numeric_limits<LocalIndex>::max();  // likewise elements
  std::map<std::string, std::vector<LocalIndex>> nodesOfSet;  // layer nodes per request, sorted
  std::vector<std::string> skippedSets;  // requested sets with free edges, the mesh going on beyond each

  bool contains(LocalIndex node) const { return node >= firstNode; }
};

// Appends the layer to mesh (its nodes and elements after the existing ones) for every
// request: beyond each free edge of the mesh whose two nodes lie in the set, the mirror
// image (across the edge's line, in the plane of its element) of the elements that
// `mayMirror` marks and whose centroids lie within `depth` of the edge; at convex corners
// between two such edges, the image across both, where it lies within `depth` of both. Images closer than `spacing` / 4 to a node
// of the set or of the layer share that node. An edge where mesh nodes lie within `depth`
// beyond it (a slit, a fold) gets no layer. Without requests the mesh is unchanged.
SupportLayer addSupportLayer(HostQuadMesh& mesh, const std::vector<SupportLayerRequest>& requests,
                             const std::vector<std::uint8_t>& mayMirror, double depth, double spacing);

}  // namespace perishell::mesh
