#include "app/platform/gltf_camera_render.h"

#include <algorithm>
#include <cstddef>
#include <vector>

#include <glm/gtc/type_ptr.hpp>

#include "app/platform/egl_context.h"
#include "app/platform/gl_camera.h"
#include "app/platform/gl_util.h"
#include "app/platform/viewport_shaders.h"

namespace facet::app {
namespace {

// The 3D panel's mesh vertex layout (kMeshVertexShader's attributes 0-3).
struct MeshVertex {
  float position[3];
  float normal[3];
  float uv[2];
  float textured;
};

// Owns what one render makes, so every return path frees it.
struct GlObjects {
  GLuint program = 0, vao = 0, vbo = 0;
  std::vector<GLuint> textures;
  ~GlObjects() {
    for (GLuint t : textures)
      if (t) glDeleteTextures(1, &t);
    if (vbo) glDeleteBuffers(1, &vbo);
    if (vao) glDeleteVertexArrays(1, &vao);
    if (program) glDeleteProgram(program);
  }
};

}  // namespace

bool RenderGltfThroughCamera(const GltfScene& scene, int camera_index, ImageRgba8* out, std::string* error) {
  if (camera_index < 0 || camera_index >= static_cast<int>(scene.cameras.size())) {
    *error = "camera " + std::to_string(camera_index) + " does not exist (the file has " +
             std::to_string(scene.cameras.size()) + ")";
    return false;
  }
  const Camera& camera = scene.cameras[camera_index].camera;
  const int w = camera.width_px, h = camera.height_px;
  OffscreenTarget target;
  if (!target.Create(w, h, error)) return false;

  // Depth range from the model's extent along the optical axis, so nothing is clipped.
  double nearest = 1e300, farthest = 0.0;
  for (const Eigen::Vector3f& p : scene.positions) {
    const double z = camera.CamFromWorld(p.cast<double>()).z();
    nearest = std::min(nearest, z);
    farthest = std::max(farthest, z);
  }
  const double znear = scene.cameras[camera_index].znear;
  const double near_depth = std::max(znear > 0.0 ? znear : 1e-3, std::min(nearest, farthest) * 0.5);
  const double far_depth = std::max(near_depth * 2.0, farthest * 1.5);
  const GlCameraMatrices matrices = GlMatricesFromCamera(camera, w, h, near_depth, far_depth);
  const glm::mat4 clip_from_world(matrices.projection * matrices.view);

  GlObjects gl;
  gl.program = BuildGlProgram(kMeshVertexShader, kMeshFragmentShader, error);
  if (gl.program == 0) return false;
  for (const ImageRgba8& image : scene.images) gl.textures.push_back(UploadGlTextureRgba8(image, /*mipmaps=*/true));

  // One vertex run per batch, each triangle with its own vertices as the 3D panel uploads them.
  std::vector<MeshVertex> vertices;
  std::vector<std::pair<size_t, size_t>> runs;  // first vertex, count
  for (const GltfBatch& batch : scene.batches) {
    const size_t first = vertices.size();
    const bool textured = batch.image >= 0 && batch.image < static_cast<int>(gl.textures.size());
    for (std::uint32_t i : batch.indices) {
      MeshVertex v{};
      const Eigen::Vector3f& p = scene.positions[i];
      const Eigen::Vector3f& n = scene.normals[i];
      std::copy(p.data(), p.data() + 3, v.position);
      std::copy(n.data(), n.data() + 3, v.normal);
      v.uv[0] = scene.uvs[i].x();
      v.uv[1] = scene.uvs[i].y();
      v.textured = textured ? 1.0f : 0.0f;
      vertices.push_back(v);
    }
    runs.emplace_back(first, vertices.size() - first);
  }
  glGenVertexArrays(1, &gl.vao);
  glGenBuffers(1, &gl.vbo);
  glBindVertexArray(gl.vao);
  glBindBuffer(GL_ARRAY_BUFFER, gl.vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(vertices.size() * sizeof(MeshVertex)),
               vertices.empty() ? nullptr : vertices.data(), GL_STATIC_DRAW);
  const GLsizei stride = sizeof(MeshVertex);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<void*>(offsetof(MeshVertex, position)));
  glEnableVertexAttribArray(1);
  glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<void*>(offsetof(MeshVertex, normal)));
  glEnableVertexAttribArray(2);
  glVertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<void*>(offsetof(MeshVertex, uv)));
  glEnableVertexAttribArray(3);
  glVertexAttribPointer(3, 1, GL_FLOAT, GL_FALSE, stride, reinterpret_cast<void*>(offsetof(MeshVertex, textured)));

  target.Bind();
  glDisable(GL_BLEND);
  glDisable(GL_CULL_FACE);
  glDisable(GL_SCISSOR_TEST);
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LEQUAL);
  glDepthMask(GL_TRUE);
  glClearColor(0.0f, 0.0f, 0.0f, 0.0f);  // alpha 0 marks what no triangle covers
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glUseProgram(gl.program);
  glUniformMatrix4fv(glGetUniformLocation(gl.program, "u_clip_from_world"), 1, GL_FALSE,
                     glm::value_ptr(clip_from_world));
  const Eigen::Vector3f eye = camera.CenterInWorld().cast<float>();
  glUniform3f(glGetUniformLocation(gl.program, "u_eye"), eye.x(), eye.y(), eye.z());
  glUniform1i(glGetUniformLocation(gl.program, "u_atlas"), 0);
  glActiveTexture(GL_TEXTURE0);
  for (size_t b = 0; b < scene.batches.size(); ++b) {
    const int image = scene.batches[b].image;
    const bool textured = image >= 0 && image < static_cast<int>(gl.textures.size()) && gl.textures[image] != 0;
    glUniform1i(glGetUniformLocation(gl.program, "u_use_texture"), textured ? 1 : 0);
    glBindTexture(GL_TEXTURE_2D, textured ? gl.textures[image] : 0);
    glDrawArrays(GL_TRIANGLES, static_cast<GLint>(runs[b].first), static_cast<GLsizei>(runs[b].second));
  }
  glFinish();
  const GLenum gl_error = glGetError();
  if (gl_error != GL_NO_ERROR) {
    *error = "OpenGL error 0x" + std::to_string(gl_error) + " while rendering";
    return false;
  }
  *out = target.Read(/*keep_alpha=*/true);
  glBindVertexArray(0);
  return true;
}

}  // namespace facet::app
