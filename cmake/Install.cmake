# The install tree (GNUInstallDirs), relocatable: install with --prefix
# anywhere and both the CMake package and motormix.pc still point inside it.
#
#   bin/motormix
#   include/motormix/...            core and config headers, version.hpp, generated message headers
#   lib/libmotormix_core.a, lib/libmotormix_config.a  (or .so with BUILD_SHARED_LIBS=ON)
#   lib/cmake/motormix/             find_package(motormix): motormix::core, ::config, ::lcmtypes
#   lib/pkgconfig/motormix.pc
#   lib/python3/dist-packages/motormix/   message types for Python (Debian's layout)
#   share/java/motormix-lcmtypes.jar      message types for lcm-spy (when built)
#   share/motormix/lcmtypes/*.lcm, share/motormix/config/*.yaml, share/motormix/examples/
#   share/doc/motormix/             README, CHANGELOG, BENCHMARKS
include(CMakePackageConfigHelpers)
set(MOTORMIX_INSTALL_CMAKEDIR ${CMAKE_INSTALL_LIBDIR}/cmake/motormix)

install(TARGETS motormix RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(TARGETS motormix_core motormix_config motormix_signing motormix_lcmtypes EXPORT motormixTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
  INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY include/motormix DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(FILES ${MOTORMIX_GENERATED_INCLUDE}/motormix/version.hpp
  ${MOTORMIX_GENERATED_INCLUDE}/motormix/eigen_layout.hpp
  DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/motormix)
install(DIRECTORY ${MOTORMIX_LCM_CPP_DIR}/motormix DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${MOTORMIX_LCM_PYTHON_DIR}/motormix DESTINATION ${MOTORMIX_INSTALL_PYTHONDIR}
  FILES_MATCHING PATTERN "*.py")
install(FILES python/motormix_signing.py DESTINATION ${MOTORMIX_INSTALL_PYTHONDIR})
install(FILES ${MOTORMIX_LCM_SOURCES} DESTINATION ${CMAKE_INSTALL_DATADIR}/motormix/lcmtypes)
install(DIRECTORY config/ DESTINATION ${CMAKE_INSTALL_DATADIR}/motormix/config
  FILES_MATCHING PATTERN "*.yaml")
install(DIRECTORY examples/ DESTINATION ${CMAKE_INSTALL_DATADIR}/motormix/examples)
# The shipped scenarios (also compiled into motormix sim), as examples to copy.
install(DIRECTORY scenarios/ DESTINATION ${CMAKE_INSTALL_DATADIR}/motormix/scenarios
  FILES_MATCHING PATTERN "*.yaml")
install(FILES README.md CHANGELOG.md BENCHMARKS.md SIM.md ROBUSTNESS.md DESTINATION ${CMAKE_INSTALL_DOCDIR})
# The guide keeps its place next to the README, so the links between them hold.
install(DIRECTORY docs/ DESTINATION ${CMAKE_INSTALL_DOCDIR}/docs)
if(MOTORMIX_JAVA_BUILT)
  install_jar(motormix_lcmtypes_java DESTINATION ${CMAKE_INSTALL_DATADIR}/java)
endif()

# CMake package.
install(EXPORT motormixTargets NAMESPACE motormix:: DESTINATION ${MOTORMIX_INSTALL_CMAKEDIR})
get_target_property(motormix_core_type motormix_core TYPE)
if(motormix_core_type STREQUAL "STATIC_LIBRARY")
  set(MOTORMIX_STATIC ON)  # yaml-cpp and pugixml are then needed at link time (never in users' headers)
else()
  set(MOTORMIX_STATIC OFF)
endif()
configure_package_config_file(cmake/motormixConfig.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/motormixConfig.cmake
  INSTALL_DESTINATION ${MOTORMIX_INSTALL_CMAKEDIR})
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/motormixConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/motormixConfig.cmake
  ${CMAKE_CURRENT_BINARY_DIR}/motormixConfigVersion.cmake
  DESTINATION ${MOTORMIX_INSTALL_CMAKEDIR})

# pkg-config: prefix found relative to the .pc file, so the tree can move.
file(RELATIVE_PATH MOTORMIX_PC_TO_PREFIX
  /prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig /prefix)
string(REGEX REPLACE "/$" "" MOTORMIX_PC_TO_PREFIX "${MOTORMIX_PC_TO_PREFIX}")
if(MOTORMIX_STATIC)
  set(MOTORMIX_PC_REQUIRES "eigen3 lcm yaml-cpp pugixml libsodium")
  set(MOTORMIX_PC_REQUIRES_PRIVATE "")
else()
  set(MOTORMIX_PC_REQUIRES "eigen3 lcm")
  set(MOTORMIX_PC_REQUIRES_PRIVATE "yaml-cpp pugixml libsodium")
endif()
configure_file(cmake/motormix.pc.in ${CMAKE_CURRENT_BINARY_DIR}/motormix.pc @ONLY)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/motormix.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
