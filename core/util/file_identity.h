// What a file was when a session last read or wrote it, to notice that something else wrote
// it since (another program, another Facet without the lock, a copy put back): the stat
// identity (device, inode, size, modification time in ns) for the quick check, and a hash
// of the bytes so that a file rewritten with the same content (touched, copied back) still
// counts as unchanged.
#pragma once

#include <cstdint>
#include <string>

namespace facet {

struct FileIdentity {
  bool exists = false;
  std::uint64_t device = 0, inode = 0, size_bytes = 0;
  std::int64_t modified_ns = 0;    // st_mtim, ns since 1970
  std::uint64_t content_hash = 0;  // FNV-1a 64 of the bytes; 0 when not read
  friend bool operator==(const FileIdentity&, const FileIdentity&) = default;
};

// The identity of `path` now (exists == false when it is not there), hashing its bytes (at
// most core/util/file_read.h's kMaxTextFileBytes; a longer or unreadable file hashes to 0).
FileIdentity IdentifyFile(const std::string& path);

// Whether the file at `path` is still what `known` describes: the same stat identity, or
// other stat figures with the same bytes. A file that is gone is unchanged only when it was
// gone then too.
bool FileUnchangedSince(const std::string& path, const FileIdentity& known);

}  // namespace facet
