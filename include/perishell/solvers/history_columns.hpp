#pragma once
// The history.csv columns the explicit and the implicit run write alike (docs/deck.md,
// `output`): support reactions, load-point displacements and probes. Built once at run start
// from the model, on the host; each row reads host copies the run makes at history steps.
#include <perishell/model/model.hpp>

#include <ostream>
#include <string>
#include <vector>

namespace perishell::solvers {

using HostNodalForces = Kokkos::View<const double* [6], Kokkos::LayoutRight, Kokkos::HostSpace>;
using HostDisplacements = Kokkos::View<const double* [3], Kokkos::LayoutRight, Kokkos::HostSpace>;
using HostRotations = Kokkos::View<const double* [4], Kokkos::LayoutRight, Kokkos::HostSpace>;

// An output.probes point snapped to its nearest mesh node.
struct SnappedProbe {
  std::string name;
  LocalIndex node = -1;
  double distance = 0.0;  // [m] from the deck's point to the node
};

// How far a probe may lie from its nearest node [m]: max(mesh.spacing, the longest element
// edge). A point on the shell is nearer than that to a node of its element (a square's centre
// is 0.71 edges from its corners); the edge term admits generated meshes whose cells came out
// larger than the spacing (round(length / spacing) cells) and graded Gmsh meshes, whose
// mesh.spacing is only nominal. A point farther off is a mistake in the deck (units, a typo).
double probeReach(const model::Model& model);

// The nearest node of every output.probes point (the first in node order on a tie). Throws
// DeckError naming output.probes.<name> and the distance when it is farther than probeReach.
std::vector<SnappedProbe> snapProbes(const model::Model& model);

// One line per probe: its node, where the node is and how far it is from the deck's point.
void printProbes(const model::Model& model, const std::vector<SnappedProbe>& probes, std::ostream& log);

class HistoryColumns {
 public:
  // Snaps the probes (throws DeckError as snapProbes) and splits the supports' DOFs.
  explicit HistoryColumns(const model::Model& model);

  // reaction-<support>-x/y/z for each support, then reaction-total-x/y/z.
  std::vector<std::string> reactionColumns() const;
  // outOfBalance: P - F_int at every node DOF [N, N m]; a prescribed DOF's reaction is minus it
  // and goes to the supports that prescribe that DOF, in equal shares when several do (two
  // edge sets meeting at a corner), so the supports together carry every prescribed DOF once.
  void appendReactions(const HostNodalForces& outOfBalance, std::vector<double>& row) const;

  // <load>-ux/uy/uz for each point-force load: the mean displacement of its nodes.
  std::vector<std::string> loadPointColumns() const;
  void appendLoadPoints(const HostDisplacements& displacements, std::vector<double>& row) const;

  // <probe>-ux/uy/uz/rx/ry/rz for each probe: its node's displacement and rotation vector.
  std::vector<std::string> probeColumns() const;
  void appendProbes(const HostDisplacements& displacements, const HostRotations& rotations,
                    std::vector<double>& row) const;
  const std::vector<SnappedProbe>& probes() const { return probes_; }

 private:
  struct DofShare {
    LocalIndex node;
    int dof;        // 0..2: ux uy uz
    double weight;  // 1 / the number of supports prescribing this node DOF
  };
  const model::Model* model_;
  std::vector<std::vector<DofShare>> supportShares_;  // per deck support
  std::vector<DofShare> prescribed_;  // every prescribed translational node DOF once, weight 1
  std::vector<SnappedProbe> probes_;
};

}  // namespace perishell::solvers
