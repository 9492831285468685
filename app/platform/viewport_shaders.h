// GLSL sources of the 3D panel (app/panels/viewport_panel.cpp): the textured or shaded mesh, the
// coloured lines (outlines, frustums, axes, a grid that fades out) and the photos.
#pragma once

namespace facet::app {

constexpr const char* kMeshVertexShader = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec2 a_uv;
layout(location = 3) in float a_textured;
layout(location = 4) in vec4 a_source_tint;
uniform mat4 u_clip_from_world;
out vec3 v_position;
out vec3 v_normal;
out vec2 v_uv;
out float v_textured;
out vec4 v_source_tint;
void main() {
  v_position = a_position;
  v_normal = a_normal;
  v_uv = a_uv;
  v_textured = a_textured;
  v_source_tint = a_source_tint;
  gl_Position = u_clip_from_world * vec4(a_position, 1.0);
}
)";

// Textured faces show the atlas nearly unlit (it already holds the photo's shading); the
// others are a neutral grey lit by a headlight plus a fixed key light, so that faces of a
// box differ in tone from any viewpoint. With u_show_sources (View > Texture sources) a face
// with a source photo shows that photo's colour over the texture's brightness, so the photo's
// content stays readable under the tint.
constexpr const char* kMeshFragmentShader = R"(#version 330 core
in vec3 v_position;
in vec3 v_normal;
in vec2 v_uv;
in float v_textured;
in vec4 v_source_tint;
uniform sampler2D u_atlas;
uniform int u_use_texture;
uniform int u_show_sources;
uniform vec3 u_eye;
out vec4 frag_color;
void main() {
  vec3 n = normalize(v_normal);
  vec3 to_eye = normalize(u_eye - v_position);
  if (dot(n, to_eye) < 0.0) n = -n;
  float head = max(dot(n, to_eye), 0.0);
  float key = max(dot(n, normalize(vec3(0.45, 0.3, 0.85))), 0.0);
  float light = 0.25 + 0.5 * head + 0.25 * key;
  if (u_show_sources != 0 && v_source_tint.a > 0.5) {
    float luma = v_textured > 0.5 ? dot(texture(u_atlas, v_uv).rgb, vec3(0.299, 0.587, 0.114)) : 0.6;
    frag_color = vec4(v_source_tint.rgb * (0.45 + 0.75 * luma) * (0.75 + 0.25 * light), 1.0);
  } else if (u_use_texture != 0 && v_textured > 0.5) {
    vec3 albedo = texture(u_atlas, v_uv).rgb;
    frag_color = vec4(albedo * (0.8 + 0.2 * light), 1.0);
  } else {
    frag_color = vec4(vec3(0.70, 0.71, 0.72) * light, 1.0);
  }
}
)";

constexpr const char* kLineVertexShader = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec4 a_color;
uniform mat4 u_clip_from_world;
out vec4 v_color;
out vec3 v_position;
void main() {
  v_color = a_color;
  v_position = a_position;
  gl_Position = u_clip_from_world * vec4(a_position, 1.0);
}
)";

// The grid fades out towards its rim and, line family by line family, with distance from
// the eye (minor lines sooner), so that it never ends in a hard edge nor turns to moire.
constexpr const char* kLineFragmentShader = R"(#version 330 core
in vec4 v_color;
in vec3 v_position;
uniform int u_fade;
uniform vec3 u_fade_center;
uniform float u_fade_radius;
uniform vec3 u_eye;
uniform float u_fade_eye_distance;
uniform int u_lighten_dark;
out vec4 frag_color;
void main() {
  float alpha = v_color.a;
  vec3 rgb = v_color.rgb;
  // Outlines are dark to read on the mesh; with the mesh hidden they must read on the background.
  if (u_lighten_dark != 0 && max(rgb.r, max(rgb.g, rgb.b)) < 0.2) rgb = vec3(0.85);
  if (u_fade != 0) {
    float rim = length(v_position.xy - u_fade_center.xy) / u_fade_radius;
    alpha *= 1.0 - smoothstep(0.55, 1.0, rim);
    float eye = length(v_position - u_eye) / u_fade_eye_distance;
    alpha *= 1.0 - smoothstep(0.4, 1.0, eye);
  }
  if (alpha <= 0.002) discard;
  frag_color = vec4(rgb, alpha);
}
)";

constexpr const char* kPhotoVertexShader = R"(#version 330 core
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec2 a_uv;
uniform mat4 u_clip_from_world;
out vec2 v_uv;
void main() {
  v_uv = a_uv;
  gl_Position = u_clip_from_world * vec4(a_position, 1.0);
}
)";

constexpr const char* kPhotoFragmentShader = R"(#version 330 core
in vec2 v_uv;
uniform sampler2D u_photo;
uniform float u_alpha;
out vec4 frag_color;
void main() {
  frag_color = vec4(texture(u_photo, v_uv).rgb, u_alpha);
}
)";

}  // namespace facet::app
