# A jar of the message types, so lcm-spy (and any Java tool) decodes the
# motormix channels. Built when a JDK and LCM's lcm.jar (Debian: liblcm-java)
# are found, or required with -DMOTORMIX_BUILD_JAVA=ON.
#
# Sets MOTORMIX_JAVA_JAR (path of the built jar) and MOTORMIX_LCM_JAR when built.
set(MOTORMIX_JAVA_BUILT OFF)
if(NOT MOTORMIX_BUILD_JAVA STREQUAL "OFF")
  find_package(Java 1.8 COMPONENTS Development QUIET)
  include(UseJava)
  find_jar(MOTORMIX_LCM_JAR NAMES lcm PATHS /usr/share/java /usr/local/share/java
    DOC "LCM's Java library (lcm.jar)")
  if(Java_FOUND AND MOTORMIX_LCM_JAR)
    set(MOTORMIX_JAVA_BUILT ON)
  elseif(MOTORMIX_BUILD_JAVA STREQUAL "ON")
    message(FATAL_ERROR "MOTORMIX_BUILD_JAVA=ON needs a JDK and LCM's lcm.jar "
      "(Debian: scripts/install-deps --java installs default-jdk-headless and liblcm-java)")
  else()
    message(STATUS "motormix: no JDK or no lcm.jar: the Java message types (for lcm-spy) are not built")
  endif()
endif()

if(MOTORMIX_JAVA_BUILT)
  set(java_dir ${CMAKE_CURRENT_BINARY_DIR}/lcmtypes/java)
  set(java_sources)
  set(lcm_sources)
  foreach(lcm_file ${MOTORMIX_LCM_SOURCES})
    get_filename_component(type_name ${lcm_file} NAME_WE)
    list(APPEND java_sources ${java_dir}/motormix/${type_name}.java)
    list(APPEND lcm_sources ${CMAKE_CURRENT_SOURCE_DIR}/${lcm_file})
  endforeach()
  add_custom_command(
    OUTPUT ${java_sources}
    COMMAND ${CMAKE_COMMAND} -E make_directory ${java_dir}
    COMMAND ${LCM_GEN} --java --jpath ${java_dir} ${lcm_sources}
    DEPENDS ${lcm_sources}
    COMMENT "Generating LCM Java bindings"
    VERBATIM)
  add_jar(motormix_lcmtypes_java SOURCES ${java_sources} INCLUDE_JARS ${MOTORMIX_LCM_JAR}
    OUTPUT_NAME motormix-lcmtypes VERSION ${PROJECT_VERSION})
  get_target_property(MOTORMIX_JAVA_JAR motormix_lcmtypes_java JAR_FILE)
endif()
