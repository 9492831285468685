// COLMAP's sparse reconstruction ("model": cameras, images, points3D), read from its text
// (.txt) or binary (.bin) files into plain structs, exactly as COLMAP stores it: COLMAP's
// pixel convention (the centre of the top-left pixel is (0.5, 0.5)), its camera models and
// parameters, its quaternions. Conversion to Facet's cameras is in core/io/colmap_camera.h.
//
// Every reader validates before it allocates (counts against the bytes left, ids unique and
// referred to, numbers finite) and reports a broken file by name and record, never throws.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace facet {

// COLMAP's camera models, with COLMAP's numeric ids (the binary files store them).
enum class ColmapCameraModel : int {
  kSimplePinhole = 0,        // f, cx, cy
  kPinhole = 1,              // fx, fy, cx, cy
  kSimpleRadial = 2,         // f, cx, cy, k
  kRadial = 3,               // f, cx, cy, k1, k2
  kOpenCv = 4,               // fx, fy, cx, cy, k1, k2, p1, p2
  kOpenCvFisheye = 5,        // fx, fy, cx, cy, k1, k2, k3, k4
  kFullOpenCv = 6,           // fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6
  kFov = 7,                  // fx, fy, cx, cy, omega
  kSimpleRadialFisheye = 8,  // f, cx, cy, k
  kRadialFisheye = 9,        // f, cx, cy, k1, k2
  kThinPrismFisheye = 10,    // fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, sx1, sy1
};
constexpr int kNumColmapCameraModels = 11;
const char* ColmapCameraModelName(ColmapCameraModel model);  // "SIMPLE_PINHOLE", ...
int ColmapCameraModelNumParams(ColmapCameraModel model);
// The model named `name` (COLMAP's spelling), or false.
bool ColmapCameraModelFromName(const std::string& name, ColmapCameraModel* model);
// The model with COLMAP's numeric id, or false for an id outside 0..10.
bool ColmapCameraModelFromId(int id, ColmapCameraModel* model);

struct ColmapCamera {
  std::uint32_t camera_id = 0;
  ColmapCameraModel model = ColmapCameraModel::kSimplePinhole;
  std::uint64_t width_px = 0;
  std::uint64_t height_px = 0;
  std::vector<double> params;  // ColmapCameraModelNumParams(model) of them, COLMAP's pixels
};

// COLMAP's "no 3D point" for a 2D point (-1 in the text files).
constexpr std::uint64_t kColmapNoPoint3D = ~std::uint64_t{0};

struct ColmapPoint2D {
  Eigen::Vector2d xy_px = Eigen::Vector2d::Zero();  // COLMAP's pixels: (0.5, 0.5) = first pixel's centre
  std::uint64_t point3d_id = kColmapNoPoint3D;
};

struct ColmapImage {
  std::uint32_t image_id = 0;
  // cam_from_world: p_in_cam = R(q) * p_in_world + t; q as the file stores it (w, x, y, z),
  // within a factor 2 of unit length (checked), normalised where it is used.
  Eigen::Quaterniond cam_from_world_rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d cam_from_world_translation = Eigen::Vector3d::Zero();
  std::uint32_t camera_id = 0;
  std::string name;  // the photo's path relative to COLMAP's image folder
  std::vector<ColmapPoint2D> points2d;
};

struct ColmapTrackElement {
  std::uint32_t image_id = 0;
  std::uint32_t point2d_index = 0;  // into that image's points2d
};

struct ColmapPoint3D {
  std::uint64_t point3d_id = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  std::uint8_t rgb[3] = {0, 0, 0};
  double error_px = 0.0;  // COLMAP's mean reprojection error of the point (-1: unknown)
  std::vector<ColmapTrackElement> track;
};

struct ColmapModel {
  std::vector<ColmapCamera> cameras;  // in file order
  std::vector<ColmapImage> images;
  std::vector<ColmapPoint3D> points3d;

  const ColmapCamera* FindCamera(std::uint32_t camera_id) const;
  const ColmapImage* FindImage(std::uint32_t image_id) const;
};

// The most records of each kind a model may have: far above a city-scale reconstruction's
// images, and a bound on what a hostile count can make the reader allocate.
constexpr std::uint64_t kMaxColmapCameras = 1'000'000;
constexpr std::uint64_t kMaxColmapImages = 1'000'000;
constexpr std::uint64_t kMaxColmapPoints3D = 100'000'000;
constexpr std::uint64_t kMaxColmapFileBytes = 4ull << 30;

// Reads the model in folder `dir`: cameras, images and points3D all .bin or all .txt (.bin
// preferred when both are complete). points3D may be absent (an empty point list then).
// "" on success, else the error naming the file and the record; *model is then empty.
std::string ReadColmapModel(const std::string& dir, ColmapModel* model);
std::string ReadColmapModelText(const std::string& dir, ColmapModel* model);
std::string ReadColmapModelBinary(const std::string& dir, ColmapModel* model);

// Parsers of one file's contents, for the readers above and the fuzz targets. `file_name`
// names the file in errors. They check the records themselves; the cross-checks between the
// files (image -> camera, track -> image and point index) are ValidateColmapModel's.
std::string ParseColmapCamerasText(const std::string& text, const std::string& file_name,
                                   std::vector<ColmapCamera>* cameras);
std::string ParseColmapImagesText(const std::string& text, const std::string& file_name,
                                  std::vector<ColmapImage>* images);
std::string ParseColmapPoints3DText(const std::string& text, const std::string& file_name,
                                    std::vector<ColmapPoint3D>* points);
std::string ParseColmapCamerasBinary(const std::string& bytes, const std::string& file_name,
                                     std::vector<ColmapCamera>* cameras);
std::string ParseColmapImagesBinary(const std::string& bytes, const std::string& file_name,
                                    std::vector<ColmapImage>* images);
std::string ParseColmapPoints3DBinary(const std::string& bytes, const std::string& file_name,
                                      std::vector<ColmapPoint3D>* points);
// The cross-checks: ids unique, every image's camera present, every track element naming a
// present image and one of its 2D points. "" when consistent.
std::string ValidateColmapModel(const ColmapModel& model);

}  // namespace facet
