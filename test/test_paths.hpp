#pragma once
// Where the tests find the source tree and the motormix binary. Defined in a
// source that CMake generates (test/CMakeLists.txt), so that no test's compile
// command holds an absolute path: a clone in another directory reuses every
// cached test object, and only that one small file is compiled again.

namespace motormix::test {

const char* source_dir();       // the project's source tree
const char* motormix_binary();  // the motormix executable of this build

}  // namespace motormix::test
