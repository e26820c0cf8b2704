#pragma once
// Nodal results as an XDMF 3 time series that ParaView (XDMF3 reader) opens as one dataset
// with a time slider. Host side: the caller passes host views; copies from the device are
// the caller's, made at output steps only.
//
// Files, all in one directory (paths inside the .xmf are relative to it):
//   <base>_mesh.h5    written once by the constructor: "/geometry" (nodes x 3, float64,
//                     x y z in m) and "/topology" (elements x 4, int32, counter-clockwise);
//   <base>_NNNNNN.h5  one per step (NNNNNN = step index from 0, six digits or more):
//                     "/time" (1 value, float64, s) and "/fields/<name>" (float64; nodes
//                     for a scalar, nodes x 3 for a vector);
//   <base>.xmf        a Temporal collection with one Uniform grid per step; the first step
//                     writes it whole, each later one replaces its closing tags by the
//                     step's grid and the closing tags (atomic_file.hpp, replaceFileTail), so
//                     a step costs its own grid and the file is complete XML after each step.
// The .h5 files are written atomically (atomic_file.hpp), the step's .h5 before the .xmf, so
// the .xmf on disk only ever lists complete .h5 files. A step that fails validation
// writes nothing; a step whose write fails leaves the previous .xmf as it was.
// Files of an earlier run in the same directory are replaced as this run reaches them; its
// .xmf lists only this run's steps from the first writeStep on (the run drivers clear an
// earlier run's files first, io/output_directory.hpp).
#include <perishell/core/types.hpp>
#include <perishell/mesh/quad_mesh.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace perishell::io {

using HostNodalValues = Kokkos::View<const double**, Kokkos::LayoutRight, Kokkos::HostSpace>;

struct NodalField {
  std::string name;        // letters, digits, '_', '-', '.'; starts with a letter, digit or '_'
  int components;          // 1: Scalar, 3: Vector
  HostNodalValues values;  // nodes x components
};

// Scalar fields from one value per node (a copy, made at output steps). Integer data
// (flags, counts) are written as float64, which holds every int exactly.
NodalField makeScalarField(std::string name, const Kokkos::View<const double*, Kokkos::HostSpace>& values);
NodalField makeScalarField(std::string name, const Kokkos::View<const int*, Kokkos::HostSpace>& values);
// The rotation vector (axis times angle, the logarithm of model.md §5) of each node's unit
// quaternion (w, x, y, z), a Vector field.
NodalField makeRotationVectorField(
    std::string name, const Kokkos::View<const double* [4], Kokkos::LayoutRight, Kokkos::HostSpace>& quaternions);

// The field on its first numNodes nodes (a model's own mesh, without its support layer).
NodalField firstNodes(const NodalField& field, LocalIndex numNodes);

class XdmfTimeSeriesWriter {
 public:
  // The directory must exist. baseName follows the field-name rule. Throws
  // std::invalid_argument on an empty mesh or connectivity outside the node range, and
  // std::runtime_error (naming the path and the reason) if the mesh file cannot be written.
  XdmfTimeSeriesWriter(std::string directory, std::string baseName, const mesh::HostQuadMesh& mesh);

  // Throws std::invalid_argument, before writing anything, if time is not finite or
  // decreases, or a field has an empty/ill-formed/repeated name, components other than 1
  // or 3, or values whose extents are not nodes x components.
  void writeStep(double time, const std::vector<NodalField>& fields);

  // What a step holds: its time and its fields' names and components.
  struct FieldRecord {
    std::string name;
    int components;
  };
  struct StepRecord {
    double time;
    std::vector<FieldRecord> fields;
  };

  // Continues the series an earlier run over the same mesh left in this directory (a restart,
  // io/checkpoint.hpp): its first earlier.size() steps stay as written, their step files must
  // exist (else std::runtime_error naming the first missing one); its step files after those are
  // removed and the .xmf is rewritten to list the kept steps, so writeStep appends to them.
  // Call before the first writeStep.
  void continueSeries(std::vector<StepRecord> earlier);

  int numSteps() const { return static_cast<int>(steps_.size()); }
  const std::vector<StepRecord>& steps() const { return steps_; }
  std::string xdmfPath() const;
  std::string meshPath() const;
  std::string stepPath(int step) const;

 private:

  std::string stepFileName(int step) const;
  std::string xdmfHeader() const;
  std::string xdmfGrid(int step, const StepRecord& record) const;
  static std::string xdmfClosing();

  std::string directory_;
  std::string baseName_;
  LocalIndex numNodes_;
  LocalIndex numElements_;
  // 0 for a quad mesh (topology numElements x 4, "Quadrilateral"); with triangles, the length
  // of the "Mixed" topology: per element its XDMF type (4 triangle, 5 quad) and its corners.
  std::size_t mixedTopologyLength_ = 0;
  std::vector<StepRecord> steps_;
  std::uintmax_t xdmfBytes_ = 0;  // the .xmf's size as this writer left it
};

}  // namespace perishell::io
