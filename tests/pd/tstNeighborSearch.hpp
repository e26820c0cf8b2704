// The device bond list against O(N^2) brute force on the host: the same bond set (exact
// lists), symmetric rows, consistent full/half maps, exact counts on a lattice, the
// partial-volume factor, pre-cracks, and rejected inputs.
#include <perishell/mesh/quad_mesh.hpp>
#include <perishell/pd/make_body.hpp>
#include <perishell/pd/neighbor_search.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace {

using HostPositions = perishell::CoordinateView<Kokkos::HostSpace>;
using HostBondList = perishell::pd::BondList<Kokkos::HostSpace>;
using Bond = std::pair<int, int>;
using Cut = std::function<bool(const HostPositions&, int, int)>;

HostBondList buildOnDevice(const HostPositions& positions, const double horizon, const double gridSpacing,
                           const std::vector<perishell::mesh::CrackSegment>& cracks = {}) {
  Kokkos::View<perishell::mesh::CrackSegment*, Kokkos::HostSpace> hostCracks("cracks", cracks.size());
  for (std::size_t c = 0; c < cracks.size(); ++c) hostCracks(c) = cracks[c];
  const auto devicePositions = Kokkos::create_mirror_view_and_copy(TEST_MEMSPACE{}, positions);
  const auto deviceCracks = Kokkos::create_mirror_view_and_copy(TEST_MEMSPACE{}, hostCracks);
  const auto bonds =
      perishell::pd::buildBondList(TEST_EXECSPACE{}, devicePositions, horizon, gridSpacing, deviceCracks);
  return perishell::pd::mirrorTo<Kokkos::HostSpace>(bonds);
}

double distance(const HostPositions& x, const int i, const int j) {
  double squared = 0.0;
  for (int d = 0; d < 3; ++d) squared += (x(j, d) - x(i, d)) * (x(j, d) - x(i, d));
  return std::sqrt(squared);
}

// All pairs i < j within the horizon (with the documented 1e-10 relative tolerance), minus
// those `isCut` removes; sorted by (i, j).
std::vector<Bond> bruteForceBonds(const HostPositions& x, const double horizon, const Cut& isCut = {}) {
  std::vector<Bond> bonds;
  const int n = static_cast<int>(x.extent(0));
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j)
      if (distance(x, i, j) <= horizon * (1.0 + 1e-10) && !(isCut && isCut(x, i, j))) bonds.emplace_back(i, j);
  return bonds;
}

std::vector<Bond> halfBondsOf(const HostBondList& bonds) {
  std::vector<Bond> half;
  for (std::size_t b = 0; b < bonds.numBonds(); ++b) half.emplace_back(bonds.halfBonds(b, 0), bonds.halfBonds(b, 1));
  return half;
}

std::vector<int> rowOf(const HostBondList& bonds, const int node) {
  return {bonds.neighbours.data() + bonds.offsets(node), bonds.neighbours.data() + bonds.offsets(node + 1)};
}

bool hasBond(const HostBondList& bonds, const int i, const int j) {
  const auto row = rowOf(bonds, i);
  return std::binary_search(row.begin(), row.end(), j);
}

double expectedVolumeFactor(const double xi, const double horizon, const double gridSpacing) {
  if (xi <= horizon - 0.5 * gridSpacing) return 1.0;
  return (horizon + 0.5 * gridSpacing - std::min(xi, horizon)) / gridSpacing;
}

// Everything a correct list must satisfy given the reference bond set.
void expectMatchesReference(const HostBondList& bonds, const HostPositions& x, const double horizon,
                            const double gridSpacing, const std::vector<Bond>& reference) {
  const int n = static_cast<int>(x.extent(0));
  ASSERT_EQ(bonds.numNodes(), n);
  ASSERT_EQ(bonds.numBonds(), reference.size());
  ASSERT_EQ(bonds.numFullEntries(), 2 * reference.size());
  ASSERT_EQ(bonds.offsets(n), 2 * reference.size());
  EXPECT_TRUE(halfBondsOf(bonds) == reference) << "half list differs from brute force";

  std::vector<std::vector<int>> referenceRows(n);
  for (const auto& [i, j] : reference) {
    referenceRows[i].push_back(j);
    referenceRows[j].push_back(i);
  }
  std::vector<int> referencesPerHalfBond(reference.size(), 0);
  for (int i = 0; i < n; ++i) {
    std::sort(referenceRows[i].begin(), referenceRows[i].end());
    EXPECT_EQ(rowOf(bonds, i), referenceRows[i]) << "row of node " << i;
    for (auto k = bonds.offsets(i); k < bonds.offsets(i + 1); ++k) {
      const int j = bonds.neighbours(k);
      EXPECT_TRUE(hasBond(bonds, j, i)) << "asymmetric: " << j << " in row " << i;
      const auto half = bonds.fullToHalf(k);
      ASSERT_LT(half, bonds.numBonds());
      EXPECT_EQ(bonds.halfBonds(half, 0), std::min(i, j));
      EXPECT_EQ(bonds.halfBonds(half, 1), std::max(i, j));
      ++referencesPerHalfBond[half];
    }
  }
  EXPECT_TRUE(std::all_of(referencesPerHalfBond.begin(), referencesPerHalfBond.end(), [](int c) { return c == 2; }));

  for (std::size_t b = 0; b < bonds.numBonds(); ++b) {
    const double xi = distance(x, bonds.halfBonds(b, 0), bonds.halfBonds(b, 1));
    EXPECT_NEAR(bonds.referenceLength(b), xi, 1e-15 * horizon) << "bond " << b;
    EXPECT_NEAR(bonds.volumeFactor(b), expectedVolumeFactor(xi, horizon, gridSpacing), 1e-12) << "bond " << b;
    EXPECT_GT(bonds.volumeFactor(b), 0.0);
    EXPECT_LE(bonds.volumeFactor(b), 1.0);
  }
}

HostPositions makeLattice(const int nodesX, const int nodesY, const double spacing) {
  HostPositions x("lattice", nodesX * nodesY);
  for (int j = 0; j < nodesY; ++j)
    for (int i = 0; i < nodesX; ++i) {
      x(j * nodesX + i, 0) = i * spacing;
      x(j * nodesX + i, 1) = j * spacing;
      x(j * nodesX + i, 2) = 0.0;
    }
  return x;
}

TEST(TEST_CATEGORY, bond_list_square_lattice_matches_brute_force_and_exact_counts) {
  const int nodesX = 30, nodesY = 20, m = 3;
  const double dx = 0.01, horizon = m * dx;
  const auto x = makeLattice(nodesX, nodesY, dx);
  const auto bonds = buildOnDevice(x, horizon, dx);
  expectMatchesReference(bonds, x, horizon, dx, bruteForceBonds(x, horizon));

  // Exact counts from integer lattice offsets (a, b) with a^2 + b^2 <= m^2.
  int interiorNeighbours = 0, cornerNeighbours = 0;
  long exactBonds = 0;
  for (int a = -m; a <= m; ++a)
    for (int b = -m; b <= m; ++b) {
      if ((a == 0 && b == 0) || a * a + b * b > m * m) continue;
      ++interiorNeighbours;
      cornerNeighbours += a >= 0 && b >= 0;
      exactBonds += (nodesX - std::abs(a)) * (nodesY - std::abs(b));
    }
  exactBonds /= 2;  // every offset counted with its opposite
  EXPECT_EQ(interiorNeighbours, 28);
  EXPECT_EQ(static_cast<long>(bonds.numBonds()), exactBonds);
  const int centre = 10 * nodesX + 15;
  EXPECT_EQ(static_cast<int>(bonds.offsets(centre + 1) - bonds.offsets(centre)), interiorNeighbours);
  EXPECT_EQ(static_cast<int>(bonds.offsets(1) - bonds.offsets(0)), cornerNeighbours);  // node (0, 0)

  // Partial-volume factors of the centre node's bonds by offset.
  const auto factor = [&](int a, int b) {
    const int j = centre + b * nodesX + a;
    const auto lo = std::min(centre, j), hi = std::max(centre, j);
    for (auto k = bonds.offsets(lo); k < bonds.offsets(lo + 1); ++k)
      if (bonds.neighbours(k) == hi) return bonds.volumeFactor(bonds.fullToHalf(k));
    return -1.0;
  };
  EXPECT_DOUBLE_EQ(factor(1, 0), 1.0);
  EXPECT_DOUBLE_EQ(factor(2, -1), 1.0);                      // sqrt(5) dx < 2.5 dx
  EXPECT_NEAR(factor(2, 2), 3.5 - 2.0 * std::sqrt(2.0), 1e-12);  // 2 sqrt(2) dx in the outer half cell
  EXPECT_NEAR(factor(3, 0), 0.5, 1e-9);                      // exactly at delta
  EXPECT_NEAR(factor(0, -3), 0.5, 1e-9);
  EXPECT_EQ(factor(3, 1), -1.0);                             // sqrt(10) dx > delta: no bond
}

HostPositions randomPoints(const int n, const unsigned seed,
                           const std::function<void(std::mt19937&, double*)>& place) {
  HostPositions x("random points", n);
  std::mt19937 generator(seed);
  for (int i = 0; i < n; ++i) {
    double p[3];
    place(generator, p);
    for (int d = 0; d < 3; ++d) x(i, d) = p[d];
  }
  return x;
}

TEST(TEST_CATEGORY, bond_list_random_box_matches_brute_force) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto x = randomPoints(1500, 7u, [&](std::mt19937& g, double* p) {
    p[0] = 0.1 * unit(g);
    p[1] = 0.08 * unit(g);
    p[2] = 0.05 * unit(g);
  });
  const double horizon = 0.012, dx = 0.005;
  const auto reference = bruteForceBonds(x, horizon);
  EXPECT_GT(reference.size(), 1500u * 3u);  // a meaningful number of bonds
  expectMatchesReference(buildOnDevice(x, horizon, dx), x, horizon, dx, reference);
}

TEST(TEST_CATEGORY, bond_list_cylinder_surface_matches_brute_force) {
  const double pi = 3.14159265358979323846, radius = 0.05, height = 0.2;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto x = randomPoints(2000, 11u, [&](std::mt19937& g, double* p) {
    const double angle = 2.0 * pi * unit(g);
    p[0] = radius * std::cos(angle);
    p[1] = height * unit(g);
    p[2] = radius * std::sin(angle);
  });
  const double horizon = 0.01, dx = 0.004;
  const auto reference = bruteForceBonds(x, horizon);
  EXPECT_GT(reference.size(), 2000u * 3u);
  expectMatchesReference(buildOnDevice(x, horizon, dx), x, horizon, dx, reference);
}

TEST(TEST_CATEGORY, bond_list_far_apart_clusters_cap_the_cell_grid) {
  // Cells of size delta over the box would be ~(2e4)^3; the capped grid must still find
  // every bond.
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int placed = 0;
  const auto x = randomPoints(300, 3u, [&](std::mt19937& g, double* p) {
    const double corner = (placed++ % 2) * 1.0e3;
    for (int d = 0; d < 3; ++d) p[d] = corner + 0.2 * unit(g);
  });
  const double horizon = 0.05, dx = 0.02;
  const auto reference = bruteForceBonds(x, horizon);
  EXPECT_GT(reference.size(), 300u);
  expectMatchesReference(buildOnDevice(x, horizon, dx), x, horizon, dx, reference);
}

TEST(TEST_CATEGORY, bond_list_precracks_remove_crossing_bonds_only) {
  const int nodesX = 30, nodesY = 20;
  const double dx = 0.01, horizon = 3 * dx;
  const auto x = makeLattice(nodesX, nodesY, dx);
  // An edge crack along y = 9.5 dx from outside the plate to x = 14.3 dx, and an interior
  // crack along the node column x = 20 dx from y = 2.3 dx to 12.2 dx (its nodes lie on it).
  const double edgeY = 9.5 * dx, edgeTip = 14.3 * dx;
  const double columnX = 20 * dx, columnLow = 2.3 * dx, columnHigh = 12.2 * dx;
  const std::vector<perishell::mesh::CrackSegment> cracks = {
      {{-dx, edgeY, 0.0}, {edgeTip, edgeY, 0.0}, {0.0, 0.0, 1.0}},
      {{columnX, columnLow, 0.0}, {columnX, columnHigh, 0.0}, {0.0, 0.0, 1.0}}};
  // The same rule written for these two lines in the plane: end points on opposite sides
  // (a node on the line counts as the positive side: above y, right of x), crossing point
  // within the segment.
  const Cut crossesACrack = [&](const HostPositions& p, int i, int j) {
    const double xi = p(i, 0), yi = p(i, 1), xj = p(j, 0), yj = p(j, 1);
    if ((yi - edgeY) * (yj - edgeY) < 0.0) {
      const double crossingX = xi + (xj - xi) * (edgeY - yi) / (yj - yi);
      if (crossingX >= -dx && crossingX <= edgeTip) return true;
    }
    if ((xi - columnX >= 0.0) != (xj - columnX >= 0.0)) {
      const double crossingY = yi + (yj - yi) * (columnX - xi) / (xj - xi);
      if (crossingY >= columnLow && crossingY <= columnHigh) return true;
    }
    return false;
  };
  const auto bonds = buildOnDevice(x, horizon, dx, cracks);
  const auto reference = bruteForceBonds(x, horizon, crossesACrack);
  expectMatchesReference(bonds, x, horizon, dx, reference);
  for (const auto& [i, j] : halfBondsOf(bonds)) EXPECT_FALSE(crossesACrack(x, i, j)) << i << "-" << j;
  const auto uncut = bruteForceBonds(x, horizon);
  EXPECT_GT(uncut.size() - bonds.numBonds(), 100u);  // both cracks cut many bonds

  const auto node = [&](int i, int j) { return j * nodesX + i; };
  EXPECT_FALSE(hasBond(bonds, node(14, 9), node(14, 10)));  // crosses at x = 14 dx, behind the tip
  EXPECT_FALSE(hasBond(bonds, node(12, 9), node(14, 10)));  // crosses at 13 dx
  EXPECT_FALSE(hasBond(bonds, node(13, 9), node(15, 10)));  // crosses at 14 dx
  EXPECT_TRUE(hasBond(bonds, node(14, 9), node(15, 10)));   // crosses the line at 14.5 dx, past the tip
  EXPECT_TRUE(hasBond(bonds, node(14, 9), node(16, 10)));   // at 15 dx
  EXPECT_TRUE(hasBond(bonds, node(15, 8), node(15, 11)));   // beside the tip
  EXPECT_TRUE(hasBond(bonds, node(16, 9), node(16, 10)));
  EXPECT_TRUE(hasBond(bonds, node(14, 9), node(14, 8)));    // same side
  EXPECT_FALSE(hasBond(bonds, node(19, 5), node(21, 5)));   // through the column crack
  EXPECT_FALSE(hasBond(bonds, node(19, 5), node(20, 5)));   // node on the crack: positive side
  EXPECT_TRUE(hasBond(bonds, node(20, 5), node(21, 5)));    // both on the positive side
  EXPECT_TRUE(hasBond(bonds, node(20, 4), node(20, 6)));    // along the crack
  EXPECT_TRUE(hasBond(bonds, node(19, 13), node(21, 13)));  // above the column crack's end
  EXPECT_FALSE(hasBond(bonds, node(19, 12), node(21, 12)));
}

// A 1 m x 0.6 m plate, 10 x 6 quads, slit along x = 0.5 from y = 0 to the tip at y = 0.3:
// the quads right of the slit use copies of its nodes at y = 0, 0.1, 0.2 (numbered 77, 78,
// 79 after the plate's 77 nodes 0..76), so its two faces coincide and are not connected.
perishell::mesh::HostQuadMesh slitPlate() {
  const auto plate = perishell::mesh::makeRectangularPlate(1.0, 0.6, 10, 6);
  const int nodesX = 11, numNodes = plate.numNodes();
  perishell::mesh::HostQuadMesh slit{HostPositions("slit plate", numNodes + 3), plate.quads};
  for (int n = 0; n < numNodes; ++n)
    for (int d = 0; d < 3; ++d) slit.coordinates(n, d) = plate.coordinates(n, d);
  for (int row = 0; row < 3; ++row)
    for (int d = 0; d < 3; ++d) slit.coordinates(numNodes + row, d) = plate.coordinates(row * nodesX + 5, d);
  for (int e = 0; e < plate.numElements(); ++e) {
    double centroidX = 0.0;
    for (int a = 0; a < 4; ++a) centroidX += 0.25 * plate.coordinates(plate.quads(e, a), 0);
    if (centroidX < 0.5) continue;
    for (int a = 0; a < 4; ++a) {
      const int n = plate.quads(e, a);
      if (n % nodesX == 5 && n / nodesX < 3) slit.quads(e, a) = numNodes + n / nodesX;
    }
  }
  return slit;
}

TEST(TEST_CATEGORY, bond_list_never_crosses_a_slit_of_the_mesh) {
  const auto mesh = slitPlate();
  const int numNodes = mesh.numNodes(), firstCopy = numNodes - 3;
  const double horizon = 0.3, spacing = 0.1;
  Kokkos::View<perishell::LocalIndex*, Kokkos::HostSpace> all("all nodes", numNodes);
  for (int n = 0; n < numNodes; ++n) all(n) = n;
  const auto built = perishell::pd::buildBondsAmong(TEST_EXECSPACE{}, mesh, all, horizon, spacing, {});
  const auto bonds = perishell::pd::mirrorTo<Kokkos::HostSpace>(built.bonds);
  // Reference: the side of each node (-1 left, +1 right, 0 on the line beyond the slit) and
  // the straight bond crossing x = 0.5 at y <= 0.3 from one side to the other is cut.
  const auto side = [&](int n) {
    const double x = mesh.coordinates(n, 0), y = mesh.coordinates(n, 1);
    if (std::abs(x - 0.5) > 1e-12) return x < 0.5 ? -1 : 1;
    if (n >= firstCopy) return 1;
    return y < 0.3 - 1e-12 ? -1 : 0;
  };
  const auto crossesSlit = [&](const HostPositions& x, int i, int j) {
    if (distance(x, i, j) < 1e-9) return true;  // the slit's coincident nodes never bond
    if (side(i) * side(j) >= 0) return false;
    const double xi = x(i, 0), xj = x(j, 0);
    const double y = std::abs(xi - xj) < 1e-12 ? std::min(x(i, 1), x(j, 1))
                                               : x(i, 1) + (0.5 - xi) / (xj - xi) * (x(j, 1) - x(i, 1));
    return y <= 0.3 + 1e-12;
  };
  const auto reference = bruteForceBonds(mesh.coordinates, horizon, crossesSlit);
  for (const auto& [i, j] : halfBondsOf(bonds))
    EXPECT_TRUE(std::binary_search(reference.begin(), reference.end(), Bond{i, j}))
        << "bond " << i << " (" << mesh.coordinates(i, 0) << ", " << mesh.coordinates(i, 1) << ") - " << j << " ("
        << mesh.coordinates(j, 0) << ", " << mesh.coordinates(j, 1) << ") crosses the slit";
  expectMatchesReference(bonds, mesh.coordinates, horizon, spacing, reference);
  // The slit cuts something, and bonds still run around its tip.
  EXPECT_LT(reference.size(), bruteForceBonds(mesh.coordinates, horizon).size() - 3);
  EXPECT_TRUE(hasBond(bonds, 3 * 11 + 4, 4 * 11 + 6));  // (0.4, 0.3) - (0.6, 0.4): past the tip
  EXPECT_FALSE(hasBond(bonds, 4, 6));                   // (0.4, 0) - (0.6, 0): across the slit
  EXPECT_FALSE(hasBond(bonds, 11 + 5, firstCopy + 2));  // along the slit, face to face
  EXPECT_TRUE(hasBond(bonds, 11 + 5, 2 * 11 + 5));      // along one face
}

TEST(TEST_CATEGORY, bond_list_of_no_nodes_is_empty) {
  const auto bonds = buildOnDevice(HostPositions("none", 0), 0.03, 0.01);
  EXPECT_EQ(bonds.numNodes(), 0);
  EXPECT_EQ(bonds.numBonds(), 0u);
  EXPECT_EQ(bonds.numFullEntries(), 0u);
  EXPECT_EQ(bonds.offsets(0), 0u);
}

void expectInvalid(const std::function<void()>& build, const std::vector<std::string>& mentions) {
  try {
    build();
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& error) {
    const std::string message = error.what();
    for (const auto& word : mentions) EXPECT_NE(message.find(word), std::string::npos) << message;
  }
}

TEST(TEST_CATEGORY, bond_list_rejects_bad_parameters) {
  const auto x = makeLattice(4, 4, 0.01);
  const auto build = [&](double horizon, double dx) { return [=] { buildOnDevice(x, horizon, dx); }; };
  expectInvalid(build(0.0, 0.01), {"horizon", "got 0"});
  expectInvalid(build(-0.03, 0.01), {"horizon", "-0.03"});
  expectInvalid(build(NAN, 0.01), {"horizon"});
  expectInvalid(build(INFINITY, 0.01), {"horizon"});
  expectInvalid(build(0.03, 0.0), {"gridSpacing"});
  expectInvalid(build(0.03, NAN), {"gridSpacing"});
  expectInvalid(build(0.005, 0.01), {"horizon", "at least gridSpacing", "0.005"});
  auto broken = makeLattice(4, 4, 0.01);
  broken(5, 1) = NAN;
  broken(7, 2) = INFINITY;
  expectInvalid([&] { buildOnDevice(broken, 0.03, 0.01); }, {"positions", "2 node coordinates are not finite"});
}

}  // namespace
