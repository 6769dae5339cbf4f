# Eigen's alignment is part of motormix's ABI: the public types hold
# fixed-size Eigen objects (AxisVector, the fixed-capacity matrices), whose
# alignment, size and field offsets follow the largest SIMD width the
# compiler is told about. Left to itself, a program compiled with -mavx or
# -march=native lays them out for 32 or 64 bytes while the libraries were
# built for 16: every call then reads the wrong bytes (seen: a segfault in
# the embedding example). So the alignment is pinned, for the libraries and
# for everything that uses them:
# - EIGEN_MAX_ALIGN_BYTES=16 is a PUBLIC definition of motormix::core (the
#   CMake package passes it on) and in motormix.pc's Cflags. It is Eigen's
#   own switch for this ("binary compatibility between code compiled with
#   different SIMD options"); Eigen still uses wider instructions, unaligned.
# - The generated <motormix/eigen_layout.hpp> records the alignments the
#   libraries were compiled with, and every public header that includes
#   Eigen includes it: a program that includes motormix's headers with other
#   alignments stops at compile time, naming the fix, instead of crashing.
set(MOTORMIX_EIGEN_ALIGN_DEFINITION EIGEN_MAX_ALIGN_BYTES=16)

# The alignments Eigen derives under that definition with this compiler and
# these flags, found by compiling (nothing is run, so cross builds work too).
include(CheckCXXSourceCompiles)
include(CMakePushCheckState)
function(_motormix_eigen_alignment macro out)
  cmake_push_check_state(RESET)
  set(CMAKE_REQUIRED_DEFINITIONS -D${MOTORMIX_EIGEN_ALIGN_DEFINITION})
  set(CMAKE_REQUIRED_LIBRARIES Eigen3::Eigen)
  set(CMAKE_REQUIRED_QUIET ON)
  foreach(bytes 16 0 8 32 64 128)
    check_cxx_source_compiles("#include <Eigen/Core>
static_assert(${macro} == ${bytes}, \"\");
int main() { return 0; }" MOTORMIX_${macro}_IS_${bytes})
    if(MOTORMIX_${macro}_IS_${bytes})
      cmake_pop_check_state()
      set(${out} ${bytes} PARENT_SCOPE)
      return()
    endif()
  endforeach()
  cmake_pop_check_state()
  message(FATAL_ERROR "motormix: could not find ${macro} of Eigen with ${MOTORMIX_EIGEN_ALIGN_DEFINITION}")
endfunction()
_motormix_eigen_alignment(EIGEN_MAX_STATIC_ALIGN_BYTES MOTORMIX_EIGEN_STATIC_ALIGN_BYTES)
_motormix_eigen_alignment(EIGEN_MAX_ALIGN_BYTES MOTORMIX_EIGEN_MAX_ALIGN_BYTES)
message(STATUS "motormix: Eigen alignment ${MOTORMIX_EIGEN_STATIC_ALIGN_BYTES} bytes "
  "(static), ${MOTORMIX_EIGEN_MAX_ALIGN_BYTES} (heap), pinned by ${MOTORMIX_EIGEN_ALIGN_DEFINITION}")
configure_file(${CMAKE_CURRENT_LIST_DIR}/eigen_layout.hpp.in
  ${MOTORMIX_GENERATED_INCLUDE}/motormix/eigen_layout.hpp @ONLY)
