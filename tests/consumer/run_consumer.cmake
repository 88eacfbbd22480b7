# ctest's consumer test: installs the build into a scratch prefix, then configures, builds and runs
# tests/consumer against it three times: asking for the core alone with PCL, OctoMap, libpng and libtiff
# made unfindable (a core user needs none of them), for io with PCL and OctoMap unfindable (libpng and
# libtiff are found through the config's find_dependency), and for every component; then twice against
# the build folder itself (its exported targets, occ_improve_DIR=<build>): the core alone and every
# component.
#   cmake -DBUILD_DIR=... -DSOURCE_DIR=... -DWORK_DIR=... [-DLINKER_FLAGS=...] -P run_consumer.cmake
# LINKER_FLAGS are the build's own (a sanitizer build's static libraries need its runtime to link).
# With -DCXX=<compiler>, the core alone is also built from pkg-config's flags of the scratch install
# (whose prefix is not the configured one: the .pc file must point at where it lies).
foreach(var BUILD_DIR SOURCE_DIR WORK_DIR)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "run_consumer.cmake needs -D${var}=...")
  endif()
endforeach()

function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    string(REPLACE ";" " " command "${ARGN}")
    message(FATAL_ERROR "consumer test: '${command}' failed (${rc})")
  endif()
endfunction()

set(prefix ${WORK_DIR}/prefix)
file(REMOVE_RECURSE ${WORK_DIR})
run(${CMAKE_COMMAND} --install ${BUILD_DIR} --prefix ${prefix})
set(without_pcl_and_octomap -DCMAKE_DISABLE_FIND_PACKAGE_PCL=TRUE -DCMAKE_DISABLE_FIND_PACKAGE_octomap=TRUE)
# The build_tree_* cases find the build folder itself (README: "from a build tree"), not the install,
# and check that the library they link is the build folder's.
foreach(case core io all build_tree_core build_tree_all)
  set(build ${WORK_DIR}/${case})
  if(case MATCHES "core$")
    set(options -DOCC_IMPROVE_CONSUMER_COMPONENTS=core ${without_pcl_and_octomap} -DCMAKE_DISABLE_FIND_PACKAGE_PNG=TRUE
                -DCMAKE_DISABLE_FIND_PACKAGE_TIFF=TRUE)
  elseif(case STREQUAL "io")
    set(options -DOCC_IMPROVE_CONSUMER_COMPONENTS=io ${without_pcl_and_octomap})
  else()
    set(options -DCMAKE_DISABLE_FIND_PACKAGE_VTK=TRUE)
  endif()
  if(case MATCHES "^build_tree")
    # The build folder's own library, not the scratch install (which lies inside the build folder too).
    list(APPEND options -Docc_improve_DIR=${BUILD_DIR} -DOCC_IMPROVE_CONSUMER_EXPECT_DIR=${BUILD_DIR}/libocc_improve)
  else()
    list(APPEND options -DCMAKE_PREFIX_PATH=${prefix} -DOCC_IMPROVE_CONSUMER_EXPECT_DIR=${prefix})
  endif()
  run(${CMAKE_COMMAND} -S ${SOURCE_DIR} -B ${build} ${options}
      "-DCMAKE_EXE_LINKER_FLAGS=${LINKER_FLAGS}")
  run(${CMAKE_COMMAND} --build ${build})
  run(${build}/occ_improve_consumer)
endforeach()

find_program(PKG_CONFIG_EXECUTABLE pkg-config)
if(DEFINED CXX AND PKG_CONFIG_EXECUTABLE)
  file(GLOB_RECURSE pc_file ${prefix}/occ_improve.pc)
  get_filename_component(pc_dir "${pc_file}" DIRECTORY)
  execute_process(COMMAND ${CMAKE_COMMAND} -E env PKG_CONFIG_PATH=${pc_dir}
                          ${PKG_CONFIG_EXECUTABLE} --cflags --libs occ_improve
                  OUTPUT_VARIABLE pc_flags OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "consumer test: pkg-config --cflags --libs occ_improve failed (${rc})")
  endif()
  separate_arguments(pc_flags UNIX_COMMAND "${pc_flags}")
  separate_arguments(linker_flags UNIX_COMMAND "${LINKER_FLAGS}")
  run(${CXX} -std=c++17 ${SOURCE_DIR}/main.cpp -o ${WORK_DIR}/pkg_config_consumer ${pc_flags} ${linker_flags})
  run(${WORK_DIR}/pkg_config_consumer)
endif()
