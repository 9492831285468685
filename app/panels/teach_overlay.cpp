#include "app/panels/teach_overlay.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
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
// The 95 % ellipse of a 2-D Gaussian: sqrt of chi^2(2 dof) at 0.95.
constexpr double kEllipse95Scale = 2.4477;

struct Screen {
  const ViewTransform& view;
  Eigen::Vector2d rect_min, rect_max;
  Eigen::Vector2d operator()(const Eigen::Vector2d& uv_px) const {
    return {view.origin.x + static_cast<double>(view.zoom) * uv_px.x(),
            view.origin.y + static_cast<double>(view.zoom) * uv_px.y()};
  }
};

ImVec2 Im(const Eigen::Vector2d& p) { return ImVec2(static_cast<float>(p.x()), static_cast<float>(p.y())); }

void Line(ImDrawList* draw, const Screen& s, Eigen::Vector2d a, Eigen::Vector2d b, ImU32 color, float width,
          bool dashed = false) {
  const Eigen::Vector2d margin(8.0, 8.0);
  if (!ClipSegmentToRect(&a, &b, s.rect_min - margin, s.rect_max + margin)) return;
  const double length = (b - a).norm();
  if (!(length > 0.0)) return;
  const Eigen::Vector2d dir = (b - a) / length;
  const double dash = dashed ? 9.0 : length;
  for (double t = 0.0; t < length; t += dashed ? 2.0 * dash : length) {
    const Eigen::Vector2d p = a + t * dir, q = a + std::min(length, t + dash) * dir;
    draw->AddLine(Im(p), Im(q), kShadow, width + 2.0f);
    draw->AddLine(Im(p), Im(q), color, width);
  }
}

// An image line l . (u, v, 1) = 0 across the view.
void InfiniteLine(ImDrawList* draw, const Screen& s, const Eigen::Vector3d& l, ImU32 color, float width, bool dashed) {
  const double n = l.head<2>().norm();
  if (!(n > 0.0)) return;
  double cu, cv;
  s.view.ToImage(Im(0.5 * (s.rect_min + s.rect_max)), &cu, &cv);
  const Eigen::Vector2d center(cu, cv), normal = l.head<2>() / n;
  const Eigen::Vector2d foot = center - (l.dot(Eigen::Vector3d(cu, cv, 1.0)) / n) * normal;
  const Eigen::Vector2d dir(-normal.y(), normal.x());
  const double reach = 2.0 * (s.rect_max - s.rect_min).norm() / s.view.zoom + 1.0;
  Line(draw, s, s(foot - reach * dir), s(foot + reach * dir), color, width, dashed);
}

void Marker(ImDrawList* draw, const Eigen::Vector2d& p, ImU32 color, float radius) {
  draw->AddCircleFilled(Im(p), radius + 1.5f, kShadow);
  draw->AddCircleFilled(Im(p), radius, color);
}

void Label(ImDrawList* draw, const Eigen::Vector2d& p, ImU32 color, const std::string& text) {
  DrawShadowedText(draw, ImVec2(static_cast<float>(p.x()) + 8.0f, static_cast<float>(p.y()) - 18.0f), color,
                   text.c_str());
}

// Lines of text in a dark box at the view's bottom-left, its bottom at `*y`, which moves up
// above it (the photo's top, where the vanishing points often are, stays clear).
void TextBox(ImDrawList* draw, const Screen& s, float* y, const std::vector<std::pair<ImU32, std::string>>& lines) {
  if (lines.empty()) return;
  const float pad = 5.0f, line_h = ImGui::GetTextLineHeight();
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
    points.push_back(Im(s(center_px + axes * Eigen::Vector2d(std::cos(angle), std::sin(angle)))));
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

void DrawVanishingConstruction(ImDrawList* draw, const AppState& state, const Image& image, const Screen& s,
                               float* text_y) {
  const std::optional<TeachVanishing> teach = TeachVanishingFor(state, image.id);
  if (!teach) {
    TextBox(draw, s, text_y,
            {{IM_COL32(255, 255, 255, 230), "Vanishing points: no calibration from line families on this photo yet"}});
    return;
  }
  const VanishingConstruction& c = teach->construction;
  // Each family's segments extended to its own vanishing point.
  for (const Segment& segment : state.document.project().segments) {
    if (segment.image_id != image.id) continue;
    const int a = static_cast<int>(segment.axis);
    if (!c.present[a]) continue;
    const Eigen::Vector2d undistorted_a = image.camera.UndistortPixel(segment.a_px);
    const Eigen::Vector2d undistorted_b = image.camera.UndistortPixel(segment.b_px);
    const ImU32 color = AxisColor(segment.axis, 150);
    if (c.finite[a]) {
      const Eigen::Vector2d& v = c.points_px[a];
      const Eigen::Vector2d far_end =
          (undistorted_a - v).norm() > (undistorted_b - v).norm() ? undistorted_a : undistorted_b;
      Line(draw, s, s(far_end), s(v), color, 1.0f);
    } else {
      const Eigen::Vector2d mid = 0.5 * (undistorted_a + undistorted_b);
      InfiniteLine(draw, s, mid.homogeneous().cross(teach->vanishing_points_px[a]), color, 1.0f, false);
    }
  }
  if (!c.horizon.isZero()) {
    InfiniteLine(draw, s, c.horizon, kHorizonColor, 1.5f, true);
    // Labelled where it crosses the view's left part.
    const double n = c.horizon.head<2>().norm();
    if (std::abs(c.horizon.y()) > 1e-9 * n) {
      double u0, v0;
      s.view.ToImage(Im(s.rect_min + Eigen::Vector2d(40.0, 0.0)), &u0, &v0);
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
  const FocalConstruction* shown = nullptr;
  for (const FocalConstruction& f : c.focal_constructions)
    if (f.valid && (shown == nullptr || f.circle_radius_px < shown->circle_radius_px)) shown = &f;
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
    draw->AddLine(Im(s(p)), Im(s(f.focal_end_px)), kShadow, 5.0f);
    draw->AddLine(Im(s(p)), Im(s(f.focal_end_px)), kConstructionColor, 3.0f);
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
  s.view.ToImage(Im(0.5 * (s.rect_min + s.rect_max)), &cu, &cv);
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
    draw->AddRectFilled(Im(min), Im(max), IM_COL32(40, 40, 44, 255));
    if (const TiledTexture* texture = texture_of(other_id)) DrawTiledTexture(draw, *texture, inset, Im(min), Im(max));
    draw->PushClipRect(Im(min), Im(max), true);
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
    draw->AddRect(Im(min), Im(max), kEpipolarColor, 0.0f, 0, 1.5f);
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

}  // namespace

void DrawTeachImageOverlay(ImDrawList* draw_list, const AppState& state, const Image& image, const ViewTransform& view,
                           ImVec2 clip_min, ImVec2 clip_max, const std::function<const TiledTexture*(Id)>& texture_of) {
  if (!state.teach.vanishing_points && !state.teach.epipolar) return;
  draw_list->PushClipRect(clip_min, clip_max, true);
  const Screen s{view, Eigen::Vector2d(clip_min.x, clip_min.y), Eigen::Vector2d(clip_max.x, clip_max.y)};
  float text_y = clip_max.y - 8.0f;
  if (state.teach.vanishing_points) DrawVanishingConstruction(draw_list, state, image, s, &text_y);
  if (state.teach.epipolar) DrawEpipolar(draw_list, state, image, s, &text_y, texture_of);
  draw_list->PopClipRect();
}

void DrawTeachViewportOverlay(ImDrawList* draw_list, const AppState& state, double length,
                              const std::function<bool(const Eigen::Vector3d&, ImVec2*)>& to_screen) {
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
    auto point = [](const Eigen::Vector3d& e) {
      return std::abs(e.z()) > 1e-12 * e.norm()
                 ? "(" + FormatNumber(e.x() / e.z(), 6) + ", " + FormatNumber(e.y() / e.z(), 6) + ") px"
                 : std::string("at infinity");
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
