#pragma once
// A case deck: the YAML file that describes one run (mesh, material, zones, supports, loads,
// solver, output), read with Teuchos' YAML parser and validated against the schema in
// docs/deck.md. The result is a plain host struct in SI units; no Teuchos types appear here
// so that consumers stay light.
#include <perishell/mesh/crack_segment.hpp>

#include <array>
#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace perishell {

// Every problem with a deck: what() is "<deck file>: <key path>: <reason>" (without the key
// path for file-level problems such as YAML syntax errors). Key paths are relative to the
// root key and dot-separated, e.g. "material.poisson-ratio" or "loads.top.curve".
class DeckError : public std::runtime_error {
 public:
  DeckError(const std::string& sourceName, const std::string& keyPath, const std::string& reason,
            int line = 0);
  const std::string& sourceName() const { return sourceName_; }
  const std::string& keyPath() const { return keyPath_; }
  const std::string& reason() const { return reason_; }
  // The YAML line the parser reported (1-based), 0 when unknown.
  int line() const { return line_; }

 private:
  std::string sourceName_;
  std::string keyPath_;
  std::string reason_;
  int line_;
};

namespace deck {

using Vector3 = std::array<double, 3>;

enum class MeshGenerator { Plate, Cylinder, HexagonalPrism, Gmsh };

struct PreCrack {
  std::string name;
  mesh::CrackSegment segment;  // metres; normal is unit length
};

// A node set defined in the deck: the nodes whose reference position lies in the box, for
// loads and supports on points the generators do not name (e.g. crack flanks).
struct BoxNodeSet {
  std::string name;
  Vector3 min{}, max{};  // [m]
};

struct Mesh {
  MeshGenerator generator = MeshGenerator::Plate;
  double spacing = 0.0;  // Δx [m]
  // Only the keys of the chosen generator are set; the others stay 0 / empty.
  double lengthX = 0.0, lengthY = 0.0;  // plate [m]
  double radius = 0.0, height = 0.0;    // cylinder [m]
  double side = 0.0, length = 0.0;      // hexagonal prism [m]
  std::string file;                     // gmsh: resolved against the deck's directory
  std::vector<PreCrack> preCracks;      // in deck order
  std::vector<BoxNodeSet> nodeSets;     // in deck order; added to the mesh's own sets
};

struct Material {
  double youngModulus = 0.0;             // E [Pa]
  double poissonRatio = 0.0;             // ν
  double density = 0.0;                  // ρ [kg/m^3]
  double thickness = 0.0;                // t [m]
  std::optional<double> fractureEnergy;  // G_c [J/m^2]; absent: bonds never break
};

enum class ForceKernel { BondScatter, NodeGather };

struct Peridynamics {
  double horizonFactor = 3.0;  // m = δ/Δx
  ForceKernel forceKernel = ForceKernel::NodeGather;
  // Clamped edges of PD regions get a held layer one horizon wide (mesh/support_layer.hpp).
  bool supportLayer = true;
};

enum class ZoneKind { Pd, Ccm };
enum class RegionShape { Box, Cylinder, ElementSet };

struct PdRegion {
  std::string name;
  RegionShape shape = RegionShape::Box;
  Vector3 boxMin{}, boxMax{};  // box [m]
  Vector3 center{}, axis{};    // cylinder [m]; axis is unit length
  double radius = 0.0, halfLength = 0.0;
  std::string elementSet;  // element-set
};

struct NamedPoint {
  std::string name;
  Vector3 position{};  // [m]
};

struct PdRatio {
  double target = 0.0;  // fraction of elements flagged PD, in [0, 1]
  std::vector<NamedPoint> around;
};

enum class TransitionProfile { Cubic, Linear };

// The PD-CCM morphing transition around the PD zone (model.md §4, docs/coupling.md): alpha
// falls from 1 on the PD nodes to 0 at distance `width` along the profile.
struct Transition {
  double width = 0.0;  // L_c [m]; the reader fills in its default 2 delta; 0 here also means 2 delta
  TransitionProfile profile = TransitionProfile::Cubic;
};

// zones.adaptive (explicit runs): a CCM element turns PD when its largest surface strain
// reaches strainFraction x the bonds' critical stretch s_c, and with it the CCM elements
// within `margin` of it (coupling/adaptive_zone.hpp).
struct AdaptiveZone {
  double strainFraction = 0.5;
  long long checkEvery = 10;  // steps between checks
  double margin = 0.0;        // [m]; the reader fills in its default 2 delta
};

struct Zones {
  ZoneKind defaultKind = ZoneKind::Pd;
  std::vector<PdRegion> pdRegions;
  std::optional<PdRatio> pdRatio;
  Transition transition;
  std::optional<AdaptiveZone> adaptive;
  // Whether any element can be PD (the ν <= 1/3 rule and fracture depend on it).
  bool hasPd() const {
    return defaultKind == ZoneKind::Pd || !pdRegions.empty() || (pdRatio && pdRatio->target > 0.0) || adaptive;
  }
};

// Values are the DOF's index in a node's six (model.md §1).
enum class Dof { Ux = 0, Uy = 1, Uz = 2, Rx = 3, Ry = 4, Rz = 5 };

struct Support {
  std::string name;
  std::string set;  // node or edge set of the mesh
  std::vector<Dof> dofs;
  double value = 0.0;  // prescribed value [m or rad], times the curve when one is given
  std::string curve;   // empty: constant
};

enum class LoadType { PointForce, EdgeTraction, Pressure };

struct Load {
  std::string name;
  LoadType type = LoadType::PointForce;
  std::string set;  // point-force, edge-traction: node / edge set; pressure: element set, empty = all
  // point-force: vector [N]; edge-traction: vector [Pa] (fixed global direction) or value [Pa]
  // (along the outward in-plane edge normal); pressure: value [Pa] along the element normal or
  // vector [Pa] (force per unit reference area in a fixed global direction).
  std::optional<Vector3> vector;
  std::optional<double> value;
  std::optional<Vector3> moment;  // point-force: moment on every node of the set [N m]
  bool follower = false;  // pressure only: turns with the element
  std::string curve;      // empty: see docs/deck.md (constant, or the implicit ramp)
};

enum class CurveType { Ramp, Step, Table };

struct Curve {
  std::string name;
  CurveType type = CurveType::Ramp;
  double endTime = 0.0;   // ramp [s]
  double stepTime = 0.0;  // step [s]
  std::vector<double> times, values;  // table: strictly increasing times [s]
};

enum class SolverType { Explicit, Implicit };
// How Newton solves K du = r (docs/implicit.md, "Linear solvers"): PCG (GMRES for the exact
// tangent) with a point or nodal-block Jacobi, smoothed-aggregation multigrid, or a sparse
// Cholesky factorization of a recent tangent; Direct refactors at every Newton iteration; Auto
// picks Cholesky or Amg by size and by the iterations AMG needs (solvers::NewtonOptions).
enum class Preconditioner { Jacobi, BlockJacobi, Amg, Cholesky, Direct, Auto };
// Where a GPU run factors its tangent (Cholesky, Direct): on the device (cuSOLVER), on the
// host (CHOLMOD, vectors cross PCIe at each application), or Auto (solvers::NewtonOptions).
// Host runs always factor on the host.
enum class Factorization { Auto, Host, Device };
// Auto: Exact where the model applies moments, else Symmetric (TangentForm, core/types.hpp).
enum class Tangent { Auto, Symmetric, Exact };

struct ExplicitSettings {
  // Exactly one of endTime / steps is set.
  std::optional<double> endTime;  // [s]
  std::optional<long long> steps;
  std::optional<double> timeStep;  // dt [s]; absent: safetyFactor times the stable estimate
  double safetyFactor = 0.9;
  double damping = 0.0;  // mass-proportional damping coefficient [1/s]
  // The CCM elements' formulation (docs/explicit.md, "The explicit shell element").
  enum class ShellElement { OnePoint, Mitc4 } shellElement = ShellElement::OnePoint;
  double hourglassCoefficient = 0.1;  // r of the one-point element's hourglass stiffness
};

struct ImplicitSettings {
  int increments = 1;
  int maxIterations = 100;
  double tolerance = 1e-8;  // Newton: residual norm relative to the external load norm
  Preconditioner preconditioner = Preconditioner::Auto;
  Factorization factorization = Factorization::Auto;
  int maxCuts = 8;  // bisections of an increment Newton fails on, before the run stops
  Tangent tangent = Tangent::Auto;
  // Newton reuses the AMG hierarchy while its Krylov iterations stay within this factor of
  // those right after a rebuild; 0 rebuilds it every iteration (solvers::NewtonOptions).
  double amgReuse = 1.5;
  // Couplings weaker than this (scaled) are ignored by the AMG aggregation
  // (multigrid::SmoothedAggregationOptions::dropTolerance).
  double amgDropTolerance = 0.05;
  // The most nodes of the AMG's densely inverted coarsest level
  // (multigrid::SmoothedAggregationOptions::maxCoarseNodes).
  int amgCoarseNodes = 200;
  // Whether the AMG smoother and prolongator scale the PD nodes and the shell-only nodes each
  // by their own spectrum (multigrid::SmoothedAggregationOptions::regionScaling).
  bool amgRegionScaling = true;
  // Whether a distributed run couples its ranks' preconditioners through a coarse space of
  // each rank's rigid-body modes (solvers::NewtonOptions::coarseSpace).
  bool coarseSpace = true;
  // Whether each rank's preconditioner of a distributed run covers its exchanged halo nodes too
  // (solvers::NewtonOptions::overlap).
  bool overlap = true;
  bool lineSearch = false;  // solvers::NewtonOptions::lineSearch
  // Mixed: the shell elements' local forces are Newton unknowns of their own
  // (solvers::NewtonOptions::mixedFormat); Displacement: the classical Newton.
  enum class Newton { Mixed, Displacement } newton = Newton::Mixed;
  // Load: the load factor steps 1/increments at a time. ArcLength: the load factor is an
  // unknown of the arc-length method (solvers::StaticNewtonSolver::advanceByArcLength); its
  // first step is 1/increments, and the run ends at load factor 1 or after maxIncrements.
  enum class Control { Load, ArcLength } control = Control::Load;
  int maxIncrements = 0;  // 0: 10 x increments
};

struct Solver {
  SolverType type = SolverType::Explicit;
  ExplicitSettings explicitSettings;  // read when type == Explicit
  ImplicitSettings implicitSettings;  // read when type == Implicit
};

enum class OutputField { Displacement, Rotation, Velocity, Damage, Zone };
enum class HistoryQuantity { Energy, Reactions, BrokenBonds, CrackTip, LoadPoints };

struct Output {
  std::string directory = "output";  // resolved against the deck's directory
  long long every = 0;               // steps or increments between writes; 0: the final state only
  long long historyEvery = 100;      // steps or increments between history rows; default: every (100 if 0)
  std::vector<OutputField> fields{OutputField::Displacement, OutputField::Damage};
  std::vector<HistoryQuantity> history;
  // History probes: each point snaps to its nearest mesh node at run start (solvers/history_columns.hpp),
  // whose displacement and rotation vector are written as columns <name>-ux .. <name>-rz.
  std::vector<NamedPoint> probes;  // in deck order
  // Checkpoints (docs/reliability.md §9): every this many steps or increments, and/or every
  // this many wall-clock minutes; 0: none on a schedule (a stopped run still writes one).
  long long checkpointEvery = 0;
  double checkpointMinutes = 0.0;
  bool checkpoints() const { return checkpointEvery > 0 || checkpointMinutes > 0.0; }
};

// Load factor of a curve at time t (docs/deck.md: ramp t/end-time clamped to [0, 1]; step
// 0 before its time and 1 from it; table linear between points, held beyond the ends).
double evaluateCurve(const Curve& curve, double time);

}  // namespace deck

struct Deck {
  std::string sourceName;  // the file (or name) it was read from
  int version = 1;
  std::string title;
  deck::Mesh mesh;
  deck::Material material;
  deck::Peridynamics peridynamics;
  deck::Zones zones;
  std::vector<deck::Support> supports;
  std::vector<deck::Load> loads;
  std::vector<deck::Curve> curves;
  deck::Solver solver;
  deck::Output output;
  // Legal but suspicious settings (e.g. an explicit run with no supports), for the caller to print.
  std::vector<std::string> warnings;

  // The curve with this name, or nullptr.
  const deck::Curve* findCurve(const std::string& name) const;
};

// The largest deck read [bytes]; a larger one is refused before parsing (docs/deck.md).
constexpr std::size_t maxDeckBytes = std::size_t(1) << 20;

// Reads and validates a deck file; relative paths in it (mesh.file, output.directory) are
// resolved against the file's directory. Throws DeckError.
Deck readDeck(const std::string& path);

// Same for deck text; sourceName names it in messages and its directory anchors relative paths.
Deck parseDeck(const std::string& yamlText, const std::string& sourceName);

}  // namespace perishell
