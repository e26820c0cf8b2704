#pragma once
// Nodal fields of a distributed run brought together on the root, in mesh-node order, for
// output (docs/parallel.md): each rank sends its owned nodes' rows; the root writes the one
// file set a single-rank run writes. On a single rank, a host copy.
#include <perishell/core/types.hpp>
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

 private:
  Communicator communicator_;
  LocalIndex numMeshNodes_ = 0;
  bool distributed_ = false;
  std::vector<LocalIndex> ownedLocal_;
  std::vector<long long> meshNodeOfRow_;  // root: the mesh node of each gathered row
};

}  // namespace perishell::parallel
