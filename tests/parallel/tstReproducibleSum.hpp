// parallel::reproducibleSum: the same bits whatever the order of the terms (and hence the
// thread count, the backend's reduction tree or the split over ranks), close to the exact
// sum, and non-finite when a term is.
#include <perishell/parallel/reproducible_sum.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace reproducible_sum_test {

template <class MemorySpaceT>
struct ViewTerm {
  Kokkos::View<double*, MemorySpaceT> values;
  KOKKOS_INLINE_FUNCTION double operator()(const std::size_t i) const { return values(i); }
};

template <class ExecutionSpaceT>
double reproducibleSumOf(const std::vector<double>& terms) {
  using MemorySpace = typename ExecutionSpaceT::memory_space;
  Kokkos::View<double*, Kokkos::HostSpace> host("terms", terms.size());
  std::copy(terms.begin(), terms.end(), host.data());
  const ViewTerm<MemorySpace> term{Kokkos::create_mirror_view_and_copy(MemorySpace{}, host)};
  return perishell::parallel::reproducibleSum(ExecutionSpaceT{}, terms.size(), term,
                                              perishell::parallel::Communicator::self(),
                                              static_cast<long long>(terms.size()));
}

// Terms over 30 decades with both signs: plain summation gives a different value per order.
std::vector<double> wideTerms(std::size_t count, bool positive) {
  std::mt19937_64 random(42);
  std::uniform_real_distribution<double> mantissa(1.0, 2.0), exponent(-50.0, 50.0);
  std::vector<double> terms(count);
  for (std::size_t i = 0; i < count; ++i)
    terms[i] = (positive || i % 2 == 0 ? 1.0 : -1.0) * mantissa(random) * std::pow(2.0, exponent(random));
  return terms;
}

TEST(TEST_CATEGORY, reproducible_sum_is_the_same_in_any_order) {
  auto terms = wideTerms(200000, false);
  const double inOrder = reproducibleSumOf<TEST_EXECSPACE>(terms);
  std::reverse(terms.begin(), terms.end());
  const double reversed = reproducibleSumOf<TEST_EXECSPACE>(terms);
  std::shuffle(terms.begin(), terms.end(), std::mt19937_64(7));
  const double shuffled = reproducibleSumOf<TEST_EXECSPACE>(terms);
  EXPECT_EQ(inOrder, reversed);
  EXPECT_EQ(inOrder, shuffled);
  // Plain summation of the same terms does depend on the order (what the sum exists for).
  double forward = 0.0, backward = 0.0;
  for (const double x : terms) forward += x;
  for (auto x = terms.rbegin(); x != terms.rend(); ++x) backward += *x;
  EXPECT_NE(forward, backward);
}

TEST(TEST_CATEGORY, reproducible_sum_is_accurate) {
  const auto terms = wideTerms(100000, true);
  long double reference = 0.0L, compensation = 0.0L;  // Neumaier in extended precision
  for (const double x : terms) {
    const long double next = reference + x;
    compensation += std::fabs(reference) >= std::fabs(x) ? (reference - next) + x : (x - next) + reference;
    reference = next;
  }
  const double exact = static_cast<double>(reference + compensation);
  EXPECT_NEAR(reproducibleSumOf<TEST_EXECSPACE>(terms), exact, 4e-16 * exact);
  EXPECT_EQ(reproducibleSumOf<TEST_EXECSPACE>({1.0, 2.0, 3.5}), 6.5);
  EXPECT_EQ(reproducibleSumOf<TEST_EXECSPACE>({0.0, 0.0}), 0.0);
  EXPECT_EQ(reproducibleSumOf<TEST_EXECSPACE>({}), 0.0);
}

TEST(TEST_CATEGORY, reproducible_sum_of_a_non_finite_term_is_not_finite) {
  EXPECT_TRUE(std::isnan(reproducibleSumOf<TEST_EXECSPACE>({1.0, std::numeric_limits<double>::quiet_NaN(), 2.0})));
  EXPECT_FALSE(std::isfinite(reproducibleSumOf<TEST_EXECSPACE>({1.0, std::numeric_limits<double>::infinity()})));
}

}  // namespace reproducible_sum_test
