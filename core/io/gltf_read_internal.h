// The glTF reader's checked access to its hostile input (core/io/gltf_read.cpp): JSON fields
// read through helpers that check type and range, the JSON bounded before it is parsed, and
// buffer and image URIs confined to the glTF's folder. Every failure throws GltfError, which
// the reader turns into its returned message. Internal to the reader and its tests.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

namespace facet::gltf_internal {

using Json = nlohmann::json;

// A whole number read from JSON is at most 2^53 (exact in a double); counts and offsets are
// then checked against what they index.
constexpr std::uint64_t kMaxWholeNumber = 1ull << 53;
constexpr int kMaxIndex = 2147483647;
// JSON nesting and size: a glTF nests a few levels (extras may add some); the value count
// bounds the parsed tree's memory whatever the text's length.
constexpr int kMaxJsonDepth = 64;
constexpr std::size_t kMaxJsonValues = 8'000'000;

// Thrown inside the reader only and turned into the returned message at its boundary.
struct GltfError {
  std::string message;
};
[[noreturn]] void Fail(const std::string& message);

// Text from the file (a URI, decoded) quoted in a message: printable ASCII only, shortened.
std::string Quoted(const std::string& text);

// The file's JSON, its nesting and size bounded before the tree grows.
Json ParseJson(const std::uint8_t* begin, const std::uint8_t* end);

// ---- JSON fields, each checked for its type and range; `what` names the field in failures ----
const Json& RequireObject(const Json& value, const std::string& what);
// The member `key` of `object` (which must be an object), or nullptr when absent.
const Json* Member(const Json& object, const char* key);
// The array `key` of `object`; an empty array when absent.
const Json& ArrayMember(const Json& object, const char* key, const std::string& what);
// A whole number in [0, max] (max <= 2^53); a float with an integral value is accepted.
std::uint64_t WholeNumber(const Json& value, std::uint64_t max, const std::string& what);
std::uint64_t WholeMember(const Json& object, const char* key, std::uint64_t fallback, std::uint64_t max,
                          const std::string& what);
int IndexValue(const Json& value, const std::string& what);
// The index `key` of `object`, or -1 when absent.
int IndexMember(const Json& object, const char* key, const std::string& what);
double FiniteNumber(const Json& value, const std::string& what);
double NumberMember(const Json& object, const char* key, double fallback, const std::string& what);
// Exactly `length` finite numbers.
std::vector<double> NumberArray(const Json& value, size_t length, const std::string& what);
std::string StringMember(const Json& object, const char* key, const std::string& fallback, const std::string& what);
// The element `index` of `array` (an object), or a failure naming what is missing.
const Json& Element(const Json& array, int index, const std::string& what);

// ---- URIs ----
// The bytes a `uri` names, for `what` ("buffer 0", "image 2"): a data: URI with base64
// content, or a file inside `folder` (nothing outside it is opened or described), at most
// `max_bytes`. Other schemes (http:, file:) are refused: a mesh is never fetched from elsewhere.
std::vector<std::uint8_t> UriBytes(const std::string& uri, const std::filesystem::path& folder,
                                   std::uint64_t max_bytes, const std::string& what);

}  // namespace facet::gltf_internal
