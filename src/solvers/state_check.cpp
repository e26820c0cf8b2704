#include <perishell/solvers/state_check.hpp>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace perishell::solvers {

namespace {

std::string formatNumber(double value) {
  std::ostringstream text;
  text.precision(4);
  text << value;
  return text.str();
}

std::string formatPoint(const std::array<double, 3>& point) {
  return "[" + formatNumber(point[0]) + ", " + formatNumber(point[1]) + ", " + formatNumber(point[2]) + "] m";
}

double norm(const deck::Vector3& vector) { return std::hypot(vector[0], vector[1], vector[2]); }

}  // namespace

std::string DisplacementExtent::describe() const {
  if (!finite) return "the displacement is not finite at the node at " + formatPoint(at);
  return "the largest displacement is |u| = " + formatNumber(largest) + " m at the node at " + formatPoint(at) +
         (largest > limit ? " (more than " + formatNumber(blownUpDisplacementFactor) + " x the model's size)" : "");
}

DisplacementExtent displacementExtent(const model::Model& model, const HostDisplacements& displacements) {
  const auto& x = model.shell.mesh.coordinates;
  const LocalIndex numNodes = model.numMeshNodes();
  DisplacementExtent extent;
  std::array<double, 3> low{HUGE_VAL, HUGE_VAL, HUGE_VAL}, high{-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
  for (LocalIndex node = 0; node < numNodes; ++node) {
    for (int d = 0; d < 3; ++d) {
      low[d] = std::min(low[d], x(node, d));
      high[d] = std::max(high[d], x(node, d));
    }
    const double length = std::hypot(displacements(node, 0), displacements(node, 1), displacements(node, 2));
    const bool finiteNode = std::isfinite(length);
    if (!finiteNode && extent.finite) {
      extent.finite = false;
      extent.at = {x(node, 0), x(node, 1), x(node, 2)};
    }
    if (finiteNode && length > extent.largest) {
      extent.largest = length;
      if (extent.finite) extent.at = {x(node, 0), x(node, 1), x(node, 2)};
    }
  }
  const double diagonal = numNodes > 0 ? std::hypot(high[0] - low[0], high[1] - low[1], high[2] - low[2]) : 0.0;
  extent.limit = blownUpDisplacementFactor * diagonal;
  return extent;
}

std::string largestActionText(const Deck& deck) {
  std::string text;
  double largest = -1.0;
  auto consider = [&](double magnitude, const std::string& key, const char* unit) {
    if (magnitude > largest) {
      largest = magnitude;
      text = key + " = " + formatNumber(magnitude) + " " + unit;
    }
  };
  for (const auto& load : deck.loads) {
    const char* unit = load.type == deck::LoadType::PointForce ? "N" : "Pa";
    const std::string key = "loads." + load.name;
    if (load.value) consider(std::fabs(*load.value), key + ".value", unit);
    if (load.vector) consider(norm(*load.vector), key + ".vector (magnitude)", unit);
    if (load.moment) consider(norm(*load.moment), key + ".moment (magnitude)", "N m");
  }
  if (!text.empty()) return "the largest load is " + text;
  for (const auto& support : deck.supports)
    if (support.value != 0.0) consider(std::fabs(support.value), "supports." + support.name + ".value", "m or rad");
  return text.empty() ? text : "the largest prescribed value is " + text;
}

std::string explicitBlowUpCause(const Deck& deck, double timeStep, double criticalTimeStep) {
  const auto& settings = deck.solver.explicitSettings;
  const double ratio = timeStep / criticalTimeStep;
  const std::string actions = largestActionText(deck);
  if (settings.timeStep && ratio > 1.0)
    return "solver.dt = " + formatNumber(timeStep) + " s is " + formatNumber(ratio) +
           " x the estimated critical step " + formatNumber(criticalTimeStep) +
           " s: lower solver.dt, or leave it out to use a safe fraction of the estimate";
  std::string cause = settings.timeStep
                          ? "solver.dt = " + formatNumber(timeStep) + " s is " + formatNumber(ratio) +
                                " x the estimated critical step " + formatNumber(criticalTimeStep) + " s, below it"
                          : "the time step was the estimated critical step " + formatNumber(criticalTimeStep) +
                                " s x " + formatNumber(settings.safetyFactor) + " (the deck sets no dt)";
  return cause + (actions.empty() ? "; the material and mesh set the estimate, check their values"
                                  : "; the loads are the likely cause: " + actions);
}

std::string implicitBlowUpCause(const Deck& deck) {
  const std::string actions = largestActionText(deck);
  return actions.empty() ? "the material values or the supports"
                         : "the loads (" + actions + "), or supports that leave the model free to move";
}

}  // namespace perishell::solvers
