#pragma once
// Belos::MultiVec<double> over a LayoutLeft Kokkos::View, so that Belos' host-side solver
// logic drives Kokkos / Kokkos Kernels kernels on any execution space. Belos 13.2 ships no
// Kokkos adapter of its own; this one implements the run-time polymorphic interface in
// BelosMultiVec.hpp, which Belos reaches through MultiVecTraits<double, MultiVec<double>>.
#include <perishell/core/types.hpp>
#include <perishell/parallel/communicator.hpp>

#include <BelosMultiVec.hpp>
#include <BelosTypes.hpp>
#include <Teuchos_SerialDenseMatrix.hpp>

#include <KokkosBlas1_dot.hpp>
#include <KokkosBlas1_fill.hpp>
#include <KokkosBlas1_nrm1.hpp>
#include <KokkosBlas1_nrm2.hpp>
#include <KokkosBlas1_nrminf.hpp>
#include <KokkosBlas1_scal.hpp>
#include <KokkosBlas1_update.hpp>
#include <KokkosBlas3_gemm.hpp>
#include <Kokkos_Core.hpp>
#include <Kokkos_Random.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace perishell::belos {

// The rows of a linear system split over the ranks of a distributed run (docs/parallel.md):
// each rank's vectors hold its owned rows and its halo rows. Dots and norms take the owned
// rows only and reduce them over the ranks; the operator sets the halo rows of its input to
// their owners' values before it multiplies, and leaves zeros in the halo rows of its output.
// Null on a single rank: every row is owned and nothing is reduced.
template <class MemorySpaceT>
struct DistributedRows {
  Kokkos::View<const std::uint8_t*, MemorySpaceT> owned;  // 1 for a row this rank owns
  parallel::Communicator communicator = parallel::Communicator::self();
  long long globalRows = 0;  // owned rows over every rank
  // Sets the halo rows of a vector to their owners' values. Collective.
  std::function<void(const VectorView<MemorySpaceT>&)> fillHalo;
};

template <class MemorySpaceT>
using SharedRows = std::shared_ptr<const DistributedRows<MemorySpaceT>>;

namespace detail {

enum class RowReduction { Dot, AbsSum, AbsMax };

// sum (or max) over the owned rows of a(:, i) . b(:, j), |a(:, i)| or max |a(:, i)|.
template <class ExecutionSpaceT, class ViewT>
double ownedRowReduction(const Kokkos::View<const std::uint8_t*, typename ExecutionSpaceT::memory_space>& owned,
                         const ViewT& a, int i, const ViewT& b, int j, RowReduction kind) {
  double result = 0.0;
  const Kokkos::RangePolicy<ExecutionSpaceT> rows(0, static_cast<std::int64_t>(a.extent(0)));
  if (kind == RowReduction::AbsMax) {
    Kokkos::parallel_reduce(
        "perishell::belos::owned_max", rows,
        KOKKOS_LAMBDA(const std::int64_t row, double& largest) {
          const double value = owned(row) ? Kokkos::Experimental::fabs(a(row, i)) : 0.0;
          largest = value > largest ? value : largest;
        },
        Kokkos::Max<double>(result));
    return result;
  }
  Kokkos::parallel_reduce(
      "perishell::belos::owned_sum", rows,
      KOKKOS_LAMBDA(const std::int64_t row, double& sum) {
        if (owned(row)) sum += kind == RowReduction::Dot ? a(row, i) * b(row, j) : Kokkos::Experimental::fabs(a(row, i));
      },
      result);
  return result;
}

// The kernels live in free functions: nvcc rejects extended lambdas whose enclosing
// function is a non-public class member.

template <class ViewT>
using IndexViewOf = Kokkos::View<int*, typename ViewT::device_type>;

template <class ViewT>
IndexViewOf<ViewT> indicesOnDevice(const std::vector<int>& index) {
  IndexViewOf<ViewT> device(Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::belos::index"),
                            index.size());
  auto host = Kokkos::create_mirror_view(device);
  for (std::size_t j = 0; j < index.size(); ++j) host(j) = index[j];
  Kokkos::deep_copy(device, host);
  return device;
}

// dst(:, j) = src(:, index[j]) for every j.
template <class ViewT>
void gatherColumns(const ViewT& src, const std::vector<int>& index, const ViewT& dst) {
  using execution_space = typename ViewT::execution_space;
  const auto cols = indicesOnDevice<ViewT>(index);
  const int numCols = static_cast<int>(index.size());
  Kokkos::parallel_for(
      "perishell::belos::gather_columns",
      Kokkos::RangePolicy<execution_space>(0, static_cast<std::int64_t>(src.extent(0))),
      KOKKOS_LAMBDA(const std::int64_t row) {
        for (int j = 0; j < numCols; ++j) dst(row, j) = src(row, cols(j));
      });
}

// dst(:, index[j]) = src(:, j) for every j.
template <class ViewT>
void scatterColumns(const ViewT& src, const std::vector<int>& index, const ViewT& dst) {
  using execution_space = typename ViewT::execution_space;
  const auto cols = indicesOnDevice<ViewT>(index);
  const int numCols = static_cast<int>(index.size());
  Kokkos::parallel_for(
      "perishell::belos::scatter_columns",
      Kokkos::RangePolicy<execution_space>(0, static_cast<std::int64_t>(dst.extent(0))),
      KOKKOS_LAMBDA(const std::int64_t row) {
        for (int j = 0; j < numCols; ++j) dst(row, cols(j)) = src(row, j);
      });
}

}  // namespace detail

template <class ExecutionSpaceT>
class KokkosMultiVector final : public Belos::MultiVec<double> {
  static_assert(Kokkos::is_execution_space<ExecutionSpaceT>::value,
                "KokkosMultiVector needs a Kokkos execution space");

 public:
  using execution_space = ExecutionSpaceT;
  using memory_space = typename ExecutionSpaceT::memory_space;
  using view_type = MultiVectorView<memory_space>;
  // The same storage typed with the execution space: Kokkos Kernels launches on a view's
  // execution space, and view_type alone would pick memory_space's default one.
  using device_view_type =
      Kokkos::View<double**, Kokkos::LayoutLeft, Kokkos::Device<ExecutionSpaceT, memory_space>>;

  // rows: how the rows are split over ranks (DistributedRows), or null on a single rank.
  KokkosMultiVector(const std::string& name, std::ptrdiff_t length, int numVectors,
                    SharedRows<memory_space> rows = nullptr)
      : view_(name, checkedLength(length), checkedNumVectors(numVectors)), rows_(std::move(rows)) {}

  // Aliases the caller's storage: Belos' writes land in `view`.
  explicit KokkosMultiVector(const view_type& view, SharedRows<memory_space> rows = nullptr)
      : view_(view), rows_(std::move(rows)) {
    if (view_.extent(1) == 0) {
      throw std::invalid_argument(
          "perishell::belos::KokkosMultiVector: a Belos multivector needs at least one column");
    }
  }

  const view_type& view() const { return view_; }
  device_view_type deviceView() const { return view_; }

  // ------------------------------------------------------------------ creation
  Belos::MultiVec<double>* Clone(const int numvecs) const override {
    // Belos allows uninitialized contents; the zero fill (one kernel) keeps fresh
    // multivectors deterministic.
    return new KokkosMultiVector(view_.label(), localLength(), numvecs, rows_);
  }

  Belos::MultiVec<double>* CloneCopy() const override {
    auto* copy = new KokkosMultiVector(view_.label(), localLength(), GetNumberVecs(), rows_);
    Kokkos::deep_copy(copy->view_, view_);
    return copy;
  }

  Belos::MultiVec<double>* CloneCopy(const std::vector<int>& index) const override {
    checkIndex(index, "CloneCopy");
    auto* copy = new KokkosMultiVector(view_.label(), localLength(), static_cast<int>(index.size()), rows_);
    if (isContiguous(index)) {
      Kokkos::deep_copy(copy->view_, columns(index.front(), index.size()));
    } else {
      detail::gatherColumns(deviceView(), index, copy->deviceView());
    }
    return copy;
  }

  Belos::MultiVec<double>* CloneViewNonConst(const std::vector<int>& index) override {
    checkIndex(index, "CloneViewNonConst");
    if (!isContiguous(index)) {
      throw std::invalid_argument(
          "perishell::belos::KokkosMultiVector::CloneViewNonConst: column indices " +
          describe(index) +
          " are not contiguous and increasing; a writable view must alias the parent's storage, "
          "which a LayoutLeft View can only do for a contiguous column range");
    }
    return new KokkosMultiVector(columns(index.front(), index.size()), rows_);
  }

  const Belos::MultiVec<double>* CloneView(const std::vector<int>& index) const override {
    checkIndex(index, "CloneView");
    if (isContiguous(index)) {
      return new KokkosMultiVector(columns(index.front(), index.size()), rows_);
    }
    // Read-only, so a copy is an acceptable stand-in for a view here.
    return CloneCopy(index);
  }

  // ------------------------------------------------------------------ dimensions
  // The rows over every rank (this rank's on a single rank).
  std::ptrdiff_t GetGlobalLength() const override {
    return rows_ ? static_cast<std::ptrdiff_t>(rows_->globalRows) : localLength();
  }
  std::ptrdiff_t localLength() const { return static_cast<std::ptrdiff_t>(view_.extent(0)); }
  const SharedRows<memory_space>& rows() const { return rows_; }
  int GetNumberVecs() const override { return static_cast<int>(view_.extent(1)); }

  // ------------------------------------------------------------------ updates
  // *this = alpha * A * B + beta * *this
  void MvTimesMatAddMv(const double alpha, const Belos::MultiVec<double>& A,
                       const Teuchos::SerialDenseMatrix<int, double>& B, const double beta) override {
    const auto& a = cast(A, "MvTimesMatAddMv");
    checkLength(a, "MvTimesMatAddMv");
    if (B.numRows() != a.GetNumberVecs() || B.numCols() != GetNumberVecs()) {
      std::ostringstream msg;
      msg << "perishell::belos::KokkosMultiVector::MvTimesMatAddMv: B is " << B.numRows() << " x "
          << B.numCols() << " but A has " << a.GetNumberVecs() << " columns and *this has "
          << GetNumberVecs();
      throw std::invalid_argument(msg.str());
    }
    // B(i, j) goes through operator(), which honours B's stride when B views a larger matrix.
    device_view_type b(Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::belos::B"),
                       B.numRows(), B.numCols());
    auto bHost = Kokkos::create_mirror_view(b);
    for (int j = 0; j < B.numCols(); ++j)
      for (int i = 0; i < B.numRows(); ++i) bHost(i, j) = B(i, j);
    Kokkos::deep_copy(b, bHost);
    // gemm reads A while it writes C, so A must not share storage with *this.
    const device_view_type aView = overlaps(a.view_, view_) ? copyOf(a.view_) : a.deviceView();
    KokkosBlas::gemm("N", "N", alpha, aView, b, beta, deviceView());
  }

  // *this = alpha * A + beta * B
  void MvAddMv(const double alpha, const Belos::MultiVec<double>& A, const double beta,
               const Belos::MultiVec<double>& B) override {
    const auto& a = cast(A, "MvAddMv");
    const auto& b = cast(B, "MvAddMv");
    checkShape(a, "MvAddMv");
    checkShape(b, "MvAddMv");
    // update() is elementwise, so an input that is exactly *this is fine (CG does x = x + a p);
    // one that only partly overlaps *this would race and is copied first.
    const device_view_type aView = partlyOverlaps(a.view_, view_) ? copyOf(a.view_) : a.deviceView();
    const device_view_type bView = partlyOverlaps(b.view_, view_) ? copyOf(b.view_) : b.deviceView();
    KokkosBlas::update(alpha, aView, beta, bView, 0.0, deviceView());
  }

  void MvScale(const double alpha) override {
    const device_view_type v = deviceView();
    KokkosBlas::scal(v, alpha, v);
  }

  void MvScale(const std::vector<double>& alpha) override {
    if (alpha.size() != view_.extent(1)) {
      throw std::invalid_argument("perishell::belos::KokkosMultiVector::MvScale: " +
                                  std::to_string(alpha.size()) + " factors for " +
                                  std::to_string(view_.extent(1)) + " columns");
    }
    Kokkos::View<double*, typename device_view_type::device_type> factors(
        Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::belos::scale"), alpha.size());
    auto host = Kokkos::create_mirror_view(factors);
    for (std::size_t j = 0; j < alpha.size(); ++j) host(j) = alpha[j];
    Kokkos::deep_copy(factors, host);
    const device_view_type v = deviceView();
    KokkosBlas::scal(v, factors, v);
  }

  // B = alpha * A^T * (*this); B is m x k with m = A's columns, k = this' columns.
  void MvTransMv(const double alpha, const Belos::MultiVec<double>& A,
                 Teuchos::SerialDenseMatrix<int, double>& B) const override {
    const auto& a = cast(A, "MvTransMv");
    checkLength(a, "MvTransMv");
    const int m = a.GetNumberVecs();
    const int k = GetNumberVecs();
    if (B.numRows() < m || B.numCols() < k) {
      std::ostringstream msg;
      msg << "perishell::belos::KokkosMultiVector::MvTransMv: B is " << B.numRows() << " x "
          << B.numCols() << " but the result is " << m << " x " << k;
      throw std::invalid_argument(msg.str());
    }
    // One multi-column dot per column of *this rather than KokkosBlas::gemm: Kernels 3.4's
    // gemm gives each 24 x 64 block of C to one team, so for this small C a single team
    // would walk all n rows; dot is a full-width parallel reduction.
    if (rows_) {
      std::vector<double> dots(std::size_t(m) * k);
      for (int j = 0; j < k; ++j)
        for (int i = 0; i < m; ++i)
          dots[std::size_t(j) * m + i] = detail::ownedRowReduction<ExecutionSpaceT>(
              rows_->owned, a.deviceView(), i, deviceView(), j, detail::RowReduction::Dot);
      rows_->communicator.sum(dots.data(), static_cast<int>(dots.size()));
      for (int j = 0; j < k; ++j)
        for (int i = 0; i < m; ++i) B(i, j) = alpha * dots[std::size_t(j) * m + i];
      return;
    }
    device_view_type c(Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::belos::AtB"), m, k);
    const device_view_type aView = a.deviceView();
    const device_view_type self = deviceView();
    for (int j = 0; j < k; ++j) {
      KokkosBlas::dot(Kokkos::subview(c, Kokkos::ALL(), j), aView, Kokkos::subview(self, Kokkos::ALL(), j));
    }
    const auto cHost = onHost(c);
    for (int j = 0; j < k; ++j)
      for (int i = 0; i < m; ++i) B(i, j) = alpha * cHost(i, j);
  }

  // b[i] = A[i]^T * (*this)[i]
  void MvDot(const Belos::MultiVec<double>& A, std::vector<double>& b) const override {
    const auto& a = cast(A, "MvDot");
    checkShape(a, "MvDot");
    if (rows_) {
      std::vector<double> dots(view_.extent(1));
      for (std::size_t j = 0; j < dots.size(); ++j)
        dots[j] = detail::ownedRowReduction<ExecutionSpaceT>(rows_->owned, a.deviceView(), int(j), deviceView(),
                                                             int(j), detail::RowReduction::Dot);
      rows_->communicator.sum(dots.data(), static_cast<int>(dots.size()));
      if (b.size() < dots.size()) b.resize(dots.size());
      std::copy(dots.begin(), dots.end(), b.begin());
      return;
    }
    Kokkos::View<double*, typename device_view_type::device_type> dots("perishell::belos::dots",
                                                                      view_.extent(1));
    KokkosBlas::dot(dots, a.deviceView(), deviceView());
    copyToHost(dots, b);
  }

  void MvNorm(std::vector<double>& normvec, Belos::NormType type = Belos::TwoNorm) const override {
    if (rows_) {
      distributedNorm(normvec, type);
      return;
    }
    Kokkos::View<double*, typename device_view_type::device_type> norms("perishell::belos::norms",
                                                                       view_.extent(1));
    switch (type) {
      case Belos::OneNorm: KokkosBlas::nrm1(norms, deviceView()); break;
      case Belos::TwoNorm: KokkosBlas::nrm2(norms, deviceView()); break;
      case Belos::InfNorm: KokkosBlas::nrminf(norms, deviceView()); break;
      default:
        throw std::invalid_argument("perishell::belos::KokkosMultiVector::MvNorm: unsupported norm type " +
                                    std::to_string(static_cast<int>(type)));
    }
    copyToHost(norms, normvec);
  }

  // ------------------------------------------------------------------ initialization
  // Copies the first index.size() columns of A into columns index of *this.
  void SetBlock(const Belos::MultiVec<double>& A, const std::vector<int>& index) override {
    const auto& a = cast(A, "SetBlock");
    checkIndex(index, "SetBlock");
    checkLength(a, "SetBlock");
    if (static_cast<std::size_t>(a.GetNumberVecs()) < index.size()) {
      throw std::invalid_argument("perishell::belos::KokkosMultiVector::SetBlock: A has " +
                                  std::to_string(a.GetNumberVecs()) + " columns for " +
                                  std::to_string(index.size()) + " target indices");
    }
    const auto source = Kokkos::subview(a.view_, Kokkos::ALL(), std::make_pair(std::size_t{0}, index.size()));
    const device_view_type src = overlaps(source, view_) ? copyOf(source) : device_view_type(source);
    if (isContiguous(index)) {
      Kokkos::deep_copy(columns(index.front(), index.size()), src);
    } else {
      detail::scatterColumns(src, index, deviceView());
    }
  }

  void MvRandom() override {
    // A fresh seed per call: Belos expects two MvRandom calls to give different vectors.
    static std::atomic<std::uint64_t> calls{0};
    const std::uint64_t seed = 0x9E3779B97F4A7C15ull * (calls.fetch_add(1) + 1);
    Kokkos::Random_XorShift64_Pool<ExecutionSpaceT> pool(seed);
    Kokkos::fill_random(deviceView(), pool, -1.0, 1.0);
  }

  void MvInit(const double alpha) override { KokkosBlas::fill(deviceView(), alpha); }

  void MvPrint(std::ostream& os) const override {
    const auto host = onHost(view_);
    os << "KokkosMultiVector '" << view_.label() << "' " << host.extent(0) << " x " << host.extent(1) << "\n";
    for (std::size_t i = 0; i < host.extent(0); ++i) {
      for (std::size_t j = 0; j < host.extent(1); ++j) os << (j ? " " : "") << host(i, j);
      os << "\n";
    }
  }

 private:
  // Norms over the owned rows of every rank: sums of squares and of magnitudes are summed,
  // largest magnitudes maximised.
  void distributedNorm(std::vector<double>& normvec, Belos::NormType type) const {
    const auto kind = type == Belos::OneNorm   ? detail::RowReduction::AbsSum
                      : type == Belos::TwoNorm ? detail::RowReduction::Dot
                      : type == Belos::InfNorm ? detail::RowReduction::AbsMax
                                               : throw std::invalid_argument(
                                                     "perishell::belos::KokkosMultiVector::MvNorm: unsupported norm type " +
                                                     std::to_string(static_cast<int>(type)));
    std::vector<double> norms(view_.extent(1));
    for (std::size_t j = 0; j < norms.size(); ++j)
      norms[j] = detail::ownedRowReduction<ExecutionSpaceT>(rows_->owned, deviceView(), int(j), deviceView(), int(j),
                                                            kind);
    if (kind == detail::RowReduction::AbsMax)
      rows_->communicator.max(norms.data(), static_cast<int>(norms.size()));
    else
      rows_->communicator.sum(norms.data(), static_cast<int>(norms.size()));
    if (kind == detail::RowReduction::Dot)
      for (auto& norm : norms) norm = std::sqrt(norm);
    if (normvec.size() < norms.size()) normvec.resize(norms.size());
    std::copy(norms.begin(), norms.end(), normvec.begin());
  }

  static std::size_t checkedLength(std::ptrdiff_t length) {
    if (length < 0) {
      throw std::invalid_argument("perishell::belos::KokkosMultiVector: negative length " +
                                  std::to_string(length));
    }
    return static_cast<std::size_t>(length);
  }

  static std::size_t checkedNumVectors(int numVectors) {
    if (numVectors <= 0) {
      throw std::invalid_argument("perishell::belos::KokkosMultiVector: needs at least one column, got " +
                                  std::to_string(numVectors));
    }
    return static_cast<std::size_t>(numVectors);
  }

  static const KokkosMultiVector& cast(const Belos::MultiVec<double>& mv, const char* where) {
    const auto* kokkos = dynamic_cast<const KokkosMultiVector*>(&mv);
    if (kokkos == nullptr) {
      throw std::invalid_argument(std::string("perishell::belos::KokkosMultiVector::") + where +
                                  ": the other multivector is not a KokkosMultiVector on the same "
                                  "execution space");
    }
    return *kokkos;
  }

  void checkLength(const KokkosMultiVector& other, const char* where) const {
    if (other.view_.extent(0) != view_.extent(0)) {
      throw std::invalid_argument(std::string("perishell::belos::KokkosMultiVector::") + where +
                                  ": lengths differ (" + std::to_string(other.view_.extent(0)) +
                                  " vs " + std::to_string(view_.extent(0)) + ")");
    }
  }

  void checkShape(const KokkosMultiVector& other, const char* where) const {
    checkLength(other, where);
    if (other.view_.extent(1) != view_.extent(1)) {
      throw std::invalid_argument(std::string("perishell::belos::KokkosMultiVector::") + where +
                                  ": column counts differ (" + std::to_string(other.view_.extent(1)) +
                                  " vs " + std::to_string(view_.extent(1)) + ")");
    }
  }

  void checkIndex(const std::vector<int>& index, const char* where) const {
    if (index.empty()) {
      throw std::invalid_argument(std::string("perishell::belos::KokkosMultiVector::") + where +
                                  ": empty column index set");
    }
    for (const int j : index) {
      if (j < 0 || j >= GetNumberVecs()) {
        throw std::invalid_argument(std::string("perishell::belos::KokkosMultiVector::") + where +
                                    ": column index " + std::to_string(j) + " outside [0, " +
                                    std::to_string(GetNumberVecs()) + ")");
      }
    }
  }

  static bool isContiguous(const std::vector<int>& index) {
    for (std::size_t j = 1; j < index.size(); ++j)
      if (index[j] != index[0] + static_cast<int>(j)) return false;
    return true;
  }

  static std::string describe(const std::vector<int>& index) {
    std::string text = "{";
    for (std::size_t j = 0; j < index.size(); ++j) text += (j ? ", " : "") + std::to_string(index[j]);
    return text + "}";
  }

  // A column range of a LayoutLeft View is still LayoutLeft and shares the parent's allocation.
  view_type columns(int first, std::size_t count) const {
    const auto begin = static_cast<std::size_t>(first);
    return Kokkos::subview(view_, Kokkos::ALL(), std::make_pair(begin, begin + count));
  }

  template <class ViewA, class ViewB>
  static bool overlaps(const ViewA& a, const ViewB& b) {
    if (a.span() == 0 || b.span() == 0) return false;
    const double* aBegin = a.data();
    const double* bBegin = b.data();
    return aBegin < bBegin + b.span() && bBegin < aBegin + a.span();
  }

  static bool partlyOverlaps(const view_type& a, const view_type& b) {
    const bool identical = a.data() == b.data() && a.extent(0) == b.extent(0) &&
                           a.extent(1) == b.extent(1) && a.stride(1) == b.stride(1);
    return !identical && overlaps(a, b);
  }

  template <class ViewT>
  static device_view_type copyOf(const ViewT& source) {
    device_view_type copy(Kokkos::view_alloc(Kokkos::WithoutInitializing, "perishell::belos::copy"),
                          source.extent(0), source.extent(1));
    Kokkos::deep_copy(copy, source);
    return copy;
  }

  // The fence matters where memory_space is host-accessible: create_mirror_view_and_copy then
  // returns the view itself without waiting for kernels still writing it.
  template <class ViewT>
  static auto onHost(const ViewT& view) {
    ExecutionSpaceT().fence();
    return Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace(), view);
  }

  // Belos wants every reduction result on the host; Belos' MVOPTester expects callers'
  // vectors never to shrink, so only grow them.
  template <class DeviceVector>
  static void copyToHost(const DeviceVector& device, std::vector<double>& out) {
    const auto host = onHost(device);
    if (out.size() < host.extent(0)) out.resize(host.extent(0));
    for (std::size_t j = 0; j < host.extent(0); ++j) out[j] = host(j);
  }

  view_type view_;
  SharedRows<memory_space> rows_;
};

}  // namespace perishell::belos
