#include "core/util/project_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <sstream>
#include <utility>

namespace facet {
namespace {

// A lock file is a few dozen bytes; anything longer is not ours and is not read further.
constexpr size_t kMaxLockFileBytes = 4096;
constexpr size_t kMaxHostChars = 64;
// Taking the lock races with a holder that removes the file as it releases it (the lock is
// then on a removed file): open the new one and try again, a few times.
constexpr int kLockAttempts = 8;

std::string ThisHost() {
  char name[256] = {};
  if (::gethostname(name, sizeof(name) - 1) != 0) return std::string();
  return name;
}

// Printable ASCII only, bounded: the text comes from a file anyone could have written.
std::string Printable(const std::string& text, size_t max_chars) {
  std::string out;
  for (char c : text) {
    if (out.size() >= max_chars) break;
    if (c >= 0x20 && c < 0x7f) out += c;
  }
  return out;
}

bool SameFile(const struct stat& a, const struct stat& b) { return a.st_dev == b.st_dev && a.st_ino == b.st_ino; }

LockHolder ReadHolder(int fd) {
  std::string text(kMaxLockFileBytes, '\0');
  const ssize_t n = ::pread(fd, text.data(), text.size(), 0);
  text.resize(n > 0 ? static_cast<size_t>(n) : 0);
  LockHolder holder;
  std::istringstream lines(text);
  for (std::string line; std::getline(lines, line);) {
    const size_t space = line.find(' ');
    if (space == std::string::npos) continue;
    const std::string key = line.substr(0, space), value = line.substr(space + 1);
    char* end = nullptr;
    if (key == "pid") {
      const long pid = std::strtol(value.c_str(), &end, 10);
      if (end != value.c_str() && *end == '\0' && pid > 0) holder.pid = pid;
    } else if (key == "host") {
      holder.host = Printable(value, kMaxHostChars);
    } else if (key == "since") {
      const long long since = std::strtoll(value.c_str(), &end, 10);
      if (end != value.c_str() && *end == '\0' && since > 0) holder.since_unix_s = since;
    }
  }
  return holder;
}

std::string FormatSince(std::int64_t since_unix_s) {
  const std::time_t since = static_cast<std::time_t>(since_unix_s), now = std::time(nullptr);
  std::tm since_tm{}, now_tm{};
  if (::localtime_r(&since, &since_tm) == nullptr || ::localtime_r(&now, &now_tm) == nullptr) return std::string();
  const bool today = since_tm.tm_year == now_tm.tm_year && since_tm.tm_yday == now_tm.tm_yday;
  char text[64] = {};
  std::strftime(text, sizeof(text), today ? "%H:%M" : "%Y-%m-%d %H:%M", &since_tm);
  return text;
}

}  // namespace

ProjectLock::ProjectLock(ProjectLock&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)), path_(std::move(other.path_)) {
  other.path_.clear();
}

ProjectLock& ProjectLock::operator=(ProjectLock&& other) noexcept {
  if (this != &other) {
    Release();
    fd_ = std::exchange(other.fd_, -1);
    path_ = std::move(other.path_);
    other.path_.clear();
  }
  return *this;
}

bool ProjectLock::Covers(const std::string& project_path) const {
  if (fd_ < 0) return false;
  struct stat mine {
  }, named{};
  return ::fstat(fd_, &mine) == 0 && ::lstat(LockFileFor(project_path).c_str(), &named) == 0 && SameFile(mine, named);
}

void ProjectLock::Release() {
  if (fd_ < 0) return;
  // Removed while still locked, and only when the name is still this file: a session that
  // opens it meanwhile finds, once it has the lock, that the name has gone, and tries again.
  struct stat mine {
  }, named{};
  if (::fstat(fd_, &mine) == 0 && ::lstat(path_.c_str(), &named) == 0 && SameFile(mine, named)) ::unlink(path_.c_str());
  ::close(fd_);
  fd_ = -1;
  path_.clear();
}

std::string LockFileFor(const std::string& project_path) { return project_path + ".lock"; }

ProjectLockResult TryLockProject(const std::string& project_path) {
  ProjectLockResult result;
  const std::string path = LockFileFor(project_path);
  for (int attempt = 0; attempt < kLockAttempts; ++attempt) {
    const int fd = ::open(path.c_str(), O_RDWR | O_CREAT | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK, 0644);
    if (fd < 0) {
      result.error = errno == ELOOP ? "the lock file " + path + " is a symlink"
                                    : "cannot make the lock file " + path + ": " + std::strerror(errno);
      return result;
    }
    struct stat opened {};
    if (::fstat(fd, &opened) != 0 || !S_ISREG(opened.st_mode)) {
      ::close(fd);
      result.error = "the lock file " + path + " is not a regular file";
      return result;
    }
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
      const int flock_errno = errno;
      if (flock_errno == EWOULDBLOCK) result.holder = ReadHolder(fd);
      ::close(fd);
      if (flock_errno != EWOULDBLOCK) result.error = "cannot lock " + path + ": " + std::strerror(flock_errno);
      return result;
    }
    struct stat named {};
    if (::lstat(path.c_str(), &named) != 0 || !SameFile(opened, named)) {
      ::close(fd);  // the previous holder removed it as we opened it
      continue;
    }
    std::ostringstream text;
    text << "pid " << ::getpid() << "\nhost " << Printable(ThisHost(), kMaxHostChars) << "\nsince "
         << static_cast<long long>(std::time(nullptr)) << "\n";
    const std::string bytes = text.str();
    // The holder's details are for the message only: a failure to write them keeps the lock.
    if (::ftruncate(fd, 0) == 0) {
      [[maybe_unused]] const ssize_t written = ::pwrite(fd, bytes.data(), bytes.size(), 0);
    }
    result.lock.fd_ = fd;
    result.lock.path_ = path;
    return result;
  }
  result.error = "cannot lock " + path + ": it was replaced " + std::to_string(kLockAttempts) + " times in a row";
  return result;
}

std::string DescribeLockHolder(const std::string& project_path, const LockHolder& holder) {
  std::string text = std::filesystem::path(project_path).filename().string() + " is open in another Facet";
  std::string details;
  if (holder.pid > 0) details = "pid " + std::to_string(holder.pid);
  if (!holder.host.empty() && holder.host != Printable(ThisHost(), kMaxHostChars))
    details += (details.empty() ? "on " : " on ") + holder.host;
  if (holder.since_unix_s > 0) {
    const std::string since = FormatSince(holder.since_unix_s);
    if (!since.empty()) details += (details.empty() ? "since " : ", since ") + since;
  }
  return details.empty() ? text : text + " (" + details + ")";
}

}  // namespace facet
