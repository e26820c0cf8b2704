#pragma once
// Category header: a test written once in a tst*.hpp runs on the OpenMP backend.
#include <Kokkos_Core.hpp>
#include <gtest/gtest.h>

#define TEST_CATEGORY openmp
#define TEST_EXECSPACE Kokkos::OpenMP
#define TEST_MEMSPACE Kokkos::HostSpace
