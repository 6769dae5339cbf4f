# Generates C++ and Python bindings of .lcm files at build time (and Java,
# see LcmJava.cmake). Generated code lives only in the build tree; the
# install rules copy it into the prefix.
#
# Sets in the caller's scope:
#   MOTORMIX_LCM_CPP_DIR     include root of the generated headers (motormix/*.hpp)
#   MOTORMIX_LCM_PYTHON_DIR  root of the generated Python package (motormix/*.py)
function(motormix_lcm_types target)
  set(cpp_dir ${CMAKE_CURRENT_BINARY_DIR}/lcmtypes/cpp)
  set(py_dir ${CMAKE_CURRENT_BINARY_DIR}/lcmtypes/python)
  set(outputs ${py_dir}/motormix/__init__.py)
  set(sources)
  foreach(lcm_file ${ARGN})
    get_filename_component(type_name ${lcm_file} NAME_WE)
    list(APPEND outputs ${cpp_dir}/motormix/${type_name}.hpp ${py_dir}/motormix/${type_name}.py)
    list(APPEND sources ${CMAKE_CURRENT_SOURCE_DIR}/${lcm_file})
  endforeach()
  add_custom_command(
    OUTPUT ${outputs}
    COMMAND ${CMAKE_COMMAND} -E make_directory ${cpp_dir} ${py_dir}
    COMMAND ${LCM_GEN} --cpp --cpp-std c++11 --cpp-hpath ${cpp_dir} ${sources}
    COMMAND ${LCM_GEN} --python --ppath ${py_dir} ${sources}
    DEPENDS ${sources}
    COMMENT "Generating LCM bindings"
    VERBATIM)
  add_custom_target(${target}_gen ALL DEPENDS ${outputs})
  add_library(${target} INTERFACE)
  add_dependencies(${target} ${target}_gen)
  target_include_directories(${target} SYSTEM INTERFACE
    $<BUILD_INTERFACE:${cpp_dir}> $<INSTALL_INTERFACE:${CMAKE_INSTALL_INCLUDEDIR}>)
  # LCM's coretypes decode floats through int32_t pointers; with strict
  # aliasing, optimized builds may read the float before the write (seen:
  # every float field decoded as 0 at -O2). Whoever includes the generated
  # types compiles without that assumption, inside this build and outside.
  target_compile_options(${target} INTERFACE -fno-strict-aliasing)
  set(MOTORMIX_LCM_CPP_DIR ${cpp_dir} PARENT_SCOPE)
  set(MOTORMIX_LCM_PYTHON_DIR ${py_dir} PARENT_SCOPE)
endfunction()
