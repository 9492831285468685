// COLMAP's text model (cameras.txt, images.txt, points3D.txt), as COLMAP 3.8 writes it:
// '#' comment lines, one record per line, images.txt two lines per image (the second, the 2D
// points, may be empty).
#include <charconv>
#include <cmath>
#include <string_view>
#include <vector>

#include "core/io/colmap_model.h"

namespace facet {
namespace {

std::vector<std::string_view> SplitWords(std::string_view line) {
  std::vector<std::string_view> words;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) words.push_back(line.substr(start, i - start));
  }
  return words;
}

bool ParseDouble(std::string_view word, double* value) {
  const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), *value);
  return ec == std::errc() && end == word.data() + word.size() && std::isfinite(*value);
}

template <typename Int>
bool ParseInt(std::string_view word, Int* value) {
  const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), *value);
  return ec == std::errc() && end == word.data() + word.size();
}

// The lines of `text` with their 1-based numbers; a final line without '\n' counts.
struct Lines {
  explicit Lines(const std::string& text) : text_(text) {}
  bool Next(std::string_view* line) {
    if (at_ >= text_.size()) return false;
    const size_t end = text_.find('\n', at_);
    const size_t stop = end == std::string::npos ? text_.size() : end;
    *line = std::string_view(text_).substr(at_, stop - at_);
    at_ = end == std::string::npos ? text_.size() : end + 1;
    ++number_;
    return true;
  }
  // The next line that is neither blank nor a comment.
  bool NextRecord(std::string_view* line) {
    while (Next(line)) {
      const size_t first = line->find_first_not_of(" \t\r");
      if (first != std::string_view::npos && (*line)[first] != '#') return true;
    }
    return false;
  }
  size_t number() const { return number_; }

 private:
  const std::string& text_;
  size_t at_ = 0;
  size_t number_ = 0;
};

std::string At(const std::string& file_name, size_t line) {
  return file_name + ", line " + std::to_string(line) + ": ";
}

}  // namespace

std::string ParseColmapCamerasText(const std::string& text, const std::string& file_name,
                                   std::vector<ColmapCamera>* cameras) {
  cameras->clear();
  Lines lines(text);
  std::string_view line;
  while (lines.NextRecord(&line)) {
    const std::string at = At(file_name, lines.number());
    const std::vector<std::string_view> words = SplitWords(line);
    if (words.size() < 4) return at + "a camera needs CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]";
    ColmapCamera camera;
    if (!ParseInt(words[0], &camera.camera_id)) return at + "bad camera id \"" + std::string(words[0]) + "\"";
    if (!ColmapCameraModelFromName(std::string(words[1]), &camera.model))
      return at + "unknown camera model \"" + std::string(words[1]) + "\"";
    if (!ParseInt(words[2], &camera.width_px) || !ParseInt(words[3], &camera.height_px) || camera.width_px == 0 ||
        camera.height_px == 0)
      return at + "bad image size";
    const size_t num_params = ColmapCameraModelNumParams(camera.model);
    if (words.size() != 4 + num_params)
      return at + ColmapCameraModelName(camera.model) + " has " + std::to_string(num_params) + " parameters, not " +
             std::to_string(words.size() - 4);
    camera.params.resize(num_params);
    for (size_t i = 0; i < num_params; ++i)
      if (!ParseDouble(words[4 + i], &camera.params[i]))
        return at + "bad parameter \"" + std::string(words[4 + i]) + "\"";
    if (cameras->size() >= kMaxColmapCameras) return at + "more than the most cameras a model may have";
    cameras->push_back(std::move(camera));
  }
  return "";
}

std::string ParseColmapImagesText(const std::string& text, const std::string& file_name,
                                  std::vector<ColmapImage>* images) {
  images->clear();
  Lines lines(text);
  std::string_view line;
  while (lines.NextRecord(&line)) {
    const std::string at = At(file_name, lines.number());
    const std::vector<std::string_view> words = SplitWords(line);
    if (words.size() < 10) return at + "an image needs IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME";
    ColmapImage image;
    if (!ParseInt(words[0], &image.image_id)) return at + "bad image id \"" + std::string(words[0]) + "\"";
    double v[7];
    for (int i = 0; i < 7; ++i)
      if (!ParseDouble(words[1 + i], &v[i])) return at + "bad pose number \"" + std::string(words[1 + i]) + "\"";
    const Eigen::Vector4d q(v[0], v[1], v[2], v[3]);
    if (!(q.norm() > 0.5 && q.norm() < 2.0)) return at + "the rotation quaternion is not of unit length";
    image.cam_from_world_rotation = Eigen::Quaterniond(v[0], v[1], v[2], v[3]);
    image.cam_from_world_translation = Eigen::Vector3d(v[4], v[5], v[6]);
    if (!ParseInt(words[8], &image.camera_id)) return at + "bad camera id \"" + std::string(words[8]) + "\"";
    // The name is the rest of the line (a file name may hold spaces), trailing blanks cut.
    const size_t name_start = static_cast<size_t>(words[9].data() - line.data());
    std::string_view name = line.substr(name_start);
    name = name.substr(0, name.find_last_not_of(" \t\r") + 1);
    image.name = std::string(name);
    // The 2D points line follows (empty for an image with none); a file ending here has none.
    std::string_view points_line;
    if (lines.Next(&points_line)) {
      const std::string points_at = At(file_name, lines.number());
      const std::vector<std::string_view> p = SplitWords(points_line);
      if (p.size() % 3 != 0) return points_at + "2D points come as X Y POINT3D_ID triples";
      image.points2d.resize(p.size() / 3);
      for (size_t k = 0; k < image.points2d.size(); ++k) {
        ColmapPoint2D& point = image.points2d[k];
        if (!ParseDouble(p[3 * k], &point.xy_px.x()) || !ParseDouble(p[3 * k + 1], &point.xy_px.y()))
          return points_at + "bad 2D point " + std::to_string(k);
        std::int64_t id = 0;
        if (!ParseInt(p[3 * k + 2], &id) || id < -1)
          return points_at + "bad 3D point id of 2D point " + std::to_string(k);
        point.point3d_id = id == -1 ? kColmapNoPoint3D : static_cast<std::uint64_t>(id);
      }
    }
    if (images->size() >= kMaxColmapImages) return at + "more than the most images a model may have";
    images->push_back(std::move(image));
  }
  return "";
}

std::string ParseColmapPoints3DText(const std::string& text, const std::string& file_name,
                                    std::vector<ColmapPoint3D>* points) {
  points->clear();
  Lines lines(text);
  std::string_view line;
  while (lines.NextRecord(&line)) {
    const std::string at = At(file_name, lines.number());
    const std::vector<std::string_view> words = SplitWords(line);
    if (words.size() < 8 || (words.size() - 8) % 2 != 0)
      return at + "a 3D point needs POINT3D_ID X Y Z R G B ERROR and IMAGE_ID POINT2D_IDX pairs";
    ColmapPoint3D point;
    if (!ParseInt(words[0], &point.point3d_id) || point.point3d_id == kColmapNoPoint3D)
      return at + "bad 3D point id \"" + std::string(words[0]) + "\"";
    for (int i = 0; i < 3; ++i)
      if (!ParseDouble(words[1 + i], &point.position[i]))
        return at + "bad coordinate \"" + std::string(words[1 + i]) + "\"";
    for (int i = 0; i < 3; ++i) {
      unsigned value = 0;
      if (!ParseInt(words[4 + i], &value) || value > 255)
        return at + "bad colour \"" + std::string(words[4 + i]) + "\"";
      point.rgb[i] = static_cast<std::uint8_t>(value);
    }
    if (!ParseDouble(words[7], &point.error_px)) return at + "bad error \"" + std::string(words[7]) + "\"";
    point.track.resize((words.size() - 8) / 2);
    for (size_t k = 0; k < point.track.size(); ++k)
      if (!ParseInt(words[8 + 2 * k], &point.track[k].image_id) ||
          !ParseInt(words[9 + 2 * k], &point.track[k].point2d_index))
        return at + "bad track element " + std::to_string(k);
    if (points->size() >= kMaxColmapPoints3D) return at + "more than the most 3D points a model may have";
    points->push_back(std::move(point));
  }
  return "";
}

}  // namespace facet
