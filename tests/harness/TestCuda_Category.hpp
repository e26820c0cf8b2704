#pragma once
// Category header: a test written once in a tst*.hpp runs on the CUDA backend.
#include <Kokkos_Core.hpp>
#include <gtest/gtest.h>

#define TEST_CATEGORY cuda
#define TEST_EXECSPACE Kokkos::Cuda
#define TEST_MEMSPACE Kokkos::CudaSpace
