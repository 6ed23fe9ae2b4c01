// Helpers of the report's to_json and from_json functions (stage_reports.cc, run_report.cc):
// a field read when its key is there (and not null), optional values written as null, and
// {name: value} objects kept in their order.
#pragma once

#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace gf::json_fields {

using json = nlohmann::ordered_json;

// *out = j[key] when j has the key with a value; otherwise *out keeps its default.
template <typename T>
void Read(const json& j, const char* key, T* out) {
  if (j.is_object() && j.contains(key) && !j[key].is_null()) *out = j[key].get<T>();
}

template <typename T>
void Read(const json& j, const char* key, std::optional<T>* out) {
  if (j.is_object() && j.contains(key) && !j[key].is_null()) *out = j[key].get<T>();
}

// An object's members in their order.
template <typename T>
void Read(const json& j, const char* key, std::vector<std::pair<std::string, T>>* out) {
  out->clear();
  if (!j.is_object() || !j.contains(key) || !j[key].is_object()) return;
  for (const auto& [name, value] : j[key].items()) out->push_back({name, value.template get<T>()});
}

template <typename T>
json OrNull(const std::optional<T>& value) {
  return value ? json(*value) : json();
}

inline json OrNull(const std::string& name) { return name.empty() ? json() : json(name); }

// `pairs` as one object, in their order.
template <typename T>
json Object(const std::vector<std::pair<std::string, T>>& pairs) {
  json out = json::object();
  for (const auto& [name, value] : pairs) out[name] = value;
  return out;
}

}  // namespace gf::json_fields
