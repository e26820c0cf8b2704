#include <perishell/parallel/communicator.hpp>

#include <algorithm>
#include <cstdlib>
#include <limits>
#include <numeric>
#include <stdexcept>

#if PERISHELL_HAVE_MPI
#include <mpi.h>
#endif

namespace perishell::parallel {

#if PERISHELL_HAVE_MPI

namespace {
bool initialised() {
  int flag = 0;
  MPI_Initialized(&flag);
  int finalised = 0;
  MPI_Finalized(&finalised);
  return flag != 0 && finalised == 0;
}
void check(int code, const char* what) {
  if (code != MPI_SUCCESS) throw std::runtime_error(std::string("MPI: ") + what + " failed");
}
}  // namespace

Environment::Environment(int& argc, char**& argv) {
  // Only the main thread calls MPI (Kokkos' threads never do).
  int provided = 0;
  if (initialised()) return;
  check(MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided), "MPI_Init_thread");
  initialisedHere_ = true;
}

Environment::~Environment() {
  if (initialisedHere_ && initialised()) MPI_Finalize();
}

Communicator Communicator::world() {
  if (!initialised()) return {0, 1};
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  return {rank, size};
}

int Communicator::nodeLocalRank() const {
  if (size_ == 1) return 0;
  MPI_Comm node;
  check(MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank_, MPI_INFO_NULL, &node), "split by node");
  int local = 0;
  MPI_Comm_rank(node, &local);
  MPI_Comm_free(&node);
  return local;
}

void Communicator::sum(double* values, int count) const {
  if (size_ > 1) check(MPI_Allreduce(MPI_IN_PLACE, values, count, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD), "sum");
}
void Communicator::sum(long long* values, int count) const {
  if (size_ > 1) check(MPI_Allreduce(MPI_IN_PLACE, values, count, MPI_LONG_LONG, MPI_SUM, MPI_COMM_WORLD), "sum");
}
void Communicator::max(double* values, int count) const {
  if (size_ > 1) check(MPI_Allreduce(MPI_IN_PLACE, values, count, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD), "max");
}
void Communicator::min(double* values, int count) const {
  if (size_ > 1) check(MPI_Allreduce(MPI_IN_PLACE, values, count, MPI_DOUBLE, MPI_MIN, MPI_COMM_WORLD), "min");
}
int Communicator::max(int value) const {
  if (size_ > 1) check(MPI_Allreduce(MPI_IN_PLACE, &value, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD), "max");
  return value;
}

bool Communicator::any(bool value) const {
  int flag = value ? 1 : 0;
  if (size_ > 1) check(MPI_Allreduce(MPI_IN_PLACE, &flag, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD), "any");
  return flag != 0;
}

bool Communicator::anySharedOnNode(int value) const {
  if (size_ == 1) return false;
  MPI_Comm node;
  check(MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, rank_, MPI_INFO_NULL, &node), "split by node");
  int nodeSize = 1;
  MPI_Comm_size(node, &nodeSize);
  std::vector<int> values(nodeSize);
  check(MPI_Allgather(&value, 1, MPI_INT, values.data(), 1, MPI_INT, node), "gather on the node");
  MPI_Comm_free(&node);
  std::sort(values.begin(), values.end());
  return any(std::adjacent_find(values.begin(), values.end()) != values.end());
}

std::string Communicator::broadcast(const std::string& text) const {
  if (size_ == 1) return text;
  long long length = static_cast<long long>(text.size());
  check(MPI_Bcast(&length, 1, MPI_LONG_LONG, 0, MPI_COMM_WORLD), "broadcast");
  std::string result = rank_ == 0 ? text : std::string(static_cast<std::size_t>(length), '\0');
  if (length > 0) check(MPI_Bcast(result.data(), static_cast<int>(length), MPI_CHAR, 0, MPI_COMM_WORLD), "broadcast");
  return result;
}

void Communicator::broadcast(std::vector<int>& values) const {
  if (size_ == 1) return;
  long long length = static_cast<long long>(values.size());
  check(MPI_Bcast(&length, 1, MPI_LONG_LONG, 0, MPI_COMM_WORLD), "broadcast");
  values.resize(static_cast<std::size_t>(length));
  if (length > 0) check(MPI_Bcast(values.data(), static_cast<int>(length), MPI_INT, 0, MPI_COMM_WORLD), "broadcast");
}

namespace {
template <class T>
std::vector<T> gatherOnRoot(const std::vector<T>& values, MPI_Datatype type, int rank, int size) {
  // Counts as long long, so that every rank sees the same totals and refuses alike.
  const long long mine = static_cast<long long>(values.size());
  std::vector<long long> wide(size);
  check(MPI_Allgather(&mine, 1, MPI_LONG_LONG, wide.data(), 1, MPI_LONG_LONG, MPI_COMM_WORLD), "gather counts");
  long long sum = 0;
  for (const long long c : wide) sum += c;
  if (sum > std::numeric_limits<int>::max())
    throw std::runtime_error("MPI: a gather of " + std::to_string(sum) + " values passes MPI's int counts");
  const int count = static_cast<int>(mine);
  std::vector<int> counts(wide.begin(), wide.end()), offsets(size);
  std::exclusive_scan(counts.begin(), counts.end(), offsets.begin(), 0);
  const int total = static_cast<int>(sum);
  std::vector<T> result(rank == 0 ? total : 0);
  check(MPI_Gatherv(values.data(), count, type, result.data(), counts.data(), offsets.data(), type, 0,
                    MPI_COMM_WORLD), "gather");
  return result;
}
}  // namespace

std::vector<double> Communicator::gather(const std::vector<double>& values) const {
  if (size_ == 1) return values;
  return gatherOnRoot(values, MPI_DOUBLE, rank_, size_);
}
std::vector<long long> Communicator::gather(const std::vector<long long>& values) const {
  if (size_ == 1) return values;
  return gatherOnRoot(values, MPI_LONG_LONG, rank_, size_);
}

struct PendingExchange::Requests {
  std::vector<MPI_Request> requests;
};

void PendingExchange::wait() {
  if (!requests_) return;
  auto requests = std::move(requests_);
  check(MPI_Waitall(static_cast<int>(requests->requests.size()), requests->requests.data(), MPI_STATUSES_IGNORE),
        "wait");
}

PendingExchange Communicator::startExchange(const std::vector<int>& ranks, const std::vector<const double*>& sends,
                                            const std::vector<int>& sendCounts, const std::vector<double*>& receives,
                                            const std::vector<int>& receiveCounts) const {
  PendingExchange pending;
  pending.requests_ = std::make_unique<PendingExchange::Requests>();
  auto& requests = pending.requests_->requests;
  requests.resize(2 * ranks.size(), MPI_REQUEST_NULL);
  for (std::size_t k = 0; k < ranks.size(); ++k)
    check(MPI_Irecv(receives[k], receiveCounts[k], MPI_DOUBLE, ranks[k], 7, MPI_COMM_WORLD, &requests[k]), "receive");
  for (std::size_t k = 0; k < ranks.size(); ++k)
    check(MPI_Isend(sends[k], sendCounts[k], MPI_DOUBLE, ranks[k], 7, MPI_COMM_WORLD, &requests[ranks.size() + k]),
          "send");
  return pending;
}

std::vector<std::vector<long long>> Communicator::allToAll(const std::vector<std::vector<long long>>& lists) const {
  if (size_ == 1) return lists;
  std::vector<int> sendCounts(size_), receiveCounts(size_), sendOffsets(size_), receiveOffsets(size_);
  for (int r = 0; r < size_; ++r) sendCounts[r] = static_cast<int>(lists[r].size());
  check(MPI_Alltoall(sendCounts.data(), 1, MPI_INT, receiveCounts.data(), 1, MPI_INT, MPI_COMM_WORLD), "alltoall");
  std::exclusive_scan(sendCounts.begin(), sendCounts.end(), sendOffsets.begin(), 0);
  std::exclusive_scan(receiveCounts.begin(), receiveCounts.end(), receiveOffsets.begin(), 0);
  std::vector<long long> send, receive(receiveOffsets.back() + receiveCounts.back());
  for (const auto& list : lists) send.insert(send.end(), list.begin(), list.end());
  check(MPI_Alltoallv(send.data(), sendCounts.data(), sendOffsets.data(), MPI_LONG_LONG, receive.data(),
                      receiveCounts.data(), receiveOffsets.data(), MPI_LONG_LONG, MPI_COMM_WORLD), "alltoallv");
  std::vector<std::vector<long long>> result(size_);
  for (int r = 0; r < size_; ++r)
    result[r].assign(receive.begin() + receiveOffsets[r], receive.begin() + receiveOffsets[r] + receiveCounts[r]);
  return result;
}

void Communicator::abort(int exitCode) const {
  if (size_ > 1) MPI_Abort(MPI_COMM_WORLD, exitCode);
  std::exit(exitCode);
}

#else  // a single rank

Environment::Environment(int&, char**&) {}
Environment::~Environment() = default;
Communicator Communicator::world() { return {0, 1}; }
int Communicator::nodeLocalRank() const { return 0; }
void Communicator::sum(double*, int) const {}
void Communicator::sum(long long*, int) const {}
void Communicator::max(double*, int) const {}
void Communicator::min(double*, int) const {}
int Communicator::max(int value) const { return value; }
bool Communicator::any(bool value) const { return value; }
bool Communicator::anySharedOnNode(int) const { return false; }
std::string Communicator::broadcast(const std::string& text) const { return text; }
void Communicator::broadcast(std::vector<int>&) const {}
std::vector<double> Communicator::gather(const std::vector<double>& values) const { return values; }
std::vector<long long> Communicator::gather(const std::vector<long long>& values) const { return values; }
struct PendingExchange::Requests {};
void PendingExchange::wait() { requests_.reset(); }
PendingExchange Communicator::startExchange(const std::vector<int>& ranks, const std::vector<const double*>&,
                                            const std::vector<int>&, const std::vector<double*>&,
                                            const std::vector<int>&) const {
  if (!ranks.empty()) throw std::logic_error("Communicator::exchange: a single rank has no neighbours");
  return {};
}
std::vector<std::vector<long long>> Communicator::allToAll(const std::vector<std::vector<long long>>& lists) const {
  return lists;
}
void Communicator::abort(int exitCode) const { std::exit(exitCode); }

#endif

// After the two definitions of Requests: unique_ptr destroys a complete type.
PendingExchange::PendingExchange() = default;
PendingExchange::~PendingExchange() {
  // A destructor must not throw; wait() reports failures where it is called.
  try {
    wait();
  } catch (...) {
  }
}
PendingExchange::PendingExchange(PendingExchange&&) noexcept = default;
PendingExchange& PendingExchange::operator=(PendingExchange&& other) noexcept {
  if (this != &other) {
    try {
      wait();
    } catch (...) {
    }
    requests_ = std::move(other.requests_);
  }
  return *this;
}
bool PendingExchange::active() const { return requests_ != nullptr; }

void Communicator::exchange(const std::vector<int>& ranks, const std::vector<const double*>& sends,
                            const std::vector<int>& sendCounts, const std::vector<double*>& receives,
                            const std::vector<int>& receiveCounts) const {
  startExchange(ranks, sends, sendCounts, receives, receiveCounts).wait();
}

}  // namespace perishell::parallel
