// One Facet per project (core/util/project_lock.h) and the project file's identity
// (core/util/file_identity.h): a second attempt, from this process or another one, fails and
// names the holder; the lock goes with its holder's death (a child killed with SIGKILL leaves
// a file but no lock); a released lock removes its file; a symlinked lock file is refused and
// its target untouched; a file rewritten with other bytes counts as changed, one rewritten
// with the same bytes (a new inode, a new mtime) as unchanged.
#include <doctest/doctest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "core/util/file_identity.h"
#include "core/util/file_write.h"
#include "core/util/project_lock.h"
#include "tests/temp_files.h"

namespace {

namespace fs = std::filesystem;


// A child that takes the lock, reports (one byte on a pipe) whether it has it, and then
// waits to be killed. Returns its pid; *locked tells whether it took the lock.
pid_t StartHolder(const std::string& project, bool* locked) {
  int fds[2];
  REQUIRE(::pipe(fds) == 0);
  const pid_t pid = ::fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    ::close(fds[0]);
    facet::ProjectLockResult result = facet::TryLockProject(project);
    const char answer = result.ok() ? 'y' : 'n';
    [[maybe_unused]] const ssize_t n = ::write(fds[1], &answer, 1);
    for (;;) ::pause();
  }
  ::close(fds[1]);
  char answer = 0;
  REQUIRE(::read(fds[0], &answer, 1) == 1);
  ::close(fds[0]);
  *locked = answer == 'y';
  return pid;
}

}  // namespace

TEST_CASE("a second lock on a project fails and names its holder, in this process and in another") {
  const facet::testing::TempDir dir("project_lock");
  const std::string project = dir / "street.facet";
  facet::WriteFileAtomically(project, "{}");

  facet::ProjectLockResult first = facet::TryLockProject(project);
  REQUIRE_MESSAGE(first.ok(), first.error);
  CHECK(first.lock.path() == project + ".lock");
  CHECK(fs::is_regular_file(project + ".lock"));
  CHECK(first.lock.Covers(project));
  CHECK(first.lock.Covers(dir / "./street.facet"));  // another spelling of the same file
  CHECK_FALSE(first.lock.Covers(dir / "other.facet"));

  const facet::ProjectLockResult second = facet::TryLockProject(project);
  CHECK_FALSE(second.ok());
  CHECK(second.error.empty());
  REQUIRE(second.holder.has_value());
  CHECK(second.holder->pid == ::getpid());
  CHECK(second.holder->since_unix_s > 0);
  const std::string message = facet::DescribeLockHolder(project, *second.holder);
  CHECK(message.rfind("street.facet is open in another Facet (pid " + std::to_string(::getpid()) + ", since ", 0) == 0);

  // Another process cannot take it either.
  bool child_locked = true;
  const pid_t child = StartHolder(project, &child_locked);
  CHECK_FALSE(child_locked);
  ::kill(child, SIGKILL);
  ::waitpid(child, nullptr, 0);

  // Released: the file is removed, and the lock can be taken again.
  first.lock.Release();
  CHECK_FALSE(first.lock.held());
  CHECK_FALSE(fs::exists(project + ".lock"));
  facet::ProjectLockResult again = facet::TryLockProject(project);
  CHECK_MESSAGE(again.ok(), again.error);
}

TEST_CASE("a lock held by another process names it, and goes when that process dies") {
  const facet::testing::TempDir dir("project_lock");
  const std::string project = dir / "street.facet";
  facet::WriteFileAtomically(project, "{}");

  bool child_locked = false;
  const pid_t child = StartHolder(project, &child_locked);
  REQUIRE(child_locked);
  const facet::ProjectLockResult refused = facet::TryLockProject(project);
  CHECK_FALSE(refused.ok());
  REQUIRE(refused.holder.has_value());
  CHECK(refused.holder->pid == child);
  CHECK(facet::DescribeLockHolder(project, *refused.holder).find("(pid " + std::to_string(child) + ", since ") !=
        std::string::npos);

  // A crash: the file stays, the lock does not.
  ::kill(child, SIGKILL);
  int status = 0;
  ::waitpid(child, &status, 0);
  CHECK(WIFSIGNALED(status));
  CHECK(fs::exists(project + ".lock"));
  facet::ProjectLockResult taken = facet::TryLockProject(project);
  REQUIRE_MESSAGE(taken.ok(), taken.error);
  CHECK(facet::testing::ReadText(project + ".lock").find("pid " + std::to_string(::getpid()) + "\n") != std::string::npos);
}

TEST_CASE("a lock file that is a symlink or not a regular file is refused, and nothing is written through it") {
  const facet::testing::TempDir dir("project_lock");
  const std::string project = dir / "street.facet";
  const std::string victim = dir / "victim.facet";
  facet::WriteFileAtomically(victim, "precious");
  fs::create_symlink(victim, project + ".lock");
  const facet::ProjectLockResult linked = facet::TryLockProject(project);
  CHECK_FALSE(linked.ok());
  CHECK_FALSE(linked.holder.has_value());
  CHECK(linked.error.find("symlink") != std::string::npos);
  CHECK(facet::testing::ReadText(victim) == "precious");

  const std::string folder_project = dir / "folder.facet";
  fs::create_directory(folder_project + ".lock");
  const facet::ProjectLockResult folder = facet::TryLockProject(folder_project);
  CHECK_FALSE(folder.ok());
  CHECK_FALSE(folder.error.empty());
}

TEST_CASE("a hostile lock file's text is shown bounded and printable") {
  const facet::testing::TempDir dir("project_lock");
  const std::string project = dir / "street.facet";
  facet::LockHolder holder;
  holder.pid = 77;
  holder.host = "elsewhere";
  holder.since_unix_s = 0;
  CHECK(facet::DescribeLockHolder(project, holder) == "street.facet is open in another Facet (pid 77 on elsewhere)");
  CHECK(facet::DescribeLockHolder(project, facet::LockHolder{}) == "street.facet is open in another Facet");

  // Held by a process that wrote garbage: the message still names the project.
  facet::ProjectLockResult held = facet::TryLockProject(project);
  REQUIRE(held.ok());
  {
    std::ofstream out(project + ".lock", std::ios::binary | std::ios::trunc);
    out << "pid -5\nhost " << std::string(500, 'h') << "\x01\nsince x\n";
  }
  const facet::ProjectLockResult refused = facet::TryLockProject(project);
  REQUIRE(refused.holder.has_value());
  CHECK(refused.holder->pid == 0);
  CHECK(refused.holder->host.size() <= 64);
  CHECK(refused.holder->since_unix_s == 0);
}

TEST_CASE("a file's identity: other bytes are a change, the same bytes rewritten are not") {
  const facet::testing::TempDir dir("project_lock");
  const std::string path = dir / "street.facet";
  REQUIRE(facet::WriteFileAtomically(path, "version one").empty());
  const facet::FileIdentity known = facet::IdentifyFile(path);
  CHECK(known.exists);
  CHECK(known.size_bytes == 11);
  CHECK(known.content_hash != 0);
  CHECK(facet::FileUnchangedSince(path, known));

  // Rewritten with the same bytes (a new inode: the write renames a temporary file).
  REQUIRE(facet::WriteFileAtomically(path, "version one").empty());
  CHECK(facet::IdentifyFile(path).inode != known.inode);
  CHECK(facet::FileUnchangedSince(path, known));

  // Other bytes of the same length.
  REQUIRE(facet::WriteFileAtomically(path, "version two").empty());
  CHECK_FALSE(facet::FileUnchangedSince(path, known));

  // Gone: a change; and a file that was not there is unchanged while it stays away.
  fs::remove(path);
  CHECK_FALSE(facet::FileUnchangedSince(path, known));
  const facet::FileIdentity absent = facet::IdentifyFile(path);
  CHECK_FALSE(absent.exists);
  CHECK(facet::FileUnchangedSince(path, absent));
}
