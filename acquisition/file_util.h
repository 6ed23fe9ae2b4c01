// Small file helpers used at the I/O edges of every module.
//
// Every output GlassFusion writes goes through WriteFileAtomically: the content is written to a
// temporary name in the same folder, then renamed over the final name, so an interrupted run never
// leaves a truncated file that looks complete.
#pragma once

#include <functional>
#include <string>

namespace gf {

// Whole text file; throws InputError("<path>: ...") when it is missing or unreadable.
std::string ReadTextFile(const std::string& path);

// Calls write(temporary_path), then renames temporary_path to path. If write throws, the temporary
// file is removed and the exception propagates; path is untouched. The parent folder must exist.
void WriteFileAtomically(const std::string& path,
                         const std::function<void(const std::string& temporary_path)>& write);
void WriteTextFileAtomically(const std::string& path, const std::string& content);

// Output folders that appear only when complete (capture, synth, colmap-export): StageFolder
// checks that out_dir does not exist or is an empty folder (InputError otherwise) and creates a
// fresh, empty "<out_dir>.partial-<pid>" beside it (with a further "-<n>" when that name is taken:
// it never reuses, nor empties, a folder that is already there); PublishFolder renames the
// finished staging folder to out_dir, replacing at most the empty folder. Neither ever replaces
// outputs: folders written in place and replaced with --force are RunFolders (run_folder.h).
std::string StageFolder(const std::string& out_dir);
void PublishFolder(const std::string& staging_dir, const std::string& out_dir);

bool IsRegularFile(const std::string& path);
bool IsDirectory(const std::string& path);

}  // namespace gf
