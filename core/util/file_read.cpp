#include "core/util/file_read.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace facet {
namespace {

std::string KindOf(mode_t mode) {
  if (S_ISDIR(mode)) return "a folder";
  if (S_ISFIFO(mode)) return "a pipe (FIFO)";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  return "not a regular file";
}

std::string Megabytes(std::uint64_t bytes) { return std::to_string(bytes >> 20) + " MB"; }

// Reads at most max_bytes; a larger file is refused, or with `head_only` read up to max_bytes.
template <typename Buffer>
bool ReadInto(const std::string& path, std::uint64_t max_bytes, Buffer* bytes, std::string* error,
              bool head_only = false) {
  bytes->clear();
  // O_NONBLOCK: opening a FIFO without a writer returns at once instead of blocking, so the
  // check below can refuse it.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    *error = path + ": cannot open (" + std::strerror(errno) + ")";
    return false;
  }
  struct stat st;
  if (::fstat(fd, &st) != 0) {
    *error = path + ": cannot read (" + std::strerror(errno) + ")";
    ::close(fd);
    return false;
  }
  if (!S_ISREG(st.st_mode)) {
    *error = path + ": " + KindOf(st.st_mode) + ", not a file that can be read";
    ::close(fd);
    return false;
  }
  auto size = static_cast<std::uint64_t>(st.st_size);
  if (head_only) size = std::min(size, max_bytes);
  if (size > max_bytes) {
    *error = path + ": " + Megabytes(size) + ", larger than the limit of " + Megabytes(max_bytes) + " for this kind of file";
    ::close(fd);
    return false;
  }
  bytes->resize(static_cast<size_t>(size));
  size_t done = 0;
  // Reads to the end even if the file grew since fstat, but never past the limit.
  for (;;) {
    if (done == bytes->size()) {
      if (bytes->size() >= max_bytes || (head_only && done == size)) break;
      bytes->resize(static_cast<size_t>(std::min<std::uint64_t>(max_bytes, bytes->size() + (1u << 16))));
    }
    const ssize_t n = ::read(fd, reinterpret_cast<char*>(bytes->data()) + done, bytes->size() - done);
    if (n < 0) {
      if (errno == EINTR) continue;
      *error = path + ": read error (" + std::strerror(errno) + ")";
      ::close(fd);
      bytes->clear();
      return false;
    }
    if (n == 0) break;
    done += static_cast<size_t>(n);
  }
  ::close(fd);
  if (!head_only && done == bytes->size() && done >= max_bytes && size < max_bytes) {
    *error = path + ": grew past the limit of " + Megabytes(max_bytes) + " while being read";
    bytes->clear();
    return false;
  }
  bytes->resize(done);
  return true;
}

}  // namespace

bool ReadRegularFileHead(const std::string& path, std::uint64_t head_bytes, std::vector<std::uint8_t>* bytes,
                         std::string* error) {
  return ReadInto(path, head_bytes, bytes, error, /*head_only=*/true);
}

bool ReadRegularFile(const std::string& path, std::uint64_t max_bytes, std::string* bytes, std::string* error) {
  return ReadInto(path, max_bytes, bytes, error);
}

bool ReadRegularFile(const std::string& path, std::uint64_t max_bytes, std::vector<std::uint8_t>* bytes,
                     std::string* error) {
  return ReadInto(path, max_bytes, bytes, error);
}

}  // namespace facet
