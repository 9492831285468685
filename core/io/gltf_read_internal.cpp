#include "core/io/gltf_read_internal.h"

#include <algorithm>
#include <cassert>
#include <cmath>

#include <nlohmann/json.hpp>

#include "core/util/file_read.h"
#include "core/util/utf8.h"

namespace facet::gltf_internal {

namespace fs = std::filesystem;

void Fail(const std::string& message) { throw GltfError{message}; }

// Text from the file (a URI, decoded) quoted in a message: printable ASCII only, shortened.
std::string Quoted(const std::string& text) { return QuotedAscii(text, 80); }


namespace {

// RFC 4648 base64 (the alphabet with + and /, '=' padding at the end only); false on any
// other character.
bool DecodeBase64(const std::string& text, size_t begin, std::vector<std::uint8_t>* out) {
  out->clear();
  out->reserve((text.size() - begin) / 4 * 3);
  std::uint32_t accumulator = 0;
  int bits = 0;
  size_t padding = 0;
  for (size_t i = begin; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '=') {
      ++padding;
      continue;
    }
    int value = -1;
    if (c >= 'A' && c <= 'Z') {
      value = c - 'A';
    } else if (c >= 'a' && c <= 'z') {
      value = c - 'a' + 26;
    } else if (c >= '0' && c <= '9') {
      value = c - '0' + 52;
    } else if (c == '+') {
      value = 62;
    } else if (c == '/') {
      value = 63;
    }
    if (value < 0 || padding > 0) return false;
    accumulator = (accumulator << 6) | static_cast<std::uint32_t>(value);
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out->push_back(static_cast<std::uint8_t>((accumulator >> bits) & 0xFF));
    }
  }
  return padding <= 2 && (text.size() - begin) % 4 == 0;
}

int HexValue(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return c - 'A' + 10;
}

// A relative URI reference as a file name: %XX escapes decoded (a space is written %20).
std::string DecodePercentEscapes(const std::string& uri) {
  std::string out;
  for (size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit(static_cast<unsigned char>(uri[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(uri[i + 2]))) {
      out += static_cast<char>(HexValue(uri[i + 1]) * 16 + HexValue(uri[i + 2]));
      i += 2;
    } else {
      out += uri[i];
    }
  }
  return out;
}

// True when `inner` is `outer` or lies under it (both canonical).
bool IsWithin(const fs::path& inner, const fs::path& outer) {
  auto o = outer.begin();
  auto i = inner.begin();
  for (; o != outer.end(); ++o, ++i) {
    if (o->empty()) continue;  // a trailing separator
    if (i == inner.end() || *i != *o) return false;
  }
  return true;
}

// The side file a relative `uri` names inside `folder`, or a failure that says why it is not
// read; nothing outside the folder is opened or described.
fs::path ConfinedSideFile(const std::string& uri, const fs::path& folder, const std::string& what) {
  const std::string relative = DecodePercentEscapes(uri);
  auto refuse = [&](const std::string& why) {
    Fail(what + ": its URI " + Quoted(relative) + " " + why + " (not read: only files in the glTF's folder are)");
  };
  if (folder.empty()) refuse("names a side file, and this glTF is read without its folder");
  if (relative.empty()) refuse("is empty");
  if (relative.find('\0') != std::string::npos) refuse("holds a NUL byte");
  if (relative[0] == '/' || relative[0] == '\\') refuse("is an absolute path");
  size_t start = 0;
  while (start <= relative.size()) {
    const size_t end = std::min(relative.find_first_of("/\\", start), relative.size());
    if (relative.compare(start, end - start, "..") == 0) refuse("leaves the glTF's folder ('..')");
    start = end + 1;
  }
  const fs::path file = folder / relative;
  // A symbolic link inside the folder must not lead out of it either.
  std::error_code ec;
  const fs::path real_folder = fs::weakly_canonical(folder, ec);
  if (ec) refuse("cannot be resolved (" + ec.message() + ")");
  const fs::path real_file = fs::weakly_canonical(file, ec);
  if (ec || !IsWithin(real_file, real_folder)) refuse("leaves the glTF's folder through a symbolic link");
  return file;
}


// Counts nesting and values without building anything, so the tree is only built from text
// already known to be within bounds. (nlohmann's callback parser would bound it in one pass,
// but it rescans the parent container after every object closes: 100,000 sibling nodes took
// seconds in Release and minutes under AddressSanitizer.)
class JsonBounds : public nlohmann::json_sax<Json> {
 public:
  bool null() override { return Value(); }
  bool boolean(bool) override { return Value(); }
  bool number_integer(number_integer_t) override { return Value(); }
  bool number_unsigned(number_unsigned_t) override { return Value(); }
  bool number_float(number_float_t, const string_t&) override { return Value(); }
  bool string(string_t&) override { return Value(); }
  bool binary(binary_t&) override { return Value(); }
  bool start_object(std::size_t) override { return Open(); }
  bool key(string_t&) override { return true; }
  bool end_object() override { return Close(); }
  bool start_array(std::size_t) override { return Open(); }
  bool end_array() override { return Close(); }
  // The parser's own message is raised by the full parse that follows, with its position.
  bool parse_error(std::size_t, const std::string&, const nlohmann::detail::exception&) override { return false; }

 private:
  bool Value() {
    if (++values_ > kMaxJsonValues)
      Fail("its JSON holds more than " + std::to_string(kMaxJsonValues) + " values, the most read");
    return true;
  }
  bool Open() {
    if (++depth_ > kMaxJsonDepth) Fail("its JSON nests deeper than " + std::to_string(kMaxJsonDepth) + " levels");
    return Value();
  }
  bool Close() {
    --depth_;
    return true;
  }
  int depth_ = 0;
  std::size_t values_ = 0;
};

}  // namespace

Json ParseJson(const std::uint8_t* begin, const std::uint8_t* end) {
  JsonBounds bounds;
  Json::sax_parse(begin, end, &bounds);
  return Json::parse(begin, end);
}


const Json& RequireObject(const Json& value, const std::string& what) {
  if (!value.is_object()) Fail(what + " is not a JSON object");
  return value;
}

// The member `key` of `object` (which must be an object), or nullptr when absent.
const Json* Member(const Json& object, const char* key) {
  const auto it = object.find(key);
  return it == object.end() ? nullptr : &*it;
}

// The array `key` of `object`; an empty array when absent.
const Json& ArrayMember(const Json& object, const char* key, const std::string& what) {
  static const Json kEmpty = Json::array();
  const Json* value = Member(object, key);
  if (value == nullptr) return kEmpty;
  if (!value->is_array()) Fail(what + "." + key + " is not an array");
  return *value;
}

// A whole number in [0, max] (max <= 2^53); a float with an integral value is accepted.
std::uint64_t WholeNumber(const Json& value, std::uint64_t max, const std::string& what) {
  assert(max <= kMaxWholeNumber);
  if (value.is_number_unsigned()) {
    const auto u = value.get<std::uint64_t>();
    if (u <= max) return u;
  } else if (value.is_number_float()) {
    const double d = value.get<double>();
    if (d >= 0.0 && d <= static_cast<double>(max) && d == std::floor(d)) return static_cast<std::uint64_t>(d);
  } else if (!value.is_number_integer()) {
    Fail(what + " is not a number");
  }
  Fail(what + " is " + value.dump() + ", not a whole number in [0, " + std::to_string(max) + "]");
}

std::uint64_t WholeMember(const Json& object, const char* key, std::uint64_t fallback, std::uint64_t max,
                          const std::string& what) {
  const Json* value = Member(object, key);
  return value == nullptr ? fallback : WholeNumber(*value, max, what + "." + key);
}

int IndexValue(const Json& value, const std::string& what) {
  return static_cast<int>(WholeNumber(value, kMaxIndex, what));
}

// The index `key` of `object`, or -1 when absent.
int IndexMember(const Json& object, const char* key, const std::string& what) {
  const Json* value = Member(object, key);
  return value == nullptr ? -1 : IndexValue(*value, what + "." + key);
}

double FiniteNumber(const Json& value, const std::string& what) {
  if (!value.is_number()) Fail(what + " is not a number");
  const double d = value.get<double>();
  if (!std::isfinite(d)) Fail(what + " is not finite");
  return d;
}

double NumberMember(const Json& object, const char* key, double fallback, const std::string& what) {
  const Json* value = Member(object, key);
  return value == nullptr ? fallback : FiniteNumber(*value, what + "." + key);
}

// Exactly `length` finite numbers.
std::vector<double> NumberArray(const Json& value, size_t length, const std::string& what) {
  if (!value.is_array() || value.size() != length)
    Fail(what + " is not an array of " + std::to_string(length) + " numbers");
  std::vector<double> out;
  for (size_t i = 0; i < length; ++i) out.push_back(FiniteNumber(value[i], what + "[" + std::to_string(i) + "]"));
  return out;
}

std::string StringMember(const Json& object, const char* key, const std::string& fallback, const std::string& what) {
  const Json* value = Member(object, key);
  if (value == nullptr) return fallback;
  if (!value->is_string()) Fail(what + "." + key + " is not a string");
  return value->get<std::string>();
}

// The element `index` of `array` (an object), or a failure naming what is missing.
const Json& Element(const Json& array, int index, const std::string& what) {
  if (index < 0 || static_cast<size_t>(index) >= array.size()) Fail(what + " " + std::to_string(index) + " missing");
  return RequireObject(array[static_cast<size_t>(index)], what + " " + std::to_string(index));
}

// The bytes a `uri` names, for `what` ("buffer 0", "image 2"): a data: URI with base64
// content, or a file inside `folder` (ConfinedSideFile), at most `max_bytes`. Other schemes
// (http:, file:) are refused: a mesh is never fetched from elsewhere.
std::vector<std::uint8_t> UriBytes(const std::string& uri, const fs::path& folder, std::uint64_t max_bytes,
                                   const std::string& what) {
  std::vector<std::uint8_t> bytes;
  if (uri.rfind("data:", 0) == 0) {
    const size_t comma = uri.find(',');
    if (comma == std::string::npos || uri.rfind(";base64", comma) == std::string::npos ||
        uri.rfind(";base64", comma) + 7 != comma)
      Fail(what + ": its data: URI is not base64");
    if ((uri.size() - comma - 1) / 4 * 3 > max_bytes)
      Fail(what + ": its data: URI holds more than " + std::to_string(max_bytes) + " bytes");
    if (!DecodeBase64(uri, comma + 1, &bytes)) Fail(what + ": its data: URI holds a character that is not base64");
    return bytes;
  }
  const size_t colon = uri.find(':');
  if (colon != std::string::npos && uri.find('/') > colon)
    Fail(what + ": its URI " + Quoted(uri.substr(0, colon + 1)) + "... is not a file beside the glTF (not read)");
  const fs::path file = ConfinedSideFile(uri, folder, what);
  std::string error;
  if (!ReadRegularFile(file.string(), max_bytes, &bytes, &error)) Fail(what + ": " + error);
  return bytes;
}

}  // namespace facet::gltf_internal
