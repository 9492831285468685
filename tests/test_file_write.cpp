// Writing files without trusting what is at the path (core/util/file_write.h, issue 25): a
// FIFO, a device, a socket and a folder are refused by name and left as they were; a symbolic
// link is followed for a user's save (the link kept) and refused for the recovery file (its
// target untouched); appending never follows a link nor blocks on a FIFO; a file moved aside
// keeps its bytes and never replaces another.
#include <doctest/doctest.h>

#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include "core/util/file_write.h"
#include "tests/temp_files.h"

namespace facet {
namespace {

namespace fs = std::filesystem;


bool Contains(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

// Nothing but the named entry in the folder: no temporary file left behind.
size_t EntriesIn(const testing::TempDir& dir) {
  size_t n = 0;
  for ([[maybe_unused]] const auto& entry : fs::directory_iterator(dir.path)) ++n;
  return n;
}

TEST_CASE("a FIFO, a socket and a folder are refused by name and left as they were") {
  const testing::TempDir dir("file_write");
  const std::string fifo = dir / "out.fifo";
  REQUIRE(::mkfifo(fifo.c_str(), 0644) == 0);
  for (const Symlinks symlinks : {Symlinks::kFollow, Symlinks::kRefuse}) {
    const std::string error = WriteFileAtomically(fifo, "bytes", symlinks);
    CHECK(error == "refusing to write " + fifo + ": it is a FIFO, not a regular file");
    CHECK(fs::is_fifo(fs::symlink_status(fifo)));
  }
  // A link to it, followed for a user's save: refused at the end of the chain, both named.
  const std::string link = dir / "link.png";
  fs::create_symlink(fifo, link);
  CHECK(WriteFileAtomically(link, "bytes") ==
        "refusing to write " + fifo + ": it is a FIFO, not a regular file (" + link + " links to it)");
  CHECK(fs::is_fifo(fs::symlink_status(fifo)));
  CHECK(fs::is_symlink(link));

  const std::string socket_path = dir / "out.sock";
  const int sock = ::socket(AF_UNIX, SOCK_STREAM, 0);
  REQUIRE(sock >= 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  REQUIRE(socket_path.size() < sizeof address.sun_path);
  std::strcpy(address.sun_path, socket_path.c_str());
  REQUIRE(::bind(sock, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0);
  CHECK(WriteFileAtomically(socket_path, "bytes") ==
        "refusing to write " + socket_path + ": it is a socket, not a regular file");
  CHECK(fs::is_socket(fs::symlink_status(socket_path)));
  ::close(sock);

  const std::string folder = dir / "sub";
  fs::create_directories(folder);
  CHECK(WriteFileAtomically(folder, "bytes") == "refusing to write " + folder + ": it is a folder, not a regular file");
  CHECK(fs::is_directory(folder));
  CHECK(EntriesIn(dir) == 4);  // the FIFO, the link, the socket and the folder: no temporary file
}

TEST_CASE("a device is refused, never replaced by a regular file") {
  // Reading what /dev/null is only looks (lstat); writing is tried on a node of our own, made
  // where the test may (as root, which is where the replacement did the harm: /dev/zero).
  CHECK(DescribeNonRegular("/dev/null") == "a character device");
  const testing::TempDir dir("file_write");
  const std::string node = dir / "null";
  if (::mknod(node.c_str(), S_IFCHR | 0666, makedev(1, 3)) != 0) {
    MESSAGE("mknod not permitted (not root): a device node is covered through DescribeNonRegular only");
    return;
  }
  for (const Symlinks symlinks : {Symlinks::kFollow, Symlinks::kRefuse}) {
    CHECK(WriteFileAtomically(node, "bytes", symlinks) ==
          "refusing to write " + node + ": it is a character device, not a regular file");
    struct stat info {};
    REQUIRE(::lstat(node.c_str(), &info) == 0);
    CHECK(S_ISCHR(info.st_mode));
  }
  CHECK(Contains(AppendToFile(node, "bytes"), "it is a character device"));
  CHECK(EntriesIn(dir) == 1);
}

TEST_CASE("a user's save writes through a link to a regular file; the recovery file refuses the link") {
  const testing::TempDir dir("file_write");
  const std::string other = dir / "other.facet";
  testing::WriteText(other, "the other project");
  const std::string link = dir / "mine.facet";
  fs::create_symlink("other.facet", link);  // relative, as users make them

  // Symlinks::kFollow: the file it points to gets the bytes, the link stays a link.
  CHECK(WriteFileAtomically(link, "saved through the link") == "");
  CHECK(fs::is_symlink(link));
  CHECK(testing::ReadText(other) == "saved through the link");

  // Symlinks::kRefuse: refused by name, its target untouched.
  testing::WriteText(other, "the other project");
  const std::string error = WriteFileAtomically(link, "recovery text", Symlinks::kRefuse);
  CHECK(error == "refusing to write " + link + ": it is a symbolic link (to other.facet), not a file Facet wrote");
  CHECK(fs::is_symlink(link));
  CHECK(testing::ReadText(other) == "the other project");
  // Also a dangling link: nothing is created where it points.
  const std::string dangling = dir / "dangling.recovery";
  fs::create_symlink(dir / "created-through-link", dangling);
  CHECK(Contains(WriteFileAtomically(dangling, "recovery text", Symlinks::kRefuse), "it is a symbolic link"));
  CHECK_FALSE(fs::exists(dir / "created-through-link"));
  CHECK(EntriesIn(dir) == 3);

  // A regular file is replaced whole, either way.
  const std::string plain = dir / "plain.recovery";
  CHECK(WriteFileAtomically(plain, "one", Symlinks::kRefuse) == "");
  CHECK(WriteFileAtomically(plain, "two", Symlinks::kRefuse) == "");
  CHECK(testing::ReadText(plain) == "two");
}

TEST_CASE("appending refuses a link and a FIFO at once, and appends to a regular file") {
  const testing::TempDir dir("file_write");
  const std::string other = dir / "other.facet";
  testing::WriteText(other, "the other project");
  const std::string link = dir / "journal.recovery";
  fs::create_symlink(other, link);
  CHECK(AppendToFile(link, "record") == "cannot append to " + link + ": it is a symbolic link");
  CHECK(testing::ReadText(other) == "the other project");

  // No reader on the FIFO: opening it for writing would wait for one forever.
  const std::string fifo = dir / "fifo.recovery";
  REQUIRE(::mkfifo(fifo.c_str(), 0644) == 0);
  CHECK(AppendToFile(fifo, "record") == "cannot append to " + fifo + ": it is a FIFO");

  const std::string plain = dir / "plain.recovery";
  testing::WriteText(plain, "base\n");
  CHECK(AppendToFile(plain, "record\n") == "");
  CHECK(testing::ReadText(plain) == "base\nrecord\n");
}

TEST_CASE("a file moved aside keeps its bytes and never replaces another") {
  const testing::TempDir dir("file_write");
  const std::string path = dir / "p.facet.recovery";
  testing::WriteText(path, "first");
  std::string first, second;
  REQUIRE(MoveFileAside(path, "broken", &first) == "");
  CHECK(first.rfind(path + ".broken-", 0) == 0);
  // "-YYYYMMDD-HHMMSS"
  CHECK(first.size() == path.size() + std::string(".broken-20260101-120000").size());
  CHECK_FALSE(fs::exists(path));
  CHECK(testing::ReadText(first) == "first");
  // Within the same second the name is taken: the second gets another, the first is kept.
  testing::WriteText(path, "second");
  REQUIRE(MoveFileAside(path, "broken", &second) == "");
  CHECK(second != first);
  CHECK(testing::ReadText(first) == "first");
  CHECK(testing::ReadText(second) == "second");
  CHECK(EntriesIn(dir) == 2);

  CHECK(Contains(MoveFileAside(path, "broken", &second), "No such file"));
  const std::string fifo = dir / "fifo";
  REQUIRE(::mkfifo(fifo.c_str(), 0644) == 0);
  CHECK(MoveFileAside(fifo, "broken", &second) == "cannot move " + fifo + " aside: it is a FIFO");
}

}  // namespace
}  // namespace facet
