#pragma once
// What the per-message benchmarks (signing_cost, receive_cost) share: their
// `--messages N --passes P` options and the median over passes.

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

namespace motormix::bench {

inline double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

// Reads --messages and --passes into the defaults given; false (with the
// usage on stderr) when either is outside its range.
inline bool read_passes(int argc, char** argv, const char* name, int max_messages, int& messages,
                        int& passes) {
  for (int i = 1; i + 1 < argc; i += 2) {
    if (std::strcmp(argv[i], "--messages") == 0) messages = std::atoi(argv[i + 1]);
    if (std::strcmp(argv[i], "--passes") == 0) passes = std::atoi(argv[i + 1]);
  }
  if (messages < 1 || messages > max_messages || passes < 1 || passes > 100) {
    std::fprintf(stderr, "usage: %s [--messages N] [--passes P]\n", name);
    return false;
  }
  return true;
}

}  // namespace motormix::bench
