# Writes a C++ source holding each scenario file's text (cmake -P, with OUT
# and FILES, a '|'-separated list), for src/sim/shipped_scenarios.hpp
# (the sim target has src/sim as a private include directory).
set(body "// Generated from scenarios/*.yaml by cmake/EmbedScenarios.cmake. Do not edit.\n")
string(APPEND body "#include \"shipped_scenarios.hpp\"\n\nnamespace motormix::sim {\n\n")
string(APPEND body "const std::vector<ShippedScenario>& shipped_scenario_texts() {\n")
string(APPEND body "  static const std::vector<ShippedScenario> texts = {\n")
string(REPLACE "|" ";" FILES "${FILES}")
list(SORT FILES)
foreach(file IN LISTS FILES)
  get_filename_component(name ${file} NAME_WE)
  file(READ ${file} text)
  string(APPEND body "      {\"${name}\", R\"motormix_yaml(${text})motormix_yaml\"},\n")
endforeach()
string(APPEND body "  };\n  return texts;\n}\n\n}  // namespace motormix::sim\n")
file(WRITE ${OUT}.tmp "${body}")
file(COPY_FILE ${OUT}.tmp ${OUT} ONLY_IF_DIFFERENT)
