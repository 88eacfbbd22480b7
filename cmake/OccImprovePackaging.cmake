include(CMakePackageConfigHelpers)
set(occ_improve_cmake_dir ${CMAKE_INSTALL_LIBDIR}/cmake/occ_improve)

# One export set per component, so that a user of occ_improve::core alone never needs PCL, OctoMap or
# libpng: find_package(occ_improve CONFIG REQUIRED COMPONENTS core) loads only the core's targets.
set(occ_improve_components core)
if(TARGET occ_improve_io)
  list(APPEND occ_improve_components io)
endif()
if(TARGET occ_improve_octomap)
  list(APPEND occ_improve_components octomap)
endif()
if(TARGET occ_improve_pcl)
  list(APPEND occ_improve_components pcl)
endif()
set(occ_improve_pcl_uses_octomap OFF)
if(TARGET occ_improve_pcl AND TARGET occ_improve_octomap)
  set(occ_improve_pcl_uses_octomap ON)
endif()
# The same targets exported from the build tree beside the config file below, so that a downstream
# project finds this build without installing it: cmake -Docc_improve_DIR=<this build folder>.
foreach(component ${occ_improve_components})
  install(EXPORT occ_improve_${component}_targets
          NAMESPACE occ_improve::
          FILE occ_improve-${component}-targets.cmake
          DESTINATION ${occ_improve_cmake_dir})
  export(EXPORT occ_improve_${component}_targets
         NAMESPACE occ_improve::
         FILE ${PROJECT_BINARY_DIR}/occ_improve-${component}-targets.cmake)
endforeach()

# One config for both: it loads the targets files found beside it (build folder or installed cmake folder).
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/occ_improve-config.cmake.in
                              ${PROJECT_BINARY_DIR}/occ_improve-config.cmake
                              INSTALL_DESTINATION ${occ_improve_cmake_dir})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/occ_improve-config-version.cmake
                                 COMPATIBILITY SameMajorVersion)
install(FILES ${PROJECT_BINARY_DIR}/occ_improve-config.cmake
              ${PROJECT_BINARY_DIR}/occ_improve-config-version.cmake
        DESTINATION ${occ_improve_cmake_dir})

# The prefix relative to the .pc file (pkg-config's ${pcfiledir}): an install moved or made with
# `cmake --install --prefix` elsewhere than the configured prefix still points at its own headers.
if(IS_ABSOLUTE "${CMAKE_INSTALL_LIBDIR}")
  set(occ_improve_pc_prefix "${CMAKE_INSTALL_PREFIX}")
else()
  file(RELATIVE_PATH occ_improve_pc_up "/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/")
  string(REGEX REPLACE "/$" "" occ_improve_pc_up "${occ_improve_pc_up}")
  set(occ_improve_pc_prefix "\${pcfiledir}/${occ_improve_pc_up}")
endif()
configure_file(${PROJECT_SOURCE_DIR}/cmake/occ_improve.pc.in ${PROJECT_BINARY_DIR}/occ_improve.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/occ_improve.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
