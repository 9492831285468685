#include "core/util/file_identity.h"

#include <sys/stat.h>

#include "core/util/file_read.h"

namespace facet {
namespace {

bool StatIdentity(const std::string& path, FileIdentity* identity) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return false;
  identity->exists = true;
  identity->device = static_cast<std::uint64_t>(st.st_dev);
  identity->inode = static_cast<std::uint64_t>(st.st_ino);
  identity->size_bytes = static_cast<std::uint64_t>(st.st_size);
  identity->modified_ns = static_cast<std::int64_t>(st.st_mtim.tv_sec) * 1000000000 + st.st_mtim.tv_nsec;
  return true;
}

std::uint64_t HashBytes(const std::string& bytes) {
  std::uint64_t hash = 14695981039346656037ull;
  for (unsigned char c : bytes) hash = (hash ^ c) * 1099511628211ull;
  return hash;
}

std::uint64_t HashFile(const std::string& path) {
  std::string bytes, error;
  return ReadRegularFile(path, kMaxTextFileBytes, &bytes, &error) ? HashBytes(bytes) : 0;
}

}  // namespace

FileIdentity IdentifyFile(const std::string& path) {
  FileIdentity identity;
  if (!StatIdentity(path, &identity)) return identity;
  identity.content_hash = HashFile(path);
  return identity;
}

bool FileUnchangedSince(const std::string& path, const FileIdentity& known) {
  FileIdentity now;
  if (!StatIdentity(path, &now)) return !known.exists;
  if (!known.exists) return false;
  now.content_hash = known.content_hash;
  if (now == known) return true;
  return known.content_hash != 0 && HashFile(path) == known.content_hash;
}

}  // namespace facet
