// The 3D panel. GL resources are rebuilt only when what they show changes: the mesh and
// atlas on a new mesh_revision, the line geometry (mesh outlines, frustums, grid, axes) when
// primitives, calibrated cameras or the selected primitive change, a photo texture once per photo. Each frame
// renders those buffers into an offscreen target shown as an ImGui image.
#include "app/panels/viewport_panel.h"

#include "app/platform/gl_util.h"  // epoxy first

#include <imgui.h>
#include <glm/glm.hpp>
#include <glm/gtc/type_ptr.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "app/panels/teach_overlay.h"
#include "app/panels/texture_sections.h"
#include "app/panels/widgets.h"
#include "app/platform/gl_camera.h"
#include "app/platform/viewport_shaders.h"
#include "app/state/model_edits.h"
#include "app/state/model_pick.h"
#include "app/state/move_tool.h"
#include "app/state/orbit_camera.h"
#include "app/state/reference_edits.h"

namespace facet::app {
namespace {

// Multisampling quadruples the panel's cost under llvmpipe; software renderers go without.
constexpr int kMsaaSamplesHardware = 4;
constexpr int kMaxPhotoTextureSide = 1024;
constexpr float kPickRadiusPx = 8.0f;
constexpr float kClickSlopPx = 4.0f;
constexpr int kViewportHover = 2;  // AppState::hover_panel
constexpr const char* kHelpText = "drag: orbit \xc2\xb7 right-drag: pan \xc2\xb7 wheel: zoom \xc2\xb7 F: frame";

// ---------------------------------------------------------------------------------------
// Vertex formats

struct GpuMeshVertex {
  float position[3];
  float normal[3];
  float uv[2];
  float textured;
  float source_tint[4];  // View > Texture sources: the dominant photo's colour; alpha 0 for none
};

struct LineVertex {
  float position[3];
  std::uint8_t rgba[4];
};

struct PhotoVertex {
  float position[3];
  float uv[2];
};

using Rgba = std::array<std::uint8_t, 4>;
constexpr Rgba kBoxEdgeColor = {20, 22, 26, 255};
constexpr Rgba kSelectedBoxEdgeColor = {255, 160, 40, 255};
constexpr Rgba kFrustumColor = {150, 190, 230, 255};
constexpr Rgba kActiveFrustumColor = {255, 210, 60, 255};
constexpr Rgba kAxisX = {230, 60, 60, 255};
constexpr Rgba kAxisY = {70, 200, 70, 255};
constexpr Rgba kAxisZ = {70, 120, 255, 255};
constexpr Rgba kGridMinor = {150, 155, 165, 80};
constexpr Rgba kGridMajor = {190, 195, 205, 190};
// Reference geometry: see-through faces and firmer outlines in a colour the model never uses.
constexpr Rgba kReferenceFaceColor = {70, 205, 215, 60};
constexpr Rgba kReferenceEdgeColor = {70, 205, 215, 170};

// A range of vertices inside one buffer.
struct DrawRange {
  GLint first = 0;
  GLsizei count = 0;
};

// One calibrated camera as drawn: its frustum lines (inside the scene line buffer) and its
// photo quad (four vertices of the photo buffer, as a triangle fan).
struct CameraDraw {
  Id image_id = kNoId;
  GLint photo_first = 0;
};

struct PhotoTexture {
  GLuint texture = 0;
  // What the texture was made from, to notice a reloaded photo.
  int source_width = 0;
  int source_height = 0;
  const void* source_pixels = nullptr;
};

// What the line and photo geometry was built from; rebuilt when any of it differs.
struct SceneKey {
  std::vector<Primitive> primitives;
  std::vector<Image> images;
  Id active_image_id = kNoId;
  Id selected_primitive_id = kNoId;
  Id photo_view_image_id = kNoId;
  std::vector<Reference> references;  // their visibility
  std::uint64_t reference_revision = 0;
  bool operator==(const SceneKey&) const = default;
};

struct Program {
  GLuint id = 0;
  GLint clip_from_world = -1;
};

struct GlResources {
  bool initialised = false;
  std::string error;  // non-empty: GL setup failed, the panel shows the message

  Program mesh_program;
  GLint mesh_atlas = -1, mesh_use_texture = -1, mesh_eye = -1, mesh_show_sources = -1;
  Program line_program;
  GLint line_lighten_dark = -1;
  GLint line_fade = -1, line_fade_center = -1, line_fade_radius = -1, line_eye = -1, line_fade_eye_distance = -1;
  Program photo_program;
  GLint photo_sampler = -1, photo_alpha = -1;

  GLuint mesh_vao = 0, mesh_vbo = 0;
  GLsizei mesh_vertex_count = 0;
  GLuint atlas_texture = 0;
  bool mesh_uploaded = false;
  std::uint64_t mesh_revision = 0;
  std::uint64_t atlas_revision = 0;

  GLuint lines_vao = 0, lines_vbo = 0;
  DrawRange box_edges, frustums, active_frustum, axes, grid_minor, grid_major;
  DrawRange reference_faces, reference_edges;  // triangles and lines of the visible references
  GLuint photos_vao = 0, photos_vbo = 0;
  std::vector<CameraDraw> cameras;
  DrawRange background;  // unit quad for the photo behind a photo view
  bool scene_built = false;
  SceneKey scene_key;

  std::map<Id, PhotoTexture> photo_textures;
  GlRenderTarget target;
  bool wide_lines = false;
  int msaa_samples = 1;
};

// Scene measures that size the grid, the frustums and the framing.
struct SceneMeasure {
  SceneBounds bounds;          // primitives and camera centres
  SceneBounds frame_bounds;    // what Frame shows: the primitives (everything when none)
  double size = 1.0;           // diagonal of the primitives (or of everything when none)
  double frustum_depth = 0.3;  // world units from apex to image plane (at most)
  double grid_minor = 0.1, grid_major = 1.0, grid_half_extent = 5.0;
  Eigen::Vector3d grid_center = Eigen::Vector3d::Zero();
};

}  // namespace

// Everything the panel keeps between frames: this panel's own view state (the document and
// the selection stay in AppState).
struct ViewportPanelState::Impl {
  bool picture_only = false;  // ShowViewportPictureOnly
  GlResources gl;
  OrbitCamera orbit;
  bool framed_once = false;
  std::uint64_t framed_generation = 0;  // AppState::document_generation when last framed
  bool had_content = false;
  // What the view last framed (automatically or by the user's Frame), and whether the
  // project had primitives then: a large change of the model reframes (NeedsReframe).
  SceneBounds framed_bounds;
  bool had_primitives = false;
  bool show_texture = true, show_mesh = true, show_wireframe = true, show_cameras = true, show_grid = true;
  bool left_pressed_here = false;
  ImVec2 left_press_pos;
  ElementPick hovered;  // the element under the mouse (also in AppState::hover)
  bool frame_requested = false;
  Id view_from_photo_requested = kNoId;
  ViewportReport report;
  MoveDrag move_drag;  // the Move tool's drag in this panel
};

ViewportPanelState::ViewportPanelState() = default;
ViewportPanelState::~ViewportPanelState() = default;

namespace {

using PanelState = ViewportPanelState::Impl;

// Made on the first draw and freed by ShutdownViewportPanel while the context is current.
PanelState& Panel(ViewportPanelState* owner) {
  if (!owner->impl) owner->impl = std::make_unique<PanelState>();
  return *owner->impl;
}

ImTextureID ToImTexture(GLuint texture) { return reinterpret_cast<ImTextureID>(static_cast<std::intptr_t>(texture)); }

// Uploads a double matrix as GL's float mat4 (column-major, as GLM stores it).
void SetMatrix(GLint location, const glm::dmat4& m) {
  const glm::mat4 m_float(m);
  glUniformMatrix4fv(location, 1, GL_FALSE, glm::value_ptr(m_float));
}

// ---------------------------------------------------------------------------------------
// GL setup

bool BuildProgram(const char* vs, const char* fs, const char* name, Program* program, std::string* error) {
  std::string detail;
  program->id = BuildGlProgram(vs, fs, &detail);
  if (program->id == 0) {
    *error = std::string(name) + ": " + detail;
    return false;
  }
  program->clip_from_world = glGetUniformLocation(program->id, "u_clip_from_world");
  return true;
}

void SetupLineAttributes() {
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(LineVertex),
                        reinterpret_cast<void*>(offsetof(LineVertex, position)));
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 4, GL_UNSIGNED_BYTE, GL_TRUE, sizeof(LineVertex),
                        reinterpret_cast<void*>(offsetof(LineVertex, rgba)));
}

void SetupPhotoAttributes() {
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(PhotoVertex),
                        reinterpret_cast<void*>(offsetof(PhotoVertex, position)));
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 2, GL_FLOAT, GL_FALSE, sizeof(PhotoVertex),
                        reinterpret_cast<void*>(offsetof(PhotoVertex, uv)));
}

void SetupMeshAttributes() {
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(GpuMeshVertex),
                        reinterpret_cast<void*>(offsetof(GpuMeshVertex, position)));
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(GpuMeshVertex),
                        reinterpret_cast<void*>(offsetof(GpuMeshVertex, normal)));
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, sizeof(GpuMeshVertex),
                        reinterpret_cast<void*>(offsetof(GpuMeshVertex, uv)));
  glEnableVertexAttribArray(3);
  glVertexAttribPointer(3, 1, GL_FLOAT, GL_FALSE, sizeof(GpuMeshVertex),
                        reinterpret_cast<void*>(offsetof(GpuMeshVertex, textured)));
  glEnableVertexAttribArray(4);
  glVertexAttribPointer(4, 4, GL_FLOAT, GL_FALSE, sizeof(GpuMeshVertex),
                        reinterpret_cast<void*>(offsetof(GpuMeshVertex, source_tint)));
}

bool InitGl(GlResources* gl) {
  gl->initialised = true;
  std::string error;
  if (!BuildProgram(kMeshVertexShader, kMeshFragmentShader, "mesh shader", &gl->mesh_program, &error) ||
      !BuildProgram(kLineVertexShader, kLineFragmentShader, "line shader", &gl->line_program, &error) ||
      !BuildProgram(kPhotoVertexShader, kPhotoFragmentShader, "photo shader", &gl->photo_program, &error)) {
    gl->error = error;
    return false;
  }
  gl->mesh_atlas = glGetUniformLocation(gl->mesh_program.id, "u_atlas");
  gl->mesh_use_texture = glGetUniformLocation(gl->mesh_program.id, "u_use_texture");
  gl->mesh_eye = glGetUniformLocation(gl->mesh_program.id, "u_eye");
  gl->mesh_show_sources = glGetUniformLocation(gl->mesh_program.id, "u_show_sources");
  gl->line_fade = glGetUniformLocation(gl->line_program.id, "u_fade");
  gl->line_lighten_dark = glGetUniformLocation(gl->line_program.id, "u_lighten_dark");
  gl->line_fade_center = glGetUniformLocation(gl->line_program.id, "u_fade_center");
  gl->line_fade_radius = glGetUniformLocation(gl->line_program.id, "u_fade_radius");
  gl->line_eye = glGetUniformLocation(gl->line_program.id, "u_eye");
  gl->line_fade_eye_distance = glGetUniformLocation(gl->line_program.id, "u_fade_eye_distance");
  gl->photo_sampler = glGetUniformLocation(gl->photo_program.id, "u_photo");
  gl->photo_alpha = glGetUniformLocation(gl->photo_program.id, "u_alpha");

  GLint saved_vao = 0, saved_buffer = 0;
  glGetIntegerv(GL_VERTEX_ARRAY_BINDING, &saved_vao);
  glGetIntegerv(GL_ARRAY_BUFFER_BINDING, &saved_buffer);
  glGenVertexArrays(1, &gl->mesh_vao);
  glGenBuffers(1, &gl->mesh_vbo);
  glBindVertexArray(gl->mesh_vao);
  glBindBuffer(GL_ARRAY_BUFFER, gl->mesh_vbo);
  SetupMeshAttributes();
  glGenVertexArrays(1, &gl->lines_vao);
  glGenBuffers(1, &gl->lines_vbo);
  glBindVertexArray(gl->lines_vao);
  glBindBuffer(GL_ARRAY_BUFFER, gl->lines_vbo);
  SetupLineAttributes();
  glGenVertexArrays(1, &gl->photos_vao);
  glGenBuffers(1, &gl->photos_vbo);
  glBindVertexArray(gl->photos_vao);
  glBindBuffer(GL_ARRAY_BUFFER, gl->photos_vbo);
  SetupPhotoAttributes();
  glBindVertexArray(static_cast<GLuint>(saved_vao));
  glBindBuffer(GL_ARRAY_BUFFER, static_cast<GLuint>(saved_buffer));

  // Lines wider than one pixel are an error in forward-compatible contexts.
  GLint flags = 0;
  glGetIntegerv(GL_CONTEXT_FLAGS, &flags);
  GLfloat range[2] = {1.0f, 1.0f};
  glGetFloatv(GL_ALIASED_LINE_WIDTH_RANGE, range);
  gl->wide_lines = (flags & GL_CONTEXT_FLAG_FORWARD_COMPATIBLE_BIT) == 0 && range[1] >= 2.0f;
  const char* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
  const std::string renderer_name = renderer ? renderer : "";
  const bool software = renderer_name.find("llvmpipe") != std::string::npos ||
                        renderer_name.find("softpipe") != std::string::npos ||
                        renderer_name.find("SwiftShader") != std::string::npos;
  gl->msaa_samples = software ? 1 : kMsaaSamplesHardware;
  while (glGetError() != GL_NO_ERROR) {
  }
  return true;
}

void ReleaseGl(GlResources* gl) {
  if (!gl->initialised) return;
  for (Program* p : {&gl->mesh_program, &gl->line_program, &gl->photo_program}) {
    if (p->id) glDeleteProgram(p->id);
  }
  for (GLuint* vao : {&gl->mesh_vao, &gl->lines_vao, &gl->photos_vao}) {
    if (*vao) glDeleteVertexArrays(1, vao);
  }
  for (GLuint* buffer : {&gl->mesh_vbo, &gl->lines_vbo, &gl->photos_vbo}) {
    if (*buffer) glDeleteBuffers(1, buffer);
  }
  if (gl->atlas_texture) glDeleteTextures(1, &gl->atlas_texture);
  for (auto& [id, photo] : gl->photo_textures) {
    if (photo.texture) glDeleteTextures(1, &photo.texture);
  }
  gl->target.Release();
  gl->photo_textures.clear();
  gl->initialised = false;
}

// ---------------------------------------------------------------------------------------
// Uploads (only when their source changed)

// Per triangle of the mesh, the colour of the photo that gave most of its face's texture
// (TextureSourceColour), alpha 0 where no photo did: what View > Texture sources draws.
std::vector<std::array<float, 4>> SourceTints(const AppState& state) {
  const Project& project = state.document.project();
  std::map<std::pair<Id, FaceId>, std::array<float, 4>> by_face;
  for (const FaceTextureReport& report : state.last_bake.faces) {
    if (report.sources.empty()) continue;
    for (size_t i = 0; i < project.images.size(); ++i) {
      if (project.images[i].id != report.sources.front().image_id) continue;
      const std::array<std::uint8_t, 3> c = TextureSourceColour(i);
      by_face[{report.primitive_id, report.face}] = {c[0] / 255.0f, c[1] / 255.0f, c[2] / 255.0f, 1.0f};
    }
  }
  const TexturedMesh& mesh = state.mesh;
  std::vector<std::array<float, 4>> tints(mesh.triangle_face.size(), {0.0f, 0.0f, 0.0f, 0.0f});
  for (size_t t = 0; t < tints.size() && t < mesh.triangle_primitive.size(); ++t) {
    const auto it = by_face.find({mesh.triangle_primitive[t], mesh.triangle_face[t]});
    if (it != by_face.end()) tints[t] = it->second;
  }
  return tints;
}

// `geometry`, when given, replaces the mesh's positions and normals (the same triangles moved:
// the Solver steps window's stepped state keeps the document's texture). `tints`: per
// triangle, View > Texture sources' colour (SourceTints), or empty.
void UploadMesh(const TexturedMesh& mesh, const TexturedMesh* geometry, const std::vector<std::array<float, 4>>& tints,
                std::uint64_t revision,
                std::uint64_t atlas_revision, GlResources* gl) {
  // Triangles are expanded to their own vertices so that "textured" can be per triangle.
  std::vector<GpuMeshVertex> vertices;
  const size_t triangle_count = mesh.indices.size() / 3;
  vertices.reserve(triangle_count * 3);
  const std::vector<Eigen::Vector3f>& positions = geometry != nullptr ? geometry->positions : mesh.positions;
  const std::vector<Eigen::Vector3f>& normals = geometry != nullptr ? geometry->normals : mesh.normals;
  const bool has_normals = normals.size() == positions.size();
  const bool has_uvs = mesh.uvs.size() == mesh.positions.size();
  const bool has_atlas = !mesh.atlas.empty();
  for (size_t t = 0; t < triangle_count; ++t) {
    std::uint32_t idx[3] = {mesh.indices[3 * t], mesh.indices[3 * t + 1], mesh.indices[3 * t + 2]};
    if (idx[0] >= positions.size() || idx[1] >= positions.size() || idx[2] >= positions.size()) continue;
    Eigen::Vector3f face_normal =
        (positions[idx[1]] - positions[idx[0]]).cross(positions[idx[2]] - positions[idx[0]]);
    face_normal = face_normal.norm() > 0 ? face_normal.normalized() : Eigen::Vector3f::UnitZ();
    const bool textured = has_atlas && has_uvs && t < mesh.triangle_textured.size() && mesh.triangle_textured[t] != 0;
    for (std::uint32_t i : idx) {
      GpuMeshVertex v{};
      const Eigen::Vector3f& p = positions[i];
      const Eigen::Vector3f n = has_normals ? normals[i] : face_normal;
      v.position[0] = p.x(), v.position[1] = p.y(), v.position[2] = p.z();
      v.normal[0] = n.x(), v.normal[1] = n.y(), v.normal[2] = n.z();
      if (has_uvs) v.uv[0] = mesh.uvs[i].x(), v.uv[1] = mesh.uvs[i].y();
      v.textured = textured ? 1.0f : 0.0f;
      if (t < tints.size()) std::copy(tints[t].begin(), tints[t].end(), v.source_tint);
      vertices.push_back(v);
    }
  }
  glBindBuffer(GL_ARRAY_BUFFER, gl->mesh_vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(GpuMeshVertex)),
               vertices.empty() ? nullptr : vertices.data(), GL_STATIC_DRAW);
  gl->mesh_vertex_count = static_cast<GLsizei>(vertices.size());
  // During a drag only positions change; the atlas is uploaded only when it is new.
  if (!gl->mesh_uploaded || gl->atlas_revision != atlas_revision) {
    if (gl->atlas_texture) glDeleteTextures(1, &gl->atlas_texture);
    gl->atlas_texture = UploadGlTextureRgba8(mesh.atlas, /*mipmaps=*/true);
    gl->atlas_revision = atlas_revision;
  }
  gl->mesh_uploaded = true;
  gl->mesh_revision = revision;
}

// Makes a texture for each loaded photo that has none yet (at most one per frame: the
// downsampling of a large photo takes a few tens of ms), and drops those of photos gone.
void UpdatePhotoTextures(const AppState& state, GlResources* gl) {
  for (auto it = gl->photo_textures.begin(); it != gl->photo_textures.end();) {
    const auto photo = state.photos.find(it->first);
    const bool stale = photo == state.photos.end() || photo->second.width != it->second.source_width ||
                       photo->second.height != it->second.source_height ||
                       photo->second.pixels.data() != it->second.source_pixels;
    if (stale) {
      if (it->second.texture) glDeleteTextures(1, &it->second.texture);
      it = gl->photo_textures.erase(it);
    } else {
      ++it;
    }
  }
  for (const auto& [id, image] : state.photos) {
    if (image.empty() || gl->photo_textures.count(id)) continue;
    PhotoTexture photo;
    photo.texture = UploadGlTextureRgba8(DownsampleRgba8(image, kMaxPhotoTextureSide), /*mipmaps=*/true);
    photo.source_width = image.width;
    photo.source_height = image.height;
    photo.source_pixels = image.pixels.data();
    gl->photo_textures[id] = photo;
    break;
  }
}

SceneMeasure MeasureScene(const Project& project) {
  SceneMeasure m;
  Eigen::AlignedBox3d box_bounds;
  for (const Primitive& primitive : project.primitives) {
    for (VertexId v = 0; v < primitive.mesh.VertexIdEnd(); ++v) {
      if (primitive.mesh.IsVertex(v)) box_bounds.extend(primitive.mesh.vertex(v).position);
    }
  }
  Eigen::AlignedBox3d all_bounds = box_bounds;
  for (const Image& image : project.images) {
    if (image.camera_calibrated) all_bounds.extend(image.camera.CenterInWorld());
  }
  if (all_bounds.isEmpty()) all_bounds.extend(Eigen::Vector3d::Zero());
  m.bounds.center = all_bounds.center();
  m.bounds.radius = std::max(0.5 * all_bounds.diagonal().norm(), 1e-3);
  if (box_bounds.isEmpty() && all_bounds.diagonal().norm() < 1e-9) m.bounds.radius = 1.0;
  m.size = box_bounds.isEmpty() ? 2.0 * m.bounds.radius : std::max(box_bounds.diagonal().norm(), 1e-3);
  m.frame_bounds = m.bounds;
  if (!box_bounds.isEmpty()) {
    m.frame_bounds.center = box_bounds.center();
    constexpr double kFrameMargin = 1.2;  // room around the model, for its outline and handles
    m.frame_bounds.radius = std::max(kFrameMargin * 0.5 * box_bounds.diagonal().norm(), 1e-3);
  }
  m.frustum_depth = 0.2 * m.size;

  // Grid steps are powers of ten: 4 to 40 minor cells across the scene, major every ten.
  m.grid_minor = std::pow(10.0, std::floor(std::log10(m.size / 4.0)));
  m.grid_major = 10.0 * m.grid_minor;
  m.grid_center = Eigen::Vector3d(std::round(m.bounds.center.x() / m.grid_major) * m.grid_major,
                                  std::round(m.bounds.center.y() / m.grid_major) * m.grid_major, 0.0);
  const double reach = m.bounds.radius + (m.bounds.center.head<2>() - m.grid_center.head<2>()).norm();
  m.grid_half_extent = std::max(2.0, std::ceil(2.0 * reach / m.grid_major)) * m.grid_major;
  // Keep the minor lines to a few hundred.
  while (2.0 * m.grid_half_extent / m.grid_minor > 400.0) m.grid_minor *= 2.0;
  return m;
}

void PushLine(std::vector<LineVertex>* lines, const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Rgba& color) {
  for (const Eigen::Vector3d* p : {&a, &b}) {
    LineVertex v{};
    v.position[0] = static_cast<float>(p->x());
    v.position[1] = static_cast<float>(p->y());
    v.position[2] = static_cast<float>(p->z());
    std::copy(color.begin(), color.end(), v.rgba);
    lines->push_back(v);
  }
}

// The four image corners of a camera at `depth` in front of it, in world: top-left,
// top-right, bottom-right, bottom-left (pixel edges, so the quad covers the whole photo).
std::array<Eigen::Vector3d, 4> ImagePlaneCorners(const Camera& camera, double depth) {
  const double w = camera.width_px, h = camera.height_px;
  const std::array<Eigen::Vector2d, 4> corners_px = {Eigen::Vector2d(-0.5, -0.5), Eigen::Vector2d(w - 0.5, -0.5),
                                                     Eigen::Vector2d(w - 0.5, h - 0.5), Eigen::Vector2d(-0.5, h - 0.5)};
  std::array<Eigen::Vector3d, 4> out;
  const Eigen::Matrix3d world_from_cam = camera.cam_from_world_rotation.transpose();
  for (int i = 0; i < 4; ++i) {
    const Eigen::Vector3d p_in_cam((corners_px[i].x() - camera.principal_point_px.x()) / camera.focal_px * depth,
                                   (corners_px[i].y() - camera.principal_point_px.y()) / camera.focal_px * depth,
                                   depth);
    out[i] = world_from_cam * p_in_cam + camera.CenterInWorld();
  }
  return out;
}

// The image's camera with its size filled in from the image when calibration left it unset.
Camera CameraOf(const Image& image) {
  Camera camera = image.camera;
  if (camera.width_px <= 0 || camera.height_px <= 0) {
    camera.width_px = image.width_px;
    camera.height_px = image.height_px;
  }
  return camera;
}

bool Drawable(const Image& image) {
  const Camera camera = CameraOf(image);
  return image.camera_calibrated && camera.width_px > 0 && camera.height_px > 0 && camera.focal_px > 0;
}

// The project the panel draws: the Solver steps window's stepped state while it steps, else
// the document's.
const Project& ShownProject(const AppState& state) {
  const Project* stepped = TeachSteppedProject(state);
  return stepped != nullptr ? *stepped : state.document.project();
}

void BuildSceneGeometry(const AppState& state, const SceneMeasure& measure, Id photo_view_id, GlResources* gl) {
  const Project& project = ShownProject(state);
  std::vector<LineVertex> lines;
  auto begin_range = [&](DrawRange* range) { range->first = static_cast<GLint>(lines.size()); };
  auto end_range = [&](DrawRange* range) { range->count = static_cast<GLsizei>(lines.size()) - range->first; };

  // Outlines: the meshes' edges, so polygons show without their triangles' diagonals.
  begin_range(&gl->box_edges);
  for (const Primitive& primitive : project.primitives) {
    const PolyMesh& mesh = primitive.mesh;
    const Rgba& color = primitive.id == state.selection.primitive_id ? kSelectedBoxEdgeColor : kBoxEdgeColor;
    for (EdgeId e = 0; e < mesh.EdgeIdEnd(); ++e) {
      if (!mesh.IsEdge(e)) continue;
      PushLine(&lines, mesh.vertex(mesh.Origin(2 * e)).position, mesh.vertex(mesh.Dest(2 * e)).position, color);
    }
  }
  end_range(&gl->box_edges);

  // Reference meshes (app/state/reference_edits.h): faces as triangles, then their outlines.
  auto visible_references = [&](auto&& each) {
    for (const Reference& reference : project.references) {
      const auto loaded = state.references.find(reference.id);
      if (reference.visible && loaded != state.references.end()) each(loaded->second.mesh);
    }
  };
  begin_range(&gl->reference_faces);
  visible_references([&](const ReferenceMesh& mesh) {
    for (const auto& t : mesh.triangles) {
      PushLine(&lines, mesh.positions[t[0]], mesh.positions[t[1]], kReferenceFaceColor);
      LineVertex third = lines.back();  // PushLine gives two corners; the third shares their colour
      for (int k = 0; k < 3; ++k) third.position[k] = static_cast<float>(mesh.positions[t[2]][k]);
      lines.push_back(third);
    }
  });
  end_range(&gl->reference_faces);
  begin_range(&gl->reference_edges);
  visible_references([&](const ReferenceMesh& mesh) {
    for (const auto& e : mesh.edges) PushLine(&lines, mesh.positions[e[0]], mesh.positions[e[1]], kReferenceEdgeColor);
  });
  end_range(&gl->reference_edges);

  std::vector<PhotoVertex> photo_vertices;
  gl->cameras.clear();
  gl->active_frustum = DrawRange();
  begin_range(&gl->frustums);
  for (const Image& image : project.images) {
    if (!Drawable(image) || image.id == photo_view_id) continue;
    const bool active = image.id == state.active_image_id;
    const size_t first = lines.size();
    const Camera camera = CameraOf(image);
    const Eigen::Vector3d apex = camera.CenterInWorld();
    // Proportional to the scene, but never reaching far into it from a close camera.
    const double depth = std::min(measure.frustum_depth, 0.4 * (apex - measure.bounds.center).norm() + 1e-9);
    const std::array<Eigen::Vector3d, 4> corners = ImagePlaneCorners(camera, depth);
    const Rgba& color = active ? kActiveFrustumColor : kFrustumColor;
    for (int i = 0; i < 4; ++i) {
      PushLine(&lines, apex, corners[i], color);
      PushLine(&lines, corners[i], corners[(i + 1) % 4], color);
    }
    // A small tick above the top edge tells which way is up in the photo.
    const Eigen::Vector3d top_mid = 0.5 * (corners[0] + corners[1]);
    const Eigen::Vector3d up = (corners[0] - corners[3]).normalized() * 0.12 * (corners[1] - corners[0]).norm();
    PushLine(&lines, corners[0] + 0.35 * (corners[1] - corners[0]), top_mid + up, color);
    PushLine(&lines, top_mid + up, corners[0] + 0.65 * (corners[1] - corners[0]), color);
    if (active) gl->active_frustum = {static_cast<GLint>(first), static_cast<GLsizei>(lines.size() - first)};

    CameraDraw draw;
    draw.image_id = image.id;
    draw.photo_first = static_cast<GLint>(photo_vertices.size());
    const float uvs[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    for (int i = 0; i < 4; ++i) {
      PhotoVertex v{};
      v.position[0] = static_cast<float>(corners[i].x());
      v.position[1] = static_cast<float>(corners[i].y());
      v.position[2] = static_cast<float>(corners[i].z());
      v.uv[0] = uvs[i][0], v.uv[1] = uvs[i][1];
      photo_vertices.push_back(v);
    }
    gl->cameras.push_back(draw);
  }
  end_range(&gl->frustums);

  begin_range(&gl->axes);
  const double axis_length = 0.35 * measure.size;
  PushLine(&lines, Eigen::Vector3d::Zero(), axis_length * Eigen::Vector3d::UnitX(), kAxisX);
  PushLine(&lines, Eigen::Vector3d::Zero(), axis_length * Eigen::Vector3d::UnitY(), kAxisY);
  PushLine(&lines, Eigen::Vector3d::Zero(), axis_length * Eigen::Vector3d::UnitZ(), kAxisZ);
  end_range(&gl->axes);

  // Grid on z = 0; lines through the origin are left to the axes where they overlap.
  const double half = measure.grid_half_extent;
  const Eigen::Vector3d& c = measure.grid_center;
  const int minor_steps = static_cast<int>(std::lround(half / measure.grid_minor));
  const double major_every = measure.grid_major / measure.grid_minor;
  auto is_major = [&](int i) {
    const double k = (c.x() / measure.grid_minor + i) / major_every;  // same phase on x and y: c is a major multiple
    return std::abs(k - std::round(k)) < 1e-6;
  };
  for (int pass = 0; pass < 2; ++pass) {
    DrawRange* range = pass == 0 ? &gl->grid_minor : &gl->grid_major;
    begin_range(range);
    for (int i = -minor_steps; i <= minor_steps; ++i) {
      if (is_major(i) != (pass == 1)) continue;
      const double offset = i * measure.grid_minor;
      const Rgba& color = pass == 0 ? kGridMinor : kGridMajor;
      PushLine(&lines, {c.x() + offset, c.y() - half, 0.0}, {c.x() + offset, c.y() + half, 0.0}, color);
      PushLine(&lines, {c.x() - half, c.y() + offset, 0.0}, {c.x() + half, c.y() + offset, 0.0}, color);
    }
    end_range(range);
  }

  glBindBuffer(GL_ARRAY_BUFFER, gl->lines_vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(lines.size() * sizeof(LineVertex)),
               lines.empty() ? nullptr : lines.data(), GL_STATIC_DRAW);

  // The background quad of a photo view: a unit square the draw maps onto the photo's rect.
  gl->background.first = static_cast<GLint>(photo_vertices.size());
  const float unit[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  for (const auto& corner : unit) {
    PhotoVertex v{};
    v.position[0] = corner[0], v.position[1] = corner[1];
    v.uv[0] = corner[0], v.uv[1] = corner[1];
    photo_vertices.push_back(v);
  }
  gl->background.count = 4;
  glBindBuffer(GL_ARRAY_BUFFER, gl->photos_vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(photo_vertices.size() * sizeof(PhotoVertex)),
               photo_vertices.data(), GL_STATIC_DRAW);
  gl->scene_built = true;
}

// ---------------------------------------------------------------------------------------
// The frame

struct ViewSetup {
  Camera camera;  // the facet camera of the view (panel-sized for the orbit)
  GlCameraMatrices gl;
  glm::dmat4 clip_from_world = glm::dmat4(1.0);
  Eigen::Vector3d eye = Eigen::Vector3d::Zero();
  int width_px = 1, height_px = 1;
};

ViewSetup MakeView(const OrbitCamera& orbit, const SceneMeasure& measure, int width_px, int height_px) {
  ViewSetup view;
  view.width_px = width_px;
  view.height_px = height_px;
  view.camera = ViewCameraOf(orbit, width_px, height_px);
  view.eye = view.camera.CenterInWorld();
  // Depth range: everything drawn lies within the sphere holding the scene and the grid.
  const double grid_reach = measure.grid_half_extent * std::sqrt(2.0);
  const Eigen::Vector3d all_center = 0.5 * (measure.bounds.center + measure.grid_center);
  const double all_radius = 0.5 * (measure.bounds.center - measure.grid_center).norm() +
                            std::max(measure.bounds.radius + measure.frustum_depth * 2.0, grid_reach);
  const double eye_to_center = (view.eye - all_center).norm();
  const double far_depth = std::max(eye_to_center + all_radius, 1e-3);
  const double closest =
      std::min(eye_to_center - measure.bounds.radius - measure.frustum_depth * 2.0, std::abs(view.eye.z()));
  const double near_depth = std::max(far_depth * 2e-4, 0.5 * closest);
  view.gl = GlMatricesFromCamera(view.camera, width_px, height_px, near_depth, far_depth);
  view.clip_from_world = view.gl.projection * view.gl.view;
  return view;
}

// Panel pixel (from its top-left, continuous: pixel edges at integers) of a world point, or
// false when it is behind the eye.
bool PanelPixelOf(const ViewSetup& view, const Eigen::Vector3d& p_in_world, ImVec2* out) {
  const glm::dvec4 clip = view.clip_from_world * HomogeneousGlm(p_in_world);
  if (clip.w <= 1e-9) return false;
  const double x = (clip.x / clip.w + 1.0) * 0.5 * view.width_px;
  const double y = (1.0 - clip.y / clip.w) * 0.5 * view.height_px;
  *out = ImVec2(static_cast<float>(x), static_cast<float>(y));
  return true;
}

void SetLineWidth(const GlResources& gl, float width) {
  if (gl.wide_lines) glLineWidth(width);
}

void RenderScene(const AppState& state, const PanelState& panel, const ViewSetup& view, const SceneMeasure& measure) {
  const GlResources& gl = panel.gl;
  const glm::dmat4& clip_from_world = view.clip_from_world;
  const Eigen::Vector3f eye = view.eye.cast<float>();

  glDisable(GL_SCISSOR_TEST);
  glDisable(GL_CULL_FACE);
  glEnable(GL_MULTISAMPLE);
  glClearColor(0.145f, 0.155f, 0.175f, 1.0f);
  glDepthMask(GL_TRUE);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glBlendEquation(GL_FUNC_ADD);
  glBlendFuncSeparate(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA, GL_ONE, GL_ONE_MINUS_SRC_ALPHA);
  glActiveTexture(GL_TEXTURE0);

  // Viewing through a photo: the photo fills its (fitted) rect behind everything.
  if (panel.orbit.photo_image_id != kNoId) {
    const auto photo = gl.photo_textures.find(panel.orbit.photo_image_id);
    if (photo != gl.photo_textures.end()) {
      const double s = view.gl.image_scale;
      const double x0 = view.gl.image_offset_px.x, y0 = view.gl.image_offset_px.y;
      const double x1 = x0 + s * view.camera.width_px, y1 = y0 + s * view.camera.height_px;
      // Unit square (x right, y down) onto the rect in NDC (y up).
      glm::dmat4 ndc_from_unit(1.0);  // [column][row]
      ndc_from_unit[0][0] = 2.0 * (x1 - x0) / view.width_px;
      ndc_from_unit[3][0] = 2.0 * x0 / view.width_px - 1.0;
      ndc_from_unit[1][1] = -2.0 * (y1 - y0) / view.height_px;
      ndc_from_unit[3][1] = 1.0 - 2.0 * y0 / view.height_px;
      glDisable(GL_DEPTH_TEST);
      glDisable(GL_BLEND);
      glUseProgram(gl.photo_program.id);
      SetMatrix(gl.photo_program.clip_from_world, ndc_from_unit);
      glUniform1i(gl.photo_sampler, 0);
      glUniform1f(gl.photo_alpha, 1.0f);
      glBindTexture(GL_TEXTURE_2D, photo->second.texture);
      glBindVertexArray(gl.photos_vao);
      glDrawArrays(GL_TRIANGLE_FAN, gl.background.first, gl.background.count);
    }
  }

  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);

  // The grid first, without writing depth, so that it never hides what stands on it.
  glEnable(GL_BLEND);
  glUseProgram(gl.line_program.id);
  SetMatrix(gl.line_program.clip_from_world, clip_from_world);
  glUniform3f(gl.line_eye, eye.x(), eye.y(), eye.z());
  glUniform1i(gl.line_lighten_dark, 0);
  glBindVertexArray(gl.lines_vao);
  if (panel.show_grid) {
    glDepthMask(GL_FALSE);
    glUniform1i(gl.line_fade, 1);
    glUniform3f(gl.line_fade_center, static_cast<float>(measure.grid_center.x()),
                static_cast<float>(measure.grid_center.y()), 0.0f);
    glUniform1f(gl.line_fade_radius, static_cast<float>(measure.grid_half_extent));
    // Lines fade before their spacing shrinks to a few pixels.
    glUniform1f(gl.line_fade_eye_distance, static_cast<float>(measure.grid_minor * 250.0));
    glDrawArrays(GL_LINES, gl.grid_minor.first, gl.grid_minor.count);
    glUniform1f(gl.line_fade_eye_distance, static_cast<float>(measure.grid_major * 250.0));
    glDrawArrays(GL_LINES, gl.grid_major.first, gl.grid_major.count);
    glDepthMask(GL_TRUE);
  }
  glUniform1i(gl.line_fade, 0);

  // The mesh, pushed back a little so that the outlines drawn on its faces win.
  if (panel.show_mesh && gl.mesh_vertex_count > 0) {
    glDisable(GL_BLEND);
    glEnable(GL_POLYGON_OFFSET_FILL);
    glPolygonOffset(1.0f, 1.0f);
    glUseProgram(gl.mesh_program.id);
    SetMatrix(gl.mesh_program.clip_from_world, clip_from_world);
    glUniform3f(gl.mesh_eye, eye.x(), eye.y(), eye.z());
    glUniform1i(gl.mesh_atlas, 0);
    glUniform1i(gl.mesh_use_texture, panel.show_texture && gl.atlas_texture != 0 ? 1 : 0);
    glUniform1i(gl.mesh_show_sources, state.texture.show_sources ? 1 : 0);
    glBindTexture(GL_TEXTURE_2D, gl.atlas_texture);
    glBindVertexArray(gl.mesh_vao);
    glDrawArrays(GL_TRIANGLES, 0, gl.mesh_vertex_count);
    glDisable(GL_POLYGON_OFFSET_FILL);
    glEnable(GL_BLEND);
  }

  // Photos on their frustums' image planes.
  if (panel.show_cameras && !gl.cameras.empty()) {
    glUseProgram(gl.photo_program.id);
    SetMatrix(gl.photo_program.clip_from_world, clip_from_world);
    glUniform1i(gl.photo_sampler, 0);
    glUniform1f(gl.photo_alpha, 0.92f);
    glBindVertexArray(gl.photos_vao);
    for (const CameraDraw& camera : gl.cameras) {
      const auto photo = gl.photo_textures.find(camera.image_id);
      if (photo == gl.photo_textures.end() || photo->second.texture == 0) continue;
      glBindTexture(GL_TEXTURE_2D, photo->second.texture);
      glDrawArrays(GL_TRIANGLE_FAN, camera.photo_first, 4);
    }
  }

  glUseProgram(gl.line_program.id);
  glBindVertexArray(gl.lines_vao);
  // Reference geometry: see-through, so it never hides the model or the photo behind it, and
  // without writing depth, so overlapping faces of it do not hide each other.
  if (gl.reference_faces.count > 0 || gl.reference_edges.count > 0) {
    glDepthMask(GL_FALSE);
    glDrawArrays(GL_TRIANGLES, gl.reference_faces.first, gl.reference_faces.count);
    glDrawArrays(GL_LINES, gl.reference_edges.first, gl.reference_edges.count);
    glDepthMask(GL_TRUE);
  }
  if (panel.show_wireframe) {
    glUniform1i(gl.line_lighten_dark, panel.show_mesh && gl.mesh_vertex_count > 0 ? 0 : 1);
    glDrawArrays(GL_LINES, gl.box_edges.first, gl.box_edges.count);
    glUniform1i(gl.line_lighten_dark, 0);
  }
  // After the outlines: a first box usually sits at the origin, its edges along the axes.
  SetLineWidth(gl, 2.5f);
  glDrawArrays(GL_LINES, gl.axes.first, gl.axes.count);
  SetLineWidth(gl, 1.0f);
  if (panel.show_cameras) {
    glDrawArrays(GL_LINES, gl.frustums.first, gl.frustums.count);
    if (gl.active_frustum.count > 0) {
      SetLineWidth(gl, 2.5f);
      glDrawArrays(GL_LINES, gl.active_frustum.first, gl.active_frustum.count);
      SetLineWidth(gl, 1.0f);
    }
  }
}

// ---------------------------------------------------------------------------------------
// Interaction

// The pick ray of a panel pixel, unprojected with the same matrices the frame used.
PickRay RayOf(const ViewSetup& view, ImVec2 pixel_in_panel) {
  PickRay ray;
  const glm::dmat4 world_from_clip = glm::inverse(view.clip_from_world);
  const double ndc_x = 2.0 * pixel_in_panel.x / view.width_px - 1.0;
  const double ndc_y = 1.0 - 2.0 * pixel_in_panel.y / view.height_px;
  const glm::dvec4 near_h = world_from_clip * glm::dvec4(ndc_x, ndc_y, -1.0, 1.0);
  const glm::dvec4 far_h = world_from_clip * glm::dvec4(ndc_x, ndc_y, 1.0, 1.0);
  const glm::dvec3 origin = glm::dvec3(near_h) / near_h.w;
  ray.origin = ToEigen(origin);
  ray.direction = ToEigen(glm::normalize(glm::dvec3(far_h) / far_h.w - origin));
  ray.clip_from_world = view.clip_from_world;
  ray.width_px = view.width_px;
  ray.height_px = view.height_px;
  ray.mouse_px = Eigen::Vector2d(pixel_in_panel.x, pixel_in_panel.y);
  return ray;
}

bool FramePressed(const ImGuiIO& io) {
  if (io.WantTextInput || io.KeyCtrl || io.KeyAlt || io.KeySuper) return false;
  // Letters use their upper-case ASCII code as key index (GLFW's codes, also in offscreen mode).
  if (ImGui::IsKeyPressed('F', false)) return true;
  for (ImWchar c : io.InputQueueCharacters) {
    if (c == 'f' || c == 'F') return true;
  }
  return false;
}

std::string ImageLabel(const Project& project, const Image& image) {
  size_t index = 0;
  while (index < project.images.size() && project.images[index].id != image.id) ++index;
  std::string name = image.path;
  const size_t slash = name.find_last_of("/\\");
  if (slash != std::string::npos) name = name.substr(slash + 1);
  return "Image " + std::to_string(index + 1) + ": " + name;
}

void DrawToolbar(AppState* state, PanelState* panel, const SceneMeasure& measure, int width_px, int height_px) {
  const Project& project = state->document.project();
  if (ImGui::SmallButton("Frame")) {
    OrbitFrame(&panel->orbit, measure.frame_bounds, width_px, height_px);
    panel->framed_bounds = measure.frame_bounds;
  }
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Frame the model's primitives (F, or double-click)");
  ImGui::SameLine();
  std::string preview = "View from photo";
  if (panel->orbit.photo_image_id != kNoId) {
    if (const Image* image = project.FindImage(panel->orbit.photo_image_id)) preview = ImageLabel(project, *image);
  }
  // The "Show" button keeps its room; the combo takes what is left, up to a comfortable width.
  const float show_width = ImGui::CalcTextSize("Show").x + 2.0f * ImGui::GetStyle().FramePadding.x;
  ImGui::SetNextItemWidth(
      std::clamp(ImGui::GetContentRegionAvail().x - show_width - ImGui::GetStyle().ItemSpacing.x, 80.0f, 260.0f));
  // As tall as the small buttons beside it.
  ImGui::PushStyleVar(ImGuiStyleVar_FramePadding, ImVec2(ImGui::GetStyle().FramePadding.x, 0.0f));
  const bool combo_open = ImGui::BeginCombo("##view_from_photo", preview.c_str());
  ImGui::PopStyleVar();
  if (combo_open) {
    bool any = false;
    for (const Image& image : project.images) {
      if (!Drawable(image)) continue;
      any = true;
      const std::string label = ImageLabel(project, image);
      ImGui::PushID(static_cast<int>(image.id));
      if (ImGui::Selectable(label.c_str(), panel->orbit.photo_image_id == image.id)) {
        OrbitViewFromPhoto(&panel->orbit, image.id, CameraOf(image), measure.bounds);
      }
      ImGui::PopID();
    }
    if (!any) ImGui::TextDisabled("No calibrated image yet");
    ImGui::EndCombo();
  }
  if (ImGui::IsItemHovered()) ImGui::SetTooltip("Look through a calibrated photo's camera");
  ImGui::SameLine();
  if (ImGui::SmallButton("Show")) ImGui::OpenPopup("##viewport_show");
  if (ImGui::BeginPopup("##viewport_show")) {
    ImGui::Checkbox("Mesh", &panel->show_mesh);
    ImGui::Checkbox("Texture", &panel->show_texture);
    ImGui::Checkbox("Mesh edges", &panel->show_wireframe);
    ImGui::Checkbox("Cameras and photos", &panel->show_cameras);
    ImGui::Checkbox("Ground grid", &panel->show_grid);
    // Reference meshes (File > Add reference mesh...): shown or hidden, removed; each an edit.
    const std::vector<Reference> references = state->document.project().references;
    if (!references.empty()) {
      ImGui::Separator();
      ImGui::TextDisabled("Reference meshes");
    }
    for (const Reference& reference : references) {
      ImGui::PushID(static_cast<int>(reference.id));
      bool visible = reference.visible;
      const std::string name = std::filesystem::path(reference.path).filename().string();
      if (ImGui::Checkbox(name.c_str(), &visible)) SetReferenceVisibleEdit(state, reference.id, visible);
      RecordItem(state, "viewport.reference." + std::to_string(reference.id));
      const auto loaded = state->references.find(reference.id);
      if (ImGui::IsItemHovered())
        ImGui::SetTooltip("%s", loaded != state->references.end() && !loaded->second.error.empty()
                                    ? loaded->second.error.c_str()
                                    : reference.path.c_str());
      ImGui::SameLine();
      if (ImGui::SmallButton("Remove")) RemoveReferenceEdit(state, reference.id);
      RecordItem(state, "viewport.reference_remove." + std::to_string(reference.id));
      ImGui::PopID();
    }
    ImGui::EndPopup();
  }
}

// Where DrawOverlay put its texts (screen px; empty when not drawn), for the item report.
struct OverlayTextRects {
  Rect help;         // counts and mouse help, bottom left
  Rect bake_status;  // "baking texture...", right above the help
  Rect tool_hint;    // the Move tool's hint, above those
};

void DrawOverlay(const AppState& state, const PanelState& panel, const ViewSetup& view, ImVec2 origin, ImVec2 size,
                 ImVec2 view_scale, OverlayTextRects* text_rects) {
  ImDrawList* draw = ImGui::GetWindowDrawList();
  draw->PushClipRect(origin, ImVec2(origin.x + size.x, origin.y + size.y), true);
  const Project& project = ShownProject(state);

  // The selected, hovered and V_connect-start elements: faces tinted, edges thick, vertices
  // as dots and rings (drawn over the rendered picture, so hidden ones show too).
  auto to_screen = [&](const Eigen::Vector3d& p, ImVec2* out) {
    ImVec2 px;
    if (!PanelPixelOf(view, p, &px)) return false;
    *out = ImVec2(origin.x + px.x / view_scale.x, origin.y + px.y / view_scale.y);
    return true;
  };
  auto draw_element = [&](const ElementRef& ref, ImU32 color, bool strong) {
    const Primitive* primitive = project.FindPrimitive(ref.primitive_id);
    if (primitive == nullptr || !ElementExists(project, ref)) return;
    const PolyMesh& mesh = primitive->mesh;
    ImVec2 a, b;
    switch (ref.kind) {
      case ElementKind::kVertex:
        if (!to_screen(mesh.vertex(ref.element).position, &a)) return;
        if (strong) draw->AddCircleFilled(a, 5.5f, color);
        draw->AddCircle(a, strong ? 6.5f : 8.0f, strong ? IM_COL32(20, 20, 20, 255) : color, 0, strong ? 1.5f : 2.0f);
        break;
      case ElementKind::kEdge:
        if (!to_screen(mesh.vertex(mesh.Origin(2 * ref.element)).position, &a) ||
            !to_screen(mesh.vertex(mesh.Dest(2 * ref.element)).position, &b)) {
          return;
        }
        draw->AddLine(a, b, color, strong ? 4.0f : 3.0f);
        break;
      case ElementKind::kFace: {
        std::vector<ImVec2> polygon;
        for (VertexId v : FaceVertices(mesh, ref.element)) {
          if (!to_screen(mesh.vertex(v).position, &a)) return;
          polygon.push_back(a);
        }
        const ImU32 fill = (color & ~IM_COL32_A_MASK) | IM_COL32(0, 0, 0, strong ? 80 : 50);
        // Faces are convex or nearly (K-ops keep convex parts convex); the outline is exact.
        draw->AddConvexPolyFilled(polygon.data(), static_cast<int>(polygon.size()), fill);
        draw->AddPolyline(polygon.data(), static_cast<int>(polygon.size()), color, ImDrawFlags_Closed, 2.0f);
        break;
      }
      case ElementKind::kNone: break;
    }
  };
  const ImU32 kSelectedColor = IM_COL32(255, 160, 40, 255);
  const ImU32 kHoverColor = IM_COL32(255, 235, 90, 255);
  draw_element(state.selection.element, kSelectedColor, true);
  for (const ElementRef& extra : state.selection.extra) draw_element(extra, kSelectedColor, true);
  if (!(state.selection.connect_from == state.selection.element))
    draw_element(state.selection.connect_from, kSelectedColor, true);
  if (!(state.hover == state.selection.element)) draw_element(state.hover, kHoverColor, false);
  // Free vertices: cyan rings, so that the user sees what the solve may move.
  for (const Primitive& primitive : project.primitives) {
    for (VertexId v = 0; v < primitive.mesh.VertexIdEnd(); ++v) {
      ImVec2 p;
      if (primitive.mesh.IsVertex(v) && primitive.mesh.vertex(v).local.free &&
          to_screen(primitive.mesh.vertex(v).position, &p)) {
        draw->AddCircle(p, 4.5f, IM_COL32(80, 230, 255, 255), 0, 2.0f);
      }
    }
  }

  // Vertices whose pin the last solve flagged as a likely wrong click: red rings, so that the
  // 3D view points at the same corner the image panel marks.
  for (const FlaggedPin& flagged : state.last_update.joint.flagged_pins) {
    const auto pin =
        std::find_if(project.pins.begin(), project.pins.end(), [&](const Pin& p) { return p.id == flagged.pin_id; });
    if (pin == project.pins.end() || project.FindVertex(pin->vertex) == nullptr) continue;
    ImVec2 p;
    if (!to_screen(VertexInWorld(project, pin->vertex), &p)) continue;
    draw->AddCircle(p, 9.0f, IM_COL32(0, 0, 0, 200), 0, 4.0f);
    draw->AddCircle(p, 9.0f, IM_COL32(255, 50, 50, 255), 0, 2.5f);
  }

  if (panel.picture_only) {  // File > Export view: the model, not the UI's help
    draw->PopClipRect();
    return;
  }
  // Help and counts in the bottom-left corner.
  char counts[128];
  std::snprintf(counts, sizeof(counts), "%zu vertices \xc2\xb7 %zu triangles", state.mesh.positions.size(),
                state.mesh.indices.size() / 3);
  const float line_h = ImGui::GetTextLineHeight();
  const ImVec2 help_size = ImGui::CalcTextSize(kHelpText);
  const ImVec2 counts_size = ImGui::CalcTextSize(counts);
  const float pad = 6.0f;
  const ImVec2 box_min(origin.x + pad, origin.y + size.y - pad - 2 * line_h - 6.0f);
  const ImVec2 box_max(box_min.x + std::max(help_size.x, counts_size.x) + 8.0f, origin.y + size.y - pad);
  draw->AddRectFilled(box_min, box_max, IM_COL32(0, 0, 0, 110), 3.0f);
  draw->AddText(ImVec2(box_min.x + 4.0f, box_min.y + 2.0f), IM_COL32(230, 230, 230, 230), counts);
  draw->AddText(ImVec2(box_min.x + 4.0f, box_min.y + 2.0f + line_h + 2.0f), IM_COL32(200, 200, 200, 200), kHelpText);
  text_rects->help = {box_min.x, box_min.y, box_max.x - box_min.x, box_max.y - box_min.y};

  // Status lines stack upwards from the help box, each in its own row, so none covers another.
  float row_bottom = box_min.y - 2.0f;
  auto draw_row = [&](const char* text, ImU32 color, ImU32 background) {
    const ImVec2 text_size = ImGui::CalcTextSize(text);
    const ImVec2 row_min(box_min.x, row_bottom - line_h - 6.0f);
    const ImVec2 row_max(row_min.x + text_size.x + 8.0f, row_bottom);
    draw->AddRectFilled(row_min, row_max, background, 3.0f);
    draw->AddText(ImVec2(row_min.x + 4.0f, row_min.y + 3.0f), color, text);
    row_bottom = row_min.y - 2.0f;
    return Rect{row_min.x, row_min.y, row_max.x - row_min.x, row_max.y - row_min.y};
  };
  // The texture catching up with an edit in the background.
  if (BakeInFlight(state)) {
    text_rects->bake_status = draw_row("baking texture...", IM_COL32(200, 200, 200, 230), IM_COL32(0, 0, 0, 110));
  }
  if (state.tool == Tool::kMove) {  // the Move tool's help, or what the drag did
    const std::string hint = MoveToolHint(panel.move_drag);
    text_rects->tool_hint = draw_row(hint.c_str(), IM_COL32(255, 210, 60, 255), IM_COL32(0, 0, 0, 140));
  }
  if (panel.orbit.photo_image_id != kNoId) {
    if (const Image* image = project.FindImage(panel.orbit.photo_image_id)) {
      const std::string label = "Viewing from " + ImageLabel(project, *image);
      draw->AddText(ImVec2(origin.x + pad + 2.0f, origin.y + pad), IM_COL32(255, 210, 60, 255), label.c_str());
    }
  }
  draw->PopClipRect();
}

// Where the panel's canvas is this frame and what the mouse does on it.
struct CanvasFrame {
  ImVec2 origin{0, 0};                   // screen position of the canvas's top-left
  ImVec2 size{16, 16};                   // screen px
  float scale_x = 1.0f, scale_y = 1.0f;  // framebuffer px per screen px
  int width_px = 1, height_px = 1;       // framebuffer px
  bool hovered = false, active = false;
  bool left_pressed = false;  // the left button went down on the canvas this frame
  ImVec2 mouse_px{0, 0};      // the mouse in framebuffer px from the canvas's top-left
  ImVec2 delta_px{0, 0};      // the mouse's motion this frame, framebuffer px
};

// Frames the model when a project shows up (first frame, another file, first content); a
// photo view of an image that lost its calibration (or was deleted) falls back to the orbit.
void FollowProject(const AppState& state, PanelState* panel, const SceneMeasure& measure, int width_px, int height_px) {
  const Project& project = state.document.project();
  const bool has_content =
      !project.primitives.empty() || std::any_of(project.images.begin(), project.images.end(), Drawable);
  const bool has_primitives = !project.primitives.empty();
  // Large edits reframe: the first primitive, or a model that grew, shrank or moved a lot
  // since the last framing. Not during a drag (the user is placing something), nor while
  // looking through a photo; otherwise the user's own orbit stays.
  const bool large_edit = !state.drag_start && ((has_primitives && !panel->had_primitives) ||
                                                (has_primitives && NeedsReframe(panel->framed_bounds, measure.frame_bounds)));
  const bool new_document = !panel->framed_once || panel->framed_generation != state.document_generation;
  if (new_document) {
    // Another project: the default orbit direction, out of any photo view (its image ids
    // start again), framed on the new model.
    panel->orbit = OrbitCamera();
  }
  if (new_document || (has_content && !panel->had_content) || large_edit) {
    if (panel->orbit.photo_image_id == kNoId) OrbitFrame(&panel->orbit, measure.frame_bounds, width_px, height_px);
    panel->framed_once = true;
    panel->framed_generation = state.document_generation;
    panel->framed_bounds = measure.frame_bounds;
  }
  panel->had_content = has_content;
  if (!state.drag_start) panel->had_primitives = has_primitives;
  if (panel->orbit.photo_image_id != kNoId) {
    const Image* image = project.FindImage(panel->orbit.photo_image_id);
    if (!image || !Drawable(*image)) {
      OrbitLeavePhotoView(&panel->orbit, width_px, height_px);
    } else {
      panel->orbit.photo_camera = CameraOf(*image);  // follow re-calibration
    }
  }
}

// The canvas is an invisible button so that drags on it do not move the window.
// The canvas's place and framebuffer size, before its button is submitted.
CanvasFrame PlaceCanvas(ImVec2 size, float scale_x, float scale_y) {
  CanvasFrame frame;
  frame.size = size;
  frame.scale_x = scale_x;
  frame.scale_y = scale_y;
  frame.width_px = std::max(1, static_cast<int>(std::lround(size.x * scale_x)));
  frame.height_px = std::max(1, static_cast<int>(std::lround(size.y * scale_y)));
  frame.origin = ImGui::GetCursorScreenPos();
  return frame;
}

// Submits the canvas's button and reads the mouse over it.
void ReadCanvasInput(PanelState* panel, CanvasFrame* frame) {
  const ImGuiIO& io = ImGui::GetIO();
  ImGui::InvisibleButton(
      "##viewport_canvas", frame->size,
      ImGuiButtonFlags_MouseButtonLeft | ImGuiButtonFlags_MouseButtonRight | ImGuiButtonFlags_MouseButtonMiddle);
  frame->hovered = ImGui::IsItemHovered();
  frame->active = ImGui::IsItemActive();
  const ImVec2 mouse(io.MousePos.x - frame->origin.x, io.MousePos.y - frame->origin.y);
  frame->mouse_px = ImVec2(mouse.x * frame->scale_x, mouse.y * frame->scale_y);
  frame->delta_px = ImVec2(io.MouseDelta.x * frame->scale_x, io.MouseDelta.y * frame->scale_y);
  frame->left_pressed = ImGui::IsItemActivated() && ImGui::IsMouseClicked(ImGuiMouseButton_Left);
  if (frame->left_pressed) {
    panel->left_pressed_here = true;
    panel->left_press_pos = io.MousePos;
  }
}

// Orbit (left drag, unless the Move tool holds the mouse), pan (right or middle drag), zoom
// (wheel), frame (double click, F, or a request) and view-from-photo requests.
void HandleViewGestures(const Project& project, PanelState* panel, const SceneMeasure& measure,
                        const CanvasFrame& frame) {
  const ImGuiIO& io = ImGui::GetIO();
  const int width_px = frame.width_px, height_px = frame.height_px;
  const ImVec2 delta_px = frame.delta_px;
  if (frame.active && !MoveToolOwnsMouse(panel->move_drag) &&
      ImGui::IsMouseDragging(ImGuiMouseButton_Left, kClickSlopPx) && (delta_px.x != 0 || delta_px.y != 0)) {
    OrbitRotate(&panel->orbit, delta_px.x, delta_px.y, width_px, height_px);
  }
  if (frame.active &&
      (ImGui::IsMouseDragging(ImGuiMouseButton_Right, 1.0f) || ImGui::IsMouseDragging(ImGuiMouseButton_Middle, 1.0f)) &&
      (delta_px.x != 0 || delta_px.y != 0)) {
    OrbitPan(&panel->orbit, delta_px.x, delta_px.y, width_px, height_px);
  }
  if (frame.hovered && io.MouseWheel != 0.0f) OrbitZoom(&panel->orbit, io.MouseWheel, width_px, height_px);
  if ((frame.hovered && ImGui::IsMouseDoubleClicked(ImGuiMouseButton_Left)) ||
      ((frame.hovered || frame.active) && FramePressed(io)) || panel->frame_requested) {
    OrbitFrame(&panel->orbit, measure.frame_bounds, width_px, height_px);
    panel->framed_bounds = measure.frame_bounds;
  }
  panel->frame_requested = false;
  if (panel->view_from_photo_requested != kNoId) {
    const Image* image = project.FindImage(panel->view_from_photo_requested);
    if (image && Drawable(*image)) OrbitViewFromPhoto(&panel->orbit, image->id, CameraOf(*image), measure.bounds);
    panel->view_from_photo_requested = kNoId;
  }
}

// Hover and clicks: the element under the cursor for the current tool (select picks
// everything); a click (not a drag) applies the tool to it, or clears the selection. With the
// Move tool a press on an element drags it (app/state/move_tool.h).
void HandlePicking(AppState* state, PanelState* panel, const ViewSetup& view, const CanvasFrame& frame) {
  const ImGuiIO& io = ImGui::GetIO();
  const Project& project = state->document.project();
  const PickFilter filter = state->tool == Tool::kMove ? MoveToolPickFilter() : PickFilterOf(state->tool);
  const double radius_px = kPickRadiusPx * frame.scale_x;
  if (state->tool == Tool::kMove || MoveToolOwnsMouse(panel->move_drag)) {
    MoveToolInput move;
    move.ray = RayOf(view, frame.mouse_px);
    move.pressed = frame.left_pressed && frame.hovered;
    if (move.pressed) move.pressed_on = PickByRay(project, move.ray, filter, radius_px);
    move.released = ImGui::IsMouseReleased(ImGuiMouseButton_Left);
    move.shift = io.KeyShift;
    move.no_snap = io.KeyAlt;
    move.cancel = ImGui::IsKeyPressed(ImGui::GetKeyIndex(ImGuiKey_Escape), false);
    MoveToolFrame(state, &panel->move_drag, move);
  }
  const bool picking = frame.hovered && !ImGui::IsMouseDragging(ImGuiMouseButton_Left, kClickSlopPx) &&
                       (filter.vertices || filter.edges || filter.faces);
  panel->hovered = picking ? PickByRay(project, RayOf(view, frame.mouse_px), filter, radius_px) : ElementPick();
  if (frame.hovered) {
    state->hover = panel->hovered.element;
    state->hover_panel = kViewportHover;
  } else if (state->hover_panel == kViewportHover) {
    state->hover = {};
    state->hover_panel = 0;
  }
  if (panel->left_pressed_here && ImGui::IsMouseReleased(ImGuiMouseButton_Left)) {
    panel->left_pressed_here = false;
    const float dx = io.MousePos.x - panel->left_press_pos.x, dy = io.MousePos.y - panel->left_press_pos.y;
    if (dx * dx + dy * dy <= kClickSlopPx * kClickSlopPx && frame.hovered && !state->drag_start) {
      const ElementPick picked = PickByRay(project, RayOf(view, frame.mouse_px), filter, radius_px);
      if (!ApplyToolClick(state, picked.element, picked.t) && state->tool == Tool::kSelect) state->selection = {};
    }
  }
}

// GL work: uploads when their sources changed, then the frame into the panel's target.
// Returns false (after drawing the message) when the target cannot be made.
bool RenderToTarget(const AppState& state, PanelState* panel, const ViewSetup& view, const SceneMeasure& measure,
                    const CanvasFrame& frame) {
  GlResources& gl = panel->gl;
  const SavedGlState saved = SavedGlState::Capture();
  if (TeachSteppedProject(state) != nullptr) {
    // Revisions of the stepped mesh have the top bit set, so they never equal the document's;
    // a new texture of the document (a bake that finished) is uploaded with the next one.
    const TexturedMesh& stepped = state.teach.solver.mesh;
    const std::uint64_t revision =
        (std::uint64_t{1} << 63) | ((state.teach.solver.mesh_revision << 32) ^ state.mesh_revision);
    if (!gl.mesh_uploaded || gl.mesh_revision != revision) {
      const bool same_triangles = stepped.positions.size() == state.mesh.positions.size() &&
                                  stepped.triangle_face == state.mesh.triangle_face &&
                                  stepped.triangle_primitive == state.mesh.triangle_primitive;
      UploadMesh(same_triangles ? state.mesh : stepped, same_triangles ? &stepped : nullptr,
                 same_triangles ? SourceTints(state) : std::vector<std::array<float, 4>>(), revision,
                 state.atlas_revision, &gl);
    }
  } else if (!gl.mesh_uploaded || gl.mesh_revision != state.mesh_revision) {
    UploadMesh(state.mesh, nullptr, SourceTints(state), state.mesh_revision, state.atlas_revision, &gl);
  }
  UpdatePhotoTextures(state, &gl);
  // The project may have changed (a tool click): read it again.
  const Project& current = ShownProject(state);
  SceneKey key{current.primitives,           current.images,
               state.active_image_id,        state.selection.primitive_id,
               panel->orbit.photo_image_id, current.references,
               state.reference_revision};
  if (!gl.scene_built || !(key == gl.scene_key)) {
    BuildSceneGeometry(state, measure, panel->orbit.photo_image_id, &gl);
    gl.scene_key = std::move(key);
  }
  std::string target_error;
  if (!gl.target.Ensure(frame.width_px, frame.height_px, gl.msaa_samples, &target_error)) {
    saved.Restore();
    ImGui::GetWindowDrawList()->AddText(frame.origin, IM_COL32(255, 100, 100, 255), target_error.c_str());
    return false;
  }
  gl.target.BindForDrawing();
  RenderScene(state, *panel, view, measure);
  gl.target.Resolve();
  saved.Restore();
  return true;
}

}  // namespace

void DrawViewportPanel(AppState* state, ViewportPanelState* owner) {
  PanelState& panel = Panel(owner);
  GlResources& gl = panel.gl;
  const ImGuiIO& io = ImGui::GetIO();

  if (!gl.initialised) {
    const SavedGlState saved = SavedGlState::Capture();
    InitGl(&gl);
    saved.Restore();
  }
  if (!gl.error.empty()) {
    ImGui::TextColored(ImVec4(1.0f, 0.4f, 0.4f, 1.0f), "3D view unavailable: %s", gl.error.c_str());
    return;
  }

  const SceneMeasure measure = MeasureScene(state->document.project());
  const ImVec2 avail_before_toolbar = ImGui::GetContentRegionAvail();
  const float scale_x = io.DisplayFramebufferScale.x > 0 ? io.DisplayFramebufferScale.x : 1.0f;
  const float scale_y = io.DisplayFramebufferScale.y > 0 ? io.DisplayFramebufferScale.y : 1.0f;
  // The toolbar needs the view size for framing; the toolbar's own height is small, so the
  // size before it is a fine approximation for that one click.
  DrawToolbar(state, &panel, measure, std::max(1, static_cast<int>(avail_before_toolbar.x * scale_x)),
              std::max(1, static_cast<int>(avail_before_toolbar.y * scale_y)));

  const ImVec2 size(std::max(ImGui::GetContentRegionAvail().x, 16.0f),
                    std::max(ImGui::GetContentRegionAvail().y, 16.0f));
  CanvasFrame frame = PlaceCanvas(size, scale_x, scale_y);
  FollowProject(*state, &panel, measure, frame.width_px, frame.height_px);
  ReadCanvasInput(&panel, &frame);
  HandleViewGestures(state->document.project(), &panel, measure, frame);

  const ViewSetup view = MakeView(panel.orbit, measure, frame.width_px, frame.height_px);
  panel.report.drawn = true;
  panel.report.origin_x = frame.origin.x;
  panel.report.origin_y = frame.origin.y;
  panel.report.width_px = frame.width_px;
  panel.report.height_px = frame.height_px;
  for (int i = 0; i < 16; ++i) panel.report.clip_from_world[i] = glm::value_ptr(view.clip_from_world)[i];
  HandlePicking(state, &panel, view, frame);

  if (!RenderToTarget(*state, &panel, view, measure, frame)) return;
  // A GL texture's first row is the bottom of the picture: flip V.
  ImGui::GetWindowDrawList()->AddImage(ToImTexture(gl.target.color_texture()), frame.origin,
                                       ImVec2(frame.origin.x + size.x, frame.origin.y + size.y), ImVec2(0, 1),
                                       ImVec2(1, 0));
  OverlayTextRects text_rects;
  DrawOverlay(*state, panel, view, frame.origin, size, ImVec2(scale_x, scale_y), &text_rects);
  if (text_rects.help.w > 0.0f) state->item_rects["viewport.help"] = text_rects.help;
  if (text_rects.bake_status.w > 0.0f) state->item_rects["viewport.bake_status"] = text_rects.bake_status;
  if (text_rects.tool_hint.w > 0.0f) state->item_rects["viewport.tool_hint"] = text_rects.tool_hint;
  if (state->texture.show_sources) {
    ImDrawList* draw = ImGui::GetWindowDrawList();
    draw->PushClipRect(frame.origin, ImVec2(frame.origin.x + size.x, frame.origin.y + size.y), true);
    DrawTextureSourceLegend(draw, *state, frame.origin, size);
    draw->PopClipRect();
  }
  if (state->teach.vanishing_points || state->teach.epipolar || state->teach.solver_steps) {  // View > Teach
    ImDrawList* draw = ImGui::GetWindowDrawList();
    draw->PushClipRect(frame.origin, ImVec2(frame.origin.x + size.x, frame.origin.y + size.y), true);
    DrawTeachViewportOverlay(draw, *state, 0.5 * measure.size, [&](const Eigen::Vector3d& p, ImVec2* out) {
      ImVec2 px;
      if (!PanelPixelOf(view, p, &px)) return false;
      *out = ImVec2(frame.origin.x + px.x / scale_x, frame.origin.y + px.y / scale_y);
      return true;
    });
    draw->PopClipRect();
  }
}

void RequestViewportFrame(ViewportPanelState* panel) { Panel(panel).frame_requested = true; }

void ShowViewportPictureOnly(ViewportPanelState* panel) { Panel(panel).picture_only = true; }

void CopyViewportView(const ViewportPanelState& from, ViewportPanelState* to) {
  PanelState& out = Panel(to);
  if (!from.impl) return;
  const PanelState& in = *from.impl;
  out.orbit = in.orbit;
  out.framed_once = in.framed_once;
  out.framed_generation = in.framed_generation;
  out.had_content = in.had_content;
  out.framed_bounds = in.framed_bounds;
  out.had_primitives = in.had_primitives;
  out.show_texture = in.show_texture;
  out.show_mesh = in.show_mesh;
  out.show_wireframe = in.show_wireframe;
  out.show_cameras = in.show_cameras;
  out.show_grid = in.show_grid;
}

ViewportReport LastViewportReport(const ViewportPanelState& panel) {
  return panel.impl ? panel.impl->report : ViewportReport();
}

void RequestViewportViewFromPhoto(ViewportPanelState* panel, Id image_id) {
  Panel(panel).view_from_photo_requested = image_id;
}

void ShutdownViewportPanel(ViewportPanelState* panel) {
  if (!panel->impl) return;
  ReleaseGl(&panel->impl->gl);
  panel->impl.reset();
}

}  // namespace facet::app
