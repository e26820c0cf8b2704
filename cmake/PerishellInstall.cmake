# Installs the library, headers and a relocatable perishellConfig.cmake so that
# find_package(perishell) works downstream (checked by tests/install_consumer).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

install(TARGETS perishell perishell_belos EXPORT perishellTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY include/perishell DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(FILES "${PROJECT_BINARY_DIR}/include/perishell/core/config.hpp"
        DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/perishell/core)
install(TARGETS perishell_app RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(EXPORT perishellTargets NAMESPACE perishell::
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/perishell)

# Where this build found its dependencies, so that a consumer finds the same ones.
get_filename_component(PERISHELL_KOKKOS_DIR "${Kokkos_DIR}" ABSOLUTE)
get_filename_component(PERISHELL_KOKKOSKERNELS_DIR "${KokkosKernels_DIR}" ABSOLUTE)
get_filename_component(PERISHELL_BELOS_DIR "${Belos_DIR}" ABSOLUTE)
configure_package_config_file(cmake/perishellConfig.cmake.in
  "${PROJECT_BINARY_DIR}/perishellConfig.cmake"
  INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/perishell)
write_basic_package_version_file("${PROJECT_BINARY_DIR}/perishellConfigVersion.cmake"
  COMPATIBILITY SameMinorVersion)
install(FILES "${PROJECT_BINARY_DIR}/perishellConfig.cmake" "${PROJECT_BINARY_DIR}/perishellConfigVersion.cmake"
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/perishell)
