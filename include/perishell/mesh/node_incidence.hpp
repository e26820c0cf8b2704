#pragma once
// Node-to-element incidence: for every node, the corners of the elements it belongs to, as
// entries 4 e + a (corner a of element e; a triangle a b c c lists its node c once), in
// ascending element order. Element contributions summed to the nodes through it add in that
// fixed order: the same bits on every run, thread count and backend, which an atomic scatter
// (adding in whatever order the threads reach the node) does not give.
// Built on the device: counts by atomic increments (integers: exact in any order), a prefix
// sum, a fill, then each node's few entries sorted.
#include <perishell/mesh/quad_mesh.hpp>

namespace perishell::mesh {

template <class MemorySpaceT>
struct NodeIncidence {
  Kokkos::View<RowOffset*, MemorySpaceT> offsets;  // node n's entries: offsets(n) .. offsets(n + 1)
  Kokkos::View<LocalIndex*, MemorySpaceT> entries;
};

template <class ExecutionSpaceT, class ConnectivityT>
NodeIncidence<typename ExecutionSpaceT::memory_space> makeNodeIncidence(const ExecutionSpaceT& space,
                                                                       const ConnectivityT& quads,
                                                                       LocalIndex numNodes) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  using Memory = typename ExecutionSpaceT::memory_space;
  const auto numElements = static_cast<LocalIndex>(quads.extent(0));
  NodeIncidence<Memory> incidence;
  const Kokkos::View<RowOffset*, Memory> offsets("node incidence offsets", std::size_t(numNodes) + 1);
  Kokkos::parallel_for(
      "perishell::mesh::nodeIncidence::count", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, numElements),
      KOKKOS_LAMBDA(const LocalIndex e) {
        for (int a = 0; a < cornerCount(quads, e); ++a) Kokkos::atomic_increment(&offsets(quads(e, a) + 1));
      });
  Kokkos::parallel_scan(
      "perishell::mesh::nodeIncidence::offsets", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, numNodes + 1),
      KOKKOS_LAMBDA(const LocalIndex n, RowOffset& sum, const bool final) {
        sum += offsets(n);
        if (final) offsets(n) = sum;
      });
  RowOffset total = 0;
  Kokkos::deep_copy(space, total, Kokkos::subview(offsets, numNodes));
  space.fence();
  const Kokkos::View<LocalIndex*, Memory> entries("node incidence entries", total);
  const Kokkos::View<RowOffset*, Memory> cursor("node incidence cursor", numNodes);
  Kokkos::parallel_for(
      "perishell::mesh::nodeIncidence::fill", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, numElements),
      KOKKOS_LAMBDA(const LocalIndex e) {
        for (int a = 0; a < cornerCount(quads, e); ++a) {
          const LocalIndex node = quads(e, a);
          entries(offsets(node) + Kokkos::atomic_fetch_add(&cursor(node), RowOffset(1))) = 4 * e + a;
        }
      });
  Kokkos::parallel_for(
      "perishell::mesh::nodeIncidence::sort", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, numNodes),
      KOKKOS_LAMBDA(const LocalIndex n) {
        for (RowOffset i = offsets(n) + 1; i < offsets(n + 1); ++i) {
          const LocalIndex entry = entries(i);
          RowOffset j = i;
          for (; j > offsets(n) && entries(j - 1) > entry; --j) entries(j) = entries(j - 1);
          entries(j) = entry;
        }
      });
  incidence.offsets = offsets;
  incidence.entries = entries;
  return incidence;
}

}  // namespace perishell::mesh
