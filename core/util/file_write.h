// The one way Facet writes a file (projects, exports, screenshots, settings, reports, recovery
// files): to a temporary file beside the target, flushed to disk, then renamed over it, so a
// failed write (a full disk, a killed process) leaves the old file intact.
//
// What the target may be: a regular file (replaced), nothing (created), or a symbolic link.
// Anything else that exists (a device such as /dev/zero, a FIFO, a socket, a folder) is refused
// with a message naming the file and what it is: the rename would replace the node by a
// regular file. A symbolic link, by the caller's choice:
// - Symlinks::kFollow (a user's Save, Export, screenshot): the file is written where the link
//   points (also when it points to nothing yet), keeping the link, as editors do: the user
//   chose that name. The end of the chain gets the checks above.
// - Symlinks::kRefuse (the recovery file, which the program names on its own, app/state/autosave.h):
//   a link is refused by name, so a link planted at the recovery file's name cannot make
//   autosave overwrite another file (a project, a device).
#pragma once

#include <string>

namespace facet {

enum class Symlinks { kFollow, kRefuse };

// "" on success, else what failed and why (the old file, if any, is untouched).
std::string WriteFileAtomically(const std::string& path, const std::string& bytes,
                                Symlinks symlinks = Symlinks::kFollow);

// The one exception, for a journal whose reader drops a torn last record (the recovery file,
// core/io/recovery_io.h): appends `bytes` to the existing regular file `path` and flushes it to
// disk. "" on success; else what failed and why, and the file is cut back to its old length
// where that is still possible (a crash can leave part of `bytes` at the end). A missing file
// is an error (ENOENT), not created: the caller then writes the whole file atomically. A
// symbolic link, a FIFO, a device or a folder is refused (never followed, never blocks).
std::string AppendToFile(const std::string& path, const std::string& bytes);

// What `path` is when it exists and is not a regular file, in words ("a symbolic link", "a
// FIFO", "a character device", "a block device", "a socket", "a folder"); "" for a regular
// file or nothing at all. Links are not followed.
std::string DescribeNonRegular(const std::string& path);

// Keeps a file a user may still need out of the way, never deleting or replacing anything:
// renames the regular file `path` to `PATH.TAG-YYYYMMDD-HHMMSS` (local time; `-2`, `-3`, ...
// appended when that name is taken) and sets *moved_to to the new name. "" on success, else
// what failed and why (the file is then where it was).
std::string MoveFileAside(const std::string& path, const std::string& tag, std::string* moved_to);

}  // namespace facet
