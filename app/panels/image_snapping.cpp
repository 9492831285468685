#include "app/panels/image_snapping.h"

#include <chrono>
#include <utility>

#include "app/panels/image_overlay.h"

namespace facet::app {

const PhotoSnapFeatures* PhotoFeatures::Get(const AppState& state, Id image_id) {
  const auto photo = state.photos.find(image_id);
  if (photo == state.photos.end() || photo->second.empty()) return nullptr;
  Entry& entry = entries_[image_id];
  if (entry.pixels != photo->second.pixels.data()) {
    entry = Entry();
    entry.pixels = photo->second.pixels.data();
    // A copy, so the worker never reads a photo the app frees or replaces meanwhile.
    entry.pending = std::async(std::launch::async, [copy = photo->second] {
      PhotoSnapFeatures found;
      found.corners = DetectCorners(copy).corners_px;  // a failure leaves none: snapping goes on without
      found.segments = DetectLineSegments(copy, LineDetectionOptions{});
      return found;
    });
  }
  if (!entry.ready && entry.pending.valid()) {
    const bool wait = state.bake_mode == BakeMode::kFinishNextFrame;
    if (wait || entry.pending.wait_for(std::chrono::seconds(0)) == std::future_status::ready) {
      entry.features = entry.pending.get();
      entry.ready = true;
    }
  }
  return entry.ready ? &entry.features : nullptr;
}

void PhotoFeatures::CollectGarbage(const AppState& state) {
  for (auto it = entries_.begin(); it != entries_.end();) {
    const auto photo = state.photos.find(it->first);
    const bool keep = state.document.project().FindImage(it->first) != nullptr && photo != state.photos.end() &&
                      photo->second.pixels.data() == it->second.pixels;
    it = keep ? std::next(it) : entries_.erase(it);
  }
}

SnapFeatures CollectSnapFeatures(const AppState& state, const Image& image, const std::vector<ProjectedPrimitive>& model,
                                 const PhotoSnapFeatures* photo, const SnapRequest& request) {
  SnapFeatures features;
  if (photo != nullptr) {
    features.corners = photo->corners;
    features.segments = photo->segments;
    for (const Eigen::Vector4d& s : photo->segments) {
      features.detected_segment_ends.push_back(s.head<2>());
      features.detected_segment_ends.push_back(s.tail<2>());
    }
  }
  const Project& project = state.document.project();
  for (const Segment& s : project.segments) {
    if (s.image_id != image.id || s.id == request.exclude_segment) continue;
    features.segment_ends.push_back(s.a_px);
    features.segment_ends.push_back(s.b_px);
    features.segments.emplace_back(s.a_px.x(), s.a_px.y(), s.b_px.x(), s.b_px.y());
  }
  for (const ProjectedPrimitive& pp : model) {
    if (pp.primitive_id == request.exclude_primitive) continue;
    const Primitive* primitive = project.FindPrimitive(pp.primitive_id);
    if (primitive == nullptr) continue;
    const PolyMesh& mesh = primitive->mesh;
    for (VertexId v = 0; v < pp.uv_px.size(); ++v) {
      if (mesh.IsVertex(v) && pp.in_front[v]) features.model_vertices.push_back(pp.uv_px[v]);
    }
    for (EdgeId e = 0; e < mesh.EdgeIdEnd(); ++e) {
      if (!mesh.IsEdge(e)) continue;
      const VertexId a = mesh.Origin(2 * e), b = mesh.Dest(2 * e);
      if (a >= pp.uv_px.size() || b >= pp.uv_px.size() || !pp.in_front[a] || !pp.in_front[b]) continue;
      features.model_edges.emplace_back(pp.uv_px[a].x(), pp.uv_px[a].y(), pp.uv_px[b].x(), pp.uv_px[b].y());
    }
  }
  if (request.vanishing_direction) {
    const auto calibration = state.last_update.calibration.find(image.id);
    if (calibration != state.last_update.calibration.end() && calibration->second.IsUsable()) {
      const Eigen::Vector3d& vp = calibration->second.vanishing_points[static_cast<int>(request.axis)];
      if (vp.squaredNorm() > 0.0) {
        features.has_vanishing_direction = true;
        features.anchor_px = request.anchor_px;
        features.vanishing_point = vp;
      }
    }
  }
  return features;
}

void DrawSnapMarker(ImDrawList* draw_list, ImVec2 p, SnapKind kind, bool with_label) {
  if (kind == SnapKind::kNone) return;
  const float r = 6.0f;
  const ImVec2 diamond[4] = {ImVec2(p.x, p.y - r), ImVec2(p.x + r, p.y), ImVec2(p.x, p.y + r), ImVec2(p.x - r, p.y)};
  draw_list->AddPolyline(diamond, 4, IM_COL32(0, 0, 0, 220), ImDrawFlags_Closed, 3.5f);
  draw_list->AddPolyline(diamond, 4, IM_COL32(80, 255, 230, 255), ImDrawFlags_Closed, 1.5f);
  if (with_label) {
    DrawShadowedText(draw_list, ImVec2(p.x + r + 4.0f, p.y + 2.0f), IM_COL32(80, 255, 230, 255), SnapKindName(kind));
  }
}

}  // namespace facet::app
