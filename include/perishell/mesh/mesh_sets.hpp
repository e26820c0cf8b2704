#pragma once
// Named subsets of a quad mesh, the handles a model deck uses for supports, loads, parts
// and PD zones: node sets, element sets and edge sets. An edge is a pair of node indices
// ordered as the quad that owns it traverses it (counter-clockwise), so a boundary edge
// has the shell on its left when seen against the node normal. Host data, built once.
#include <perishell/mesh/quad_mesh.hpp>

#include <algorithm>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace perishell::mesh {

using MeshEdge = std::pair<LocalIndex, LocalIndex>;

struct MeshSets {
  // Node sets hold sorted, unique indices; element and edge sets keep construction order.
  std::map<std::string, std::vector<LocalIndex>> nodeSets;
  std::map<std::string, std::vector<LocalIndex>> elementSets;
  std::map<std::string, std::vector<MeshEdge>> edgeSets;

  const std::vector<LocalIndex>& nodeSet(const std::string& name) const {
    return lookup(nodeSets, "node", name);
  }
  const std::vector<LocalIndex>& elementSet(const std::string& name) const {
    return lookup(elementSets, "element", name);
  }
  const std::vector<MeshEdge>& edgeSet(const std::string& name) const {
    return lookup(edgeSets, "edge", name);
  }
  // The nodes of a node set, or of an edge set (sorted, unique): what point loads and
  // supports act on. Throws std::invalid_argument, listing the node sets, for other names.
  std::vector<LocalIndex> nodesOfNodeOrEdgeSet(const std::string& name) const {
    if (const auto found = nodeSets.find(name); found != nodeSets.end()) return found->second;
    if (const auto found = edgeSets.find(name); found != edgeSets.end()) {
      std::vector<LocalIndex> nodes;
      for (const auto& [first, second] : found->second) nodes.insert(nodes.end(), {first, second});
      std::sort(nodes.begin(), nodes.end());
      nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
      return nodes;
    }
    return nodeSet(name);
  }

 private:
  // A misspelt set name in a deck should list what exists, not just fail.
  template <class SetT>
  static const SetT& lookup(const std::map<std::string, SetT>& sets, const char* kind,
                            const std::string& name) {
    const auto found = sets.find(name);
    if (found != sets.end()) return found->second;
    std::string known;
    for (const auto& entry : sets) known += (known.empty() ? "'" : ", '") + entry.first + "'";
    throw std::invalid_argument("mesh has no " + std::string(kind) + " set '" + name +
                                "' (" + kind + " sets: " + (known.empty() ? "none" : known) + ")");
  }
};

// A shell mid-surface mesh with its named sets, as generators and readers return it.
struct ShellMesh {
  HostQuadMesh mesh;
  MeshSets sets;
};

}  // namespace perishell::mesh
