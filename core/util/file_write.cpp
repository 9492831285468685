#include "core/util/file_write.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <ctime>
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

std::string DescribeNonRegular(const std::string& path) {
  struct stat info {};
  if (::lstat(path.c_str(), &info) != 0) return "";
  if (S_ISREG(info.st_mode)) return "";
  if (S_ISLNK(info.st_mode)) return "a symbolic link";
  if (S_ISFIFO(info.st_mode)) return "a FIFO";
  if (S_ISCHR(info.st_mode)) return "a character device";
  if (S_ISBLK(info.st_mode)) return "a block device";
  if (S_ISSOCK(info.st_mode)) return "a socket";
  if (S_ISDIR(info.st_mode)) return "a folder";
  return "not a regular file";
}

std::string WriteFileAtomically(const std::string& requested_path, const std::string& bytes, Symlinks symlinks) {
  namespace fs = std::filesystem;
  std::string path = requested_path;
  if (symlinks == Symlinks::kRefuse) {
    std::error_code link_ec;
    if (fs::is_symlink(path, link_ec)) {
      const fs::path target = fs::read_symlink(path, link_ec);
      return "refusing to write " + path + ": it is a symbolic link" +
             (link_ec ? std::string() : " (to " + target.string() + ")") + ", not a file Facet wrote";
    }
  } else {
    // Renaming over a symlink would replace the link by a file; write where it points instead,
    // also when it points to nothing yet (weakly_canonical would keep a dangling link's own name).
    for (int hops = 0; hops < 40; ++hops) {
      std::error_code link_ec;
      if (!fs::is_symlink(path, link_ec)) break;
      const fs::path target = fs::read_symlink(path, link_ec);
      if (link_ec) break;
      path = (target.is_absolute() ? target : fs::path(path).parent_path() / target).lexically_normal().string();
    }
  }
  // The rename would replace a device or a FIFO by a regular file (as root, /dev/zero itself).
  if (const std::string what = DescribeNonRegular(path); !what.empty())
    return "refusing to write " + path + ": it is " + what + ", not a regular file" +
           (path == requested_path ? std::string() : " (" + requested_path + " links to it)");
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
  // O_NOFOLLOW: a link is refused (ELOOP), not appended through; O_NONBLOCK: opening a FIFO
  // with no reader fails at once instead of waiting for one.
  const int fd = ::open(path.c_str(), O_WRONLY | O_APPEND | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK);
  if (fd < 0) {
    const int err = errno;
    const std::string what = DescribeNonRegular(path);
    return "cannot append to " + path + ": " + (what.empty() ? std::strerror(err) : "it is " + what);
  }
  struct stat before {};
  if (::fstat(fd, &before) != 0 || !S_ISREG(before.st_mode)) {
    ::close(fd);
    const std::string what = DescribeNonRegular(path);
    return "cannot append to " + path + ": it is " + (what.empty() ? "not a regular file" : what);
  }
  const int flags = ::fcntl(fd, F_GETFL);
  if (flags >= 0) ::fcntl(fd, F_SETFL, flags & ~O_NONBLOCK);
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

std::string MoveFileAside(const std::string& path, const std::string& tag, std::string* moved_to) {
  struct stat info {};
  if (::lstat(path.c_str(), &info) != 0) return "cannot move " + path + " aside: " + std::strerror(errno);
  if (!S_ISREG(info.st_mode)) return "cannot move " + path + " aside: it is " + DescribeNonRegular(path);
  const std::time_t now = std::time(nullptr);
  std::tm local{};
  ::localtime_r(&now, &local);
  char stamp[32];
  std::strftime(stamp, sizeof stamp, "%Y%m%d-%H%M%S", &local);
  const std::string stem = path + "." + tag + "-" + stamp;
  for (int n = 1; n <= 1000; ++n) {
    const std::string candidate = n == 1 ? stem : stem + "-" + std::to_string(n);
    // RENAME_NOREPLACE: an existing file of that name (an earlier one kept aside) is never
    // replaced, without a window between a check and the rename.
    if (::renameat2(AT_FDCWD, path.c_str(), AT_FDCWD, candidate.c_str(), RENAME_NOREPLACE) == 0) {
      *moved_to = candidate;
      return "";
    }
    if (errno == EEXIST) continue;
    if (errno != EINVAL && errno != ENOSYS) return "cannot move " + path + " aside: " + std::strerror(errno);
    // A file system without RENAME_NOREPLACE: a hard link is as exclusive (EEXIST).
    if (::link(path.c_str(), candidate.c_str()) == 0) {
      ::unlink(path.c_str());
      *moved_to = candidate;
      return "";
    }
    if (errno == EEXIST) continue;
    return "cannot move " + path + " aside: " + std::strerror(errno);
  }
  return "cannot move " + path + " aside: 1000 files of the name " + stem + "-N exist already";
}

}  // namespace facet
