#pragma once
// The free edges of a quad mesh (edges of one element: its boundary, and both faces of a
// slit), the ones with mesh material beyond them within some distance (slits, notches,
// folds), and per node the direction into its elements. Host data, built once at setup:
// the support layer (support_layer.hpp) grows beyond free edges, and bonds never cross the
// ones with material beyond (pd/neighbor_search.hpp).
#include <perishell/mesh/boundary_face.hpp>
#include <perishell/mesh/quad_mesh.hpp>

#include <cstdint>

#include <array>
#include <unordered_map>
#include <utility>
#include <vector>

namespace perishell::mesh {

using Point3 = std::array<double, 3>;

Point3 nodePoint(const HostQuadMesh& mesh, LocalIndex node);
Point3 elementCentroid(const HostQuadMesh& mesh, LocalIndex element);

// An edge a-b as its element traverses it (counter-clockwise about the element's normal),
// with unit tangent (b - a) / length, the element's unit normal, and the unit in-plane
// normal `outward` pointing away from the element.
struct FreeEdge {
  LocalIndex a, b, element;
  Point3 origin, tangent, outward, normal;
  double length;
};

// Sorted by (a, b). Edges of zero length are left out.
std::vector<FreeEdge> findFreeEdges(const HostQuadMesh& mesh);

// Uniform hash grid of points, for neighbourhood queries at setup.
class NodeGrid {
 public:
  explicit NodeGrid(double cell);
  void insert(const Point3& p, LocalIndex id);
  // Calls visit(id) for every point in the cells that the box [lower, upper] touches.
  template <class Visit>
  void forEachIn(const Point3& lower, const Point3& upper, Visit&& visit) const {
    const auto low = cellOf(lower), high = cellOf(upper);
    for (long long i = low[0]; i <= high[0]; ++i)
      for (long long j = low[1]; j <= high[1]; ++j)
        for (long long k = low[2]; k <= high[2]; ++k) {
          const auto found = cells_.find(key({i, j, k}));
          if (found == cells_.end()) continue;
          for (const LocalIndex id : found->second) visit(id);
        }
  }

 private:
  std::array<long long, 3> cellOf(const Point3& p) const;
  static long long key(const std::array<long long, 3>& c);
  double cell_;
  std::unordered_map<long long, std::vector<LocalIndex>> cells_;
};

// Whether mesh nodes lie beyond the edge (more than a quarter of its length past its line,
// at most `depth`, within `depth` of its plane, their foot on the edge): the material goes
// on there. `nodeGrid` is a grid over the mesh nodes from makeNodeGrid.
bool materialBeyond(const HostQuadMesh& mesh, const NodeGrid& nodeGrid, const FreeEdge& edge, double depth);

// The box around the edge, `reach` beyond it on every side: where a grid query for what lies
// near the edge looks.
std::pair<Point3, Point3> edgeBox(const HostQuadMesh& mesh, const FreeEdge& edge, double reach);

// The grid of every node of the mesh, cells of size `cell`.
NodeGrid makeNodeGrid(const HostQuadMesh& mesh, double cell);

// Per node, sum (c_e - x) / sum |c_e - x| over its elements e (c_e the centroid): about zero
// inside the mesh, pointing into the material at its boundary (0.7 long on a straight edge).
CoordinateView<Kokkos::HostSpace> nodeMaterialDirections(const HostQuadMesh& mesh);

// The free edges with material beyond them within `depth` (materialBeyond) as boundary faces,
// extended by `depth` beyond an end that a free edge with void beyond shares (a mouth).
std::vector<BoundaryFace> boundaryFaces(const HostQuadMesh& mesh, double depth);

// Per point, 1 where a face lies within `reach` of it.
std::vector<std::uint8_t> pointsNearFaces(const CoordinateView<Kokkos::HostSpace>& points,
                                          const std::vector<BoundaryFace>& faces, double reach);

}  // namespace perishell::mesh
