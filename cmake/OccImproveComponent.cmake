# occ_improve_add_component(NAME SOURCES...): the library occ_improve_NAME of one find_package component,
# its alias occ_improve::NAME, its public include/ folder and, when installing, its own export set
# (occ_improve_NAME_targets), so that each component is found on its own (see OccImprovePackaging).
function(occ_improve_add_component name)
  add_library(occ_improve_${name} ${ARGN})
  add_library(occ_improve::${name} ALIAS occ_improve_${name})
  set_target_properties(occ_improve_${name} PROPERTIES EXPORT_NAME ${name} POSITION_INDEPENDENT_CODE ON)
  target_include_directories(occ_improve_${name} PUBLIC
    $<BUILD_INTERFACE:${CMAKE_CURRENT_SOURCE_DIR}/include>
    $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  occ_improve_set_warnings(occ_improve_${name})
  if(OCC_IMPROVE_INSTALL)
    install(TARGETS occ_improve_${name} EXPORT occ_improve_${name}_targets
            ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR})
    install(DIRECTORY include/ DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
  endif()
endfunction()
