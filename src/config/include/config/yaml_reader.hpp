#pragma once
// Strict reading of a YAML mapping: every key read is remembered, finish()
// rejects the rest, and every error names the full key path, the value found
// and what is allowed.

#include <motormix/config/config_error.hpp>
#include <motormix/enum_names.hpp>

#include <yaml-cpp/yaml.h>

#include <optional>
#include <set>
#include <string>
#include <vector>

namespace motormix::config {

// Every key a MapReader reads, as the loader reads it: the configuration
// reference (docs/configuration.md) is generated from these records by
// loading the bundled configurations, so it cannot drift from the loader.
struct KeyRecord {
  std::string path;      // key path, list indices as []: geometry.rotors[].spin
  std::string kind;      // number, text, choice, mapping, value (a list or a structure)
  std::string fallback;  // the default, as text; empty when required or structured
  std::string allowed;   // "0 to 1", "one of off, roll_pitch, ...", ...
  bool required = false;
};

// While one of these lives on a thread, that thread's MapReaders record
// every key they read into it.
class KeyLog {
 public:
  KeyLog();
  ~KeyLog();
  KeyLog(const KeyLog&) = delete;
  KeyLog& operator=(const KeyLog&) = delete;
  const std::vector<KeyRecord>& records() const { return records_; }
  void add(KeyRecord r) { records_.push_back(std::move(r)); }

 private:
  std::vector<KeyRecord> records_;
  KeyLog* previous_;
};

class MapReader {
 public:
  // `node` must be a mapping (or null, read as empty); `path` is its key path
  // ("" for the document root).
  MapReader(const YAML::Node& node, std::string path);

  bool has(const std::string& key) const;
  std::string path_of(const std::string& key) const;

  double number(const std::string& key, double fallback, double lo, double hi);
  double required_number(const std::string& key, double lo, double hi);
  std::string text(const std::string& key, const std::string& fallback);
  bool boolean(const std::string& key, bool fallback);
  std::string choice(const std::string& key, const std::string& fallback,
                     const std::vector<std::string>& allowed);
  // A choice among the names of an enumeration's table (enum_names.hpp).
  template <typename E, std::size_t N>
  E choice(const std::string& key, E fallback, const EnumName<E> (&table)[N]) {
    return *parse_in(table, choice(key, name_in(table, fallback), names_in(table)));
  }
  MapReader map(const std::string& key);   // an absent key reads as an empty map
  YAML::Node raw(const std::string& key);  // marks the key as read
  // An optional key that is read only when present (by has() and one of the
  // readers above): known here even when absent, so finish() does not call
  // it unknown and the configuration reference lists it.
  void allow(const std::string& key) { raw(key); }

  // Throws ConfigError naming the first key that was never read.
  void finish() const;

 private:
  YAML::Node get(const std::string& key);  // raw() without a record
  std::string text_as(const std::string& key, const std::string& fallback, const char* kind,
                      const std::string& allowed);
  // Whether a KeyLog listens on this thread: the record's text is built
  // only then.
  static bool recording();
  void record(const std::string& key, const char* kind, std::string fallback, std::string allowed,
              bool required = false) const;

  YAML::Node node_;
  std::string path_;
  std::set<std::string> read_;
};

// Error helpers shared by the loader.
[[noreturn]] void fail(const std::string& path, const std::string& found,
                       const std::string& allowed);
std::string describe(const YAML::Node& node);  // the value as written, for messages
double to_number(const YAML::Node& node, const std::string& path, double lo, double hi);

}  // namespace motormix::config
