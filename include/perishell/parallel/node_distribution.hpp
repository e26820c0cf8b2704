#pragma once
// How a solver's nodes are shared among ranks (docs/parallel.md): which local nodes this rank
// owns, their global numbers, and the halo exchange that sets every halo node's state to its
// owner's. A single-rank run has an empty distribution: every node owned, nothing exchanged.
//
// The exchange packs the listed nodal views on the device (one buffer per neighbour, node by
// node), stages the buffers through host memory and sends them with MPI, then unpacks on the
// device. Host staging works with any MPI (Debian's Open MPI is not CUDA-aware). It may be
// started and finished apart (startExchange, finishExchange), so that a solver works on what
// the exchange does not write while the messages travel.
#include <perishell/core/types.hpp>
#include <perishell/parallel/communicator.hpp>
#include <perishell/parallel/domain.hpp>

#include <cstdint>
#include <stdexcept>
#include <type_traits>
#include <vector>

namespace perishell::parallel {

// Where the exchange's buffers are staged on the host: page-locked memory for a GPU's
// buffers, so that the copies run at full speed without a driver-side bounce buffer; the
// device buffers themselves where they are host memory already.
template <class MemorySpaceT>
struct StagingSpace {
  using type = std::conditional_t<Kokkos::SpaceAccessibility<Kokkos::HostSpace, MemorySpaceT>::accessible,
                                  MemorySpaceT, Kokkos::HostSpace>;
};
#ifdef KOKKOS_ENABLE_CUDA
template <>
struct StagingSpace<Kokkos::CudaSpace> {
  using type = Kokkos::CudaHostPinnedSpace;
};
#endif

template <class MemorySpaceT>
class NodeDistribution {
 public:
  NodeDistribution() = default;

  explicit NodeDistribution(const LocalDomain& domain, const Communicator& communicator)
      : communicator_(communicator), ranks_(domain.ranks), sendLists_(domain.sendNodes),
        receiveLists_(domain.receiveNodes) {
    const auto hostOwned = Kokkos::View<const std::uint8_t*, Kokkos::HostSpace, Kokkos::MemoryUnmanaged>(
        domain.owned.data(), domain.owned.size());
    owned_ = Kokkos::View<std::uint8_t*, MemorySpaceT>("owned nodes", domain.owned.size());
    Kokkos::deep_copy(owned_, hostOwned);
    Kokkos::View<long long*, Kokkos::HostSpace> hostGlobal("global node ids", domain.nodes.size());
    for (std::size_t k = 0; k < domain.nodes.size(); ++k) hostGlobal(k) = domain.nodes[k];
    globalIds_ = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, hostGlobal);
    sendNodes_ = flatten(domain.sendNodes, sendOffsets_, "halo send nodes");
    meshNodes_ = communicator.sum(domain.numOwned());
    receiveNodes_ = flatten(domain.receiveNodes, receiveOffsets_, "halo receive nodes");
    Kokkos::View<int*, Kokkos::HostSpace> slots("owner slots", domain.owned.size());
    for (std::size_t k = 0; k < domain.owned.size(); ++k) slots(k) = domain.owned[k] ? 0 : -1;
    for (std::size_t r = 0; r < domain.receiveNodes.size(); ++r)
      for (const LocalIndex node : domain.receiveNodes[r]) slots(node) = 1 + static_cast<int>(r);
    ownerSlots_ = Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, slots);
  }

  bool distributed() const { return owned_.extent(0) > 0; }
  const Communicator& communicator() const { return communicator_; }
  // 1 where this rank owns the node; empty on a single rank (every node owned).
  const Kokkos::View<std::uint8_t*, MemorySpaceT>& owned() const { return owned_; }
  // The global (mesh) number of every local node; empty on a single rank (local = global).
  const Kokkos::View<long long*, MemorySpaceT>& globalIds() const { return globalIds_; }
  // The ranks this one exchanges halo nodes with, and for neighbour k the local nodes it sends
  // them (owned) and those it receives (halo), in the exchange's order.
  const std::vector<int>& neighbourRanks() const { return ranks_; }
  const std::vector<std::vector<LocalIndex>>& sendLists() const { return sendLists_; }
  const std::vector<std::vector<LocalIndex>>& receiveLists() const { return receiveLists_; }
  // The local nodes the exchange writes (every neighbour's receive list, flattened).
  Kokkos::View<const LocalIndex*, MemorySpaceT> receivedNodes() const { return receiveNodes_; }
  // Per local node: 0 where this rank owns it, 1 + k where neighbourRanks()[k] owns it (a halo
  // node the exchange fills), -1 for the rest of the halo; empty on a single rank.
  const Kokkos::View<int*, MemorySpaceT>& ownerSlots() const { return ownerSlots_; }
  // The mesh nodes over every rank: how many terms of a sum over owned nodes may be non-zero
  // (parallel/reproducible_sum.hpp); on a single rank, the local count.
  long long meshNodes(std::size_t localNodes) const {
    return distributed() ? meshNodes_ : static_cast<long long>(localNodes);
  }

  // Sets every halo node's rows of `views` (each nodes x columns) to the owner's. Collective.
  template <class ExecutionSpaceT, class... ViewTs>
  void exchange(const ExecutionSpaceT& space, const ViewTs&... views) {
    startExchange(space, views...);
    finishExchange(space, views...);
  }

  // The first half of exchange(): packs the owned rows the neighbours need, stages them and
  // starts the messages. Until finishExchange the halo rows keep their old values; the views'
  // owned rows may be read, not written (they were sent already, but an exchange started again
  // before finishing is refused). Collective.
  template <class ExecutionSpaceT, class... ViewTs>
  void startExchange(const ExecutionSpaceT& space, const ViewTs&... views) {
    if (!distributed()) return;
    if (pending_.active()) throw std::logic_error("NodeDistribution: an exchange started before the last one finished");
    const int width = (0 + ... + static_cast<int>(views.extent(1)));
    if (bufferWidth_ < width) {
      bufferWidth_ = width;
      sendBuffer_ = Kokkos::View<double*, MemorySpaceT>("halo send buffer", sendNodes_.extent(0) * width);
      receiveBuffer_ = Kokkos::View<double*, MemorySpaceT>("halo receive buffer", receiveNodes_.extent(0) * width);
      hostSend_ = stagingMirror(sendBuffer_);
      hostReceive_ = stagingMirror(receiveBuffer_);
    }
    exchangeWidth_ = width;
    int column = 0;
    (pack(space, views, column, width), ...);
    Kokkos::deep_copy(space, hostSend_, sendBuffer_);
    space.fence();
    pending_ = startStaged(hostSend_.data(), sendOffsets_, hostReceive_.data(), receiveOffsets_, width);
  }

  // The second half: waits for the messages and unpacks them into the halo rows of the same
  // views, in the same order. Nothing when no exchange is in flight. Collective.
  template <class ExecutionSpaceT, class... ViewTs>
  void finishExchange(const ExecutionSpaceT& space, const ViewTs&... views) {
    if (!pending_.active()) return;
    const int width = (0 + ... + static_cast<int>(views.extent(1)));
    if (width != exchangeWidth_) throw std::logic_error("NodeDistribution: an exchange finished with other views");
    pending_.wait();
    Kokkos::deep_copy(space, receiveBuffer_, hostReceive_);
    int column = 0;
    (unpack(space, views, column, width), ...);
  }
  bool exchangeInFlight() const { return pending_.active(); }

  // The reverse of exchange(): adds every exchanged halo node's rows of `views` into its
  // owner's rows on the owning rank (an overlapping Schwarz's halo contributions), one
  // neighbour after the other in rank order, so the sums do not depend on timing. The halo rows
  // are left as they were. Collective.
  template <class ExecutionSpaceT, class ViewT>
  void accumulate(const ExecutionSpaceT& space, const ViewT& view) {
    if (!distributed()) return;
    const int width = static_cast<int>(view.extent(1));
    if (accumulateWidth_ < width) {
      accumulateWidth_ = width;
      returnBuffer_ = Kokkos::View<double*, MemorySpaceT>("halo return buffer", receiveNodes_.extent(0) * width);
      gatherBuffer_ = Kokkos::View<double*, MemorySpaceT>("halo gather buffer", sendNodes_.extent(0) * width);
      hostReturn_ = stagingMirror(returnBuffer_);
      hostGather_ = stagingMirror(gatherBuffer_);
    }
    packRows(space, view, receiveNodes_, returnBuffer_);
    Kokkos::deep_copy(space, hostReturn_, returnBuffer_);
    space.fence();
    exchangeStaged(hostReturn_.data(), receiveOffsets_, hostGather_.data(), sendOffsets_, width);
    Kokkos::deep_copy(space, gatherBuffer_, hostGather_);
    for (std::size_t k = 0; k < ranks_.size(); ++k) addRows(space, view, sendOffsets_[k], sendOffsets_[k + 1]);
  }

  // The steps below launch kernels; public only because nvcc rejects extended lambdas in
  // private member functions.
  template <class ExecutionSpaceT, class ViewT>
  void packRows(const ExecutionSpaceT& space, const ViewT& view, const Kokkos::View<LocalIndex*, MemorySpaceT>& nodes,
                const Kokkos::View<double*, MemorySpaceT>& buffer) const {
    const int width = static_cast<int>(view.extent(1));
    Kokkos::parallel_for(
        "perishell::parallel::NodeDistribution::packRows",
        Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, nodes.extent(0)), KOKKOS_LAMBDA(const std::size_t k) {
          for (int c = 0; c < width; ++c) buffer(k * width + c) = view(nodes(k), c);
        });
  }
  template <class ExecutionSpaceT, class ViewT>
  void addRows(const ExecutionSpaceT& space, const ViewT& view, std::size_t first, std::size_t last) const {
    const auto nodes = sendNodes_;
    const auto buffer = gatherBuffer_;
    const int width = static_cast<int>(view.extent(1));
    Kokkos::parallel_for(
        "perishell::parallel::NodeDistribution::addRows", Kokkos::RangePolicy<ExecutionSpaceT>(space, first, last),
        KOKKOS_LAMBDA(const std::size_t k) {
          for (int c = 0; c < width; ++c) view(nodes(k), c) += buffer(k * width + c);
        });
  }
  template <class ExecutionSpaceT, class ViewT>
  void pack(const ExecutionSpaceT& space, const ViewT& view, int& column, int width) const {
    const auto nodes = sendNodes_;
    const auto buffer = sendBuffer_;
    const int first = column, columns = static_cast<int>(view.extent(1));
    Kokkos::parallel_for(
        "perishell::parallel::NodeDistribution::pack", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, nodes.extent(0)),
        KOKKOS_LAMBDA(const std::size_t k) {
          for (int c = 0; c < columns; ++c) buffer(k * width + first + c) = view(nodes(k), c);
        });
    column += columns;
  }
  template <class ExecutionSpaceT, class ViewT>
  void unpack(const ExecutionSpaceT& space, const ViewT& view, int& column, int width) const {
    const auto nodes = receiveNodes_;
    const auto buffer = receiveBuffer_;
    const int first = column, columns = static_cast<int>(view.extent(1));
    Kokkos::parallel_for(
        "perishell::parallel::NodeDistribution::unpack",
        Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, nodes.extent(0)), KOKKOS_LAMBDA(const std::size_t k) {
          for (int c = 0; c < columns; ++c) view(nodes(k), c) = buffer(k * width + first + c);
        });
    column += columns;
  }

  // One host-staged message each way per neighbour k: `width` doubles per item, neighbour k's
  // items at [offsets[k], offsets[k + 1]) of each buffer (halo nodes here; the overlap import's
  // matrix entries). Collective.
  void exchangeStaged(const double* out, const std::vector<std::size_t>& outOffsets, double* in,
                      const std::vector<std::size_t>& inOffsets, int width) const {
    startStaged(out, outOffsets, in, inOffsets, width).wait();
  }
  PendingExchange startStaged(const double* out, const std::vector<std::size_t>& outOffsets, double* in,
                              const std::vector<std::size_t>& inOffsets, int width) const {
    std::vector<const double*> sends;
    std::vector<double*> receives;
    std::vector<int> sendCounts, receiveCounts;
    for (std::size_t k = 0; k < ranks_.size(); ++k) {
      sends.push_back(out + outOffsets[k] * width);
      sendCounts.push_back(static_cast<int>((outOffsets[k + 1] - outOffsets[k]) * width));
      receives.push_back(in + inOffsets[k] * width);
      receiveCounts.push_back(static_cast<int>((inOffsets[k + 1] - inOffsets[k]) * width));
    }
    return communicator_.startExchange(ranks_, sends, sendCounts, receives, receiveCounts);
  }

 private:
  using Staging = typename StagingSpace<MemorySpaceT>::type;
  using StagingView = Kokkos::View<double*, Staging>;
  // The host side of a device buffer: the buffer itself where it is host memory (no copy).
  static StagingView stagingMirror(const Kokkos::View<double*, MemorySpaceT>& buffer) {
    if constexpr (std::is_same_v<Staging, MemorySpaceT>)
      return buffer;
    else
      return StagingView(buffer.label() + " (staged)", buffer.extent(0));
  }

  static Kokkos::View<LocalIndex*, MemorySpaceT> flatten(const std::vector<std::vector<LocalIndex>>& lists,
                                                        std::vector<std::size_t>& offsets, const char* label) {
    offsets.assign(1, 0);
    for (const auto& list : lists) offsets.push_back(offsets.back() + list.size());
    Kokkos::View<LocalIndex*, Kokkos::HostSpace> host(std::string(label), offsets.back());
    for (std::size_t k = 0; k < lists.size(); ++k)
      std::copy(lists[k].begin(), lists[k].end(), host.data() + offsets[k]);
    return Kokkos::create_mirror_view_and_copy(MemorySpaceT{}, host);
  }

  // A solver that is not distributed communicates with nobody, even inside an mpirun world.
  Communicator communicator_ = Communicator::self();
  long long meshNodes_ = 0;
  std::vector<int> ranks_;
  Kokkos::View<std::uint8_t*, MemorySpaceT> owned_;
  Kokkos::View<long long*, MemorySpaceT> globalIds_;
  Kokkos::View<LocalIndex*, MemorySpaceT> sendNodes_, receiveNodes_;
  Kokkos::View<int*, MemorySpaceT> ownerSlots_;
  std::vector<std::vector<LocalIndex>> sendLists_, receiveLists_;
  std::vector<std::size_t> sendOffsets_, receiveOffsets_;
  int bufferWidth_ = 0;    // doubles per node the buffers hold
  int exchangeWidth_ = 0;  // doubles per node the exchange in flight sends
  Kokkos::View<double*, MemorySpaceT> sendBuffer_, receiveBuffer_;
  StagingView hostSend_, hostReceive_;
  // The exchange in flight; a copy of the distribution starts with none.
  struct InFlight : PendingExchange {
    InFlight() = default;
    InFlight(const InFlight&) : PendingExchange() {}
    InFlight(InFlight&&) noexcept = default;
    InFlight& operator=(const InFlight&) {
      wait();
      return *this;
    }
    InFlight& operator=(InFlight&&) noexcept = default;
    InFlight& operator=(PendingExchange&& started) {
      PendingExchange::operator=(std::move(started));
      return *this;
    }
  };
  InFlight pending_;
  int accumulateWidth_ = 0;  // doubles per node the reverse buffers hold
  Kokkos::View<double*, MemorySpaceT> returnBuffer_, gatherBuffer_;
  StagingView hostReturn_, hostGather_;
};

}  // namespace perishell::parallel
