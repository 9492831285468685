// Reading a whole file without trusting the path: only a regular file is read (a folder, a
// FIFO, a socket or a device such as /dev/zero is refused before anything can block or
// stream forever), and never more than a stated number of bytes. Every reader in core and
// the app goes through it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace facet {

// Limits per kind of file (bytes). A project or CLI JSON is text of at most a few MB in
// practice; a photo file of 512 MB is beyond any camera's.
constexpr std::uint64_t kMaxTextFileBytes = 256ull << 20;
constexpr std::uint64_t kMaxImageFileBytes = 512ull << 20;

// Reads all of `path` into *bytes. False with *error naming the file and the reason (not
// found, not a regular file and what it is, larger than `max_bytes` with the limit, a read
// error).
bool ReadRegularFile(const std::string& path, std::uint64_t max_bytes, std::string* bytes, std::string* error);
bool ReadRegularFile(const std::string& path, std::uint64_t max_bytes, std::vector<std::uint8_t>* bytes,
                     std::string* error);

// The first `head_bytes` of `path` (all of it when shorter), with the same refusals: for
// reading a header without reading the whole file.
bool ReadRegularFileHead(const std::string& path, std::uint64_t head_bytes, std::vector<std::uint8_t>* bytes,
                         std::string* error);

}  // namespace facet
