#pragma once
// One place for the Kokkos spaces and View types perishell uses. Everything that launches
// work is templated on an execution space; these aliases pick the build's defaults.
#include <Kokkos_Core.hpp>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace perishell {

using ExecutionSpace = Kokkos::DefaultExecutionSpace;
using MemorySpace = ExecutionSpace::memory_space;
using HostExecutionSpace = Kokkos::DefaultHostExecutionSpace;

// Node and element indices: int covers 2^31 nodes, far beyond one GPU's memory.
using LocalIndex = int;
// CRS row offsets: size_t, because nnz of a 6-DOF shell tangent passes 2^31 well before
// the node count does (deps.md: Kokkos Kernels' default offset on CUDA is unsigned int).
using RowOffset = std::size_t;

template <class MemorySpaceT>
using VectorView = Kokkos::View<double*, MemorySpaceT>;
template <class MemorySpaceT>
using MultiVectorView = Kokkos::View<double**, Kokkos::LayoutLeft, MemorySpaceT>;
// Small per-entity arrays are LayoutRight in every space (an entity's values are
// contiguous, and host/device mirrors share one layout, so they copy without reordering).
// Node coordinates: one row per node, x y z.
template <class MemorySpaceT>
using CoordinateView = Kokkos::View<double* [3], Kokkos::LayoutRight, MemorySpaceT>;
// Quad connectivity: one row per element, four node indices counter-clockwise.
template <class MemorySpaceT>
using QuadConnectivityView = Kokkos::View<LocalIndex* [4], Kokkos::LayoutRight, MemorySpaceT>;

// Which tangent the implicit kernels assemble (model.md §5): the exact derivative of the
// internal force under R <- exp(phi) R, non-symmetric by -1/2 skew(m) on a node's rotation
// block where moments act, or its symmetric part, which CG can solve with. The two agree at
// equilibrium where no moment is applied.
enum class TangentForm { Exact, Symmetric };

template <class ExecutionSpaceT>
inline constexpr bool is_execution_space_v = Kokkos::is_execution_space<ExecutionSpaceT>::value;

// The range policy of the kernels every explicit step launches. Kokkos 3.4 puts a functor
// above 512 bytes (ours capture a body's views) in CUDA constant memory and then makes the
// host wait for the previous such kernel to finish before it launches the next, so the GPU
// idles between a step's kernels; the light-weight hint passes the functor as a kernel
// argument (up to 4 kB) and the launches queue. Host backends ignore the hint.
template <class ExecutionSpaceT, class IndexT>
auto queuedRangePolicy(const ExecutionSpaceT& space, IndexT begin, IndexT end) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  return Kokkos::Experimental::require(Kokkos::RangePolicy<ExecutionSpaceT>(space, begin, end),
                                       Kokkos::Experimental::WorkItemProperty::HintLightWeight);
}

// Sets every entry of a contiguous view to `value` as one flat range. Kokkos 3.4 fills a
// rank-2 view with an MDRange kernel: 309 us for the 1e6 x 6 nodal forces on the H200
// (ncu), 11 % of an explicit step; the flat fill takes 60 us.
template <class ExecutionSpaceT, class ViewT>
void fillContiguous(const ExecutionSpaceT& space, const ViewT& view, typename ViewT::non_const_value_type value) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  if (!view.span_is_contiguous()) throw std::logic_error("fillContiguous: the view is not contiguous");
  using Flat = Kokkos::View<typename ViewT::non_const_value_type*, typename ViewT::memory_space,
                            Kokkos::MemoryTraits<Kokkos::Unmanaged>>;
  Kokkos::deep_copy(space, Flat(view.data(), view.span()), value);
}

// A set-up list built on the host, as a view of MemorySpaceT (set-up only: it allocates and
// copies).
template <class MemorySpaceT, class T>
Kokkos::View<T*, MemorySpaceT> viewOf(const std::vector<T>& host, const std::string& label) {
  Kokkos::View<T*, MemorySpaceT> view(label, host.size());
  Kokkos::deep_copy(view, Kokkos::View<const T*, Kokkos::HostSpace, Kokkos::MemoryUnmanaged>(host.data(), host.size()));
  return view;
}

}  // namespace perishell
