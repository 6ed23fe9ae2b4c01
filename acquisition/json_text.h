// JSON text for files and the terminal that never fails on the strings in it.
//
// Paths are bytes: a folder named in another encoding than UTF-8 (a Latin-1 "caf\xe9") is a valid
// input, but nlohmann's dump() throws on a string that is not UTF-8, and a run would fail after all
// its work, writing report.json. Every JSON GlassFusion writes goes through JsonText, which
// replaces such bytes by U+FFFD, the Unicode replacement character: the text stays valid JSON and
// the rest of the path readable.
//
// Usage:
//   WriteTextFileAtomically(path, gf::JsonText(report) + "\n");
#pragma once

#include <string>

namespace gf {

// j.dump(indent) with bytes that are not UTF-8 replaced by U+FFFD. Json: nlohmann::json or
// nlohmann::ordered_json.
template <typename Json>
std::string JsonText(const Json& j, int indent = 2) {
  return j.dump(indent, ' ', false, Json::error_handler_t::replace);
}

}  // namespace gf
