// A COLMAP binary model writer for the tests only (Facet writes text models): the byte layout
// of core/io/colmap_model_binary.cpp, so the binary reader can be compared with the text
// reader on one model, and broken files can be cut from a good one.
#pragma once

#include <cstring>
#include <string>

#include "core/io/colmap_model.h"

namespace facet::testing {

template <typename T>
void AppendBytes(std::string* out, T value) {
  char buffer[sizeof(T)];
  std::memcpy(buffer, &value, sizeof(T));
  out->append(buffer, sizeof(T));
}

inline std::string ColmapCamerasBinary(const ColmapModel& model) {
  std::string out;
  AppendBytes<std::uint64_t>(&out, model.cameras.size());
  for (const ColmapCamera& c : model.cameras) {
    AppendBytes<std::uint32_t>(&out, c.camera_id);
    AppendBytes<std::int32_t>(&out, static_cast<std::int32_t>(c.model));
    AppendBytes<std::uint64_t>(&out, c.width_px);
    AppendBytes<std::uint64_t>(&out, c.height_px);
    for (double p : c.params) AppendBytes<double>(&out, p);
  }
  return out;
}

inline std::string ColmapImagesBinary(const ColmapModel& model) {
  std::string out;
  AppendBytes<std::uint64_t>(&out, model.images.size());
  for (const ColmapImage& image : model.images) {
    AppendBytes<std::uint32_t>(&out, image.image_id);
    const Eigen::Quaterniond& q = image.cam_from_world_rotation;
    for (double v : {q.w(), q.x(), q.y(), q.z()}) AppendBytes<double>(&out, v);
    for (int k = 0; k < 3; ++k) AppendBytes<double>(&out, image.cam_from_world_translation[k]);
    AppendBytes<std::uint32_t>(&out, image.camera_id);
    out.append(image.name);
    out.push_back('\0');
    AppendBytes<std::uint64_t>(&out, image.points2d.size());
    for (const ColmapPoint2D& p : image.points2d) {
      AppendBytes<double>(&out, p.xy_px.x());
      AppendBytes<double>(&out, p.xy_px.y());
      AppendBytes<std::uint64_t>(&out, p.point3d_id);
    }
  }
  return out;
}

inline std::string ColmapPoints3DBinary(const ColmapModel& model) {
  std::string out;
  AppendBytes<std::uint64_t>(&out, model.points3d.size());
  for (const ColmapPoint3D& p : model.points3d) {
    AppendBytes<std::uint64_t>(&out, p.point3d_id);
    for (int k = 0; k < 3; ++k) AppendBytes<double>(&out, p.position[k]);
    for (std::uint8_t c : p.rgb) AppendBytes<std::uint8_t>(&out, c);
    AppendBytes<double>(&out, p.error_px);
    AppendBytes<std::uint64_t>(&out, p.track.size());
    for (const ColmapTrackElement& e : p.track) {
      AppendBytes<std::uint32_t>(&out, e.image_id);
      AppendBytes<std::uint32_t>(&out, e.point2d_index);
    }
  }
  return out;
}

}  // namespace facet::testing
