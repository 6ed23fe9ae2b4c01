#include "acquisition/run_folder.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "acquisition/errors.h"
#include "acquisition/file_util.h"

namespace fs = std::filesystem;

namespace gf {
namespace {

constexpr const char* kFormatLine = "glassfusion-run 1";

std::string Header() {
  return std::string(kFormatLine) +
         "\n"
         "# A GlassFusion output folder. glassfusion wrote the files and made the folders listed\n"
         "# below (paths relative to this folder); `--force` removes only those (folders only "
         "when\n"
         "# left empty) and nothing else here. .glassfusion-run.lock keeps two runs out at once.\n";
}

// The absolute, canonical form of a path that may not exist yet, without a trailing separator.
fs::path Canonical(const std::string& path) {
  std::error_code ec;
  fs::path p = fs::weakly_canonical(fs::absolute(path), ec);
  if (ec) p = fs::absolute(path).lexically_normal();
  if (p.filename().empty() && p.has_parent_path()) p = p.parent_path();
  return p;
}

// Whether `inner` lies strictly inside `outer` (both canonical).
bool Inside(const fs::path& inner, const fs::path& outer) {
  const auto [o, i] = std::mismatch(outer.begin(), outer.end(), inner.begin(), inner.end());
  return o == outer.end() && i != inner.end();
}

// A plain relative path: no root, no "." or ".." or empty component, no line break.
bool PlainRelative(const std::string& relative) {
  if (relative.empty() || relative.find_first_of("\n\r") != std::string::npos) return false;
  const fs::path p(relative);
  if (p.is_absolute() || p.has_root_name()) return false;
  for (const fs::path& part : p)
    if (part.empty() || part == "." || part == "..") return false;
  return true;
}

// Whether `dir` holds anything but the marker, the lock and the marker's temporary name while a
// writer sharing the folder creates it (all named .glassfusion-run*).
bool HoldsForeign(const fs::path& dir) {
  std::error_code ec;
  for (const auto& entry : fs::directory_iterator(dir, ec))
    if (entry.path().filename().string().rfind(RunFolder::kMarkerName, 0) != 0) return true;
  return false;
}

// The pid holding a flock on the file open as `fd`, from /proc/locks; "" when unknown.
std::string FlockHolder(int fd) {
  struct stat st;
  if (::fstat(fd, &st) != 0) return "";
  char want[64];
  std::snprintf(want, sizeof(want), "%02x:%02x:%lu", major(st.st_dev), minor(st.st_dev),
                static_cast<unsigned long>(st.st_ino));
  std::ifstream locks("/proc/locks");
  std::string line;
  while (std::getline(locks, line)) {
    std::istringstream words(line);
    std::string id, type, advisory, mode, pid, file;
    if (!(words >> id >> type >> advisory >> mode >> pid >> file)) continue;
    if (type == "FLOCK" && file == want && pid != "0") return pid;
  }
  return "";
}

}  // namespace

RunFolder::RunFolder(const std::string& dir, const Options& options) : dir_(dir) {
  GF_CHECK(!options.shared || options.earlier == kKeep, "a shared lock only adds to a folder");
  CheckInputs(options.inputs);
  const fs::path path(dir_);
  std::error_code ec;
  if (fs::exists(path, ec) && !fs::is_directory(path, ec))
    throw InputError(dir_, "exists and is not a folder");
  const std::string not_ours = std::string("is not empty and holds no run (no ") + kMarkerName +
                               "); choose a new or empty folder (nothing was deleted: glassfusion "
                               "replaces only folders it marked as its own)";
  if (fs::is_directory(path, ec) && !IsMarked(dir_) && HoldsForeign(path))
    throw InputError(dir_, not_ours);
  fs::create_directories(path, ec);
  if (ec) throw InputError(dir_, "cannot create output folder: " + ec.message());
  Lock(options.shared);
  try {
    if (!IsMarked(dir_)) {
      if (HoldsForeign(path)) throw InputError(dir_, not_ours);  // filled meanwhile
      CreateMarker(false);
      return;
    }
    for (const std::string& entry : ReadMarker(dir_)) {
      const bool file = entry.rfind("file ", 0) == 0;
      (file ? files_ : folders_).insert(entry.substr(file ? 5 : 7));
    }
    if (options.earlier == kKeep) {
      CreateMarker(false);
      return;
    }
    if (options.earlier == kRefuse && HoldsForeign(path))
      throw InputError(dir_,
                       "is not empty (an earlier run); choose a new folder, or --force to replace "
                       "what that run wrote");
    RemoveEarlierRun();
    CreateMarker(true);
  } catch (...) {
    if (marker_fd_ >= 0) ::close(marker_fd_);
    ::close(lock_fd_);
    throw;
  }
}

RunFolder::~RunFolder() {
  if (marker_fd_ >= 0) ::close(marker_fd_);
  if (lock_fd_ >= 0) ::close(lock_fd_);  // releases the flock
}

void RunFolder::CheckInputs(const std::vector<std::string>& inputs) const {
  const fs::path out = Canonical(dir_);
  for (const std::string& input : inputs) {
    std::error_code ec;
    if (input.empty() || !fs::exists(input, ec)) continue;  // a device URI, or nothing on disk
    const fs::path in = Canonical(input);
    const std::string kept = " (nothing was written or deleted)";
    if (out == in)
      throw InputError(dir_, "is the input; choose another folder for the outputs" + kept);
    if (Inside(out, in))
      throw InputError(dir_,
                       "lies inside the input " + input + "; write the outputs outside it" + kept);
    if (Inside(in, out))
      throw InputError(dir_, "contains the input " + input +
                                 "; write the outputs to a folder of their own" + kept);
  }
}

void RunFolder::Lock(bool shared) {
  const std::string lock = (fs::path(dir_) / kLockName).string();
  lock_fd_ = ::open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (lock_fd_ < 0) throw InputError(lock, std::string("cannot open: ") + std::strerror(errno));
  if (::flock(lock_fd_, (shared ? LOCK_SH : LOCK_EX) | LOCK_NB) == 0) {
    // Our pid, for the message of whoever comes second where /proc/locks does not say; the
    // run does not depend on it, so a failure to write it is ignored.
    if (!shared && ::ftruncate(lock_fd_, 0) == 0) {
      const std::string pid = std::to_string(::getpid()) + "\n";
      [[maybe_unused]] const ssize_t written = ::pwrite(lock_fd_, pid.data(), pid.size(), 0);
    }
    return;
  }
  const int error = errno;
  std::string holder = FlockHolder(lock_fd_);
  if (holder.empty()) {
    char buffer[32] = {};
    if (::pread(lock_fd_, buffer, sizeof(buffer) - 1, 0) > 0) holder = buffer;
    holder.erase(std::remove(holder.begin(), holder.end(), '\n'), holder.end());
  }
  ::close(lock_fd_);
  lock_fd_ = -1;
  if (error != EWOULDBLOCK) throw InputError(lock, std::string("cannot lock: ") + strerror(error));
  throw InputError(dir_, "another glassfusion run is writing here" +
                             (holder.empty() ? std::string() : " (pid " + holder + ")") +
                             "; wait for it to end, or choose another folder");
}

void RunFolder::RemoveEarlierRun() {
  std::error_code ec;
  const fs::path root = fs::canonical(dir_, ec);
  // Only inside this folder: an entry whose folder resolves elsewhere (a link) is left alone.
  auto here = [&](const fs::path& p) {
    const fs::path parent = Canonical(p.parent_path().string());
    return parent == root || Inside(parent, root);
  };
  std::set<std::string> kept_files, kept_folders;
  for (const std::string& file : files_) {
    const fs::path p = fs::path(dir_) / file;
    const fs::file_status status = fs::symlink_status(p, ec);
    if (!fs::exists(status)) continue;
    if (fs::is_directory(status) || !here(p) || !fs::remove(p, ec) || ec) kept_files.insert(file);
  }
  std::vector<std::string> folders(folders_.begin(), folders_.end());
  auto depth = [](const std::string& f) { return std::count(f.begin(), f.end(), '/'); };
  std::stable_sort(folders.begin(), folders.end(),
                   [&](const std::string& a, const std::string& b) { return depth(a) > depth(b); });
  for (const std::string& folder : folders) {
    const fs::path p = fs::path(dir_) / folder;
    const fs::file_status status = fs::symlink_status(p, ec);
    if (!fs::exists(status)) continue;
    if (!fs::is_directory(status) || !here(p) || !fs::is_empty(p, ec) || !fs::remove(p, ec) || ec)
      kept_folders.insert(folder);
  }
  files_ = kept_files;
  folders_ = kept_folders;
}

void RunFolder::CreateMarker(bool replace_existing) {
  const fs::path marker = fs::path(dir_) / kMarkerName;
  if (replace_existing) {  // what could not be removed stays listed
    std::string text = Header();
    for (const std::string& f : folders_) text += "folder " + f + "\n";
    for (const std::string& f : files_) text += "file " + f + "\n";
    WriteTextFileAtomically(marker.string(), text);
  } else if (!IsMarked(dir_)) {
    // Written whole under another name, then linked into place: link() fails rather than
    // replacing a marker that a writer sharing the folder made meanwhile.
    const std::string temporary = marker.string() + ".new-" + std::to_string(::getpid());
    WriteTextFileAtomically(temporary, Header());
    if (::link(temporary.c_str(), marker.c_str()) != 0 && errno != EEXIST) {
      const int error = errno;
      ::unlink(temporary.c_str());
      throw InputError(marker.string(), std::string("cannot create: ") + strerror(error));
    }
    ::unlink(temporary.c_str());
  }
  marker_fd_ = ::open(marker.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC);
  if (marker_fd_ < 0)
    throw InputError(marker.string(), std::string("cannot open: ") + std::strerror(errno));
}

void RunFolder::Append(const std::string& kind, const std::string& relative) {
  const std::string line = kind + " " + relative + "\n";
  // One write() of a whole line with O_APPEND: writers sharing the folder never interleave.
  if (::write(marker_fd_, line.data(), line.size()) != static_cast<ssize_t>(line.size()))
    throw InputError((fs::path(dir_) / kMarkerName).string(),
                     std::string("cannot record ") + relative + ": " + std::strerror(errno));
}

namespace {

void CheckPlain(const std::string& dir, const std::string& relative) {
  if (!PlainRelative(relative))
    throw InputError((fs::path(dir) / relative).string(),
                     "not a plain path inside the output folder");
  const std::string top = fs::path(relative).begin()->string();
  if (top == RunFolder::kMarkerName || top == RunFolder::kLockName)
    throw InputError((fs::path(dir) / relative).string(), "is reserved for glassfusion's marker");
}

}  // namespace

std::string RunFolder::File(const std::string& relative) {
  CheckPlain(dir_, relative);
  const fs::path p(relative);
  std::lock_guard<std::mutex> lock(mutex_);
  if (p.has_parent_path()) FolderLocked(p.parent_path().generic_string());
  const std::string path = (fs::path(dir_) / p).string();
  if (files_.count(relative)) return path;
  std::error_code ec;
  if (fs::exists(fs::symlink_status(path, ec)))
    throw InputError(path,
                     "is already there and no glassfusion run here wrote it; glassfusion never "
                     "overwrites such a file (move it, or choose another output folder)");
  Append("file", relative);
  files_.insert(relative);
  return path;
}

std::string RunFolder::Folder(const std::string& relative) {
  CheckPlain(dir_, relative);
  std::lock_guard<std::mutex> lock(mutex_);
  return FolderLocked(fs::path(relative).generic_string());
}

std::string RunFolder::FolderLocked(const std::string& relative) {
  fs::path sofar;
  for (const fs::path& part : fs::path(relative)) {
    sofar /= part;
    const std::string rel = sofar.generic_string();
    if (seen_.count(rel)) continue;
    const fs::path full = fs::path(dir_) / sofar;
    std::error_code ec;
    const fs::file_status status = fs::symlink_status(full, ec);
    if (!fs::is_directory(status)) {
      if (fs::exists(status))
        throw InputError(full.string(),
                         "is in the way: glassfusion needs a folder of its own here");
      if (!folders_.count(rel)) Append("folder", rel);
      folders_.insert(rel);
      fs::create_directory(full, ec);
      if (ec) throw InputError(full.string(), "cannot create folder: " + ec.message());
    }
    seen_.insert(rel);
  }
  return (fs::path(dir_) / relative).string();
}

void RunFolder::RecordTree(const std::string& relative) {
  CheckPlain(dir_, relative);
  std::lock_guard<std::mutex> lock(mutex_);
  const fs::path top = fs::path(dir_) / relative;
  if (!folders_.count(relative)) Append("folder", relative);
  folders_.insert(relative);
  std::error_code ec;
  for (const auto& entry : fs::recursive_directory_iterator(top, ec)) {
    const std::string rel =
        (fs::path(relative) / entry.path().lexically_relative(top)).generic_string();
    const bool folder = entry.is_directory() && !entry.is_symlink();
    std::set<std::string>& listed = folder ? folders_ : files_;
    if (!PlainRelative(rel) || listed.count(rel)) continue;
    Append(folder ? "folder" : "file", rel);
    listed.insert(rel);
  }
  if (ec) throw InputError(top.string(), "cannot list: " + ec.message());
}

bool RunFolder::IsMarked(const std::string& dir) {
  std::error_code ec;
  return fs::is_regular_file(fs::symlink_status(fs::path(dir) / kMarkerName, ec));
}

std::vector<std::string> RunFolder::ReadMarker(const std::string& dir) {
  const std::string path = (fs::path(dir) / kMarkerName).string();
  const std::string text = ReadTextFile(path);
  if (text.rfind(kFormatLine, 0) != 0)
    throw InputError(path, std::string("is not a GlassFusion marker (its first line is not \"") +
                               kFormatLine + "\"); nothing was deleted");
  std::vector<std::string> entries;
  size_t start = 0;
  for (size_t end; (end = text.find('\n', start)) != std::string::npos; start = end + 1) {
    const std::string line = text.substr(start, end - start);  // a torn last line never counts
    for (const char* kind : {"file ", "folder "})
      if (line.rfind(kind, 0) == 0 && PlainRelative(line.substr(std::strlen(kind))))
        entries.push_back(line);
  }
  return entries;
}

std::string IndexedFileName(int number, const std::string& timestamp) {
  char prefix[16];
  std::snprintf(prefix, sizeof(prefix), "%06d", number);
  return prefix + (timestamp.empty() ? "" : "_" + timestamp) + ".png";
}

std::string StampOfIndexedName(const std::string& name) {
  const size_t underscore = name.find('_');
  const size_t dot = name.rfind(".png");
  if (underscore == std::string::npos || dot == std::string::npos || dot <= underscore) return "";
  return name.substr(underscore + 1, dot - underscore - 1);
}

}  // namespace gf
