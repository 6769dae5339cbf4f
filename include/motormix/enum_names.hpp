#pragma once
// One table per enumeration gives both its text (logs, status, JSON, the
// --check description) and its parsing (configuration, command line), so a
// value cannot be spelled one way when it is read and another when written.

#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace motormix {

template <typename E>
struct EnumName {
  E value;
  const char* name;
};

// The name of `value`; "?" for a value the table does not hold (a corrupted
// or cast enumerator), never a null pointer.
template <typename E, std::size_t N>
constexpr const char* name_in(const EnumName<E> (&table)[N], E value) {
  for (const EnumName<E>& entry : table) {
    if (entry.value == value) return entry.name;
  }
  return "?";
}

// The value named `text` exactly, or nothing.
template <typename E, std::size_t N>
constexpr std::optional<E> parse_in(const EnumName<E> (&table)[N], std::string_view text) {
  for (const EnumName<E>& entry : table) {
    if (text == entry.name) return entry.value;
  }
  return std::nullopt;
}

// Every name, in table order (for "one of ..." messages and readers).
template <typename E, std::size_t N>
std::vector<std::string> names_in(const EnumName<E> (&table)[N]) {
  std::vector<std::string> names;
  names.reserve(N);
  for (const EnumName<E>& entry : table) names.emplace_back(entry.name);
  return names;
}

// "a, b, c": every name, for messages and help texts.
template <typename E, std::size_t N>
std::string joined_names(const EnumName<E> (&table)[N]) {
  std::string text;
  for (const EnumName<E>& entry : table)
    text += (text.empty() ? "" : ", ") + std::string(entry.name);
  return text;
}

}  // namespace motormix
