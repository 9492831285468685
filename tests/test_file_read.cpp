// Reading files without trusting the path (core/util/file_read.h, issue 14): a FIFO, a device
// and a folder are refused at once (never blocking or streaming forever), a file over the
// limit is refused with the limit in the message, and the photo, project and CLI readers go
// through it; a photo over the pixel limit is refused before it is decoded.
#include <doctest/doctest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "core/image/image_io.h"
#include "core/io/project_io.h"
#include "core/util/file_read.h"
#include "tests/temp_files.h"

namespace facet {
namespace {

namespace fs = std::filesystem;


// A PNG header (signature and IHDR) claiming w x h pixels; stb reads the size from it alone.
std::string PngHeader(std::uint32_t w, std::uint32_t h) {
  std::string b = "\x89PNG\r\n\x1a\n";
  const auto be32 = [&](std::uint32_t v) {
    for (int s = 24; s >= 0; s -= 8) b.push_back(static_cast<char>((v >> s) & 0xFF));
  };
  be32(13);
  b += "IHDR";
  be32(w);
  be32(h);
  b += std::string("\x08\x02\x00\x00\x00", 5);  // 8 bit RGB, no interlace
  be32(0);                                       // CRC (not checked for the size)
  return b;
}

TEST_CASE("a regular file is read whole; its bytes are the file's") {
  const testing::TempDir dir("file_read");
  const std::string content = std::string("facet\0bytes", 11) + std::string(100000, 'x');
  testing::WriteText(dir / "a.bin", content);
  std::string text, error;
  REQUIRE_MESSAGE(ReadRegularFile(dir / "a.bin", kMaxTextFileBytes, &text, &error), error);
  CHECK(text == content);
  std::vector<std::uint8_t> bytes;
  REQUIRE(ReadRegularFile(dir / "a.bin", kMaxTextFileBytes, &bytes, &error));
  CHECK(bytes.size() == content.size());
  testing::WriteText(dir / "empty", "");
  REQUIRE(ReadRegularFile(dir / "empty", kMaxTextFileBytes, &text, &error));
  CHECK(text.empty());
}

TEST_CASE("a folder, a FIFO and a device are refused at once, saying what they are") {
  const testing::TempDir dir("file_read");
  REQUIRE(::mkfifo((dir / "pipe").c_str(), 0600) == 0);
  std::string text, error;
  CHECK_FALSE(ReadRegularFile(dir.path.string(), kMaxTextFileBytes, &text, &error));
  CHECK(error.find("a folder") != std::string::npos);
  // Without a writer, opening a FIFO for reading would block forever: it must return.
  CHECK_FALSE(ReadRegularFile(dir / "pipe", kMaxTextFileBytes, &text, &error));
  CHECK(error.find("a pipe (FIFO)") != std::string::npos);
  // /dev/zero would stream until memory runs out.
  CHECK_FALSE(ReadRegularFile("/dev/zero", kMaxTextFileBytes, &text, &error));
  CHECK(error.find("a character device") != std::string::npos);
  CHECK_FALSE(ReadRegularFile(dir / "missing", kMaxTextFileBytes, &text, &error));
  CHECK(error.find("cannot open") != std::string::npos);

  // The photo, project and size readers refuse them the same way.
  for (const std::string path : {dir / "pipe", std::string("/dev/zero")}) {
    CAPTURE(path);
    const ImageReadResult image = ReadImage(path);
    CHECK_FALSE(image.ok());
    int w = 0, h = 0;
    CHECK_FALSE(ReadImageSize(path, &w, &h, &error));
    CHECK_FALSE(LoadProject(path).ok());
  }
}

TEST_CASE("a file over the limit is refused with the limit in the message") {
  const testing::TempDir dir("file_read");
  testing::WriteText(dir / "big", std::string(3u << 20, 'x'));
  std::string text, error;
  CHECK_FALSE(ReadRegularFile(dir / "big", 2u << 20, &text, &error));
  CHECK(error.find("3 MB, larger than the limit of 2 MB") != std::string::npos);
  CHECK(text.empty());
  CHECK(ReadRegularFile(dir / "big", 3u << 20, &text, &error));
  CHECK(text.size() == (3u << 20));
  // A header read takes the first bytes of any size of file, and all of a short one.
  std::vector<std::uint8_t> head;
  REQUIRE(ReadRegularFileHead(dir / "big", 1000, &head, &error));
  CHECK(head.size() == 1000);
  testing::WriteText(dir / "short", "abc");
  REQUIRE(ReadRegularFileHead(dir / "short", 1000, &head, &error));
  CHECK(head.size() == 3);
  CHECK_FALSE(ReadRegularFileHead("/dev/zero", 1000, &head, &error));
}

TEST_CASE("a photo over the pixel limit is refused from its header, before decoding") {
  const testing::TempDir dir("file_read");
  testing::WriteText(dir / "huge.png", PngHeader(20000, 20000));
  const ImageReadResult huge = ReadImage(dir / "huge.png");
  INFO(huge.error);
  REQUIRE_FALSE(huge.ok());
  CHECK(huge.error.find("20000 x 20000 px (400 MP) is more than the limit of 150 MP") != std::string::npos);
  CHECK(huge.image.empty());
}

}  // namespace
}  // namespace facet
