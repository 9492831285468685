// One Facet per project: an advisory lock, flock(2) on `PROJECT.lock` beside the project
// file, held while a session has the project open for writing. The kernel drops the lock
// when its holder's descriptor closes, so a crashed or killed session never leaves a stale
// lock (the file it leaves holds no lock and is taken over). The holder writes its pid, host
// and start time into the file so that the next one can say who has the project open.
// flock locks belong to an open file description: a second attempt from the same process
// fails too, and a forked child shares its parent's lock (the descriptor is close-on-exec).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

namespace facet {

// Who holds a project's lock, as its lock file says.
struct LockHolder {
  long pid = 0;                   // 0 when the file did not say (being written, or not Facet's)
  std::string host;               // gethostname() of the holder
  std::int64_t since_unix_s = 0;  // when it took the lock (seconds since 1970, UTC)
};

struct ProjectLockResult;
ProjectLockResult TryLockProject(const std::string& project_path);

// A held lock; releasing it (Release or the destructor) removes the lock file. Move-only.
class ProjectLock {
 public:
  ProjectLock() = default;
  ProjectLock(ProjectLock&& other) noexcept;
  ProjectLock& operator=(ProjectLock&& other) noexcept;
  ProjectLock(const ProjectLock&) = delete;
  ProjectLock& operator=(const ProjectLock&) = delete;
  ~ProjectLock() { Release(); }

  bool held() const { return fd_ >= 0; }
  // The lock file's path (empty when not held).
  const std::string& path() const { return path_; }
  // Whether this lock is the one of the project at `project_path` (however the path is
  // spelled: the lock file's identity is compared, not the text).
  bool Covers(const std::string& project_path) const;
  void Release();

 private:
  friend ProjectLockResult TryLockProject(const std::string& project_path);
  int fd_ = -1;
  std::string path_;
};

struct ProjectLockResult {
  ProjectLock lock;                  // held on success
  std::optional<LockHolder> holder;  // set when another session (or descriptor) holds it
  std::string error;                 // the lock file could not be made (a read-only folder): no lock, no holder
  bool ok() const { return lock.held(); }
};

// The lock file of the project at `project_path`: `PROJECT.lock`.
std::string LockFileFor(const std::string& project_path);

// Takes the project's lock without waiting. The lock file is never followed through a
// symlink and must be a regular file.
ProjectLockResult TryLockProject(const std::string& project_path);

// "street.facet is open in another Facet (pid 1234 on host, since 02:40)": the time is local,
// with the date when it is not today; the host only when it is not this machine's.
std::string DescribeLockHolder(const std::string& project_path, const LockHolder& holder);

}  // namespace facet
