#pragma once
// One place for the Kokkos spaces and View types perishell uses. Everything that launches
// work is templated on an execution space; these aliases pick the build's defaults.
#include <Kokkos_Core.hpp>

#include <cstdint>
#include <type_traits>

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

}  // namespace perishell
