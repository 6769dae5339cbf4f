#include "config/yaml_reader.hpp"

#include <cmath>
#include <regex>
#include <sstream>

namespace motormix::config {

namespace {

std::string format_number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

std::string where(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  if (mark.line < 0) return "";
  return " (line " + std::to_string(mark.line + 1) + ")";
}

thread_local KeyLog* t_key_log = nullptr;

}  // namespace

KeyLog::KeyLog() : previous_(t_key_log) { t_key_log = this; }
KeyLog::~KeyLog() { t_key_log = previous_; }

bool MapReader::recording() { return t_key_log != nullptr; }

void MapReader::record(const std::string& key, const char* kind, std::string fallback,
                       std::string allowed, bool required) const {
  if (t_key_log == nullptr) return;
  static const std::regex kIndex(R"(\[[0-9]+\])");
  t_key_log->add({std::regex_replace(path_of(key), kIndex, "[]"), kind, std::move(fallback),
                  std::move(allowed), required});
}

void fail(const std::string& path, const std::string& found, const std::string& allowed) {
  throw ConfigError("config key '" + path + "': found " + found + "; allowed: " + allowed);
}

std::string describe(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "nothing";
  if (node.IsScalar()) return "'" + node.Scalar() + "'" + where(node);
  if (node.IsSequence()) return "a list of " + std::to_string(node.size()) + where(node);
  return "a mapping" + where(node);
}

double to_number(const YAML::Node& node, const std::string& path, double lo, double hi) {
  // The range is spelled only for a refusal: a start-up reads hundreds of
  // numbers that pass.
  const auto refuse = [&] {
    fail(path, describe(node), "a number from " + format_number(lo) + " to " + format_number(hi));
  };
  if (!node.IsScalar()) refuse();
  double value = 0.0;
  try {
    value = node.as<double>();
  } catch (const YAML::Exception&) {
    refuse();
  }
  if (!std::isfinite(value) || value < lo || value > hi) refuse();
  return value;
}

MapReader::MapReader(const YAML::Node& node, std::string path)
    : node_(node), path_(std::move(path)) {
  if (node_.IsDefined() && !node_.IsNull() && !node_.IsMap()) {
    fail(path_.empty() ? "(document)" : path_, describe(node_), "a mapping of keys to values");
  }
}

bool MapReader::has(const std::string& key) const {
  return node_.IsMap() && node_[key].IsDefined() && !node_[key].IsNull();
}

std::string MapReader::path_of(const std::string& key) const {
  return path_.empty() ? key : path_ + "." + key;
}

YAML::Node MapReader::get(const std::string& key) {
  read_.insert(key);
  if (!node_.IsMap()) return YAML::Node();
  return node_[key];
}

YAML::Node MapReader::raw(const std::string& key) {
  record(key, "value", "", "");
  return get(key);
}

double MapReader::number(const std::string& key, double fallback, double lo, double hi) {
  if (recording())
    record(key, "number", format_number(fallback), format_number(lo) + " to " + format_number(hi));
  if (!has(key)) {
    read_.insert(key);
    return fallback;
  }
  return to_number(get(key), path_of(key), lo, hi);
}

double MapReader::required_number(const std::string& key, double lo, double hi) {
  if (recording()) record(key, "number", "", format_number(lo) + " to " + format_number(hi), true);
  if (!has(key)) {
    fail(path_of(key), "nothing",
         "a number from " + format_number(lo) + " to " + format_number(hi) + " (required)");
  }
  return to_number(get(key), path_of(key), lo, hi);
}

bool MapReader::boolean(const std::string& key, bool fallback) {
  record(key, "boolean", fallback ? "true" : "false", "true or false");
  const YAML::Node node = get(key);
  if (!node.IsDefined() || node.IsNull()) return fallback;
  if (!node.IsScalar() || (node.Scalar() != "true" && node.Scalar() != "false")) {
    fail(path_of(key), describe(node), "true or false");
  }
  return node.Scalar() == "true";
}

std::string MapReader::text(const std::string& key, const std::string& fallback) {
  return text_as(key, fallback, "text", "a non-empty string");
}

std::string MapReader::text_as(const std::string& key, const std::string& fallback,
                               const char* kind, const std::string& allowed) {
  record(key, kind, fallback, allowed);
  if (!has(key)) {
    read_.insert(key);
    return fallback;
  }
  const YAML::Node value = get(key);
  if (!value.IsScalar() || value.Scalar().empty()) {
    fail(path_of(key), describe(value), "a non-empty string");
  }
  return value.Scalar();
}

std::string MapReader::choice(const std::string& key, const std::string& fallback,
                              const std::vector<std::string>& allowed) {
  std::string list;
  for (const std::string& a : allowed) list += (list.empty() ? "" : ", ") + a;
  const std::string value = text_as(key, fallback, "choice", "one of " + list);
  for (const std::string& a : allowed) {
    if (a == value) return value;
  }
  fail(path_of(key), "'" + value + "'" + where(node_[key]), "one of " + list);
}

MapReader MapReader::map(const std::string& key) {
  record(key, "mapping", "", "");
  return MapReader(get(key), path_of(key));
}

void MapReader::finish() const {
  if (!node_.IsMap()) return;
  for (const auto& entry : node_) {
    const std::string key = entry.first.Scalar();
    if (read_.count(key) == 0) {
      std::string known;
      for (const std::string& k : read_) known += (known.empty() ? "" : ", ") + k;
      throw ConfigError("config key '" + path_of(key) + "'" + where(entry.first) +
                        " is not known here; known keys: " + known);
    }
  }
}

}  // namespace motormix::config
