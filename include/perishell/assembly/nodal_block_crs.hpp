#pragma once
// The sparsity of the global tangent of a 6-DOF-per-node shell model (3 displacements,
// 3 rotations; paper §3.2.1, model.md) and atomic assembly into it.
//
// Two nodes are coupled when they share a quad element (CCM shell) or a bond (PD microbeam),
// so the sparsity is a graph of 6x6 blocks: block row n lists the nodes coupled to n,
// ascending, n itself included. The scalar CRS matrix (row 6 node + dof) stores every block
// dense and keeps a block row's 6 scalar rows contiguous:
//   rowMap(6 n + d) = 36 nodeRowMap(n) + 6 d len(n),   len(n) = nodeRowMap(n+1) - nodeRowMap(n)
// so a value's slot follows from nodeRowMap alone (slot(), no search), and the scalar
// columns of a row are ascending (Kokkos Kernels and Belos take the CRS as it is).
//
// The pattern keeps the quads and bond node pairs it was built from (views share storage),
// and, per element and per bond, the position of each node pair in its block row, so an
// element or bond kernel adds its whole local matrix with atomicAdd*Matrix from inside its
// own parallel_for. Built once on the device by buildNodalBlockPattern.
#include <perishell/core/types.hpp>

#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

namespace perishell::assembly {

inline constexpr int dofPerNode = 6;

// Whether a bond may join a node to itself: never in a PD body, but a bond between a node and
// its own mirror image (assembly/mirror_images.hpp) adds its tangent to the node alone.
enum class SelfBonds { Refused, Allowed };

template <class MemorySpaceT>
struct NodalBlockPattern {
  using memory_space = MemorySpaceT;

  LocalIndex numNodes = 0;
  // Block graph: the nodes coupled to node n are nodeColumns(nodeRowMap(n) .. nodeRowMap(n+1)-1).
  Kokkos::View<RowOffset*, MemorySpaceT> nodeRowMap;    // numNodes + 1
  Kokkos::View<LocalIndex*, MemorySpaceT> nodeColumns;  // ascending per node, self included
  // Scalar CRS of the 6 numNodes x 6 numNodes tangent, every block dense.
  Kokkos::View<RowOffset*, MemorySpaceT> rowMap;    // 6 numNodes + 1
  Kokkos::View<LocalIndex*, MemorySpaceT> columns;  // 36 x number of blocks, ascending per row
  // The model the pattern was built from: quads (0 rows for a PD-only model) and bond end
  // nodes (0 rows for a CCM-only model).
  QuadConnectivityView<MemorySpaceT> quads;
  Kokkos::View<LocalIndex* [2], Kokkos::LayoutRight, MemorySpaceT> bondNodes;
  // elementBlock(e, a, b): position of node quads(e, b) within the block row of quads(e, a).
  Kokkos::View<LocalIndex* [4][4], Kokkos::LayoutRight, MemorySpaceT> elementBlock;
  // bondBlock(k, a, b): the same for the end nodes bondNodes(k, a), bondNodes(k, b).
  Kokkos::View<LocalIndex* [2][2], Kokkos::LayoutRight, MemorySpaceT> bondBlock;

  LocalIndex numRows() const { return dofPerNode * numNodes; }
  RowOffset numBlocks() const { return nodeColumns.extent(0); }
  RowOffset numEntries() const { return columns.extent(0); }

  // Index into the CRS values of K(6 rowNode + rowDof, 6 nodeColumns(nodeRowMap(rowNode) +
  // blockPosition) + columnDof).
  KOKKOS_INLINE_FUNCTION RowOffset slot(LocalIndex rowNode, int rowDof, LocalIndex blockPosition,
                                        int columnDof) const {
    const RowOffset blockRowStart = nodeRowMap(rowNode);
    const RowOffset blockRowLength = nodeRowMap(rowNode + 1) - blockRowStart;
    return dofPerNode * dofPerNode * blockRowStart + rowDof * dofPerNode * blockRowLength +
           dofPerNode * static_cast<RowOffset>(blockPosition) + columnDof;
  }

  // Adds a quad element's 24x24 matrix (local DOF 6 a + d: node quads(element, a), DOF d).
  template <class ValuesViewT>
  KOKKOS_INLINE_FUNCTION void atomicAddElementMatrix(LocalIndex element, const double K[24][24],
                                                     const ValuesViewT& values) const {
    atomicAddElementMatrix<4>(element, K, values);
  }

  // The same for the first `Corners` nodes of the element: 3 for a triangle (a b c c), whose
  // matrix is 18 x 18.
  template <int Corners, class ValuesViewT>
  KOKKOS_INLINE_FUNCTION void atomicAddElementMatrix(LocalIndex element, const double K[6 * Corners][6 * Corners],
                                                     const ValuesViewT& values) const {
    for (int a = 0; a < Corners; ++a) {
      const LocalIndex rowNode = quads(element, a);
      for (int b = 0; b < Corners; ++b) addBlock(rowNode, elementBlock(element, a, b), K, 6 * a, 6 * b, values);
    }
  }

  // Adds a bond's 12x12 matrix (local DOF 6 a + d: node bondNodes(bond, a), DOF d).
  template <class ValuesViewT>
  KOKKOS_INLINE_FUNCTION void atomicAddBondMatrix(LocalIndex bond, const double K[12][12],
                                                  const ValuesViewT& values) const {
    for (int a = 0; a < 2; ++a) {
      const LocalIndex rowNode = bondNodes(bond, a);
      for (int b = 0; b < 2; ++b) addBlock(rowNode, bondBlock(bond, a, b), K, 6 * a, 6 * b, values);
    }
  }

 private:
  template <int LocalSize, class ValuesViewT>
  KOKKOS_INLINE_FUNCTION void addBlock(LocalIndex rowNode, LocalIndex blockPosition,
                                       const double K[LocalSize][LocalSize], int firstRow, int firstColumn,
                                       const ValuesViewT& values) const {
    for (int i = 0; i < dofPerNode; ++i) {
      // The 6 columns of one block row are contiguous in values.
      const RowOffset first = slot(rowNode, i, blockPosition, 0);
      for (int j = 0; j < dofPerNode; ++j) Kokkos::atomic_add(&values(first + j), K[firstRow + i][firstColumn + j]);
    }
  }
};

template <class TargetMemorySpaceT, class SourceMemorySpaceT>
NodalBlockPattern<TargetMemorySpaceT> mirrorTo(const NodalBlockPattern<SourceMemorySpaceT>& source) {
  const TargetMemorySpaceT target;
  NodalBlockPattern<TargetMemorySpaceT> result;
  result.numNodes = source.numNodes;
  result.nodeRowMap = Kokkos::create_mirror_view_and_copy(target, source.nodeRowMap);
  result.nodeColumns = Kokkos::create_mirror_view_and_copy(target, source.nodeColumns);
  result.rowMap = Kokkos::create_mirror_view_and_copy(target, source.rowMap);
  result.columns = Kokkos::create_mirror_view_and_copy(target, source.columns);
  result.quads = Kokkos::create_mirror_view_and_copy(target, source.quads);
  result.bondNodes = Kokkos::create_mirror_view_and_copy(target, source.bondNodes);
  result.elementBlock = Kokkos::create_mirror_view_and_copy(target, source.elementBlock);
  result.bondBlock = Kokkos::create_mirror_view_and_copy(target, source.bondBlock);
  return result;
}

namespace detail {

// Exclusive scan of counts (n entries) into offsets (n + 1 entries); returns offsets(n).
template <class ExecutionSpaceT, class CountView, class OffsetView>
RowOffset blockPatternScan(const ExecutionSpaceT& space, const char* label, const CountView& counts,
                           const OffsetView& offsets) {
  const LocalIndex n = static_cast<LocalIndex>(counts.extent(0));
  Kokkos::parallel_scan(label, Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, n + 1),
                        KOKKOS_LAMBDA(const LocalIndex i, RowOffset& partial, const bool final) {
                          if (final) offsets(i) = partial;
                          if (i < n) partial += static_cast<RowOffset>(counts(i));
                        });
  RowOffset total = 0;
  Kokkos::deep_copy(space, Kokkos::View<RowOffset, Kokkos::HostSpace>(&total), Kokkos::subview(offsets, n));
  space.fence();
  return total;
}

// Restores the max-heap property of values[root .. end-1] below root.
KOKKOS_INLINE_FUNCTION void siftDown(LocalIndex* values, LocalIndex root, LocalIndex end) {
  while (2 * root + 1 < end) {
    LocalIndex child = 2 * root + 1;
    if (child + 1 < end && values[child] < values[child + 1]) ++child;
    if (!(values[root] < values[child])) return;
    const LocalIndex swapped = values[root];
    values[root] = values[child];
    values[child] = swapped;
    root = child;
  }
}

// In-place heapsort of values[0 .. length-1]: O(k log k) without scratch memory, so a node
// with hundreds of bonds costs one thread no more than a few thousand compares.
KOKKOS_INLINE_FUNCTION void heapSort(LocalIndex* values, LocalIndex length) {
  for (LocalIndex start = length / 2 - 1; start >= 0; --start) siftDown(values, start, length);
  for (LocalIndex end = length - 1; end > 0; --end) {
    const LocalIndex largest = values[0];
    values[0] = values[end];
    values[end] = largest;
    siftDown(values, 0, end);
  }
}

// Position of key in the ascending values[0 .. length-1] (the caller knows it is there).
KOKKOS_INLINE_FUNCTION LocalIndex positionInSorted(const LocalIndex* values, LocalIndex length, LocalIndex key) {
  LocalIndex low = 0, high = length;
  while (low < high) {
    const LocalIndex middle = low + (high - low) / 2;
    if (values[middle] < key)
      low = middle + 1;
    else
      high = middle;
  }
  return low;
}

// Throws std::invalid_argument naming the first quad with a node outside [0, numNodes).
template <class ExecutionSpaceT, class QuadsView>
void checkQuadNodes(const ExecutionSpaceT& space, LocalIndex numNodes, const QuadsView& quads) {
  const LocalIndex numElements = static_cast<LocalIndex>(quads.extent(0));
  LocalIndex firstBad = std::numeric_limits<LocalIndex>::max();
  Kokkos::parallel_reduce(
      "perishell::checkQuadNodes", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, numElements),
      KOKKOS_LAMBDA(const LocalIndex e, LocalIndex& first) {
        for (int a = 0; a < 4; ++a)
          if ((quads(e, a) < 0 || quads(e, a) >= numNodes) && e < first) first = e;
      },
      Kokkos::Min<LocalIndex>(firstBad));
  if (firstBad >= numElements) return;
  const auto row = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, Kokkos::subview(quads, firstBad, Kokkos::ALL));
  std::ostringstream what;
  what << "buildNodalBlockPattern: element " << firstBad << " has nodes (" << row(0) << ", " << row(1) << ", "
       << row(2) << ", " << row(3) << "); node indices must lie in [0, " << numNodes << ")";
  throw std::invalid_argument(what.str());
}

// Throws std::invalid_argument naming the first bond with an end node outside [0, numNodes)
// or, unless allowed, joining a node to itself.
template <class ExecutionSpaceT, class BondNodesView>
void checkBondNodes(const ExecutionSpaceT& space, LocalIndex numNodes, const BondNodesView& bondNodes,
                    SelfBonds selfBonds) {
  const bool selfAllowed = selfBonds == SelfBonds::Allowed;
  const LocalIndex numBonds = static_cast<LocalIndex>(bondNodes.extent(0));
  LocalIndex firstBad = std::numeric_limits<LocalIndex>::max();
  Kokkos::parallel_reduce(
      "perishell::checkBondNodes", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, numBonds),
      KOKKOS_LAMBDA(const LocalIndex k, LocalIndex& first) {
        const LocalIndex i = bondNodes(k, 0), j = bondNodes(k, 1);
        const bool bad = i < 0 || i >= numNodes || j < 0 || j >= numNodes || (i == j && !selfAllowed);
        if (bad && k < first) first = k;
      },
      Kokkos::Min<LocalIndex>(firstBad));
  if (firstBad >= numBonds) return;
  const auto ends =
      Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, Kokkos::subview(bondNodes, firstBad, Kokkos::ALL));
  std::ostringstream what;
  what << "buildNodalBlockPattern: bond " << firstBad << " (nodes " << ends(0) << ", " << ends(1) << ") ";
  if (ends(0) == ends(1))
    what << "joins node " << ends(0) << " to itself";
  else
    what << "has a node index outside [0, " << numNodes << ")";
  throw std::invalid_argument(what.str());
}

}  // namespace detail

// Builds the pattern on the device: candidate neighbours per node (self, the other 3 nodes
// of each incident quad, the other end of each incident bond) by counting, scan and atomic
// fill; per-node sort and unique; scans for the block and scalar offsets; block positions
// of each element and bond by binary search in the sorted block rows. quads or bondNodes may
// have 0 rows; a node in no element and no bond gets its diagonal block alone, so the matrix
// stays square and a Dirichlet elimination can pin its DOF. Throws std::invalid_argument for
// a node index out of range or a bond joining a node to itself (unless selfBonds allows it).
template <class ExecutionSpaceT>
NodalBlockPattern<typename ExecutionSpaceT::memory_space> buildNodalBlockPattern(
    const ExecutionSpaceT& space, LocalIndex numNodes,
    const QuadConnectivityView<typename ExecutionSpaceT::memory_space>& quads,
    const Kokkos::View<LocalIndex* [2], Kokkos::LayoutRight, typename ExecutionSpaceT::memory_space>& bondNodes,
    SelfBonds selfBonds = SelfBonds::Refused) {
  static_assert(is_execution_space_v<ExecutionSpaceT>);
  using MemorySpaceT = typename ExecutionSpaceT::memory_space;
  using Policy = Kokkos::RangePolicy<ExecutionSpaceT>;
  if (numNodes < 0)
    throw std::invalid_argument("buildNodalBlockPattern: the node count must be >= 0, got " + std::to_string(numNodes));
  // 6 numNodes scalar rows must fit LocalIndex columns.
  if (numNodes > std::numeric_limits<LocalIndex>::max() / dofPerNode)
    throw std::invalid_argument("buildNodalBlockPattern: " + std::to_string(numNodes) +
                                " nodes exceed the LocalIndex range of 6-DOF columns");
  detail::checkQuadNodes(space, numNodes, quads);
  detail::checkBondNodes(space, numNodes, bondNodes, selfBonds);
  const LocalIndex numElements = static_cast<LocalIndex>(quads.extent(0));
  const LocalIndex numBonds = static_cast<LocalIndex>(bondNodes.extent(0));

  NodalBlockPattern<MemorySpaceT> pattern;
  pattern.numNodes = numNodes;
  pattern.quads = quads;
  pattern.bondNodes = bondNodes;

  // Candidate neighbours, duplicates included.
  Kokkos::View<LocalIndex*, MemorySpaceT> candidateCount("perishell::candidateCount", numNodes);
  Kokkos::parallel_for(
      "perishell::countNodeCandidates", Policy(space, 0, numNodes),
      KOKKOS_LAMBDA(const LocalIndex node) { candidateCount(node) = 1; });
  Kokkos::parallel_for(
      "perishell::countElementCandidates", Policy(space, 0, numElements), KOKKOS_LAMBDA(const LocalIndex e) {
        for (int a = 0; a < 4; ++a) Kokkos::atomic_add(&candidateCount(quads(e, a)), 3);
      });
  Kokkos::parallel_for(
      "perishell::countBondCandidates", Policy(space, 0, numBonds), KOKKOS_LAMBDA(const LocalIndex k) {
        Kokkos::atomic_add(&candidateCount(bondNodes(k, 0)), 1);
        Kokkos::atomic_add(&candidateCount(bondNodes(k, 1)), 1);
      });
  Kokkos::View<RowOffset*, MemorySpaceT> candidateOffsets("perishell::candidateOffsets", numNodes + 1);
  const RowOffset numCandidates =
      detail::blockPatternScan(space, "perishell::scanNodeCandidates", candidateCount, candidateOffsets);

  Kokkos::View<LocalIndex*, MemorySpaceT> candidates(Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::candidates"),
                                                     numCandidates);
  Kokkos::View<LocalIndex*, MemorySpaceT> filled("perishell::candidatesFilled", numNodes);
  Kokkos::parallel_for(
      "perishell::fillNodeCandidates", Policy(space, 0, numNodes), KOKKOS_LAMBDA(const LocalIndex node) {
        candidates(candidateOffsets(node)) = node;
        filled(node) = 1;
      });
  Kokkos::parallel_for(
      "perishell::fillElementCandidates", Policy(space, 0, numElements), KOKKOS_LAMBDA(const LocalIndex e) {
        for (int a = 0; a < 4; ++a) {
          const LocalIndex node = quads(e, a);
          const RowOffset first = candidateOffsets(node) + Kokkos::atomic_fetch_add(&filled(node), 3);
          int written = 0;
          for (int b = 0; b < 4; ++b)
            if (b != a) candidates(first + written++) = quads(e, b);
        }
      });
  Kokkos::parallel_for(
      "perishell::fillBondCandidates", Policy(space, 0, numBonds), KOKKOS_LAMBDA(const LocalIndex k) {
        for (int a = 0; a < 2; ++a) {
          const LocalIndex node = bondNodes(k, a);
          candidates(candidateOffsets(node) + Kokkos::atomic_fetch_add(&filled(node), 1)) = bondNodes(k, 1 - a);
        }
      });

  // Sort and unique each node's candidates in place; candidateCount becomes the block count.
  Kokkos::parallel_for(
      "perishell::uniqueNodeCandidates", Policy(space, 0, numNodes), KOKKOS_LAMBDA(const LocalIndex node) {
        LocalIndex* row = candidates.data() + candidateOffsets(node);
        const LocalIndex length = static_cast<LocalIndex>(candidateOffsets(node + 1) - candidateOffsets(node));
        detail::heapSort(row, length);
        LocalIndex distinct = 1;
        for (LocalIndex i = 1; i < length; ++i)
          if (row[i] != row[distinct - 1]) row[distinct++] = row[i];
        candidateCount(node) = distinct;
      });
  pattern.nodeRowMap = Kokkos::View<RowOffset*, MemorySpaceT>("perishell::nodeRowMap", numNodes + 1);
  const RowOffset numBlocks =
      detail::blockPatternScan(space, "perishell::scanNodeBlocks", candidateCount, pattern.nodeRowMap);
  pattern.nodeColumns = Kokkos::View<LocalIndex*, MemorySpaceT>(
      Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::nodeColumns"), numBlocks);
  const auto nodeRowMap = pattern.nodeRowMap;
  const auto nodeColumns = pattern.nodeColumns;
  Kokkos::parallel_for(
      "perishell::copyNodeColumns", Policy(space, 0, numNodes), KOKKOS_LAMBDA(const LocalIndex node) {
        const RowOffset from = candidateOffsets(node);
        for (RowOffset p = nodeRowMap(node); p < nodeRowMap(node + 1); ++p)
          nodeColumns(p) = candidates(from + (p - nodeRowMap(node)));
      });

  // Scalar CRS: rows of node n are 6 n .. 6 n + 5, each 6 len(n) long (header comment).
  const LocalIndex numRows = dofPerNode * numNodes;
  pattern.rowMap = Kokkos::View<RowOffset*, MemorySpaceT>("perishell::blockCrsRowMap", numRows + 1);
  pattern.columns = Kokkos::View<LocalIndex*, MemorySpaceT>(
      Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::blockCrsColumns"),
      dofPerNode * dofPerNode * numBlocks);
  const auto rowMap = pattern.rowMap;
  const auto columns = pattern.columns;
  Kokkos::parallel_for(
      "perishell::fillBlockCrs", Policy(space, 0, numRows + 1), KOKKOS_LAMBDA(const LocalIndex row) {
        if (row == numRows) {
          rowMap(row) = dofPerNode * dofPerNode * nodeRowMap(numNodes);
          return;
        }
        const LocalIndex node = row / dofPerNode;
        const RowOffset blockStart = nodeRowMap(node), blockLength = nodeRowMap(node + 1) - blockStart;
        const RowOffset start = dofPerNode * dofPerNode * blockStart + (row % dofPerNode) * dofPerNode * blockLength;
        rowMap(row) = start;
        for (RowOffset p = 0; p < blockLength; ++p)
          for (int d = 0; d < dofPerNode; ++d)
            columns(start + dofPerNode * p + d) = dofPerNode * nodeColumns(blockStart + p) + d;
      });

  pattern.elementBlock = decltype(pattern.elementBlock)(
      Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::elementBlock"), numElements);
  const auto elementBlock = pattern.elementBlock;
  Kokkos::parallel_for(
      "perishell::findElementBlocks", Policy(space, 0, numElements), KOKKOS_LAMBDA(const LocalIndex e) {
        for (int a = 0; a < 4; ++a) {
          const LocalIndex node = quads(e, a);
          const LocalIndex* row = nodeColumns.data() + nodeRowMap(node);
          const LocalIndex length = static_cast<LocalIndex>(nodeRowMap(node + 1) - nodeRowMap(node));
          for (int b = 0; b < 4; ++b) elementBlock(e, a, b) = detail::positionInSorted(row, length, quads(e, b));
        }
      });
  pattern.bondBlock =
      decltype(pattern.bondBlock)(Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::bondBlock"), numBonds);
  const auto bondBlock = pattern.bondBlock;
  Kokkos::parallel_for(
      "perishell::findBondBlocks", Policy(space, 0, numBonds), KOKKOS_LAMBDA(const LocalIndex k) {
        for (int a = 0; a < 2; ++a) {
          const LocalIndex node = bondNodes(k, a);
          const LocalIndex* row = nodeColumns.data() + nodeRowMap(node);
          const LocalIndex length = static_cast<LocalIndex>(nodeRowMap(node + 1) - nodeRowMap(node));
          for (int b = 0; b < 2; ++b) bondBlock(k, a, b) = detail::positionInSorted(row, length, bondNodes(k, b));
        }
      });
  space.fence();
  return pattern;
}

}  // namespace perishell::assembly
