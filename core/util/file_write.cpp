#include "core/util/file_write.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

namespace facet {
namespace {

// Writes all of `bytes` to `fd`, going on after short and interrupted writes: 0, else the
// failed write's errno.
int WriteAll(int fd, const std::string& bytes) {
  size_t written = 0;
  while (written < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + written, bytes.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      return errno;
    }
    written += static_cast<size_t>(n);
  }
  return 0;
}

}  // namespace

std::string WriteFileAtomically(const std::string& requested_path, const std::string& bytes) {
  namespace fs = std::filesystem;
  // Renaming over a symlink would replace the link by a file; write where it points instead,
  // also when it points to nothing yet (weakly_canonical would keep a dangling link's own name).
  std::string path = requested_path;
  for (int hops = 0; hops < 40; ++hops) {
    std::error_code link_ec;
    if (!fs::is_symlink(path, link_ec)) break;
    const fs::path target = fs::read_symlink(path, link_ec);
    if (link_ec) break;
    path = (target.is_absolute() ? target : fs::path(path).parent_path() / target).lexically_normal().string();
  }
  std::string temp = path + ".tmp-XXXXXX";
  const int fd = ::mkstemp(temp.data());
  if (fd < 0) return "cannot create a temporary file beside " + path + ": " + std::strerror(errno);
  auto fail = [&](const std::string& what, int err) {
    ::close(fd);
    ::unlink(temp.c_str());
    return "cannot save " + path + ": " + what + ": " + std::strerror(err);
  };
  // mkstemp makes the file private (0600); keep the replaced file's mode, else the usual 0644.
  struct stat existing {};
  const mode_t mode =
      ::stat(path.c_str(), &existing) == 0 && S_ISREG(existing.st_mode) ? (existing.st_mode & 07777) : 0644;
  if (::fchmod(fd, mode) != 0) return fail("setting permissions", errno);
  if (const int err = WriteAll(fd, bytes); err != 0) return fail("writing", err);
  if (::fsync(fd) != 0) return fail("flushing to disk", errno);
  if (::close(fd) != 0) {
    const int err = errno;
    ::unlink(temp.c_str());
    return "cannot save " + path + ": closing: " + std::strerror(err);
  }
  if (::rename(temp.c_str(), path.c_str()) != 0) {
    const int err = errno;
    ::unlink(temp.c_str());
    return "cannot save " + path + ": replacing the file: " + std::strerror(err);
  }
  // Make the rename itself durable; failure here does not undo a completed save.
  const fs::path folder = fs::path(path).parent_path();
  const int dir_fd = ::open(folder.empty() ? "." : folder.c_str(), O_RDONLY | O_DIRECTORY);
  if (dir_fd >= 0) {
    ::fsync(dir_fd);
    ::close(dir_fd);
  }
  return "";
}

std::string AppendToFile(const std::string& path, const std::string& bytes) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) return "cannot append to " + path + ": " + std::strerror(errno);
  struct stat before {};
  if (::fstat(fd, &before) != 0 || !S_ISREG(before.st_mode)) {
    ::close(fd);
    return "cannot append to " + path + ": not a regular file";
  }
  auto fail = [&](const std::string& what, int err) {
    // A partial record at the end would be dropped by the reader, but the next append would
    // land behind it and be dropped with it: cut it off.
    if (::ftruncate(fd, before.st_size) == 0) ::fsync(fd);
    ::close(fd);
    return "cannot append to " + path + ": " + what + ": " + std::strerror(err);
  };
  if (const int err = WriteAll(fd, bytes); err != 0) return fail("writing", err);
  if (::fdatasync(fd) != 0) return fail("flushing to disk", errno);
  if (::close(fd) != 0) return "cannot append to " + path + ": closing: " + std::strerror(errno);
  return "";
}

}  // namespace facet
