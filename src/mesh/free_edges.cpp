#include <perishell/mesh/free_edges.hpp>

#include <algorithm>
#include <cmath>
#include <utility>

namespace perishell::mesh {

namespace {

Point3 operator-(const Point3& a, const Point3& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
double dot(const Point3& a, const Point3& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Point3 cross(const Point3& a, const Point3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
Point3 scaled(double s, const Point3& a) { return {s * a[0], s * a[1], s * a[2]}; }
Point3 node(const HostQuadMesh& mesh, LocalIndex n) { return nodePoint(mesh, n); }
Point3 centroid(const HostQuadMesh& mesh, LocalIndex e) { return elementCentroid(mesh, e); }

}  // namespace

Point3 nodePoint(const HostQuadMesh& mesh, LocalIndex node) {
  return {mesh.coordinates(node, 0), mesh.coordinates(node, 1), mesh.coordinates(node, 2)};
}

Point3 elementCentroid(const HostQuadMesh& mesh, LocalIndex element) {
  Point3 centroid{0.0, 0.0, 0.0};
  const int corners = cornerCount(mesh.quads, element);
  for (int a = 0; a < corners; ++a)
    for (int d = 0; d < 3; ++d) centroid[d] += mesh.coordinates(mesh.quads(element, a), d) / corners;
  return centroid;
}

NodeGrid::NodeGrid(double cell) : cell_(cell) {}

void NodeGrid::insert(const Point3& p, LocalIndex id) { cells_[key(cellOf(p))].push_back(id); }

std::array<long long, 3> NodeGrid::cellOf(const Point3& p) const {
  return {std::llround(std::floor(p[0] / cell_)), std::llround(std::floor(p[1] / cell_)),
          std::llround(std::floor(p[2] / cell_))};
}

long long NodeGrid::key(const std::array<long long, 3>& c) {
  const long long mask = (1LL << 21) - 1;
  return ((c[0] & mask) << 42) | ((c[1] & mask) << 21) | (c[2] & mask);
}

NodeGrid makeNodeGrid(const HostQuadMesh& mesh, double cell) {
  NodeGrid grid(cell);
  for (LocalIndex n = 0; n < mesh.numNodes(); ++n) grid.insert(node(mesh, n), n);
  return grid;
}

std::vector<FreeEdge> findFreeEdges(const HostQuadMesh& mesh) {
  std::unordered_map<unsigned long long, std::pair<int, FreeEdge>> edges;
  for (LocalIndex e = 0; e < mesh.numElements(); ++e)
    for (int k = 0, corners = cornerCount(mesh.quads, e); k < corners; ++k) {
      const LocalIndex a = mesh.quads(e, k), b = mesh.quads(e, (k + 1) % corners);
      const auto key = (static_cast<unsigned long long>(std::min(a, b)) << 32) | unsigned(std::max(a, b));
      auto& entry = edges[key];
      ++entry.first;
      entry.second.a = a;
      entry.second.b = b;
      entry.second.element = e;
    }
  std::vector<FreeEdge> free;
  for (auto& [key, entry] : edges) {
    if (entry.first != 1) continue;
    FreeEdge edge = entry.second;
    const LocalIndex e = edge.element;
    edge.origin = node(mesh, edge.a);
    const Point3 along = node(mesh, edge.b) - edge.origin;
    edge.length = std::sqrt(dot(along, along));
    if (!(edge.length > 0.0)) continue;
    edge.tangent = scaled(1.0 / edge.length, along);
    const Point3 area = cross(node(mesh, mesh.quads(e, 2)) - node(mesh, mesh.quads(e, 0)),
                              node(mesh, mesh.quads(e, 3)) - node(mesh, mesh.quads(e, 1)));
    edge.normal = scaled(1.0 / std::sqrt(dot(area, area)), area);
    const Point3 outward = cross(edge.tangent, edge.normal);
    edge.outward = scaled(1.0 / std::sqrt(dot(outward, outward)), outward);
    if (dot(centroid(mesh, e) - edge.origin, edge.outward) > 0.0) edge.outward = scaled(-1.0, edge.outward);
    free.push_back(edge);
  }
  // Hash order must not decide anything downstream.
  std::sort(free.begin(), free.end(),
            [](const FreeEdge& x, const FreeEdge& y) { return std::make_pair(x.a, x.b) < std::make_pair(y.a, y.b); });
  return free;
}

std::pair<Point3, Point3> edgeBox(const HostQuadMesh& mesh, const FreeEdge& edge, double reach) {
  const Point3 end = node(mesh, edge.b);
  Point3 lower, upper;
  for (int d = 0; d < 3; ++d) {
    lower[d] = std::min(edge.origin[d], end[d]) - reach;
    upper[d] = std::max(edge.origin[d], end[d]) + reach;
  }
  return {lower, upper};
}

bool materialBeyond(const HostQuadMesh& mesh, const NodeGrid& nodeGrid, const FreeEdge& edge, double depth) {
  const auto [lower, upper] = edgeBox(mesh, edge, depth);
  bool found = false;
  nodeGrid.forEachIn(lower, upper, [&](LocalIndex n) {
    const Point3 r = node(mesh, n) - edge.origin;
    const double along = dot(r, edge.tangent) / edge.length, beyond = dot(r, edge.outward);
    if (along >= -1e-9 && along <= 1.0 + 1e-9 && beyond > 0.25 * edge.length && beyond <= depth &&
        std::abs(dot(r, edge.normal)) < 0.5 * depth)
      found = true;
  });
  return found;
}

CoordinateView<Kokkos::HostSpace> nodeMaterialDirections(const HostQuadMesh& mesh) {
  CoordinateView<Kokkos::HostSpace> directions("node material directions", mesh.numNodes());
  std::vector<double> lengths(mesh.numNodes(), 0.0);
  for (LocalIndex e = 0; e < mesh.numElements(); ++e) {
    const Point3 c = centroid(mesh, e);
    for (int k = 0; k < cornerCount(mesh.quads, e); ++k) {
      const LocalIndex n = mesh.quads(e, k);
      const Point3 toCentroid = c - node(mesh, n);
      for (int d = 0; d < 3; ++d) directions(n, d) += toCentroid[d];
      lengths[n] += std::sqrt(dot(toCentroid, toCentroid));
    }
  }
  for (LocalIndex n = 0; n < mesh.numNodes(); ++n)
    if (lengths[n] > 0.0)
      for (int d = 0; d < 3; ++d) directions(n, d) /= lengths[n];
  return directions;
}

std::vector<BoundaryFace> boundaryFaces(const HostQuadMesh& mesh, double depth) {
  std::vector<BoundaryFace> faces;
  const auto edges = findFreeEdges(mesh);
  if (edges.empty()) return faces;
  const NodeGrid grid = makeNodeGrid(mesh, depth);
  std::vector<std::uint8_t> facing(edges.size()), onRim(mesh.numNodes(), 0);
  for (std::size_t k = 0; k < edges.size(); ++k) {
    facing[k] = materialBeyond(mesh, grid, edges[k], depth);
    if (!facing[k]) onRim[edges[k].a] = onRim[edges[k].b] = 1;  // a free edge with void beyond
  }
  for (std::size_t k = 0; k < edges.size(); ++k) {
    if (!facing[k]) continue;
    const FreeEdge& edge = edges[k];
    BoundaryFace face;
    face.before = onRim[edge.a] ? depth : 0.0;
    face.after = onRim[edge.b] ? depth : 0.0;
    for (int d = 0; d < 3; ++d) {
      face.origin[d] = edge.origin[d];
      face.tangent[d] = edge.tangent[d];
      face.outward[d] = edge.outward[d];
      face.normal[d] = edge.normal[d];
    }
    face.length = edge.length;
    faces.push_back(face);
  }
  return faces;
}

std::vector<std::uint8_t> pointsNearFaces(const CoordinateView<Kokkos::HostSpace>& points,
                                          const std::vector<BoundaryFace>& faces, double reach) {
  const LocalIndex numPoints = static_cast<LocalIndex>(points.extent(0));
  std::vector<std::uint8_t> near(numPoints, 0);
  if (faces.empty()) return near;
  NodeGrid grid(reach);
  for (LocalIndex p = 0; p < numPoints; ++p) grid.insert({points(p, 0), points(p, 1), points(p, 2)}, p);
  for (const auto& face : faces) {
    Point3 lower, upper;
    for (int d = 0; d < 3; ++d) {
      const double end = face.origin[d] + face.length * face.tangent[d];
      lower[d] = std::min(face.origin[d], end) - reach;
      upper[d] = std::max(face.origin[d], end) + reach;
    }
    grid.forEachIn(lower, upper, [&](LocalIndex p) {
      double r[3], along = 0.0;
      for (int d = 0; d < 3; ++d) {
        r[d] = points(p, d) - face.origin[d];
        along += r[d] * face.tangent[d];
      }
      along = std::clamp(along, 0.0, face.length);
      double squared = 0.0;
      for (int d = 0; d < 3; ++d) squared += (r[d] - along * face.tangent[d]) * (r[d] - along * face.tangent[d]);
      if (squared <= reach * reach) near[p] = 1;
    });
  }
  return near;
}

}  // namespace perishell::mesh
