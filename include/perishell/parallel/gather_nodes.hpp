#pragma once
// Nodal fields of a distributed run brought together on the root, in mesh-node order, for
// output and checkpoints (docs/parallel.md): each rank sends its owned nodes' rows; the root
// writes the one file set a single-rank run writes. On a single rank, a host copy. And back:
// a checkpoint's mesh-ordered rows handed to every rank's local nodes, so that a run continues
// on any rank count.
#include <perishell/core/types.hpp>
#include <perishell/io/checkpoint.hpp>
#include <perishell/parallel/communicator.hpp>
#include <perishell/parallel/domain.hpp>

#include <string>
#include <vector>

namespace perishell::parallel {

class NodeGather {
 public:
  // domain: this rank's part, or nullptr on a single rank.
  NodeGather(const LocalDomain* domain, const Communicator& communicator, LocalIndex numMeshNodes)
      : communicator_(communicator), numMeshNodes_(numMeshNodes) {
    if (!domain || !communicator.distributed()) return;
    meshNodeOfLocal_.assign(domain->nodes.begin(), domain->nodes.end());
    std::vector<long long> mine;
    for (LocalIndex k = 0; k < domain->numNodes(); ++k)
      if (domain->owned[k]) {
        ownedLocal_.push_back(k);
        mine.push_back(domain->nodes[k]);
      }
    meshNodeOfRow_ = communicator.gather(mine);
    distributed_ = true;
  }

  bool root() const { return communicator_.root(); }
  const Communicator& communicator() const { return communicator_; }
  // The mesh node of a local node.
  long long meshNode(LocalIndex local) const { return distributed_ ? meshNodeOfLocal_[local] : local; }

  // The view's rows (nodes x columns, or nodes) of every mesh node on the root; empty on the
  // other ranks. Collective.
  template <class ViewT>
  Kokkos::View<typename ViewT::non_const_data_type, Kokkos::LayoutRight, Kokkos::HostSpace> gather(
      const ViewT& view) const {
    using Result = Kokkos::View<typename ViewT::non_const_data_type, Kokkos::LayoutRight, Kokkos::HostSpace>;
    const auto local = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, view);
    if (!distributed_) {
      Result copy(view.label(), local.extent(0));
      Kokkos::deep_copy(copy, local);
      return copy;
    }
    const int columns = ViewT::rank == 1 ? 1 : static_cast<int>(view.extent(1));
    const auto at = [&](const auto& v, std::size_t row, int column) -> auto& {
      if constexpr (ViewT::rank == 1) return v(row);
      else return v(row, column);
    };
    std::vector<double> rows;
    rows.reserve(ownedLocal_.size() * columns);
    for (const LocalIndex k : ownedLocal_)
      for (int c = 0; c < columns; ++c) rows.push_back(at(local, k, c));
    const auto all = communicator_.gather(rows);
    Result result(view.label(), communicator_.root() ? numMeshNodes_ : 0);
    if (communicator_.root())
      for (std::size_t r = 0; r < meshNodeOfRow_.size(); ++r)
        for (int c = 0; c < columns; ++c) at(result, meshNodeOfRow_[r], c) = all[r * columns + c];
    return result;
  }

  // Rows in mesh-node order (numMeshNodes x columns, row-major, as gather returns them) into
  // `view`'s rows of every local node, owned and halo alike (a halo node takes its owner's
  // values). False, `view` unchanged, when `rows` does not hold numMeshNodes x columns values.
  template <class ViewT, class ValueT>
  bool scatter(const std::vector<ValueT>& rows, const ViewT& view) const {
    const std::size_t columns = ViewT::rank == 1 ? 1 : view.extent(1);
    if (rows.size() != static_cast<std::size_t>(numMeshNodes_) * columns) return false;
    auto local = Kokkos::create_mirror_view(Kokkos::HostSpace{}, view);
    for (std::size_t k = 0; k < local.extent(0); ++k)
      for (std::size_t c = 0; c < columns; ++c) {
        const auto value = rows[static_cast<std::size_t>(meshNode(static_cast<LocalIndex>(k))) * columns + c];
        if constexpr (ViewT::rank == 1) local(k) = value;
        else local(k, c) = value;
      }
    Kokkos::deep_copy(view, local);
    return true;
  }

 private:
  Communicator communicator_;
  LocalIndex numMeshNodes_ = 0;
  bool distributed_ = false;
  std::vector<LocalIndex> ownedLocal_;
  std::vector<LocalIndex> meshNodeOfLocal_;  // distributed: the mesh node of every local node
  std::vector<long long> meshNodeOfRow_;  // root: the mesh node of each gathered row
};

// A nodal view as a checkpoint entry in mesh-node order, the same on any rank count: gathered
// to the root, which alone writes the checkpoint (other ranks put nothing). Collective.
template <class ViewT>
void putNodalView(io::Checkpoint& checkpoint, const std::string& name, const ViewT& view, const NodeGather& gather) {
  const auto rows = gather.gather(view);
  if (gather.root()) io::putView(checkpoint, name, rows);
}

// The entry back into every local node's rows of `view`; throws io::CheckpointError naming the
// entry and `mismatch` (what another length means) when it is not one row per mesh node.
template <class ViewT>
void takeNodalView(const io::Checkpoint& checkpoint, const std::string& name, const ViewT& view,
                   const NodeGather& gather, const std::string& mismatch) {
  static_assert(std::is_same_v<typename ViewT::non_const_value_type, double>, "nodal checkpoint entries are reals");
  const auto& rows = checkpoint.reals(name);
  if (!gather.scatter(rows, view))
    throw io::CheckpointError(checkpoint.context() + "'" + name + "' holds " + std::to_string(rows.size()) +
                              " values, not one row per node of this model: " + mismatch);
}

}  // namespace perishell::parallel
