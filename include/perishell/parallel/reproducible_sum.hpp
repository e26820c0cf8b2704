#pragma once
// Sums whose value does not depend on the order of addition: not on the thread count, the
// backend's reduction tree or how the terms are split over ranks (docs/parallel.md). Each
// term x is split exactly into x = t1 + t2 + r, t1 a multiple of q1 = 2^(e - 52 + h) and t2 of
// q2 = q1 2^(h - 52), where 2^e bounds every |x| and 2^h the number of terms that may be
// non-zero (a number that must not depend on the rank count, so that neither do the quanta):
// every partial sum of the t1 (and of the t2) is then a multiple of its quantum below 2^53
// quanta, so it is exact in any order, and t1 + t2 carries x to about 2^(2h - 104) of the
// largest term. The split of t1 is Dekker's (x + s) - s with s = 1.5 2^(e + h), exact under
// IEEE rounding (no -ffast-math: it would fold (x + s) - s into x).
#include <perishell/core/types.hpp>
#include <perishell/parallel/communicator.hpp>

#include <algorithm>
#include <cmath>

namespace perishell::parallel {

// The sum over i in [0, count) of term(i) and over every rank (count and term are this rank's).
// At most nonZeroTerms terms over all ranks are non-zero (in a distributed solver: the owned
// ones; the halo's give 0). Collective. A non-finite term gives a non-finite sum, and so do
// terms beyond about 2^(1000 - h) (a blown-up state).
template <class ExecutionSpaceT, class TermT>
double reproducibleSum(const ExecutionSpaceT& space, std::size_t count, const TermT& term,
                       const Communicator& communicator, long long nonZeroTerms) {
  double largest = 0.0;
  Kokkos::parallel_reduce(
      "perishell::parallel::reproducibleSum::largest", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, count),
      KOKKOS_LAMBDA(const std::size_t i, double& maximum) {
        const double magnitude = Kokkos::Experimental::fabs(term(i));
        if (magnitude > maximum) maximum = magnitude;
      },
      Kokkos::Max<double>(largest));
  // An empty range gives Max's identity. A NaN term escapes the maximum but not the sums below.
  largest = std::max(communicator.max(largest), 0.0);
  int e = 0, h = 0;
  std::frexp(largest, &e);  // largest < 2^e
  std::frexp(static_cast<double>(std::max(nonZeroTerms, 1LL)), &h);  // terms < 2^h
  ++h;
  const double split1 = std::ldexp(1.5, e + h), split2 = std::ldexp(1.5, e + 2 * h - 52);
  double sums[2] = {0.0, 0.0};
  Kokkos::parallel_reduce(
      "perishell::parallel::reproducibleSum::coarse", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, count),
      KOKKOS_LAMBDA(const std::size_t i, double& partial) {
        const double shifted = term(i) + split1;
        partial += shifted - split1;
      },
      sums[0]);
  Kokkos::parallel_reduce(
      "perishell::parallel::reproducibleSum::fine", Kokkos::RangePolicy<ExecutionSpaceT>(space, 0, count),
      KOKKOS_LAMBDA(const std::size_t i, double& partial) {
        const double x = term(i);
        const double shifted = x + split1;
        const double rest = x - (shifted - split1);
        const double shiftedRest = rest + split2;
        partial += shiftedRest - split2;
      },
      sums[1]);
  communicator.sum(sums, 2);
  return sums[0] + sums[1];
}

}  // namespace perishell::parallel
