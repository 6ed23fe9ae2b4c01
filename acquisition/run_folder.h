// An output folder that GlassFusion writes in place and may later replace: a run folder
// (reconstruct, compare's with_fill/ and without_fill/), a comparison, the demo's folder, a batch.
// DESIGN.md: nothing of the user's is deleted.
//
// Two files mark such a folder as ours:
//  - `.glassfusion-run`, the marker: a text file appended to as the run writes, so an interrupted
//    run still lists what it wrote. Line 1 is `glassfusion-run 1` (the format), lines starting
//    with '#' are comments, then one entry per line, relative to the folder:
//        file keyframes/1305031102.160407.hole_mask.png
//        folder keyframes
//    A path is recorded before its file is written, a folder before it is created (only folders
//    this run created are listed). Only lines ending in a newline count, so a line torn by a crash
//    names nothing. Paths are relative, without "." or "..", and hold no newline.
//  - `.glassfusion-run.lock`, the lock: flock(LOCK_EX | LOCK_NB) on it for the RunFolder's whole
//    life, so a second writer fails at once instead of mixing its files with ours (advisory: it
//    binds glassfusion, not other programs). It holds the pid of the process that took it last.
//    The kernel drops the lock when the process ends, however it ends; the file stays.
//
// Opening a folder (the constructor), in this order, each refusal an InputError "<dir>: <why>":
//  1. `dir` must not be, contain or lie inside any of `inputs` (canonical paths; an input may be
//     a folder or a file such as an .oni; inputs that are no path on disk, e.g. a device URI, are
//     ignored);
//  2. it must be absent, empty, or hold a marker (a folder with anything else is the user's);
//  3. it is created if absent, and locked (refused while another process holds the lock);
//  4. an earlier run's files (anything beside marker and lock): refused for kRefuse; for kReplace
//     the marker's files are removed, then its folders that are left empty, deepest first; for
//     kKeep they stay and the run goes on adding to the same marker. Files of the user's are
//     never touched; entries that could not be removed stay listed.
// While open, File() refuses to hand out a path where a file exists that this folder's marker
// does not list, so nothing of the user's is overwritten either.
//
// Thread-safety: File() and Folder() may be called from several threads at once.
// Usage:
//   gf::RunFolder run("out", {gf::RunFolder::kReplace, {"capture/"}});
//   gf::WriteTextFileAtomically(run.File("report.json"), text);   // "out/report.json"
//   const std::string keyframes = run.Folder("keyframes");
#pragma once

#include <mutex>
#include <set>
#include <string>
#include <vector>

namespace gf {

class RunFolder {
 public:
  // What to do with an earlier run found in the folder.
  enum Earlier {
    kRefuse,   // a new run needs a new or empty folder (no --force)
    kReplace,  // --force: remove the files the earlier run wrote, then write the new run
    kKeep,     // add to it (a batch resuming, colmap-import adding to a run)
  };
  struct Options {
    Earlier earlier = kRefuse;
    // What the run reads: the folder must not be, contain or lie inside any of them.
    std::vector<std::string> inputs;
    // flock(LOCK_SH) instead of LOCK_EX: several cooperating writers at once (the tasks of one
    // Slurm job array), each excluding exclusive writers. Only with kKeep.
    bool shared = false;
  };

  static constexpr const char* kMarkerName = ".glassfusion-run";
  static constexpr const char* kLockName = ".glassfusion-run.lock";

  // Opens (creates, locks, prepares) `dir` as described above. Throws InputError.
  RunFolder(const std::string& dir, const Options& options);
  // Releases the lock.
  ~RunFolder();
  RunFolder(const RunFolder&) = delete;
  RunFolder& operator=(const RunFolder&) = delete;

  const std::string& dir() const { return dir_; }

  // Records file `relative` in the marker, creates its parent folders (Folder), and returns
  // dir/relative for the caller to write. Throws InputError when the path is not a plain relative
  // path, when a file the marker does not list is already there, or when the marker cannot be
  // written.
  std::string File(const std::string& relative);
  // Creates folder dir/relative and the folders above it, recording each one it creates; returns
  // its path. Throws InputError as File does, or when something there is not a folder (or a link).
  std::string Folder(const std::string& relative);
  // Records every file and folder under dir/relative (a folder this run made wholesale, e.g.
  // moved into place by PublishFolder), and the folder itself.
  void RecordTree(const std::string& relative);

  // Whether `dir` holds a marker.
  static bool IsMarked(const std::string& dir);
  // The entries of dir's marker, "file PATH" and "folder PATH", in file order. Throws InputError
  // when it is missing or not a marker.
  static std::vector<std::string> ReadMarker(const std::string& dir);

 private:
  void CheckInputs(const std::vector<std::string>& inputs) const;
  void Lock(bool shared);
  void RemoveEarlierRun();
  void CreateMarker(bool replace_existing);
  void Append(const std::string& kind, const std::string& relative);  // mutex_ held
  std::string FolderLocked(const std::string& relative);              // mutex_ held

  std::string dir_;
  int lock_fd_ = -1;
  int marker_fd_ = -1;
  std::mutex mutex_;
  std::set<std::string> files_;    // relative paths the marker lists as files
  std::set<std::string> folders_;  // relative paths the marker lists as folders
  std::set<std::string> seen_;     // folders known to exist (checked once, then trusted)
};

// An image named by a number and a timestamp, <number:06d>_<ts>.png (<number:06d>.png without a
// timestamp): undistorted/'s files (the frame's index) and colmap-export's (the image id). Sorted
// by name, they are in number order. StampOfIndexedName gives the timestamp back ("" when none).
std::string IndexedFileName(int number, const std::string& timestamp);
std::string StampOfIndexedName(const std::string& name);

}  // namespace gf
