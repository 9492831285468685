#include "core/solve/pin_proposals.h"

#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>

#include <Eigen/Dense>

#include "core/geometry/ray_pair.h"
#include "core/mesh/triangulate.h"
#include "core/util/timer.h"

namespace facet {
namespace {

constexpr double kInvalid = -2.0;  // a score of a position that compared too little

// A camera in the px of its grey photo (working resolution).
struct WorkingView {
  Camera camera;
  const GrayImage* photo = nullptr;
  double scale = 1.0;  // photo px per camera px
  Eigen::Vector3d center = Eigen::Vector3d::Zero();

  Eigen::Vector2d ToPhoto(const Eigen::Vector2d& uv_camera) const {
    return (uv_camera + Eigen::Vector2d::Constant(0.5)) * scale - Eigen::Vector2d::Constant(0.5);
  }
  Eigen::Vector2d FromPhoto(const Eigen::Vector2d& uv_photo) const {
    return (uv_photo + Eigen::Vector2d::Constant(0.5)) / scale - Eigen::Vector2d::Constant(0.5);
  }
  bool InsidePhoto(const Eigen::Vector2d& uv_photo) const {
    return uv_photo.x() >= 0.0 && uv_photo.y() >= 0.0 && uv_photo.x() <= photo->width - 1 &&
           uv_photo.y() <= photo->height - 1;
  }
};

WorkingView MakeWorkingView(const ProposalView& view) {
  WorkingView w;
  w.photo = view.photo;
  w.camera = *view.camera;
  w.scale = view.camera->width_px > 0 ? static_cast<double>(view.photo->width) / view.camera->width_px : 1.0;
  w.camera.focal_px *= w.scale;
  w.camera.principal_point_px = w.ToPhoto(view.camera->principal_point_px);
  w.camera.width_px = view.photo->width;
  w.camera.height_px = view.photo->height;
  w.center = w.camera.CenterInWorld();
  return w;
}

// The homography of the plane with unit normal n through x (world) from A's normalised
// camera rays (K_A^-1 times A's pinhole px, in A's camera frame) to V's pinhole photo px.
Eigen::Matrix3d PlaneHomography(const WorkingView& a, const WorkingView& v, const Eigen::Vector3d& n,
                                const Eigen::Vector3d& x) {
  const Eigen::Matrix3d& r_a = a.camera.cam_from_world_rotation;
  const Eigen::Matrix3d& r_v = v.camera.cam_from_world_rotation;
  const Eigen::Vector3d t_av = r_v * a.center + v.camera.cam_from_world_translation;  // A's centre in V
  const double plane_distance = n.dot(x - a.center);
  return v.camera.K() * (r_v + t_av * n.transpose() / plane_distance) * r_a.transpose();
}

bool InsidePolygon2d(const std::vector<Eigen::Vector2d>& polygon, const Eigen::Vector2d& p) {
  bool inside = false;
  for (size_t i = 0, j = polygon.size() - 1; i < polygon.size(); j = i++) {
    const Eigen::Vector2d& a = polygon[i];
    const Eigen::Vector2d& b = polygon[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) && p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x()) {
      inside = !inside;
    }
  }
  return inside;
}

// A's window: its samples' values and rays, each labelled with the plane that warps it.
struct Window {
  std::vector<Eigen::Vector3d> rays;                      // K_A^-1 (pinhole px, 1), A's camera frame
  std::vector<Eigen::Vector2d> uvs;                       // A's photo px
  Eigen::Vector3d center_ray = Eigen::Vector3d::UnitZ();  // the pin's
  std::vector<float> values;
  std::vector<int> labels;               // index into normals, -1: not compared
  std::vector<Eigen::Vector3d> normals;  // the faces', then the fronto-parallel plane's
  int total = 0;                         // samples in the window
  int labelled = 0;                      // of them, on a plane (in A's photo, and on a face when there are faces)
};

double Parabola(double minus, double zero, double plus) {
  const double denominator = minus - 2.0 * zero + plus;
  if (!(denominator < 0.0)) return 0.0;  // not a maximum
  return std::clamp(0.5 * (minus - plus) / denominator, -1.0, 1.0);
}

// The derivative (V px per A px) at A's ray `ray` of the map A px -> V pinhole px of
// homography h (A's lens distortion left out: it bends the map little over a pixel).
Eigen::Matrix2d HomographyJacobian(const Eigen::Matrix3d& h, const Eigen::Matrix3d& k_inv, const Eigen::Vector3d& ray) {
  auto map = [&](const Eigen::Vector3d& r) -> Eigen::Vector2d {
    const Eigen::Vector3d q = h * r;
    return q.head<2>() / q.z();
  };
  Eigen::Matrix2d j;
  j.col(0) = map(ray + k_inv.col(0)) - map(ray);
  j.col(1) = map(ray + k_inv.col(1)) - map(ray);
  return j;
}

// A pixel's footprint as 3 x 3 taps over [-1/2, 1/2]^2: a photo sampled where the other photo
// sees coarser is averaged over the other's pixel, so that both see the texture alike.
const double kTaps[] = {-1.0 / 3.0, 0.0, 1.0 / 3.0};

bool LargestStretch(const Eigen::Matrix2d& j, double* stretch) {
  if (!j.allFinite()) return false;
  *stretch = Eigen::JacobiSVD<Eigen::Matrix2d>(j).singularValues()(0);
  return true;
}

class Matcher {
 public:
  Matcher(const WorkingView& a, const Window& window, const PinProposalOptions& options)
      : a_(a), window_(window), options_(options) {}

  // Which planes (labels) a view sees: a face turned away from it is hidden there.
  std::vector<bool> LabelsSeenBy(const WorkingView& v, const Eigen::Vector3d& x) const {
    std::vector<bool> seen(window_.normals.size(), true);
    const Eigen::Vector3d to_view = (v.center - x).normalized();
    for (size_t l = 0; l + 1 < window_.normals.size(); ++l)
      seen[l] = window_.normals[l].dot(to_view) >= options_.min_view_cos;
    return seen;
  }

  // v's photo at pinhole px `pinhole`, averaged over `taps` (pinhole px offsets) when given.
  static bool SampleView(const WorkingView& v, const Eigen::Vector2d& pinhole, const std::vector<Eigen::Vector2d>& taps,
                         float* value) {
    auto sample = [&](const Eigen::Vector2d& p, float* out) {
      const Eigen::Vector2d uv = v.camera.HasDistortion() ? v.camera.DistortPixel(p) : p;
      return v.photo->Sample(uv.x(), uv.y(), out);
    };
    if (taps.empty()) return sample(pinhole, value);
    float sum = 0.0f;
    for (const Eigen::Vector2d& t : taps) {
      float tap = 0.0f;
      if (!sample(pinhole + t, &tap)) return false;
      sum += tap;
    }
    *value = sum / static_cast<float>(taps.size());
    return true;
  }

  // NCC of A's window against view v, each sample warped by its plane's homography through x
  // and moved by shift (v's pinhole photo px). kInvalid when too little was compared.
  double Ncc(const WorkingView& v, const Eigen::Vector3d& x, const std::vector<bool>& seen,
             const Eigen::Vector2d& shift) const {
    std::vector<Eigen::Matrix3d> h(window_.normals.size());
    // Where v sees finer than A: v averaged over A's pixel (taps in v's px).
    std::vector<std::vector<Eigen::Vector2d>> taps(h.size());
    const Eigen::Matrix3d k_inv = a_.camera.K().inverse();
    for (size_t l = 0; l < h.size(); ++l) {
      if (!seen[l]) continue;
      h[l] = PlaneHomography(a_, v, window_.normals[l], x);
      const Eigen::Matrix2d j = HomographyJacobian(h[l], k_inv, window_.center_ray);
      double stretch = 0.0;
      if (LargestStretch(j, &stretch) && stretch > 1.0) {
        for (double ty : kTaps)
          for (double tx : kTaps) taps[l].push_back(j * Eigen::Vector2d(tx, ty));
      }
    }
    double sa = 0, sb = 0, saa = 0, sbb = 0, sab = 0;
    int n = 0;
    for (size_t k = 0; k < window_.rays.size(); ++k) {
      const int l = window_.labels[k];
      if (l < 0 || !seen[l]) continue;
      const Eigen::Vector3d q = h[l] * window_.rays[k];
      if (!(q.z() > 0.0)) continue;
      const Eigen::Vector2d pinhole = q.head<2>() / q.z() + shift;
      float value = 0.0f;
      if (!SampleView(v, pinhole, taps[l], &value)) continue;
      const double va = window_.values[k], vb = value;
      sa += va;
      sb += vb;
      saa += va * va;
      sbb += vb * vb;
      sab += va * vb;
      ++n;
    }
    if (n < options_.min_compared_fraction * window_.labelled || n < 9) return kInvalid;
    const double var_a = saa - sa * sa / n, var_b = sbb - sb * sb / n;
    const double cov = sab - sa * sb / n;
    // A flat patch in v matches nothing (and must not divide by ~0).
    const double floor = 1e-6 * n;
    if (var_a <= floor || var_b <= floor) return 0.0;
    return cov / std::sqrt(var_a * var_b);
  }

 private:
  const WorkingView& a_;
  const Window& window_;
  const PinProposalOptions& options_;
};

PointMatch Refused(PointMatch match, PinProposalRefusal refusal, std::string reason) {
  match.refusal = refusal;
  match.reason = std::move(reason);
  return match;
}

std::string Fixed(double value, int digits) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.*f", digits, value);
  return text;
}

// A face in its plane's frame, for hit tests.
struct PlanarFace {
  Eigen::Vector3d normal, origin, axis_u, axis_v;
  std::vector<Eigen::Vector2d> polygon;
};

// The nearest face turned to A that A's ray along `dir` (world) hits, or -1.
int FaceHit(const std::vector<PlanarFace>& planar, const WorkingView& a, const Eigen::Vector3d& dir) {
  int label = -1;
  double nearest = std::numeric_limits<double>::infinity();
  for (size_t f = 0; f < planar.size(); ++f) {
    const PlanarFace& p = planar[f];
    const double denominator = p.normal.dot(dir);
    if (!(denominator < 0.0)) continue;  // the face turns away from A (or is edge on)
    const double lambda = p.normal.dot(p.origin - a.center) / denominator;
    if (!(lambda > 0.0) || lambda >= nearest) continue;
    const Eigen::Vector3d r = a.center + lambda * dir - p.origin;
    if (!InsidePolygon2d(p.polygon, Eigen::Vector2d(r.dot(p.axis_u), r.dot(p.axis_v)))) continue;
    nearest = lambda;
    label = static_cast<int>(f);
  }
  return label;
}

// How far (A's photo px) a compared sample stays inside its face's outline.
const Eigen::Vector2d kOutlineMargin[] = {{1.5, 0.0}, {-1.5, 0.0}, {0.0, 1.5},  {0.0, -1.5},
                                          {1.1, 1.1}, {1.1, -1.1}, {-1.1, 1.1}, {-1.1, -1.1}};

// A's window around the pin, labelled by the faces (or the fronto-parallel plane).
Window MakeWindow(const WorkingView& a, const Eigen::Vector2d& pin_photo, const Eigen::Vector3d& point_on_ray,
                  const Eigen::Vector3d& x_estimate, const std::vector<ProposalFace>& faces,
                  const PinProposalOptions& options) {
  Window w;
  const int h = options.window_half_px;
  const Eigen::Matrix3d k_inv = a.camera.K().inverse();
  w.center_ray = k_inv * (a.camera.HasDistortion() ? a.camera.UndistortPixel(pin_photo) : pin_photo).homogeneous();
  const Eigen::Matrix3d world_from_a = a.camera.cam_from_world_rotation.transpose();
  // The faces moved with the point onto A's ray (the model's vertex may sit off the pin's ray).
  const Eigen::Vector3d delta = point_on_ray - x_estimate;
  std::vector<PlanarFace> planar;
  for (const ProposalFace& f : faces) {
    if (f.corners_in_world.size() < 3) continue;
    PlanarFace p;
    p.normal = f.normal.normalized();
    p.origin = f.corners_in_world[0] + delta;
    const Eigen::Vector3d e = f.corners_in_world[1] - f.corners_in_world[0];
    p.axis_u = (e - e.dot(p.normal) * p.normal).normalized();
    p.axis_v = p.normal.cross(p.axis_u);
    for (const Eigen::Vector3d& c : f.corners_in_world) {
      const Eigen::Vector3d r = c + delta - p.origin;
      p.polygon.emplace_back(r.dot(p.axis_u), r.dot(p.axis_v));
    }
    planar.push_back(std::move(p));
    w.normals.push_back(planar.back().normal);
  }
  // A face A sees edge on is left out like one B sees edge on (Matcher::LabelsSeenBy).
  std::vector<bool> steep_in_a;
  for (const PlanarFace& p : planar)
    steep_in_a.push_back(p.normal.dot((a.center - point_on_ray).normalized()) >= options.min_view_cos);
  const Eigen::Vector3d fronto = a.camera.cam_from_world_rotation.row(2).transpose();
  w.normals.push_back(fronto);
  const int fronto_label = static_cast<int>(w.normals.size()) - 1;
  int on_faces = 0;
  for (int j = -h; j <= h; ++j) {
    for (int i = -h; i <= h; ++i) {
      const Eigen::Vector2d uv = pin_photo + Eigen::Vector2d(i, j);
      float value = 0.0f;
      ++w.total;
      if (!a.photo->Sample(uv.x(), uv.y(), &value)) continue;
      const Eigen::Vector2d pinhole = a.camera.HasDistortion() ? a.camera.UndistortPixel(uv) : uv;
      const Eigen::Vector3d ray = k_inv * pinhole.homogeneous();
      int label = planar.empty() ? fronto_label : FaceHit(planar, a, world_from_a * ray);
      if (label >= 0 && label != fronto_label && !steep_in_a[label]) label = -1;
      // A sample near a face's outline mixes the face with what is beyond it, differently in
      // each photo: only samples whose neighbourhood lies on the same face are compared.
      if (label >= 0 && label != fronto_label) {
        for (const Eigen::Vector2d& offset : kOutlineMargin) {
          const Eigen::Vector2d near_uv = uv + offset;
          const Eigen::Vector2d near_pinhole = a.camera.HasDistortion() ? a.camera.UndistortPixel(near_uv) : near_uv;
          if (FaceHit(planar, a, world_from_a * (k_inv * near_pinhole.homogeneous())) != label) {
            label = -1;
            break;
          }
        }
      }
      if (label >= 0 && label != fronto_label) ++on_faces;
      w.rays.push_back(ray);
      w.uvs.push_back(uv);
      w.values.push_back(value);
      w.labels.push_back(label);
    }
  }
  // Too little of the window on the faces (a vertex seen edge on, a face smaller than the
  // window): the fronto-parallel plane warps all of it.
  if (!planar.empty() && on_faces < options.min_face_fraction * w.total) {
    std::fill(w.labels.begin(), w.labels.end(), fronto_label);
  }
  w.labelled = static_cast<int>(std::count_if(w.labels.begin(), w.labels.end(), [](int l) { return l >= 0; }));
  return w;
}

// Where B sees coarser than A, A's window averaged over B's pixel (taps in A's px), with the
// faces' (or the plane's) homography to B through x.
void PrefilterWindowFor(const WorkingView& a, const WorkingView& b, const Eigen::Vector3d& x, Window* w) {
  const Eigen::Matrix3d k_inv = a.camera.K().inverse();
  for (size_t l = 0; l < w->normals.size(); ++l) {
    const Eigen::Matrix2d j = HomographyJacobian(PlaneHomography(a, b, w->normals[l], x), k_inv, w->center_ray);
    if (!j.allFinite() || std::abs(j.determinant()) < 1e-12) continue;
    const Eigen::Matrix2d j_inv = j.inverse();
    double stretch = 0.0;
    if (!LargestStretch(j_inv, &stretch) || stretch <= 1.0) continue;
    for (size_t k = 0; k < w->values.size(); ++k) {
      if (w->labels[k] != static_cast<int>(l)) continue;
      float sum = 0.0f;
      int n = 0;
      for (double ty : kTaps) {
        for (double tx : kTaps) {
          const Eigen::Vector2d uv = w->uvs[k] + j_inv * Eigen::Vector2d(tx, ty);
          float tap = 0.0f;
          if (!a.photo->Sample(uv.x(), uv.y(), &tap)) continue;
          sum += tap;
          ++n;
        }
      }
      if (n > 0) w->values[k] = sum / static_cast<float>(n);
    }
  }
}

double WindowStd(const Window& w) {
  double s = 0, ss = 0;
  int n = 0;
  for (size_t k = 0; k < w.values.size(); ++k) {
    if (w.labels[k] < 0) continue;
    s += w.values[k];
    ss += static_cast<double>(w.values[k]) * w.values[k];
    ++n;
  }
  if (n < 2) return 0.0;
  return std::sqrt(std::max(0.0, ss / n - (s / n) * (s / n)));
}

}  // namespace

const char* PinProposalRefusalName(PinProposalRefusal refusal) {
  switch (refusal) {
    case PinProposalRefusal::kNone: return "proposed";
    case PinProposalRefusal::kBehindCamera: return "behind the camera";
    case PinProposalRefusal::kOutsidePhoto: return "outside the photo";
    case PinProposalRefusal::kFacesAway: return "faces away";
    case PinProposalRefusal::kOccluded: return "hidden by the model";
    case PinProposalRefusal::kNoBaseline: return "no baseline";
    case PinProposalRefusal::kFlatWindow: return "flat window";
    case PinProposalRefusal::kNoMatch: return "no match";
    case PinProposalRefusal::kLowScore: return "low score";
    case PinProposalRefusal::kPeakAtSearchEnd: return "peak at the search's end";
    case PinProposalRefusal::kNotUnique: return "not unique";
    case PinProposalRefusal::kInconsistent: return "inconsistent";
  }
  return "?";
}

bool PinProposalOptions::Check(std::string* error) const {
  auto fail = [&](const char* what) {
    if (error != nullptr) *error = std::string("pin proposals: ") + what;
    return false;
  };
  if (window_half_px < 1 || window_half_px > 64) return fail("window_half_px must be in 1..64");
  if (!(depth_range_fraction > 0.0 && depth_range_fraction < 1.0))
    return fail("depth_range_fraction must be in (0, 1)");
  if (!(min_search_half_px >= 1.0 && max_search_half_px >= min_search_half_px && max_search_half_px <= 5000.0))
    return fail("search half-widths must satisfy 1 <= min <= max <= 5000 px");
  if (!(min_window_std >= 0.0)) return fail("min_window_std must be >= 0");
  if (!(min_compared_fraction > 0.0 && min_compared_fraction <= 1.0))
    return fail("min_compared_fraction must be in (0, 1]");
  if (!(min_view_cos >= 0.0 && min_view_cos < 1.0)) return fail("min_view_cos must be in [0, 1)");
  if (!(min_face_fraction >= 0.0 && min_face_fraction <= 1.0)) return fail("min_face_fraction must be in [0, 1]");
  if (!(min_score > -1.0 && min_score <= 1.0)) return fail("min_score must be in (-1, 1]");
  if (!(min_uniqueness >= 0.0 && min_uniqueness <= 1.0)) return fail("min_uniqueness must be in [0, 1]");
  if (!(unique_radius_px >= 1.0)) return fail("unique_radius_px must be >= 1");
  if (!(check_pin_max_px > 0.0 && check_radius_px >= 0.0 && check_min_score <= 1.0))
    return fail("check tolerances must be positive");
  return true;
}

PointMatch MatchPointAlongEpipolar(const ProposalView& a_view, const ProposalView& b_view,
                                   const std::vector<ProposalView>& checks, const Eigen::Vector3d& x_estimate,
                                   const std::vector<ProposalFace>& faces, const PinProposalOptions& options) {
  assert(a_view.camera && a_view.photo && a_view.pin_px && b_view.camera && b_view.photo &&
         "MatchPointAlongEpipolar: A needs camera, photo and pin; B camera and photo");
  PointMatch match;
  const WorkingView a = MakeWorkingView(a_view);
  const WorkingView b = MakeWorkingView(b_view);

  // Is the point where B can see it?
  const Eigen::Vector3d x_in_b = b.camera.CamFromWorld(x_estimate);
  if (!(x_in_b.z() > 0.0)) return Refused(match, PinProposalRefusal::kBehindCamera, "behind the camera");
  const Eigen::Vector2d model_in_b = b.camera.Project(x_estimate);
  if (!b.InsidePhoto(model_in_b)) return Refused(match, PinProposalRefusal::kOutsidePhoto, "outside the photo");

  // A's ray through the pin, and the model's depth on it.
  const Eigen::Vector2d pin_photo = a.ToPhoto(*a_view.pin_px);
  const Eigen::Vector2d pin_pinhole = a.camera.HasDistortion() ? a.camera.UndistortPixel(pin_photo) : pin_photo;
  const Eigen::Vector3d ray_cam = a.camera.K().inverse() * pin_pinhole.homogeneous();
  const Eigen::Vector3d ray = (a.camera.cam_from_world_rotation.transpose() * ray_cam).normalized();
  const double d0 = (x_estimate - a.center).dot(ray);
  if (!(d0 > 0.0)) return Refused(match, PinProposalRefusal::kBehindCamera, "behind the pinned photo's camera");
  const Eigen::Vector3d point_on_ray = a.center + d0 * ray;

  Window window = MakeWindow(a, pin_photo, point_on_ray, x_estimate, faces, options);
  PrefilterWindowFor(a, b, point_on_ray, &window);
  const double window_std = WindowStd(window);
  if (window_std < options.min_window_std) {
    return Refused(match, PinProposalRefusal::kFlatWindow,
                   "the pinned photo is flat around the pin (" + Fixed(window_std, 1) + " grey levels)");
  }

  // The line: B's pinhole px of C_A + d ray is (e + d m) / (e_z + d m_z).
  const Eigen::Matrix3d k_b = b.camera.K();
  const Eigen::Vector3d e = k_b * (b.camera.cam_from_world_rotation * a.center + b.camera.cam_from_world_translation);
  const Eigen::Vector3d m = k_b * (b.camera.cam_from_world_rotation * ray);
  auto depth_z = [&](double d) { return e.z() + d * m.z(); };
  auto pixel_at = [&](double d) -> Eigen::Vector2d { return (e + d * m).head<2>() / depth_z(d); };
  if (!(depth_z(d0) > 0.0)) return Refused(match, PinProposalRefusal::kBehindCamera, "behind the camera");
  double d_lo = d0 * (1.0 - options.depth_range_fraction), d_hi = d0 * (1.0 + options.depth_range_fraction);
  for (int k = 0; k < 60 && depth_z(d_lo) <= 0.05 * depth_z(d0); ++k) d_lo = 0.5 * (d_lo + d0);
  for (int k = 0; k < 60 && depth_z(d_hi) <= 0.05 * depth_z(d0); ++k) d_hi = 0.5 * (d_hi + d0);
  const Eigen::Vector2d p0 = pixel_at(d0), p_lo = pixel_at(d_lo), p_hi = pixel_at(d_hi);
  if ((p_hi - p_lo).norm() < 1e-6) {
    return Refused(match, PinProposalRefusal::kNoBaseline, "the two photos are taken from one point");
  }
  const Eigen::Vector2d along = (p_hi - p_lo).normalized();
  const Eigen::Vector2d across(-along.y(), along.x());
  const int k_axis = std::abs(along.x()) >= std::abs(along.y()) ? 0 : 1;
  // The depth on A's ray of the line's point p0 + s along (infinite past the ray's vanishing point).
  auto depth_of = [&](double s) {
    const double p = (p0 + s * along)(k_axis);
    const double denominator = p * m.z() - m(k_axis);
    return std::abs(denominator) < 1e-15 ? std::numeric_limits<double>::infinity()
                                         : (e(k_axis) - p * e.z()) / denominator;
  };
  const int s_min = -static_cast<int>(
      std::floor(std::clamp((p_lo - p0).norm(), options.min_search_half_px, options.max_search_half_px)));
  const int s_max = static_cast<int>(
      std::floor(std::clamp((p_hi - p0).norm(), options.min_search_half_px, options.max_search_half_px)));

  const Matcher matcher(a, window, options);
  auto point_at = [&](double s, Eigen::Vector3d* x) {
    const double d = depth_of(s);
    if (!(d > 0.0) || !std::isfinite(d) || !(depth_z(d) > 0.0)) return false;
    *x = a.center + d * ray;
    return true;
  };
  auto score_at = [&](double s, double t) {
    Eigen::Vector3d x;
    if (!point_at(s, &x)) return kInvalid;
    return matcher.Ncc(b, x, matcher.LabelsSeenBy(b, x), t * across);
  };

  std::vector<double> scores(static_cast<size_t>(s_max - s_min + 1), kInvalid);
  int best = -1;
  for (int s = s_min; s <= s_max; ++s) {
    const double score = score_at(s, 0.0);
    scores[s - s_min] = score;
    if (score > kInvalid && (best < 0 || score > scores[best])) best = s - s_min;
  }
  match.searched_px = static_cast<int>(scores.size());
  if (best < 0) return Refused(match, PinProposalRefusal::kNoMatch, "no position on the line could be compared");
  // The best is at an end of the compared stretch: the true peak may lie beyond it.
  auto valid = [&](int k) { return k >= 0 && k < static_cast<int>(scores.size()) && scores[k] > kInvalid; };
  if (!valid(best - 1) || !valid(best + 1)) {
    match.uv_px = b.FromPhoto(pixel_at(depth_of(best + s_min)));
    match.score = scores[best];
    return Refused(match, PinProposalRefusal::kPeakAtSearchEnd,
                   "the best match is at the end of the depths the model allows");
  }
  // The second best peak: a local maximum further than the radius.
  for (int k = 0; k < static_cast<int>(scores.size()); ++k) {
    if (!valid(k) || std::abs(k - best) <= options.unique_radius_px) continue;
    const bool peak = (!valid(k - 1) || scores[k] >= scores[k - 1]) && (!valid(k + 1) || scores[k] >= scores[k + 1]);
    if (peak) match.second_score = std::max(match.second_score, scores[k]);
  }

  // Sub-pixel: a quadratic fitted to the NCC on a 3 x 3 grid about the peak (along and
  // across the line; the two interact where the window is only a corner), its maximum taken,
  // at grid steps of 1, 1/2 and 1/4 px.
  double s = best + s_min, t = 0.0;
  for (double step : {1.0, 0.5, 0.25}) {
    double f[3][3];
    bool complete = true;
    for (int j = 0; j < 3 && complete; ++j) {
      for (int i = 0; i < 3 && complete; ++i) {
        f[j][i] = score_at(s + (i - 1) * step, t + (j - 1) * step);
        complete = f[j][i] > kInvalid;
      }
    }
    if (!complete) break;
    // f ~ c + g . (x, y) + 1/2 (x, y) H (x, y)^T on the grid's coordinates in steps.
    const Eigen::Vector2d g(0.5 * (f[1][2] - f[1][0]), 0.5 * (f[2][1] - f[0][1]));
    Eigen::Matrix2d hessian;
    hessian(0, 0) = f[1][2] - 2.0 * f[1][1] + f[1][0];
    hessian(1, 1) = f[2][1] - 2.0 * f[1][1] + f[0][1];
    hessian(0, 1) = hessian(1, 0) = 0.25 * (f[2][2] - f[2][0] - f[0][2] + f[0][0]);
    Eigen::Vector2d delta = Eigen::Vector2d::Zero();
    if (hessian.determinant() > 0.0 && hessian(0, 0) < 0.0) {
      delta = -hessian.inverse() * g;
    } else {  // not a maximum there: the best grid point
      int bi = 1, bj = 1;
      for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i)
          if (f[j][i] > f[bj][bi]) bi = i, bj = j;
      delta = Eigen::Vector2d(bi - 1, bj - 1);
    }
    delta = delta.cwiseMax(-1.0).cwiseMin(1.0);
    s += step * delta.x();
    t += step * delta.y();
  }
  match.score = score_at(s, t);
  Eigen::Vector2d found = p0 + s * along + t * across;
  if (b.camera.HasDistortion()) found = b.camera.DistortPixel(found);
  match.uv_px = b.FromPhoto(found);
  match.uniqueness = match.score > 0.0 ? 1.0 - std::max(match.second_score, 0.0) / match.score : 0.0;

  if (!(match.score >= options.min_score)) {
    return Refused(match, PinProposalRefusal::kLowScore,
                   "the best match scores " + Fixed(match.score, 2) + " (below " + Fixed(options.min_score, 2) + ")");
  }
  if (match.uniqueness < options.min_uniqueness) {
    return Refused(
        match, PinProposalRefusal::kNotUnique,
        "a second match along the line scores " + Fixed(match.second_score, 2) + " against " + Fixed(match.score, 2));
  }

  // Third photos: the point from A's pin and B's match.
  const RayPairClosestPoints rays =
      ClosestPointsOfRays(a_view.camera->CenterInWorld(), a_view.camera->RayDirectionInWorld(*a_view.pin_px),
                          b_view.camera->CenterInWorld(), b_view.camera->RayDirectionInWorld(match.uv_px));
  if (!rays.valid) return match;
  const Eigen::Vector3d x = rays.midpoint;
  for (const ProposalView& check : checks) {
    if (check.camera == nullptr || check.photo == nullptr || check.photo->empty()) continue;
    const WorkingView c = MakeWorkingView(check);
    if (!(c.camera.CamFromWorld(x).z() > 0.0)) continue;
    const Eigen::Vector2d in_c = c.camera.Project(x);
    if (!c.InsidePhoto(in_c)) continue;
    const std::vector<bool> seen = matcher.LabelsSeenBy(c, x);
    if (std::none_of(seen.begin(), seen.end(), [](bool v) { return v; })) continue;
    const std::string photo = "photo " + std::to_string(check.image_id);
    if (check.pin_px) {
      const double off_px = (check.camera->Project(x) - *check.pin_px).norm();
      if (off_px > options.check_pin_max_px) {
        return Refused(match, PinProposalRefusal::kInconsistent,
                       "the point lands " + Fixed(off_px, 1) + " px from its pin in " + photo);
      }
      ++match.checked_views;
      continue;
    }
    const int r = static_cast<int>(std::ceil(options.check_radius_px)) + 1;
    double best_score = kInvalid;
    Eigen::Vector2d best_shift = Eigen::Vector2d::Zero();
    for (int dy = -r; dy <= r; ++dy) {
      for (int dx = -r; dx <= r; ++dx) {
        const double score = matcher.Ncc(c, x, seen, Eigen::Vector2d(dx, dy));
        if (score > best_score) {
          best_score = score;
          best_shift = Eigen::Vector2d(dx, dy);
        }
      }
    }
    if (best_score <= kInvalid) continue;  // too little of the window in that photo
    if (best_score < options.check_min_score || best_shift.norm() > options.check_radius_px) {
      return Refused(match, PinProposalRefusal::kInconsistent,
                     "in " + photo + " the point matches " + Fixed(best_score, 2) + " at " +
                         Fixed(best_shift.norm() / c.scale, 1) + " px from where it lands");
    }
    ++match.checked_views;
  }
  return match;
}

namespace {

// The faces of the primitive's mesh at vertex v.
std::vector<FaceId> FacesAt(const PolyMesh& mesh, VertexId v) {
  std::vector<FaceId> faces;
  for (FaceId f = 0; f < mesh.FaceIdEnd(); ++f) {
    if (!mesh.IsFace(f)) continue;
    const std::vector<VertexId> vs = FaceVertices(mesh, f);
    if (std::find(vs.begin(), vs.end(), v) != vs.end()) faces.push_back(f);
  }
  return faces;
}

// Whether the segment from `from` to `to` crosses a triangle of the model other than the
// faces at the vertex (Moller-Trumbore), short of `to` by a small margin.
bool Occluded(const Project& project, const VertexRef& vertex, const std::vector<FaceId>& own_faces,
              const Eigen::Vector3d& from, const Eigen::Vector3d& to) {
  const Eigen::Vector3d dir = to - from;
  constexpr double kMargin = 1e-4;  // of the distance: the vertex's own neighbourhood
  for (const Primitive& primitive : project.primitives) {
    const PolyMesh& mesh = primitive.mesh;
    for (FaceId f = 0; f < mesh.FaceIdEnd(); ++f) {
      if (!mesh.IsFace(f)) continue;
      if (primitive.id == vertex.primitive_id && std::count(own_faces.begin(), own_faces.end(), f)) continue;
      for (const CornerTriangle& tri : TriangulateFace(mesh, f)) {
        const Eigen::Vector3d p0 = mesh.vertex(mesh.Origin(tri[0])).position;
        const Eigen::Vector3d e1 = mesh.vertex(mesh.Origin(tri[1])).position - p0;
        const Eigen::Vector3d e2 = mesh.vertex(mesh.Origin(tri[2])).position - p0;
        const Eigen::Vector3d pv = dir.cross(e2);
        const double det = e1.dot(pv);
        if (std::abs(det) < 1e-14) continue;
        const Eigen::Vector3d tv = from - p0;
        const double u = tv.dot(pv) / det;
        if (u < 0.0 || u > 1.0) continue;
        const Eigen::Vector3d qv = tv.cross(e1);
        const double v = dir.dot(qv) / det;
        if (v < 0.0 || u + v > 1.0) continue;
        const double t = e2.dot(qv) / det;
        if (t > kMargin && t < 1.0 - kMargin) return true;
      }
    }
  }
  return false;
}

}  // namespace

PinProposalSummary ProposePins(const Project& project, Id image_id, const GrayPhotoLookup& photo_of,
                               const PinProposalOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  PinProposalSummary summary;
  summary.image_id = image_id;
  if (!options.Check(&summary.error)) return summary;
  const Image* target = project.FindImage(image_id);
  if (target == nullptr) {
    summary.error = "no image " + std::to_string(image_id);
    return summary;
  }
  if (!target->camera_calibrated) {
    summary.error = "the photo is not calibrated";
    return summary;
  }
  const GrayImage* target_photo = photo_of(image_id);
  if (target_photo == nullptr || target_photo->empty()) {
    summary.error = "the photo is not loaded";
    return summary;
  }
  // Pins by vertex, in the order of their first pins.
  std::vector<VertexRef> order;
  std::map<std::pair<Id, VertexId>, std::vector<const Pin*>> pins_of;
  for (const Pin& pin : project.pins) {
    const auto key = std::make_pair(pin.vertex.primitive_id, pin.vertex.vertex);
    if (!pins_of.count(key)) order.push_back(pin.vertex);
    pins_of[key].push_back(&pin);
  }
  const ProposalView b{image_id, &target->camera, target_photo, std::nullopt};
  const Eigen::Vector3d center_b = target->camera.CenterInWorld();
  for (const VertexRef& vertex : order) {
    const std::vector<const Pin*>& pins = pins_of[{vertex.primitive_id, vertex.vertex}];
    if (std::any_of(pins.begin(), pins.end(), [&](const Pin* p) { return p->image_id == image_id; })) continue;
    const Primitive* primitive = project.FindPrimitive(vertex.primitive_id);
    if (primitive == nullptr || project.FindVertex(vertex) == nullptr) continue;
    const Eigen::Vector3d x = VertexInWorld(project, vertex);
    // A: the pinned photo that sees the vertex most nearly as B does.
    const Pin* source = nullptr;
    double best_cos = -2.0;
    for (const Pin* pin : pins) {
      const Image* image = project.FindImage(pin->image_id);
      if (image == nullptr || !image->camera_calibrated) continue;
      const GrayImage* photo = photo_of(pin->image_id);
      if (photo == nullptr || photo->empty()) continue;
      const double cos = (x - image->camera.CenterInWorld()).normalized().dot((x - center_b).normalized());
      if (cos > best_cos) {
        best_cos = cos;
        source = pin;
      }
    }
    if (source == nullptr) continue;
    PinProposal proposal;
    proposal.vertex = vertex;
    proposal.image_id = image_id;
    proposal.source_image_id = source->image_id;
    proposal.source_pin_id = source->id;
    auto refuse = [&](PinProposalRefusal refusal) {
      proposal.match.refusal = refusal;
      proposal.match.reason = PinProposalRefusalName(refusal);
      summary.proposals.push_back(proposal);
    };
    if (!(target->camera.CamFromWorld(x).z() > 0.0)) {
      refuse(PinProposalRefusal::kBehindCamera);
      continue;
    }
    const Eigen::Vector2d uv = target->camera.Project(x);
    if (!(uv.x() >= -0.5 && uv.y() >= -0.5 && uv.x() <= target->width_px - 0.5 && uv.y() <= target->height_px - 0.5)) {
      refuse(PinProposalRefusal::kOutsidePhoto);
      continue;
    }
    const PolyMesh& mesh = primitive->mesh;
    const std::vector<FaceId> face_ids = FacesAt(mesh, vertex.vertex);
    std::vector<ProposalFace> faces;
    bool any_faces_b = face_ids.empty();
    for (FaceId f : face_ids) {
      ProposalFace face;
      for (VertexId v : FaceVertices(mesh, f)) face.corners_in_world.push_back(mesh.vertex(v).position);
      face.normal = FaceNormal(mesh, f);
      if (face.normal.squaredNorm() < 0.5) continue;  // degenerate
      if (face.normal.dot((center_b - x).normalized()) >= options.min_view_cos) any_faces_b = true;
      faces.push_back(std::move(face));
    }
    if (!any_faces_b) {
      refuse(PinProposalRefusal::kFacesAway);
      continue;
    }
    if (Occluded(project, vertex, face_ids, center_b, x)) {
      refuse(PinProposalRefusal::kOccluded);
      continue;
    }
    const Image* source_image = project.FindImage(source->image_id);
    const ProposalView a{source->image_id, &source_image->camera, photo_of(source->image_id), source->uv_px};
    std::vector<ProposalView> checks;
    for (const Image& image : project.images) {
      if (image.id == image_id || image.id == source->image_id || !image.camera_calibrated) continue;
      const GrayImage* photo = photo_of(image.id);
      if (photo == nullptr || photo->empty()) continue;
      ProposalView check{image.id, &image.camera, photo, std::nullopt};
      for (const Pin* pin : pins) {
        if (pin->image_id == image.id) check.pin_px = pin->uv_px;
      }
      checks.push_back(check);
    }
    proposal.match = MatchPointAlongEpipolar(a, b, checks, x, faces, options);
    if (proposal.Proposed()) ++summary.proposed;
    summary.proposals.push_back(std::move(proposal));
  }
  summary.time_ms = internal::MsSince(start);
  return summary;
}

}  // namespace facet
