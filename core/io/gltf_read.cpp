// A deliberately small glTF reader (binary .glb, or JSON .gltf with .bin files or data: URIs):
// what ExportGlb writes and what a mesh from another tool needs for reference geometry, each
// access bounds-checked, anything else refused by name.
#include "core/io/gltf_read.h"

#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <nlohmann/json.hpp>

#include "core/io/gltf_constants.h"

#include "core/util/file_read.h"

namespace facet {
namespace {

using namespace gltf;

using Json = nlohmann::json;

constexpr std::uint64_t kMaxGlbBytes = 1ull << 30;

std::uint32_t U32(const std::vector<std::uint8_t>& b, size_t offset) {
  std::uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= static_cast<std::uint32_t>(b[offset + i]) << (8 * i);
  return v;
}

// Thrown inside the reader only and turned into the returned message at its boundary.
struct GltfError {
  std::string message;
};

[[noreturn]] void Fail(const std::string& message) { throw GltfError{message}; }

int ComponentSize(int component_type) {
  switch (component_type) {
    case kUnsignedByte: return 1;
    case kUnsignedShort: return 2;
    case kUnsignedInt:
    case kFloat: return 4;
    default: Fail("component type " + std::to_string(component_type) + " is not supported");
  }
}

int ComponentCount(const std::string& type) {
  if (type == "SCALAR") return 1;
  if (type == "VEC2") return 2;
  if (type == "VEC3") return 3;
  if (type == "VEC4") return 4;
  Fail("accessor type " + type + " is not supported");
}

class GlbReader {
 public:
  // buffers[i] holds the bytes of the file's buffer i (the BIN chunk, a .bin file or a data:
  // URI), already checked to hold at least its byteLength.
  // `folder` is where the glTF file is: its images' relative URIs are resolved there.
  GlbReader(Json gltf, std::vector<std::vector<std::uint8_t>> buffers, std::filesystem::path folder)
      : gltf_(std::move(gltf)), buffers_(std::move(buffers)), folder_(std::move(folder)) {}

  // The bytes of a bufferView, checked against its buffer.
  const std::uint8_t* View(int index, size_t* length, size_t* stride) const {
    const Json& views = gltf_.at("bufferViews");
    if (index < 0 || index >= static_cast<int>(views.size())) Fail("bufferView " + std::to_string(index) + " missing");
    const Json& view = views[index];
    const int buffer = view.value("buffer", 0);
    if (buffer < 0 || buffer >= static_cast<int>(buffers_.size()))
      Fail("bufferView " + std::to_string(index) + " uses buffer " + std::to_string(buffer) + ", which is missing");
    const std::vector<std::uint8_t>& bytes = buffers_[buffer];
    const size_t offset = view.value("byteOffset", size_t{0});
    *length = view.at("byteLength").get<size_t>();
    *stride = view.value("byteStride", size_t{0});
    if (offset > bytes.size() || *length > bytes.size() - offset)
      Fail("bufferView " + std::to_string(index) + " runs past its buffer");
    return bytes.data() + offset;
  }

  // Accessor `index` as doubles, `components` per element (which must match its type).
  std::vector<double> Accessor(int index, int components) const {
    const Json& accessors = gltf_.at("accessors");
    if (index < 0 || index >= static_cast<int>(accessors.size()))
      Fail("accessor " + std::to_string(index) + " missing");
    const Json& a = accessors[index];
    const std::string where = "accessor " + std::to_string(index);
    if (a.contains("sparse")) Fail(where + " is sparse (not supported)");
    if (!a.contains("bufferView")) Fail(where + " has no bufferView");
    const int component_type = a.at("componentType").get<int>();
    const int size = ComponentSize(component_type);
    if (ComponentCount(a.at("type").get<std::string>()) != components)
      Fail(where + " has type " + a.at("type").get<std::string>() + ", " + std::to_string(components) +
           " components expected");
    const size_t count = a.at("count").get<size_t>();
    size_t length = 0, stride = 0;
    const std::uint8_t* data = View(a.at("bufferView").get<int>(), &length, &stride);
    const size_t offset = a.value("byteOffset", size_t{0});
    const size_t element = static_cast<size_t>(size) * components;
    if (stride == 0) stride = element;
    if (count > 0 && (offset > length || (count - 1) * stride + element > length - offset))
      Fail(where + " runs past its bufferView");
    std::vector<double> out(count * components);
    for (size_t i = 0; i < count; ++i) {
      const std::uint8_t* e = data + offset + i * stride;
      for (int c = 0; c < components; ++c) {
        const std::uint8_t* p = e + c * size;
        double v = 0.0;
        if (component_type == kFloat) {
          float f;
          std::memcpy(&f, p, 4);
          v = f;
        } else if (component_type == kUnsignedInt) {
          std::uint32_t u;
          std::memcpy(&u, p, 4);
          v = u;
        } else if (component_type == kUnsignedShort) {
          std::uint16_t u;
          std::memcpy(&u, p, 2);
          v = u;
        } else {
          v = *p;
        }
        out[i * components + c] = v;
      }
    }
    return out;
  }

  const Json& gltf() const { return gltf_; }
  const std::filesystem::path& folder() const { return folder_; }

 private:
  Json gltf_;
  std::vector<std::vector<std::uint8_t>> buffers_;
  std::filesystem::path folder_;
};

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

// A relative URI reference as a file name: %XX escapes decoded (a space is written %20).
std::string DecodePercentEscapes(const std::string& uri) {
  std::string out;
  for (size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit(static_cast<unsigned char>(uri[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(uri[i + 2]))) {
      out += static_cast<char>(std::stoi(uri.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      out += uri[i];
    }
  }
  return out;
}

// The bytes a `uri` names, for `what` ("buffer 0", "image 2"): a data: URI with base64
// content, or a file relative to the folder of the glTF file (`folder`). Other schemes
// (http:, file:) are refused: a mesh is never fetched from elsewhere.
std::vector<std::uint8_t> UriBytes(const std::string& uri, const std::filesystem::path& folder, std::uint64_t max_bytes,
                                   const std::string& what) {
  std::vector<std::uint8_t> bytes;
  if (uri.rfind("data:", 0) == 0) {
    const size_t comma = uri.find(',');
    if (comma == std::string::npos || uri.rfind(";base64", comma) == std::string::npos ||
        uri.rfind(";base64", comma) + 7 != comma)
      Fail(what + ": its data: URI is not base64");
    if (!DecodeBase64(uri, comma + 1, &bytes)) Fail(what + ": its data: URI holds a character that is not base64");
    return bytes;
  }
  const size_t colon = uri.find(':');
  if (colon != std::string::npos && uri.find('/') > colon)
    Fail(what + ": its URI " + uri.substr(0, colon + 1) + "... is not a file beside the glTF (not read)");
  std::string error;
  if (!ReadRegularFile((folder / DecodePercentEscapes(uri)).string(), max_bytes, &bytes, &error))
    Fail(what + ": " + error);
  return bytes;
}

// Every buffer of the file, each holding at least its byteLength. A buffer without a URI is
// the GLB's BIN chunk (`glb_bin`, for buffer 0 of a .glb only).
std::vector<std::vector<std::uint8_t>> LoadBuffers(const Json& gltf, const std::filesystem::path& folder, bool is_glb,
                                                   std::vector<std::uint8_t> glb_bin) {
  std::vector<std::vector<std::uint8_t>> buffers;
  const Json& list = gltf.value("buffers", Json::array());
  for (size_t i = 0; i < list.size(); ++i) {
    const std::string what = "buffer " + std::to_string(i);
    const Json& buffer = list[i];
    if (buffer.contains("uri")) {
      buffers.push_back(UriBytes(buffer["uri"].get<std::string>(), folder, kMaxGlbBytes, what));
    } else if (is_glb && i == 0) {
      buffers.push_back(std::move(glb_bin));
    } else {
      Fail(what + " has no uri" + (is_glb ? "" : " (only a .glb's first buffer may be its BIN chunk)"));
    }
    const size_t declared = buffer.at("byteLength").get<size_t>();
    if (buffers.back().size() < declared)
      Fail(what + " holds " + std::to_string(buffers.back().size()) + " bytes, its byteLength says " +
           std::to_string(declared));
  }
  return buffers;
}

Eigen::Matrix4d NodeMatrix(const Json& node) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  if (node.contains("matrix")) {
    const Json& v = node["matrix"];
    if (v.size() != 16) Fail("a node's matrix does not have 16 numbers");
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r) m(r, c) = v[4 * c + r].get<double>();  // column-major
    return m;
  }
  Eigen::Vector3d t = Eigen::Vector3d::Zero(), s = Eigen::Vector3d::Ones();
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  auto vector3 = [](const Json& v) {
    if (!v.is_array() || v.size() != 3) Fail("a node's translation or scale does not have 3 numbers");
    return Eigen::Vector3d(v[0].get<double>(), v[1].get<double>(), v[2].get<double>());
  };
  if (node.contains("translation")) t = vector3(node["translation"]);
  if (node.contains("scale")) s = vector3(node["scale"]);
  if (node.contains("rotation")) {
    const Json& r = node["rotation"];  // x, y, z, w
    if (!r.is_array() || r.size() != 4) Fail("a node's rotation does not have 4 numbers");
    q = Eigen::Quaterniond(r[3].get<double>(), r[0].get<double>(), r[1].get<double>(), r[2].get<double>());
    if (std::abs(q.norm() - 1.0) > 1e-3) Fail("a node's rotation is not a unit quaternion");
    q.normalize();
  }
  m.topLeftCorner<3, 3>() = q.toRotationMatrix() * s.asDiagonal();
  m.topRightCorner<3, 1>() = t;
  return m;
}

void ReadPrimitive(const GlbReader& reader, const Json& primitive, const Eigen::Matrix4d& world_from_node,
                   const std::vector<int>& material_image, const std::vector<Eigen::Vector4f>& material_color,
                   GltfScene* scene) {
  if (primitive.value("mode", kTriangles) != kTriangles) Fail("a primitive is not made of triangles (mode != 4)");
  const Json& attributes = primitive.at("attributes");
  if (!attributes.contains("POSITION")) Fail("a primitive has no POSITION");
  const std::vector<double> p = reader.Accessor(attributes["POSITION"].get<int>(), 3);
  const size_t n = p.size() / 3;
  std::vector<double> nrm, uv;
  if (attributes.contains("NORMAL")) nrm = reader.Accessor(attributes["NORMAL"].get<int>(), 3);
  if (attributes.contains("TEXCOORD_0")) uv = reader.Accessor(attributes["TEXCOORD_0"].get<int>(), 2);
  if ((!nrm.empty() && nrm.size() != 3 * n) || (!uv.empty() && uv.size() != 2 * n))
    Fail("a primitive's attributes differ in count");
  const Eigen::Matrix3d linear = world_from_node.topLeftCorner<3, 3>();
  const Eigen::Matrix3d normal_matrix = linear.inverse().transpose();
  const auto base = static_cast<std::uint32_t>(scene->positions.size());
  for (size_t v = 0; v < n; ++v) {
    const Eigen::Vector3d x = (world_from_node * Eigen::Vector4d(p[3 * v], p[3 * v + 1], p[3 * v + 2], 1.0)).head<3>();
    scene->positions.push_back(x.cast<float>());
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
    if (!nrm.empty())
      normal = (normal_matrix * Eigen::Vector3d(nrm[3 * v], nrm[3 * v + 1], nrm[3 * v + 2])).normalized();
    scene->normals.push_back(normal.cast<float>());
    scene->uvs.push_back(uv.empty()
                             ? Eigen::Vector2f(0.0f, 0.0f)
                             : Eigen::Vector2f(static_cast<float>(uv[2 * v]), static_cast<float>(uv[2 * v + 1])));
  }
  GltfBatch batch;
  if (primitive.contains("material")) {
    const int m = primitive["material"].get<int>();
    if (m < 0 || m >= static_cast<int>(material_image.size())) Fail("a primitive's material is missing");
    batch.image = uv.empty() ? -1 : material_image[m];
    batch.base_color = material_color[m];
  }
  if (primitive.contains("indices")) {
    const std::vector<double> idx = reader.Accessor(primitive["indices"].get<int>(), 1);
    for (double i : idx) {
      if (i >= static_cast<double>(n)) Fail("a primitive's index is out of range");
      batch.indices.push_back(base + static_cast<std::uint32_t>(i));
    }
  } else {
    for (size_t v = 0; v < n; ++v) batch.indices.push_back(base + static_cast<std::uint32_t>(v));
  }
  if (batch.indices.size() % 3 != 0) Fail("a primitive's index count is not a multiple of 3");
  scene->batches.push_back(std::move(batch));
}

GltfCamera ReadCamera(const Json& camera_json, const Json& node, const Eigen::Matrix4d& world_from_node,
                      const GltfReadOptions& options) {
  if (camera_json.value("type", "") != "perspective")
    Fail("camera " + camera_json.value("name", "") + " is not perspective");
  const Json& p = camera_json.at("perspective");
  GltfCamera out;
  out.name = node.value("name", camera_json.value("name", ""));
  out.yfov_rad = p.at("yfov").get<double>();
  out.aspect_ratio = p.value("aspectRatio", 0.0);
  out.znear = p.value("znear", 0.0);
  if (!(out.yfov_rad > 0.0 && out.yfov_rad < M_PI)) Fail("camera " + out.name + " has a yfov outside (0, pi)");
  int w = 0, h = options.default_height_px;
  const Json extras = camera_json.value("extras", Json::object());
  if (extras.contains("image_size_px")) {
    w = extras["image_size_px"][0].get<int>();
    h = extras["image_size_px"][1].get<int>();
  } else if (out.aspect_ratio > 0.0) {
    w = static_cast<int>(std::lround(out.aspect_ratio * h));
  } else {
    w = h;
  }
  if (w <= 0 || h <= 0) Fail("camera " + out.name + " has no image size");
  Camera& cam = out.camera;
  cam.width_px = w;
  cam.height_px = h;
  cam.focal_px = h / (2.0 * std::tan(out.yfov_rad / 2.0));
  // OpenCV pixel centres at integers: the image spans [-0.5, w - 0.5], its centre is (w - 1) / 2.
  cam.principal_point_px = Eigen::Vector2d((w - 1) / 2.0, (h - 1) / 2.0);
  if (extras.contains("principal_point_px")) {
    out.has_principal_point = true;
    cam.principal_point_px = {extras["principal_point_px"][0].get<double>(),
                              extras["principal_point_px"][1].get<double>()};
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

void ReadScene(const GlbReader& reader, const GltfReadOptions& options, GltfScene* scene) {
  const Json& g = reader.gltf();
  if (!g.contains("asset") || g["asset"].value("version", "") != "2.0") Fail("not a glTF 2.0 asset");
  // Each material's base-colour image and factor.
  std::vector<int> material_image;
  std::vector<Eigen::Vector4f> material_color;
  for (const Json& m : g.value("materials", Json::array())) {
    const Json pbr = m.value("pbrMetallicRoughness", Json::object());
    int image = -1;
    if (pbr.contains("baseColorTexture")) {
      const Json& info = pbr["baseColorTexture"];
      if (info.value("texCoord", 0) != 0)
        Fail("a material samples TEXCOORD_" + std::to_string(info.value("texCoord", 0)));
      const int texture = info.at("index").get<int>();
      const Json& textures = g.at("textures");
      if (texture < 0 || texture >= static_cast<int>(textures.size()))
        Fail("texture " + std::to_string(texture) + " missing");
      image = textures[texture].value("source", -1);
    }
    material_image.push_back(image);
    Eigen::Vector4f color = Eigen::Vector4f::Ones();
    if (pbr.contains("baseColorFactor"))
      for (int k = 0; k < 4; ++k) color[k] = pbr["baseColorFactor"][k].get<float>();
    material_color.push_back(color);
  }
  if (options.decode_images) {
    for (const Json& image : g.value("images", Json::array())) {
      std::vector<std::uint8_t> bytes;
      if (image.contains("uri")) {
        bytes = UriBytes(image["uri"].get<std::string>(), reader.folder(), kMaxImageFileBytes,
                         "image " + std::to_string(scene->images.size()));
      } else if (image.contains("bufferView")) {
        size_t length = 0, stride = 0;
        const std::uint8_t* data = reader.View(image["bufferView"].get<int>(), &length, &stride);
        bytes.assign(data, data + length);
      } else {
        Fail("image " + std::to_string(scene->images.size()) + " has neither a uri nor a bufferView");
      }
      ImageReadResult decoded = DecodeImage(bytes, "image " + std::to_string(scene->images.size()));
      if (!decoded.ok()) Fail(decoded.error);
      scene->images.push_back(std::move(decoded.image));
    }
  }
  const Json& nodes = g.value("nodes", Json::array());
  const Json& meshes = g.value("meshes", Json::array());
  const Json& cameras = g.value("cameras", Json::array());
  std::vector<int> roots;
  if (g.contains("scenes") && !g["scenes"].empty()) {
    const int s = g.value("scene", 0);
    if (s < 0 || s >= static_cast<int>(g["scenes"].size())) Fail("scene " + std::to_string(s) + " missing");
    for (const Json& n : g["scenes"][s].value("nodes", Json::array())) roots.push_back(n.get<int>());
  } else {
    for (int n = 0; n < static_cast<int>(nodes.size()); ++n) roots.push_back(n);
  }
  int visited = 0;
  std::function<void(int, const Eigen::Matrix4d&)> visit = [&](int index, const Eigen::Matrix4d& parent) {
    if (index < 0 || index >= static_cast<int>(nodes.size())) Fail("node " + std::to_string(index) + " missing");
    if (++visited > static_cast<int>(nodes.size())) Fail("the node hierarchy has a cycle");
    const Json& node = nodes[index];
    const Eigen::Matrix4d world = parent * NodeMatrix(node);
    if (node.contains("mesh")) {
      const int m = node["mesh"].get<int>();
      if (m < 0 || m >= static_cast<int>(meshes.size())) Fail("mesh " + std::to_string(m) + " missing");
      for (const Json& primitive : meshes[m].at("primitives"))
        ReadPrimitive(reader, primitive, world, material_image, material_color, scene);
    }
    if (node.contains("camera")) {
      const int c = node["camera"].get<int>();
      if (c < 0 || c >= static_cast<int>(cameras.size())) Fail("camera " + std::to_string(c) + " missing");
      scene->cameras.push_back(ReadCamera(cameras[c], node, world, options));
    }
    for (const Json& child : node.value("children", Json::array())) visit(child.get<int>(), world);
  };
  for (int root : roots) visit(root, Eigen::Matrix4d::Identity());
  for (const GltfBatch& batch : scene->batches)
    if (batch.image >= static_cast<int>(scene->images.size()) && options.decode_images)
      Fail("a material's image is missing");
}

}  // namespace

std::string ReadGlb(const std::string& path, const GltfReadOptions& options, GltfScene* scene) {
  *scene = GltfScene();
  std::vector<std::uint8_t> bytes;
  std::string error;
  if (!ReadRegularFile(path, kMaxGlbBytes, &bytes, &error)) return error;
  if (bytes.size() < 20 || U32(bytes, 0) != kGlbMagic) return path + ": not a binary glTF (.glb) file";
  if (U32(bytes, 4) != 2) return path + ": GLB version " + std::to_string(U32(bytes, 4)) + ", 2 expected";
  if (U32(bytes, 8) != bytes.size()) return path + ": the GLB header's length does not match the file (truncated?)";
  const size_t json_length = U32(bytes, 12);
  if (U32(bytes, 16) != kChunkJson || json_length > bytes.size() - 20)
    return path + ": the first GLB chunk is not a complete JSON chunk";
  std::vector<std::uint8_t> bin;
  const size_t bin_header = 20 + json_length;
  if (bin_header + 8 <= bytes.size() && U32(bytes, bin_header + 4) == kChunkBin) {
    const size_t bin_length = U32(bytes, bin_header);
    if (bin_length > bytes.size() - bin_header - 8) return path + ": the BIN chunk runs past the file";
    bin.assign(bytes.begin() + static_cast<long>(bin_header + 8),
               bytes.begin() + static_cast<long>(bin_header + 8 + bin_length));
  }
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  try {
    Json gltf = Json::parse(bytes.begin() + 20, bytes.begin() + 20 + static_cast<long>(json_length));
    std::vector<std::vector<std::uint8_t>> buffers = LoadBuffers(gltf, folder, true, std::move(bin));
    ReadScene(GlbReader(std::move(gltf), std::move(buffers), folder), options, scene);
  } catch (const GltfError& e) {
    *scene = GltfScene();
    return path + ": " + e.message;
  } catch (const Json::exception& e) {
    *scene = GltfScene();
    return path + ": malformed glTF JSON (" + std::string(e.what()) + ")";
  }
  return "";
}

std::string ReadGltf(const std::string& path, const GltfReadOptions& options, GltfScene* scene) {
  *scene = GltfScene();
  std::vector<std::uint8_t> head;
  std::string error;
  if (!ReadRegularFileHead(path, 4, &head, &error)) return error;
  if (head.size() == 4 && U32(head, 0) == kGlbMagic) return ReadGlb(path, options, scene);
  std::string text;
  if (!ReadRegularFile(path, kMaxTextFileBytes, &text, &error)) return error;
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  try {
    Json gltf = Json::parse(text);
    if (!gltf.is_object()) Fail("not a glTF file (its JSON is not an object)");
    std::vector<std::vector<std::uint8_t>> buffers = LoadBuffers(gltf, folder, false, {});
    ReadScene(GlbReader(std::move(gltf), std::move(buffers), folder), options, scene);
  } catch (const GltfError& e) {
    *scene = GltfScene();
    return path + ": " + e.message;
  } catch (const Json::exception& e) {
    *scene = GltfScene();
    return path + ": malformed glTF JSON (" + std::string(e.what()) + ")";
  }
  return "";
}

}  // namespace facet
