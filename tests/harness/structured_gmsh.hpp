#pragma once
// A structured n1 x n2 quad grid on a parametrised surface, written as a Gmsh 4.1 file: the
// shell benchmarks' meshes (curved panels, spheres, twisted strips) with named points
// (physical dimension 0, one node each) and named grid lines (physical dimension 1), read back
// by the project's Gmsh reader as node and edge sets. Node (i, j), 0 <= i <= n1, 0 <= j <= n2,
// sits at position(i / n1, j / n2); quads run counter-clockwise in (i, j). Cells that
// splitIntoTriangles selects are written as two triangles (Gmsh type 2) across a diagonal
// that alternates with i + j, as a mesher's right-angled triangles do.
#include <algorithm>
#include <array>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace perishell_test {

class StructuredGmshGrid {
 public:
  using Position = std::function<std::array<double, 3>(double, double)>;

  StructuredGmshGrid(int cells1, int cells2, Position position)
      : cells1_(cells1), cells2_(cells2), position_(std::move(position)) {}

  int tag(int i, int j) const { return 1 + j * (cells1_ + 1) + i; }  // Gmsh node tag

  // Cells (i, j) for which `split` is true become two triangles.
  void splitIntoTriangles(std::function<bool(int, int)> split) { split_ = std::move(split); }

  void addPoint(const std::string& name, int i, int j) { groups_.push_back({name, 0, {tag(i, j)}}); }

  // The grid line from (i0, j0) to (i1, j1); one index must stay fixed.
  void addLine(const std::string& name, int i0, int j0, int i1, int j1) {
    if (i0 != i1 && j0 != j1) throw std::invalid_argument("addLine: " + name + " is not a grid line");
    const int steps = std::max(std::abs(i1 - i0), std::abs(j1 - j0));
    const int di = (i1 > i0) - (i1 < i0), dj = (j1 > j0) - (j1 < j0);
    Group group{name, 1, {}};
    for (int k = 0; k <= steps; ++k) group.nodes.push_back(tag(i0 + k * di, j0 + k * dj));
    groups_.push_back(group);
  }

  void write(const std::string& path) const {
    std::ostringstream msh;
    msh.precision(17);
    const int shellTag = static_cast<int>(groups_.size()) + 1;
    msh << "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n" << shellTag << "\n";
    for (std::size_t g = 0; g < groups_.size(); ++g)
      msh << groups_[g].dimension << " " << g + 1 << " \"" << groups_[g].name << "\"\n";
    msh << "2 " << shellTag << " \"shell\"\n$EndPhysicalNames\n";
    // One entity per group, tagged as its physical group; the surface is entity 1.
    int points = 0, curves = 0;
    for (const auto& group : groups_) (group.dimension == 0 ? points : curves) += 1;
    msh << "$Entities\n" << points << " " << curves << " 1 0\n";
    for (std::size_t g = 0; g < groups_.size(); ++g)
      if (groups_[g].dimension == 0) {
        const auto x = coordinates(groups_[g].nodes[0]);
        msh << g + 1 << " " << x[0] << " " << x[1] << " " << x[2] << " 1 " << g + 1 << "\n";
      }
    for (std::size_t g = 0; g < groups_.size(); ++g)
      if (groups_[g].dimension == 1) msh << g + 1 << " 0 0 0 0 0 0 1 " << g + 1 << " 0\n";
    msh << "1 0 0 0 0 0 0 1 " << shellTag << " 0\n$EndEntities\n";
    const int numNodes = (cells1_ + 1) * (cells2_ + 1);
    msh << "$Nodes\n1 " << numNodes << " 1 " << numNodes << "\n2 1 0 " << numNodes << "\n";
    for (int k = 1; k <= numNodes; ++k) msh << k << "\n";
    for (int k = 1; k <= numNodes; ++k) {
      const auto x = coordinates(k);
      msh << x[0] << " " << x[1] << " " << x[2] << "\n";
    }
    std::vector<std::array<int, 4>> quads;
    std::vector<std::array<int, 3>> triangles;
    for (int j = 0; j < cells2_; ++j)
      for (int i = 0; i < cells1_; ++i) {
        const int a = tag(i, j), b = tag(i + 1, j), c = tag(i + 1, j + 1), d = tag(i, j + 1);
        if (!split_ || !split_(i, j))
          quads.push_back({a, b, c, d});
        else if ((i + j) % 2 == 0)
          triangles.insert(triangles.end(), {{a, b, c}, {a, c, d}});
        else
          triangles.insert(triangles.end(), {{a, b, d}, {b, c, d}});
      }
    int numElements = static_cast<int>(quads.size() + triangles.size());
    for (const auto& group : groups_)
      numElements += group.dimension == 0 ? 1 : static_cast<int>(group.nodes.size()) - 1;
    const int surfaceBlocks = (quads.empty() ? 0 : 1) + (triangles.empty() ? 0 : 1);
    msh << "$EndNodes\n$Elements\n" << groups_.size() + surfaceBlocks << " " << numElements << " 1 " << numElements
        << "\n";
    int element = 1;
    for (std::size_t g = 0; g < groups_.size(); ++g) {
      const auto& nodes = groups_[g].nodes;
      if (groups_[g].dimension == 0) {
        msh << "0 " << g + 1 << " 15 1\n" << element++ << " " << nodes[0] << "\n";
        continue;
      }
      msh << "1 " << g + 1 << " 1 " << nodes.size() - 1 << "\n";
      for (std::size_t k = 0; k + 1 < nodes.size(); ++k) msh << element++ << " " << nodes[k] << " " << nodes[k + 1] << "\n";
    }
    if (!quads.empty()) {
      msh << "2 1 3 " << quads.size() << "\n";
      for (const auto& q : quads) msh << element++ << " " << q[0] << " " << q[1] << " " << q[2] << " " << q[3] << "\n";
    }
    if (!triangles.empty()) {
      msh << "2 1 2 " << triangles.size() << "\n";
      for (const auto& t : triangles) msh << element++ << " " << t[0] << " " << t[1] << " " << t[2] << "\n";
    }
    msh << "$EndElements\n";
    std::ofstream file(path);
    file << msh.str();
    if (!file) throw std::runtime_error("cannot write " + path);
  }

 private:
  struct Group {
    std::string name;
    int dimension;
    std::vector<int> nodes;  // Gmsh tags, in order along a line
  };

  std::array<double, 3> coordinates(int nodeTag) const {
    const int i = (nodeTag - 1) % (cells1_ + 1), j = (nodeTag - 1) / (cells1_ + 1);
    return position_(double(i) / cells1_, double(j) / cells2_);
  }

  int cells1_, cells2_;
  Position position_;
  std::function<bool(int, int)> split_;
  std::vector<Group> groups_;
};

}  // namespace perishell_test
