#pragma once
// Greedy aggregation of a node graph for smoothed-aggregation multigrid (Vanek, Mandel and
// Brezina 1996, "Algebraic multigrid by smoothed aggregation for second and fourth order
// elliptic problems", phases 1-3): roots whose whole neighbourhood is still free take it as
// an aggregate, leftovers join the neighbouring aggregate they are most connected to, and
// nodes with no aggregated neighbour form their own.
//
// It runs on the host: the pass is sequential by nature and happens once per sparsity
// pattern (which never changes during a run), never per solve or per Newton iteration.
#include <perishell/core/types.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

namespace perishell::multigrid {

// Node adjacency (self included) on the host.
struct HostNodeGraph {
  std::vector<RowOffset> rowMap;   // numNodes + 1
  std::vector<LocalIndex> columns;  // neighbours of node n: columns[rowMap[n] .. rowMap[n+1])

  LocalIndex numNodes() const { return rowMap.empty() ? 0 : static_cast<LocalIndex>(rowMap.size() - 1); }
};

struct Aggregates {
  LocalIndex numAggregates = 0;
  std::vector<LocalIndex> aggregateOf;  // per node
  // Members of aggregate a: members[offsets[a] .. offsets[a+1]), ascending.
  std::vector<RowOffset> offsets;
  std::vector<LocalIndex> members;
};

// The node graph of a scalar CRS whose rows come in groups of blockSize per node: nodes i and
// j are adjacent when any row of i has a column of j.
template <class HostRowMap, class HostEntries>
HostNodeGraph nodeGraphOf(const HostRowMap& rowMap, const HostEntries& entries, int blockSize) {
  const LocalIndex numNodes = static_cast<LocalIndex>((rowMap.extent(0) - 1) / blockSize);
  HostNodeGraph graph;
  graph.rowMap.assign(1, 0);
  std::vector<LocalIndex> neighbours;
  for (LocalIndex node = 0; node < numNodes; ++node) {
    neighbours.clear();
    for (RowOffset k = rowMap(blockSize * node); k < rowMap(blockSize * (node + 1)); ++k)
      neighbours.push_back(entries(k) / blockSize);
    std::sort(neighbours.begin(), neighbours.end());
    neighbours.erase(std::unique(neighbours.begin(), neighbours.end()), neighbours.end());
    graph.columns.insert(graph.columns.end(), neighbours.begin(), neighbours.end());
    graph.rowMap.push_back(graph.columns.size());
  }
  return graph;
}

// The node graph of strong couplings only (Vanek, Mandel and Brezina 1996, "strongly coupled
// neighbourhood"; MueLu's "aggregation: drop tol", amalgamated per node): nodes i != j are
// adjacent when some non-zero entry of their block has |a_pq| >= dropTolerance sqrt(|a_pp a_qq|).
// The scaled entries are unitless, so translations and rotations compare alike; a supported
// DOF (zero off-diagonals after elimination) couples to nothing. dropTolerance 0 keeps every
// stored block (nodeGraphOf).
template <class HostRowMap, class HostEntries, class HostValues>
HostNodeGraph strongNodeGraphOf(const HostRowMap& rowMap, const HostEntries& entries, const HostValues& values,
                                int blockSize, double dropTolerance) {
  if (!(dropTolerance > 0.0)) return nodeGraphOf(rowMap, entries, blockSize);
  const LocalIndex numRows = static_cast<LocalIndex>(rowMap.extent(0) - 1);
  std::vector<double> diagonal(numRows, 0.0);
  for (LocalIndex row = 0; row < numRows; ++row)
    for (RowOffset k = rowMap(row); k < rowMap(row + 1); ++k)
      if (entries(k) == row) diagonal[row] = std::abs(values(k));
  const LocalIndex numNodes = numRows / blockSize;
  HostNodeGraph graph;
  graph.rowMap.assign(1, 0);
  std::vector<LocalIndex> neighbours;
  for (LocalIndex node = 0; node < numNodes; ++node) {
    neighbours.assign(1, node);
    for (LocalIndex row = blockSize * node; row < blockSize * (node + 1); ++row)
      for (RowOffset k = rowMap(row); k < rowMap(row + 1); ++k) {
        const LocalIndex column = entries(k);
        if (column / blockSize != node && values(k) != 0.0 &&
            std::abs(values(k)) >= dropTolerance * std::sqrt(diagonal[row] * diagonal[column]))
          neighbours.push_back(column / blockSize);
      }
    std::sort(neighbours.begin(), neighbours.end());
    neighbours.erase(std::unique(neighbours.begin(), neighbours.end()), neighbours.end());
    graph.columns.insert(graph.columns.end(), neighbours.begin(), neighbours.end());
    graph.rowMap.push_back(graph.columns.size());
  }
  return graph;
}

inline Aggregates aggregateNodes(const HostNodeGraph& graph) {
  const LocalIndex numNodes = graph.numNodes();
  constexpr LocalIndex none = -1;
  Aggregates result;
  result.aggregateOf.assign(numNodes, none);
  auto neighbours = [&](LocalIndex node) {
    return std::make_pair(graph.columns.begin() + graph.rowMap[node], graph.columns.begin() + graph.rowMap[node + 1]);
  };
  // Phase 1: a root and its whole (still free) neighbourhood.
  for (LocalIndex node = 0; node < numNodes; ++node) {
    if (result.aggregateOf[node] != none) continue;
    const auto [first, last] = neighbours(node);
    if (std::any_of(first, last, [&](LocalIndex m) { return result.aggregateOf[m] != none; })) continue;
    if (last - first <= 1) continue;  // an isolated node is left to phase 3
    for (auto it = first; it != last; ++it) result.aggregateOf[*it] = result.numAggregates;
    ++result.numAggregates;
  }
  // Phase 2: leftovers join the phase-1 aggregate they share the most edges with.
  const std::vector<LocalIndex> phaseOne = result.aggregateOf;
  std::vector<int> links(result.numAggregates, 0);
  for (LocalIndex node = 0; node < numNodes; ++node) {
    if (phaseOne[node] != none) continue;
    const auto [first, last] = neighbours(node);
    LocalIndex best = none;
    for (auto it = first; it != last; ++it) {
      const LocalIndex a = phaseOne[*it];
      if (a == none) continue;
      ++links[a];
      if (best == none || links[a] > links[best]) best = a;
    }
    for (auto it = first; it != last; ++it)
      if (phaseOne[*it] != none) links[phaseOne[*it]] = 0;
    result.aggregateOf[node] = best;
  }
  // Phase 3: whatever has no aggregated neighbour is an aggregate of its own, except nodes
  // coupled to nothing (supported on every DOF: their near-null rows are zero), which all
  // share one. Kept apart, a clamped edge's nodes stayed one coarse node each on every level,
  // coarsening stalled at their count, and the dense coarse levels cost seconds per update.
  LocalIndex decoupled = none;
  for (LocalIndex node = 0; node < numNodes; ++node) {
    if (result.aggregateOf[node] != none) continue;
    const auto [first, last] = neighbours(node);
    if (std::any_of(first, last, [&](LocalIndex m) { return m != node; })) {
      result.aggregateOf[node] = result.numAggregates++;
    } else {
      if (decoupled == none) decoupled = result.numAggregates++;
      result.aggregateOf[node] = decoupled;
    }
  }

  result.offsets.assign(result.numAggregates + 1, 0);
  for (LocalIndex node = 0; node < numNodes; ++node) ++result.offsets[result.aggregateOf[node] + 1];
  for (LocalIndex a = 0; a < result.numAggregates; ++a) result.offsets[a + 1] += result.offsets[a];
  result.members.resize(numNodes);
  std::vector<RowOffset> next(result.offsets.begin(), result.offsets.end() - 1);
  for (LocalIndex node = 0; node < numNodes; ++node) result.members[next[result.aggregateOf[node]]++] = node;
  return result;
}

}  // namespace perishell::multigrid
