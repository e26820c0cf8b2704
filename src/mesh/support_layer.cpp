#include <perishell/mesh/free_edges.hpp>
#include <perishell/mesh/support_layer.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <map>
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

// second after first (row-major 3 x 3).
std::array<double, 9> compose(const std::array<double, 9>& second, const std::array<double, 9>& first) {
  std::array<double, 9> product{};
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) product[3 * r + c] += second[3 * r + k] * first[3 * k + c];
  return product;
}

}  // namespace

FreeEdge mirrorPlaneEdge(const FreeEdge& edge, std::uint8_t heldDofs) {
  // The outward normal's part in the held (or else the free) translations, kept normal to
  // the edge, where it lies within 30 degrees of them.
  const auto projected = [&](bool heldAxes) {
    Point p{0.0, 0.0, 0.0};
    for (int a = 0; a < 3; ++a)
      if (((heldDofs >> a) & 1u) == (heldAxes ? 1u : 0u)) p[a] = edge.outward[a];
    return p - dot(p, edge.tangent) * edge.tangent;
  };
  constexpr double within30Degrees = 0.866;
  FreeEdge plane = edge;
  for (const bool heldAxes : {true, false}) {
    const Point p = projected(heldAxes);
    if (std::sqrt(dot(p, p)) < within30Degrees) continue;
    plane.outward = unit(p);
    const Point z = cross(plane.outward, edge.tangent);
    plane.normal = dot(z, edge.normal) >= 0.0 ? z : -1.0 * z;
    break;
  }
  return plane;
}

std::optional<MirrorMaps> mirrorMaps(const FreeEdge& edge, std::uint8_t heldDofs) {
  // A component along `axis` is held when the axis lies in the span of the held global axes.
  const auto held = [&](const Point& axis, int firstDof) {
    double inSpan = 0.0;
    for (int a = 0; a < 3; ++a)
      if (heldDofs & (1u << (firstDof + a))) inSpan += axis[a] * axis[a];
    return inSpan >= 1.0 - 1e-6;
  };
  const FreeEdge plane = mirrorPlaneEdge(edge, heldDofs);
  const Point n = plane.outward, t = plane.tangent, z = plane.normal;
  enum class Part { Free, Held, Even, Odd };
  const bool un = held(n, 0), ut = held(t, 0), w = held(z, 0), thetaT = held(t, 3);
  const Part membrane = un && ut ? Part::Held : un ? Part::Even : ut ? Part::Odd : Part::Free;
  const Part bending = w && thetaT ? Part::Held : thetaT ? Part::Even : w ? Part::Odd : Part::Free;
  if (membrane == Part::Free || bending == Part::Free) return std::nullopt;
  // Signs of (u_n, u_t, w) and (theta_n, theta_t, theta_z) in the image (model-setup.md).
  const auto sign = [](Part part, double even) { return part == Part::Held ? 0.0 : part == Part::Even ? even : -even; };
  const double displacementSigns[3] = {sign(membrane, -1.0), sign(membrane, 1.0), sign(bending, 1.0)};
  const double rotationSigns[3] = {sign(bending, 1.0), sign(bending, -1.0), sign(membrane, -1.0)};
  const Point frame[3] = {n, t, z};
  MirrorMaps maps{};
  for (int k = 0; k < 3; ++k)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) {
        maps.displacement[3 * r + c] += displacementSigns[k] * frame[k][r] * frame[k][c];
        maps.rotation[3 * r + c] += rotationSigns[k] * frame[k][r] * frame[k][c];
      }
  return maps;
}

namespace {

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
    std::vector<LocalIndex> nodes, mirrored;  // the request's held and mirrored layer nodes, sorted
    bool hasFreeEdges = false, hasRoom = false, narrow = false;
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
      std::optional<MirrorMaps> maps;  // a Mirrored request's
    };
    struct Image {  // how an image follows its master
      MirrorMaps maps;
      std::array<double, 9> reflection;
    };
    const auto reflectionAcross = [](const FreeEdge& edge) {
      std::array<double, 9> matrix{};
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) matrix[3 * r + c] = (r == c ? 1.0 : 0.0) - 2.0 * edge.outward[r] * edge.outward[c];
      return matrix;
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
      std::optional<MirrorMaps> maps;
      const FreeEdge* imaged = &edge;
      if (requests[owner].motion == LayerMotion::Mirrored) {
        maps = mirrorMaps(edge, requests[owner].heldDofs);
        if (!maps) continue;
        imaged = &planeEdges_.emplace_back(mirrorPlaneEdge(edge, requests[owner].heldDofs));
      }
      result[owner].hasFreeEdges = true;
      if (materialBeyond(mesh_, realNodes_, edge, depth_)) continue;
      edges.push_back({imaged, owner, maps});
      result[owner].hasRoom = true;
      if (!reachesDepth(edge)) result[owner].narrow = true;
    }
    const auto isHeld = [&](int set) { return requests[set].motion == LayerMotion::Held; };

    // follows: how the image follows its master (none when a Held set owns it; the first image stays).
    const auto imageNode = [&](const Point& image, std::initializer_list<int> sets, LocalIndex master,
                               const std::optional<Image>& follows) {
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
      if (found >= firstNode_) {
        for (const int set : sets) (isHeld(set) ? result[set].nodes : result[set].mirrored).push_back(found);
        if (follows) mirrors_.emplace(found, MirrorImage{found, master, follows->maps, follows->reflection});
      }
      return found;
    };
    // The image of an element under `mirrors` reflections: after an odd number its corners
    // are taken in reverse, so that its normal keeps the original's side. A triangle's image
    // is a triangle (a b c c, mesh/quad_mesh.hpp).
    const auto addImage = [&](LocalIndex element, std::initializer_list<int> sets, int mirrors, auto&& map,
                              const std::optional<Image>& follows) {
      const int corners = cornerCount(mesh_.quads, element);
      std::array<LocalIndex, 4> image;
      for (int k = 0; k < corners; ++k) {
        const LocalIndex source = mesh_.quads(element, mirrors % 2 == 1 ? corners - 1 - k : k);
        image[k] = imageNode(map(node(source)), sets, source, follows);
      }
      if (corners == 3) image[3] = image[2];
      std::array<LocalIndex, 4> key = image;
      std::sort(key.begin(), key.begin() + corners);
      if (std::adjacent_find(key.begin(), key.begin() + corners) != key.begin() + corners) return;  // degenerate image
      if (corners == 3) key[3] = -1;
      if (*std::max_element(key.begin(), key.end()) < firstNode_) return;  // all on the mesh's own nodes
      if (elementKeys_.insert(key).second) quads_.push_back(image);
    };

    for (const auto& [edge, set, maps] : edges)
      forEachMirrored(*edge, [&, edge = edge, set = set, maps = maps](LocalIndex element) {
        std::optional<Image> follows;
        if (maps) follows = Image{*maps, reflectionAcross(*edge)};
        addImage(element, {set}, 1, [&](const Point& p) { return mirror(*edge, p); }, follows);
      });
    // Convex corners: the images across both edges fill the wedge that neither strip covers.
    for (const auto& first : edges)
      for (const auto& second : edges) {
        if (first.edge->b != second.edge->a) continue;
        if (dot(cross(first.edge->tangent, second.edge->tangent), first.edge->normal) < minimumCornerTurn) continue;
        const Point corner = node(first.edge->b);
        const double reach = std::sqrt(2.0) * depth_ + largestDiameter_;
        const auto across = [&](const Point& p) { return mirror(*second.edge, mirror(*first.edge, p)); };
        std::optional<Image> follows;
        if (first.maps && second.maps)
          follows = Image{{compose(second.maps->displacement, first.maps->displacement),
                           compose(second.maps->rotation, first.maps->rotation)},
                          compose(reflectionAcross(*second.edge), reflectionAcross(*first.edge))};
        centroidGrid_.forEachIn(corner - Point{reach, reach, reach}, corner + Point{reach, reach, reach},
                                [&](LocalIndex element) {
                                  const Point c = centroid(element);
                                  if (dot(c - corner, c - corner) > reach * reach) return;
                                  const Point image = across(c);
                                  const double beyond[2] = {dot(image - corner, first.edge->outward),
                                                            dot(image - corner, second.edge->outward)};
                                  for (const double distance : beyond)
                                    if (!(distance > 0.0 && distance <= depth_)) return;
                                  addImage(element, {first.set, second.set}, 2, across, follows);
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
    const auto renumber = [&](std::vector<LocalIndex>& nodes) {
      for (LocalIndex& n : nodes) n = renumbered[n - firstNode_];
      nodes.erase(std::remove(nodes.begin(), nodes.end(), -1), nodes.end());
      std::sort(nodes.begin(), nodes.end());
      nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
    };
    std::set<LocalIndex> held;
    for (auto& built : result) {
      renumber(built.nodes);
      held.insert(built.nodes.begin(), built.nodes.end());
    }
    // A node both held and mirrored (a corner between a clamp and a symmetry plane) is held.
    for (auto& built : result) {
      renumber(built.mirrored);
      built.mirrored.erase(std::remove_if(built.mirrored.begin(), built.mirrored.end(),
                                          [&](LocalIndex n) { return held.count(n) > 0; }),
                           built.mirrored.end());
    }
    for (const auto& [oldNode, image] : mirrors_) {
      const LocalIndex n = renumbered[oldNode - firstNode_];
      if (n >= 0 && held.count(n) == 0) images_.push_back({n, image.master, image.maps, image.reflection});
    }
    std::sort(images_.begin(), images_.end(),
              [](const MirrorImage& a, const MirrorImage& b) { return a.node < b.node; });
    std::vector<const FreeEdge*> mirrorEdges;
    for (const auto& tagged : edges)
      if (tagged.maps) mirrorEdges.push_back(tagged.edge);
    computeShares(mirrorEdges);
    return result;
  }

  std::vector<MirrorImage> takeImages() { return std::move(images_); }

  // The share of each node's neighbourhood inside the mirror lines (SupportLayer::mirrorShare):
  // 0 beyond any line (every image, and the held layer's nodes beyond one), 1/2 per distinct
  // line through the node (two edges of one straight or gently curved line are one; a corner
  // turns by more than minimumCornerTurn). Only nodes within reach of a mirror edge count: the
  // edges' own nodes and the layer's.
  void computeShares(const std::vector<const FreeEdge*>& mirrorEdges) {
    if (mirrorEdges.empty()) return;
    const double reach = depth_ + largestDiameter_;
    const auto shareOf = [&](const Point& p) {
      std::vector<Point> lines;
      for (const FreeEdge* edge : mirrorEdges) {
        const Local l = local(*edge, p);
        if (l.along * edge->length < -reach || (l.along - 1.0) * edge->length > reach || l.offPlane > reach) continue;
        if (-l.inside > tolerance_ && -l.inside <= reach) return 0.0;
        if (std::abs(l.inside) > tolerance_) continue;
        const bool known = std::any_of(lines.begin(), lines.end(), [&](const Point& line) {
          const Point turn = cross(line, edge->outward);
          return std::sqrt(dot(turn, turn)) < minimumCornerTurn && dot(line, edge->outward) > 0.0;
        });
        if (!known) lines.push_back(edge->outward);
      }
      return std::pow(0.5, static_cast<double>(lines.size()));
    };
    for (const FreeEdge* edge : mirrorEdges)
      for (const LocalIndex n : {edge->a, edge->b}) share_[n] = shareOf(node(n));
    for (LocalIndex k = 0; k < numLayerNodes(); ++k) {
      const double share = shareOf(layerNode(firstNode_ + k));
      if (share < 1.0) share_[firstNode_ + k] = share;
    }
  }
  std::map<LocalIndex, double> takeShares() { return std::move(share_); }

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
    const auto [lower, upper] = edgeBox(mesh_, edge, depth_ + largestDiameter_);
    std::vector<LocalIndex> selected;
    centroidGrid_.forEachIn(lower, upper, [&](LocalIndex element) {
      const Local l = local(edge, centroid(element));
      if (l.along >= 0.0 && l.along < 1.0 && l.inside > 0.0 && l.inside <= depth_ && l.offPlane <= depth_)
        selected.push_back(element);
    });
    std::sort(selected.begin(), selected.end());
    for (const LocalIndex element : selected) visit(element);
  }

  // Whether the mesh goes on for `depth` inside the edge (a node that far in, along it): if
  // not, the model is narrower than the horizon there and so is its layer.
  bool reachesDepth(const FreeEdge& edge) const {
    const auto [lower, upper] = edgeBox(mesh_, edge, depth_);
    bool reached = false;
    realNodes_.forEachIn(lower, upper, [&](LocalIndex n) {
      const Local l = local(edge, node(n));
      reached = reached || (l.along > -0.01 && l.along < 1.01 && l.inside >= depth_ - tolerance_);
    });
    return reached;
  }

  // A corner turns by at least ~17 degrees (sine 0.3); flatter ones need no fill.
  static constexpr double minimumCornerTurn = 0.3;

  HostQuadMesh& mesh_;
  double depth_, tolerance_;
  LocalIndex firstNode_;
  double largestDiameter_ = 0.0;
  NodeGrid realNodes_, centroidGrid_;
  std::vector<FreeEdge> freeEdges_;
  std::deque<FreeEdge> planeEdges_;  // mirrored edges in their mirror plane's frame (stable addresses)
  std::vector<double> coordinates_;                // new layer nodes, x y z each
  std::vector<std::array<LocalIndex, 4>> quads_;  // layer elements
  std::set<std::array<LocalIndex, 4>> elementKeys_;
  std::map<LocalIndex, MirrorImage> mirrors_;  // by layer node, before renumbering
  std::vector<MirrorImage> images_;
  std::map<LocalIndex, double> share_;
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
    if (built[r].narrow) layer.narrowSets.push_back(requests[r].setName);
    if (!built[r].nodes.empty()) layer.nodesOfSet[requests[r].setName] = std::move(built[r].nodes);
    if (!built[r].mirrored.empty()) layer.mirroredNodesOfSet[requests[r].setName] = std::move(built[r].mirrored);
  }
  layer.mirrorImages = builder.takeImages();
  layer.mirrorShare = builder.takeShares();
  builder.append();
  return layer;
}

}  // namespace perishell::mesh
