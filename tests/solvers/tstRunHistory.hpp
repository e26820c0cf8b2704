// History columns both run drivers write (solvers/history_columns.hpp): the supports'
// reactions add up to minus the applied load whatever the overlap of their sets (a node DOF
// held by several supports is shared among them, not counted by each), and a probe reports
// its node's displacement and rotation vector.
#include <perishell/core/rotation.hpp>
#include <perishell/model/model.hpp>
#include <perishell/solvers/explicit/explicit_run.hpp>
#include <perishell/solvers/implicit/implicit_run.hpp>
#include <perishell/solvers/implicit/static_solver_from_model.hpp>

#include <solvers/run_files.hpp>

#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <string>

namespace perishell_test_run_history {

using namespace perishell_test_run_files;

// A scratch output directory, removed with the test.
struct Scratch {
  std::string path;
  Scratch() {
    char pattern[] = "/tmp/perishell_history_XXXXXX";
    path = mkdtemp(pattern) ? pattern : "";
  }
  ~Scratch() {
    if (!path.empty()) std::filesystem::remove_all(path);
  }
};

// A 0.1 m x 0.1 m x 1 mm steel plate meshed at 20 mm; `inner` is the node at (0.06, 0.04).
std::string plateDeck(const std::string& zones, const std::string& supports, const std::string& loads,
                      const std::string& solver, const std::string& output) {
  return R"(perishell:
  version: 1
  mesh:
    generator: plate
    length-x: 0.1
    length-y: 0.1
    spacing: 0.02
    node-sets:
      inner: {box: {min: [0.059, 0.039, -0.001], max: [0.061, 0.041, 0.001]}}
  material: {young-modulus: 210.0e9, poisson-ratio: 0.3, density: 7850.0, thickness: 1.0e-3}
  zones: )" + zones + R"(
  supports:
)" + supports + R"(  loads:
)" + loads + "  solver: " + solver + "\n  output:\n" + output;
}

template <class ExecutionSpaceT>
History runImplicitDeck(const std::string& text, std::string* log = nullptr) {
  const Scratch scratch;
  std::ostringstream out;
  const auto model = perishell::model::buildModel(perishell::parseDeck(text, "plate.yaml"));
  const auto summary = perishell::solvers::runImplicit(model, {scratch.path, backendOf<ExecutionSpaceT>()}, out);
  if (log) *log = out.str();
  return readHistory(summary.historyPath);
}

}  // namespace perishell_test_run_history

TEST(TEST_CATEGORY, run_history_reactions_add_up_to_the_applied_load) {
  using namespace perishell_test_run_history;
  const std::string clampedEdges =
      "    left: {set: left, dofs: [ux, uy, uz, rx, ry, rz]}\n"
      "    right: {set: right, dofs: [ux, uy, uz, rx, ry, rz]}\n"
      "    bottom: {set: bottom, dofs: [ux, uy, uz, rx, ry, rz]}\n"
      "    top: {set: top, dofs: [ux, uy, uz, rx, ry, rz]}\n";
  // A quarter plate: hinges at x = 0 and y = 0, symmetry planes at x = 0.1 and y = 0.1. PD
  // layers move as odd images beyond the hinges and even ones beyond the planes
  // (assembly/mirror_images.hpp); the images' reactions belong to their supports.
  const std::string hingesAndSymmetry =
      "    left: {set: left, dofs: [ux, uy, uz]}\n"
      "    bottom: {set: bottom, dofs: [ux, uy, uz]}\n"
      "    symmetryX: {set: right, dofs: [ux, ry, rz]}\n"
      "    symmetryY: {set: top, dofs: [uy, rx, rz]}\n";
  // The clamp and a roller share the corner (0, 0) in uz only; the pin shares it in ux, uy.
  const std::string clampAndRoller =
      "    clamp: {set: left, dofs: [ux, uy, uz, rx, ry, rz]}\n"
      "    roller: {set: bottom, dofs: [uz]}\n"
      "    pin: {set: bottom-left, dofs: [ux, uy]}\n";
  struct Case {
    const char* name;
    std::string zones, supports, loads;
    std::array<double, 3> applied;  // the total load [N]
  };
  const std::vector<Case> cases{
      // 100 kPa on 0.01 m^2 (a deflection of 0.6 t); the four edges share the four corners. At
      // 1 kPa the in-plane totals, zero here, come out at 3e-11 of the load: what is left there
      // is the round-off of the bond forces, about eps E t dx per node, not Newton's residual.
      {"pressure, four clamped edges, PD", "{default: pd}", clampedEdges,
       "    q: {type: pressure, value: 1.0e5}\n", {0.0, 0.0, 1000.0}},
      {"pressure, two hinges and two mirrored symmetry planes, PD", "{default: pd}", hingesAndSymmetry,
       "    q: {type: pressure, value: 1.0e5}\n", {0.0, 0.0, 1000.0}},
      // A traction on the right edge's section, 0.1 m x 1 mm.
      {"edge traction, clamp and roller, CCM", "{default: ccm}", clampAndRoller,
       "    pull: {type: edge-traction, set: right, vector: [2.0e6, 1.0e6, 5.0e4]}\n", {200.0, 100.0, 5.0}},
      // Two point forces, one on a free corner and one inside; a PD box in a CCM plate.
      {"point forces, clamp and roller, mixed",
       "{default: ccm, pd-regions: {box: {box: {min: [0.05, 0, -1], max: [0.1, 0.1, 1]}}}}", clampAndRoller,
       "    corner: {type: point-force, set: top-right, vector: [10.0, -20.0, 5.0]}\n"
       "    inside: {type: point-force, set: inner, vector: [10.0, -20.0, 5.0]}\n",
       {20.0, -40.0, 10.0}},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    // Newton to 1e-12 of the load: the free DOFs' residual, all that separates the reactions'
    // total from minus the load, is then below the bound asserted here.
    const auto history = runImplicitDeck<TEST_EXECSPACE>(
        plateDeck(c.zones, c.supports, c.loads, "{type: implicit, increments: 1, tolerance: 1.0e-12}",
                  "    history: [reactions]\n"));
    ASSERT_EQ(history.rows.size(), 1u);
    auto row = history.rows.back();
    const double scale = std::hypot(c.applied[0], c.applied[1], c.applied[2]);
    const char* axes[3] = {"x", "y", "z"};
    for (int d = 0; d < 3; ++d) {
      const std::string axis = axes[d];
      EXPECT_NEAR(row["reaction-total-" + axis], -c.applied[d], 1e-10 * scale) << axis;
      double supports = 0.0;
      for (const auto& column : history.columns)
        if (column.rfind("reaction-", 0) == 0 && column.rfind("reaction-total-", 0) != 0 &&
            column.substr(column.size() - 2) == "-" + axis)
          supports += row[column];
      EXPECT_NEAR(supports, row["reaction-total-" + axis], 1e-13 * scale) << axis;
    }
    if (c.supports == hingesAndSymmetry)  // the planes carry no z force: w is even across them
      for (const char* plane : {"symmetryX", "symmetryY"})
        EXPECT_NEAR(row[std::string("reaction-") + plane + "-z"], 0.0, 1e-10 * scale) << plane;
    else if (c.supports == clampedEdges)  // by symmetry each edge carries a quarter
      for (const char* edge : {"left", "right", "bottom", "top"})
        EXPECT_NEAR(row[std::string("reaction-") + edge + "-z"], -c.applied[2] / 4, 1e-10 * scale) << edge;
    else
      EXPECT_EQ(row["reaction-roller-x"], 0.0);  // the roller holds uz only
  }
}

TEST(TEST_CATEGORY, run_history_probes_report_their_node_in_the_implicit_run) {
  using namespace perishell_test_run_history;
  // Clamped on the left, a force and a twisting moment on the top-right corner; `tip` lies
  // 0.5 mm off that corner, `centre` on the node at (0.04, 0.06).
  const std::string text = plateDeck(
      "{default: ccm}", "    clamp: {set: left, dofs: [ux, uy, uz, rx, ry, rz]}\n",
      "    push: {type: point-force, set: top-right, vector: [1.0, 2.0, -3.0], moment: [0.05, 0.02, 0.01]}\n",
      "{type: implicit, increments: 1}",
      "    history: [load-points]\n    probes: {tip: [0.1, 0.1005, 0.0], centre: [0.04, 0.06, 0.0]}\n");
  std::string log;
  const auto history = runImplicitDeck<TEST_EXECSPACE>(text, &log);
  EXPECT_NE(log.find("probe tip: node 35 at [0.1, 0.1, 0] m, 0.0005 m from the deck's point\n"
                     "probe centre: node 20 at [0.04, 0.06, 0] m, 0 m from the deck's point\n"),
            std::string::npos)
      << log;
  const std::vector<std::string> probeColumns{"tip-ux",    "tip-uy",    "tip-uz",    "tip-rx",    "tip-ry",
                                              "tip-rz",    "centre-ux", "centre-uy", "centre-uz", "centre-rx",
                                              "centre-ry", "centre-rz"};
  ASSERT_GE(history.columns.size(), probeColumns.size());
  EXPECT_EQ(std::vector<std::string>(history.columns.end() - 12, history.columns.end()), probeColumns);
  auto row = history.rows.back();
  for (const char* axis : {"ux", "uy", "uz"})  // the same node as the load's
    EXPECT_EQ(row[std::string("tip-") + axis], row[std::string("push-") + axis]) << axis;

  // The same solve by hand: the nodes' displacements and the rotation vectors of their quaternions.
  const auto model = perishell::model::buildModel(perishell::parseDeck(text, "plate.yaml"));
  auto solver = perishell::solvers::makeStaticSolver(TEST_EXECSPACE{}, model);
  solver.advanceTo(1.0);
  const auto u = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, solver.kinematics().displacements);
  const auto q = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, solver.kinematics().rotations);
  for (const auto& [probe, node] : {std::pair<std::string, int>{"tip", 35}, {"centre", 20}}) {
    const double quaternion[4] = {q(node, 0), q(node, 1), q(node, 2), q(node, 3)};
    double theta[3];
    perishell::rotation::rotationVector(quaternion, theta);
    const char* axes[3] = {"x", "y", "z"};
    for (int d = 0; d < 3; ++d) {
      EXPECT_NEAR(row[probe + "-u" + axes[d]], u(node, d), 1e-9 * std::abs(row["tip-uz"])) << probe << d;
      EXPECT_NEAR(row[probe + "-r" + axes[d]], theta[d], 1e-9 * std::abs(row["tip-rx"])) << probe << d;
    }
  }
  EXPECT_GT(std::abs(row["tip-rx"]), 1e-4);  // the moment turns the corner about every axis
  EXPECT_GT(std::abs(row["tip-ry"]), 1e-4);
  EXPECT_GT(std::abs(row["tip-rz"]), 1e-5);  // about the normal: the stiffer drilling tie (3.2e-5)
}

TEST(TEST_CATEGORY, run_history_probes_and_shared_corners_in_the_explicit_run) {
  using namespace perishell_test_run_history;
  const Scratch scratch;
  const std::string text = plateDeck(
      "{default: pd}",
      "    clamp: {set: left, dofs: [ux, uy, uz, rx, ry, rz]}\n    roller: {set: bottom, dofs: [uz]}\n",
      "    push: {type: point-force, set: inner, vector: [0.0, 0.0, -50.0]}\n",
      "{type: explicit, steps: 60}",
      "    history-every: 20\n    history: [reactions, load-points]\n    probes: {inner: [0.06, 0.04, 0.0]}\n");
  const auto model = perishell::model::buildModel(perishell::parseDeck(text, "plate.yaml"));
  std::ostringstream log;
  const auto summary = perishell::solvers::runExplicit(model, {scratch.path, backendOf<TEST_EXECSPACE>()}, log);
  auto history = readHistory(summary.historyPath);
  ASSERT_EQ(history.rows.size(), 4u);  // steps 0, 20, 40, 60
  for (auto& row : history.rows) {
    SCOPED_TRACE("step " + std::to_string(row["step"]));
    for (const char* axis : {"ux", "uy", "uz"})
      EXPECT_EQ(row[std::string("inner-") + axis], row[std::string("push-") + axis]) << axis;
    for (const char* axis : {"x", "y", "z"})
      EXPECT_NEAR(row[std::string("reaction-clamp-") + axis] + row[std::string("reaction-roller-") + axis],
                  row[std::string("reaction-total-") + axis], 1e-12 * 50.0) << axis;
  }
  auto last = history.rows.back();
  EXPECT_LT(last["inner-uz"], 0.0);  // pushed down; the bending wave has reached the supports
  EXPECT_NE(last["reaction-clamp-z"], 0.0);
  EXPECT_NE(last["reaction-roller-z"], 0.0);
  EXPECT_GT(std::abs(last["inner-rx"]) + std::abs(last["inner-ry"]), 0.0);
}
