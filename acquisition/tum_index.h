// The index files of folder datasets: TUM RGB-D's rgb.txt and depth.txt ("timestamp filename" per
// line, '#' comments), and what stands where an index file should be.
//
// Usage:
//   const std::string problem = gf::IndexFileProblem(folder + "/rgb.txt");  // "" when usable
//   std::vector<gf::IndexLine> color = gf::ReadTumIndex(folder, "rgb.txt");
#pragma once

#include <string>
#include <vector>

namespace gf {

struct IndexLine {
  double timestamp;            // seconds, finite
  std::string timestamp_text;  // as the index writes it
  std::string path;            // absolute or folder-relative as listed, resolved against the folder
};

// The lines of <folder>/<name>, sorted by time (stable). Throws InputError naming the file (and
// the line) when it is missing, lists no image, or holds a line that is not "timestamp filename"
// with a finite number of seconds ("nan" and "inf", which std::stod reads, included).
std::vector<IndexLine> ReadTumIndex(const std::string& folder, const std::string& name);

// Whether anything is at `path`, a dangling link included (symlink_status does not follow it).
bool PathListed(const std::string& path);

// "" when `path` is a regular file (or a link to one), else what stands there instead: "file not
// found", "is a link to nothing", "is a folder, not a file" or "is not a regular file".
std::string IndexFileProblem(const std::string& path);

}  // namespace gf
