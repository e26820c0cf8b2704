// The 6-DOF nodal block pattern of the global tangent (paper §3.2.1), built on the device:
// its block graph against a brute-force std::set construction, atomic element and bond
// assembly against a dense host assembly, PD-only / CCM-only / isolated-node patterns, the
// inhomogeneous symmetric Dirichlet elimination against a reduced dense solve, and bad input.
#include <perishell/assembly/dirichlet.hpp>
#include <perishell/assembly/nodal_block_crs.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <set>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

// Device code sits in free functions of a named namespace: nvcc rejects KOKKOS_LAMBDA inside
// a TEST body, which gtest makes a private member function.
namespace perishell_test_nodal_block_crs {

using perishell::LocalIndex;
using perishell::RowOffset;
using perishell::assembly::NodalBlockPattern;
using MemorySpace = TEST_EXECSPACE::memory_space;
using HostQuads = perishell::QuadConnectivityView<Kokkos::HostSpace>;
using HostBonds = Kokkos::View<LocalIndex* [2], Kokkos::LayoutRight, Kokkos::HostSpace>;
using HostPattern = NodalBlockPattern<Kokkos::HostSpace>;
using DenseMatrix = std::vector<std::vector<double>>;
constexpr int dof = perishell::assembly::dofPerNode;

// A cellsX x cellsY plate of quads, nodes row by row (x fastest), corners counter-clockwise.
HostQuads plateQuads(int cellsX, int cellsY) {
  HostQuads quads("plate quads", cellsX * cellsY);
  for (int j = 0; j < cellsY; ++j)
    for (int i = 0; i < cellsX; ++i) {
      const int e = j * cellsX + i, first = j * (cellsX + 1) + i;
      quads(e, 0) = first;
      quads(e, 1) = first + 1;
      quads(e, 2) = first + cellsX + 2;
      quads(e, 3) = first + cellsX + 1;
    }
  return quads;
}

HostBonds makeBonds(const std::vector<std::pair<LocalIndex, LocalIndex>>& pairs) {
  HostBonds bonds("bonds", pairs.size());
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    bonds(k, 0) = pairs[k].first;
    bonds(k, 1) = pairs[k].second;
  }
  return bonds;
}

// The 3 x 2 plate (12 nodes) with bonds: (0,11), (3,8) and (0,2) join nodes that share no
// element, (5,10) and (6,7) nodes that do.
HostBonds plateBonds() { return makeBonds({{0, 11}, {3, 8}, {0, 2}, {5, 10}, {6, 7}}); }

NodalBlockPattern<MemorySpace> buildOnDevice(LocalIndex numNodes, const HostQuads& quads, const HostBonds& bonds) {
  return perishell::assembly::buildNodalBlockPattern(TEST_EXECSPACE{}, numNodes,
                                                     Kokkos::create_mirror_view_and_copy(MemorySpace{}, quads),
                                                     Kokkos::create_mirror_view_and_copy(MemorySpace{}, bonds));
}

std::vector<std::set<LocalIndex>> bruteForceAdjacency(LocalIndex numNodes, const HostQuads& quads,
                                                      const HostBonds& bonds) {
  std::vector<std::set<LocalIndex>> adjacency(numNodes);
  for (LocalIndex n = 0; n < numNodes; ++n) adjacency[n].insert(n);
  for (std::size_t e = 0; e < quads.extent(0); ++e)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) adjacency[quads(e, a)].insert(quads(e, b));
  for (std::size_t k = 0; k < bonds.extent(0); ++k)
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b) adjacency[bonds(k, a)].insert(bonds(k, b));
  return adjacency;
}

// Every structural property the assembly relies on, checked on a host copy of the pattern.
void expectConsistentPattern(const HostPattern& pattern, const std::vector<std::set<LocalIndex>>& adjacency) {
  const LocalIndex numNodes = pattern.numNodes;
  ASSERT_EQ(pattern.nodeRowMap.extent(0), std::size_t(numNodes + 1));
  ASSERT_EQ(pattern.rowMap.extent(0), std::size_t(dof * numNodes + 1));
  RowOffset blocks = 0;
  for (LocalIndex n = 0; n < numNodes; ++n) {
    ASSERT_EQ(pattern.nodeRowMap(n), blocks) << "node " << n;
    const std::vector<LocalIndex> expected(adjacency[n].begin(), adjacency[n].end());
    const std::vector<LocalIndex> got(pattern.nodeColumns.data() + pattern.nodeRowMap(n),
                                      pattern.nodeColumns.data() + pattern.nodeRowMap(n + 1));
    EXPECT_EQ(got, expected) << "block row of node " << n;
    blocks += expected.size();
  }
  ASSERT_EQ(pattern.nodeRowMap(numNodes), blocks);
  ASSERT_EQ(pattern.numEntries(), 36 * blocks);
  EXPECT_EQ(pattern.rowMap(dof * numNodes), 36 * blocks);

  for (LocalIndex n = 0; n < numNodes; ++n) {
    const LocalIndex length = static_cast<LocalIndex>(pattern.nodeRowMap(n + 1) - pattern.nodeRowMap(n));
    for (int d = 0; d < dof; ++d) {
      const LocalIndex row = dof * n + d;
      ASSERT_EQ(pattern.rowMap(row + 1) - pattern.rowMap(row), RowOffset(dof * length)) << "row " << row;
      for (RowOffset s = pattern.rowMap(row) + 1; s < pattern.rowMap(row + 1); ++s)
        ASSERT_LT(pattern.columns(s - 1), pattern.columns(s)) << "row " << row;
      for (LocalIndex p = 0; p < length; ++p)
        for (int c = 0; c < dof; ++c) {
          const RowOffset s = pattern.slot(n, d, p, c);
          ASSERT_GE(s, pattern.rowMap(row));
          ASSERT_LT(s, pattern.rowMap(row + 1));
          ASSERT_EQ(pattern.columns(s), dof * pattern.nodeColumns(pattern.nodeRowMap(n) + p) + c);
        }
    }
  }
  for (std::size_t e = 0; e < pattern.quads.extent(0); ++e)
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b)
        EXPECT_EQ(pattern.nodeColumns(pattern.nodeRowMap(pattern.quads(e, a)) + pattern.elementBlock(e, a, b)),
                  pattern.quads(e, b))
            << "element " << e << " (" << a << ", " << b << ")";
  for (std::size_t k = 0; k < pattern.bondNodes.extent(0); ++k)
    for (int a = 0; a < 2; ++a)
      for (int b = 0; b < 2; ++b)
        EXPECT_EQ(pattern.nodeColumns(pattern.nodeRowMap(pattern.bondNodes(k, a)) + pattern.bondBlock(k, a, b)),
                  pattern.bondNodes(k, b))
            << "bond " << k << " (" << a << ", " << b << ")";
}

// Deterministic pseudo-random numbers in [-1, 1), the same on host and device (splitmix64).
KOKKOS_INLINE_FUNCTION double pseudoRandom(std::uint64_t key) {
  std::uint64_t z = key + 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * (2.0 / 9007199254740992.0) - 1.0;
}

// Entry (i, j) of the local matrix of item `index` (salt 1: elements, 2: bonds). Symmetric
// matrices get a diagonal shift above the largest off-diagonal row sum (size - 1), so they
// are strictly diagonally dominant and their assembly is symmetric positive definite.
KOKKOS_INLINE_FUNCTION double localEntry(int salt, int index, int size, int i, int j, bool symmetric) {
  if (symmetric && i > j) {
    const int swapped = i;
    i = j;
    j = swapped;
  }
  const std::uint64_t key = ((std::uint64_t(salt) * 1000003u + std::uint64_t(index)) * 64u + i) * 64u + j;
  return pseudoRandom(key) + ((symmetric && i == j) ? double(size) : 0.0);
}

void assembleOnDevice(const NodalBlockPattern<MemorySpace>& pattern, const perishell::VectorView<MemorySpace>& values,
                      bool symmetric) {
  using Policy = Kokkos::RangePolicy<TEST_EXECSPACE>;
  Kokkos::parallel_for(
      "assemble_elements", Policy(0, static_cast<int>(pattern.quads.extent(0))), KOKKOS_LAMBDA(const int e) {
        double K[24][24];
        for (int i = 0; i < 24; ++i)
          for (int j = 0; j < 24; ++j) K[i][j] = localEntry(1, e, 24, i, j, symmetric);
        pattern.atomicAddElementMatrix(e, K, values);
      });
  Kokkos::parallel_for(
      "assemble_bonds", Policy(0, static_cast<int>(pattern.bondNodes.extent(0))), KOKKOS_LAMBDA(const int k) {
        double K[12][12];
        for (int i = 0; i < 12; ++i)
          for (int j = 0; j < 12; ++j) K[i][j] = localEntry(2, k, 12, i, j, symmetric);
        pattern.atomicAddBondMatrix(k, K, values);
      });
  Kokkos::fence();
}

DenseMatrix denseAssembly(LocalIndex numNodes, const HostQuads& quads, const HostBonds& bonds, bool symmetric) {
  DenseMatrix K(dof * numNodes, std::vector<double>(dof * numNodes, 0.0));
  for (std::size_t e = 0; e < quads.extent(0); ++e)
    for (int i = 0; i < 24; ++i)
      for (int j = 0; j < 24; ++j)
        K[dof * quads(e, i / dof) + i % dof][dof * quads(e, j / dof) + j % dof] +=
            localEntry(1, int(e), 24, i, j, symmetric);
  for (std::size_t k = 0; k < bonds.extent(0); ++k)
    for (int i = 0; i < 12; ++i)
      for (int j = 0; j < 12; ++j)
        K[dof * bonds(k, i / dof) + i % dof][dof * bonds(k, j / dof) + j % dof] +=
            localEntry(2, int(k), 12, i, j, symmetric);
  return K;
}

DenseMatrix crsToDense(const HostPattern& pattern, const Kokkos::View<double*, Kokkos::HostSpace>& values) {
  const int numRows = dof * pattern.numNodes;
  DenseMatrix K(numRows, std::vector<double>(numRows, 0.0));
  for (int row = 0; row < numRows; ++row)
    for (RowOffset s = pattern.rowMap(row); s < pattern.rowMap(row + 1); ++s) K[row][pattern.columns(s)] = values(s);
  return K;
}

double maxAbsDifference(const DenseMatrix& a, const DenseMatrix& b) {
  double largest = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < a.size(); ++j) largest = std::max(largest, std::abs(a[i][j] - b[i][j]));
  return largest;
}

// Assembles random local matrices through the pattern and returns max |CRS - dense|.
double assemblyError(LocalIndex numNodes, const HostQuads& quads, const HostBonds& bonds) {
  const auto pattern = buildOnDevice(numNodes, quads, bonds);
  perishell::VectorView<MemorySpace> values("values", pattern.numEntries());
  assembleOnDevice(pattern, values, /*symmetric=*/false);
  const auto hostPattern = perishell::assembly::mirrorTo<Kokkos::HostSpace>(pattern);
  const auto hostValues = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, values);
  return maxAbsDifference(crsToDense(hostPattern, hostValues), denseAssembly(numNodes, quads, bonds, false));
}

// Gaussian elimination with partial pivoting.
std::vector<double> denseSolve(DenseMatrix A, std::vector<double> b) {
  const std::size_t n = b.size();
  for (std::size_t k = 0; k < n; ++k) {
    std::size_t pivot = k;
    for (std::size_t i = k + 1; i < n; ++i)
      if (std::abs(A[i][k]) > std::abs(A[pivot][k])) pivot = i;
    std::swap(A[k], A[pivot]);
    std::swap(b[k], b[pivot]);
    for (std::size_t i = k + 1; i < n; ++i) {
      const double factor = A[i][k] / A[k][k];
      if (factor == 0.0) continue;
      for (std::size_t j = k; j < n; ++j) A[i][j] -= factor * A[k][j];
      b[i] -= factor * b[k];
    }
  }
  std::vector<double> x(n);
  for (std::size_t k = n; k-- > 0;) {
    double sum = b[k];
    for (std::size_t j = k + 1; j < n; ++j) sum -= A[k][j] * x[j];
    x[k] = sum / A[k][k];
  }
  return x;
}

template <class Build>
std::string exceptionMessage(Build build) {
  try {
    build();
  } catch (const std::invalid_argument& error) {
    return error.what();
  }
  return "(no std::invalid_argument thrown)";
}

TEST(TEST_CATEGORY, nodal_block_pattern_plate_with_bonds_matches_brute_force) {
  const LocalIndex numNodes = 12;
  const auto quads = plateQuads(3, 2);
  const auto bonds = plateBonds();
  const auto pattern = perishell::assembly::mirrorTo<Kokkos::HostSpace>(buildOnDevice(numNodes, quads, bonds));
  // Quads alone: node (i, j) couples to its 3x3 window, sum (2+3+3+2)(2+3+2) = 70 blocks;
  // the bonds (0,11), (3,8), (0,2) add 2 blocks each, (5,10) and (6,7) none.
  EXPECT_EQ(pattern.numBlocks(), RowOffset(76));
  EXPECT_EQ(pattern.numEntries(), RowOffset(36 * 76));
  EXPECT_EQ(pattern.numRows(), 72);
  expectConsistentPattern(pattern, bruteForceAdjacency(numNodes, quads, bonds));
  // Node 0: its element's nodes 0, 1, 4, 5 and bond partners 2 and 11.
  const std::vector<LocalIndex> nodeZero(pattern.nodeColumns.data(), pattern.nodeColumns.data() + pattern.nodeRowMap(1));
  EXPECT_EQ(nodeZero, (std::vector<LocalIndex>{0, 1, 2, 4, 5, 11}));
}

TEST(TEST_CATEGORY, nodal_block_atomic_assembly_matches_dense_assembly) {
  const double error = assemblyError(12, plateQuads(3, 2), plateBonds());
  EXPECT_LT(error, 1e-12);
  // A larger plate, where many threads hit the same blocks at once.
  const int cells = 12;
  std::vector<std::pair<LocalIndex, LocalIndex>> pairs;
  const int side = cells + 1;
  for (int node = 0; node + 2 * side + 1 < side * side; node += 3) pairs.push_back({node, node + 2 * side + 1});
  const double largeError = assemblyError(side * side, plateQuads(cells, cells), makeBonds(pairs));
  EXPECT_LT(largeError, 1e-12);
}

TEST(TEST_CATEGORY, nodal_block_pattern_pd_only_ccm_only_and_isolated_nodes) {
  // PD only: bonds (0,1), (1,2), (3,1); node 4 is in no bond.
  const HostQuads noQuads("no quads", 0);
  const auto bonds = makeBonds({{0, 1}, {1, 2}, {3, 1}});
  const auto pdOnly = perishell::assembly::mirrorTo<Kokkos::HostSpace>(buildOnDevice(5, noQuads, bonds));
  const std::vector<RowOffset> rowMap(pdOnly.nodeRowMap.data(), pdOnly.nodeRowMap.data() + 6);
  const std::vector<LocalIndex> columns(pdOnly.nodeColumns.data(), pdOnly.nodeColumns.data() + pdOnly.numBlocks());
  EXPECT_EQ(rowMap, (std::vector<RowOffset>{0, 2, 6, 8, 10, 11}));
  EXPECT_EQ(columns, (std::vector<LocalIndex>{0, 1, 0, 1, 2, 3, 1, 2, 1, 3, 4}));
  expectConsistentPattern(pdOnly, bruteForceAdjacency(5, noQuads, bonds));
  EXPECT_LT(assemblyError(5, noQuads, bonds), 1e-12);

  // CCM only, plus node 12 in no element: its block row is its diagonal block alone.
  const HostBonds noBonds("no bonds", 0);
  const auto quads = plateQuads(3, 2);
  const auto ccmOnly = perishell::assembly::mirrorTo<Kokkos::HostSpace>(buildOnDevice(13, quads, noBonds));
  EXPECT_EQ(ccmOnly.numBlocks(), RowOffset(71));
  EXPECT_EQ(ccmOnly.nodeRowMap(13) - ccmOnly.nodeRowMap(12), RowOffset(1));
  EXPECT_EQ(ccmOnly.nodeColumns(ccmOnly.nodeRowMap(12)), 12);
  EXPECT_EQ(ccmOnly.columns(ccmOnly.rowMap(dof * 12 + 3) + 5), dof * 12 + 5);
  expectConsistentPattern(ccmOnly, bruteForceAdjacency(13, quads, noBonds));
  EXPECT_LT(assemblyError(13, quads, noBonds), 1e-12);

  // Neither: a block diagonal of 3 nodes, 3 x 36 entries.
  const auto diagonal = perishell::assembly::mirrorTo<Kokkos::HostSpace>(buildOnDevice(3, noQuads, noBonds));
  EXPECT_EQ(diagonal.numBlocks(), RowOffset(3));
  EXPECT_EQ(diagonal.numEntries(), RowOffset(108));
  expectConsistentPattern(diagonal, bruteForceAdjacency(3, noQuads, noBonds));
}

TEST(TEST_CATEGORY, eliminate_dirichlet_solves_to_prescribed_values_and_the_reduced_system) {
  // Plate and bonds on nodes 0..11 (an SPD assembly) and node 12 in nothing: its diagonal is
  // 0, so elimination must fall back to 1 there.
  const LocalIndex numNodes = 13;
  const int n = dof * numNodes;
  const auto quads = plateQuads(3, 2);
  const auto bonds = plateBonds();
  const auto pattern = buildOnDevice(numNodes, quads, bonds);
  perishell::VectorView<MemorySpace> values("values", pattern.numEntries());
  assembleOnDevice(pattern, values, /*symmetric=*/true);
  const auto hostPattern = perishell::assembly::mirrorTo<Kokkos::HostSpace>(pattern);
  const DenseMatrix assembled =
      crsToDense(hostPattern, Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, values));

  std::vector<int> constrainedDof;
  for (int d = 0; d < dof; ++d) constrainedDof.insert(constrainedDof.end(), {dof * 0 + d, dof * 12 + d});
  constrainedDof.insert(constrainedDof.end(), {dof * 3 + 2, dof * 7 + 2, dof * 9 + 5});
  Kokkos::View<bool*, Kokkos::HostSpace> hostConstrained("constrained", n);
  Kokkos::View<double*, Kokkos::HostSpace> hostPrescribed("prescribed", n);
  std::vector<double> load(n);
  for (int i = 0; i < n; ++i) {
    load[i] = pseudoRandom(7000 + i);
    hostPrescribed(i) = 1e3;  // ignored on free DOF
  }
  for (int c : constrainedDof) {
    hostConstrained(c) = true;
    hostPrescribed(c) = 0.01 * pseudoRandom(9000 + c);
  }
  const auto isConstrained = Kokkos::create_mirror_view_and_copy(MemorySpace{}, hostConstrained);
  const auto prescribed = Kokkos::create_mirror_view_and_copy(MemorySpace{}, hostPrescribed);
  perishell::VectorView<MemorySpace> rhs("rhs", n);
  Kokkos::deep_copy(rhs, Kokkos::View<double*, Kokkos::HostSpace>(load.data(), n));
  perishell::assembly::eliminateDirichlet(TEST_EXECSPACE{}, pattern.rowMap, pattern.columns, values, rhs,
                                          isConstrained, prescribed);
  const DenseMatrix eliminated =
      crsToDense(hostPattern, Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, values));
  const auto eliminatedRhs = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, rhs);

  double asymmetry = 0.0, scale = 0.0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      asymmetry = std::max(asymmetry, std::abs(eliminated[i][j] - eliminated[j][i]));
      scale = std::max(scale, std::abs(eliminated[i][j]));
    }
  EXPECT_LE(asymmetry, 1e-14 * scale);  // only the round-off of atomic accumulation order
  for (int c : constrainedDof) {
    for (int j = 0; j < n; ++j)
      if (j != c) {
        ASSERT_EQ(eliminated[c][j], 0.0) << "row " << c;
        ASSERT_EQ(eliminated[j][c], 0.0) << "column " << c;
      }
    const double expectedDiagonal = c >= dof * 12 ? 1.0 : assembled[c][c];
    EXPECT_EQ(eliminated[c][c], expectedDiagonal) << "DOF " << c;
    EXPECT_EQ(eliminatedRhs(c), expectedDiagonal * hostPrescribed(c)) << "DOF " << c;
  }
  EXPECT_GT(eliminated[0][0], 20.0);  // the assembled diagonal, not 1

  const std::vector<double> x = denseSolve(eliminated, std::vector<double>(eliminatedRhs.data(), eliminatedRhs.data() + n));
  for (int c : constrainedDof) EXPECT_DOUBLE_EQ(x[c], hostPrescribed(c)) << "DOF " << c;

  // Reduced system on the free DOF: K_FF x_F = f_F - K_FC u_C, from the assembled matrix.
  std::vector<int> freeDof;
  for (int i = 0; i < n; ++i)
    if (!hostConstrained(i)) freeDof.push_back(i);
  ASSERT_EQ(freeDof.size(), std::size_t(n - 15));
  DenseMatrix reduced(freeDof.size(), std::vector<double>(freeDof.size()));
  std::vector<double> reducedRhs(freeDof.size());
  for (std::size_t a = 0; a < freeDof.size(); ++a) {
    reducedRhs[a] = load[freeDof[a]];
    for (int c : constrainedDof) reducedRhs[a] -= assembled[freeDof[a]][c] * hostPrescribed(c);
    for (std::size_t b = 0; b < freeDof.size(); ++b) reduced[a][b] = assembled[freeDof[a]][freeDof[b]];
  }
  const std::vector<double> xFree = denseSolve(reduced, reducedRhs);
  double largestFree = 0.0, largestDifference = 0.0;
  for (std::size_t a = 0; a < freeDof.size(); ++a) {
    largestFree = std::max(largestFree, std::abs(xFree[a]));
    largestDifference = std::max(largestDifference, std::abs(x[freeDof[a]] - xFree[a]));
  }
  EXPECT_GT(largestFree, 1e-3);
  EXPECT_LE(largestDifference, 1e-10 * largestFree);
}

TEST(TEST_CATEGORY, nodal_block_pattern_rejects_bad_nodes_naming_the_item) {
  const HostBonds noBonds("no bonds", 0);
  const HostQuads noQuads("no quads", 0);
  auto quads = plateQuads(3, 2);
  quads(1, 2) = 12;  // 12 nodes: indices 0..11
  const std::string outOfRangeElement = exceptionMessage([&] { buildOnDevice(12, quads, noBonds); });
  EXPECT_NE(outOfRangeElement.find("element 1 has nodes (1, 2, 12, 5)"), std::string::npos) << outOfRangeElement;
  EXPECT_NE(outOfRangeElement.find("[0, 12)"), std::string::npos) << outOfRangeElement;

  const std::string outOfRangeBond =
      exceptionMessage([&] { buildOnDevice(12, noQuads, makeBonds({{0, 1}, {2, 3}, {4, -1}, {5, 12}})); });
  EXPECT_NE(outOfRangeBond.find("bond 2 (nodes 4, -1) has a node index outside [0, 12)"), std::string::npos)
      << outOfRangeBond;

  const std::string selfBond = exceptionMessage([&] { buildOnDevice(12, noQuads, makeBonds({{0, 1}, {3, 3}})); });
  EXPECT_NE(selfBond.find("bond 1 (nodes 3, 3) joins node 3 to itself"), std::string::npos) << selfBond;
}

}  // namespace perishell_test_nodal_block_crs
