# Known wrong code in the compiler, checked for with the flags of this build.
#
# GCC 12.2 (Debian 12's) with AVX-512 enabled (-march=native on a CPU that
# has it, -march=x86-64-v4) builds some constant vectors wrongly: the array
# {0.5, 0.5, 0, 0} passed by value arrives as {0.5, 0.5, 0.5, 0.5}. It showed
# in motormix's own tests (two PX4 conformance cases read a wrong expected
# value) and can hit any code. The case below is compiled and run at -O2 with
# this build's flags where the build machine can run them; a wrong answer
# gives a warning with the ways out. Nothing is checked when cross-compiling
# or when the flags do not enable AVX-512.
include(CheckCXXSourceCompiles)
include(CheckCXXSourceRuns)
include(CMakePushCheckState)
cmake_push_check_state(RESET)
set(CMAKE_REQUIRED_QUIET ON)
check_cxx_source_compiles("#if !defined(__AVX512F__)
#error no AVX-512
#endif
int main() { return 0; }" MOTORMIX_FLAGS_ENABLE_AVX512)
if(MOTORMIX_FLAGS_ENABLE_AVX512 AND NOT CMAKE_CROSSCOMPILING)
  set(CMAKE_REQUIRED_FLAGS -O2)
  check_cxx_source_runs("#include <array>
using Four = std::array<double, 4>;
__attribute__((noinline)) int differs(double x, Four want) {
  return want[0] != x || want[1] != x || want[2] != 0.0 || want[3] != 0.0;
}
int main() { return differs(0.5, {0.5, 0.5, 0.0, 0.0}) | differs(0.25, {0.25, 0.25, 0.0, 0.0}); }"
    MOTORMIX_AVX512_CONSTANTS_RIGHT)
  if(NOT MOTORMIX_AVX512_CONSTANTS_RIGHT)
    message(WARNING "motormix: this compiler (${CMAKE_CXX_COMPILER_ID} "
      "${CMAKE_CXX_COMPILER_VERSION}) builds constant vectors wrongly with the AVX-512 these "
      "flags enable ({0.5, 0.5, 0, 0} became {0.5, 0.5, 0.5, 0.5} in a check just run), so "
      "any code of this build may be wrong. Build without AVX-512 (-march=x86-64-v3, or "
      "-march=native -mno-avx512f), with clang, or with a newer GCC.")
  endif()
endif()
cmake_pop_check_state()
