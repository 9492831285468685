// Synthetic photos of straight edges with a known camera, for the line-detection suites
// (tests/test_line_detection.cpp, tests/app/test_cli_detect_lines.cpp): polygons filled by area
// coverage, and the checkerboarded inside corner of a room.
#pragma once

#include <cmath>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/imgproc.hpp>

#include "core/image/image_io.h"

namespace facet::testing {

// Supersampling factor of the renderer: polygons are filled on a grid this much finer and
// averaged down by area, so each pixel holds its coverage to within 1 / factor^2. Large
// images take a smaller factor to keep the fine grid in memory.
constexpr int kSuper = 8;

struct TestCamera {
  double focal_px = 0.0;
  Eigen::Vector2d pp_px = Eigen::Vector2d::Zero();
  Eigen::Matrix3d cam_from_world = Eigen::Matrix3d::Identity();
  Eigen::Vector3d center = Eigen::Vector3d::Zero();

  Eigen::Vector3d ToCamera(const Eigen::Vector3d& x) const { return cam_from_world * (x - center); }
  Eigen::Vector2d Project(const Eigen::Vector3d& x) const {
    const Eigen::Vector3d p = ToCamera(x);
    return focal_px * p.head<2>() / p.z() + pp_px;
  }
};

// A camera at `center` looking at `target`, world z up (core/geometry/conventions.h: camera
// x right, y down, z forward).
inline TestCamera LookAt(const Eigen::Vector3d& center, const Eigen::Vector3d& target, double focal_px, int w, int h) {
  TestCamera camera;
  camera.focal_px = focal_px;
  camera.pp_px = Eigen::Vector2d(0.5 * (w - 1), 0.5 * (h - 1));
  camera.center = center;
  const Eigen::Vector3d forward = (target - center).normalized();
  const Eigen::Vector3d right = forward.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d down = forward.cross(right);
  camera.cam_from_world.row(0) = right;
  camera.cam_from_world.row(1) = down;
  camera.cam_from_world.row(2) = forward;
  return camera;
}

// Renders filled polygons (pixel coordinates, pixel centres at integers) with their grey
// levels into an RGBA image of w x h, by area coverage.
class Renderer {
 public:
  Renderer(int w, int h, int background, int super = kSuper)
      : w_(w), h_(h), super_(super), fine_(h * super, w * super, CV_8UC1, cv::Scalar(background)) {}

  void Fill(const std::vector<Eigen::Vector2d>& polygon_px, int grey) {
    // Pixel x covers [x - 0.5, x + 0.5]; on the fine grid that is cells super * x .. + super - 1
    // with centres at fine + 0.5, so fine = super * (x + 0.5) - 0.5. fillPoly takes 8 bits of
    // sub-pixel shift.
    std::vector<cv::Point> points;
    for (const Eigen::Vector2d& p : polygon_px) {
      const Eigen::Vector2d fine = super_ * (p.array() + 0.5) - 0.5;
      points.emplace_back(static_cast<int>(std::lround(fine.x() * 256)), static_cast<int>(std::lround(fine.y() * 256)));
    }
    cv::fillPoly(fine_, std::vector<std::vector<cv::Point>>{points}, cv::Scalar(grey), cv::LINE_8, 8);
  }

  ImageRgba8 Image() const {
    cv::Mat grey, rgba;
    cv::resize(fine_, grey, cv::Size(w_, h_), 0, 0, cv::INTER_AREA);
    cv::cvtColor(grey, rgba, cv::COLOR_GRAY2RGBA);
    ImageRgba8 image;
    image.width = w_;
    image.height = h_;
    image.pixels.assign(rgba.data, rgba.data + rgba.total() * 4);
    return image;
  }

 private:
  int w_, h_, super_;
  cv::Mat fine_;
};

// The inside corner of a room: checkerboards of 0.5 x 0.5 squares on the walls x = 0 and
// y = 0 and on the floor z = 0, each plane in its own pair of grey levels.
inline ImageRgba8 RenderRoomCorner(const TestCamera& camera, int w, int h, int super = kSuper) {
  Renderer renderer(w, h, 128, super);
  const double size = 0.5;
  const int n = 8;
  for (int plane = 0; plane < 3; ++plane) {
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        std::vector<Eigen::Vector2d> quad;
        for (const auto& [di, dj] : {std::pair{0, 0}, {1, 0}, {1, 1}, {0, 1}}) {
          const double u = (i + di) * size, v = (j + dj) * size;
          const Eigen::Vector3d x = plane == 0   ? Eigen::Vector3d(0, u, v)
                                    : plane == 1 ? Eigen::Vector3d(u, 0, v)
                                                 : Eigen::Vector3d(u, v, 0);
          quad.push_back(camera.Project(x));
        }
        const int grey = ((i + j) % 2 == 0 ? 60 : 190) + 20 * plane;
        renderer.Fill(quad, grey);
      }
    }
  }
  return renderer.Image();
}

}  // namespace facet::testing
