// Helpers shared by the suites that drive the real application offscreen (`facet render`):
// temporary folders, running the binary with an input script, reading its report and saved
// projects, locating image pixels and the projected model on the screenshot, and the
// line-pin scene (the synthetic box with its photo) that the line-pin suites share.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <thread>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <doctest/doctest.h>
#include <Eigen/Dense>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/io/project_io.h"
#include "core/mesh/box.h"
#include "core/scene/project.h"
#include "tests/synthetic_scene.h"
#include "tests/temp_files.h"

namespace facet::testing {

namespace fs = std::filesystem;

// The projected model's colour (app/panels/image_overlay.h, kModelEdgeColor), RGB.
constexpr std::array<int, 3> kModelEdgeRgb = {255, 220, 0};


struct RunResult {
  int exit_code = -1;
  std::string stderr_text;
};

// Snapping (app/panels/image_snapping.h) moves a point placed in a photo onto a corner or
// edge nearby. A suite that checks that points land exactly where its mouse went sets this
// once (`render --no-snap`, the Snap option off); tests/app/test_snapping.cpp covers snapping.
inline bool& RenderWithoutSnapping() {
  static bool without = false;
  return without;
}

// Runs `facet render` without a display and with private config and data folders (the data
// folder holds an unsaved project's recovery file under --autosave). A render that hangs is
// killed (exit code 124) rather than hanging the suite.
// With `working_dir`, the app runs there (a script's relative paths are relative to it).
inline RunResult RunRender(const TempDir& dir, const std::string& args_in, const std::string& working_dir = "") {
  const std::string args = (RenderWithoutSnapping() ? "--no-snap " : "") + args_in;
  constexpr int kRenderTimeoutS = 300;
  const std::string err = dir / "stderr.txt";
  const std::string cd = working_dir.empty() ? std::string() : "cd '" + working_dir + "' && ";
  const std::string cmd = cd + "env -u DISPLAY -u WAYLAND_DISPLAY XDG_CONFIG_HOME='" + (dir / "config") +
                          "' XDG_DATA_HOME='" + (dir / "data") + "' timeout " + std::to_string(kRenderTimeoutS) + " '" +
                          std::string(FACET_APP_EXE) + "' render " + args + " 2> '" + err + "'";
  const int status = std::system(cmd.c_str());
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  std::ifstream in(err);
  std::ostringstream ss;
  ss << in.rdbuf();
  r.stderr_text = ss.str();
  return r;
}

// A `facet render` started in the background (fork + exec) in RunRender's environment, with
// stderr in dir/NAME.stderr.txt, for a test that stops it from the outside (StopRender).
struct BackgroundRender {
  pid_t pid = -1;
  bool reaped = false;  // it ended by itself (WaitForFile noticed)
  int status = 0;       // waitpid's, once reaped
};

inline BackgroundRender StartRender(const TempDir& dir, const std::string& name, const std::vector<std::string>& args) {
  // Built before fork; the suites run no other threads, so the child may set its environment.
  const std::string exe = FACET_APP_EXE, err = dir / (name + ".stderr.txt");
  const std::string config = dir / "config", data = dir / "data";
  std::vector<std::string> words = {exe, "render"};
  if (RenderWithoutSnapping()) words.push_back("--no-snap");
  words.insert(words.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& w : words) argv.push_back(w.data());
  argv.push_back(nullptr);
  BackgroundRender render;
  render.pid = ::fork();
  REQUIRE(render.pid >= 0);
  if (render.pid == 0) {
    ::unsetenv("DISPLAY");
    ::unsetenv("WAYLAND_DISPLAY");
    ::setenv("XDG_CONFIG_HOME", config.c_str(), 1);
    ::setenv("XDG_DATA_HOME", data.c_str(), 1);
    const int fd = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd >= 0) ::dup2(fd, 2);
    ::execv(exe.c_str(), argv.data());
    ::_exit(127);
  }
  return render;
}

// Waits until `path` exists; false when the render ended first or `timeout_s` passed.
inline bool WaitForFile(const std::string& path, BackgroundRender* render, double timeout_s) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (!fs::exists(path)) {
    if (!render->reaped && ::waitpid(render->pid, &render->status, WNOHANG) == render->pid) render->reaped = true;
    if (render->reaped || std::chrono::steady_clock::now() > until) return fs::exists(path);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return true;
}

// Sends `signal` to a running background render and reaps it. Returns the signal that ended
// it, or 0 when it had exited by itself.
inline int StopRender(BackgroundRender* render, int signal) {
  if (!render->reaped) {
    ::kill(render->pid, signal);
    ::waitpid(render->pid, &render->status, 0);
    render->reaped = true;
  }
  return WIFSIGNALED(render->status) ? WTERMSIG(render->status) : 0;
}

// Waits up to `timeout_s` for a background render to end by itself, then kills what is left
// (SIGKILL) and reaps it. True when it exited by itself with status 0: a test that reads what
// the exit leaves behind (the removed recovery file) must not kill it between its report and
// its clean-up.
inline bool WaitForExit(BackgroundRender* render, double timeout_s) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (!render->reaped && std::chrono::steady_clock::now() < until) {
    if (::waitpid(render->pid, &render->status, WNOHANG) == render->pid) {
      render->reaped = true;
      break;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (!render->reaped) {
    StopRender(render, SIGKILL);
    return false;
  }
  return WIFEXITED(render->status) && WEXITSTATUS(render->status) == 0;
}

struct CliResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

// A command-line run of facet (not `render`): exit code, stdout, stderr.
// Runs facet with `args` (already shell-quoted where needed), without a display.
inline CliResult RunFacet(const TempDir& dir, const std::string& args) {
  const std::string out = dir / "stdout.txt", err = dir / "stderr.txt";
  const std::string command = "env -u DISPLAY -u WAYLAND_DISPLAY '" + std::string(FACET_APP_EXE) + "' " + args +
                              " > '" + out + "' 2> '" + err + "'";
  const int status = std::system(command.c_str());
  CliResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = ReadText(out);
  r.err = ReadText(err);
  return r;
}

inline nlohmann::json ReadJson(const std::string& path) {
  std::ifstream in(path);
  REQUIRE_MESSAGE(in.good(), "missing report " << path);
  return nlohmann::json::parse(in);
}

// The report's log, one "level: text" line per entry (for failure messages).
inline std::string ReportLog(const nlohmann::json& report) {
  std::string text;
  for (const auto& e : report.at("log"))
    text += e.at("level").get<std::string>() + ": " + e.at("text").get<std::string>() + "\n";
  return text;
}

// Runs the app on `project_path` with `script` (written to dir/NAME.txt; the screenshot is
// dir/NAME.png); requires success and returns the report (dir/NAME.json).
inline nlohmann::json RenderScript(const TempDir& dir, const std::string& project_path, const std::string& name,
                                   const std::string& script) {
  WriteText(dir / (name + ".txt"), script);
  const RunResult run = RunRender(dir, "'" + project_path + "' -o '" + (dir / (name + ".png")) + "' --script '" +
                                           (dir / (name + ".txt")) + "' --report '" + (dir / (name + ".json")) + "'");
  INFO("stderr: " << run.stderr_text);
  REQUIRE(run.exit_code == 0);
  return ReadJson(dir / (name + ".json"));
}

// Runs a script that must fail on a refused command; returns its stderr.
inline std::string RenderScriptRefused(const TempDir& dir, const std::string& project_path, const std::string& name,
                                       const std::string& script) {
  WriteText(dir / (name + ".txt"), script);
  const RunResult run = RunRender(
      dir, "'" + project_path + "' -o '" + (dir / (name + ".png")) + "' --script '" + (dir / (name + ".txt")) + "'");
  CHECK(run.exit_code != 0);
  return run.stderr_text;
}

// A project the script saved; requires that it loads.
inline facet::Project LoadProjectFile(const std::string& path) {
  const facet::ProjectLoadResult loaded = facet::LoadProject(path);
  INFO("load " << path << ": " << loaded.error);
  REQUIRE(loaded.ok());
  return loaded.project;
}

// "x y" for script coordinates, with full precision unless a test asks for fewer digits.
inline std::string FormatXY(const Eigen::Vector2d& p, int significant_digits = 17) {
  std::ostringstream out;
  out.precision(significant_digits);
  out << p.x() << " " << p.y();
  return out.str();
}

// "x y" of the centre of a named item rectangle of the report's "items".
inline std::string ItemCenter(const nlohmann::json& items, const std::string& name) {
  const nlohmann::json& r = items.at(name);
  std::ostringstream s;
  s << r.at("x").get<double>() + 0.5 * r.at("w").get<double>() << " "
    << r.at("y").get<double>() + 0.5 * r.at("h").get<double>();
  return s.str();
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

// RMS (px) of every pin's distance to its vertex projected by its image's camera; every pinned
// vertex must be in front of its camera.
inline double PinRmsPx(const facet::Project& project) {
  double sum_sq = 0.0;
  for (const facet::Pin& pin : project.pins) {
    const facet::Camera& camera = project.FindImage(pin.image_id)->camera;
    const Eigen::Vector3d x = facet::VertexInWorld(project, pin.vertex);
    REQUIRE(camera.CamFromWorld(x).z() > 0.0);
    sum_sq += (camera.Project(x) - pin.uv_px).squaredNorm();
  }
  return std::sqrt(sum_sq / static_cast<double>(project.pins.size()));
}

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

// The synthetic box scene (one calibrated image, its line families, the box) with its photo,
// the pins of the top corners 4..7 removed so that those vertices are pickable and free to
// follow a line pin (the bottom pins, the lines and the locked height keep the box fixed).
struct LineScene {
  std::string path;
  SyntheticScene scene;
  View view;
};

inline LineScene WriteLineScene(const TempDir& dir) {
  LineScene f;
  f.scene = MakeBoxScene();
  facet::Project& p = f.scene.project;
  std::erase_if(p.pins, [](const facet::Pin& pin) { return pin.vertex.vertex >= 4; });
  const facet::Camera& cam = f.scene.true_camera;
  // Lines ending at a top corner would be picked there before the vertex: leave them out
  // (the bottom edges and the lines across the faces still calibrate the image).
  std::vector<Eigen::Vector2d> top;
  for (int c = 4; c < 8; ++c) top.push_back(cam.Project(f.scene.true_box.mesh.vertex(c).position));
  std::erase_if(p.segments, [&](const facet::Segment& s) {
    return std::any_of(top.begin(), top.end(), [&](const Eigen::Vector2d& t) {
      return (s.a_px - t).norm() < 1.0 || (s.b_px - t).norm() < 1.0;
    });
  });
  cv::Mat photo(cam.height_px, cam.width_px, CV_8UC3, cv::Scalar(150, 150, 150));
  const auto corners = BoxCorners(f.scene.true_box);
  for (const auto& e : facet::BoxEdges()) {
    const Eigen::Vector2d a = cam.Project(corners[e[0]]), b = cam.Project(corners[e[1]]);
    cv::line(photo, cv::Point(static_cast<int>(a.x()), static_cast<int>(a.y())),
             cv::Point(static_cast<int>(b.x()), static_cast<int>(b.y())), cv::Scalar(40, 40, 40), 2, cv::LINE_AA);
  }
  REQUIRE(cv::imwrite(dir / "synthetic.png", photo));
  f.path = dir / "scene.facet";
  REQUIRE(facet::SaveProject(p, f.path) == "");
  f.view = ViewFromReport(RenderScript(dir, f.path, "probe", "frames 3\n"));
  REQUIRE(f.view.zoom > 0.1);
  return f;
}

// Largest distance (px) of the constraint's edge ends, projected by its image's camera, from
// its line.
inline double LinePinDistancePx(const facet::Project& project, const facet::Constraint& c) {
  const facet::Image* image = project.FindImage(c.image_id);
  REQUIRE(image != nullptr);
  const Eigen::Vector2d d = (c.line_b_px - c.line_a_px).normalized();
  const Eigen::Vector2d n(-d.y(), d.x());
  double worst = 0.0;
  for (const facet::VertexRef& v : c.vertices) {
    const Eigen::Vector2d uv = image->camera.Project(facet::VertexInWorld(project, v));
    worst = std::max(worst, std::abs((uv - c.line_a_px).dot(n)));
  }
  return worst;
}

// A line in the photo near the top front x edge (corners 4 -> 5): its true projection moved
// `shift_px` sideways, between 10 % and 90 % of its length.
inline void ShiftedLine(const LineScene& f, double shift_px, Eigen::Vector2d* a, Eigen::Vector2d* b) {
  const auto corners = BoxCorners(f.scene.true_box);
  const Eigen::Vector2d p4 = f.scene.true_camera.Project(corners[4]), p5 = f.scene.true_camera.Project(corners[5]);
  const Eigen::Vector2d d = (p5 - p4).normalized();
  const Eigen::Vector2d n(-d.y(), d.x());
  *a = p4 + 0.1 * (p5 - p4) + shift_px * n;
  *b = p4 + 0.9 * (p5 - p4) + shift_px * n;
}

}  // namespace facet::testing
