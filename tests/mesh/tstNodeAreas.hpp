// Node areas by element mapping with atomic_add: exact tributary areas on a regular plate,
// exact total area on a distorted plate and on a faceted cylinder.
#include <perishell/mesh/node_areas.hpp>

#include <cmath>

namespace {

template <class ExecutionSpaceT>
Kokkos::View<double*, Kokkos::HostSpace> nodeAreasOnHost(const perishell::mesh::HostQuadMesh& hostMesh) {
  const auto mesh = perishell::mesh::mirrorTo<typename ExecutionSpaceT::memory_space>(hostMesh);
  const auto areas = perishell::mesh::computeNodeAreas(ExecutionSpaceT{}, mesh);
  return Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, areas);
}

double sum(const Kokkos::View<double*, Kokkos::HostSpace>& values) {
  double total = 0.0;
  for (std::size_t i = 0; i < values.extent(0); ++i) total += values(i);
  return total;
}

TEST(TEST_CATEGORY, node_areas_regular_plate_are_tributary_areas) {
  const int cellsX = 30, cellsY = 20;
  const double lengthX = 0.3, lengthY = 0.1;
  const double cellArea = (lengthX / cellsX) * (lengthY / cellsY);
  const auto hostMesh = perishell::mesh::makeRectangularPlate(lengthX, lengthY, cellsX, cellsY);
  const auto areas = nodeAreasOnHost<TEST_EXECSPACE>(hostMesh);
  ASSERT_EQ(areas.extent(0), std::size_t((cellsX + 1) * (cellsY + 1)));
  EXPECT_NEAR(sum(areas), lengthX * lengthY, 1e-12 * lengthX * lengthY);  // round-off of ~1e3 sums
  for (int j = 0; j <= cellsY; ++j)
    for (int i = 0; i <= cellsX; ++i) {
      const int touchingCells = (i == 0 || i == cellsX ? 1 : 2) * (j == 0 || j == cellsY ? 1 : 2);
      EXPECT_NEAR(areas(j * (cellsX + 1) + i), 0.25 * touchingCells * cellArea, 1e-12 * cellArea)
          << "node (" << i << ", " << j << ")";
    }
}

TEST(TEST_CATEGORY, node_areas_distorted_plate_sum_to_exact_area) {
  // Interior nodes moved in-plane (the boundary is kept): the plate area cannot change.
  const int cells = 16;
  auto hostMesh = perishell::mesh::makeRectangularPlate(1.0, 1.0, cells, cells);
  const double h = 1.0 / cells;
  for (int j = 1; j < cells; ++j)
    for (int i = 1; i < cells; ++i) {
      const int node = j * (cells + 1) + i;
      hostMesh.coordinates(node, 0) += 0.3 * h * std::sin(7.0 * node);
      hostMesh.coordinates(node, 1) += 0.3 * h * std::cos(5.0 * node);
    }
  const auto areas = nodeAreasOnHost<TEST_EXECSPACE>(hostMesh);
  EXPECT_NEAR(sum(areas), 1.0, 1e-13);
  for (std::size_t i = 0; i < areas.extent(0); ++i) EXPECT_GT(areas(i), 0.0);
}

TEST(TEST_CATEGORY, node_areas_faceted_cylinder_sum_to_facet_area) {
  // Roll a plate into a closed cylinder of radius r (the seam's nodes stay distinct): every
  // quad is a flat rectangle of width 2 r sin(pi/n), so the total is n * width * height.
  const int around = 24, along = 10;
  const double radius = 0.2, height = 0.5;
  auto hostMesh = perishell::mesh::makeRectangularPlate(1.0, height, around, along);
  const double pi = 3.14159265358979323846;
  for (int node = 0; node < hostMesh.numNodes(); ++node) {
    const double angle = 2.0 * pi * hostMesh.coordinates(node, 0);
    hostMesh.coordinates(node, 0) = radius * std::cos(angle);
    hostMesh.coordinates(node, 2) = radius * std::sin(angle);
  }
  const auto areas = nodeAreasOnHost<TEST_EXECSPACE>(hostMesh);
  const double facetArea = around * 2.0 * radius * std::sin(pi / around) * height;
  EXPECT_NEAR(sum(areas), facetArea, 1e-13);
  EXPECT_LT(facetArea, 2.0 * pi * radius * height);
}

TEST(TEST_CATEGORY, rectangular_plate_rejects_bad_sizes) {
  EXPECT_THROW(perishell::mesh::makeRectangularPlate(0.0, 1.0, 2, 2), std::invalid_argument);
  EXPECT_THROW(perishell::mesh::makeRectangularPlate(1.0, NAN, 2, 2), std::invalid_argument);
  EXPECT_THROW(perishell::mesh::makeRectangularPlate(1.0, 1.0, 0, 2), std::invalid_argument);
}

}  // namespace
