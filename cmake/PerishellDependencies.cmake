# Finds the dependency stack (bootstrapped or user-provided) and wraps Teuchos/Belos,
# whose TriBITS config exports plain library targets, in one interface target.
find_package(Kokkos 3.4 REQUIRED)
find_package(KokkosKernels REQUIRED)
find_package(Belos REQUIRED)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(HDF5 REQUIRED COMPONENTS C)
# CHOLMOD (SuiteSparse; Debian: libsuitesparse-dev, installed by the bootstrap) ships no CMake
# package in Debian 12: found by header and library.
find_path(CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse)
find_library(CHOLMOD_LIBRARY cholmod)
if(NOT CHOLMOD_INCLUDE_DIR OR NOT CHOLMOD_LIBRARY)
  message(FATAL_ERROR "perishell: CHOLMOD not found (header cholmod.h: ${CHOLMOD_INCLUDE_DIR}, library: "
                      "${CHOLMOD_LIBRARY}); install it: apt-get install libsuitesparse-dev, or set "
                      "CHOLMOD_INCLUDE_DIR and CHOLMOD_LIBRARY")
endif()

if(PERISHELL_BACKEND STREQUAL "cuda")
  kokkos_check(DEVICES CUDA)
else()
  kokkos_check(DEVICES OPENMP)
endif()

add_library(perishell_belos INTERFACE)
target_include_directories(perishell_belos SYSTEM INTERFACE
  "$<BUILD_INTERFACE:${Belos_INCLUDE_DIRS}>" "$<INSTALL_INTERFACE:${Belos_INCLUDE_DIRS}>")
target_link_libraries(perishell_belos INTERFACE ${Belos_LIBRARIES} ${Belos_TPL_LIBRARIES})
