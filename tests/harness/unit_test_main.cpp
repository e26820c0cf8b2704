// Every test binary initialises Kokkos once; Kokkos arguments (--kokkos-threads=N,
// --kokkos-device-id=N) pass through.
#include <Kokkos_Core.hpp>
#include <gtest/gtest.h>

int main(int argc, char* argv[]) {
  Kokkos::ScopeGuard kokkos(argc, argv);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
