#include <perishell/assembly/quad_crs_pattern.hpp>

#include <algorithm>
#include <vector>

namespace perishell::assembly {

QuadCrsPattern<Kokkos::HostSpace> buildQuadCrsPattern(const mesh::HostQuadMesh& mesh) {
  const LocalIndex numNodes = mesh.numNodes();
  const LocalIndex numElements = mesh.numElements();
  std::vector<std::vector<LocalIndex>> adjacency(numNodes);
  for (LocalIndex e = 0; e < numElements; ++e)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) adjacency[mesh.quads(e, a)].push_back(mesh.quads(e, b));

  QuadCrsPattern<Kokkos::HostSpace> pattern;
  pattern.rowMap = Kokkos::View<RowOffset*, Kokkos::HostSpace>("crs row map", numNodes + 1);
  for (LocalIndex row = 0; row < numNodes; ++row) {
    auto& columns = adjacency[row];
    std::sort(columns.begin(), columns.end());
    columns.erase(std::unique(columns.begin(), columns.end()), columns.end());
    pattern.rowMap(row + 1) = pattern.rowMap(row) + columns.size();
  }
  pattern.columns = Kokkos::View<LocalIndex*, Kokkos::HostSpace>("crs columns", pattern.rowMap(numNodes));
  for (LocalIndex row = 0; row < numNodes; ++row)
    std::copy(adjacency[row].begin(), adjacency[row].end(), pattern.columns.data() + pattern.rowMap(row));

  pattern.valueSlot = decltype(pattern.valueSlot)("crs element slots", numElements);
  for (LocalIndex e = 0; e < numElements; ++e)
    for (int a = 0; a < 4; ++a) {
      const LocalIndex row = mesh.quads(e, a);
      const LocalIndex* first = pattern.columns.data() + pattern.rowMap(row);
      const LocalIndex* last = pattern.columns.data() + pattern.rowMap(row + 1);
      for (int b = 0; b < 4; ++b)
        pattern.valueSlot(e, a, b) = static_cast<RowOffset>(
            std::lower_bound(first, last, mesh.quads(e, b)) - pattern.columns.data());
    }
  return pattern;
}

}  // namespace perishell::assembly
