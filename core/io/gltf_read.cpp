// A deliberately small glTF reader (binary .glb, or JSON .gltf with .bin files or data: URIs):
// what ExportGlb writes and what a mesh from another tool needs for reference geometry. The
// file is hostile until checked: every JSON field is read through a helper that checks its
// type and range, every count, offset and stride is checked against its buffer with
// overflow-safe arithmetic before anything is allocated, the node hierarchy is walked without
// recursion, and side files are confined to the glTF's folder.
#include "core/io/gltf_read.h"

#include <cassert>
#include <cctype>
#include <cfloat>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <new>
#include <stdexcept>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <nlohmann/json.hpp>

#include "core/io/gltf_constants.h"
#include "core/io/gltf_read_internal.h"

#include "core/util/file_read.h"
#include "core/util/utf8.h"

namespace facet {
namespace {

using namespace gltf;
using namespace gltf_internal;

using Json = nlohmann::json;
namespace fs = std::filesystem;

constexpr std::uint64_t kMaxGlbBytes = 1ull << 30;
// All buffers of one file together (a file may name the same side file many times).
constexpr std::uint64_t kMaxBufferBytes = 1ull << 30;
constexpr int kMaxCameraSidePx = 1 << 16;

std::uint32_t U32(const std::vector<std::uint8_t>& b, size_t offset) {
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(b[offset + i]) << (8 * i);
  return v;
}

// ---- Accessors ----

int ComponentSize(int component_type, const std::string& where) {
  switch (component_type) {
    case kUnsignedByte: return 1;
    case kUnsignedShort: return 2;
    case kUnsignedInt:
    case kFloat: return 4;
    default: Fail(where + ": component type " + std::to_string(component_type) + " is not supported");
  }
}

int ComponentCount(const std::string& type, const std::string& where) {
  if (type == "SCALAR") return 1;
  if (type == "VEC2") return 2;
  if (type == "VEC3") return 3;
  if (type == "VEC4") return 4;
  Fail(where + ": accessor type " + Quoted(type) + " is not supported");
}

// An accessor's elements located in its buffer, every one checked to lie inside it.
struct AccessorSpan {
  const std::uint8_t* data = nullptr;  // the first element
  size_t count = 0;
  size_t stride = 0;  // bytes from one element to the next
  int components = 0;
  int component_type = 0;
  int component_size = 0;
};

class GlbReader {
 public:
  // buffers[i] holds exactly the byteLength bytes of the file's buffer i (the BIN chunk, a
  // side file or a data: URI). `folder` is where the glTF file is (empty: no side files).
  GlbReader(Json gltf, std::vector<std::vector<std::uint8_t>> buffers, fs::path folder)
      : gltf_(std::move(gltf)), buffers_(std::move(buffers)), folder_(std::move(folder)) {}

  // The bytes of a bufferView, checked against its buffer; *stride is 0 when it has none.
  const std::uint8_t* View(int index, size_t* length, size_t* stride) const {
    const std::string where = "bufferView " + std::to_string(index);
    const Json& view = Element(ArrayMember(gltf_, "bufferViews", "the glTF"), index, "bufferView");
    const Json* buffer_json = Member(view, "buffer");
    if (buffer_json == nullptr) Fail(where + " has no buffer");
    const int buffer = IndexValue(*buffer_json, where + ".buffer");
    if (static_cast<size_t>(buffer) >= buffers_.size())
      Fail(where + " uses buffer " + std::to_string(buffer) + ", which is missing");
    const std::vector<std::uint8_t>& bytes = buffers_[static_cast<size_t>(buffer)];
    const std::uint64_t offset = WholeMember(view, "byteOffset", 0, kMaxWholeNumber, where);
    const Json* length_json = Member(view, "byteLength");
    if (length_json == nullptr) Fail(where + " has no byteLength");
    const std::uint64_t view_length = WholeNumber(*length_json, kMaxWholeNumber, where + ".byteLength");
    // The specification's range: 4 to 252 bytes; 0 means tightly packed.
    constexpr std::uint64_t kMinStride = 4, kMaxStride = 252;
    const std::uint64_t view_stride = WholeMember(view, "byteStride", 0, kMaxWholeNumber, where);
    if (view_stride != 0 && (view_stride < kMinStride || view_stride > kMaxStride))
      Fail(where + ": byteStride " + std::to_string(view_stride) + " is outside [4, 252]");
    if (offset > bytes.size() || view_length > bytes.size() - offset) Fail(where + " runs past its buffer");
    *length = static_cast<size_t>(view_length);
    *stride = static_cast<size_t>(view_stride);
    return bytes.data() + offset;
  }

  // Accessor `index` located and checked: `components` per element (which its type must
  // match); `integers_only` refuses float components (indices).
  AccessorSpan Locate(int index, int components, bool integers_only, const std::string& role) const {
    const std::string where = "accessor " + std::to_string(index) + " (" + role + ")";
    const Json& a = Element(ArrayMember(gltf_, "accessors", "the glTF"), index, "accessor");
    if (Member(a, "sparse") != nullptr) Fail(where + " is sparse (not supported)");
    const Json* view_json = Member(a, "bufferView");
    if (view_json == nullptr) Fail(where + " has no bufferView");
    const Json* type_json = Member(a, "componentType");
    if (type_json == nullptr) Fail(where + " has no componentType");
    AccessorSpan span;
    span.component_type = IndexValue(*type_json, where + ".componentType");
    span.component_size = ComponentSize(span.component_type, where);
    if (integers_only && span.component_type == kFloat) Fail(where + " holds floats; indices must be integers");
    const std::string type = StringMember(a, "type", "", where);
    if (ComponentCount(type, where) != components)
      Fail(where + " has type " + Quoted(type) + ", " + std::to_string(components) + " components expected");
    span.components = components;
    const Json* count_json = Member(a, "count");
    if (count_json == nullptr) Fail(where + " has no count");
    const std::uint64_t count = WholeNumber(*count_json, kMaxWholeNumber, where + ".count");
    const std::uint64_t offset = WholeMember(a, "byteOffset", 0, kMaxWholeNumber, where);
    size_t length = 0, stride = 0;
    const std::uint8_t* data = View(IndexValue(*view_json, where + ".bufferView"), &length, &stride);
    const std::uint64_t element = static_cast<std::uint64_t>(span.component_size) * components;
    if (stride == 0) stride = element;
    if (stride < element)
      Fail(where + ": its bufferView's byteStride " + std::to_string(stride) + " is less than an element's " +
           std::to_string(element) + " bytes");
    // The last element ends inside the view: (count - 1) * stride + element <= length - offset,
    // arranged so that nothing overflows.
    if (offset > length) Fail(where + ": byteOffset " + std::to_string(offset) + " is past its bufferView");
    const std::uint64_t available = length - offset;
    if (count > 0 && (element > available || count - 1 > (available - element) / stride))
      Fail(where + ": count " + std::to_string(count) + " runs past its bufferView (" + std::to_string(length) +
           " bytes)");
    span.data = data + offset;
    span.count = static_cast<size_t>(count);
    span.stride = stride;
    return span;
  }

  const Json& gltf() const { return gltf_; }
  const fs::path& folder() const { return folder_; }

 private:
  Json gltf_;
  std::vector<std::vector<std::uint8_t>> buffers_;
  fs::path folder_;
};

// The elements of a located accessor as doubles, `components` per element.
std::vector<double> ReadSpan(const AccessorSpan& span) {
  std::vector<double> out(span.count * static_cast<size_t>(span.components));
  for (size_t i = 0; i < span.count; ++i) {
    const std::uint8_t* e = span.data + i * span.stride;
    for (int c = 0; c < span.components; ++c) {
      const std::uint8_t* p = e + c * span.component_size;
      double v = 0.0;
      if (span.component_type == kFloat) {
        float f;
        std::memcpy(&f, p, 4);
        v = f;
      } else if (span.component_type == kUnsignedInt) {
        std::uint32_t u;
        std::memcpy(&u, p, 4);
        v = u;
      } else if (span.component_type == kUnsignedShort) {
        std::uint16_t u;
        std::memcpy(&u, p, 2);
        v = u;
      } else {
        v = *p;
      }
      out[i * static_cast<size_t>(span.components) + static_cast<size_t>(c)] = v;
    }
  }
  return out;
}

// ---- URIs ----

// Every buffer of the file, each exactly its byteLength long. A buffer without a URI is the
// GLB's BIN chunk (`glb_bin`, for buffer 0 of a .glb only).
std::vector<std::vector<std::uint8_t>> LoadBuffers(const Json& gltf, const fs::path& folder, bool is_glb,
                                                   std::vector<std::uint8_t> glb_bin) {
  std::vector<std::vector<std::uint8_t>> buffers;
  std::uint64_t total = 0;
  const Json& list = ArrayMember(gltf, "buffers", "the glTF");
  for (size_t i = 0; i < list.size(); ++i) {
    const std::string what = "buffer " + std::to_string(i);
    const Json& buffer = RequireObject(list[i], what);
    const Json* length_json = Member(buffer, "byteLength");
    if (length_json == nullptr) Fail(what + " has no byteLength");
    const std::uint64_t declared = WholeNumber(*length_json, kMaxWholeNumber, what + ".byteLength");
    if (declared > kMaxBufferBytes - total)
      Fail(what + ": the buffers' byteLengths add up to more than " + std::to_string(kMaxBufferBytes) +
           " bytes, the most read");
    total += declared;
    if (Member(buffer, "uri") != nullptr) {
      // A side file may be padded a little past its byteLength; one far longer is not read (a
      // small buffer naming a huge file would cost its whole size for nothing).
      constexpr std::uint64_t kPaddingBytes = 4096;
      const std::string uri = StringMember(buffer, "uri", "", what);
      buffers.push_back(UriBytes(uri, folder, std::min(declared + kPaddingBytes, kMaxGlbBytes), what));
    } else if (is_glb && i == 0) {
      buffers.push_back(std::move(glb_bin));
    } else {
      Fail(what + " has no uri" + (is_glb ? "" : " (only a .glb's first buffer may be its BIN chunk)"));
    }
    if (buffers.back().size() < declared)
      Fail(what + " holds " + std::to_string(buffers.back().size()) + " bytes, its byteLength says " +
           std::to_string(declared));
    buffers.back().resize(static_cast<size_t>(declared));
  }
  return buffers;
}

// ---- Nodes, primitives, cameras ----

Eigen::Matrix4d NodeMatrix(const Json& node, const std::string& where) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  if (const Json* matrix = Member(node, "matrix")) {
    const std::vector<double> v = NumberArray(*matrix, 16, where + ".matrix");
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) m(r, c) = v[static_cast<size_t>(4 * c + r)];  // column-major
    return m;
  }
  Eigen::Vector3d t = Eigen::Vector3d::Zero(), s = Eigen::Vector3d::Ones();
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  if (const Json* translation = Member(node, "translation")) {
    const std::vector<double> v = NumberArray(*translation, 3, where + ".translation");
    t = Eigen::Vector3d(v[0], v[1], v[2]);
  }
  if (const Json* scale = Member(node, "scale")) {
    const std::vector<double> v = NumberArray(*scale, 3, where + ".scale");
    s = Eigen::Vector3d(v[0], v[1], v[2]);
  }
  if (const Json* rotation = Member(node, "rotation")) {
    const std::vector<double> r = NumberArray(*rotation, 4, where + ".rotation");  // x, y, z, w
    q = Eigen::Quaterniond(r[3], r[0], r[1], r[2]);
    if (!(std::abs(q.norm() - 1.0) <= 1e-3)) Fail(where + ".rotation is not a unit quaternion");
    q.normalize();
  }
  m.topLeftCorner<3, 3>() = q.toRotationMatrix() * s.asDiagonal();
  m.topRightCorner<3, 1>() = t;
  if (!m.allFinite()) Fail(where + "'s transform is not finite");
  return m;
}

struct Materials {
  std::vector<int> image;  // base-colour image per material, -1 when none
  std::vector<Eigen::Vector4f> color;
};

// Running totals over the whole scene, against the options' caps.
struct Budget {
  size_t primitives = 0;
  size_t indices = 0;
};

bool FitsFloat(double v) { return std::abs(v) <= static_cast<double>(FLT_MAX); }

void ReadPrimitive(const GlbReader& reader, const Json& primitive_json, const std::string& where,
                   const Eigen::Matrix4d& world_from_node, const Materials& materials, const GltfReadOptions& options,
                   Budget* budget, GltfScene* scene) {
  if (++budget->primitives > options.max_primitives)
    Fail("more than " + std::to_string(options.max_primitives) +
         " primitives (a mesh counted once per node that uses it), the most read");
  const Json& primitive = RequireObject(primitive_json, where);
  if (WholeMember(primitive, "mode", kTriangles, kMaxIndex, where) != kTriangles)
    Fail(where + " is not made of triangles (mode != 4)");
  const Json* attributes_json = Member(primitive, "attributes");
  if (attributes_json == nullptr) Fail(where + " has no attributes");
  const Json& attributes = RequireObject(*attributes_json, where + ".attributes");
  const int position_index = IndexMember(attributes, "POSITION", where + ".attributes");
  if (position_index < 0) Fail(where + " has no POSITION");
  const AccessorSpan p_span = reader.Locate(position_index, 3, false, "POSITION");
  const size_t n = p_span.count;
  if (n > options.max_vertices - scene->positions.size())
    Fail("more than " + std::to_string(options.max_vertices) +
         " vertices (a mesh counted once per node that uses it), the most read");
  const int normal_index = IndexMember(attributes, "NORMAL", where + ".attributes");
  const int uv_index = IndexMember(attributes, "TEXCOORD_0", where + ".attributes");
  AccessorSpan n_span, uv_span;
  if (normal_index >= 0) n_span = reader.Locate(normal_index, 3, false, "NORMAL");
  if (uv_index >= 0) uv_span = reader.Locate(uv_index, 2, false, "TEXCOORD_0");
  if ((normal_index >= 0 && n_span.count != n) || (uv_index >= 0 && uv_span.count != n))
    Fail(where + "'s attributes differ in count");
  const int material = IndexMember(primitive, "material", where);
  if (material >= static_cast<int>(materials.image.size())) Fail(where + "'s material is missing");
  const int indices_index = IndexMember(primitive, "indices", where);
  AccessorSpan i_span;
  size_t index_count = n;
  if (indices_index >= 0) {
    i_span = reader.Locate(indices_index, 1, true, "indices");
    index_count = i_span.count;
  }
  if (index_count % 3 != 0) Fail(where + "'s index count " + std::to_string(index_count) + " is not a multiple of 3");
  if (index_count > 3 * options.max_triangles - budget->indices)
    Fail("more than " + std::to_string(options.max_triangles) +
         " triangles (a mesh counted once per node that uses it), the most read");

  // Every count is within its buffer and the caps: now the data is read.
  const std::vector<double> p = ReadSpan(p_span);
  const std::vector<double> nrm = normal_index >= 0 ? ReadSpan(n_span) : std::vector<double>();
  const std::vector<double> uv = uv_index >= 0 ? ReadSpan(uv_span) : std::vector<double>();
  const Eigen::Matrix3d linear = world_from_node.topLeftCorner<3, 3>();
  const Eigen::Matrix3d normal_matrix = linear.inverse().transpose();
  const auto base = static_cast<std::uint32_t>(scene->positions.size());
  for (size_t v = 0; v < n; ++v) {
    const Eigen::Vector3d x_node(p[3 * v], p[3 * v + 1], p[3 * v + 2]);
    if (!x_node.allFinite()) Fail(where + ": POSITION " + std::to_string(v) + " is not finite (NaN or infinite)");
    const Eigen::Vector3d x = (world_from_node * x_node.homogeneous()).head<3>();
    if (!x.allFinite() || !FitsFloat(x.x()) || !FitsFloat(x.y()) || !FitsFloat(x.z()))
      Fail(where + ": POSITION " + std::to_string(v) + " is not finite once its node transforms are applied");
    scene->positions.push_back(x.cast<float>());
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    if (!nrm.empty()) {
      const Eigen::Vector3d n_node(nrm[3 * v], nrm[3 * v + 1], nrm[3 * v + 2]);
      if (!n_node.allFinite()) Fail(where + ": NORMAL " + std::to_string(v) + " is not finite (NaN or infinite)");
      normal = (normal_matrix * n_node).normalized();
      // A degenerate node transform (a zero scale) or a zero normal: the file then has none.
      if (!normal.allFinite()) normal.setZero();
    }
    scene->normals.push_back(normal.cast<float>());
    Eigen::Vector2f texcoord(0.0f, 0.0f);
    if (!uv.empty()) {
      if (!std::isfinite(uv[2 * v]) || !std::isfinite(uv[2 * v + 1]))
        Fail(where + ": TEXCOORD_0 " + std::to_string(v) + " is not finite (NaN or infinite)");
      texcoord = Eigen::Vector2f(static_cast<float>(uv[2 * v]), static_cast<float>(uv[2 * v + 1]));
    }
    scene->uvs.push_back(texcoord);
  }
  GltfBatch batch;
  if (material >= 0) {
    batch.image = uv.empty() ? -1 : materials.image[static_cast<size_t>(material)];
    batch.base_color = materials.color[static_cast<size_t>(material)];
  }
  batch.indices.reserve(index_count);
  if (indices_index >= 0) {
    for (double i : ReadSpan(i_span)) {
      if (i >= static_cast<double>(n))
        Fail(where + "'s index " + std::to_string(static_cast<std::uint64_t>(i)) + " is out of range");
      batch.indices.push_back(base + static_cast<std::uint32_t>(i));
    }
  } else {
    for (size_t v = 0; v < n; ++v) batch.indices.push_back(base + static_cast<std::uint32_t>(v));
  }
  budget->indices += index_count;
  scene->batches.push_back(std::move(batch));
}

GltfCamera ReadCamera(const Json& camera_json, const std::string& where, const Json& node,
                      const Eigen::Matrix4d& world_from_node, const GltfReadOptions& options) {
  const Json& camera = RequireObject(camera_json, where);
  GltfCamera out;
  out.name = StringMember(node, "name", StringMember(camera, "name", "", where), "a node");
  if (StringMember(camera, "type", "", where) != "perspective") Fail(where + " is not perspective");
  const Json* perspective = Member(camera, "perspective");
  if (perspective == nullptr) Fail(where + " has no perspective");
  const Json& p = RequireObject(*perspective, where + ".perspective");
  const Json* yfov = Member(p, "yfov");
  if (yfov == nullptr) Fail(where + " has no yfov");
  out.yfov_rad = FiniteNumber(*yfov, where + ".perspective.yfov");
  out.aspect_ratio = NumberMember(p, "aspectRatio", 0.0, where + ".perspective");
  out.znear = NumberMember(p, "znear", 0.0, where + ".perspective");
  if (!(out.yfov_rad > 0.0 && out.yfov_rad < M_PI)) Fail(where + " has a yfov outside (0, pi)");
  if (out.aspect_ratio < 0.0) Fail(where + " has a negative aspectRatio");
  assert(options.default_height_px > 0);
  int w = 0, h = options.default_height_px;
  static const Json kNoExtras = Json::object();
  const Json* extras_json = Member(camera, "extras");
  const Json& extras = extras_json != nullptr && extras_json->is_object() ? *extras_json : kNoExtras;
  if (const Json* size = Member(extras, "image_size_px")) {
    const std::string what = where + ".extras.image_size_px";
    if (!size->is_array() || size->size() != 2) Fail(what + " is not an array of 2 numbers");
    w = static_cast<int>(WholeNumber((*size)[0], kMaxCameraSidePx, what + "[0]"));
    h = static_cast<int>(WholeNumber((*size)[1], kMaxCameraSidePx, what + "[1]"));
  } else if (out.aspect_ratio > 0.0) {
    const double width = out.aspect_ratio * h;
    if (!(width >= 1.0 && width <= kMaxCameraSidePx))
      Fail(where + "'s aspectRatio makes an image " + std::to_string(width) + " px wide, outside [1, " +
           std::to_string(kMaxCameraSidePx) + "]");
    w = static_cast<int>(std::lround(width));
  } else {
    w = h;
  }
  if (w <= 0 || h <= 0) Fail(where + " has no image size");
  Camera& cam = out.camera;
  cam.width_px = w;
  cam.height_px = h;
  cam.focal_px = h / (2.0 * std::tan(out.yfov_rad / 2.0));
  // OpenCV pixel centres at integers: the image spans [-0.5, w - 0.5], its centre is (w - 1) / 2.
  cam.principal_point_px = Eigen::Vector2d((w - 1) / 2.0, (h - 1) / 2.0);
  if (const Json* pp = Member(extras, "principal_point_px")) {
    const std::vector<double> v = NumberArray(*pp, 2, where + ".extras.principal_point_px");
    out.has_principal_point = true;
    cam.principal_point_px = {v[0], v[1]};
  }
  // A camera node may carry no scale: its rotation is the linear part, orthonormalised.
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(world_from_node.topLeftCorner<3, 3>(),
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d world_from_gltf_cam = svd.matrixU() * svd.matrixV().transpose();
  // glTF's camera looks down -Z with +Y up; OpenCV's down +Z with Y down.
  const Eigen::Matrix3d cam_from_world = Eigen::Vector3d(1, -1, -1).asDiagonal() * world_from_gltf_cam.transpose();
  cam.SetPose(cam_from_world, world_from_node.topRightCorner<3, 1>());
  return out;
}

Materials ReadMaterials(const Json& g) {
  Materials materials;
  const Json& list = ArrayMember(g, "materials", "the glTF");
  for (size_t i = 0; i < list.size(); ++i) {
    const std::string where = "material " + std::to_string(i);
    const Json& m = RequireObject(list[i], where);
    int image = -1;
    Eigen::Vector4f color = Eigen::Vector4f::Ones();
    if (const Json* pbr_json = Member(m, "pbrMetallicRoughness")) {
      const std::string pbr_where = where + ".pbrMetallicRoughness";
      const Json& pbr = RequireObject(*pbr_json, pbr_where);
      if (const Json* info_json = Member(pbr, "baseColorTexture")) {
        const Json& info = RequireObject(*info_json, pbr_where + ".baseColorTexture");
        const std::uint64_t tex_coord = WholeMember(info, "texCoord", 0, kMaxIndex, pbr_where + ".baseColorTexture");
        if (tex_coord != 0) Fail(where + " samples TEXCOORD_" + std::to_string(tex_coord));
        const int texture = IndexMember(info, "index", pbr_where + ".baseColorTexture");
        if (texture < 0) Fail(pbr_where + ".baseColorTexture has no index");
        const Json& texture_json = Element(ArrayMember(g, "textures", "the glTF"), texture, "texture");
        image = IndexMember(texture_json, "source", "texture " + std::to_string(texture));
      }
      if (const Json* factor = Member(pbr, "baseColorFactor")) {
        const std::vector<double> v = NumberArray(*factor, 4, pbr_where + ".baseColorFactor");
        for (int k = 0; k < 4; ++k) {
          if (!FitsFloat(v[static_cast<size_t>(k)])) Fail(pbr_where + ".baseColorFactor is out of range");
          color[k] = static_cast<float>(v[static_cast<size_t>(k)]);
        }
      }
    }
    materials.image.push_back(image);
    materials.color.push_back(color);
  }
  return materials;
}

void ReadImages(const GlbReader& reader, GltfScene* scene) {
  const Json& list = ArrayMember(reader.gltf(), "images", "the glTF");
  for (size_t i = 0; i < list.size(); ++i) {
    const std::string what = "image " + std::to_string(i);
    const Json& image = RequireObject(list[i], what);
    std::vector<std::uint8_t> bytes;
    if (Member(image, "uri") != nullptr) {
      bytes = UriBytes(StringMember(image, "uri", "", what), reader.folder(), kMaxImageFileBytes, what);
    } else if (Member(image, "bufferView") != nullptr) {
      size_t length = 0, stride = 0;
      const std::uint8_t* data = reader.View(IndexMember(image, "bufferView", what), &length, &stride);
      bytes.assign(data, data + length);
    } else {
      Fail(what + " has neither a uri nor a bufferView");
    }
    ImageReadResult decoded = DecodeImage(bytes, what);
    if (!decoded.ok()) Fail(decoded.error);
    scene->images.push_back(std::move(decoded.image));
  }
}

// The scene's root nodes: the default scene's, else every node that is no node's child.
std::vector<int> RootNodes(const Json& g, const Json& nodes) {
  std::vector<int> roots;
  const Json& scenes = ArrayMember(g, "scenes", "the glTF");
  if (!scenes.empty()) {
    const std::uint64_t s = WholeMember(g, "scene", 0, kMaxIndex, "the glTF");
    const Json& scene = Element(scenes, static_cast<int>(s), "scene");
    const Json& list = ArrayMember(scene, "nodes", "scene " + std::to_string(s));
    for (size_t i = 0; i < list.size(); ++i)
      roots.push_back(IndexValue(list[i], "scene " + std::to_string(s) + ".nodes[" + std::to_string(i) + "]"));
    return roots;
  }
  std::vector<char> is_child(nodes.size(), 0);
  for (size_t n = 0; n < nodes.size(); ++n) {
    const std::string where = "node " + std::to_string(n);
    const Json& children = ArrayMember(RequireObject(nodes[n], where), "children", where);
    for (size_t i = 0; i < children.size(); ++i) {
      const int child = IndexValue(children[i], where + ".children[" + std::to_string(i) + "]");
      if (static_cast<size_t>(child) < nodes.size()) is_child[static_cast<size_t>(child)] = 1;
    }
  }
  for (size_t n = 0; n < nodes.size(); ++n)
    if (!is_child[n]) roots.push_back(static_cast<int>(n));
  return roots;
}

void ReadScene(const GlbReader& reader, const GltfReadOptions& options, GltfScene* scene) {
  const Json& g = reader.gltf();
  const Json* asset = Member(g, "asset");
  if (asset == nullptr || !asset->is_object() || StringMember(*asset, "version", "", "asset") != "2.0")
    Fail("not a glTF 2.0 asset");
  const Materials materials = ReadMaterials(g);
  if (options.decode_images) ReadImages(reader, scene);
  const Json& nodes = ArrayMember(g, "nodes", "the glTF");
  const Json& meshes = ArrayMember(g, "meshes", "the glTF");
  const Json& cameras = ArrayMember(g, "cameras", "the glTF");
  if (nodes.size() > options.max_nodes)
    Fail("the file has " + std::to_string(nodes.size()) + " nodes, more than the " + std::to_string(options.max_nodes) +
         " read");
  // Depth first in the file's order, with a stack instead of recursion: a hierarchy as deep
  // as the file has nodes is read as any other. Each node is queued once; a second time
  // means a cycle or a node with two parents, which glTF forbids.
  struct Pending {
    int node;
    Eigen::Matrix4d parent;
  };
  std::vector<Pending> stack;
  std::vector<char> queued(nodes.size(), 0);  // so that the stack never holds more than the nodes
  const auto queue = [&](int index, const Eigen::Matrix4d& parent) {
    Element(nodes, index, "node");
    if (queued[static_cast<size_t>(index)])
      Fail("node " + std::to_string(index) +
           " is reached twice (the node hierarchy has a cycle or a node with two parents)");
    queued[static_cast<size_t>(index)] = 1;
    stack.push_back({index, parent});
  };
  const std::vector<int> roots = RootNodes(g, nodes);
  for (auto it = roots.rbegin(); it != roots.rend(); ++it) queue(*it, Eigen::Matrix4d::Identity());
  Budget budget;
  while (!stack.empty()) {
    const Pending pending = stack.back();
    stack.pop_back();
    const std::string where = "node " + std::to_string(pending.node);
    const Json& node = Element(nodes, pending.node, "node");
    const Eigen::Matrix4d world = pending.parent * NodeMatrix(node, where);
    if (!world.allFinite()) Fail(where + "'s transform is not finite once its parents' are applied");
    const int m = IndexMember(node, "mesh", where);
    if (m >= 0) {
      const std::string mesh_where = "mesh " + std::to_string(m);
      const Json& primitives = ArrayMember(Element(meshes, m, "mesh"), "primitives", mesh_where);
      for (size_t i = 0; i < primitives.size(); ++i)
        ReadPrimitive(reader, primitives[i], mesh_where + ".primitives[" + std::to_string(i) + "]", world, materials,
                      options, &budget, scene);
    }
    const int c = IndexMember(node, "camera", where);
    if (c >= 0)
      scene->cameras.push_back(
          ReadCamera(Element(cameras, c, "camera"), "camera " + std::to_string(c), node, world, options));
    const Json& children = ArrayMember(node, "children", where);
    for (size_t i = children.size(); i-- > 0;)
      queue(IndexValue(children[i], where + ".children[" + std::to_string(i) + "]"), world);
  }
  for (const GltfBatch& batch : scene->batches)
    if (batch.image >= static_cast<int>(scene->images.size()) && options.decode_images)
      Fail("a material's image is missing");
}

// A GLB's JSON and BIN chunks, or a JSON glTF, read into *scene.
void ReadBytes(const std::vector<std::uint8_t>& bytes, const fs::path& folder, const GltfReadOptions& options,
               GltfScene* scene) {
  const bool is_glb = bytes.size() >= 4 && U32(bytes, 0) == kGlbMagic;
  std::vector<std::uint8_t> bin;
  size_t json_begin = 0, json_end = bytes.size();
  if (is_glb) {
    if (bytes.size() < 20) Fail("not a binary glTF (.glb) file (shorter than its header)");
    if (U32(bytes, 4) != 2) Fail("GLB version " + std::to_string(U32(bytes, 4)) + ", 2 expected");
    if (U32(bytes, 8) != bytes.size()) Fail("the GLB header's length does not match the file (truncated?)");
    const size_t json_length = U32(bytes, 12);
    if (U32(bytes, 16) != kChunkJson || json_length > bytes.size() - 20)
      Fail("the first GLB chunk is not a complete JSON chunk");
    json_begin = 20;
    json_end = 20 + json_length;
    const size_t bin_header = json_end;
    if (bin_header + 8 <= bytes.size() && U32(bytes, bin_header + 4) == kChunkBin) {
      const size_t bin_length = U32(bytes, bin_header);
      if (bin_length > bytes.size() - bin_header - 8) Fail("the BIN chunk runs past the file");
      bin.assign(bytes.begin() + static_cast<long>(bin_header + 8),
                 bytes.begin() + static_cast<long>(bin_header + 8 + bin_length));
    }
  }
  Json gltf = ParseJson(bytes.data() + json_begin, bytes.data() + json_end);
  if (!gltf.is_object()) Fail("not a glTF file (its JSON is not an object)");
  std::vector<std::vector<std::uint8_t>> buffers = LoadBuffers(gltf, folder, is_glb, std::move(bin));
  ReadScene(GlbReader(std::move(gltf), std::move(buffers), folder), options, scene);
}

fs::path FolderOf(const std::string& path) {
  const fs::path folder = fs::path(path).parent_path();
  return folder.empty() ? fs::path(".") : folder;
}

}  // namespace

std::string ReadGltfBytes(const std::vector<std::uint8_t>& bytes, const std::string& name, const std::string& folder,
                          const GltfReadOptions& options, GltfScene* scene) {
  *scene = GltfScene();
  std::string error;
  // Nothing the file holds may throw out of the reader: every failure becomes its message.
  try {
    ReadBytes(bytes, fs::path(folder), options, scene);
  } catch (const GltfError& e) {
    error = e.message;
  } catch (const Json::exception& e) {
    error = "malformed glTF JSON (" + std::string(e.what()) + ")";
  } catch (const std::bad_alloc&) {
    error = "too large to read (out of memory)";
  } catch (const std::exception& e) {
    error = "cannot be read (" + std::string(e.what()) + ")";
  }
  if (error.empty()) return "";
  *scene = GltfScene();
  // A message may quote the parser's last token or a side file's path, and the app's log and
  // reports are JSON, which holds UTF-8 only.
  return name + ": " + ValidUtf8OrReplaced(error, "?");
}

std::string ReadGlb(const std::string& path, const GltfReadOptions& options, GltfScene* scene) {
  *scene = GltfScene();
  std::vector<std::uint8_t> bytes;
  std::string error;
  if (!ReadRegularFile(path, kMaxGlbBytes, &bytes, &error)) return error;
  if (bytes.size() < 20 || U32(bytes, 0) != kGlbMagic) return path + ": not a binary glTF (.glb) file";
  return ReadGltfBytes(bytes, path, FolderOf(path).string(), options, scene);
}

std::string ReadGltf(const std::string& path, const GltfReadOptions& options, GltfScene* scene) {
  *scene = GltfScene();
  std::vector<std::uint8_t> head;
  std::string error;
  if (!ReadRegularFileHead(path, 4, &head, &error)) return error;
  if (head.size() == 4 && U32(head, 0) == kGlbMagic) return ReadGlb(path, options, scene);
  std::vector<std::uint8_t> bytes;
  if (!ReadRegularFile(path, kMaxTextFileBytes, &bytes, &error)) return error;
  return ReadGltfBytes(bytes, path, FolderOf(path).string(), options, scene);
}

}  // namespace facet
