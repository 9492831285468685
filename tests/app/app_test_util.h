// Helpers shared by the suites that drive the real application offscreen (`facet render`):
// temporary folders, running the binary, reading its report, and locating image pixels and
// the projected model on the screenshot.
#pragma once

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <doctest/doctest.h>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <Eigen/Dense>

#include "core/project.h"

namespace facet::testing {

namespace fs = std::filesystem;

// The projected model's colour (app/overlay_draw.h, kModelEdgeColor), RGB.
constexpr std::array<int, 3> kModelEdgeRgb = {255, 220, 0};

struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& name) {
    path = fs::temp_directory_path() / ("facet_app_test_" + std::to_string(::getpid()) + "_" + name);
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() {
    if (std::getenv("FACET_KEEP_TEST_DIRS")) return;  // for looking at the screenshots
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  std::string operator/(const std::string& file) const { return (path / file).string(); }
};

struct RunResult {
  int exit_code = -1;
  std::string stderr_text;
};

// Runs `facet render` without a display and with a private config folder. A render that
// hangs is killed (exit code 124) rather than hanging the suite.
inline RunResult RunRender(const TempDir& dir, const std::string& args) {
  constexpr int kRenderTimeoutS = 300;
  const std::string err = dir / "stderr.txt";
  const std::string cmd = "env -u DISPLAY -u WAYLAND_DISPLAY XDG_CONFIG_HOME='" + (dir / "config") + "' timeout " +
                          std::to_string(kRenderTimeoutS) + " '" + std::string(FACET_APP_EXE) + "' render " + args +
                          " 2> '" + err + "'";
  const int status = std::system(cmd.c_str());
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(err);
  std::ostringstream ss;
  ss << in.rdbuf();
  r.stderr_text = ss.str();
  return r;
}

inline nlohmann::json ReadJson(const std::string& path) {
  std::ifstream in(path);
  REQUIRE_MESSAGE(in.good(), "missing report " << path);
  return nlohmann::json::parse(in);
}

inline void WriteText(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
}

struct View {
  double origin_x, origin_y, zoom;
  double rect_x, rect_y, rect_w, rect_h;
  Eigen::Vector2d ToScreen(const Eigen::Vector2d& uv) const {
    return {origin_x + zoom * uv.x(), origin_y + zoom * uv.y()};
  }
  bool Inside(const Eigen::Vector2d& s, double margin) const {
    return s.x() >= rect_x + margin && s.y() >= rect_y + margin && s.x() < rect_x + rect_w - margin &&
           s.y() < rect_y + rect_h - margin;
  }
};

inline View ViewFromReport(const nlohmann::json& report) {
  const auto& v = report.at("image_view");
  const auto& r = v.at("rect");
  return {v.at("origin_x").get<double>(), v.at("origin_y").get<double>(), v.at("zoom").get<double>(),
          r.at("x").get<double>(),        r.at("y").get<double>(),        r.at("w").get<double>(),
          r.at("h").get<double>()};
}

inline bool IsModelColor(const cv::Vec3b& bgr, int tolerance) {
  return std::abs(bgr[2] - kModelEdgeRgb[0]) <= tolerance && std::abs(bgr[1] - kModelEdgeRgb[1]) <= tolerance &&
         std::abs(bgr[0] - kModelEdgeRgb[2]) <= tolerance;
}

inline bool ModelColorNear(const cv::Mat& shot, const Eigen::Vector2d& s, int radius_px, int tolerance) {
  const int cx = static_cast<int>(std::floor(s.x())), cy = static_cast<int>(std::floor(s.y()));
  for (int y = cy - radius_px; y <= cy + radius_px; ++y) {
    for (int x = cx - radius_px; x <= cx + radius_px; ++x) {
      if (x >= 0 && y >= 0 && x < shot.cols && y < shot.rows && IsModelColor(shot.at<cv::Vec3b>(y, x), tolerance)) {
        return true;
      }
    }
  }
  return false;
}

// The world positions of a box primitive's eight corners (its mesh vertices 0..7).
inline std::array<Eigen::Vector3d, 8> BoxCorners(const facet::Primitive& box) {
  std::array<Eigen::Vector3d, 8> corners;
  for (int c = 0; c < 8; ++c) corners[c] = box.mesh.vertex(static_cast<facet::VertexId>(c)).position;
  return corners;
}

// The 3D panel's projection from the report: screen px of a world point, and the eye.
struct Viewport3d {
  Eigen::Matrix4d clip_from_world;
  double origin_x = 0, origin_y = 0, width_px = 1, height_px = 1;
  Eigen::Vector2d ToScreen(const Eigen::Vector3d& x) const {
    const Eigen::Vector4d clip = clip_from_world * x.homogeneous();
    return {origin_x + (clip.x() / clip.w() + 1.0) * 0.5 * width_px,
            origin_y + (1.0 - clip.y() / clip.w()) * 0.5 * height_px};
  }
  // The eye: the point with clip x = y = w = 0.
  Eigen::Vector3d Eye() const {
    Eigen::Matrix3d a;
    Eigen::Vector3d b;
    int r = 0;
    for (int row : {0, 1, 3}) {
      a.row(r) = clip_from_world.block<1, 3>(row, 0);
      b(r++) = -clip_from_world(row, 3);
    }
    return a.colPivHouseholderQr().solve(b);
  }
};

inline Viewport3d ViewportFromReport(const nlohmann::json& report) {
  const auto& v = report.at("viewport");
  Viewport3d out;
  const std::vector<double> m = v.at("clip_from_world").get<std::vector<double>>();
  REQUIRE(m.size() == 16);
  out.clip_from_world = Eigen::Map<const Eigen::Matrix4d>(m.data());
  out.origin_x = v.at("origin_x").get<double>();
  out.origin_y = v.at("origin_y").get<double>();
  out.width_px = v.at("width_px").get<double>();
  out.height_px = v.at("height_px").get<double>();
  return out;
}


}  // namespace facet::testing
