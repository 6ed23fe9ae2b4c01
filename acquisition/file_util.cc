#include "acquisition/file_util.h"

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <system_error>

#include "acquisition/errors.h"

namespace fs = std::filesystem;

namespace gf {

std::string ReadTextFile(const std::string& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(path, "file not found");
  if (fs::is_directory(path, ec)) throw InputError(path, "is a folder, expected a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "cannot open for reading");
  std::ostringstream buffer;
  buffer << in.rdbuf();
  if (in.bad()) throw InputError(path, "read error");
  return buffer.str();
}

void WriteFileAtomically(const std::string& path,
                         const std::function<void(const std::string&)>& write) {
  static std::atomic<unsigned> counter{0};
  const fs::path final_path(path);
  // Keep the extension last: writers such as cv::imwrite choose the format from it.
  const std::string temporary = (final_path.parent_path() /
                                 (".tmp-" + std::to_string(::getpid()) + "-" +
                                  std::to_string(counter++) + "-" + final_path.filename().string()))
                                    .string();
  try {
    write(temporary);
  } catch (...) {
    std::error_code ec;
    fs::remove(temporary, ec);
    throw;
  }
  std::error_code ec;
  if (!fs::exists(temporary, ec)) throw InputError(path, "writer produced no output");
  fs::rename(temporary, final_path, ec);
  if (ec) {
    fs::remove(temporary, ec);
    throw InputError(path, "cannot rename temporary output into place: " + ec.message());
  }
}

void WriteTextFileAtomically(const std::string& path, const std::string& content) {
  WriteFileAtomically(path, [&](const std::string& temporary) {
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError(path, "cannot open for writing");
    out << content;
    out.close();
    if (!out) throw InputError(path, "write error (disk full?)");
  });
}

std::string StageFolder(const std::string& out_dir) {
  std::error_code ec;
  if (fs::exists(out_dir, ec) && !(fs::is_directory(out_dir, ec) && fs::is_empty(out_dir, ec)))
    throw InputError(out_dir, "already exists and is not empty; choose a new output folder");
  // Beside the final folder, so the rename stays on one file system.
  fs::path out = fs::absolute(out_dir).lexically_normal();
  if (out.filename().empty()) out = out.parent_path();
  fs::create_directories(out.parent_path(), ec);
  if (ec) throw InputError(out_dir, "cannot create output folder: " + ec.message());
  const std::string base = out.string() + ".partial-" + std::to_string(::getpid());
  std::string staging = base;
  for (int n = 2; !fs::create_directory(staging, ec); ++n) {  // false: the name is taken
    if (ec) throw InputError(out_dir, "cannot create output folder: " + ec.message());
    staging = base + "-" + std::to_string(n);
  }
  return staging;
}

void PublishFolder(const std::string& staging_dir, const std::string& out_dir) {
  std::error_code ec;
  if (fs::exists(out_dir, ec))
    fs::remove(out_dir, ec);  // only ever the empty folder StageFolder allowed
  fs::rename(staging_dir, out_dir, ec);
  if (ec) throw InputError(out_dir, "cannot move the finished output into place: " + ec.message());
}

bool IsRegularFile(const std::string& path) {
  std::error_code ec;
  return fs::is_regular_file(path, ec);
}

bool IsDirectory(const std::string& path) {
  std::error_code ec;
  return fs::is_directory(path, ec);
}

}  // namespace gf
