# `cpack -G DEB` in the build directory: one package, motormix_<version>_<arch>.deb,
# installing under /usr (binary, libraries, headers, CMake and pkg-config
# files, message types for C++, Python and Java, configs, docs).
set(CPACK_PACKAGE_NAME motormix)
set(CPACK_PACKAGE_VENDOR "motormix developers")
set(CPACK_PACKAGE_CONTACT "motormix developers <motormix@localhost>")
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY "${PROJECT_DESCRIPTION}")
set(CPACK_PACKAGE_DESCRIPTION
  "motormix subscribes to attitude and thrust commands over LCM, turns them into one command per
motor or wheel through a mixing matrix (any multirotor geometry, tables, differential drive) and
publishes PWM at a fixed loop rate, never out of range. The package also carries the mixing
library for C++ programs (CMake: find_package(motormix); pkg-config: motormix), the message types
for C++, Python and Java (lcm-spy), and example configurations.")
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_GENERATOR DEB)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION science)
set(CPACK_DEBIAN_PACKAGE_PRIORITY optional)
# Runtime dependencies: computed from the binary by dpkg-shlibdeps (exact
# package names and versions of the Debian release it was built on), or, without
# dpkg-dev, the bookworm names.
find_program(MOTORMIX_DPKG_SHLIBDEPS dpkg-shlibdeps)
if(MOTORMIX_DPKG_SHLIBDEPS)
  set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
else()
  set(CPACK_DEBIAN_PACKAGE_DEPENDS "liblcm1, libyaml-cpp0.7, libglib2.0-0, libstdc++6, libc6")
endif()
# What building against the package needs (the CMake package finds Eigen,
# LCM and yaml-cpp), and the tools that go with the bus.
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS "liblcm-bin, libeigen3-dev, liblcm-dev, libyaml-cpp-dev, pkg-config")
set(CPACK_DEBIAN_PACKAGE_SUGGESTS "liblcm-java, default-jre-headless")
include(CPack)
