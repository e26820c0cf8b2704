#include <perishell/mesh/free_edges.hpp>
#include <perishell/mesh/support_layer.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <set>
#include <unordered_map>
#include <utility>

namespace perishell::mesh {

namespace {

using Point = Point3;

Point operator-(const Point& a, const Point& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Point operator+(const Point& a, const Point& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Point operator*(double s, const Point& a) { return {s * a[0], s * a[1], s * a[2]}; }
double dot(const Point& a, const Point& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Point cross(const Point& a, const Point& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
Point unit(const Point& a) { return (1.0 / std::sqrt(dot(a, a))) * a; }

class LayerBuilder {
 public:
  LayerBuilder(HostQuadMesh& mesh, const std::vector<std::uint8_t>& mayMirror, double depth, double spacing)
      : mesh_(mesh),
        depth_(depth),
        tolerance_(0.25 * spacing),
        firstNode_(mesh.numNodes()),
        realNodes_(makeNodeGrid(mesh, spacing)),
        centroidGrid_(depth) {
    if (!(depth > 0.0 && spacing > 0.0 && std::isfinite(depth) && std::isfinite(spacing)))
      throw std::invalid_argument("support layer: depth and spacing must be positive and finite");
    if (mayMirror.size() != static_cast<std::size_t>(mesh.numElements()))
      throw std::invalid_argument("support layer: the element mask has " + std::to_string(mayMirror.size()) +
                                  " entries for " + std::to_string(mesh.numElements()) + " elements");
    freeEdges_ = findFreeEdges(mesh);
    for (LocalIndex e = 0; e < mesh.numElements(); ++e) {
      double diameter = 0.0;
      for (int k = 0; k < 4; ++k)
        for (int l = k + 1; l < 4; ++l)
          diameter = std::max(diameter, std::sqrt(dot(node(mesh.quads(e, k)) - node(mesh.quads(e, l)),
                                                       node(mesh.quads(e, k)) - node(mesh.quads(e, l)))));
      largestDiameter_ = std::max(largestDiameter_, diameter);
      if (mayMirror[e]) centroidGrid_.insert(centroid(e), e);
    }
  }

  struct Built {
    std::vector<LocalIndex> nodes;  // the request's layer nodes, sorted
    bool hasFreeEdges = false, hasRoom = false;
  };
  // The layer of every request at once (a corner between two sets' edges is filled too).
  std::vector<Built> build(const std::vector<SupportLayerRequest>& requests) {
    std::vector<int> setOf(firstNode_, -1);
    for (std::size_t r = 0; r < requests.size(); ++r)
      for (const LocalIndex n : requests[r].nodes)
        if (setOf[n] < 0) setOf[n] = static_cast<int>(r);
    std::vector<Built> result(requests.size());
    // Images may merge with the sets' own nodes (those on a mirror line map onto themselves).
    NodeGrid targets(2.0 * tolerance_);
    std::vector<LocalIndex> targetIds;
    const auto addTarget = [&](const Point& p, LocalIndex id) {
      targets.insert(p, static_cast<LocalIndex>(targetIds.size()));
      targetIds.push_back(id);
    };
    for (LocalIndex n = 0; n < firstNode_; ++n)
      if (setOf[n] >= 0) addTarget(node(n), n);

    struct TaggedEdge {
      const FreeEdge* edge;
      int set;
    };
    std::vector<TaggedEdge> edges;
    for (const auto& edge : freeEdges_) {
      const int set = setOf[edge.a];
      if (set < 0 || setOf[edge.b] < 0) continue;
      // An edge between two sets' nodes belongs to the first set holding both ends.
      int owner = -1;
      for (std::size_t r = 0; r < requests.size() && owner < 0; ++r)
        if (std::binary_search(requests[r].nodes.begin(), requests[r].nodes.end(), edge.a) &&
            std::binary_search(requests[r].nodes.begin(), requests[r].nodes.end(), edge.b))
          owner = static_cast<int>(r);
      if (owner < 0) continue;
      result[owner].hasFreeEdges = true;
      if (materialBeyond(mesh_, realNodes_, edge, depth_)) continue;
      edges.push_back({&edge, owner});
      result[owner].hasRoom = true;
    }

    const auto imageNode = [&](const Point& image, std::initializer_list<int> sets) {
      LocalIndex found = -1;
      double nearest = tolerance_;
      targets.forEachIn(image - Point{tolerance_, tolerance_, tolerance_},
                        image + Point{tolerance_, tolerance_, tolerance_}, [&](LocalIndex t) {
                          const LocalIndex id = targetIds[t];
                          const Point p = id < firstNode_ ? node(id) : layerNode(id);
                          const double distance = std::sqrt(dot(p - image, p - image));
                          if (distance <= nearest) {
                            nearest = distance;
                            found = id;
                          }
                        });
      if (found < 0) {
        found = firstNode_ + numLayerNodes();
        coordinates_.insert(coordinates_.end(), image.begin(), image.end());
        addTarget(image, found);
      }
      if (found >= firstNode_)
        for (const int set : sets) result[set].nodes.push_back(found);
      return found;
    };
    // The image of an element under `mirrors` reflections: after an odd number its corners
    // are taken in reverse, so that its normal keeps the original's side. A triangle's image
    // is a triangle (a b c c, mesh/quad_mesh.hpp).
    const auto addImage = [&](LocalIndex element, std::initializer_list<int> sets, int mirrors, auto&& map) {
      const int corners = cornerCount(mesh_.quads, element);
      std::array<LocalIndex, 4> image;
      for (int k = 0; k < corners; ++k)
        image[k] = imageNode(map(node(mesh_.quads(element, mirrors % 2 == 1 ? corners - 1 - k : k))), sets);
      if (corners == 3) image[3] = image[2];
      std::array<LocalIndex, 4> key = image;
      std::sort(key.begin(), key.begin() + corners);
      if (std::adjacent_find(key.begin(), key.begin() + corners) != key.begin() + corners) return;  // degenerate image
      if (corners == 3) key[3] = -1;
      if (*std::max_element(key.begin(), key.end()) < firstNode_) return;  // all on the mesh's own nodes
      if (elementKeys_.insert(key).second) quads_.push_back(image);
    };

    for (const auto& [edge, set] : edges)
      forEachMirrored(*edge, [&, edge = edge, set = set](LocalIndex element) {
        addImage(element, {set}, 1, [&](const Point& p) { return mirror(*edge, p); });
      });
    // Convex corners: the images across both edges fill the wedge that neither strip covers.
    for (const auto& first : edges)
      for (const auto& second : edges) {
        if (first.edge->b != second.edge->a) continue;
        if (dot(cross(first.edge->tangent, second.edge->tangent), first.edge->normal) < minimumCornerTurn) continue;
        const Point corner = node(first.edge->b);
        const double reach = std::sqrt(2.0) * depth_ + largestDiameter_;
        const auto across = [&](const Point& p) { return mirror(*second.edge, mirror(*first.edge, p)); };
        centroidGrid_.forEachIn(corner - Point{reach, reach, reach}, corner + Point{reach, reach, reach},
                                [&](LocalIndex element) {
                                  const Point c = centroid(element);
                                  if (dot(c - corner, c - corner) > reach * reach) return;
                                  const Point image = across(c);
                                  const double beyond[2] = {dot(image - corner, first.edge->outward),
                                                            dot(image - corner, second.edge->outward)};
                                  for (const double distance : beyond)
                                    if (!(distance > 0.0 && distance <= depth_)) return;
                                  addImage(element, {first.set, second.set}, 2, across);
                                });
      }
    // Images of discarded elements (repeated or degenerate) may have left unused nodes.
    std::vector<LocalIndex> renumbered(numLayerNodes(), -1);
    for (const auto& quad : quads_)
      for (const LocalIndex n : quad)
        if (n >= firstNode_) renumbered[n - firstNode_] = 0;
    std::vector<double> used;
    for (LocalIndex k = 0; k < numLayerNodes(); ++k)
      if (renumbered[k] == 0) {
        renumbered[k] = firstNode_ + static_cast<LocalIndex>(used.size() / 3);
        used.insert(used.end(), coordinates_.begin() + 3 * k, coordinates_.begin() + 3 * k + 3);
      }
    coordinates_ = std::move(used);
    for (auto& quad : quads_)
      for (LocalIndex& n : quad)
        if (n >= firstNode_) n = renumbered[n - firstNode_];
    for (auto& [nodes, hasFreeEdges, hasRoom] : result) {
      for (LocalIndex& n : nodes) n = renumbered[n - firstNode_];
      nodes.erase(std::remove(nodes.begin(), nodes.end(), -1), nodes.end());
      std::sort(nodes.begin(), nodes.end());
      nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    }
    return result;
  }

  // Writes the layer into the mesh.
  void append() {
    const LocalIndex numNew = numLayerNodes();
    CoordinateView<Kokkos::HostSpace> coordinates("mesh coordinates", firstNode_ + numNew);
    for (LocalIndex n = 0; n < firstNode_; ++n)
      for (int d = 0; d < 3; ++d) coordinates(n, d) = mesh_.coordinates(n, d);
    for (LocalIndex n = 0; n < numNew; ++n)
      for (int d = 0; d < 3; ++d) coordinates(firstNode_ + n, d) = coordinates_[3 * n + d];
    const LocalIndex numElements = mesh_.numElements();
    QuadConnectivityView<Kokkos::HostSpace> quads("mesh quads", numElements + quads_.size());
    for (LocalIndex e = 0; e < numElements; ++e)
      for (int k = 0; k < 4; ++k) quads(e, k) = mesh_.quads(e, k);
    for (std::size_t e = 0; e < quads_.size(); ++e)
      for (int k = 0; k < 4; ++k) quads(numElements + e, k) = quads_[e][k];
    mesh_.coordinates = coordinates;
    mesh_.quads = quads;
  }

 private:
  Point node(LocalIndex n) const { return nodePoint(mesh_, n); }
  LocalIndex numLayerNodes() const { return static_cast<LocalIndex>(coordinates_.size() / 3); }
  Point layerNode(LocalIndex n) const {
    const std::size_t k = 3 * static_cast<std::size_t>(n - firstNode_);
    return {coordinates_[k], coordinates_[k + 1], coordinates_[k + 2]};
  }
  Point centroid(LocalIndex e) const { return elementCentroid(mesh_, e); }
  static Point mirror(const FreeEdge& edge, const Point& p) {
    return p - (2.0 * dot(p - edge.origin, edge.outward)) * edge.outward;
  }

  // Position of p along the edge (0 at a, 1 at b), its depth inside (> 0 on the element's
  // side) and its distance from the element's plane.
  struct Local {
    double along, inside, offPlane;
  };
  static Local local(const FreeEdge& edge, const Point& p) {
    const Point r = p - edge.origin;
    return {dot(r, edge.tangent) / edge.length, -dot(r, edge.outward), std::abs(dot(r, edge.normal))};
  }

  // Calls visit(element) for the mirrorable elements whose centroids lie inside the edge's
  // strip: along it in [0, 1) and within depth of it. Their nodes reach past the depth, so
  // every node within it has its image.
  template <class Visit>
  void forEachMirrored(const FreeEdge& edge, Visit&& visit) const {
    const double reach = depth_ + largestDiameter_;
    const Point end = node(edge.b);
    Point lower, upper;
    for (int d = 0; d < 3; ++d) {
      lower[d] = std::min(edge.origin[d], end[d]) - reach;
      upper[d] = std::max(edge.origin[d], end[d]) + reach;
    }
    std::vector<LocalIndex> selected;
    centroidGrid_.forEachIn(lower, upper, [&](LocalIndex element) {
      const Local l = local(edge, centroid(element));
      if (l.along >= 0.0 && l.along < 1.0 && l.inside > 0.0 && l.inside <= depth_ && l.offPlane <= depth_)
        selected.push_back(element);
    });
    std::sort(selected.begin(), selected.end());
    for (const LocalIndex element : selected) visit(element);
  }

  // A corner turns by at least ~17 degrees (sine 0.3); flatter ones need no fill.
  static constexpr double minimumCornerTurn = 0.3;

  HostQuadMesh& mesh_;
  double depth_, tolerance_;
  LocalIndex firstNode_;
  double largestDiameter_ = 0.0;
  NodeGrid realNodes_, centroidGrid_;
  std::vector<FreeEdge> freeEdges_;
  std::vector<double> coordinates_;                // new layer nodes, x y z each
  std::vector<std::array<LocalIndex, 4>> quads_;  // layer elements
  std::set<std::array<LocalIndex, 4>> elementKeys_;
};

}  // namespace

SupportLayer addSupportLayer(HostQuadMesh& mesh, const std::vector<SupportLayerRequest>& requests,
                             const std::vector<std::uint8_t>& mayMirror, double depth, double spacing) {
  SupportLayer layer;
  layer.firstNode = mesh.numNodes();
  layer.firstElement = mesh.numElements();
  if (requests.empty()) return layer;
  LayerBuilder builder(mesh, mayMirror, depth, spacing);
  auto built = builder.build(requests);
  for (std::size_t r = 0; r < requests.size(); ++r) {
    if (built[r].hasFreeEdges && !built[r].hasRoom) layer.skippedSets.push_back(requests[r].setName);
    if (!built[r].nodes.empty()) layer.nodesOfSet[requests[r].setName] = std::move(built[r].nodes);
  }
  builder.append();
  return layer;
}

}  // namespace perishell::mesh
