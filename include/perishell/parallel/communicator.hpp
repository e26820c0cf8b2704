#pragma once
// The ranks of a distributed run (docs/parallel.md). One communicator for the whole run:
// MPI_COMM_WORLD in a build with PERISHELL_ENABLE_MPI, a single rank otherwise, so that the
// solvers call the same collectives in either build. MPI stays out of this header: only
// src/parallel/communicator.cpp includes mpi.h.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace perishell::parallel {

// MPI_Init_thread on construction, MPI_Finalize on destruction (a no-op without MPI). The app
// holds one for its lifetime; tests that need ranks hold one in main.
class Environment {
 public:
  Environment(int& argc, char**& argv);
  ~Environment();
  Environment(const Environment&) = delete;
  Environment& operator=(const Environment&) = delete;

 private:
  bool initialisedHere_ = false;  // finalise only an MPI this object started
};

// The messages of an exchange a Communicator started (startExchange): in flight until wait(),
// which the destructor also calls, so that no message outlives the buffers it reads or fills.
class PendingExchange {
 public:
  PendingExchange();
  ~PendingExchange();
  PendingExchange(PendingExchange&&) noexcept;
  PendingExchange& operator=(PendingExchange&&) noexcept;
  PendingExchange(const PendingExchange&) = delete;
  PendingExchange& operator=(const PendingExchange&) = delete;

  // True from the start until wait() returns.
  bool active() const;
  // Blocks until every send has left its buffer and every receive has filled its own.
  void wait();

 private:
  friend class Communicator;
  struct Requests;  // the MPI requests (src/parallel/communicator.cpp)
  std::unique_ptr<Requests> requests_;
};

class Communicator {
 public:
  // The world: every rank mpirun started (one without MPI, or when MPI is not initialised).
  static Communicator world();
  // This rank alone: collectives are no-ops (a solver that is not distributed).
  static Communicator self() { return {0, 1}; }

  int rank() const { return rank_; }
  // This rank's index among the ranks on its node (MPI_COMM_TYPE_SHARED): which GPU it takes.
  int nodeLocalRank() const;
  int size() const { return size_; }
  bool root() const { return rank_ == 0; }
  bool distributed() const { return size_ > 1; }

  // Element-wise reductions over every rank, in place. Each rank must pass as many values.
  void sum(double* values, int count) const;
  void sum(long long* values, int count) const;
  void max(double* values, int count) const;
  void min(double* values, int count) const;
  double sum(double value) const { sum(&value, 1); return value; }
  long long sum(long long value) const { sum(&value, 1); return value; }
  double max(double value) const { max(&value, 1); return value; }
  int max(int value) const;
  double min(double value) const { min(&value, 1); return value; }
  // True on every rank when it is true on any.
  bool any(bool value) const;
  // True on every rank when two ranks of one node pass the same value (ranks sharing a GPU:
  // the device id). Collective.
  bool anySharedOnNode(int value) const;

  // The root's text on every rank.
  std::string broadcast(const std::string& text) const;
  void broadcast(std::vector<int>& values) const;

  // Every rank's `values` concatenated in rank order, on the root (empty elsewhere). Throws
  // when the total passes MPI's int counts.
  std::vector<double> gather(const std::vector<double>& values) const;
  std::vector<long long> gather(const std::vector<long long>& values) const;

  // Point-to-point exchange with a fixed set of neighbours: sends[k] goes to ranks[k] and
  // receives[k] (sized by the caller) comes from ranks[k]. Non-blocking sends and receives,
  // completed before it returns.
  void exchange(const std::vector<int>& ranks, const std::vector<const double*>& sends,
                const std::vector<int>& sendCounts, const std::vector<double*>& receives,
                const std::vector<int>& receiveCounts) const;
  // The same exchange, returned in flight: the caller works on, then waits. Until then the send
  // buffers must stay as they are and the receive buffers unread.
  PendingExchange startExchange(const std::vector<int>& ranks, const std::vector<const double*>& sends,
                                const std::vector<int>& sendCounts, const std::vector<double*>& receives,
                                const std::vector<int>& receiveCounts) const;
  // Each rank sends lists[r] to rank r and returns what every rank sent it (index = sender).
  std::vector<std::vector<long long>> allToAll(const std::vector<std::vector<long long>>& lists) const;

  // Ends every rank at once (MPI_Abort): for an error on one rank that the others cannot know
  // of, which would otherwise leave them waiting in a collective.
  [[noreturn]] void abort(int exitCode) const;

 private:
  Communicator(int rank, int size) : rank_(rank), size_(size) {}
  int rank_ = 0, size_ = 1;
};

}  // namespace perishell::parallel
