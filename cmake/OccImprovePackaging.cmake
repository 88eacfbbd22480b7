include(CMakePackageConfigHelpers)
set(occ_improve_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/occ_improve)

install(EXPORT occ_improve_targets
        NAMESPACE occ_improve::
        FILE occ_improve-targets.cmake
        DESTINATION ${occ_improve_cmake_dir})

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/occ_improve-config.cmake.in
                              ${PROJECT_BINARY_DIR}/occ_improve-config.cmake
                              INSTALL_DESTINATION ${occ_improve_cmake_dir})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/occ_improve-config-version.cmake
                                 COMPATIBILITY SameMajorVersion)
install(FILES ${PROJECT_BINARY_DIR}/occ_improve-config.cmake
              ${PROJECT_BINARY_DIR}/occ_improve-config-version.cmake
        DESTINATION ${occ_improve_cmake_dir})

configure_file(${PROJECT_SOURCE_DIR}/cmake/occ_improve.pc.in ${PROJECT_BINARY_DIR}/occ_improve.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/occ_improve.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
