// The example publishers' command line: `--name value` pairs and --help.
#pragma once

#include <cstring>
#include <initializer_list>
#include <iostream>
#include <string>

// An option a publisher takes, and the string its value goes into (which
// holds the default until then).
struct Option {
  const char* name;
  std::string* value;
};

// Reads argv into the options. Returns -1 to go on, else the exit status:
// 0 after --help (the usage on stdout), 2 for an unknown option or a
// missing value (the usage on stderr): nothing is published then.
inline int parse_options(int argc, char** argv, std::initializer_list<Option> options,
                         const char* usage) {
  for (int i = 1; i < argc; i += 2) {
    if (!std::strcmp(argv[i], "--help") || !std::strcmp(argv[i], "-h")) {
      std::cout << usage;
      return 0;
    }
    if (i + 1 >= argc) {
      std::cerr << argv[i] << ": a value is missing\n" << usage;
      return 2;
    }
    const Option* found = nullptr;
    for (const Option& o : options)
      if (!std::strcmp(argv[i], o.name)) found = &o;
    if (found == nullptr) {
      std::cerr << argv[i] << ": unknown option\n" << usage;
      return 2;
    }
    *found->value = argv[i + 1];
  }
  return -1;
}
