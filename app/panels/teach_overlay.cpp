#include "app/panels/teach_overlay.h"

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>

#include "app/panels/image_overlay.h"
#include "app/panels/widgets.h"
#include "core/util/format.h"
#include "core/util/matrix_text.h"

namespace facet::app {
namespace {

using internal::FormatNumber;

constexpr ImU32 kShadow = IM_COL32(0, 0, 0, 190);
constexpr ImU32 kTriangleColor = IM_COL32(255, 255, 255, 230);
constexpr ImU32 kAltitudeColor = IM_COL32(255, 255, 255, 140);
constexpr ImU32 kConstructionColor = IM_COL32(255, 170, 40, 255);  // circle, turned centre, f
constexpr ImU32 kPrincipalPointColor = IM_COL32(255, 90, 220, 255);
constexpr ImU32 kHorizonColor = IM_COL32(120, 255, 160, 230);
constexpr ImU32 kEpipolarColor = IM_COL32(120, 230, 255, 240);
constexpr ImU32 kAssumptionColor = IM_COL32(250, 200, 80, 255);
constexpr ImU32 kPanelBackground = IM_COL32(0, 0, 0, 165);
constexpr ImU32 kStepsText = IM_COL32(255, 255, 255, 240);     // the solver steps' boxes: first line
constexpr ImU32 kStepsDimText = IM_COL32(200, 200, 200, 230);  // and the lines under it
// The solver's residual vectors: white, apart from the families' red, green and blue, the
// model's yellow and the pins' magenta.
constexpr ImU32 kResidualColor = IM_COL32(255, 255, 255, 255);
constexpr ImU32 kRayColor = IM_COL32(120, 230, 255, 255);  // rays of a vertex's pins in 3D
constexpr ImU32 kGapColor = IM_COL32(255, 120, 60, 255);
// The 95 % ellipse of a 2-D Gaussian: sqrt of chi^2(2 dof) at 0.95.
constexpr double kEllipse95Scale = 2.4477;

struct Screen {
  const ViewTransform& view;
  Eigen::Vector2d rect_min, rect_max;
  Eigen::Vector2d operator()(const Eigen::Vector2d& uv_px) const { return ImageToScreen(view, uv_px); }
};

void Line(ImDrawList* draw, const Screen& s, const Eigen::Vector2d& a, const Eigen::Vector2d& b, ImU32 color,
          float width, bool dashed = false) {
  DrawClippedScreenLine(draw, a, b, s.rect_min, s.rect_max, color, width, dashed ? 9.0 : 0.0, kShadow);
}

// An image line l . (u, v, 1) = 0 across the view.
void InfiniteLine(ImDrawList* draw, const Screen& s, const Eigen::Vector3d& l, ImU32 color, float width, bool dashed) {
  Eigen::Vector2d a, b;
  if (ImageLineAcrossView(s.view, l, s.rect_min, s.rect_max, &a, &b)) Line(draw, s, a, b, color, width, dashed);
}

void Marker(ImDrawList* draw, const Eigen::Vector2d& p, ImU32 color, float radius) {
  draw->AddCircleFilled(ToImVec2(p), radius + 1.5f, kShadow);
  draw->AddCircleFilled(ToImVec2(p), radius, color);
}

void Label(ImDrawList* draw, const Eigen::Vector2d& p, ImU32 color, const std::string& text) {
  DrawShadowedText(draw, ImVec2(static_cast<float>(p.x()) + 8.0f, static_cast<float>(p.y()) - 18.0f), color,
                   text.c_str());
}

// Lines of text in a dark box at the view's bottom-left, its bottom at `*y`, which moves up
// above it (the photo's top, where the vanishing points often are, stays clear).
// Each line broken at spaces to fit `max_width` (px); continuations indented.
std::vector<std::pair<ImU32, std::string>> WrappedLines(const std::vector<std::pair<ImU32, std::string>>& lines,
                                                        float max_width) {
  std::vector<std::pair<ImU32, std::string>> out;
  for (const auto& [color, text] : lines) {
    if (ImGui::CalcTextSize(text.c_str()).x <= max_width) {
      out.emplace_back(color, text);
      continue;
    }
    std::string current;
    size_t start = 0;
    while (start <= text.size()) {
      const size_t end = std::min(text.find(' ', start), text.size());
      const std::string word = text.substr(start, end - start);
      const std::string candidate = current.empty() ? word : current + " " + word;
      if (!current.empty() && ImGui::CalcTextSize(candidate.c_str()).x > max_width) {
        out.emplace_back(color, current);
        current = "  " + word;
      } else {
        current = candidate;
      }
      start = end + 1;
    }
    if (!current.empty()) out.emplace_back(color, current);
  }
  return out;
}

void TextBox(ImDrawList* draw, const Screen& s, float* y, const std::vector<std::pair<ImU32, std::string>>& unwrapped) {
  if (unwrapped.empty()) return;
  const float pad = 5.0f, line_h = ImGui::GetTextLineHeight();
  // Within the view: a line longer than the panel is wide is broken, never cut off.
  const float max_width = std::max(120.0f, static_cast<float>(s.rect_max.x() - s.rect_min.x()) - 16.0f - 2 * pad);
  const std::vector<std::pair<ImU32, std::string>> lines = WrappedLines(unwrapped, max_width);
  float width = 0.0f;
  for (const auto& [color, text] : lines) width = std::max(width, ImGui::CalcTextSize(text.c_str()).x);
  const float height = lines.size() * (line_h + 2.0f) + 2 * pad;
  const ImVec2 min(static_cast<float>(s.rect_min.x()) + 8.0f, *y - height);
  const ImVec2 max(min.x + width + 2 * pad, *y);
  draw->AddRectFilled(min, max, kPanelBackground, 3.0f);
  float at = min.y + pad;
  for (const auto& [color, text] : lines) {
    draw->AddText(ImVec2(min.x + pad, at), color, text.c_str());
    at += line_h + 2.0f;
  }
  *y = min.y - 6.0f;
}

// The 95 % ellipse of a point with covariance `cov` (px^2).
void Ellipse(ImDrawList* draw, const Screen& s, const Eigen::Vector2d& center_px, const Eigen::Matrix2d& cov,
             ImU32 color) {
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(cov);
  if (eig.info() != Eigen::Success || !(eig.eigenvalues().minCoeff() >= 0.0)) return;
  const Eigen::Matrix2d axes = eig.eigenvectors() * eig.eigenvalues().cwiseSqrt().asDiagonal() * kEllipse95Scale;
  constexpr int kSteps = 72;
  std::vector<ImVec2> points;
  for (int k = 0; k < kSteps; ++k) {
    const double angle = 2.0 * M_PI * k / kSteps;
    points.push_back(ToImVec2(s(center_px + axes * Eigen::Vector2d(std::cos(angle), std::sin(angle)))));
  }
  draw->AddPolyline(points.data(), kSteps, kShadow, ImDrawFlags_Closed, 3.5f);
  draw->AddPolyline(points.data(), kSteps, color, ImDrawFlags_Closed, 1.5f);
}

void Circle(ImDrawList* draw, const Screen& s, const Eigen::Vector2d& center_px, double radius_px, ImU32 color,
            double from_angle = 0.0, double to_angle = 2.0 * M_PI) {
  // Enough steps that a chord stays within ~1 screen px of the circle, at most 2048.
  const double radius_screen = radius_px * s.view.zoom;
  const int steps =
      std::clamp(static_cast<int>(std::abs(to_angle - from_angle) * std::sqrt(radius_screen / 2.0)), 16, 2048);
  Eigen::Vector2d previous = s(center_px + radius_px * Eigen::Vector2d(std::cos(from_angle), std::sin(from_angle)));
  for (int k = 1; k <= steps; ++k) {
    const double angle = from_angle + (to_angle - from_angle) * k / steps;
    const Eigen::Vector2d p = s(center_px + radius_px * Eigen::Vector2d(std::cos(angle), std::sin(angle)));
    Line(draw, s, previous, p, color, 1.5f);
    previous = p;
  }
}

const char* kAxisNames[3] = {"x", "y", "z"};
constexpr int kExtensionAlpha = 90;  // the extended segments, faint

void DrawVanishingConstruction(ImDrawList* draw, const AppState& state, const Image& image, const Screen& s,
                               float* text_y) {
  const std::optional<TeachVanishing> teach = TeachVanishingFor(state, image.id);
  if (!teach) {
    TextBox(draw, s, text_y,
            {{IM_COL32(255, 255, 255, 230), "Vanishing points: no calibration from line families on this photo yet"}});
    return;
  }
  const VanishingConstruction& c = teach->construction;
  // Each family's longest segments extended to its own vanishing point, faintly (every one
  // of a hundred-odd extensions hatched the photo and hid the construction).
  const std::vector<Id> extended = TeachExtendedSegments(state, image.id, c);
  int segments = 0;
  for (const Segment& segment : state.document.project().segments)
    segments += segment.image_id == image.id && c.present[static_cast<int>(segment.axis)] ? 1 : 0;
  for (const Id id : extended) {
    const Segment* segment = state.document.project().FindSegment(id);
    const int a = static_cast<int>(segment->axis);
    const Eigen::Vector2d undistorted_a = image.camera.UndistortPixel(segment->a_px);
    const Eigen::Vector2d undistorted_b = image.camera.UndistortPixel(segment->b_px);
    const ImU32 color = AxisColor(segment->axis, kExtensionAlpha);
    if (c.finite[a]) {
      const Eigen::Vector2d& v = c.points_px[a];
      const Eigen::Vector2d far_end =
          (undistorted_a - v).norm() > (undistorted_b - v).norm() ? undistorted_a : undistorted_b;
      DrawClippedScreenLine(draw, s(far_end), s(v), s.rect_min, s.rect_max, color, 1.0f);
    } else {
      const Eigen::Vector2d mid = 0.5 * (undistorted_a + undistorted_b);
      Eigen::Vector2d p, q;
      if (ImageLineAcrossView(s.view, mid.homogeneous().cross(teach->vanishing_points_px[a]), s.rect_min, s.rect_max,
                              &p, &q))
        DrawClippedScreenLine(draw, p, q, s.rect_min, s.rect_max, color, 1.0f);
    }
  }
  if (!c.horizon.isZero()) {
    InfiniteLine(draw, s, c.horizon, kHorizonColor, 1.5f, true);
    // Labelled where it crosses the view's left part.
    const double n = c.horizon.head<2>().norm();
    if (std::abs(c.horizon.y()) > 1e-9 * n) {
      double u0, v0;
      s.view.ToImage(ToImVec2(s.rect_min + Eigen::Vector2d(40.0, 0.0)), &u0, &v0);
      const double v = -(c.horizon.x() * u0 + c.horizon.z()) / c.horizon.y();
      Label(draw, s(Eigen::Vector2d(u0, v)), kHorizonColor, "horizon");
    }
  }
  // The vanishing triangle and its altitudes through the orthocentre.
  if (c.kind == VanishingConstructionKind::kThreePoints) {
    for (int k = 0; k < 3; ++k) Line(draw, s, s(c.points_px[k]), s(c.points_px[(k + 1) % 3]), kTriangleColor, 1.5f);
    for (int k = 0; k < 3; ++k) Line(draw, s, s(c.points_px[k]), s(c.altitude_feet_px[k]), kAltitudeColor, 1.0f, true);
  }
  // The focal construction on the pair with the smallest circle (the one most likely in view).
  const FocalConstruction* shown = ShownFocalConstruction(c);
  const Eigen::Vector2d& p = c.principal_point_px;
  if (shown != nullptr) {
    const FocalConstruction& f = *shown;
    Circle(draw, s, f.circle_center_px, f.circle_radius_px, kConstructionColor);
    if (c.kind != VanishingConstructionKind::kThreePoints)
      Line(draw, s, s(p), s(f.altitude_foot_px), kAltitudeColor, 1.0f, true);
    Line(draw, s, s(f.altitude_foot_px), s(f.turned_center_px), kConstructionColor, 1.0f, true);
    // The arc about h from q to s: |h s| = |h q|.
    const Eigen::Vector2d hq = f.turned_center_px - f.altitude_foot_px, hs = f.focal_end_px - f.altitude_foot_px;
    double from = std::atan2(hq.y(), hq.x()), to = std::atan2(hs.y(), hs.x());
    if (to - from > M_PI) to -= 2.0 * M_PI;
    if (from - to > M_PI) to += 2.0 * M_PI;
    Circle(draw, s, f.altitude_foot_px, hq.norm(), kConstructionColor, from, to);
    draw->AddLine(ToImVec2(s(p)), ToImVec2(s(f.focal_end_px)), kShadow, 5.0f);
    draw->AddLine(ToImVec2(s(p)), ToImVec2(s(f.focal_end_px)), kConstructionColor, 3.0f);
    Marker(draw, s(f.altitude_foot_px), kConstructionColor, 3.5f);
    Label(draw, s(f.altitude_foot_px), kConstructionColor, "h");
    Marker(draw, s(f.turned_center_px), kConstructionColor, 4.0f);
    Label(draw, s(f.turned_center_px), kConstructionColor,
          std::string("C' (centre turned about v") + kAxisNames[f.axes[0]] + " v" + kAxisNames[f.axes[1]] + ")");
    Marker(draw, s(f.focal_end_px), kConstructionColor, 3.5f);
    Label(draw, s(0.5 * (p + f.focal_end_px)), kConstructionColor, "f = " + FormatNumber(f.focal_px, 5) + " px");
  }
  // The vanishing points with their 95 % ellipses.
  for (int a = 0; a < 3; ++a) {
    if (!c.finite[a]) continue;
    const ImU32 color = AxisColor(static_cast<Axis>(a), 255);
    std::string text = std::string("v") + kAxisNames[a];
    if (teach->covariance_px2[a].allFinite()) {
      Ellipse(draw, s, c.points_px[a], teach->covariance_px2[a], color);
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(teach->covariance_px2[a]);
      const Eigen::Vector2d half = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt() * kEllipse95Scale;
      text += "  95 %: " + FormatNumber(half.y(), 3) + " x " + FormatNumber(half.x(), 3) + " px";
    } else {
      text += "  (2 segments: no redundancy, no ellipse)";
    }
    Marker(draw, s(c.points_px[a]), color, 4.5f);
    Label(draw, s(c.points_px[a]), color, text);
  }
  Marker(draw, s(p), kPrincipalPointColor, 5.0f);
  Label(draw, s(p), kPrincipalPointColor, c.principal_point_assumed ? "p (assumed)" : "p = orthocentre");

  std::vector<std::pair<ImU32, std::string>> lines;
  const ImU32 white = IM_COL32(255, 255, 255, 240), dim = IM_COL32(200, 200, 200, 230);
  lines.push_back({white, std::string("Vanishing points: ") + VanishingConstructionKindName(c.kind) +
                              " (each family's own fit, 95 % ellipses)"});
  if (static_cast<int>(extended.size()) < segments)
    lines.push_back({dim, "extended to their points: each family's " + std::to_string(kTeachExtensionsPerFamily) +
                              " longest segments (" + std::to_string(extended.size()) + " of " +
                              std::to_string(segments) + ")"});
  if (c.focal_px > 0.0)
    lines.push_back(
        {kConstructionColor, std::string("construction: f = ") + FormatNumber(c.focal_px, 6) + " px" +
                                 (c.focal_assumed ? " (assumed)" : " = |p s|, s on the arc about h through C'") +
                                 ", p = (" + FormatNumber(p.x(), 5) + ", " + FormatNumber(p.y(), 5) + ")"});
  std::string fitted = "joint fit of all segments: f = " + FormatNumber(teach->fitted_focal_px, 6);
  if (std::isfinite(teach->fitted_focal_std_px) && teach->fitted_focal_std_px > 0.0)
    fitted += " +- " + FormatNumber(teach->fitted_focal_std_px, 3);
  fitted += " px, p = (" + FormatNumber(teach->fitted_principal_point_px.x(), 5) + ", " +
            FormatNumber(teach->fitted_principal_point_px.y(), 5) + ")";
  lines.push_back({dim, fitted});
  for (const std::string& a : teach->assumptions) lines.push_back({kAssumptionColor, a});
  TextBox(draw, s, text_y, lines);
}

std::string FileName(const std::string& path) { return std::filesystem::path(path).filename().string(); }

void DrawEpipolarLine(ImDrawList* draw, const Screen& s, const TeachEpipolarLine& line, const std::string& label) {
  InfiniteLine(draw, s, line.line, kEpipolarColor, 1.5f, true);
  if (line.epipole.squaredNorm() > 0.0 && std::abs(line.epipole.z()) > 1e-12 * line.epipole.norm()) {
    const Eigen::Vector2d e = s(line.epipole.head<2>() / line.epipole.z());
    const Eigen::Vector2d margin(20.0, 20.0);
    if ((e.array() >= (s.rect_min - margin).array()).all() && (e.array() <= (s.rect_max + margin).array()).all()) {
      Marker(draw, e, kEpipolarColor, 4.5f);
      Label(draw, e, kEpipolarColor, "e (epipole)");
    }
  }
  if (label.empty()) return;
  // The label where the line crosses the middle of the view.
  double cu, cv;
  s.view.ToImage(ToImVec2(0.5 * (s.rect_min + s.rect_max)), &cu, &cv);
  const double n = line.line.head<2>().norm();
  const Eigen::Vector2d foot =
      Eigen::Vector2d(cu, cv) - (line.line.dot(Eigen::Vector3d(cu, cv, 1.0)) / n) * line.line.head<2>() / n;
  Label(draw, s(foot), kEpipolarColor, label);
}

// The epipolar lines in this photo (of pins in the others), and insets with the other photos
// carrying the lines of this photo's pointer and pins.
void DrawEpipolar(ImDrawList* draw, const AppState& state, const Image& image, const Screen& s, float* text_y,
                  const std::function<const TiledTexture*(Id)>& texture_of) {
  const Project& project = state.document.project();
  const std::vector<TeachEpipolarLine> lines = TeachEpipolarLines(state);
  int here = 0;
  for (const TeachEpipolarLine& line : lines) {
    if (line.in_image_id != image.id) continue;
    const Image* from = project.FindImage(line.from_image_id);
    std::string label = "epipolar line of " + std::string(line.from_pointer ? "the pointer" : "the pin") + " in " +
                        (from ? FileName(from->path) : std::string("?"));
    if (std::isfinite(line.pin_distance_px))
      label += ": the pin here is " + FormatNumber(line.pin_distance_px, 3) + " px off";
    DrawEpipolarLine(draw, s, line, label);
    ++here;
  }
  std::vector<Id> others;
  for (const TeachEpipolarLine& line : lines)
    if (line.from_image_id == image.id && std::find(others.begin(), others.end(), line.in_image_id) == others.end())
      others.push_back(line.in_image_id);
  const double view_w = s.rect_max.x() - s.rect_min.x();
  double bottom = s.rect_max.y() - 8.0;
  for (Id other_id : others) {
    const Image* other = project.FindImage(other_id);
    if (other == nullptr || other->width_px <= 0 || other->height_px <= 0) continue;
    const double w = 0.32 * view_w, h = w * other->height_px / other->width_px;
    const Eigen::Vector2d min(s.rect_max.x() - 8.0 - w, bottom - h), max(s.rect_max.x() - 8.0, bottom);
    if (min.y() < s.rect_min.y() + 40.0) break;
    bottom = min.y() - 24.0;
    ViewTransform inset;
    inset.zoom = static_cast<float>(w / other->width_px);
    inset.origin =
        ImVec2(static_cast<float>(min.x() + 0.5 * inset.zoom), static_cast<float>(min.y() + 0.5 * inset.zoom));
    draw->AddRectFilled(ToImVec2(min), ToImVec2(max), IM_COL32(40, 40, 44, 255));
    if (const TiledTexture* texture = texture_of(other_id))
      DrawTiledTexture(draw, *texture, inset, ToImVec2(min), ToImVec2(max));
    draw->PushClipRect(ToImVec2(min), ToImVec2(max), true);
    const Screen inset_screen{inset, min, max};
    for (const TeachEpipolarLine& line : lines) {
      if (line.from_image_id != image.id || line.in_image_id != other_id) continue;
      DrawEpipolarLine(draw, inset_screen, line, "");
      if (line.pin_id == kNoId) continue;
      const Pin* pin = project.FindPin(line.pin_id);
      for (const Pin& there : project.pins)
        if (pin != nullptr && there.image_id == other_id && there.vertex == pin->vertex)
          Marker(draw, inset_screen(there.uv_px), IM_COL32(255, 70, 200, 255), 3.5f);
    }
    draw->PopClipRect();
    draw->AddRect(ToImVec2(min), ToImVec2(max), kEpipolarColor, 0.0f, 0, 1.5f);
    DrawShadowedText(draw, ImVec2(static_cast<float>(min.x()), static_cast<float>(min.y()) - 18.0f), kEpipolarColor,
                     ("in " + FileName(other->path)).c_str());
  }
  std::vector<std::pair<ImU32, std::string>> text;
  text.push_back({IM_COL32(255, 255, 255, 240), "Epipolar geometry: select a pin, or point at the photo"});
  if (lines.empty()) {
    text.push_back({IM_COL32(200, 200, 200, 230), "(needs two calibrated photos)"});
  } else {
    text.push_back({kEpipolarColor, std::to_string(here) + " line(s) here from the other photos, " +
                                        std::to_string(others.size()) + " other photo(s) inset"});
  }
  TextBox(draw, s, text_y, text);
}

void CopyButtons(AppState* state, const char* name, const Eigen::Ref<const Eigen::MatrixXd>& m) {
  ImGui::PushID(name);
  if (ImGui::SmallButton("Copy")) ImGui::SetClipboardText(MatrixToText(m, 10).c_str());
  RecordItem(state, std::string("teach.copy.") + name);
  ImGui::SameLine();
  if (ImGui::SmallButton("Copy LaTeX")) ImGui::SetClipboardText(MatrixToLatex(m, 10).c_str());
  RecordItem(state, std::string("teach.copy_latex.") + name);
  ImGui::PopID();
}

void MatrixBlock(AppState* state, const char* name, const char* caption, const Eigen::Ref<const Eigen::MatrixXd>& m) {
  ImGui::TextUnformatted(name);
  ImGui::SameLine();
  ImGui::TextColored(kDimText, "%s", caption);
  ImGui::SameLine();
  CopyButtons(state, name, m);
  ImGui::Indent();
  ImGui::TextUnformatted(MatrixToText(m, 6).c_str());
  ImGui::Unindent();
}

// 1, 2 or 5 x 10^k, the largest not above x (x > 0).
double NiceBelow(double x) {
  const double decade = std::pow(10.0, std::floor(std::log10(x)));
  for (const double m : {5.0, 2.0, 1.0})
    if (m * decade <= x) return m * decade;
  return decade;
}

// An arrow from a to b (screen px) with its head at b when it is long enough to show one.
void Arrow(ImDrawList* draw, const Screen& s, const Eigen::Vector2d& a, const Eigen::Vector2d& b, ImU32 color) {
  Line(draw, s, a, b, color, 2.0f);
  const double length = (b - a).norm();
  if (length > 4.0) {
    const Eigen::Vector2d d = (b - a) / length, n(-d.y(), d.x());
    const double head = std::min(9.0, 0.4 * length);
    draw->AddTriangleFilled(ToImVec2(b), ToImVec2(b - head * d + 0.5 * head * n),
                            ToImVec2(b - head * d - 0.5 * head * n), color);
  }
}

// The text box of a stepped fit whose residuals are drawn `scale` times as long: `lines`, then
// a last line and, beside it, a bar of a round number of residual px about 80 screen px long.
void ResidualTextBox(ImDrawList* draw, const Screen& s, float* text_y, std::vector<std::pair<ImU32, std::string>> lines,
                     double scale) {
  const double px_per_residual_px = scale * s.view.zoom;
  if (!(px_per_residual_px > 0.0) || !std::isfinite(px_per_residual_px)) {
    TextBox(draw, s, text_y, lines);
    return;
  }
  const double bar_px = NiceBelow(80.0 / px_per_residual_px);
  const std::string bar_text = "bar = " + FormatNumber(bar_px, 4) + " px of residual";
  lines.push_back({kResidualColor, bar_text});
  const float before = *text_y;
  TextBox(draw, s, text_y, lines);
  const float line_h = ImGui::GetTextLineHeight();
  const float x0 = static_cast<float>(s.rect_min.x()) + 16.0f + ImGui::CalcTextSize(bar_text.c_str()).x + 14.0f;
  const float y0 = before - 5.0f - 0.5f * line_h - 2.0f;
  const float length = static_cast<float>(bar_px * px_per_residual_px);
  draw->AddLine(ImVec2(x0, y0), ImVec2(x0 + length, y0), kShadow, 5.0f);
  draw->AddLine(ImVec2(x0, y0), ImVec2(x0 + length, y0), kResidualColor, 3.0f);
  for (const float x : {x0, x0 + length})
    draw->AddLine(ImVec2(x, y0 - 5.0f), ImVec2(x, y0 + 5.0f), kResidualColor, 2.0f);
}

// The opening of a stepped fit's overlay: while nothing is stepped, or the fit of other photos
// is, a box that says so (`pending` or `elsewhere`) and false; true when this photo's fit is
// stepped.
bool FitStepsShownHere(ImDrawList* draw, const Screen& s, float* text_y, const AppState& state, bool on_this_photo,
                       const std::string& pending, const std::string& elsewhere) {
  std::vector<std::pair<ImU32, std::string>> lines;
  if (!TeachStepping(state)) {
    lines.push_back({kStepsText, pending});
    if (!state.teach.solver.message.empty()) lines.push_back({kStepsDimText, state.teach.solver.message});
  } else if (!on_this_photo) {
    lines.push_back({kStepsText, elsewhere});
  } else {
    return true;
  }
  TextBox(draw, s, text_y, lines);
  return false;
}

// The stepped state's residual vectors over this photo: from each pin along projection minus
// pin, residual_scale times as long, with the scale and a bar that says how many px it is.
void DrawSolverSteps(ImDrawList* draw, const AppState& state, const Image& image, const Screen& s, float* text_y) {
  const TeachSolverSteps& solver = state.teach.solver;
  const Project* stepped = TeachSteppedProject(state);
  std::vector<std::pair<ImU32, std::string>> lines;
  if (stepped == nullptr) {
    lines.push_back({kStepsText, "Solver steps: press Step (the panels then show the stepped state)"});
    TextBox(draw, s, text_y, lines);
    return;
  }
  const double scale = solver.residual_scale;
  double largest = 0.0;
  for (const TeachPinResidual& r : TeachPinResiduals(*stepped)) {
    if (r.image_id != image.id) continue;
    largest = std::max(largest, r.residual_px.norm());
    const Eigen::Vector2d a = s(r.uv_px);
    Arrow(draw, s, a, s(r.uv_px + scale * r.residual_px), kResidualColor);  // its head at the projection
    Marker(draw, a, kResidualColor, 2.5f);
  }
  const JointSolveSteps& steps = *solver.steps;
  lines.push_back({kStepsText, "Solver steps: step " + std::to_string(steps.steps) +
                                   (steps.finished ? " (finished)" : "") +
                                   ", showing the stepped state, not the project"});
  if (steps.steps > 0)
    lines.push_back({kStepsDimText, "observation cost " + FormatNumber(steps.summary.initial_cost, 5) + " -> " +
                                        FormatNumber(steps.summary.final_cost, 5) + " px^2; largest residual here " +
                                        FormatNumber(largest, 4) + " px"});
  else
    lines.push_back({kStepsDimText, std::string("the start (") + TeachStepStartName(solver.start) +
                                        "); largest residual here " + FormatNumber(largest, 4) + " px"});
  lines.push_back({kResidualColor, "residual vectors (projection - pin) drawn x" + FormatNumber(scale, 4)});
  ResidualTextBox(draw, s, text_y, std::move(lines), scale);
}

// The stepped vanishing-point fit over its photo: each segment's residual (from each endpoint
// to the line through the midpoint and the family's current vanishing point), scaled; the
// current vanishing points and their paths over the steps.
void DrawVpSteps(ImDrawList* draw, const AppState& state, const Image& image, const Screen& s, float* text_y) {
  const TeachSolverSteps& solver = state.teach.solver;
  if (!FitStepsShownHere(draw, s, text_y, state, solver.vp.image_id == image.id,
                         "Solver steps (vanishing-point fit of the active photo): press Step",
                         "Solver steps: the vanishing-point fit of another photo is stepped"))
    return;
  const VpFitSteps& steps = *solver.vp.steps;
  const double scale = solver.vp.residual_scale;
  double largest = 0.0;
  for (const TeachVpSegmentResidual& r : TeachVpResiduals(state)) {
    largest = std::max(largest, std::abs(r.residual_px));
    const ImU32 color = AxisColor(static_cast<Axis>(r.axis), 255);
    // Towards the current vanishing point, thin: the line the residual is measured to.
    const Eigen::Vector3d& v = steps.summary.vanishing_points[r.axis];
    const Eigen::Vector2d m = 0.5 * (r.a_px + r.b_px);
    if (std::abs(v.z()) > 1e-12)
      Line(draw, s, s(m), s(v.head<2>() / v.z()), AxisColor(static_cast<Axis>(r.axis), 70), 1.0f);
    Arrow(draw, s, s(r.a_px), s(r.a_px + scale * r.offset_a_px), kResidualColor);
    Arrow(draw, s, s(r.b_px), s(r.b_px + scale * r.offset_b_px), kResidualColor);
    Marker(draw, s(r.a_px), color, 2.0f);
    Marker(draw, s(r.b_px), color, 2.0f);
  }
  // Each vanishing point's path over the steps, then where it is now.
  for (int a = 0; a < 3; ++a) {
    const ImU32 color = AxisColor(static_cast<Axis>(a), 255);
    std::vector<Eigen::Vector2d> path;
    for (const VpFitState& p : steps.path)
      if (std::abs(p.vanishing_points[a].z()) > 1e-12)
        path.push_back(p.vanishing_points[a].head<2>() / p.vanishing_points[a].z());
    if (path.empty()) continue;
    for (size_t k = 1; k < path.size(); ++k) Line(draw, s, s(path[k - 1]), s(path[k]), color, 1.5f);
    for (const Eigen::Vector2d& p : path) Marker(draw, s(p), color, 2.0f);
    Marker(draw, s(path.back()), color, 5.0f);
    Label(draw, s(path.back()), color,
          std::string("v") + kAxisNames[a] + " (" + FormatNumber(path.back().x(), 5) + ", " +
              FormatNumber(path.back().y(), 5) + ")");
  }
  std::vector<std::pair<ImU32, std::string>> lines;
  lines.push_back({kStepsText, "Solver steps: vanishing-point fit, step " + std::to_string(steps.steps) +
                                   (steps.finished ? " (finished)" : "") +
                                   ", f = " + FormatNumber(steps.summary.focal_px, 6) + " px"});
  lines.push_back({kStepsDimText, "cost " + FormatNumber(steps.path.front().cost_px2, 5) + " -> " +
                                      FormatNumber(steps.summary.final_cost, 5) + " px^2; largest residual " +
                                      FormatNumber(largest, 4) + " px; dots: the vanishing points' path"});
  lines.push_back(
      {kResidualColor, "residuals (endpoint to the line through midpoint and v) drawn x" + FormatNumber(scale, 4)});
  ResidualTextBox(draw, s, text_y, std::move(lines), scale);
}

// The stepped two-view refinement over either photo of the pair: the epipolar lines of a few
// matches under the current F (solid) and the start's (dashed), each match's point and its
// distance to its line.
void DrawTwoViewSteps(ImDrawList* draw, const AppState& state, const Image& image, const Screen& s, float* text_y) {
  const TeachTwoViewSteps& two = state.teach.solver.two_view;
  const bool in_a = image.id == two.image_a, in_b = image.id == two.image_b;
  if (!FitStepsShownHere(draw, s, text_y, state, in_a || in_b,
                         "Solver steps (two-view refinement of F, active and second photo): press Step",
                         "Solver steps: the two-view refinement of two other photos is stepped"))
    return;
  const FundamentalFitSteps& steps = *two.steps;
  const ImU32 start_color = IM_COL32(200, 200, 200, 170);
  double largest = 0.0;
  int drawn = 0;
  for (const TeachEpipolarMatch& m : TeachEpipolarMatches(state)) {
    // distances_px: (uv_b to F uv_a, uv_a to F^T uv_b).
    const double d = in_a ? m.distances_px.y() : m.distances_px.x();
    largest = std::max(largest, std::abs(d));
    if (!m.drawn) continue;
    ++drawn;
    const Eigen::Vector2d& uv = in_a ? m.uv_a : m.uv_b;
    InfiniteLine(draw, s, in_a ? m.start_line_in_a : m.start_line_in_b, start_color, 1.0f, true);
    InfiniteLine(draw, s, in_a ? m.line_in_a : m.line_in_b, kEpipolarColor, 1.5f, false);
    Marker(draw, s(uv), kEpipolarColor, 4.0f);
    Label(draw, s(uv), kEpipolarColor, FormatNumber(std::abs(d), 3) + " px");
  }
  std::vector<std::pair<ImU32, std::string>> lines;
  lines.push_back({kStepsText, "Solver steps: two-view refinement of F, step " + std::to_string(steps.steps) +
                                   (steps.finished ? " (finished)" : "") + "; this photo is " + (in_a ? "a" : "b")});
  lines.push_back({kStepsDimText, "symmetric epipolar RMS " + FormatNumber(steps.start.symmetric_epipolar_rms_px, 4) +
                                      " -> " + FormatNumber(steps.summary.symmetric_epipolar_rms_px, 4) +
                                      " px; largest distance here " + FormatNumber(largest, 4) + " px"});
  lines.push_back({kEpipolarColor, "epipolar lines of " + std::to_string(drawn) + " of " +
                                       std::to_string(steps.uv1.size()) +
                                       " matches under the current F (dashed grey: the start)"});
  TextBox(draw, s, text_y, lines);
}

// log10 of each value (the plots span orders of magnitude); non-positive values as the
// smallest positive one.
std::vector<float> Log10Series(const std::vector<double>& values) {
  double smallest = std::numeric_limits<double>::infinity();
  for (const double v : values)
    if (v > 0.0 && std::isfinite(v)) smallest = std::min(smallest, v);
  std::vector<float> out;
  for (const double v : values)
    out.push_back(static_cast<float>(std::log10(v > 0.0 && std::isfinite(v) ? v
                                                : std::isfinite(smallest)   ? smallest
                                                                            : 1.0)));
  return out;
}

void Plot(const char* label, const std::vector<double>& values, const std::string& last) {
  const std::vector<float> series = Log10Series(values);
  if (series.empty()) {
    ImGui::TextColored(kDimText, "%s: (no iterations yet)", label);
    return;
  }
  const std::string overlay = std::string(label) + ": " + last;
  ImGui::PlotLines((std::string("##") + label).c_str(), series.data(), static_cast<int>(series.size()), 0,
                   overlay.c_str(), FLT_MAX, FLT_MAX, ImVec2(ImGui::GetContentRegionAvail().x, 70.0f));
}

}  // namespace

float DrawTeachImageOverlay(ImDrawList* draw_list, const AppState& state, const Image& image, const ViewTransform& view,
                            ImVec2 clip_min, ImVec2 clip_max,
                            const std::function<const TiledTexture*(Id)>& texture_of) {
  if (!state.teach.vanishing_points && !state.teach.epipolar && !state.teach.solver_steps) return clip_max.y;
  draw_list->PushClipRect(clip_min, clip_max, true);
  const Screen s{view, Eigen::Vector2d(clip_min.x, clip_min.y), Eigen::Vector2d(clip_max.x, clip_max.y)};
  float text_y = clip_max.y - 8.0f;
  if (state.teach.solver_steps) {
    switch (state.teach.solver.subject) {
      case TeachStepSubject::kJointSolve: DrawSolverSteps(draw_list, state, image, s, &text_y); break;
      case TeachStepSubject::kVanishingPoints: DrawVpSteps(draw_list, state, image, s, &text_y); break;
      case TeachStepSubject::kTwoView: DrawTwoViewSteps(draw_list, state, image, s, &text_y); break;
    }
  }
  if (state.teach.vanishing_points) DrawVanishingConstruction(draw_list, state, image, s, &text_y);
  if (state.teach.epipolar) DrawEpipolar(draw_list, state, image, s, &text_y, texture_of);
  draw_list->PopClipRect();
  // TextBox leaves text_y 6 px above the top box.
  return text_y < clip_max.y - 8.0f ? text_y + 6.0f : clip_max.y;
}

void DrawTeachViewportOverlay(ImDrawList* draw_list, const AppState& state, double length,
                              const std::function<bool(const Eigen::Vector3d&, ImVec2*)>& to_screen) {
  if (state.teach.epipolar) DrawTeachRays(draw_list, state, to_screen);
  if (state.teach.solver_steps && TeachSteppedProject(state) != nullptr) {
    const JointSolveSteps& steps = *state.teach.solver.steps;
    const ImVec2 min = draw_list->GetClipRectMin();
    DrawShadowedText(draw_list, ImVec2(min.x + 8.0f, min.y + 26.0f), kResidualColor,
                     ("Solver steps: step " + std::to_string(steps.steps) + " shown (not the project)").c_str());
  }
  if (!state.teach.vanishing_points) return;
  for (const Image& image : state.document.project().images) {
    if (!image.camera_calibrated) continue;
    const std::optional<TeachVanishing> teach = TeachVanishingFor(state, image.id);
    if (!teach) continue;
    ImVec2 a, b;
    if (!to_screen(teach->camera_center_in_world, &a)) continue;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& d = teach->directions_in_world[k];
      if (d.isZero()) continue;
      if (!to_screen(teach->camera_center_in_world + length * d, &b)) continue;
      const ImU32 color = AxisColor(static_cast<Axis>(k), 255);
      draw_list->AddLine(a, b, kShadow, 4.0f);
      draw_list->AddLine(a, b, color, 2.0f);
      draw_list->AddCircleFilled(b, 3.5f, color);
      DrawShadowedText(draw_list, ImVec2(b.x + 5.0f, b.y - 16.0f), color,
                       (std::string("to v") + kAxisNames[k]).c_str());
    }
  }
}

void DrawTeachRays(ImDrawList* draw, const AppState& state,
                   const std::function<bool(const Eigen::Vector3d&, ImVec2*)>& to_screen) {
  const std::string units = state.document.project().units;
  for (const TeachRayPair& pair : TeachRayPairs(state)) {
    const RayPairClosestPoints& c = pair.closest;
    // Each ray from its camera centre (or, when the centre is behind the view, from the first
    // of a few points towards the closest point that is in front) to a little beyond it.
    auto ray = [&](const Eigen::Vector3d& center, const Eigen::Vector3d& direction, double along) {
      ImVec2 a, b;
      if (!to_screen(center + 1.15 * std::max(along, 0.0) * direction, &b)) return;
      bool seen = false;
      for (const double f : {0.0, 0.5, 0.75, 0.9, 0.97}) {
        if (to_screen(center + f * std::max(along, 0.0) * direction, &a)) {
          seen = true;
          break;
        }
      }
      if (!seen) return;
      draw->AddLine(a, b, kShadow, 4.0f);
      draw->AddLine(a, b, kRayColor, 2.0f);
    };
    ray(pair.center_a, pair.direction_a, c.s);
    ray(pair.center_b, pair.direction_b, c.t);
    ImVec2 pa, pb;
    if (!to_screen(c.on_a, &pa) || !to_screen(c.on_b, &pb)) continue;
    draw->AddLine(pa, pb, kShadow, 5.0f);
    draw->AddLine(pa, pb, kGapColor, 3.0f);
    for (const ImVec2& p : {pa, pb}) {
      draw->AddCircleFilled(p, 5.0f, kShadow);
      draw->AddCircleFilled(p, 3.5f, kGapColor);
    }
    const std::string label = "ray gap " + FormatNumber(c.gap, 4) + " " + units + " (" +
                              FormatNumber(pair.gap_px_in_a, 3) + " / " + FormatNumber(pair.gap_px_in_b, 3) +
                              " px in the two photos)";
    // Beside the points, moved left as far as needed to stay in the panel.
    const float x =
        std::min(std::max(pa.x, pb.x) + 8.0f, draw->GetClipRectMax().x - ImGui::CalcTextSize(label.c_str()).x - 6.0f);
    DrawShadowedText(draw, ImVec2(x, 0.5f * (pa.y + pb.y) + 8.0f), kGapColor, label.c_str());
  }
}

namespace {

// The trace's cost (times cost_unit, plotted as `cost_label`), damping and step norm, one point
// per trial.
void TracePlots(const std::vector<LmIteration>& trace, double cost_unit, const char* step_unit,
                const char* cost_label = "cost") {
  std::vector<double> cost, lambda, step_norm;
  for (const LmIteration& it : trace) {
    cost.push_back(it.cost * cost_unit);
    lambda.push_back(it.lambda);
    step_norm.push_back(std::sqrt(it.step_squared_norm));
  }
  const auto last = [](const std::vector<double>& v, const char* unit) {
    return v.empty() ? std::string("-") : FormatNumber(v.back(), 4) + unit;
  };
  ImGui::TextColored(kDimText, "log10 scale; one point per trial (a rejected trial keeps the cost)");
  Plot(cost_label, cost, last(cost, " px^2"));
  Plot("damping lambda", lambda, last(lambda, ""));
  Plot("step norm", step_norm, last(step_norm, step_unit));
}

// The Solver steps window for the vanishing-point fit and the two-view refinement.
// The start of the steps: the same choice for every subject (the fits' own starts are as
// close to their answers as a solved project is, so stepping from them shows as little).
void DrawStepStart(AppState* state, bool stepping) {
  TeachSolverSteps& solver = state->teach.solver;
  ImGui::BeginDisabled(stepping);
  ImGui::SetNextItemWidth(150);
  if (ImGui::BeginCombo("start", solver.start == TeachStepStart::kPerturbed ? "perturbed" : "as it is")) {
    if (ImGui::Selectable("perturbed", solver.start == TeachStepStart::kPerturbed))
      solver.start = TeachStepStart::kPerturbed;
    if (ImGui::Selectable("as it is", solver.start == TeachStepStart::kAsIs)) solver.start = TeachStepStart::kAsIs;
    ImGui::EndCombo();
  }
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip(solver.subject == TeachStepSubject::kJointSolve
                          ? "perturbed: the solved project moved off its answer (the same way every time);\n"
                            "as it is: the project as solved (a converged solve stops at once)"
                          : "perturbed: the fit's answer moved off it (the same way every time);\n"
                            "as it is: the fit's own start (already close to its answer)");
  if (solver.start == TeachStepStart::kPerturbed) {
    ImGui::SameLine();
    float percent = static_cast<float>(100.0 * solver.perturbation);
    ImGui::SetNextItemWidth(120);
    if (ImGui::SliderFloat("amount", &percent, 1.0f, 40.0f, "%.0f %%")) solver.perturbation = percent / 100.0;
  }
  ImGui::EndDisabled();
}

// The start, then Step, Reset and `end` (which ends the stepping; `end_tooltip` on it unless null).
void DrawStepButtons(AppState* state, bool stepping, const char* end, const char* end_tooltip) {
  DrawStepStart(state, stepping);
  if (ImGui::Button("Step")) TeachStep(state);
  RecordItem(state, "teach.step");
  ImGui::SameLine();
  ImGui::BeginDisabled(!stepping);
  if (ImGui::Button("Reset")) TeachResetSteps(state);
  RecordItem(state, "teach.reset");
  ImGui::SameLine();
  if (ImGui::Button(end)) TeachEndSteps(state);
  if (end_tooltip != nullptr && ImGui::IsItemHovered()) ImGui::SetTooltip("%s", end_tooltip);
  ImGui::EndDisabled();
}

// "<what> drawn xN" and buttons that double and halve N (`*scale`).
void ResidualScaleRow(const char* what, double* scale) {
  ImGui::Text("%s drawn x%s", what, FormatNumber(*scale, 4).c_str());
  ImGui::SameLine();
  if (ImGui::SmallButton("x2")) *scale *= 2.0;
  ImGui::SameLine();
  if (ImGui::SmallButton("/2")) *scale /= 2.0;
}

void DrawFitStepsBody(AppState* state) {
  TeachSolverSteps& solver = state->teach.solver;
  const bool vp = solver.subject == TeachStepSubject::kVanishingPoints;
  ImGui::TextWrapped(vp ? "The vanishing-point fit of the active photo (f, principal point and rotation fitted to all "
                          "segments, the three directions orthogonal), one Levenberg-Marquardt iteration per Step, "
                          "from its answer moved off (perturbed) or its closed form (as it is). The project does not "
                          "change."
                        : "The refinement of F between the active and the second photo (symmetric point-to-epipolar-"
                          "line distance over the pinned matches RANSAC keeps), one Levenberg-Marquardt iteration "
                          "per Step, from its answer moved off (perturbed) or the 8-point estimate (as it is). The "
                          "project does not change.");
  if (!vp) {
    const Project& project = state->document.project();
    std::string preview = "(first photo sharing 7 pins)";
    if (const Image* second = project.FindImage(state->teach.second_image_id)) preview = FileName(second->path);
    ImGui::BeginDisabled(TeachStepping(*state));
    ImGui::SetNextItemWidth(220);
    if (ImGui::BeginCombo("second photo##steps", preview.c_str())) {
      for (const Image& image : project.images) {
        if (image.id == state->active_image_id) continue;
        ImGui::PushID(static_cast<int>(image.id));
        if (ImGui::Selectable(FileName(image.path).c_str(), image.id == state->teach.second_image_id))
          state->teach.second_image_id = image.id;
        ImGui::PopID();
      }
      ImGui::EndCombo();
    }
    ImGui::EndDisabled();
  }
  DrawStepButtons(state, TeachStepping(*state), "End", nullptr);
  if (!solver.message.empty()) ImGui::TextWrapped("%s", solver.message.c_str());
  if (!TeachStepping(*state)) return;
  ImGui::Separator();
  constexpr ImGuiTableFlags kFlags =
      ImGuiTableFlags_RowBg | ImGuiTableFlags_BordersInnerV | ImGuiTableFlags_SizingFixedFit | ImGuiTableFlags_ScrollY;
  if (vp) {
    const VpFitSteps& steps = *solver.vp.steps;
    ResidualScaleRow("residuals", &solver.vp.residual_scale);
    const double px2 = steps.summary.conditioning_scale_px * steps.summary.conditioning_scale_px;
    TracePlots(steps.trace, px2, " (log f, px / scale, rad)");
    ImGui::Text("%d step(s), %s%s", steps.steps, SolverTerminationName(steps.summary.termination),
                steps.finished ? " (finished)" : "");
    // The focal length (and principal point) per step: what the fit is for.
    if (ImGui::BeginTable("##teach_vp_steps", 4, kFlags, ImVec2(0.0f, 160.0f))) {
      ImGui::TableSetupScrollFreeze(0, 1);
      for (const char* name : {"step", "f (px)", "principal point (px)", "cost (px^2)"}) ImGui::TableSetupColumn(name);
      ImGui::TableHeadersRow();
      for (size_t k = 0; k < steps.path.size(); ++k) {
        const VpFitState& p = steps.path[k];
        ImGui::TableNextRow();
        ImGui::TableNextColumn();
        ImGui::Text("%d", static_cast<int>(k));
        ImGui::TableNextColumn();
        ImGui::TextUnformatted(FormatNumber(p.focal_px, 8).c_str());
        ImGui::TableNextColumn();
        ImGui::Text("%s, %s", FormatNumber(p.principal_point_px.x(), 6).c_str(),
                    FormatNumber(p.principal_point_px.y(), 6).c_str());
        ImGui::TableNextColumn();
        ImGui::TextUnformatted(FormatNumber(p.cost_px2, 6).c_str());
      }
      ImGui::EndTable();
    }
    return;
  }
  const FundamentalFitSteps& steps = *solver.two_view.steps;
  TracePlots(steps.trace, 1.0, " (rad, s)");
  ImGui::Text("%d step(s), %s%s", steps.steps, SolverTerminationName(steps.summary.termination),
              steps.finished ? " (finished)" : "");
  ImGui::Text("symmetric epipolar RMS %s -> %s px", FormatNumber(steps.start.symmetric_epipolar_rms_px, 4).c_str(),
              FormatNumber(steps.summary.symmetric_epipolar_rms_px, 4).c_str());
  // The symmetric distance per match (its lines drawn for the marked ones).
  if (ImGui::BeginTable("##teach_two_view_matches", 4, kFlags, ImVec2(0.0f, 180.0f))) {
    ImGui::TableSetupScrollFreeze(0, 1);
    for (const char* name : {"match", "b to F a (px)", "a to F^T b (px)", "RMS (px)"}) ImGui::TableSetupColumn(name);
    ImGui::TableHeadersRow();
    int i = 0;
    for (const TeachEpipolarMatch& m : TeachEpipolarMatches(*state)) {
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::Text("%d%s", i++, m.drawn ? " (drawn)" : "");
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(FormatNumber(m.distances_px.x(), 4).c_str());
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(FormatNumber(m.distances_px.y(), 4).c_str());
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(FormatNumber(std::sqrt(0.5 * m.distances_px.squaredNorm()), 4).c_str());
    }
    ImGui::EndTable();
  }
}

}  // namespace

void DrawTeachStepsWindow(AppState* state) {
  if (!state->teach.solver_steps) return;
  TeachSolverSteps& solver = state->teach.solver;
  ImGui::SetNextWindowSize(ImVec2(440, 560), ImGuiCond_FirstUseEver);
  const ImGuiViewport* viewport = ImGui::GetMainViewport();
  ImGui::SetNextWindowPos(ImVec2(viewport->Pos.x + viewport->Size.x - 460, viewport->Pos.y + 60),
                          ImGuiCond_FirstUseEver);
  if (!ImGui::Begin("Solver steps (teach)", &state->teach.solver_steps)) {
    ImGui::End();
    return;
  }
  // What to step: changing it ends the stepping (each subject starts from its own start).
  static constexpr TeachStepSubject kSubjects[] = {TeachStepSubject::kJointSolve, TeachStepSubject::kVanishingPoints,
                                                   TeachStepSubject::kTwoView};
  const auto subject_label = [](TeachStepSubject subject) {
    switch (subject) {
      case TeachStepSubject::kJointSolve: return "joint solve (the project)";
      case TeachStepSubject::kVanishingPoints: return "vanishing points (active photo)";
      case TeachStepSubject::kTwoView: return "two views (active + second photo)";
    }
    return "";
  };
  ImGui::SetNextItemWidth(260);
  if (ImGui::BeginCombo("step", subject_label(solver.subject))) {
    for (const TeachStepSubject subject : kSubjects) {
      if (ImGui::Selectable(subject_label(subject), solver.subject == subject) && solver.subject != subject) {
        TeachEndSteps(state);
        solver.subject = subject;
        solver.message.clear();
      }
    }
    ImGui::EndCombo();
  }
  RecordItem(state, "teach.subject");
  if (solver.subject != TeachStepSubject::kJointSolve) {
    DrawFitStepsBody(state);
    ImGui::End();
    return;
  }
  ImGui::TextWrapped(
      "The joint solve, one Levenberg-Marquardt iteration per Step. Stepping never changes the project: the image and "
      "3D panels show the stepped state until this window closes or the project is edited.");
  const bool stepping = TeachSteppedProject(*state) != nullptr;
  DrawStepButtons(state, stepping, "Show the project", "End stepping: the panels show the project again");
  if (!solver.message.empty()) ImGui::TextColored(kDimText, "%s", solver.message.c_str());
  if (stepping) {
    // Set when stepping begins so that the vectors shrink as the solve converges; the
    // lecturer may still enlarge them for the back row.
    ResidualScaleRow("residual vectors", &solver.residual_scale);
  }
  if (!stepping) {
    ImGui::End();
    return;
  }
  const JointSolveSteps& steps = *solver.steps;
  ImGui::Separator();
  // The cost Levenberg-Marquardt minimises (the observations' plus the constraints' augmented
  // Lagrangian rows), damping and step norm, after every trial.
  TracePlots(steps.trace, 1.0, " (scaled)", "LM cost (with the constraints' rows)");
  if (steps.steps > 0) {
    ImGui::Text("%d step(s), %s%s", steps.steps, SolverTerminationName(steps.summary.termination),
                steps.finished ? " (finished)" : "");
    ImGui::Text("observation cost %s -> %s px^2", FormatNumber(steps.summary.initial_cost, 5).c_str(),
                FormatNumber(steps.summary.final_cost, 5).c_str());
    ImGui::Text("pins RMS %s px, max %s px", FormatNumber(steps.summary.reprojection_rms_px, 4).c_str(),
                FormatNumber(steps.summary.reprojection_max_px, 4).c_str());
  }
  ImGui::Separator();
  const Project& project = state->document.project();
  if (project.constraints.empty()) {
    ImGui::TextColored(kDimText, "No spatial constraints.");
  } else if (steps.steps == 0) {
    ImGui::TextColored(kDimText, "Constraint violations: after the first step.");
  } else if (ImGui::BeginTable(
                 "##teach_constraints", 3,
                 ImGuiTableFlags_RowBg | ImGuiTableFlags_BordersInnerV | ImGuiTableFlags_SizingFixedFit)) {
    ImGui::TableSetupColumn("constraint", ImGuiTableColumnFlags_WidthStretch);
    ImGui::TableSetupColumn("violation");
    ImGui::TableSetupColumn("holds");
    ImGui::TableHeadersRow();
    for (const ConstraintDiagnostic& c : steps.summary.constraints) {
      const Constraint* constraint = project.FindConstraint(c.constraint_id);
      ImGui::TableNextRow();
      ImGui::TableNextColumn();
      ImGui::Text("#%d %s", static_cast<int>(c.constraint_id),
                  constraint != nullptr ? ConstraintKindName(constraint->kind) : "?");
      ImGui::TableNextColumn();
      ImGui::Text("%s %s", FormatNumber(c.residual, 3).c_str(), c.unit.c_str());
      ImGui::TableNextColumn();
      ImGui::TextColored(c.satisfied ? ImVec4(0.5f, 0.9f, 0.5f, 1.0f) : kWarningText, "%s", c.satisfied ? "yes" : "no");
    }
    ImGui::EndTable();
  }
  ImGui::End();
}

void DrawTeachNumbersWindow(AppState* state) {
  if (!state->teach.numbers) return;
  ImGui::SetNextWindowSize(ImVec2(430, 520), ImGuiCond_FirstUseEver);
  // Over the 3D panel's side of the default layout, so that the photo stays in view.
  const ImGuiViewport* viewport = ImGui::GetMainViewport();
  ImGui::SetNextWindowPos(ImVec2(viewport->Pos.x + 0.52f * viewport->Size.x, viewport->Pos.y + 80),
                          ImGuiCond_FirstUseEver);
  if (!ImGui::Begin("Numbers (teach)", &state->teach.numbers)) {
    ImGui::End();
    return;
  }
  const Project& project = state->document.project();
  const std::optional<TeachNumbers> numbers = TeachNumbersFor(*state);
  const Image* active = project.FindImage(state->active_image_id);
  if (!numbers || active == nullptr) {
    ImGui::TextWrapped("The active photo has no camera yet: draw two or three line families, or pin it.");
    ImGui::End();
    return;
  }
  ImGui::Text("Camera of %s", FileName(active->path).c_str());
  ImGui::TextColored(kDimText, "uv ~ K (R X + t); OpenCV pixels (origin top-left, y down); world z up");
  MatrixBlock(state, "K", "intrinsics, px", numbers->K);
  MatrixBlock(state, "R", "rotation, cam_from_world", numbers->R);
  MatrixBlock(state, "t", "translation, cam_from_world", numbers->t);
  MatrixBlock(state, "C", "centre in the world, -R^T t", numbers->center);
  ImGui::Separator();
  std::string preview = "(choose)";
  if (const Image* second = project.FindImage(state->teach.second_image_id)) preview = FileName(second->path);
  ImGui::SetNextItemWidth(220);
  if (ImGui::BeginCombo("second photo", preview.c_str())) {
    for (const Image& image : project.images) {
      if (image.id == active->id || !image.camera_calibrated) continue;
      ImGui::PushID(static_cast<int>(image.id));
      if (ImGui::Selectable(FileName(image.path).c_str(), image.id == state->teach.second_image_id))
        state->teach.second_image_id = image.id;
      ImGui::PopID();
    }
    ImGui::EndCombo();
  }
  RecordItem(state, "teach.second_photo");
  if (numbers->second_image_id == kNoId) {
    ImGui::TextColored(kDimText, "F needs a second calibrated photo.");
  } else {
    ImGui::TextColored(kDimText, "x_b^T F x_a = 0: a = %s, b = %s; ||F|| = 1", FileName(active->path).c_str(),
                       preview.c_str());
    MatrixBlock(state, "F", "fundamental matrix", numbers->F);
    // Appended piece by piece: GCC 12 warns -Wrestrict (a false positive, its bug 105651) on
    // the inlined "literal" + std::string temporary that a one-expression concatenation makes.
    auto point = [](const Eigen::Vector3d& e) {
      if (!(std::abs(e.z()) > 1e-12 * e.norm())) return std::string("at infinity");
      std::string text = "(";
      text += FormatNumber(e.x() / e.z(), 6);
      text += ", ";
      text += FormatNumber(e.y() / e.z(), 6);
      text += ") px";
      return text;
    };
    ImGui::Text("epipole in a: %s", point(numbers->epipole_in_a).c_str());
    ImGui::Text("epipole in b: %s", point(numbers->epipole_in_b).c_str());
  }
  ImGui::End();
}

void DrawTeachHistory(AppState* state, int* target) {
  UpdateTeachHistoryCounts(state);
  const JointSolveSummary& joint = state->last_update.joint;
  if (joint.degrees_of_freedom_left >= 0) {
    ImGui::Text("Current state: %d parameters, %d degrees of freedom left%s", joint.num_parameters,
                joint.degrees_of_freedom_left, joint.undetermined.empty() ? "" : " (hover: which)");
    if (ImGui::IsItemHovered()) {
      ImGui::BeginTooltip();
      ImGui::TextUnformatted(
          "Parameters minus the rank of the joint solve's Jacobian (pins, segments and constraints together)");
      for (const std::string& u : joint.undetermined) ImGui::TextColored(kWarningText, "%s", u.c_str());
      ImGui::EndTooltip();
    }
  } else {
    ImGui::TextColored(kDimText, "Degrees of freedom: after the next full solve");
  }
  const auto& undo = state->document.undo_stack();
  const auto& redo = state->document.redo_stack();
  const std::vector<ModellingStateCounts>& counts = state->teach.history_counts;
  const int n_undo = static_cast<int>(undo.size());
  if (counts.size() != undo.size() + redo.size() + 1) return;
  constexpr ImGuiTableFlags kFlags =
      ImGuiTableFlags_RowBg | ImGuiTableFlags_BordersInnerV | ImGuiTableFlags_SizingFixedFit | ImGuiTableFlags_ScrollY;
  if (!ImGui::BeginTable("##teach_history", 9, kFlags)) return;
  ImGui::TableSetupScrollFreeze(0, 1);
  for (const char* name : {"#", "edit", "prims", "V", "E", "F", "pins", "constr.", "segm."})
    ImGui::TableSetupColumn(name, std::string(name) == "edit" ? ImGuiTableColumnFlags_WidthStretch : 0);
  ImGui::TableHeadersRow();
  for (int position = 0; position < static_cast<int>(counts.size()); ++position) {
    const ModellingStateCounts& c = counts[position];
    const bool future = position > n_undo;
    std::string label = position == 0        ? (state->project_path.empty() ? "New project" : "Opened")
                        : position <= n_undo ? undo[position - 1].label
                                             : redo[redo.size() - (position - n_undo)].label;
    ImGui::TableNextRow();
    ImGui::TableNextColumn();
    if (future) ImGui::PushStyleColor(ImGuiCol_Text, kDimText);
    char text[32];
    std::snprintf(text, sizeof(text), "%3d##t%d", position, position);
    if (ImGui::Selectable(text, position == n_undo, ImGuiSelectableFlags_SpanAllColumns) && position != n_undo)
      *target = position;
    for (const std::string& cell : {label, std::to_string(c.primitives), std::to_string(c.vertices),
                                    std::to_string(c.edges), std::to_string(c.faces), std::to_string(c.pins),
                                    std::to_string(c.spatial_constraints), std::to_string(c.segments)}) {
      ImGui::TableNextColumn();
      ImGui::TextUnformatted(cell.c_str());
    }
    if (future) ImGui::PopStyleColor();
  }
  ImGui::EndTable();
}

}  // namespace facet::app
