#pragma once
// Overlapping additive Schwarz over the ranks of a distributed implicit solve (docs/parallel.md,
// "Coupling the ranks' preconditioners"). Without overlap each rank's preconditioner sees its
// owned block with the cut's neighbours held fixed; on a thin plate (a fourth-order problem)
// that costs Krylov iterations growing fast with the rank count. Here each rank's block is
// widened by its exchanged halo nodes (3 delta + the transition + 2 elements deep): A_p is the
// tangent restricted to those nodes, a principal submatrix, hence symmetric and positive
// definite wherever the tangent is. A halo row assembled locally holds only this rank's
// elements and bonds (with the initial-stress part not even semi-definite), so the halo rows
// are imported whole from their owners.
//
// OverlapImport builds A_p: the owned rows from the local tangent, the exchanged halo rows
// from their owners (their values packed on the device, staged through the host like the
// halo exchange), columns outside the overlap dropped, the other halo rows the identity. The
// pattern is the local tangent's: the local model holds every element and bond among its
// nodes, so an imported row's columns that are local are in the pattern (checked).
//
// AdditiveSchwarz applies y = sum_p R_p^T M_p R_p x, M_p ~ A_p^-1 (AMG, a Cholesky factor or
// block Jacobi of A_p): the input's halo rows are filled from their owners, M_p is applied,
// and the output's halo rows are added into their owners' rows (NodeDistribution::accumulate).
// Symmetric where each M_p is, as CG needs.
#include <perishell/core/types.hpp>
#include <perishell/parallel/node_distribution.hpp>
#include <perishell/solvers/belos/crs_operator.hpp>
#include <perishell/solvers/belos/kokkos_multivector.hpp>

#include <BelosOperator.hpp>
#include <Kokkos_Core.hpp>
#include <Teuchos_RCP.hpp>

#include <memory>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

namespace perishell::belos {

template <class ExecutionSpaceT>
class OverlapImport {
 public:
  using memory_space = typename ExecutionSpaceT::memory_space;
  using Matrix = CrsMatrix<ExecutionSpaceT>;
  using Distribution = parallel::NodeDistribution<memory_space>;
  static constexpr int dofPerNode = 6;

  // Which of the local tangent's entries each rank sends and where the received ones go
  // (host, once per pattern). Collective.
  OverlapImport(const ExecutionSpaceT& space, const Matrix& K, std::shared_ptr<Distribution> distribution)
      : space_(space), distribution_(std::move(distribution)) {
    const auto rowMap = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, K.graph.row_map);
    const auto entries = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, K.graph.entries);
    const auto globalIds = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, distribution_->globalIds());
    const auto slots = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, distribution_->ownerSlots());
    const auto& communicator = distribution_->communicator();
    const auto& ranks = distribution_->neighbourRanks();
    // Rows go out as (entries, global column DOF...) per row, in the exchange's node order.
    std::vector<std::vector<long long>> patterns(communicator.size());
    std::vector<RowOffset> sources;
    sendOffsets_.assign(1, 0);
    for (std::size_t k = 0; k < ranks.size(); ++k) {
      auto& pattern = patterns[ranks[k]];
      for (const LocalIndex node : distribution_->sendLists()[k])
        for (int d = 0; d < dofPerNode; ++d) {
          const std::size_t row = dofPerNode * static_cast<std::size_t>(node) + d;
          pattern.push_back(static_cast<long long>(rowMap(row + 1) - rowMap(row)));
          for (RowOffset e = rowMap(row); e < rowMap(row + 1); ++e) {
            const LocalIndex column = entries(e);
            pattern.push_back(dofPerNode * globalIds(column / dofPerNode) + column % dofPerNode);
            sources.push_back(e);
          }
        }
      sendOffsets_.push_back(sources.size());
    }
    const auto received = communicator.allToAll(patterns);
    std::unordered_map<long long, LocalIndex> localOf;
    for (std::size_t node = 0; node < globalIds.extent(0); ++node)
      localOf[globalIds(node)] = static_cast<LocalIndex>(node);
    std::vector<long long> targets;  // -1: a column outside the overlap, dropped
    std::unordered_map<LocalIndex, RowOffset> entryOf;
    receiveOffsets_.assign(1, 0);
    for (std::size_t k = 0; k < ranks.size(); ++k) {
      const auto& pattern = received[ranks[k]];
      std::size_t at = 0;
      for (const LocalIndex node : distribution_->receiveLists()[k])
        for (int d = 0; d < dofPerNode; ++d) {
          const std::size_t row = dofPerNode * static_cast<std::size_t>(node) + d;
          if (at >= pattern.size()) throw std::logic_error("perishell::belos::OverlapImport: a row is missing");
          const long long count = pattern[at++];
          entryOf.clear();  // the local row's entries by column: a PD row holds hundreds
          for (RowOffset e = rowMap(row); e < rowMap(row + 1); ++e) entryOf[entries(e)] = e;
          bool diagonal = false;
          for (long long c = 0; c < count; ++c, ++at) {
            const long long dof = pattern.at(at);
            long long target = -1;
            const auto found = localOf.find(dof / dofPerNode);
            if (found != localOf.end() && slots(found->second) >= 0) {
              const LocalIndex column = dofPerNode * found->second + static_cast<LocalIndex>(dof % dofPerNode);
              const auto entry = entryOf.find(column);
              if (entry == entryOf.end())
                throw std::logic_error("perishell::belos::OverlapImport: an imported row's column is local but not in "
                                       "the local pattern");
              target = static_cast<long long>(entry->second);
              diagonal = diagonal || column == static_cast<LocalIndex>(row);
            }
            targets.push_back(target);
          }
          if (!diagonal) throw std::logic_error("perishell::belos::OverlapImport: an imported row has no diagonal");
        }
      receiveOffsets_.push_back(targets.size());
    }
    sources_ = viewOf<memory_space>(sources, "perishell::overlap::sources");
    targets_ = viewOf<memory_space>(targets, "perishell::overlap::targets");
    sendBuffer_ = VectorView<memory_space>("perishell::overlap::send", sources.size());
    receiveBuffer_ = VectorView<memory_space>("perishell::overlap::receive", targets.size());
    hostSend_ = Kokkos::create_mirror_view(sendBuffer_);
    hostReceive_ = Kokkos::create_mirror_view(receiveBuffer_);
    values_ = VectorView<memory_space>("perishell::overlap::values", K.values.extent(0));
  }

  // The distribution the import exchanges over; AdditiveSchwarz shares it (and its buffers).
  const std::shared_ptr<Distribution>& distribution() const { return distribution_; }

  // A_p from this rank's K (its pattern). Collective.
  Matrix overlapped(const Matrix& K) {
    const auto sources = sources_;
    const auto send = sendBuffer_;
    const auto values = K.values;
    Kokkos::parallel_for(
        "perishell::overlap::pack", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, sources.extent(0)),
        KOKKOS_LAMBDA(const std::size_t i) { send(i) = values(sources(i)); });
    space_.fence();
    Kokkos::deep_copy(hostSend_, sendBuffer_);
    distribution_->exchangeStaged(hostSend_.data(), sendOffsets_, hostReceive_.data(), receiveOffsets_, 1);
    Kokkos::deep_copy(receiveBuffer_, hostReceive_);
    fillOverlapped(K);
    return Matrix("perishell::overlap::A_p", K.numRows(), K.numCols(), K.nnz(), values_, K.graph.row_map,
                  K.graph.entries);
  }

  // Public only because nvcc rejects extended lambdas in private member functions.
  void fillOverlapped(const Matrix& K) const {
    const auto rowMap = K.graph.row_map;
    const auto entries = K.graph.entries;
    const auto values = K.values;
    const auto overlap = values_;
    const auto slots = distribution_->ownerSlots();
    Kokkos::parallel_for(
        "perishell::overlap::owned_rows", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, K.numRows()),
        KOKKOS_LAMBDA(const LocalIndex row) {
          const int slot = slots(row / dofPerNode);
          for (RowOffset e = rowMap(row); e < rowMap(row + 1); ++e) {
            const LocalIndex column = entries(e);
            overlap(e) = slot == 0 ? (slots(column / dofPerNode) >= 0 ? values(e) : 0.0)
                                   : (slot < 0 && column == row ? 1.0 : 0.0);
          }
        });
    const auto targets = targets_;
    const auto received = receiveBuffer_;
    Kokkos::parallel_for(
        "perishell::overlap::imported_rows", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, targets.extent(0)),
        KOKKOS_LAMBDA(const std::size_t i) {
          if (targets(i) >= 0) overlap(targets(i)) = received(i);
        });
  }

 private:
  ExecutionSpaceT space_;
  std::shared_ptr<Distribution> distribution_;
  std::vector<std::size_t> sendOffsets_, receiveOffsets_;
  Kokkos::View<RowOffset*, memory_space> sources_;  // per value sent: its entry of K
  Kokkos::View<long long*, memory_space> targets_;  // per value received: its entry of A_p (-1: dropped)
  VectorView<memory_space> sendBuffer_, receiveBuffer_, values_;
  typename VectorView<memory_space>::HostMirror hostSend_, hostReceive_;
};

template <class ExecutionSpaceT>
class AdditiveSchwarz final : public Belos::Operator<double> {
 public:
  using memory_space = typename ExecutionSpaceT::memory_space;
  using Distribution = parallel::NodeDistribution<memory_space>;

  // local: M_p, a preconditioner of OverlapImport::overlapped(K).
  AdditiveSchwarz(const ExecutionSpaceT& space, std::shared_ptr<Distribution> distribution,
                  Teuchos::RCP<const Belos::Operator<double>> local, std::size_t rows)
      : space_(space),
        distribution_(std::move(distribution)),
        local_(std::move(local)),
        input_("perishell::schwarz::input", rows, 1),
        output_("perishell::schwarz::output", rows, 1) {}

  void Apply(const Belos::MultiVec<double>& x, Belos::MultiVec<double>& y,
             Belos::ETrans /*symmetric*/ = Belos::NOTRANS) const override {
    constexpr const char* who = "perishell::belos::AdditiveSchwarz::Apply";
    const auto& xk = detail::asKokkos<ExecutionSpaceT>(x, who);
    auto& yk = detail::asKokkos<ExecutionSpaceT>(y, who);
    detail::checkApplyShapes(xk, yk, input_.extent(0), input_.extent(0), who);
    KokkosMultiVector<ExecutionSpaceT> in(input_), out(output_);
    using NodeRows =
        Kokkos::View<double* [6], Kokkos::LayoutRight, memory_space, Kokkos::MemoryTraits<Kokkos::Unmanaged>>;
    const std::size_t nodes = input_.extent(0) / 6;
    const NodeRows inNodes(input_.data(), nodes), outNodes(output_.data(), nodes);
    for (std::size_t j = 0; j < xk.view().extent(1); ++j) {
      Kokkos::deep_copy(space_, Kokkos::subview(input_, Kokkos::ALL(), 0),
                        Kokkos::subview(xk.view(), Kokkos::ALL(), j));
      distribution_->exchange(space_, inNodes);
      local_->Apply(in, out);
      distribution_->accumulate(space_, outNodes);
      ownedRowsInto(Kokkos::subview(yk.view(), Kokkos::ALL(), j));
    }
  }

  bool HasApplyTranspose() const override { return true; }

  // y = the output's owned rows, zero elsewhere. Public only because nvcc rejects extended
  // lambdas in private member functions.
  template <class ColumnT>
  void ownedRowsInto(const ColumnT& y) const {
    const auto slots = distribution_->ownerSlots();
    const auto output = output_;
    Kokkos::parallel_for(
        "perishell::schwarz::owned_rows", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, y.extent(0)),
        KOKKOS_LAMBDA(const std::size_t row) { y(row) = slots(row / 6) == 0 ? output(row, 0) : 0.0; });
  }

 private:
  ExecutionSpaceT space_;
  std::shared_ptr<Distribution> distribution_;
  Teuchos::RCP<const Belos::Operator<double>> local_;
  MultiVectorView<memory_space> input_, output_;
};

}  // namespace perishell::belos
