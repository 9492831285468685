// The glTF 2.0 and GLB numbers the writer (core/io/export.cpp) and the reader
// (core/io/gltf_read.cpp) share, from the Khronos specification, so both spell them once.
#pragma once

#include <cstdint>

namespace facet::gltf {

constexpr std::uint32_t kGlbMagic = 0x46546C67;   // "glTF"
constexpr std::uint32_t kChunkJson = 0x4E4F534A;  // "JSON"
constexpr std::uint32_t kChunkBin = 0x004E4942;   // "BIN\0"
// accessor.componentType
constexpr int kUnsignedByte = 5121;
constexpr int kUnsignedShort = 5123;
constexpr int kUnsignedInt = 5125;
constexpr int kFloat = 5126;
constexpr int kTriangles = 4;  // mesh.primitive.mode

}  // namespace facet::gltf
