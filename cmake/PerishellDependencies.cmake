# Finds the dependency stack (bootstrapped or user-provided) and wraps Teuchos/Belos,
# whose TriBITS config exports plain library targets, in one interface target.
find_package(Kokkos 3.4 REQUIRED)
find_package(KokkosKernels REQUIRED)
find_package(Belos REQUIRED)
find_package(Eigen3 3.3 REQUIRED NO_MODULE)
find_package(HDF5 REQUIRED COMPONENTS C)

if(PERISHELL_BACKEND STREQUAL "cuda")
  kokkos_check(DEVICES CUDA)
else()
  kokkos_check(DEVICES OPENMP)
endif()

add_library(perishell_belos INTERFACE)
target_include_directories(perishell_belos SYSTEM INTERFACE
  "$<BUILD_INTERFACE:${Belos_INCLUDE_DIRS}>" "$<INSTALL_INTERFACE:${Belos_INCLUDE_DIRS}>")
target_link_libraries(perishell_belos INTERFACE ${Belos_LIBRARIES} ${Belos_TPL_LIBRARIES})
