#pragma once
// A coarse space that couples the ranks of a distributed implicit solve (docs/parallel.md,
// "Coupling the ranks' preconditioners"). Each rank's preconditioner M_1 (AMG, a Cholesky
// factor or block Jacobi of its block, overlapping or not) reaches only a halo's depth past
// its rank, so a smooth correction spreads slowly across the subdomains: the Krylov
// iterations grow with the rank count.
// The coarse space Z holds, for every rank p, the six rigid-body modes of its owned nodes in
// the current configuration (about their centroid; zero on constrained DOF and elsewhere);
// E = Z^T A Z (6P x 6P) is formed once per preconditioner build and pseudo-inverted on every
// rank (E is tiny). The preconditioner is the balancing (hybrid) two-level Schwarz of Mandel
// (1993), "Balancing domain decomposition", with Q = Z E^+ Z^T:
//   B = Q + (I - Q A) M_1 (I - A Q),
// symmetric and positive definite where A and M_1 are, as CG needs. W = A Z is stored, local
// rows only: an owned row of A reaches its own rank's nodes and its neighbours', so W has
// 6 (neighbours + 1) columns. An application costs two sums of 6P numbers over the ranks and
// products with Z and W on the execution space; the local preconditioner is applied once.
#include <perishell/core/types.hpp>
#include <perishell/parallel/communicator.hpp>
#include <perishell/solvers/belos/crs_operator.hpp>
#include <perishell/solvers/belos/kokkos_multivector.hpp>

#include <BelosOperator.hpp>
#include <Eigen/Dense>
#include <KokkosBlas2_gemv.hpp>
#include <KokkosBlas3_gemm.hpp>
#include <Kokkos_Core.hpp>
#include <Teuchos_RCP.hpp>

#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

namespace perishell::belos {

// Rigid-body mode `mode` (0-2 translations, 3-5 rotations about the axes) at DOF `dof` of a
// node at r from the centre: u = t, theta = 0; u = w x r, theta = w.
KOKKOS_INLINE_FUNCTION double rigidBodyModeValue(int mode, int dof, const double r[3]) {
  if (mode < 3 || dof >= 3) return dof == mode ? 1.0 : 0.0;
  const int w = mode - 3;  // (e_w x r)_dof
  return (w + 1) % 3 == dof ? -r[(w + 2) % 3] : ((w + 2) % 3 == dof ? r[(w + 1) % 3] : 0.0);
}

template <class ExecutionSpaceT>
class SubdomainCoarseSpace final : public Belos::Operator<double> {
 public:
  using memory_space = typename ExecutionSpaceT::memory_space;
  using Device = Kokkos::Device<ExecutionSpaceT, memory_space>;
  using Dense = Kokkos::View<double**, Kokkos::LayoutLeft, Device>;
  using Small = Kokkos::View<double*, Kokkos::LayoutLeft, Device>;
  static constexpr int modes = 6;

  // A: this rank's rows of the tangent (owned rows complete); slotOfNode: per local node, 0
  // where this rank owns it, 1 + k where neighbourRanks[k] owns it, -1 for a halo node no owned
  // row reads; constrained: per DOF; positions: current node positions; local: M_1. Collective.
  SubdomainCoarseSpace(const ExecutionSpaceT& space, const CrsMatrix<ExecutionSpaceT>& A,
                       const Kokkos::View<const int*, memory_space>& slotOfNode, const std::vector<int>& neighbourRanks,
                       const Kokkos::View<const bool*, memory_space>& constrained,
                       const CoordinateView<memory_space>& positions, const parallel::Communicator& communicator,
                       Teuchos::RCP<const Belos::Operator<double>> local)
      : space_(space), communicator_(communicator), local_(std::move(local)) {
    const std::size_t n = A.numRows();
    if (slotOfNode.extent(0) * modes != n || constrained.extent(0) != n || positions.extent(0) * modes != n)
      throw std::invalid_argument("perishell::belos::SubdomainCoarseSpace: A, slots, constraints and positions "
                                  "do not describe the same nodes");
    const int ranks = communicator.size();
    slotRanks_.push_back(communicator.rank());
    slotRanks_.insert(slotRanks_.end(), neighbourRanks.begin(), neighbourRanks.end());
    const int slots = static_cast<int>(slotRanks_.size());
    const auto centres = rankCentres(slotOfNode, positions);
    Kokkos::View<double* [3], Kokkos::LayoutRight, Kokkos::HostSpace> hostSlotCentres("slot centres", slots);
    for (int s = 0; s < slots; ++s)
      for (int k = 0; k < 3; ++k) hostSlotCentres(s, k) = centres[3 * slotRanks_[s] + k];
    const auto slotCentres = Kokkos::create_mirror_view_and_copy(memory_space{}, hostSlotCentres);

    Z_ = Dense("perishell::coarse::Z", n, modes);
    W_ = Dense("perishell::coarse::W", n, modes * slots);
    fillModes(A, slotOfNode, constrained, positions, slotCentres);

    // This rank's block row of E = Z^T A Z (6 x 6 slots), summed over ranks into the whole E.
    Dense blockRow("perishell::coarse::E_p", modes, modes * slots);
    KokkosBlas::gemm("T", "N", 1.0, Z_, W_, 0.0, blockRow);
    const auto hostBlockRow = Kokkos::create_mirror_view_and_copy(Kokkos::HostSpace{}, blockRow);
    const int size = modes * ranks;
    std::vector<double> E(static_cast<std::size_t>(size) * size, 0.0);
    const int row0 = modes * communicator.rank();
    for (int s = 0; s < slots; ++s)
      for (int a = 0; a < modes; ++a)
        for (int b = 0; b < modes; ++b)
          E[static_cast<std::size_t>(row0 + a) * size + modes * slotRanks_[s] + b] += hostBlockRow(a, modes * s + b);
    communicator.sum(E.data(), size * size);
    pseudoInvert(E, size);

    coarseIn_ = Small("perishell::coarse::c", modes * slots);
    projected_ = Small("perishell::coarse::projected", modes * slots);
    ownModes_ = Small("perishell::coarse::own", modes);
    hostIn_ = Kokkos::create_mirror_view(coarseIn_);
    hostProjected_ = Kokkos::create_mirror_view(projected_);
    hostOwn_ = Kokkos::create_mirror_view(ownModes_);
    s_ = MultiVectorView<memory_space>("perishell::coarse::s", n, 1);
    t_ = MultiVectorView<memory_space>("perishell::coarse::t", n, 1);
  }

  // y = B x, column by column.
  void Apply(const Belos::MultiVec<double>& x, Belos::MultiVec<double>& y,
             Belos::ETrans /*B is symmetric*/ = Belos::NOTRANS) const override {
    constexpr const char* who = "perishell::belos::SubdomainCoarseSpace::Apply";
    const auto& xk = detail::asKokkos<ExecutionSpaceT>(x, who);
    auto& yk = detail::asKokkos<ExecutionSpaceT>(y, who);
    detail::checkApplyShapes(xk, yk, Z_.extent(0), Z_.extent(0), who);
    KokkosMultiVector<ExecutionSpaceT> sVector(s_), tVector(t_);
    const auto s = Kokkos::subview(sVector.deviceView(), Kokkos::ALL(), 0);
    const auto t = Kokkos::subview(tVector.deviceView(), Kokkos::ALL(), 0);
    for (std::size_t j = 0; j < xk.view().extent(1); ++j) {
      const auto r = Kokkos::subview(xk.deviceView(), Kokkos::ALL(), j);
      const auto out = Kokkos::subview(yk.deviceView(), Kokkos::ALL(), j);
      // c = E^+ Z^T r; s = r - A Z c = r - W c
      coarseSolve(r, Z_, /*transposeOwnBlockOnly=*/true);
      Kokkos::deep_copy(space_, s, r);
      KokkosBlas::gemv("N", -1.0, W_, coarseIn_, 1.0, s);
      local_->Apply(sVector, tVector);
      // d = E^+ W^T t = E^+ Z^T A t; y = t + Z (c - d), Q r = Z c
      const std::vector<double> c(hostIn_.data(), hostIn_.data() + modes);
      coarseSolve(t, W_, false);
      for (int k = 0; k < modes; ++k) hostOwn_(k) = c[k] - hostIn_(k);
      Kokkos::deep_copy(space_, ownModes_, hostOwn_);
      Kokkos::deep_copy(space_, out, t);
      KokkosBlas::gemv("N", 1.0, Z_, ownModes_, 1.0, out);
    }
  }

  bool HasApplyTranspose() const override { return true; }

  // The steps below launch kernels; public only because nvcc rejects extended lambdas in
  // private member functions.

  // Every rank's owned-node centroid (3 per rank, rank order).
  std::vector<double> rankCentres(const Kokkos::View<const int*, memory_space>& slotOfNode,
                                  const CoordinateView<memory_space>& positions) const {
    std::vector<double> centres(4 * communicator_.size(), 0.0);
    double sums[4] = {0.0, 0.0, 0.0, 0.0};
    for (int k = 0; k < 4; ++k)
      Kokkos::parallel_reduce(
          "perishell::coarse::centroid", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, slotOfNode.extent(0)),
          KOKKOS_LAMBDA(const std::size_t node, double& partial) {
            if (slotOfNode(node) == 0) partial += k < 3 ? positions(node, k) : 1.0;
          },
          sums[k]);
    for (int k = 0; k < 4; ++k) centres[4 * communicator_.rank() + k] = sums[k];
    communicator_.sum(centres.data(), static_cast<int>(centres.size()));
    std::vector<double> result(3 * communicator_.size(), 0.0);
    for (int p = 0; p < communicator_.size(); ++p)
      for (int k = 0; k < 3; ++k) result[3 * p + k] = centres[4 * p + 3] > 0.0 ? centres[4 * p + k] / centres[4 * p + 3] : 0.0;
    return result;
  }

  // Z (this rank's modes on its owned free DOF) and W = A Z over every slot's modes.
  void fillModes(const CrsMatrix<ExecutionSpaceT>& A, const Kokkos::View<const int*, memory_space>& slotOfNode,
                 const Kokkos::View<const bool*, memory_space>& constrained,
                 const CoordinateView<memory_space>& positions,
                 const Kokkos::View<double* [3], Kokkos::LayoutRight, memory_space>& centres) const {
    const auto Z = Z_;
    const auto W = W_;
    const auto rowMap = A.graph.row_map;
    const auto entries = A.graph.entries;
    const auto values = A.values;
    // The mode values of DOF `dof` for slot `slot`'s rank, zero where it is not that rank's.
    const auto modeAt = [=] KOKKOS_FUNCTION(std::size_t dof, int slot, int mode) {
      const std::size_t node = dof / modes;
      if (slotOfNode(node) != slot || constrained(dof)) return 0.0;
      const double r[3] = {positions(node, 0) - centres(slot, 0), positions(node, 1) - centres(slot, 1),
                           positions(node, 2) - centres(slot, 2)};
      return rigidBodyModeValue(mode, static_cast<int>(dof % modes), r);
    };
    const int columns = static_cast<int>(W.extent(1));
    Kokkos::parallel_for(
        "perishell::coarse::modes", Kokkos::RangePolicy<ExecutionSpaceT>(space_, 0, Z.extent(0)),
        KOKKOS_LAMBDA(const std::size_t row) {
          for (int mode = 0; mode < modes; ++mode) Z(row, mode) = modeAt(row, 0, mode);
          for (int column = 0; column < columns; ++column) W(row, column) = 0.0;
          if (slotOfNode(row / modes) != 0) return;  // halo rows: other ranks' equations
          for (auto entry = rowMap(row); entry < rowMap(row + 1); ++entry) {
            const std::size_t dof = entries(entry);
            const int slot = slotOfNode(dof / modes);
            if (slot < 0) continue;
            for (int mode = 0; mode < modes; ++mode) W(row, modes * slot + mode) += values(entry) * modeAt(dof, slot, mode);
          }
        });
  }

 private:
  // Jacobi-scaled symmetric eigen decomposition; directions with |lambda| <= 1e-12 lambda_max
  // (a rank whose modes are all held, or linearly dependent) are left out of E^+.
  void pseudoInvert(std::vector<double>& E, int size) {
    Eigen::MatrixXd matrix(size, size);
    for (int a = 0; a < size; ++a)
      for (int b = 0; b < size; ++b)
        matrix(a, b) = 0.5 * (E[static_cast<std::size_t>(a) * size + b] + E[static_cast<std::size_t>(b) * size + a]);
    Eigen::VectorXd scale(size);
    for (int a = 0; a < size; ++a) scale(a) = matrix(a, a) > 0.0 ? 1.0 / std::sqrt(matrix(a, a)) : 0.0;
    const Eigen::MatrixXd scaled = scale.asDiagonal() * matrix * scale.asDiagonal();
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(scaled);
    const double largest = eigen.eigenvalues().cwiseAbs().maxCoeff();
    Eigen::VectorXd inverse(size);
    for (int a = 0; a < size; ++a) {
      const double lambda = eigen.eigenvalues()(a);
      inverse(a) = std::abs(lambda) > 1e-12 * largest ? 1.0 / lambda : 0.0;
    }
    inverse_ = scale.asDiagonal() * eigen.eigenvectors() * inverse.asDiagonal() * eigen.eigenvectors().transpose() *
               scale.asDiagonal();
  }

  // hostIn_ / coarseIn_ = (E^+ g) at this rank's slots, g = (M^T v) summed over the ranks, M = Z
  // (own 6 columns) or W (every slot's columns).
  template <class VectorT>
  void coarseSolve(const VectorT& v, const Dense& M, bool ownBlockOnly) const {
    const int slots = static_cast<int>(slotRanks_.size());
    const int columns = static_cast<int>(M.extent(1));
    const auto product = Kokkos::subview(projected_, std::make_pair(0, columns));
    KokkosBlas::gemv("T", 1.0, M, v, 0.0, product);
    Kokkos::deep_copy(space_, hostProjected_, projected_);
    space_.fence();
    const int size = static_cast<int>(inverse_.rows());
    Eigen::VectorXd g = Eigen::VectorXd::Zero(size);
    for (int s = 0; s < (ownBlockOnly ? 1 : slots); ++s)
      for (int k = 0; k < modes; ++k) g(modes * slotRanks_[s] + k) += hostProjected_(modes * s + k);
    communicator_.sum(g.data(), size);
    const Eigen::VectorXd c = inverse_ * g;
    for (int s = 0; s < slots; ++s)
      for (int k = 0; k < modes; ++k) hostIn_(modes * s + k) = c(modes * slotRanks_[s] + k);
    Kokkos::deep_copy(space_, coarseIn_, hostIn_);
  }

  ExecutionSpaceT space_;
  parallel::Communicator communicator_;
  Teuchos::RCP<const Belos::Operator<double>> local_;
  std::vector<int> slotRanks_;  // this rank, then its neighbours
  Dense Z_, W_;
  Eigen::MatrixXd inverse_;  // E^+
  Small coarseIn_, projected_, ownModes_;
  typename Small::HostMirror hostIn_, hostProjected_, hostOwn_;
  MultiVectorView<memory_space> s_, t_;  // the local preconditioner's input and output
};

}  // namespace perishell::belos
