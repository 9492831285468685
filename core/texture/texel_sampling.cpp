// The bake's per-texel step: which views see a texel (their z-buffers), what each samples
// there (the photo's pyramid at the texel's footprint), and how the samples combine
// (best view, or the blend of view_blend.h after the exposure gains).
#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>

#include "core/texture/bake_internal.h"
#include "core/texture/view_blend.h"

namespace facet::bake {

bool InsidePolygon(const std::vector<Eigen::Vector2d>& polygon, const Eigen::Vector2d& p) {
  bool inside = false;
  for (size_t i = 0, j = polygon.size() - 1; i < polygon.size(); j = i++) {
    const Eigen::Vector2d& a = polygon[i];
    const Eigen::Vector2d& b = polygon[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) && p.x() < a.x() + (p.y() - a.y()) * (b.x() - a.x()) / (b.y() - a.y())) {
      inside = !inside;
    }
  }
  return inside;
}

namespace {

// The z-buffer tolerance counts the depth a face's own plane spans over this many z-buffer
// pixels, with the plane's slope capped at this tangent (87 degrees from frontal).
constexpr double kDepthPixelsSpanned = 2.0;
constexpr double kMaxSlopeTangent = 20.0;
// Exposure fit: at most this many samples per face side, only where a view's feather is at
// least kGainMinFeather (clear of its boundaries) and no channel is clipped.
constexpr int kGainSamplesPerSide = 16;
constexpr double kGainMinFeather = 0.5;
constexpr float kClippedLevel = 250.0f;
// A face's own texels lie this far inside its outline (texels); the band outside is dilated.
constexpr double kOwnTexelInset = 1.0;
// A view joins a blended texel when its weight is at least this share of the largest one.
constexpr double kContributionShare = 0.01;

double DistanceToOutline(const std::vector<Eigen::Vector2d>& polygon, const Eigen::Vector2d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < polygon.size(); ++i) {
    const Eigen::Vector2d a = polygon[i], b = polygon[(i + 1) % polygon.size()];
    const double length2 = (b - a).squaredNorm();
    const double t = length2 > 0.0 ? std::clamp((p - a).dot(b - a) / length2, 0.0, 1.0) : 0.0;
    best = std::min(best, (a + t * (b - a) - p).norm());
  }
  return best;
}

// A face's texels as one view sees them: texel (i, j, 1) -> pinhole pixel times depth.
struct FaceView {
  int view = 0;
  const ViewContext* context = nullptr;
  Eigen::Matrix3d pinhole_from_texel;
};

std::vector<FaceView> FaceViews(const FaceGeometry& g, const FaceTexture& t, const std::vector<ViewContext>& views,
                                const Eigen::Matrix3d& face_from_texel) {
  std::vector<FaceView> out;
  for (int v : t.candidates) {
    const Eigen::Matrix<double, 3, 4> projection = views[v].camera->ProjectionMatrix();
    Eigen::Matrix3d pinhole_from_face;
    pinhole_from_face.col(0) = projection.leftCols<3>() * g.axis_u;
    pinhole_from_face.col(1) = projection.leftCols<3>() * g.axis_v;
    pinhole_from_face.col(2) = projection * g.origin.homogeneous();
    out.push_back({v, &views[v], pinhole_from_face * face_from_texel});
  }
  return out;
}

enum class Look { kSeen, kHidden, kOutside };

struct ViewSample {
  float rgba[4] = {0, 0, 0, 0};
  double quality = 0.0;
  double feather = 0.0;
  Eigen::Vector2d photo = Eigen::Vector2d::Zero();   // photo px
  Eigen::Vector2d axis_u = Eigen::Vector2d::Zero();  // the texel's footprint axes, photo px
  Eigen::Vector2d axis_v = Eigen::Vector2d::Zero();
};

void Fetch(const FaceView& fv, ViewSample* s) {
  fv.context->pyramid.Sample(s->photo.x(), s->photo.y(), s->axis_u, s->axis_v, s->rgba);
}

// What view `fv` shows of texel (i, j) at world point x: seen (with the sample, its quality and
// feather), hidden by something nearer in its z-buffer, or outside its photo (or facing away).
// Quality and feather are computed only with need_weights, the colour only with fetch (else
// Fetch gets it later: a blend skips the views whose weight is negligible).
Look LookAt(const FaceView& fv, const FaceGeometry& g, int face_index, const Eigen::Vector3d& x, double i, double j,
            const TextureBakeOptions& options, bool need_weights, bool fetch, ViewSample* sample) {
  const ViewContext& v = *fv.context;
  const Eigen::Vector3d q = fv.pinhole_from_texel * Eigen::Vector3d(i, j, 1.0);
  if (!(q.z() > 0.0)) return Look::kOutside;
  const Eigen::Vector3d to_camera = v.center_in_world - x;
  const double distance = to_camera.norm();
  const double cos_angle = g.normal.dot(to_camera) / distance;
  if (!(cos_angle > 0.0)) return Look::kOutside;
  const Eigen::Vector2d uv = q.head<2>() / q.z();
  if (!v.depth.Sees(uv, q.z(), face_index, v.DepthTolerance(q.z(), cos_angle, options.depth_tolerance))) {
    const Eigen::Vector2d m = v.depth.MapFromPinhole(uv);
    const bool in_map = m.x() >= 0.0 && m.y() >= 0.0 && m.x() < v.depth.width && m.y() < v.depth.height;
    return in_map ? Look::kHidden : Look::kOutside;
  }
  const Eigen::Vector2d photo = v.PhotoFromPinhole(uv);
  if (!(photo.x() >= -0.5 && photo.y() >= -0.5 && photo.x() <= v.photo->width - 0.5 &&
        photo.y() <= v.photo->height - 0.5)) {
    return Look::kOutside;
  }
  sample->photo = photo;
  if (options.filter_footprint) {
    // The texel's axes in photo pixels: columns of the homography's Jacobian (distortion's is ~1).
    sample->axis_u = ((fv.pinhole_from_texel.col(0).head<2>() - uv * fv.pinhole_from_texel(2, 0)) / q.z())
                         .cwiseProduct(v.photo_px_per_camera_px);
    sample->axis_v = ((fv.pinhole_from_texel.col(1).head<2>() - uv * fv.pinhole_from_texel(2, 1)) / q.z())
                         .cwiseProduct(v.photo_px_per_camera_px);
  }
  if (fetch) Fetch(fv, sample);
  if (!need_weights) return Look::kSeen;
  const Eigen::Vector2d centre(0.5 * (v.photo->width - 1), 0.5 * (v.photo->height - 1));
  sample->quality = ViewQuality(cos_angle, v.camera->focal_px * v.photo_px_per_camera_px.x(), distance,
                                (photo - centre).norm() / v.half_diagonal_px, options.blend_sharpness);
  sample->feather = FeatherWeight(v.depth.BoundaryDistancePx(uv), v.feather_px);
  return Look::kSeen;
}

// The face's polygon in texel coordinates and the test for "this texel is the face's own":
// its centre inside the polygon and at least `inset` texels from its outline, so its photo
// sample (bilinear, or over its footprint) does not reach across the outline into the
// neighbour or the background. A convex polygon (most faces) is tested against its edges'
// lines, a non-convex one by the even-odd rule and the distance to its outline.
struct TexelMask {
  std::vector<Eigen::Vector2d> polygon;
  std::vector<Eigen::Vector3d> edge_lines;  // convex: a x + b y + c <= 0 inside, (a, b) unit
  double inset = 0.0;
  bool Contains(int i, int j) const {
    const Eigen::Vector2d p(i, j);
    if (!edge_lines.empty()) {
      for (const Eigen::Vector3d& l : edge_lines) {
        if (l.x() * p.x() + l.y() * p.y() + l.z() > -inset + 1e-9) return false;
      }
      return true;
    }
    return InsidePolygon(polygon, p) && DistanceToOutline(polygon, p) >= inset - 1e-9;
  }
};

TexelMask MaskOf(const FaceGeometry& g, const Eigen::Matrix3d& face_from_texel) {
  TexelMask mask;
  const Eigen::Matrix3d texel_from_face = face_from_texel.inverse();
  for (const Eigen::Vector2d& st : g.corners_st) mask.polygon.push_back((texel_from_face * st.homogeneous()).head<2>());
  const size_t n = mask.polygon.size();
  double twice_area = 0.0;
  for (size_t k = 0; k < n; ++k) {
    const Eigen::Vector2d& a = mask.polygon[k];
    const Eigen::Vector2d& b = mask.polygon[(k + 1) % n];
    twice_area += a.x() * b.y() - a.y() * b.x();
  }
  const double orientation = twice_area > 0.0 ? 1.0 : -1.0;
  std::vector<Eigen::Vector3d> lines;
  for (size_t k = 0; k < n; ++k) {
    const Eigen::Vector2d& a = mask.polygon[k];
    const Eigen::Vector2d& b = mask.polygon[(k + 1) % n];
    const Eigen::Vector2d& c = mask.polygon[(k + 2) % n];
    const Eigen::Vector2d e1 = b - a, e2 = c - b;
    if (orientation * (e1.x() * e2.y() - e1.y() * e2.x()) < 0.0) return mask;  // a reflex corner: not convex
    if (!(e1.norm() > 0.0)) return mask;
    // Outward normal of edge a -> b for this orientation.
    const Eigen::Vector2d normal = orientation * Eigen::Vector2d(e1.y(), -e1.x()).normalized();
    lines.emplace_back(normal.x(), normal.y(), -normal.dot(a));
  }
  mask.edge_lines = std::move(lines);
  return mask;
}

// The mask with the largest inset up to kOwnTexelInset that leaves the face some texels (a
// sliver keeps its outline band rather than nothing).
TexelMask OwnTexels(const FaceGeometry& g, const Eigen::Matrix3d& face_from_texel, int width, int height) {
  TexelMask mask = MaskOf(g, face_from_texel);
  for (const double inset : {kOwnTexelInset, 0.0, -0.5}) {
    mask.inset = inset;
    for (int j = 0; j < height; ++j) {
      for (int i = 0; i < width; ++i) {
        if (mask.Contains(i, j)) return mask;
      }
    }
  }
  return mask;
}

void Fill(std::uint8_t* out, const float rgb[3]) {
  for (int c = 0; c < 3; ++c) out[c] = static_cast<std::uint8_t>(std::clamp(rgb[c] + 0.5f, 0.0f, 255.0f));
  out[3] = 255;
}

}  // namespace

double ViewContext::DepthTolerance(double z, double cos_angle, double relative) const {
  const double c = std::max(cos_angle, 1e-9);
  const double tangent = std::min(std::sqrt(std::max(0.0, 1.0 - c * c)) / c, kMaxSlopeTangent);
  // One z-buffer pixel subtends 1 / (focal in z-buffer pixels) radians.
  const double map_focal = camera->focal_px * depth.scale.x();
  return z * (relative + kDepthPixelsSpanned * tangent / map_focal);
}

Eigen::Matrix3d FaceFromTexel(const FaceGeometry& face, int width, int height) {
  const Eigen::Vector2d extent = face.st_max - face.st_min;
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  m(0, 0) = extent.x() / (width - 1);
  m(0, 2) = face.st_min.x();
  m(1, 1) = -extent.y() / (height - 1);
  m(1, 2) = face.st_max.y();
  m(2, 2) = 1.0;
  return m;
}

void FitViewGains(const std::vector<FaceGeometry>& geometry, const std::vector<FaceTexture>& faces,
                  const std::vector<int>& textured, const TextureBakeOptions& options,
                  std::vector<ViewContext>* views) {
  const int view_count = static_cast<int>(views->size());
  if (view_count < 2) return;
  std::vector<ExposureOverlap> overlaps(static_cast<size_t>(view_count) * view_count);
  std::vector<std::pair<int, ViewSample>> seen;
  for (int f : textured) {
    const FaceGeometry& g = geometry[f];
    const FaceTexture& t = faces[f];
    if (t.candidates.size() < 2) continue;
    const int w = t.packed_width, h = t.packed_height;
    const Eigen::Matrix3d face_from_texel = FaceFromTexel(g, w, h);
    const std::vector<FaceView> fvs = FaceViews(g, t, *views, face_from_texel);
    const TexelMask mask = OwnTexels(g, face_from_texel, w, h);
    const int step = std::max(1, std::max(w, h) / kGainSamplesPerSide);
    for (int j = step / 2; j < h; j += step) {
      for (int i = step / 2; i < w; i += step) {
        if (!mask.Contains(i, j)) continue;
        const Eigen::Vector3d x = g.InWorld((face_from_texel * Eigen::Vector3d(i, j, 1.0)).head<2>());
        seen.clear();
        for (const FaceView& fv : fvs) {
          ViewSample s;
          if (LookAt(fv, g, f, x, i, j, options, true, true, &s) != Look::kSeen || s.feather < kGainMinFeather)
            continue;
          if (std::max({s.rgba[0], s.rgba[1], s.rgba[2]}) >= kClippedLevel) continue;
          seen.emplace_back(fv.view, s);
        }
        for (size_t a = 0; a < seen.size(); ++a) {
          for (size_t b = a + 1; b < seen.size(); ++b) {
            const int va = std::min(seen[a].first, seen[b].first), vb = std::max(seen[a].first, seen[b].first);
            const ViewSample& sa = seen[a].first == va ? seen[a].second : seen[b].second;
            const ViewSample& sb = seen[a].first == va ? seen[b].second : seen[a].second;
            ExposureOverlap& o = overlaps[static_cast<size_t>(va) * view_count + vb];
            o.view_a = va;
            o.view_b = vb;
            o.count += 1.0;
            o.sum_a += Eigen::Vector3d(sa.rgba[0], sa.rgba[1], sa.rgba[2]);
            o.sum_b += Eigen::Vector3d(sb.rgba[0], sb.rgba[1], sb.rgba[2]);
          }
        }
      }
    }
  }
  std::vector<ExposureOverlap> used;
  for (const ExposureOverlap& o : overlaps) {
    if (o.count > 0.0) used.push_back(o);
  }
  const std::vector<Eigen::Vector3d> gains = FitExposureGains(view_count, used);
  for (int v = 0; v < view_count; ++v) (*views)[v].gain = gains[v];
}

void SampleFace(const FaceGeometry& g, int face_index, const FaceTexture& t, const std::vector<ViewContext>& views,
                const TextureBakeOptions& options, ImageRgba8* page, SamplingCounts* counts) {
  const int w = t.packed_width, h = t.packed_height, pad = options.padding_texels;
  const int outer_w = w + 2 * pad, outer_h = h + 2 * pad;
  std::vector<std::uint8_t> rgba(static_cast<size_t>(outer_w) * outer_h * 4, 0);
  std::vector<std::uint8_t> filled(static_cast<size_t>(outer_w) * outer_h, 0);
  const Eigen::Matrix3d face_from_texel = FaceFromTexel(g, w, h);
  const std::vector<FaceView> fvs = FaceViews(g, t, views, face_from_texel);
  const TexelMask mask = OwnTexels(g, face_from_texel, w, h);
  // A forced photo is the face's one source where it sees the texel, as in best view.
  const bool blended = options.source == TextureSource::kBlended && !t.forced;
  // One candidate view: its sample is the texel's whatever its weight.
  const bool need_weights = blended && fvs.size() > 1;
  counts->view_share.assign(fvs.size(), 0.0);
  const float grey[3] = {kOutsideGrey, kOutsideGrey, kOutsideGrey};
  std::vector<ViewSample> samples(fvs.size());
  std::vector<Look> looks(fvs.size());

  for (int j = 0; j < h; ++j) {
    for (int i = 0; i < w; ++i) {
      if (!mask.Contains(i, j)) continue;
      const size_t k = static_cast<size_t>(j + pad) * outer_w + (i + pad);
      const Eigen::Vector3d x = g.InWorld((face_from_texel * Eigen::Vector3d(i, j, 1.0)).head<2>());
      bool any_hidden = false;
      int chosen = -1;  // the one view whose sample is the texel's
      double max_weight = 0.0, best_quality = -1.0;
      int best_seen = -1;
      for (size_t v = 0; v < fvs.size(); ++v) {
        // Best view, or a single candidate: the first view that sees the texel, fetched now.
        looks[v] = LookAt(fvs[v], g, face_index, x, i, j, options, need_weights, !need_weights, &samples[v]);
        if (looks[v] == Look::kHidden) any_hidden = true;
        if (looks[v] != Look::kSeen) continue;
        if (!need_weights) {
          chosen = static_cast<int>(v);
          break;
        }
        max_weight = std::max(max_weight, samples[v].quality * samples[v].feather);
        if (samples[v].quality > best_quality) {
          best_quality = samples[v].quality;
          best_seen = static_cast<int>(v);
        }
      }
      // Seen only on visibility boundaries (every weight 0): the best of those views.
      if (need_weights && !(max_weight > 0.0)) {
        chosen = best_seen;
        if (chosen >= 0) Fetch(fvs[chosen], &samples[chosen]);
      }
      float colour[3];
      if (chosen >= 0) {
        const Eigen::Vector3d& gain = fvs[chosen].context->gain;
        for (int c = 0; c < 3; ++c) colour[c] = static_cast<float>(gain[c] * samples[chosen].rgba[c]);
        counts->from_other_views += chosen > 0;
        if (t.forced && chosen > 0) ++counts->forced_fallback;
        counts->view_share[chosen] += 1.0;
      } else if (max_weight > 0.0) {
        // The blend of the views whose weight is not negligible, each fetched only now.
        double weight_sum = 0.0;
        double blend[3] = {0.0, 0.0, 0.0};
        bool other = false;
        for (size_t v = 0; v < fvs.size(); ++v) {
          if (looks[v] != Look::kSeen) continue;
          const double weight = samples[v].quality * samples[v].feather;
          if (!(weight >= kContributionShare * max_weight)) continue;
          Fetch(fvs[v], &samples[v]);
          const Eigen::Vector3d& gain = fvs[v].context->gain;
          for (int c = 0; c < 3; ++c) blend[c] += weight * gain[c] * samples[v].rgba[c];
          weight_sum += weight;
          other = other || v > 0;
        }
        for (int c = 0; c < 3; ++c) colour[c] = static_cast<float>(blend[c] / weight_sum);
        for (size_t v = 0; v < fvs.size(); ++v) {
          if (looks[v] != Look::kSeen) continue;
          const double weight = samples[v].quality * samples[v].feather;
          if (weight >= kContributionShare * max_weight) counts->view_share[v] += weight / weight_sum;
        }
        counts->from_other_views += other;
      } else if (any_hidden) {
        ++counts->hidden;  // left for the dilation
        continue;
      } else {
        std::copy(grey, grey + 3, colour);
      }
      Fill(&rgba[4 * k], colour);
      filled[k] = 1;
    }
  }

  // Dilation: breadth-first from the face's texels, each new texel copying its parent.
  std::deque<size_t> queue;
  for (size_t k = 0; k < filled.size(); ++k) {
    if (filled[k]) queue.push_back(k);
  }
  if (queue.empty()) {
    for (size_t k = 0; k < filled.size(); ++k) Fill(&rgba[4 * k], grey);
  }
  while (!queue.empty()) {
    const size_t k = queue.front();
    queue.pop_front();
    const int i = static_cast<int>(k % outer_w), j = static_cast<int>(k / outer_w);
    const int neighbours[4][2] = {{i - 1, j}, {i + 1, j}, {i, j - 1}, {i, j + 1}};
    for (const auto& n : neighbours) {
      if (n[0] < 0 || n[1] < 0 || n[0] >= outer_w || n[1] >= outer_h) continue;
      const size_t kn = static_cast<size_t>(n[1]) * outer_w + n[0];
      if (filled[kn]) continue;
      filled[kn] = 1;
      std::copy(&rgba[4 * k], &rgba[4 * k] + 4, &rgba[4 * kn]);
      queue.push_back(kn);
    }
  }
  for (int j = 0; j < outer_h; ++j) {
    std::copy(&rgba[static_cast<size_t>(j) * outer_w * 4], &rgba[static_cast<size_t>(j + 1) * outer_w * 4],
              page->At(t.x - pad, t.y - pad + j));
  }
}

}  // namespace facet::bake
