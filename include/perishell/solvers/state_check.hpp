#pragma once
// What both run drivers check before they write results and after the last step or
// increment (docs/reliability.md): the state must be finite and must not have blown up. A
// bad state stops the run with RunStateError, whose message names the step, the quantity and
// the likely cause in the deck's terms (only keys the deck sets are suggested).
#include <perishell/model/model.hpp>

#include <array>
#include <stdexcept>
#include <string>

namespace perishell::solvers {

class RunStateError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Newton gave up on an increment after every allowed cut; the state is the last converged one.
// Its decisions rest on global norms, so every rank of a distributed run throws it alike.
class NewtonFailure : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A displacement this many times the mesh's bounding-box diagonal is a blown-up state, not a
// deformation of the shell.
constexpr double blownUpDisplacementFactor = 1.0e3;

// The largest nodal displacement of the model's mesh nodes, and where.
struct DisplacementExtent {
  bool finite = true;        // every component of every node is finite
  double largest = 0.0;      // [m], over the finite nodes
  std::array<double, 3> at{0.0, 0.0, 0.0};  // reference position of that node (or of the first non-finite one) [m]
  double limit = 0.0;        // blownUpDisplacementFactor x the mesh's bounding-box diagonal [m]
  bool blownUp() const { return !finite || largest > limit; }
  // "the displacement is not finite at node [x, y, z] m" or "the largest displacement |u| = ... m at ...".
  std::string describe() const;
};

using HostDisplacements = Kokkos::View<const double* [3], Kokkos::LayoutRight, Kokkos::HostSpace>;
DisplacementExtent displacementExtent(const model::Model& model, const HostDisplacements& displacements);

// The deck's largest load, as "loads.<name>.value = V Pa" (or .vector, .moment), or of the
// supports' prescribed values; empty when the deck has neither.
std::string largestActionText(const Deck& deck);

// The likely cause of an explicit blow-up: the deck's solver.dt against the estimated
// critical step when it sets one; otherwise that the estimate was used, and the loads.
std::string explicitBlowUpCause(const Deck& deck, double timeStep, double criticalTimeStep);

// The likely cause of a non-finite or blown-up implicit state: the loads.
std::string implicitBlowUpCause(const Deck& deck);

}  // namespace perishell::solvers
