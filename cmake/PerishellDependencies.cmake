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

# Distributed runs (docs/parallel.md): MPI for the ranks, METIS for the partition.
if(PERISHELL_ENABLE_MPI)
  find_package(MPI REQUIRED COMPONENTS C)
  find_path(METIS_INCLUDE_DIR metis.h)
  find_library(METIS_LIBRARY metis)
  if(NOT METIS_INCLUDE_DIR OR NOT METIS_LIBRARY)
    message(FATAL_ERROR "perishell: METIS not found (metis.h: ${METIS_INCLUDE_DIR}, library: ${METIS_LIBRARY}); "
                        "install it: apt-get install libmetis-dev, or set METIS_INCLUDE_DIR and METIS_LIBRARY")
  endif()
  find_program(PERISHELL_MPIEXEC NAMES mpirun mpiexec HINTS ${MPI_C_COMPILER_DIR})
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
