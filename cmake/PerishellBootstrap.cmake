# Included before project(): builds (or finds in the cache) the dependency stack with
# cmake/deps/bootstrap.sh, and for the CUDA backend picks Kokkos' nvcc_wrapper as the C++
# compiler, which must be known before project() enables CXX.
#
# Skipped when PERISHELL_BOOTSTRAP_DEPS is OFF or Kokkos_ROOT is given: then find_package
# uses Kokkos_ROOT, KokkosKernels_ROOT and Trilinos_ROOT / Belos_ROOT (or CMAKE_PREFIX_PATH).

set(PERISHELL_BACKEND "openmp" CACHE STRING "Kokkos backend of this build: openmp or cuda")
set_property(CACHE PERISHELL_BACKEND PROPERTY STRINGS openmp cuda)
if(NOT PERISHELL_BACKEND MATCHES "^(openmp|cuda)$")
  message(FATAL_ERROR "PERISHELL_BACKEND='${PERISHELL_BACKEND}': use openmp or cuda")
endif()

set(_perishell_user_kokkos "")
if(DEFINED Kokkos_ROOT)
  set(_perishell_user_kokkos "${Kokkos_ROOT}")
elseif(DEFINED ENV{Kokkos_ROOT})
  set(_perishell_user_kokkos "$ENV{Kokkos_ROOT}")
endif()
option(PERISHELL_BOOTSTRAP_DEPS
  "Build Kokkos, Kokkos Kernels, Teuchos and Belos from Debian's Trilinos source into a cache"
  ON)

if(PERISHELL_BOOTSTRAP_DEPS AND _perishell_user_kokkos STREQUAL "")
  set(_prefix_file "${CMAKE_BINARY_DIR}/perishell-deps-prefixes.cmake")
  message(STATUS "perishell: bootstrapping the ${PERISHELL_BACKEND} dependency stack "
                 "(cold cache: ~10 min on 2 cores; warm: instant)")
  execute_process(
    COMMAND bash "${CMAKE_CURRENT_LIST_DIR}/deps/bootstrap.sh"
            --backend "${PERISHELL_BACKEND}" --prefix-file "${_prefix_file}"
    RESULT_VARIABLE _bootstrap_result
    OUTPUT_QUIET)
  if(NOT _bootstrap_result EQUAL 0)
    message(FATAL_ERROR "perishell: the dependency bootstrap failed (messages above). "
                        "To use existing installs instead, pass -DKokkos_ROOT=... "
                        "-DKokkosKernels_ROOT=... -DTrilinos_ROOT=...")
  endif()
  include("${_prefix_file}")
  list(PREPEND CMAKE_PREFIX_PATH "${PERISHELL_DEPS_KOKKOS_PREFIX}" "${PERISHELL_DEPS_TRILINOS_PREFIX}")
  set(_perishell_kokkos_prefix "${PERISHELL_DEPS_KOKKOS_PREFIX}")
  get_filename_component(PERISHELL_DEPS_CACHE "${PERISHELL_DEPS_KOKKOS_PREFIX}" DIRECTORY)
else()
  set(_perishell_kokkos_prefix "${_perishell_user_kokkos}")
endif()

if(PERISHELL_BACKEND STREQUAL "cuda" AND NOT CMAKE_CXX_COMPILER)
  if(_perishell_kokkos_prefix STREQUAL "" OR NOT EXISTS "${_perishell_kokkos_prefix}/bin/nvcc_wrapper")
    message(FATAL_ERROR "perishell: the CUDA backend compiles with Kokkos' nvcc_wrapper; "
                        "set CMAKE_CXX_COMPILER to it")
  endif()
  set(CMAKE_CXX_COMPILER "${_perishell_kokkos_prefix}/bin/nvcc_wrapper" CACHE FILEPATH "C++ compiler" FORCE)
endif()
