// Every test binary initialises Kokkos once; Kokkos arguments (--kokkos-threads=N,
// --kokkos-device-id=N) pass through. OpenMP runs with 2 threads (the CI machine's cores)
// unless OMP_NUM_THREADS says otherwise.
#include <Kokkos_Core.hpp>
#include <gtest/gtest.h>

#include <cstdlib>

int main(int argc, char* argv[]) {
  setenv("OMP_NUM_THREADS", "2", /*overwrite=*/0);
  setenv("OMP_PROC_BIND", "false", /*overwrite=*/0);
  Kokkos::ScopeGuard kokkos(argc, argv);
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
