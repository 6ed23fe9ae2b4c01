#include "acquisition/tum_index.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include "acquisition/errors.h"
#include "acquisition/file_util.h"

namespace fs = std::filesystem;

namespace gf {

std::vector<IndexLine> ReadTumIndex(const std::string& folder, const std::string& name) {
  const std::string path = (fs::path(folder) / name).string();
  std::istringstream in(ReadTextFile(path));
  std::vector<IndexLine> lines;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    const size_t start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#') continue;
    std::istringstream fields(line);
    IndexLine entry;
    std::string file;
    if (!(fields >> entry.timestamp_text >> file))
      throw InputError(path,
                       "line " + std::to_string(number) + ": expected \"timestamp filename\"");
    // std::stod reads "nan" and "inf" too: a timestamp must be a finite number of seconds (a NaN
    // would compare false with every other and drop frames from the association unsaid).
    try {
      size_t used = 0;
      entry.timestamp = std::stod(entry.timestamp_text, &used);
      if (used != entry.timestamp_text.size() || !std::isfinite(entry.timestamp))
        throw std::invalid_argument("not a finite number");
    } catch (const std::exception&) {
      throw InputError(path, "line " + std::to_string(number) + ": bad timestamp \"" +
                                 entry.timestamp_text + "\" (expected a finite number of seconds)");
    }
    entry.path = (fs::path(folder) / file).string();
    lines.push_back(entry);
  }
  if (lines.empty()) throw InputError(path, "index lists no images");
  std::stable_sort(lines.begin(), lines.end(), [](const IndexLine& a, const IndexLine& b) {
    return a.timestamp < b.timestamp;
  });
  return lines;
}

bool PathListed(const std::string& path) {
  std::error_code ec;
  return fs::symlink_status(path, ec).type() != fs::file_type::not_found && !ec;
}

std::string IndexFileProblem(const std::string& path) {
  std::error_code ec;
  const fs::file_status link = fs::symlink_status(path, ec);
  if (ec || link.type() == fs::file_type::not_found) return "file not found";
  const fs::file_status target = fs::status(path, ec);
  if (ec || target.type() == fs::file_type::not_found) return "is a link to nothing";
  if (target.type() == fs::file_type::directory) return "is a folder, not a file";
  if (target.type() != fs::file_type::regular) return "is not a regular file";
  return "";
}

}  // namespace gf
