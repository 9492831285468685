// COLMAP's binary model (cameras.bin, images.bin, points3D.bin), little-endian as COLMAP 3.8
// writes it:
//   cameras.bin   u64 count; per camera: u32 id, i32 model id, u64 width, u64 height, f64 params[]
//   images.bin    u64 count; per image: u32 id, f64 qw qx qy qz, f64 tx ty tz, u32 camera id,
//                 name as bytes ending in '\0', u64 number of 2D points, per point f64 x y, u64 3D id
//   points3D.bin  u64 count; per point: u64 id, f64 x y z, u8 r g b, f64 error, u64 track length,
//                 per element u32 image id, u32 2D point index
// Every count is checked against the bytes left (times the smallest record it announces)
// before anything is allocated for it.
#include <bit>
#include <cmath>
#include <cstring>

#include "core/io/colmap_model.h"

namespace facet {
namespace {

static_assert(std::endian::native == std::endian::little, "COLMAP's binary files are little-endian");

class Cursor {
 public:
  explicit Cursor(const std::string& bytes) : bytes_(bytes) {}
  template <typename T>
  bool Read(T* value) {
    if (bytes_.size() - at_ < sizeof(T)) return false;
    std::memcpy(value, bytes_.data() + at_, sizeof(T));
    at_ += sizeof(T);
    return true;
  }
  bool ReadFinite(double* value) { return Read(value) && std::isfinite(*value); }
  // A '\0'-terminated string of at most `max_length` bytes.
  bool ReadCString(std::string* value, size_t max_length) {
    const size_t end = bytes_.find('\0', at_);
    if (end == std::string::npos || end - at_ > max_length) return false;
    value->assign(bytes_, at_, end - at_);
    at_ = end + 1;
    return true;
  }
  // Whether `count` records of at least `min_record_bytes` each fit in what is left.
  bool Fits(std::uint64_t count, std::uint64_t min_record_bytes) const {
    return count <= (bytes_.size() - at_) / min_record_bytes;
  }
  size_t offset() const { return at_; }
  bool AtEnd() const { return at_ == bytes_.size(); }

 private:
  const std::string& bytes_;
  size_t at_ = 0;
};

std::string Truncated(const std::string& file_name, const char* what, std::uint64_t index, const Cursor& cursor) {
  return file_name + ": truncated or broken at byte " + std::to_string(cursor.offset()) + " (" + what + " " +
         std::to_string(index) + ")";
}

std::string CountTooLarge(const std::string& file_name, const char* what, std::uint64_t count) {
  return file_name + ": announces " + std::to_string(count) + " " + what + ", more than the file can hold";
}

std::string TrailingBytes(const std::string& file_name, const Cursor& cursor) {
  return file_name + ": unexpected bytes after the last record, at byte " + std::to_string(cursor.offset());
}

// The smallest records: a camera with no parameters, an image with a one-byte name ('\0') and
// no points, a 2D point, a 3D point with an empty track, a track element.
constexpr std::uint64_t kMinCameraBytes = 4 + 4 + 8 + 8;
constexpr std::uint64_t kMinImageBytes = 4 + 7 * 8 + 4 + 1 + 8;
constexpr std::uint64_t kPoint2DBytes = 8 + 8 + 8;
constexpr std::uint64_t kMinPoint3DBytes = 8 + 3 * 8 + 3 + 8 + 8;
constexpr std::uint64_t kTrackElementBytes = 4 + 4;
constexpr size_t kMaxNameBytes = 4096;

}  // namespace

std::string ParseColmapCamerasBinary(const std::string& bytes, const std::string& file_name,
                                     std::vector<ColmapCamera>* cameras) {
  cameras->clear();
  Cursor in(bytes);
  std::uint64_t count = 0;
  if (!in.Read(&count)) return file_name + ": too short for the number of cameras";
  if (count > kMaxColmapCameras || !in.Fits(count, kMinCameraBytes)) return CountTooLarge(file_name, "cameras", count);
  cameras->reserve(count);
  for (std::uint64_t i = 0; i < count; ++i) {
    ColmapCamera camera;
    std::int32_t model_id = 0;
    if (!in.Read(&camera.camera_id) || !in.Read(&model_id)) return Truncated(file_name, "camera", i, in);
    if (!ColmapCameraModelFromId(model_id, &camera.model))
      return file_name + ": camera " + std::to_string(camera.camera_id) + " has unknown camera model id " +
             std::to_string(model_id);
    if (!in.Read(&camera.width_px) || !in.Read(&camera.height_px)) return Truncated(file_name, "camera", i, in);
    if (camera.width_px == 0 || camera.height_px == 0)
      return file_name + ": camera " + std::to_string(camera.camera_id) + " has an empty image size";
    camera.params.resize(ColmapCameraModelNumParams(camera.model));
    for (double& p : camera.params)
      if (!in.ReadFinite(&p)) return Truncated(file_name, "camera", i, in);
    cameras->push_back(std::move(camera));
  }
  if (!in.AtEnd()) return TrailingBytes(file_name, in);
  return "";
}

std::string ParseColmapImagesBinary(const std::string& bytes, const std::string& file_name,
                                    std::vector<ColmapImage>* images) {
  images->clear();
  Cursor in(bytes);
  std::uint64_t count = 0;
  if (!in.Read(&count)) return file_name + ": too short for the number of images";
  if (count > kMaxColmapImages || !in.Fits(count, kMinImageBytes)) return CountTooLarge(file_name, "images", count);
  images->reserve(count);
  for (std::uint64_t i = 0; i < count; ++i) {
    ColmapImage image;
    double v[7];
    if (!in.Read(&image.image_id)) return Truncated(file_name, "image", i, in);
    for (double& x : v)
      if (!in.ReadFinite(&x)) return Truncated(file_name, "image", i, in);
    const Eigen::Vector4d q(v[0], v[1], v[2], v[3]);
    if (!(q.norm() > 0.5 && q.norm() < 2.0))
      return file_name + ": image " + std::to_string(image.image_id) + " has a rotation quaternion not of unit length";
    image.cam_from_world_rotation = Eigen::Quaterniond(v[0], v[1], v[2], v[3]);
    image.cam_from_world_translation = Eigen::Vector3d(v[4], v[5], v[6]);
    if (!in.Read(&image.camera_id) || !in.ReadCString(&image.name, kMaxNameBytes))
      return Truncated(file_name, "image", i, in);
    std::uint64_t num_points = 0;
    if (!in.Read(&num_points)) return Truncated(file_name, "image", i, in);
    if (!in.Fits(num_points, kPoint2DBytes)) return CountTooLarge(file_name, "2D points", num_points);
    image.points2d.resize(num_points);
    for (ColmapPoint2D& point : image.points2d)
      if (!in.ReadFinite(&point.xy_px.x()) || !in.ReadFinite(&point.xy_px.y()) || !in.Read(&point.point3d_id))
        return Truncated(file_name, "image", i, in);
    images->push_back(std::move(image));
  }
  if (!in.AtEnd()) return TrailingBytes(file_name, in);
  return "";
}

std::string ParseColmapPoints3DBinary(const std::string& bytes, const std::string& file_name,
                                      std::vector<ColmapPoint3D>* points) {
  points->clear();
  Cursor in(bytes);
  std::uint64_t count = 0;
  if (!in.Read(&count)) return file_name + ": too short for the number of 3D points";
  if (count > kMaxColmapPoints3D || !in.Fits(count, kMinPoint3DBytes))
    return CountTooLarge(file_name, "3D points", count);
  points->reserve(count);
  for (std::uint64_t i = 0; i < count; ++i) {
    ColmapPoint3D point;
    if (!in.Read(&point.point3d_id)) return Truncated(file_name, "3D point", i, in);
    if (point.point3d_id == kColmapNoPoint3D) return file_name + ": 3D point " + std::to_string(i) + " has the id -1";
    for (int k = 0; k < 3; ++k)
      if (!in.ReadFinite(&point.position[k])) return Truncated(file_name, "3D point", i, in);
    for (std::uint8_t& c : point.rgb)
      if (!in.Read(&c)) return Truncated(file_name, "3D point", i, in);
    std::uint64_t track_length = 0;
    if (!in.ReadFinite(&point.error_px) || !in.Read(&track_length)) return Truncated(file_name, "3D point", i, in);
    if (!in.Fits(track_length, kTrackElementBytes)) return CountTooLarge(file_name, "track elements", track_length);
    point.track.resize(track_length);
    for (ColmapTrackElement& element : point.track)
      if (!in.Read(&element.image_id) || !in.Read(&element.point2d_index))
        return Truncated(file_name, "3D point", i, in);
    points->push_back(std::move(point));
  }
  if (!in.AtEnd()) return TrailingBytes(file_name, in);
  return "";
}

}  // namespace facet
