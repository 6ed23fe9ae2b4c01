// The names of a closed set (an enum class), read and written through one table of
// {name, value} pairs: settings files, camera.json and the command line spell the values by name.
#pragma once

#include <cstddef>
#include <string>
#include <utility>

namespace gf {

// *value gets the value named `text`; false (and *value unchanged) for a name not in the table.
template <typename E, std::size_t N>
bool ValueOfName(const std::pair<const char*, E> (&table)[N], const std::string& text, E* value) {
  for (const auto& [name, v] : table)
    if (text == name) {
      *value = v;
      return true;
    }
  return false;
}

// The name of `value` (the first entry's for a value not in the table).
template <typename E, std::size_t N>
const char* NameOfValue(const std::pair<const char*, E> (&table)[N], E value) {
  for (const auto& [name, v] : table)
    if (v == value) return name;
  return table[0].first;
}

}  // namespace gf
