# `cmake --install build --prefix P` (docs/library.md):
#   P/bin/rvlio                             the command (RPATH $ORIGIN/../lib)
#   P/lib/librvlio_{core,sim,io}.so.X.Y.Z (+ SONAME and dev links)
#   P/include/rvlio/...                     the public headers (PublicHeaders.cmake) + version.h
#   P/lib/cmake/rvlio/                      rvlioConfig.cmake, version file, targets
#   P/share/rvlio/config/                   default.yaml, paper_*.yaml, sensors/, grids/
#   P/share/rvlio/rvlio_plot.py             the plotting script `rvlio compare` runs
set(RVLIO_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/rvlio CACHE STRING
    "Where rvlioConfig.cmake is installed, relative to the prefix")

install(TARGETS rvlio_core rvlio_sim rvlio_io EXPORT rvlioTargets
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT runtime NAMELINK_COMPONENT dev
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev)
install(TARGETS rvlio RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT runtime)
# The public headers, an explicit list (cmake/PublicHeaders.cmake); none
# includes PCL, ROS, sqlite, yaml-cpp or nlohmann/json (checked by
# scripts/install_test.sh and the HeadersWithoutJson test).
include(${CMAKE_CURRENT_LIST_DIR}/PublicHeaders.cmake)
foreach(header ${rvlio_public_headers})
  get_filename_component(header_dir ${header} DIRECTORY)
  install(FILES ${PROJECT_SOURCE_DIR}/include/${header}
    DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/${header_dir} COMPONENT dev)
endforeach()
install(FILES ${PROJECT_BINARY_DIR}/include/rvlio/version.h
  DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/rvlio COMPONENT dev)
install(DIRECTORY ${PROJECT_SOURCE_DIR}/config/ DESTINATION ${CMAKE_INSTALL_DATADIR}/rvlio/config
  COMPONENT runtime)
install(PROGRAMS ${PROJECT_SOURCE_DIR}/scripts/rvlio_plot.py
  DESTINATION ${CMAKE_INSTALL_DATADIR}/rvlio COMPONENT runtime)

install(EXPORT rvlioTargets NAMESPACE rvlio:: DESTINATION ${RVLIO_INSTALL_CMAKEDIR}
  COMPONENT dev)
set(RVLIO_BUILT_SHARED ${RVLIO_SHARED_LIBS})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/rvlioConfig.cmake.in
  ${PROJECT_BINARY_DIR}/rvlioConfig.cmake INSTALL_DESTINATION ${RVLIO_INSTALL_CMAKEDIR})
# 0.x: only the same MINOR is compatible; from 1.0 on, the same MAJOR.
if(PROJECT_VERSION_MAJOR EQUAL 0)
  set(rvlio_compat SameMinorVersion)
else()
  set(rvlio_compat SameMajorVersion)
endif()
write_basic_package_version_file(${PROJECT_BINARY_DIR}/rvlioConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY ${rvlio_compat})
install(FILES ${PROJECT_BINARY_DIR}/rvlioConfig.cmake ${PROJECT_BINARY_DIR}/rvlioConfigVersion.cmake
  ${PROJECT_SOURCE_DIR}/cmake/RosbagStorage.cmake
  DESTINATION ${RVLIO_INSTALL_CMAKEDIR} COMPONENT dev)
