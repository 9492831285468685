#include "core/io/project_io.h"
#include "core/io/project_io_internal.h"

#include "core/geometry/camera_checks.h"
#include "core/geometry/id_limits.h"
#include "core/image/image_io.h"
#include "core/util/file_read.h"
#include "core/util/format.h"
#include "core/util/input_limits.h"
#include "core/util/utf8.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <set>
#include <unordered_map>

#include <Eigen/LU>
#include <nlohmann/json.hpp>

namespace facet {
namespace {

using Json = nlohmann::json;
// Written objects keep the field order of the format description, so files diff well.
using OrderedJson = nlohmann::ordered_json;

constexpr const char* kFormatName = "facet-project";

std::string Join(const std::string& base, const std::string& key) { return base.empty() ? key : base + "." + key; }
std::string Index(const std::string& base, size_t i) { return base + "[" + std::to_string(i) + "]"; }

const char* PrincipalPointModeName(PrincipalPointMode mode) {
  switch (mode) {
    case PrincipalPointMode::kSolve: return "solve";
    case PrincipalPointMode::kImageCenter: return "center";
    case PrincipalPointMode::kFixed: return "fixed";
  }
  return "?";
}

std::optional<PrincipalPointMode> PrincipalPointModeFromName(const std::string& name) {
  if (name == "solve") return PrincipalPointMode::kSolve;
  if (name == "center") return PrincipalPointMode::kImageCenter;
  if (name == "fixed") return PrincipalPointMode::kFixed;
  return std::nullopt;
}

// The key of a file path stored as its bytes (Writer::FilePath).
constexpr const char* kPathBytesKey = "bytes_hex";

// ---------------------------------------------------------------------------------------
// Writing. The writer records the first value JSON cannot represent (NaN, infinity,
// invalid UTF-8) with its path, so SaveProject can refuse with a precise message.

class Writer {
 public:
  const std::string& error() const { return error_; }

  OrderedJson Number(const std::string& path, double v) {
    if (!std::isfinite(v) && error_.empty()) {
      error_ = path + ": " + (std::isnan(v) ? "NaN" : "infinity") + " cannot be saved (JSON has no NaN or infinity)";
    }
    return v;
  }
  template <typename Derived>
  OrderedJson Numbers(const std::string& path, const Eigen::DenseBase<Derived>& v) {
    OrderedJson out = OrderedJson::array();
    for (Eigen::Index i = 0; i < v.size(); ++i) out.push_back(Number(Index(path, i), v(i)));
    return out;
  }
  // Row-major, so the file reads like the matrix.
  OrderedJson Matrix(const std::string& path, const Eigen::Matrix3d& m) {
    OrderedJson out = OrderedJson::array();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) out.push_back(Number(Index(path, r * 3 + c), m(r, c)));
    return out;
  }
  OrderedJson String(const std::string& path, const std::string& s) {
    if (!IsValidUtf8(s) && error_.empty()) error_ = path + ": text is not valid UTF-8";
    return s;
  }
  // A file path is bytes: UTF-8 ones as a string, any other as {"bytes_hex": "..."} (the
  // header), so that a photo in a folder named in another encoding round-trips exactly.
  static OrderedJson FilePath(const std::string& s) {
    if (IsValidUtf8(s)) return s;
    static constexpr char kDigits[] = "0123456789abcdef";
    std::string hex;
    for (const char c : s) {
      const auto byte = static_cast<unsigned char>(c);
      hex += kDigits[byte >> 4];
      hex += kDigits[byte & 15];
    }
    return OrderedJson{{kPathBytesKey, hex}};
  }

 private:
  std::string error_;
};

// A mesh is stored record by record with its ids (dead slots stay holes), so a round trip
// restores the very ids that pins and constraints refer to. No-element links are -1.
OrderedJson Link(std::uint32_t id) { return id == kNoElement ? OrderedJson(-1) : OrderedJson(id); }

OrderedJson WriteMesh(const PolyMesh& mesh, const std::string& at, Writer* w) {
  OrderedJson j;
  j["vertex_id_end"] = mesh.VertexIdEnd();
  j["edge_id_end"] = mesh.EdgeIdEnd();
  j["face_id_end"] = mesh.FaceIdEnd();
  OrderedJson vertices = OrderedJson::array();
  for (VertexId v = 0; v < mesh.VertexIdEnd(); ++v) {
    if (!mesh.IsVertex(v)) continue;
    const MeshVertex& mv = mesh.vertex(v);
    const std::string vat = Index(Join(at, "vertices"), vertices.size());
    OrderedJson jv;
    jv["id"] = v;
    jv["halfedge"] = Link(mv.halfedge);
    // Row-major 3x4 coefficients; b only when it differs from a (E_split vertices).
    jv["a"] = w->Numbers(Join(vat, "a"), mv.local.a.transpose().reshaped());
    if (mv.local.b != mv.local.a) jv["b"] = w->Numbers(Join(vat, "b"), mv.local.b.transpose().reshaped());
    jv["t"] = w->Number(Join(vat, "t"), mv.local.t);
    jv["on_edge"] = mv.local.on_edge;
    jv["free"] = mv.local.free;
    jv["offset"] = w->Numbers(Join(vat, "offset"), mv.local.offset);
    jv["position"] = w->Numbers(Join(vat, "position"), mv.position);
    vertices.push_back(std::move(jv));
  }
  j["vertices"] = std::move(vertices);
  OrderedJson edges = OrderedJson::array();
  for (EdgeId e = 0; e < mesh.EdgeIdEnd(); ++e) {
    if (!mesh.IsEdge(e)) continue;
    const std::string eat = Index(Join(at, "edges"), edges.size());
    OrderedJson je;
    je["id"] = e;
    OrderedJson sides = OrderedJson::array();
    for (int side = 0; side < 2; ++side) {
      const MeshHalfedge& h = mesh.halfedge(PolyMesh::EdgeHalfedge(e, side));
      OrderedJson jh;
      jh["origin"] = Link(h.origin);
      jh["next"] = Link(h.next);
      jh["prev"] = Link(h.prev);
      jh["face"] = Link(h.face);
      jh["uv"] = w->Numbers(Index(Join(eat, "halfedges"), side) + ".uv", h.uv);
      sides.push_back(std::move(jh));
    }
    je["halfedges"] = std::move(sides);
    edges.push_back(std::move(je));
  }
  j["edges"] = std::move(edges);
  OrderedJson faces = OrderedJson::array();
  for (FaceId f = 0; f < mesh.FaceIdEnd(); ++f) {
    if (!mesh.IsFace(f)) continue;
    const MeshFace& mf = mesh.face(f);
    faces.push_back(OrderedJson{{"id", f}, {"halfedge", Link(mf.halfedge)}, {"material", mf.material}});
  }
  j["faces"] = std::move(faces);
  return j;
}

// One writer per object kind, shared with the recovery file (project_io_internal.h); `at` is
// the object's JSON path, for the Writer's error.
OrderedJson WriteImage(const Image& im, const std::string& at, Writer* w) {
  OrderedJson j;
  j["id"] = im.id;
  j["path"] = Writer::FilePath(std::filesystem::path(im.path).generic_string());
  j["width_px"] = im.width_px;
  j["height_px"] = im.height_px;
  const std::string cam_at = Join(at, "camera");
  OrderedJson cam;
  cam["width_px"] = im.camera.width_px;
  cam["height_px"] = im.camera.height_px;
  cam["focal_px"] = w->Number(Join(cam_at, "focal_px"), im.camera.focal_px);
  cam["principal_point_px"] = w->Numbers(Join(cam_at, "principal_point_px"), im.camera.principal_point_px);
  cam["rotation"] = w->Matrix(Join(cam_at, "rotation"), im.camera.cam_from_world_rotation);
  cam["translation"] = w->Numbers(Join(cam_at, "translation"), im.camera.cam_from_world_translation);
  cam["k1"] = w->Number(Join(cam_at, "k1"), im.camera.k1);
  cam["k2"] = w->Number(Join(cam_at, "k2"), im.camera.k2);
  j["camera"] = std::move(cam);
  j["camera_calibrated"] = im.camera_calibrated;
  j["principal_point_mode"] = PrincipalPointModeName(im.principal_point_mode);
  j["fixed_principal_point_px"] = w->Numbers(Join(at, "fixed_principal_point_px"), im.fixed_principal_point_px);
  j["pose_locked"] = im.pose_locked;
  j["focal_locked"] = im.focal_locked;
  j["principal_point_locked"] = im.principal_point_locked;
  j["focal_mode"] = FocalModeName(im.focal_mode);
  j["fixed_focal_px"] = w->Number(Join(at, "fixed_focal_px"), im.fixed_focal_px);
  j["focal_prior_px"] = w->Number(Join(at, "focal_prior_px"), im.focal_prior_px);
  j["focal_prior_std_px"] = w->Number(Join(at, "focal_prior_std_px"), im.focal_prior_std_px);
  j["use_horizon"] = im.use_horizon;
  j["horizon_px"] = w->Numbers(Join(at, "horizon_px"), im.horizon_px);
  j["estimate_distortion"] = im.estimate_distortion;
  j["distortion_locked"] = im.distortion_locked;
  j["axis_quarter_turns"] = im.axis_quarter_turns;
  // Only when set: files of settled projects read as before.
  if (im.axis_turn_provisional) j["axis_turn_provisional"] = true;
  if (im.camera_from_reconstruction) j["camera_from_reconstruction"] = true;
  j["use_for_texture"] = im.use_for_texture;
  j["lens_group"] = im.lens_group;
  return j;
}

OrderedJson WriteSegment(const Segment& s, const std::string& at, Writer* w) {
  OrderedJson j;
  j["id"] = s.id;
  j["image_id"] = s.image_id;
  j["axis"] = AxisName(s.axis);
  j["a_px"] = w->Numbers(Join(at, "a_px"), s.a_px);
  j["b_px"] = w->Numbers(Join(at, "b_px"), s.b_px);
  return j;
}

OrderedJson WritePrimitive(const Primitive& prim, const std::string& at, Writer* w) {
  OrderedJson j;
  j["id"] = prim.id;
  j["name"] = w->String(Join(at, "name"), prim.name);
  j["kind"] = PrimitiveKindName(prim.shape.kind);
  j["params"] = w->Numbers(Join(at, "params"), prim.shape.params);
  j["segments"] = prim.shape.segments;
  // Only when it is not the default, so that files without turned wedges stay as they were.
  if (prim.shape.ridge_along_y) j["ridge"] = "y";
  j["rotation"] = w->Numbers(Join(at, "rotation"), prim.shape.rotation);
  j["translation"] = w->Numbers(Join(at, "translation"), prim.shape.translation);
  j["param_locked"] = prim.param_locked;
  j["rotation_locked"] = prim.rotation_locked;
  j["translation_locked"] = prim.translation_locked;
  j["attached_to"] = prim.attached_to;
  j["mesh"] = WriteMesh(prim.mesh, Join(at, "mesh"), w);
  // Face ids as the mesh numbers them; source_image 0: the bake chooses.
  OrderedJson overrides = OrderedJson::array();
  for (const FaceTextureOverride& o : prim.face_textures) {
    overrides.push_back(
        OrderedJson{{"face", o.face}, {"source_image", o.source_image}, {"excluded_images", o.excluded_images}});
  }
  j["face_textures"] = std::move(overrides);
  return j;
}

OrderedJson WritePin(const Pin& pin, const std::string& at, Writer* w) {
  OrderedJson j;
  j["id"] = pin.id;
  j["image_id"] = pin.image_id;
  j["primitive_id"] = pin.vertex.primitive_id;
  j["vertex"] = pin.vertex.vertex;
  j["uv_px"] = w->Numbers(Join(at, "uv_px"), pin.uv_px);
  return j;
}

OrderedJson WriteConstraint(const Constraint& c, const std::string& at, Writer* w) {
  OrderedJson j;
  j["id"] = c.id;
  j["kind"] = ConstraintKindName(c.kind);
  OrderedJson refs = OrderedJson::array();
  for (const VertexRef& ref : c.vertices) refs.push_back({ref.primitive_id, ref.vertex});
  j["vertices"] = std::move(refs);
  j["value"] = w->Number(Join(at, "value"), c.value);
  j["point"] = w->Numbers(Join(at, "point"), c.point);
  j["axis"] = AxisName(c.axis);
  j["image_id"] = c.image_id;
  j["line_a_px"] = w->Numbers(Join(at, "line_a_px"), c.line_a_px);
  j["line_b_px"] = w->Numbers(Join(at, "line_b_px"), c.line_b_px);
  return j;
}

OrderedJson WriteReference(const Reference& ref, const std::string& at, Writer* w) {
  OrderedJson j;
  j["id"] = ref.id;
  j["path"] = Writer::FilePath(std::filesystem::path(ref.path).generic_string());
  j["axes"] = ref.y_up ? "y_up" : "z_up";
  j["visible"] = ref.visible;
  return j;
}

template <typename T, typename WriteFn>
OrderedJson WriteList(const std::vector<T>& list, const char* key, WriteFn write, Writer* w) {
  OrderedJson out = OrderedJson::array();
  for (size_t i = 0; i < list.size(); ++i) out.push_back(write(list[i], Index(key, i), w));
  return out;
}

OrderedJson WriteProject(const Project& p, Writer* w) {
  OrderedJson root;
  root["format"] = kFormatName;
  root["version"] = Project::kFormatVersion;
  root["units"] = w->String("units", p.units);
  root["next_id"] = p.next_id;
  root["images"] = WriteList(p.images, "images", WriteImage, w);
  root["segments"] = WriteList(p.segments, "segments", WriteSegment, w);
  root["primitives"] = WriteList(p.primitives, "primitives", WritePrimitive, w);
  root["pins"] = WriteList(p.pins, "pins", WritePin, w);
  root["constraints"] = WriteList(p.constraints, "constraints", WriteConstraint, w);
  root["references"] = WriteList(p.references, "references", WriteReference, w);
  return root;
}

// ---------------------------------------------------------------------------------------
// Reading. Every accessor names the JSON path of what it reads; the first error wins.

class Reader {
 public:
  explicit Reader(std::vector<std::string>* warnings) : warnings_(warnings) {}
  const std::string& error() const { return error_; }

  bool Fail(const std::string& path, const std::string& what) {
    if (error_.empty()) error_ = (path.empty() ? std::string("(top level)") : path) + ": " + what;
    return false;
  }

  // Counts a mesh's id space (vertex, edge and face id ends) against the whole project's
  // kMaxProjectMeshIds, before it is allocated: ids may have holes, so a few bytes of file
  // could otherwise ask for any amount of memory.
  bool CountMeshIds(const std::string& path, std::uint64_t ids) {
    mesh_ids_ += ids;
    if (mesh_ids_ <= kMaxProjectMeshIds) return true;
    return Fail(path, "the meshes' ids go past the limit of " + std::to_string(kMaxProjectMeshIds) +
                          " (vertex, edge and face id ends, over all primitives)");
  }

  // The value of a required field, or null after recording "missing field".
  const Json* Field(const Json& obj, const std::string& obj_path, const char* key) {
    auto it = obj.find(key);
    if (it == obj.end()) {
      Fail(Join(obj_path, key), "missing field");
      return nullptr;
    }
    return &*it;
  }

  bool Object(const Json& j, const std::string& path, std::initializer_list<const char*> known) {
    if (!j.is_object()) return Fail(path, "expected an object, found " + TypeName(j));
    for (auto it = j.begin(); it != j.end(); ++it) {
      bool is_known = false;
      for (const char* k : known) is_known = is_known || it.key() == k;
      if (!is_known) warnings_->push_back(Join(path, it.key()) + ": unknown field ignored");
    }
    return true;
  }

  bool Array(const Json& obj, const std::string& obj_path, const char* key, const Json** out) {
    const Json* j = Field(obj, obj_path, key);
    if (!j) return false;
    if (!j->is_array()) return Fail(Join(obj_path, key), "expected an array, found " + TypeName(*j));
    *out = j;
    return true;
  }

  bool Double(const Json& j, const std::string& path, double* out) {
    if (!j.is_number()) return Fail(path, "expected a number, found " + TypeName(j));
    *out = j.get<double>();
    if (!std::isfinite(*out)) return Fail(path, "number out of range");
    return true;
  }
  bool Double(const Json& obj, const std::string& obj_path, const char* key, double* out) {
    const Json* j = Field(obj, obj_path, key);
    return j && Double(*j, Join(obj_path, key), out);
  }

  template <int N>
  bool Vector(const Json& obj, const std::string& obj_path, const char* key, Eigen::Matrix<double, N, 1>* out) {
    const Json* j = Field(obj, obj_path, key);
    if (!j) return false;
    const std::string path = Join(obj_path, key);
    if (!j->is_array() || j->size() != N) return Fail(path, "expected an array of " + std::to_string(N) + " numbers");
    for (int i = 0; i < N; ++i)
      if (!Double((*j)[i], Index(path, i), &(*out)(i))) return false;
    return true;
  }

  bool Matrix(const Json& obj, const std::string& obj_path, const char* key, Eigen::Matrix3d* out) {
    Eigen::Matrix<double, 9, 1> v;
    if (!Vector<9>(obj, obj_path, key, &v)) return false;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) (*out)(r, c) = v(r * 3 + c);
    return true;
  }

  bool Bool(const Json& j, const std::string& path, bool* out) {
    if (!j.is_boolean()) return Fail(path, "expected true or false, found " + TypeName(j));
    *out = j.get<bool>();
    return true;
  }
  bool Bool(const Json& obj, const std::string& obj_path, const char* key, bool* out) {
    const Json* j = Field(obj, obj_path, key);
    return j && Bool(*j, Join(obj_path, key), out);
  }

  bool Int(const Json& obj, const std::string& obj_path, const char* key, int min, int max, int* out) {
    const Json* j = Field(obj, obj_path, key);
    if (!j) return false;
    const std::string path = Join(obj_path, key);
    const std::string range = "expected an integer from " + std::to_string(min) + " to " + std::to_string(max);
    if (!j->is_number_integer()) return Fail(path, range + ", found " + TypeName(*j));
    if (j->is_number_unsigned()) {
      const auto v = j->get<std::uint64_t>();
      if (v > static_cast<std::uint64_t>(max) || static_cast<std::int64_t>(v) < min)
        return Fail(path, range + ", found " + j->dump());
      *out = static_cast<int>(v);
    } else {
      const auto v = j->get<std::int64_t>();
      if (v < min || v > max) return Fail(path, range + ", found " + j->dump());
      *out = static_cast<int>(v);
    }
    return true;
  }

  // Ids are positive: 0 is kNoId.
  bool IdField(const Json& obj, const std::string& obj_path, const char* key, Id* out) {
    const Json* j = Field(obj, obj_path, key);
    if (!j) return false;
    const std::string path = Join(obj_path, key);
    if (!j->is_number_unsigned() || j->get<std::uint64_t>() == 0)
      return Fail(path, "expected a positive integer id, found " + Describe(*j));
    if (j->get<std::uint64_t>() > kMaxId)
      return Fail(path, "expected an id up to " + std::to_string(kMaxId) + " (2^62), found " + Describe(*j));
    *out = j->get<std::uint64_t>();
    return true;
  }

  bool String(const Json& obj, const std::string& obj_path, const char* key, std::string* out) {
    const Json* j = Field(obj, obj_path, key);
    if (!j) return false;
    if (!j->is_string()) return Fail(Join(obj_path, key), "expected a string, found " + TypeName(*j));
    *out = j->get<std::string>();
    return true;
  }
  // Writer::FilePath's two forms: a string, or {"bytes_hex": even-length hex} (not UTF-8).
  bool FilePath(const Json& obj, const std::string& obj_path, const char* key, std::string* out) {
    const Json* j = Field(obj, obj_path, key);
    if (!j) return false;
    if (j->is_string()) {
      *out = j->get<std::string>();
      return true;
    }
    const std::string path = Join(obj_path, key);
    const auto hex_it = j->is_object() && j->size() == 1 ? j->find(kPathBytesKey) : j->end();
    if (hex_it == j->end() || !hex_it->is_string())
      return Fail(path,
                  std::string("expected a string or {\"") + kPathBytesKey + "\": \"HEX\"}, found " + TypeName(*j));
    const std::string& hex = hex_it->get_ref<const std::string&>();
    const auto digit = [](char c) {
      if (c >= '0' && c <= '9') return c - '0';
      if (c >= 'a' && c <= 'f') return c - 'a' + 10;
      if (c >= 'A' && c <= 'F') return c - 'A' + 10;
      return -1;
    };
    std::string bytes;
    for (size_t i = 0; i + 1 < hex.size(); i += 2) {
      const int high = digit(hex[i]), low = digit(hex[i + 1]);
      if (high < 0 || low < 0) break;
      bytes += static_cast<char>(high * 16 + low);
    }
    if (hex.size() % 2 != 0 || bytes.size() * 2 != hex.size() || bytes.find('\0') != std::string::npos)
      return Fail(Join(path, kPathBytesKey), "expected the path's bytes as pairs of hex digits, none zero");
    *out = std::move(bytes);
    return true;
  }

  static std::string TypeName(const Json& j) {
    if (j.is_null()) return "null";
    if (j.is_boolean()) return "a boolean";
    if (j.is_number()) return "a number";
    if (j.is_string()) return "a string";
    if (j.is_array()) return "an array";
    if (j.is_object()) return "an object";
    return "an unknown value";
  }
  static std::string Describe(const Json& j) { return j.is_number() ? j.dump() : TypeName(j); }

 private:
  std::string error_;
  std::uint64_t mesh_ids_ = 0;
  std::vector<std::string>* warnings_;
};

// The numbers of an image that must be a camera, checked where they enter (a focal length
// of 1e-300 px was exported as yfov = pi, k1 = 1e308 sent the solve 4,728 km away): the
// bounds of core/geometry/camera_checks.h, named by field.
bool CheckImageNumbers(const Image& im, const std::string& at, Reader* r) {
  const Camera& c = im.camera;
  const std::string cam_at = Join(at, "camera");
  const int camera_w = c.width_px > 0 ? c.width_px : im.width_px;
  const int camera_h = c.height_px > 0 ? c.height_px : im.height_px;
  const std::string not_a_camera = WhyNotACamera(c.focal_px, c.principal_point_px, camera_w, camera_h);
  if (im.camera_calibrated && !not_a_camera.empty()) return r->Fail(Join(cam_at, "focal_px"), not_a_camera);
  if (c.k1 != 0.0 || c.k2 != 0.0) {
    if (!not_a_camera.empty())
      return r->Fail(Join(cam_at, "k1"), "radial distortion on a camera that is not one: " + not_a_camera);
    if (!(std::abs(c.k1) <= kMaxDistortionCoefficient) || !(std::abs(c.k2) <= kMaxDistortionCoefficient))
      return r->Fail(Join(cam_at, std::abs(c.k1) <= kMaxDistortionCoefficient ? "k2" : "k1"),
                     "radial distortion k1 = " + internal::FormatNumber(c.k1, 6) +
                         ", k2 = " + internal::FormatNumber(c.k2, 6) + " is no lens (at most " +
                         internal::FormatNumber(kMaxDistortionCoefficient, 6) + " in magnitude)");
    const std::string folds = WhyDistortionFolds(c.k1, c.k2, c.focal_px, c.principal_point_px, camera_w, camera_h);
    if (!folds.empty()) return r->Fail(Join(cam_at, "k1"), folds);
  }
  if (im.focal_mode == FocalMode::kFixed) {
    const std::string why = WhyNotAFocalLength(im.fixed_focal_px, im.width_px, im.height_px);
    if (!why.empty()) return r->Fail(Join(at, "fixed_focal_px"), why);
  }
  if (im.focal_mode == FocalMode::kPrior) {
    const std::string why = WhyNotAFocalPrior(im.focal_prior_px, im.focal_prior_std_px, im.width_px, im.height_px);
    if (!why.empty()) return r->Fail(Join(at, "focal_prior_px"), why);
  }
  // Two equal points are a horizon being placed (the calibration says so), not a bad number.
  if (im.use_horizon && im.horizon_px.head<2>() != im.horizon_px.tail<2>()) {
    const std::string why = WhyNotALineOnPhoto(im.horizon_px, im.width_px, im.height_px);
    if (!why.empty()) return r->Fail(Join(at, "horizon_px"), why);
  }
  return true;
}

bool ReadImage(const Json& j, const std::string& at, Reader* r, Image* im) {
  if (!r->Object(j, at,
                 {"id", "path", "width_px", "height_px", "camera", "camera_calibrated", "principal_point_mode",
                  "fixed_principal_point_px", "pose_locked", "focal_locked", "principal_point_locked", "focal_mode",
                  "fixed_focal_px", "focal_prior_px", "focal_prior_std_px", "use_horizon", "horizon_px",
                  "estimate_distortion", "distortion_locked", "axis_quarter_turns", "axis_turn_provisional", "camera_from_reconstruction", "use_for_texture",
                  "lens_group"}))
    return false;
  constexpr int kMaxSize = std::numeric_limits<int>::max();
  if (!r->IdField(j, at, "id", &im->id) || !r->FilePath(j, at, "path", &im->path) ||
      !r->Int(j, at, "width_px", 1, kMaxSize, &im->width_px) ||
      !r->Int(j, at, "height_px", 1, kMaxSize, &im->height_px))
    return false;
  const Json* cam = r->Field(j, at, "camera");
  const std::string cam_at = Join(at, "camera");
  if (!cam ||
      !r->Object(*cam, cam_at,
                 {"width_px", "height_px", "focal_px", "principal_point_px", "rotation", "translation", "k1", "k2"}))
    return false;
  Camera& c = im->camera;
  if (!r->Int(*cam, cam_at, "width_px", 0, kMaxSize, &c.width_px) ||
      !r->Int(*cam, cam_at, "height_px", 0, kMaxSize, &c.height_px) ||
      !r->Double(*cam, cam_at, "focal_px", &c.focal_px) ||
      !r->Vector<2>(*cam, cam_at, "principal_point_px", &c.principal_point_px) ||
      !r->Matrix(*cam, cam_at, "rotation", &c.cam_from_world_rotation) ||
      !r->Vector<3>(*cam, cam_at, "translation", &c.cam_from_world_translation))
    return false;
  // Distortion and the calibration modes came after the first version-2 files: absent means
  // the defaults (a pinhole camera, focal solved, no horizon).
  if ((cam->contains("k1") && !r->Double(*cam, cam_at, "k1", &c.k1)) ||
      (cam->contains("k2") && !r->Double(*cam, cam_at, "k2", &c.k2)))
    return false;
  if (!(c.focal_px > 0)) return r->Fail(Join(cam_at, "focal_px"), "must be positive");
  // A loose tolerance: solvers leave rounding-level drift, a corrupted file is far off.
  const Eigen::Matrix3d& rot = c.cam_from_world_rotation;
  const double orthonormality_error = (rot.transpose() * rot - Eigen::Matrix3d::Identity()).norm();
  if (orthonormality_error > 1e-6 || rot.determinant() < 0)
    return r->Fail(Join(cam_at, "rotation"),
                   "not a rotation matrix (|R^T R - I| = " + std::to_string(orthonormality_error) +
                       ", det = " + std::to_string(rot.determinant()) + ")");
  std::string mode;
  if (!r->Bool(j, at, "camera_calibrated", &im->camera_calibrated) || !r->String(j, at, "principal_point_mode", &mode))
    return false;
  const auto parsed_mode = PrincipalPointModeFromName(mode);
  if (!parsed_mode)
    return r->Fail(Join(at, "principal_point_mode"),
                   "expected \"solve\", \"center\" or \"fixed\", found \"" + mode + "\"");
  im->principal_point_mode = *parsed_mode;
  if (!r->Vector<2>(j, at, "fixed_principal_point_px", &im->fixed_principal_point_px) ||
      !r->Bool(j, at, "pose_locked", &im->pose_locked) || !r->Bool(j, at, "focal_locked", &im->focal_locked) ||
      !r->Bool(j, at, "principal_point_locked", &im->principal_point_locked))
    return false;
  if (j.contains("focal_mode")) {
    std::string focal_mode;
    if (!r->String(j, at, "focal_mode", &focal_mode)) return false;
    const auto parsed_focal_mode = FocalModeFromName(focal_mode);
    if (!parsed_focal_mode)
      return r->Fail(Join(at, "focal_mode"),
                     "expected \"solve\", \"fixed\" or \"prior\", found \"" + focal_mode + "\"");
    im->focal_mode = *parsed_focal_mode;
  }
  const auto optional_double = [&](const char* key, double* out) {
    return !j.contains(key) || r->Double(j, at, key, out);
  };
  const auto optional_bool = [&](const char* key, bool* out) { return !j.contains(key) || r->Bool(j, at, key, out); };
  if (!optional_double("fixed_focal_px", &im->fixed_focal_px) ||
      !optional_double("focal_prior_px", &im->focal_prior_px) ||
      !optional_double("focal_prior_std_px", &im->focal_prior_std_px) ||
      !optional_bool("use_horizon", &im->use_horizon) ||
      (j.contains("horizon_px") && !r->Vector<4>(j, at, "horizon_px", &im->horizon_px)) ||
      !optional_bool("estimate_distortion", &im->estimate_distortion) ||
      !optional_bool("distortion_locked", &im->distortion_locked))
    return false;
  // Absent in files written before the world frames were reconciled: unchosen, so the next
  // update chooses it from the pins (the model's frame, when the file was solved).
  if (j.contains("axis_quarter_turns") &&
      !r->Int(j, at, "axis_quarter_turns", Image::kAxisTurnsUnchosen, 3, &im->axis_quarter_turns))
    return false;
  if (!optional_bool("axis_turn_provisional", &im->axis_turn_provisional) ||
      !optional_bool("camera_from_reconstruction", &im->camera_from_reconstruction))
    return false;
  if (im->axis_turn_provisional && im->axis_quarter_turns == Image::kAxisTurnsUnchosen)
    return r->Fail(Join(at, "axis_turn_provisional"), "a provisional turn needs axis_quarter_turns 0 to 3");
  if (!r->Bool(j, at, "use_for_texture", &im->use_for_texture)) return false;
  if (!r->Int(j, at, "lens_group", 0, std::numeric_limits<int>::max(), &im->lens_group)) return false;
  if (im->focal_mode == FocalMode::kFixed && !(im->fixed_focal_px > 0))
    return r->Fail(Join(at, "fixed_focal_px"), "must be positive when focal_mode is \"fixed\"");
  if (im->focal_mode == FocalMode::kPrior && !(im->focal_prior_px > 0 && im->focal_prior_std_px > 0))
    return r->Fail(Join(at, "focal_prior_px"), "a prior needs focal_prior_px > 0 and focal_prior_std_px > 0");
  return CheckImageNumbers(*im, at, r);
}

bool ReadSegment(const Json& j, const std::string& at, Reader* r, Segment* s) {
  std::string axis;
  if (!r->Object(j, at, {"id", "image_id", "axis", "a_px", "b_px"}) || !r->IdField(j, at, "id", &s->id) ||
      !r->IdField(j, at, "image_id", &s->image_id) || !r->String(j, at, "axis", &axis))
    return false;
  const auto parsed_axis = AxisFromName(axis);
  if (!parsed_axis) return r->Fail(Join(at, "axis"), "expected \"x\", \"y\" or \"z\", found \"" + axis + "\"");
  s->axis = *parsed_axis;
  return r->Vector<2>(j, at, "a_px", &s->a_px) && r->Vector<2>(j, at, "b_px", &s->b_px);
}

// A mesh link: -1 (none) or an id below `end`.
bool ReadLink(const Json& obj, const std::string& obj_path, const char* key, std::uint32_t end, Reader* r,
              std::uint32_t* out) {
  const Json* j = r->Field(obj, obj_path, key);
  if (!j) return false;
  if (j->is_number_integer() && !j->is_number_unsigned() && j->get<std::int64_t>() == -1) {
    *out = kNoElement;
    return true;
  }
  if (!j->is_number_unsigned() || j->get<std::uint64_t>() >= end)
    return r->Fail(Join(obj_path, key),
                   "expected -1 or an id below " + std::to_string(end) + ", found " + Reader::Describe(*j));
  *out = static_cast<std::uint32_t>(j->get<std::uint64_t>());
  return true;
}

bool ReadCoefficients(const Json& obj, const std::string& at, const char* key, Reader* r, ParamCoefficients* c) {
  Eigen::Matrix<double, 12, 1> v;
  if (!r->Vector<12>(obj, at, key, &v)) return false;
  for (int row = 0; row < 3; ++row)
    for (int col = 0; col < 4; ++col) (*c)(row, col) = v(row * 4 + col);
  return true;
}

bool ReadMesh(const Json& j, const std::string& at, PrimitiveId primitive, Reader* r, PolyMesh* mesh) {
  constexpr int kMaxIds = 1 << 30;
  int vertex_end = 0, edge_end = 0, face_end = 0;
  if (!r->Object(j, at, {"vertex_id_end", "edge_id_end", "face_id_end", "vertices", "edges", "faces"}) ||
      !r->Int(j, at, "vertex_id_end", 0, kMaxIds, &vertex_end) ||
      !r->Int(j, at, "edge_id_end", 0, kMaxIds, &edge_end) || !r->Int(j, at, "face_id_end", 0, kMaxIds, &face_end))
    return false;
  if (!r->CountMeshIds(at, static_cast<std::uint64_t>(vertex_end) + edge_end + face_end)) return false;
  *mesh = PolyMesh();
  mesh->GrowIdSpace(vertex_end, edge_end, face_end);
  const std::uint32_t halfedge_end = 2u * static_cast<std::uint32_t>(edge_end);
  const Json* list = nullptr;
  if (!r->Array(j, at, "vertices", &list)) return false;
  for (size_t i = 0; i < list->size(); ++i) {
    const Json& jv = (*list)[i];
    const std::string vat = Index(Join(at, "vertices"), i);
    std::uint32_t id = 0;
    if (!r->Object(jv, vat, {"id", "halfedge", "a", "b", "t", "on_edge", "free", "offset", "position"}) ||
        !ReadLink(jv, vat, "id", vertex_end, r, &id))
      return false;
    if (id == kNoElement || mesh->IsVertex(id)) return r->Fail(Join(vat, "id"), "missing or duplicate vertex id");
    mesh->ReviveVertex(id);
    MeshVertex& v = mesh->vertex(id);
    v.primitive = primitive;
    if (!ReadLink(jv, vat, "halfedge", halfedge_end, r, &v.halfedge) || !ReadCoefficients(jv, vat, "a", r, &v.local.a))
      return false;
    v.local.b = v.local.a;
    if (jv.contains("b") && !ReadCoefficients(jv, vat, "b", r, &v.local.b)) return false;
    if (!r->Double(jv, vat, "t", &v.local.t) || !r->Bool(jv, vat, "on_edge", &v.local.on_edge) ||
        !r->Bool(jv, vat, "free", &v.local.free) || !r->Vector<3>(jv, vat, "offset", &v.local.offset) ||
        !r->Vector<3>(jv, vat, "position", &v.position))
      return false;
  }
  if (!r->Array(j, at, "edges", &list)) return false;
  for (size_t i = 0; i < list->size(); ++i) {
    const Json& je = (*list)[i];
    const std::string eat = Index(Join(at, "edges"), i);
    std::uint32_t id = 0;
    const Json* sides = nullptr;
    if (!r->Object(je, eat, {"id", "halfedges"}) || !ReadLink(je, eat, "id", edge_end, r, &id) ||
        !r->Array(je, eat, "halfedges", &sides))
      return false;
    if (id == kNoElement || mesh->IsEdge(id)) return r->Fail(Join(eat, "id"), "missing or duplicate edge id");
    if (sides->size() != 2) return r->Fail(Join(eat, "halfedges"), "expected 2 half-edges");
    mesh->ReviveEdge(id);
    for (int side = 0; side < 2; ++side) {
      const Json& jh = (*sides)[side];
      const std::string hat = Index(Join(eat, "halfedges"), side);
      MeshHalfedge& h = mesh->halfedge(PolyMesh::EdgeHalfedge(id, side));
      if (!r->Object(jh, hat, {"origin", "next", "prev", "face", "uv"}) ||
          !ReadLink(jh, hat, "origin", vertex_end, r, &h.origin) ||
          !ReadLink(jh, hat, "next", halfedge_end, r, &h.next) ||
          !ReadLink(jh, hat, "prev", halfedge_end, r, &h.prev) || !ReadLink(jh, hat, "face", face_end, r, &h.face) ||
          !r->Vector<2>(jh, hat, "uv", &h.uv))
        return false;
    }
  }
  if (!r->Array(j, at, "faces", &list)) return false;
  for (size_t i = 0; i < list->size(); ++i) {
    const Json& jf = (*list)[i];
    const std::string fat = Index(Join(at, "faces"), i);
    std::uint32_t id = 0;
    if (!r->Object(jf, fat, {"id", "halfedge", "material"}) || !ReadLink(jf, fat, "id", face_end, r, &id)) return false;
    if (id == kNoElement || mesh->IsFace(id)) return r->Fail(Join(fat, "id"), "missing or duplicate face id");
    mesh->ReviveFace(id);
    MeshFace& f = mesh->face(id);
    f.primitive = primitive;
    if (!ReadLink(jf, fat, "halfedge", halfedge_end, r, &f.halfedge) ||
        !r->Int(jf, fat, "material", 0, std::numeric_limits<int>::max(), &f.material))
      return false;
  }
  const std::vector<std::string> problems = Validate(*mesh);
  if (!problems.empty()) return r->Fail(at, "broken mesh: " + problems.front());
  return true;
}

// A positive id in an array (an excluded image).
bool ReadIdValue(const Json& j, const std::string& path, Reader* r, Id* out) {
  if (!j.is_number_unsigned() || j.get<std::uint64_t>() == 0)
    return r->Fail(path, "expected a positive integer id, found " + Reader::Describe(j));
  *out = j.get<std::uint64_t>();
  return true;
}

// A primitive's per-face texture overrides: ascending by face, each with a source or an
// exclusion (a default entry is never stored), excluded images ascending. Faces and images
// are not checked against the project: an override outliving its face or photo is ignored
// by the bake (core/scene/project.h).
bool ReadFaceTextures(const Json& j, const std::string& at, Reader* r, std::vector<FaceTextureOverride>* out) {
  const Json* list = nullptr;
  if (!r->Array(j, at, "face_textures", &list)) return false;
  out->clear();
  const std::string list_at = Join(at, "face_textures");
  for (size_t i = 0; i < list->size(); ++i) {
    const Json& jo = (*list)[i];
    const std::string oat = Index(list_at, i);
    FaceTextureOverride o;
    int face = 0;
    const Json* source = nullptr;
    const Json* excluded = nullptr;
    if (!r->Object(jo, oat, {"face", "source_image", "excluded_images"}) ||
        !r->Int(jo, oat, "face", 0, std::numeric_limits<int>::max(), &face) ||
        !(source = r->Field(jo, oat, "source_image")) || !r->Array(jo, oat, "excluded_images", &excluded))
      return false;
    o.face = static_cast<FaceId>(face);
    if (!source->is_number_unsigned()) return r->Fail(Join(oat, "source_image"), "expected an image id or 0");
    o.source_image = source->get<std::uint64_t>();
    for (size_t k = 0; k < excluded->size(); ++k) {
      Id id = kNoId;
      const std::string kat = Index(Join(oat, "excluded_images"), k);
      if (!ReadIdValue((*excluded)[k], kat, r, &id)) return false;
      if (!o.excluded_images.empty() && id <= o.excluded_images.back())
        return r->Fail(kat, "excluded images must be ascending, each once");
      o.excluded_images.push_back(id);
    }
    if (o.IsDefault()) return r->Fail(oat, "names neither a source image nor an excluded one");
    if (!out->empty() && o.face <= out->back().face)
      return r->Fail(Join(oat, "face"), "overrides must be ascending by face, each face once");
    out->push_back(std::move(o));
  }
  return true;
}

bool ReadPrimitive(const Json& j, const std::string& at, Reader* r, Primitive* prim) {
  std::string kind;
  if (!r->Object(j, at,
                 {"id", "name", "kind", "params", "segments", "ridge", "rotation", "translation", "param_locked",
                  "rotation_locked", "translation_locked", "attached_to", "mesh", "face_textures"}) ||
      !r->IdField(j, at, "id", &prim->id) || !r->String(j, at, "name", &prim->name) || !r->String(j, at, "kind", &kind))
    return false;
  PrimitiveShape& shape = prim->shape;
  shape.id = prim->id;
  bool known_kind = false;
  for (PrimitiveKind k : {PrimitiveKind::kBox, PrimitiveKind::kWedge, PrimitiveKind::kPrism, PrimitiveKind::kPyramid,
                          PrimitiveKind::kCylinder, PrimitiveKind::kPlane}) {
    if (kind == PrimitiveKindName(k)) shape.kind = k, known_kind = true;
  }
  if (!known_kind) return r->Fail(Join(at, "kind"), "unknown primitive kind \"" + kind + "\"");
  if (!r->Vector<kMaxPrimitiveParams>(j, at, "params", &shape.params) ||
      !r->Int(j, at, "segments", 0, std::numeric_limits<int>::max(), &shape.segments) ||
      !r->Vector<3>(j, at, "rotation", &shape.rotation) || !r->Vector<3>(j, at, "translation", &shape.translation))
    return false;
  if (const std::string too_many = PrimitiveSidesProblem(shape); !too_many.empty())
    return r->Fail(Join(at, "segments"), too_many);
  for (int k = 0; k < kMaxPrimitiveParams; ++k)
    if (shape.params(k) < 0) return r->Fail(Index(Join(at, "params"), k), "a dimension cannot be negative");
  // A wedge's ridge: "x" (absent: files before it could turn) or "y".
  if (j.contains("ridge")) {
    std::string ridge;
    if (!r->String(j, at, "ridge", &ridge)) return false;
    if (ridge != "x" && ridge != "y") return r->Fail(Join(at, "ridge"), "expected \"x\" or \"y\", found \"" + ridge + "\"");
    if (shape.kind != PrimitiveKind::kWedge && ridge == "y") return r->Fail(Join(at, "ridge"), "only a wedge has a ridge");
    shape.ridge_along_y = ridge == "y";
  }
  const Json* locked = r->Field(j, at, "param_locked");
  if (!locked) return false;
  const std::string locked_at = Join(at, "param_locked");
  if (!locked->is_array() || locked->size() != kMaxPrimitiveParams)
    return r->Fail(locked_at, "expected an array of " + std::to_string(kMaxPrimitiveParams) + " booleans");
  for (int k = 0; k < kMaxPrimitiveParams; ++k)
    if (!r->Bool((*locked)[k], Index(locked_at, k), &prim->param_locked[k])) return false;
  if (!r->Bool(j, at, "rotation_locked", &prim->rotation_locked) ||
      !r->Bool(j, at, "translation_locked", &prim->translation_locked))
    return false;
  const Json* attached = r->Field(j, at, "attached_to");
  if (!attached) return false;
  if (!attached->is_number_unsigned()) return r->Fail(Join(at, "attached_to"), "expected an id or 0");
  prim->attached_to = attached->get<std::uint64_t>();
  if (!ReadFaceTextures(j, at, r, &prim->face_textures)) return false;
  const Json* mesh = r->Field(j, at, "mesh");
  if (!mesh) return false;
  // "from_shape" builds the primitive's unedited mesh: what files from version 1 (and
  // hand-written ones) get.
  if (mesh->is_string() && mesh->get<std::string>() == "from_shape") {
    prim->mesh = PolyMesh();
    const AddPrimitiveResult added = AddPrimitive(&prim->mesh, shape);
    if (!added.ok) return r->Fail(Join(at, "params"), added.message);
    return r->CountMeshIds(Join(at, "mesh"), static_cast<std::uint64_t>(prim->mesh.VertexIdEnd()) +
                                                 prim->mesh.EdgeIdEnd() + prim->mesh.FaceIdEnd());
  }
  return ReadMesh(*mesh, Join(at, "mesh"), prim->id, r, &prim->mesh);
}

bool ReadPin(const Json& j, const std::string& at, Reader* r, Pin* p) {
  int vertex = 0;
  if (!(r->Object(j, at, {"id", "image_id", "primitive_id", "vertex", "uv_px"}) && r->IdField(j, at, "id", &p->id) &&
        r->IdField(j, at, "image_id", &p->image_id) && r->IdField(j, at, "primitive_id", &p->vertex.primitive_id) &&
        r->Int(j, at, "vertex", 0, std::numeric_limits<int>::max(), &vertex) &&
        r->Vector<2>(j, at, "uv_px", &p->uv_px)))
    return false;
  p->vertex.vertex = static_cast<VertexId>(vertex);
  return true;
}

bool ReadConstraint(const Json& j, const std::string& at, Reader* r, Constraint* c) {
  std::string kind, axis;
  const Json* refs = nullptr;
  if (!r->Object(j, at, {"id", "kind", "vertices", "value", "point", "axis", "image_id", "line_a_px", "line_b_px"}) ||
      !r->IdField(j, at, "id", &c->id) || !r->String(j, at, "kind", &kind) || !r->Array(j, at, "vertices", &refs))
    return false;
  const auto parsed_kind = ConstraintKindFromName(kind);
  if (!parsed_kind) return r->Fail(Join(at, "kind"), "unknown constraint kind \"" + kind + "\"");
  c->kind = *parsed_kind;
  c->vertices.clear();
  for (size_t i = 0; i < refs->size(); ++i) {
    const Json& ref = (*refs)[i];
    const std::string rat = Index(Join(at, "vertices"), i);
    if (!ref.is_array() || ref.size() != 2 || !ref[0].is_number_unsigned() || !ref[1].is_number_unsigned() ||
        ref[1].get<std::uint64_t>() >= kNoElement)
      return r->Fail(rat, "expected [primitive_id, vertex]");
    c->vertices.push_back({ref[0].get<std::uint64_t>(), static_cast<VertexId>(ref[1].get<std::uint64_t>())});
  }
  const Json* image = r->Field(j, at, "image_id");
  if (!image) return false;
  if (!image->is_number_unsigned()) return r->Fail(Join(at, "image_id"), "expected an id or 0");
  c->image_id = image->get<std::uint64_t>();
  if (!r->Double(j, at, "value", &c->value) || !r->Vector<3>(j, at, "point", &c->point) ||
      !r->String(j, at, "axis", &axis) || !r->Vector<2>(j, at, "line_a_px", &c->line_a_px) ||
      !r->Vector<2>(j, at, "line_b_px", &c->line_b_px))
    return false;
  const auto parsed_axis = AxisFromName(axis);
  if (!parsed_axis) return r->Fail(Join(at, "axis"), "expected \"x\", \"y\" or \"z\", found \"" + axis + "\"");
  c->axis = *parsed_axis;
  return true;
}

bool ReadReference(const Json& j, const std::string& at, Reader* r, Reference* ref) {
  std::string axes;
  if (!(r->Object(j, at, {"id", "path", "axes", "visible"}) && r->IdField(j, at, "id", &ref->id) &&
        r->FilePath(j, at, "path", &ref->path) && r->String(j, at, "axes", &axes) &&
        r->Bool(j, at, "visible", &ref->visible)))
    return false;
  if (ref->path.empty()) return r->Fail(Join(at, "path"), "a reference needs the path of its mesh file");
  if (axes != "y_up" && axes != "z_up") return r->Fail(Join(at, "axes"), "expected \"y_up\" or \"z_up\", found \"" + axes + "\"");
  ref->y_up = axes == "y_up";
  return true;
}

// How many vertices a constraint kind takes: exactly `min` when `max` == `min`.
void ConstraintArity(ConstraintKind kind, size_t* min, size_t* max) {
  constexpr size_t kAny = std::numeric_limits<size_t>::max();
  switch (kind) {
    case ConstraintKind::kCoplanar: *min = 4, *max = kAny; return;
    case ConstraintKind::kCollinear: *min = 3, *max = kAny; return;
    case ConstraintKind::kParallel:
    case ConstraintKind::kPerpendicular:
    case ConstraintKind::kEqualLength: *min = *max = 4; return;
    case ConstraintKind::kFixedPoint: *min = *max = 1; return;
    case ConstraintKind::kDistance:
    case ConstraintKind::kAlongAxis:
    case ConstraintKind::kEdgeOnImageLine: *min = *max = 2; return;
  }
}

template <typename T, typename ReadFn>
bool ReadList(const Json& root, const char* key, Reader* r, ReadFn read, std::vector<T>* out) {
  const Json* list = nullptr;
  if (!r->Array(root, "", key, &list)) return false;
  out->resize(list->size());
  for (size_t i = 0; i < list->size(); ++i)
    if (!read((*list)[i], Index(key, i), r, &(*out)[i])) return false;
  return true;
}

// Cross-object checks: ids unique in the whole project (one counter makes them), references
// resolve, and next_id lies beyond every id so new objects never collide.
bool CheckReferences(const Project& p, Reader* r) {
  std::unordered_map<Id, std::string> owner;
  Id max_id = 0;
  auto claim = [&](Id id, const std::string& at) {
    auto [it, inserted] = owner.emplace(id, at);
    if (!inserted)
      return r->Fail(Join(at, "id"), "duplicate id " + std::to_string(id) + " (also used by " + it->second + ")");
    max_id = std::max(max_id, id);
    return true;
  };
  std::set<Id> image_ids;
  for (size_t i = 0; i < p.images.size(); ++i) {
    if (!claim(p.images[i].id, Index("images", i))) return false;
    image_ids.insert(p.images[i].id);
  }
  for (size_t i = 0; i < p.primitives.size(); ++i) {
    if (!claim(p.primitives[i].id, Index("primitives", i))) return false;
  }
  std::unordered_map<Id, Id> base_of;
  for (const Primitive& primitive : p.primitives) base_of[primitive.id] = primitive.attached_to;
  for (size_t i = 0; i < p.primitives.size(); ++i) {
    const Id base = p.primitives[i].attached_to;
    if (base != kNoId && (base == p.primitives[i].id || base_of.count(base) == 0))
      return r->Fail(Join(Index("primitives", i), "attached_to"),
                     "refers to a missing primitive " + std::to_string(base));
  }
  // Attachments form trees: a primitive rides on its base, which may not ride on it; and at
  // most kMaxAttachmentDepth bases deep (core/util/input_limits.h). Each walk up stops there,
  // so a long chain costs O(primitives x limit), not a walk of the whole chain per primitive.
  for (size_t i = 0; i < p.primitives.size(); ++i) {
    std::vector<Id> below;
    for (Id current = p.primitives[i].attached_to; current != kNoId; current = base_of.at(current)) {
      if (current == p.primitives[i].id || std::find(below.begin(), below.end(), current) != below.end())
        return r->Fail(Join(Index("primitives", i), "attached_to"), "the chain of bases of primitive " +
                                                                        std::to_string(p.primitives[i].id) +
                                                                        " loops (attachments must form trees)");
      if (static_cast<int>(below.size()) == kMaxAttachmentDepth)
        return r->Fail(Join(Index("primitives", i), "attached_to"),
                       "a primitive may sit on at most " + std::to_string(kMaxAttachmentDepth) +
                           " others (a chain of attachments); primitive " + std::to_string(p.primitives[i].id) +
                           " sits on more");
      below.push_back(current);
    }
  }
  // "vertex 3 of primitive 7", checked against the mesh.
  auto check_vertex = [&](const VertexRef& ref, const std::string& at) {
    if (p.FindPrimitive(ref.primitive_id) == nullptr)
      return r->Fail(at, "refers to a missing primitive " + std::to_string(ref.primitive_id));
    if (p.FindVertex(ref) == nullptr)
      return r->Fail(at, "refers to vertex " + std::to_string(ref.vertex) + ", which primitive " +
                             std::to_string(ref.primitive_id) + " does not have");
    return true;
  };
  std::unordered_map<Id, size_t> segments_of_image;
  for (size_t i = 0; i < p.segments.size(); ++i) {
    const std::string at = Index("segments", i);
    if (!claim(p.segments[i].id, at)) return false;
    if (!image_ids.count(p.segments[i].image_id))
      return r->Fail(Join(at, "image_id"), "refers to a missing image " + std::to_string(p.segments[i].image_id));
    if (++segments_of_image[p.segments[i].image_id] > kMaxCalibrationSegments)
      return r->Fail(Join(at, "image_id"), "a photo may have at most " + std::to_string(kMaxCalibrationSegments) +
                                               " line segments; image " + std::to_string(p.segments[i].image_id) +
                                               " has more");
  }
  for (size_t i = 0; i < p.pins.size(); ++i) {
    const std::string at = Index("pins", i);
    if (!claim(p.pins[i].id, at)) return false;
    if (!image_ids.count(p.pins[i].image_id))
      return r->Fail(Join(at, "image_id"), "refers to a missing image " + std::to_string(p.pins[i].image_id));
    if (!check_vertex(p.pins[i].vertex, Join(at, "vertex"))) return false;
  }
  for (size_t i = 0; i < p.constraints.size(); ++i) {
    const Constraint& c = p.constraints[i];
    const std::string at = Index("constraints", i);
    if (!claim(c.id, at)) return false;
    size_t min = 0, max = 0;
    ConstraintArity(c.kind, &min, &max);
    if (c.vertices.size() < min || c.vertices.size() > max)
      return r->Fail(Join(at, "vertices"), std::string("a ") + ConstraintKindName(c.kind) + " constraint takes " +
                                               (min == max ? std::to_string(min) : std::to_string(min) + " or more") +
                                               " vertices, found " + std::to_string(c.vertices.size()));
    for (size_t k = 0; k < c.vertices.size(); ++k)
      if (!check_vertex(c.vertices[k], Index(Join(at, "vertices"), k))) return false;
    if (c.kind == ConstraintKind::kEdgeOnImageLine && !image_ids.count(c.image_id))
      return r->Fail(Join(at, "image_id"), "refers to a missing image " + std::to_string(c.image_id));
  }
  for (size_t i = 0; i < p.references.size(); ++i) {
    if (!claim(p.references[i].id, Index("references", i))) return false;
  }
  if (p.next_id <= max_id)
    return r->Fail("next_id", "must be greater than every id (" + std::to_string(p.next_id) +
                                  " <= " + std::to_string(max_id) + ")");
  return true;
}

// Migration: each step upgrades a document by one version, in place, so that reading only
// ever deals with the current layout. kMigrationSteps[k] turns version k + 1 into k + 2.
using MigrationStep = bool (*)(Json* doc, std::string* error);

// Version 1 -> 2: boxes become box primitives with unedited meshes ("from_shape"), whose
// vertex i is corner i, so a pin's corner becomes its vertex; images gain intrinsics locks
// (locked: version 1 never refined intrinsics in the solve); constraints start empty.
// Malformed content is left for the reader, which reports it with its path.
bool MigrateVersion1To2(Json* doc, std::string* error) {
  Json& root = *doc;
  if (root.contains("images") && root["images"].is_array()) {
    for (Json& image : root["images"]) {
      if (!image.is_object()) continue;
      image["focal_locked"] = true;
      image["principal_point_locked"] = true;
    }
  }
  if (root.contains("boxes")) {
    if (!root["boxes"].is_array()) {
      *error = "boxes: expected an array";
      return false;
    }
    Json primitives = Json::array();
    for (const Json& box : root["boxes"]) {
      if (!box.is_object()) {
        primitives.push_back(box);
        continue;
      }
      Json prim;
      for (const char* key : {"id", "name", "rotation", "translation", "rotation_locked", "translation_locked"})
        if (box.contains(key)) prim[key] = box[key];
      prim["kind"] = "box";
      prim["segments"] = 0;
      if (box.contains("size") && box["size"].is_array()) {
        Json params = box["size"];
        params.push_back(0.0);
        prim["params"] = params;
      }
      if (box.contains("size_locked") && box["size_locked"].is_array()) {
        Json locked = box["size_locked"];
        locked.push_back(false);
        prim["param_locked"] = locked;
      }
      prim["attached_to"] = 0u;  // unsigned: the reader takes ids as unsigned integers
      prim["mesh"] = "from_shape";
      primitives.push_back(std::move(prim));
    }
    root.erase("boxes");
    root["primitives"] = std::move(primitives);
  }
  if (root.contains("pins") && root["pins"].is_array()) {
    for (Json& pin : root["pins"]) {
      if (!pin.is_object()) continue;
      if (pin.contains("box_id")) {
        pin["primitive_id"] = pin["box_id"];
        pin.erase("box_id");
      }
      if (pin.contains("corner")) {
        const Json& corner = pin["corner"];
        if (!corner.is_number_integer() || corner.get<std::int64_t>() < 0 || corner.get<std::int64_t>() > 7) {
          *error = "a pin's corner must be an integer from 0 to 7, found " + corner.dump();
          return false;
        }
        pin["vertex"] = corner;
        pin.erase("corner");
      }
    }
  }
  root["constraints"] = Json::array();
  return true;
}

// Version 2 -> 3: the user's texture choices arrive, none made yet: every photo may texture
// (use_for_texture), no face has an override.
bool MigrateVersion2To3(Json* doc, std::string* /*error*/) {
  Json& root = *doc;
  if (root.contains("images") && root["images"].is_array()) {
    for (Json& image : root["images"]) {
      if (image.is_object()) image["use_for_texture"] = true;
    }
  }
  if (root.contains("primitives") && root["primitives"].is_array()) {
    for (Json& primitive : root["primitives"]) {
      if (primitive.is_object()) primitive["face_textures"] = Json::array();
    }
  }
  return true;
}

// Version 3 -> 4: reference geometry came; an older project has none.
bool MigrateVersion3To4(Json* doc, std::string* /*error*/) {
  (*doc)["references"] = Json::array();
  return true;
}

// Version 4 -> 5: photos could share a lens (Image::lens_group); in older files each has its own.
bool MigrateVersion4To5(Json* doc, std::string* /*error*/) {
  Json& root = *doc;
  if (root.contains("images") && root["images"].is_array()) {
    for (Json& image : root["images"]) {
      if (image.is_object()) image["lens_group"] = 0;
    }
  }
  return true;
}

// kMigrationSteps[k] turns version k + 1 into k + 2.
constexpr std::array<MigrationStep, Project::kFormatVersion - 1> kMigrationSteps = {
    MigrateVersion1To2, MigrateVersion2To3, MigrateVersion3To4, MigrateVersion4To5};

bool MigrateToCurrent(Json* doc, int version, std::string* error) {
  for (int v = version; v < Project::kFormatVersion; ++v) {
    if (!kMigrationSteps[static_cast<size_t>(v - 1)](doc, error)) {
      *error = "upgrading from version " + std::to_string(v) + ": " + *error;
      return false;
    }
    (*doc)["version"] = v + 1;
  }
  return true;
}

bool ReadProject(Json& root, Reader* r, Project* p) {
  if (!root.is_object()) return r->Fail("", "expected a JSON object, found " + Reader::TypeName(root));
  std::string format;
  const Json* fmt = root.contains("format") ? &root["format"] : nullptr;
  if (!fmt) return r->Fail("format", "missing field: this is not a Facet project file");
  if (!fmt->is_string() || fmt->get<std::string>() != kFormatName)
    return r->Fail("format", "expected \"" + std::string(kFormatName) + "\": this is not a Facet project file");
  const Json* version = r->Field(root, "", "version");
  if (!version) return false;
  if (version->is_number_unsigned() && version->get<std::uint64_t>() > Project::kFormatVersion)
    return r->Fail("version", "written by a newer Facet: version " + version->dump() + ", this build reads up to " +
                                  std::to_string(Project::kFormatVersion));
  if (!version->is_number_unsigned() || version->get<std::uint64_t>() < 1)
    return r->Fail("version", "expected a positive integer, found " + Reader::Describe(*version));
  std::string migrate_error;
  if (!MigrateToCurrent(&root, version->get<int>(), &migrate_error)) return r->Fail("", migrate_error);

  if (!r->Object(
          root, "",
          {"format", "version", "units", "next_id", "images", "segments", "primitives", "pins", "constraints",
           "references"}) ||
      !r->String(root, "", "units", &p->units) || !r->IdField(root, "", "next_id", &p->next_id) ||
      !ReadList(root, "images", r, ReadImage, &p->images) ||
      !ReadList(root, "segments", r, ReadSegment, &p->segments) ||
      !ReadList(root, "primitives", r, ReadPrimitive, &p->primitives) ||
      !ReadList(root, "pins", r, ReadPin, &p->pins) ||
      !ReadList(root, "constraints", r, ReadConstraint, &p->constraints) ||
      !ReadList(root, "references", r, ReadReference, &p->references))
    return false;
  return CheckReferences(*p, r);
}

// nlohmann reports a byte offset; people look for lines and columns.
std::string LineColumn(const std::string& text, size_t byte) {
  // `byte` counts the characters read, so the offending one is at byte - 1.
  const size_t pos = std::min(byte == 0 ? 0 : byte - 1, text.size());
  size_t line = 1, line_start = 0;
  for (size_t i = 0; i < pos; ++i) {
    if (text[i] == '\n') {
      ++line;
      line_start = i + 1;
    }
  }
  return "line " + std::to_string(line) + ", column " + std::to_string(pos - line_start + 1);
}

std::string ParseErrorText(const nlohmann::json::parse_error& e) {
  // Drop nlohmann's "[json.exception...] parse error at ...: " prefix; we give our own position.
  std::string what = e.what();
  const size_t syntax = what.find("syntax error");
  if (syntax != std::string::npos) return what.substr(syntax);
  const size_t colon = what.rfind(": ");
  return colon == std::string::npos ? what : what.substr(colon + 2);
}

bool ReadWholeFile(const std::string& path, std::string* bytes, std::string* error) {
  return ReadRegularFile(path, kMaxTextFileBytes, bytes, error);
}

// JSON text to a document; a syntax error or an out-of-range number names its line and column.
// Shared with the recovery file (project_io_internal.h).
bool ParseJsonText(const std::string& text, Json* root, std::string* error) {
  if (text.find_first_not_of(" \t\r\n") == std::string::npos) {
    *error = "line 1, column 1: the file is empty";
    return false;
  }
  try {
    *root = Json::parse(text);
  } catch (const nlohmann::json::out_of_range& e) {
    // A number beyond the range of a double: nlohmann names the token but not where it is.
    const std::string what = e.what();
    const size_t open = what.find('\'');
    const size_t close = what.rfind('\'');
    const size_t at = open < close ? text.find(what.substr(open + 1, close - open - 1)) : std::string::npos;
    *error = (at == std::string::npos ? "" : LineColumn(text, at + 1) + ": ") + "number out of range" +
             (open < close ? " " + what.substr(open) : "");
    return false;
  } catch (const nlohmann::json::parse_error& e) {
    *error = LineColumn(text, e.byte) + ": " + ParseErrorText(e);
    return false;
  }
  return true;
}

}  // namespace

std::string ProjectToJson(const Project& project) {
  Writer writer;
  // Replacing invalid UTF-8 keeps this total; SaveProject refuses such text before it gets here.
  return WriteProject(project, &writer).dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n";
}

std::string CheckProjectSavable(const Project& project) {
  Writer writer;
  WriteProject(project, &writer);
  return writer.error();
}

ProjectLoadResult ProjectFromJson(const std::string& text) {
  ProjectLoadResult result;
  try {
    Json root;
    if (!ParseJsonText(text, &root, &result.error)) return result;
    Reader reader(&result.warnings);
    if (!ReadProject(root, &reader, &result.project)) {
      result.error = reader.error();
      result.project = Project();
    }
  } catch (const std::exception& e) {
    result.error = std::string("cannot read the project: ") + e.what();
  }
  if (!result.ok()) result.project = Project();
  return result;
}

std::string SaveProject(const Project& project, const std::string& path) {
  std::string error = CheckProjectSavable(project);
  if (!error.empty()) return "cannot save " + path + ": " + error;
  const std::string text = ProjectToJson(project);
  // A file that would not load again is worse than no save: the old file stays instead.
  const ProjectLoadResult check = ProjectFromJson(text);
  if (!check.ok()) return "cannot save " + path + ": the project is inconsistent: " + check.error;
  if (!(check.project == project)) return "cannot save " + path + ": the saved text does not read back equal";
  return WriteFileAtomically(path, text);
}

ProjectLoadResult LoadProject(const std::string& path) {
  ProjectLoadResult result;
  std::string bytes;
  if (!ReadWholeFile(path, &bytes, &result.error)) return result;
  result = ProjectFromJson(bytes);
  if (!result.ok()) {
    result.error = path + ": " + result.error;
    return result;
  }
  // A project moved without its folder structure: a photo missing at its stored path is
  // looked up by its file name beside the project. One still missing keeps its camera, pins
  // and lines (the app marks it until File > Relink photo).
  const std::filesystem::path folder = std::filesystem::path(path).parent_path();
  for (size_t i = 0; i < result.project.images.size(); ++i) {
    Image& image = result.project.images[i];
    const std::string resolved = ResolveImagePath(path, image.path);
    std::error_code ec;
    if (std::filesystem::is_regular_file(resolved, ec)) {
      int width = 0, height = 0;
      std::string size_error;
      if (ReadImageSize(resolved, &width, &height, &size_error)) {
        const std::string why = WhyPhotoIsNotTheImages(image, resolved, width, height);
        if (!why.empty())
          result.warnings.push_back("images[" + std::to_string(i) + "]: " + why +
                                    "; its pins and lines stay as they were (File > Relink photo)");
      }  // an unreadable photo is reported by whoever decodes it
      continue;
    }
    const std::string name = std::filesystem::path(image.path).filename().string();
    const std::filesystem::path beside = folder / name;
    const std::string at = "images[" + std::to_string(i) + "]: ";
    if (!name.empty() && name != image.path && std::filesystem::is_regular_file(beside, ec)) {
      result.warnings.push_back(at + "photo not found at " + resolved + "; using " + beside.string() +
                                " beside the project (save to keep the new path)");
      image.path = name;
    } else {
      result.warnings.push_back(at + "image file not found: " + resolved +
                                (name.empty() ? "" : " (nor " + name + " beside the project)"));
    }
  }
  // A reference mesh that is gone stays in the project (saved again as it was); only its
  // drawing is missing until the file is back.
  for (size_t i = 0; i < result.project.references.size(); ++i) {
    const std::string resolved = ResolveImagePath(path, result.project.references[i].path);
    std::error_code ec;
    if (!std::filesystem::is_regular_file(resolved, ec))
      result.warnings.push_back("references[" + std::to_string(i) + "]: reference mesh not found: " + resolved +
                                " (kept in the project; it is not drawn until the file is there)");
  }
  return result;
}

std::string WhyPhotoIsNotTheImages(const Image& image, const std::string& photo_path, int width_px, int height_px) {
  if (width_px == image.width_px && height_px == image.height_px) return {};
  return photo_path + " is " + std::to_string(width_px) + " x " + std::to_string(height_px) + " px, the image " +
         std::to_string(image.width_px) + " x " + std::to_string(image.height_px) + " px: not the same photo";
}

std::string ResolveImagePath(const std::string& project_path, const std::string& image_path) {
  namespace fs = std::filesystem;
  if (image_path.empty()) return image_path;
  const fs::path image(image_path);
  if (image.is_absolute()) return image.lexically_normal().string();
  return (fs::path(project_path).parent_path() / image).lexically_normal().string();
}

std::string RelativeImagePath(const std::string& project_path, const std::string& image_file_path) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::path folder = fs::absolute(fs::path(project_path), ec).parent_path();
  if (ec) return fs::path(image_file_path).generic_string();
  const fs::path image = fs::absolute(fs::path(image_file_path), ec);
  if (ec) return fs::path(image_file_path).generic_string();
  const fs::path relative = image.lexically_normal().lexically_relative(folder.lexically_normal());
  return relative.empty() ? image.lexically_normal().generic_string() : relative.generic_string();
}

void RebaseImagePaths(const std::string& old_project_path, const std::string& new_project_path, Project* project) {
  auto rebase = [&](std::string* stored) {
    if (stored->empty()) return;
    std::error_code ec;
    const std::string absolute = std::filesystem::absolute(ResolveImagePath(old_project_path, *stored), ec).string();
    if (!ec) *stored = RelativeImagePath(new_project_path, absolute);
  };
  for (Image& image : project->images) rebase(&image.path);
  for (Reference& reference : project->references) rebase(&reference.path);
}

}  // namespace facet

// ---------------------------------------------------------------------------------------
// The object writers and readers for the recovery file (project_io_internal.h).
namespace facet::project_io_internal {
namespace {

template <typename T>
OrderedJson WriteOne(OrderedJson (*write)(const T&, const std::string&, Writer*), const T& object,
                     const std::string& at, std::string* error) {
  Writer writer;
  OrderedJson json = write(object, at, &writer);
  if (error->empty()) *error = writer.error();
  return json;
}

template <typename T>
bool ReadOne(bool (*read)(const Json&, const std::string&, Reader*, T*), const Json& json, const std::string& at,
             T* object, std::string* error, std::vector<std::string>* warnings) {
  Reader reader(warnings);
  if (read(json, at, &reader, object)) return true;
  *error = reader.error();
  return false;
}

}  // namespace

OrderedJson ObjectToJson(const Image& image, const std::string& at, std::string* error) {
  return WriteOne(WriteImage, image, at, error);
}
OrderedJson ObjectToJson(const Segment& segment, const std::string& at, std::string* error) {
  return WriteOne(WriteSegment, segment, at, error);
}
OrderedJson ObjectToJson(const Primitive& primitive, const std::string& at, std::string* error) {
  return WriteOne(WritePrimitive, primitive, at, error);
}
OrderedJson ObjectToJson(const Pin& pin, const std::string& at, std::string* error) {
  return WriteOne(WritePin, pin, at, error);
}
OrderedJson ObjectToJson(const Constraint& constraint, const std::string& at, std::string* error) {
  return WriteOne(WriteConstraint, constraint, at, error);
}
OrderedJson ObjectToJson(const Reference& reference, const std::string& at, std::string* error) {
  return WriteOne(WriteReference, reference, at, error);
}
OrderedJson ProjectToJsonObject(const Project& project, std::string* error) {
  Writer writer;
  OrderedJson json = WriteProject(project, &writer);
  if (error->empty()) *error = writer.error();
  return json;
}

bool ObjectFromJson(const Json& json, const std::string& at, Image* image, std::string* error,
                    std::vector<std::string>* warnings) {
  return ReadOne(ReadImage, json, at, image, error, warnings);
}
bool ObjectFromJson(const Json& json, const std::string& at, Segment* segment, std::string* error,
                    std::vector<std::string>* warnings) {
  return ReadOne(ReadSegment, json, at, segment, error, warnings);
}
bool ObjectFromJson(const Json& json, const std::string& at, Primitive* primitive, std::string* error,
                    std::vector<std::string>* warnings) {
  return ReadOne(ReadPrimitive, json, at, primitive, error, warnings);
}
bool ObjectFromJson(const Json& json, const std::string& at, Pin* pin, std::string* error,
                    std::vector<std::string>* warnings) {
  return ReadOne(ReadPin, json, at, pin, error, warnings);
}
bool ObjectFromJson(const Json& json, const std::string& at, Constraint* constraint, std::string* error,
                    std::vector<std::string>* warnings) {
  return ReadOne(ReadConstraint, json, at, constraint, error, warnings);
}
bool ObjectFromJson(const Json& json, const std::string& at, Reference* reference, std::string* error,
                    std::vector<std::string>* warnings) {
  return ReadOne(ReadReference, json, at, reference, error, warnings);
}

bool ProjectFromJsonObject(Json& root, Project* project, std::string* error, std::vector<std::string>* warnings) {
  Reader reader(warnings);
  if (ReadProject(root, &reader, project)) return true;
  *error = reader.error();
  return false;
}

std::string CheckProjectReferences(const Project& project) {
  std::vector<std::string> warnings;
  Reader reader(&warnings);
  CheckReferences(project, &reader);
  return reader.error();
}

bool ParseJson(const std::string& text, Json* root, std::string* error) { return ParseJsonText(text, root, error); }

}  // namespace facet::project_io_internal
