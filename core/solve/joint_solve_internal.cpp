#include "core/solve/joint_solve_internal.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <utility>

#include <Eigen/Eigenvalues>

#include "core/geometry/camera.h"
#include "core/geometry/cross_product_matrix.h"
#include "core/mesh/primitives.h"
#include "core/solve/world_frames.h"

namespace facet::joint_solve_internal {

namespace {

constexpr double kMinDepth = 1e-12;  // relative to the distance from the camera centre

using internal::Skew;
int LargestComponent(const Eigen::Vector3d& v) {
  int k = 0;
  v.cwiseAbs().maxCoeff(&k);
  return k;
}

std::array<int, 2> OtherComponents(int dropped) { return {dropped == 0 ? 1 : 0, dropped == 2 ? 1 : 2}; }

// The base a primitive follows (AttachOnTop's rule: a box base and a top with a rectangular
// footprint), or -1.
int AttachedBase(const Project& project, int primitive_index) {
  const Primitive& p = project.primitives[primitive_index];
  if (p.attached_to == kNoId || p.shape.kind == PrimitiveKind::kPrism || p.shape.kind == PrimitiveKind::kCylinder) {
    return -1;
  }
  for (size_t i = 0; i < project.primitives.size(); ++i) {
    if (project.primitives[i].id == p.attached_to) {
      return project.primitives[i].shape.kind == PrimitiveKind::kBox && static_cast<int>(i) != primitive_index
                 ? static_cast<int>(i)
                 : -1;
    }
  }
  return -1;
}

// Project primitive indices below `primitive_index`, nearest first (bounded against cycles).
std::vector<int> BaseChain(const Project& project, int primitive_index) {
  std::vector<int> chain;
  int cur = AttachedBase(project, primitive_index);
  while (cur >= 0 && chain.size() < 64) {
    if (std::find(chain.begin(), chain.end(), cur) != chain.end() || cur == primitive_index) break;
    chain.push_back(cur);
    cur = AttachedBase(project, cur);
  }
  return chain;
}

const char* const kParamNames[6][3] = {
    {"width (x)", "depth (y)", "height (z)"},  // box
    {"width (x)", "depth (y)", "height (z)"},  // wedge
    {"radius", "height", ""},                  // prism
    {"width (x)", "depth (y)", "height"},      // pyramid
    {"radius", "height", ""},                  // cylinder
    {"width (x)", "depth (y)", ""},            // plane
};

int KindIndex(PrimitiveKind kind) {
  switch (kind) {
    case PrimitiveKind::kBox: return 0;
    case PrimitiveKind::kWedge: return 1;
    case PrimitiveKind::kPrism: return 2;
    case PrimitiveKind::kPyramid: return 3;
    case PrimitiveKind::kCylinder: return 4;
    case PrimitiveKind::kPlane: return 5;
  }
  return 0;
}

std::string PrimitiveLabel(const Primitive& p) {
  std::string label = std::string("the ") + PrimitiveKindName(p.shape.kind);
  if (!p.name.empty())
    label += " '" + p.name + "'";
  else
    label += " " + std::to_string(p.id);
  return label;
}

std::string ImageLabel(const Image& image) {
  std::string label = "the camera of image " + std::to_string(image.id);
  if (!image.path.empty()) label += " ('" + image.path + "')";
  return label;
}

bool ValidConstraintShape(const Constraint& c, std::string* why) {
  const size_t n = c.vertices.size();
  auto need = [&](bool ok, const std::string& text) {
    if (!ok && why) *why = text;
    return ok;
  };
  switch (c.kind) {
    case ConstraintKind::kCoplanar: return need(n >= 4, "needs 4 or more vertices");
    case ConstraintKind::kCollinear: return need(n >= 3, "needs 3 or more vertices");
    case ConstraintKind::kParallel:
    case ConstraintKind::kPerpendicular:
    case ConstraintKind::kEqualLength: return need(n == 4, "needs 4 vertices (two edges)");
    case ConstraintKind::kDistance:
      return need(n == 2, "needs 2 vertices") &&
             need(c.value > 0.0 && std::isfinite(c.value), "needs a positive distance");
    case ConstraintKind::kFixedPoint:
      return need(n == 1, "needs 1 vertex") && need(c.point.allFinite(), "needs a finite point");
    case ConstraintKind::kAlongAxis: return need(n == 2, "needs 2 vertices");
    case ConstraintKind::kEdgeOnImageLine:
      return need(n == 2, "needs 2 vertices") &&
             need((c.line_b_px - c.line_a_px).norm() > 1e-9, "needs two distinct image points for its line");
  }
  return false;
}

int ConstraintRows(ConstraintKind kind, int n) {
  switch (kind) {
    case ConstraintKind::kCoplanar: return n - 3;
    case ConstraintKind::kCollinear: return 2 * (n - 2);
    case ConstraintKind::kParallel: return 2;
    case ConstraintKind::kPerpendicular: return 1;
    case ConstraintKind::kEqualLength: return 1;
    case ConstraintKind::kDistance: return 1;
    case ConstraintKind::kFixedPoint: return 3;
    case ConstraintKind::kAlongAxis: return 2;
    case ConstraintKind::kEdgeOnImageLine: return 2;
  }
  return 0;
}

// Projection of p_in_cam through the distortion and its derivatives (2 x 3, and 2 x 2 with
// respect to k1, k2 when d_k is given); false on or behind the camera.
bool ProjectInCamera(const CameraState& camera, const Eigen::Vector3d& p_in_cam, double depth_floor,
                     Eigen::Vector2d* uv_px, Eigen::Matrix<double, 2, 3>* d_p, Eigen::Matrix<double, 2, 2>* d_k) {
  const double z = p_in_cam.z();
  if (!(z > depth_floor)) return false;
  const double inv_z = 1.0 / z;
  const double x = p_in_cam.x() * inv_z;
  const double y = p_in_cam.y() * inv_z;
  const double f = camera.focal_px;
  if (camera.k1 == 0.0 && camera.k2 == 0.0) {
    *uv_px = f * Eigen::Vector2d(x, y) + camera.principal_point_px;
    if (d_p != nullptr) {
      const double fz = f * inv_z;
      *d_p << fz, 0.0, -fz * x, 0.0, fz, -fz * y;
    }
  } else {
    const Eigen::Vector2d xy(x, y);
    const double r2 = xy.squaredNorm();
    const double d = 1.0 + r2 * (camera.k1 + camera.k2 * r2);
    *uv_px = f * d * xy + camera.principal_point_px;
    if (d_p != nullptr) {
      // d(xy d)/d xy = d I + 2 (k1 + 2 k2 r^2) xy xy^T, times d xy / d p.
      const Eigen::Matrix2d j =
          d * Eigen::Matrix2d::Identity() + 2.0 * (camera.k1 + 2.0 * camera.k2 * r2) * xy * xy.transpose();
      Eigen::Matrix<double, 2, 3> d_xy;
      d_xy << inv_z, 0.0, -x * inv_z, 0.0, inv_z, -y * inv_z;
      d_p->noalias() = f * j * d_xy;
    }
  }
  if (d_k != nullptr) {
    const Eigen::Vector2d xy(x, y);
    const double r2 = xy.squaredNorm();
    d_k->col(0) = f * r2 * xy;
    d_k->col(1) = f * r2 * r2 * xy;
  }
  return true;
}

// A drawn (distorted) pixel undistorted with the camera's f, c, k (Camera::UndistortPixel)
// and its derivative with respect to (focal, cx, cy, k1, k2), by the implicit function
// theorem on D(x_u) = x_d, D(x) = x (1 + k1 r^2 + k2 r^4), x_d = (uv - c) / f.
Eigen::Vector2d UndistortDrawnPixel(const CameraState& camera, const Eigen::Vector2d& uv_px,
                                    Eigen::Matrix<double, 2, 5>* d_camera) {
  const double f = camera.focal_px;
  const Eigen::Vector2d xd = (uv_px - camera.principal_point_px) / f;
  const Eigen::Vector2d xu = UndistortNormalized(xd, camera.k1, camera.k2);
  if (d_camera != nullptr) {
    const double r2 = xu.squaredNorm();
    const double d = 1.0 + r2 * (camera.k1 + camera.k2 * r2);
    const Eigen::Matrix2d j =
        d * Eigen::Matrix2d::Identity() + 2.0 * (camera.k1 + 2.0 * camera.k2 * r2) * xu * xu.transpose();
    const Eigen::Matrix2d j_inv = j.inverse();
    d_camera->col(0) = xu - j_inv * xd;
    d_camera->middleCols<2>(1) = Eigen::Matrix2d::Identity() - j_inv;
    d_camera->col(3) = -f * j_inv * (r2 * xu);
    d_camera->col(4) = -f * j_inv * (r2 * r2 * xu);
  }
  return f * xu + camera.principal_point_px;
}

// Signed distance of point p to the line through a and b, all in px: ((a x b) . p) / |(a x b)_xy|
// in homogeneous coordinates, and its derivatives with respect to a, b and p.
double LineDistance(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& p,
                    Eigen::RowVector2d* d_a, Eigen::RowVector2d* d_b, Eigen::RowVector2d* d_p) {
  const Eigen::Vector3d ah(a.x(), a.y(), 1.0), bh(b.x(), b.y(), 1.0), ph(p.x(), p.y(), 1.0);
  const Eigen::Vector3d n = ah.cross(bh);
  const double m = n.head<2>().norm();
  if (!(m > 0.0)) {
    if (d_a) d_a->setZero();
    if (d_b) d_b->setZero();
    if (d_p) d_p->setZero();
    return 0.0;
  }
  const double num = n.dot(ph);
  const Eigen::RowVector2d u = n.head<2>().transpose() / m;  // d m / d n_xy
  if (d_p != nullptr) *d_p = n.head<2>().transpose() / m;
  if (d_a != nullptr) {
    // n = a x b: d n / d a = -[b]x; d num / d a = (b x p)^T.
    const Eigen::Matrix3d dn = -Skew(bh);
    *d_a = (bh.cross(ph)).head<2>().transpose() / m - (num / (m * m)) * (u * dn.topLeftCorner<2, 2>());
  }
  if (d_b != nullptr) {
    const Eigen::Matrix3d dn = Skew(ah);
    *d_b = (ph.cross(ah)).head<2>().transpose() / m - (num / (m * m)) * (u * dn.topLeftCorner<2, 2>());
  }
  return num / m;
}

}  // namespace

int NumShapeParams(PrimitiveKind kind) {
  switch (kind) {
    case PrimitiveKind::kPrism:
    case PrimitiveKind::kCylinder:
    case PrimitiveKind::kPlane: return 2;
    default: return 3;
  }
}

bool PinResidual(const CameraState& camera, const Eigen::Vector3d& point, const Eigen::Vector2d& uv_px,
                 Eigen::Vector2d* residual, Eigen::Matrix<double, 2, 3>* d_point, Eigen::Matrix<double, 2, 9>* d_camera,
                 Eigen::Matrix<double, 2, 2>* d_distortion) {
  const Eigen::Vector3d rel = point - camera.center_in_world;
  const Eigen::Vector3d p = camera.cam_from_world_rotation * rel;
  Eigen::Vector2d uv;
  Eigen::Matrix<double, 2, 3> d_p;
  if (!ProjectInCamera(camera, p, kMinDepth * rel.norm(), &uv, &d_p, d_distortion)) return false;
  *residual = uv - uv_px;
  if (d_point != nullptr) d_point->noalias() = d_p * camera.cam_from_world_rotation;
  if (d_camera != nullptr) {
    d_camera->col(0) = (uv - camera.principal_point_px) / camera.focal_px;
    d_camera->block<2, 2>(0, 1).setIdentity();
    d_camera->block<2, 3>(0, 3).noalias() = -d_p * Skew(p);
    d_camera->block<2, 3>(0, 6).noalias() = -d_p * camera.cam_from_world_rotation;
  }
  return true;
}

double SegmentResidual(const CameraState& camera, const Eigen::Vector3d& segment_g,
                       const Eigen::Matrix<double, 2, 3>& segment_m, int axis, Eigen::Matrix<double, 1, 6>* d_camera) {
  const Eigen::Vector3d q = camera.cam_from_world_rotation.col(axis);
  const double f = camera.focal_px;
  const Eigen::Vector2d& c = camera.principal_point_px;
  const Eigen::Vector3d v(f * q.x() + c.x() * q.z(), f * q.y() + c.y() * q.z(), q.z());
  const Eigen::Vector2d mv = segment_m * v;
  const double n = mv.norm();
  if (!(n > 0.0)) {
    if (d_camera != nullptr) d_camera->setZero();
    return 0.0;
  }
  const double num = segment_g.dot(v);
  if (d_camera != nullptr) {
    const Eigen::RowVector3d d_v = segment_g.transpose() / n - (num / (n * n * n)) * (mv.transpose() * segment_m);
    (*d_camera)(0) = d_v(0) * q.x() + d_v(1) * q.y();
    (*d_camera)(1) = d_v(0) * q.z();
    (*d_camera)(2) = d_v(1) * q.z();
    Eigen::Matrix3d k;
    k << f, 0.0, c.x(), 0.0, f, c.y(), 0.0, 0.0, 1.0;
    d_camera->tail<3>() = -d_v * k * Skew(q);
  }
  return num / n;
}

double DistortedSegmentResidual(const CameraState& camera, const Eigen::Vector2d& a_px, const Eigen::Vector2d& b_px,
                                int axis, Eigen::Matrix<double, 1, 8>* d_camera) {
  const bool with_jacobian = d_camera != nullptr;
  Eigen::Matrix<double, 2, 5> da, db;
  const Eigen::Vector2d a = UndistortDrawnPixel(camera, a_px, with_jacobian ? &da : nullptr);
  const Eigen::Vector2d b = UndistortDrawnPixel(camera, b_px, with_jacobian ? &db : nullptr);
  const Eigen::Vector3d q = camera.cam_from_world_rotation.col(axis);
  const double f = camera.focal_px;
  const Eigen::Vector2d& c = camera.principal_point_px;
  const Eigen::Vector3d v(f * q.x() + c.x() * q.z(), f * q.y() + c.y() * q.z(), q.z());
  // r = l . A / |l_xy| with l = M x v, M = (mid, 1), A = (a, 1): the distance of a to the line
  // through the midpoint and the vanishing point.
  const Eigen::Vector2d mid = 0.5 * (a + b);
  const Eigen::Vector3d mh(mid.x(), mid.y(), 1.0), ah(a.x(), a.y(), 1.0);
  const Eigen::Vector3d l = mh.cross(v);
  const double n = l.head<2>().norm();
  if (!(n > 0.0)) {
    if (with_jacobian) d_camera->setZero();
    return 0.0;
  }
  const double num = l.dot(ah);
  if (with_jacobian) {
    const Eigen::RowVector2d u = l.head<2>().transpose() / n;
    // dl = -[v]x dM + [M]x dv.
    const Eigen::Matrix3d dl_dm = -Skew(v);
    const Eigen::Matrix3d dl_dv = Skew(mh);
    auto dr_dl = [&](const Eigen::Matrix3d& dl) -> Eigen::RowVector3d {
      return ah.transpose() * dl / n - (num / (n * n)) * (u * dl.topRows<2>());
    };
    const Eigen::RowVector3d d_v = dr_dl(dl_dv);
    const Eigen::RowVector2d d_mid = dr_dl(dl_dm).head<2>();
    const Eigen::RowVector2d d_a = l.head<2>().transpose() / n + 0.5 * d_mid;
    const Eigen::RowVector2d d_b = 0.5 * d_mid;
    const Eigen::Matrix<double, 1, 5> through_points = d_a * da + d_b * db;  // f, cx, cy, k1, k2
    (*d_camera)(0) = d_v(0) * q.x() + d_v(1) * q.y() + through_points(0);
    (*d_camera)(1) = d_v(0) * q.z() + through_points(1);
    (*d_camera)(2) = d_v(1) * q.z() + through_points(2);
    Eigen::Matrix3d k;
    k << f, 0.0, c.x(), 0.0, f, c.y(), 0.0, 0.0, 1.0;
    d_camera->segment<3>(3) = -d_v * k * Skew(q);
    (*d_camera)(6) = through_points(3);
    (*d_camera)(7) = through_points(4);
  }
  return num / n;
}

bool ConstraintResidual(const ConstraintTerm& term, const std::vector<Eigen::Vector3d>& points,
                        const CameraState* camera, Eigen::VectorXd* residual, Eigen::MatrixXd* d_points,
                        Eigen::MatrixXd* d_camera) {
  const int n = static_cast<int>(points.size());
  const double s = term.scale;
  residual->resize(term.num_rows);
  if (d_points != nullptr) d_points->setZero(term.num_rows, 3 * n);
  auto dp = [&](int row, int point) { return d_points->block<1, 3>(row, 3 * point); };
  const Eigen::Matrix3d eye = Eigen::Matrix3d::Identity();
  switch (term.kind) {
    case ConstraintKind::kCoplanar: {
      const int i0 = term.span[0], i1 = term.span[1], i2 = term.span[2];
      const Eigen::Vector3d e1 = points[i1] - points[i0];
      const Eigen::Vector3d e2 = points[i2] - points[i0];
      const Eigen::Vector3d normal = e1.cross(e2);
      const double len = normal.norm();
      const Eigen::Vector3d unit = normal / len;
      int row = 0;
      for (int i = 0; i < n; ++i) {
        if (i == i0 || i == i1 || i == i2) continue;
        const Eigen::Vector3d q = points[i] - points[i0];
        const double d = q.dot(normal);
        (*residual)(row) = d / (len * s);
        if (d_points != nullptr) {
          const double a = 1.0 / (len * s);
          const double b = d / (len * len * s);
          const Eigen::Vector3d g_i = a * normal;
          const Eigen::Vector3d g_1 = a * e2.cross(q) - b * e2.cross(unit);
          const Eigen::Vector3d g_2 = a * q.cross(e1) - b * unit.cross(e1);
          dp(row, i) += g_i.transpose();
          dp(row, i1) += g_1.transpose();
          dp(row, i2) += g_2.transpose();
          dp(row, i0) -= (g_i + g_1 + g_2).transpose();
        }
        ++row;
      }
      return true;
    }
    case ConstraintKind::kCollinear: {
      const int i0 = term.span[0], i1 = term.span[1];
      const Eigen::Vector3d w = points[i1] - points[i0];
      const double len = w.norm();
      const Eigen::Vector3d u = w / len;
      const Eigen::Matrix3d d_u = (eye - u * u.transpose()) / len;
      int row = 0;
      for (int i = 0; i < n; ++i) {
        if (i == i0 || i == i1) continue;
        const Eigen::Vector3d v = points[i] - points[i0];
        const Eigen::Vector3d c = v.cross(u) / s;
        const Eigen::Matrix3d g_i = -Skew(u) / s;
        const Eigen::Matrix3d g_1 = Skew(v) * d_u / s;
        for (int k = 0; k < 2; ++k) {
          const int comp = term.kept_components[k];
          (*residual)(row + k) = c(comp);
          if (d_points != nullptr) {
            dp(row + k, i) += g_i.row(comp);
            dp(row + k, i1) += g_1.row(comp);
            dp(row + k, i0) -= g_i.row(comp) + g_1.row(comp);
          }
        }
        row += 2;
      }
      return true;
    }
    case ConstraintKind::kParallel:
    case ConstraintKind::kPerpendicular:
    case ConstraintKind::kEqualLength: {
      const Eigen::Vector3d a = points[1] - points[0];
      const Eigen::Vector3d b = points[3] - points[2];
      const double la = a.norm(), lb = b.norm();
      const Eigen::Vector3d ua = a / la, ub = b / lb;
      const Eigen::Matrix3d pa = (eye - ua * ua.transpose()) / la;
      const Eigen::Matrix3d pb = (eye - ub * ub.transpose()) / lb;
      if (term.kind == ConstraintKind::kParallel) {
        const Eigen::Vector3d c = ua.cross(ub);
        const Eigen::Matrix3d g_a = -Skew(ub) * pa;
        const Eigen::Matrix3d g_b = Skew(ua) * pb;
        for (int k = 0; k < 2; ++k) {
          const int comp = term.kept_components[k];
          (*residual)(k) = c(comp);
          if (d_points != nullptr) {
            dp(k, 1) = g_a.row(comp);
            dp(k, 0) = -g_a.row(comp);
            dp(k, 3) = g_b.row(comp);
            dp(k, 2) = -g_b.row(comp);
          }
        }
      } else if (term.kind == ConstraintKind::kPerpendicular) {
        (*residual)(0) = ua.dot(ub);
        if (d_points != nullptr) {
          const Eigen::RowVector3d g_a = ub.transpose() * pa;
          const Eigen::RowVector3d g_b = ua.transpose() * pb;
          dp(0, 1) = g_a;
          dp(0, 0) = -g_a;
          dp(0, 3) = g_b;
          dp(0, 2) = -g_b;
        }
      } else {
        (*residual)(0) = (la - lb) / s;
        if (d_points != nullptr) {
          dp(0, 1) = ua.transpose() / s;
          dp(0, 0) = -ua.transpose() / s;
          dp(0, 3) = -ub.transpose() / s;
          dp(0, 2) = ub.transpose() / s;
        }
      }
      return true;
    }
    case ConstraintKind::kDistance: {
      const Eigen::Vector3d e = points[1] - points[0];
      const double len = e.norm();
      (*residual)(0) = (len - s) / s;
      if (d_points != nullptr) {
        const Eigen::RowVector3d g = e.transpose() / (len * s);
        dp(0, 1) = g;
        dp(0, 0) = -g;
      }
      return true;
    }
    case ConstraintKind::kFixedPoint: {
      residual->head<3>() = (points[0] - term.point) / s;
      if (d_points != nullptr) d_points->block<3, 3>(0, 0) = eye / s;
      return true;
    }
    case ConstraintKind::kAlongAxis: {
      const Eigen::Vector3d e = points[1] - points[0];
      const double len = e.norm();
      const Eigen::Vector3d u = e / len;
      const Eigen::Matrix3d d_u = (eye - u * u.transpose()) / len;
      for (int k = 0; k < 2; ++k) {
        const int comp = term.kept_components[k];
        (*residual)(k) = u(comp);
        if (d_points != nullptr) {
          dp(k, 1) = d_u.row(comp);
          dp(k, 0) = -d_u.row(comp);
        }
      }
      return true;
    }
    case ConstraintKind::kEdgeOnImageLine: {
      if (d_camera != nullptr) d_camera->setZero(term.num_rows, 11);
      if (camera->k1 != 0.0 || camera->k2 != 0.0 || term.undistort_line) {
        // The line is drawn on the photo: undistort its points, then measure the pinhole
        // projections of the edge's endpoints against it.
        CameraState pinhole = *camera;
        pinhole.k1 = pinhole.k2 = 0.0;
        Eigen::Matrix<double, 2, 5> da, db;
        const Eigen::Vector2d a = UndistortDrawnPixel(*camera, term.line_a_px, &da);
        const Eigen::Vector2d b = UndistortDrawnPixel(*camera, term.line_b_px, &db);
        for (int i = 0; i < 2; ++i) {
          Eigen::Vector2d uv;
          Eigen::Matrix<double, 2, 3> d_point;
          Eigen::Matrix<double, 2, 9> d_cam;
          if (!PinResidual(pinhole, points[i], Eigen::Vector2d::Zero(), &uv, &d_point, &d_cam)) return false;
          Eigen::RowVector2d g_a, g_b, g_p;
          (*residual)(i) = LineDistance(a, b, uv, &g_a, &g_b, &g_p) / s;
          if (d_points != nullptr) dp(i, i) = g_p * d_point / s;
          if (d_camera != nullptr) {
            d_camera->block<1, 9>(i, 0) = g_p * d_cam / s;
            const Eigen::Matrix<double, 1, 5> through_line = (g_a * da + g_b * db) / s;
            d_camera->block<1, 3>(i, 0) += through_line.head<3>();
            d_camera->block<1, 2>(i, 9) = through_line.tail<2>();
          }
        }
        return true;
      }
      for (int i = 0; i < 2; ++i) {
        Eigen::Vector2d r;
        Eigen::Matrix<double, 2, 3> d_point;
        Eigen::Matrix<double, 2, 9> d_cam;
        if (!PinResidual(*camera, points[i], Eigen::Vector2d::Zero(), &r, &d_point, &d_cam)) return false;
        const Eigen::RowVector2d l = term.line_px.head<2>().transpose() / s;
        (*residual)(i) = (term.line_px.head<2>().dot(r) + term.line_px.z()) / s;
        if (d_points != nullptr) dp(i, i) = l * d_point;
        if (d_camera != nullptr) d_camera->block<1, 9>(i, 0) = l * d_cam;
      }
      return true;
    }
  }
  return false;
}

void EvaluateVertex(const JointProblem& problem, const JointState& state, VertexTerm* term) {
  const PrimitiveBlock& block = problem.primitives[term->primitive];
  const PrimitiveState& own = state.primitives[term->primitive];
  const PrimitiveState& root = state.primitives[block.root];
  const PrimitiveBlock& root_block = problem.primitives[block.root];
  const bool attached = !block.bases.empty();
  PrimitiveParams theta = own.params;
  if (attached) theta.head<2>() = root.params.head<2>();
  double height = 0.0;
  for (int b : block.bases) height += state.primitives[b].params(2);
  const Eigen::Vector3d offset = term->free_vertex >= 0 ? state.free_offsets[term->free_vertex] : term->fixed_offset;
  const Eigen::Vector3d local = term->coefficients * theta + offset + Eigen::Vector3d(0.0, 0.0, height);
  const Eigen::Matrix3d& r = root.world_from_primitive;
  term->position = r * local + root.translation;

  int col = 0;
  for (int k = 0; k < kMaxPrimitiveParams; ++k) {
    const int offset_k = attached && k < 2 ? root_block.param_offset[k] : block.param_offset[k];
    if (offset_k >= 0) term->jacobian.col(col++) = r * term->coefficients.col(k);
  }
  for (int b : block.bases) {
    if (problem.primitives[b].param_offset[2] >= 0) term->jacobian.col(col++) = r.col(2);
  }
  if (root_block.rotation_offset >= 0) {
    term->jacobian.middleCols<3>(col) = -Skew(r * local);
    col += 3;
  }
  if (root_block.translation_offset >= 0) {
    term->jacobian.middleCols<3>(col).setIdentity();
    col += 3;
  }
  if (term->free_vertex >= 0) {
    term->jacobian.middleCols<3>(col) = r;
    col += 3;
  }
}

namespace {

// The parameter columns of a vertex, in the order EvaluateVertex fills them.
std::vector<int> VertexColumns(const JointProblem& problem, const VertexTerm& term) {
  std::vector<int> cols;
  const PrimitiveBlock& block = problem.primitives[term.primitive];
  const PrimitiveBlock& root_block = problem.primitives[block.root];
  const bool attached = !block.bases.empty();
  for (int k = 0; k < kMaxPrimitiveParams; ++k) {
    const int offset_k = attached && k < 2 ? root_block.param_offset[k] : block.param_offset[k];
    if (offset_k >= 0) cols.push_back(offset_k);
  }
  for (int b : block.bases) {
    if (problem.primitives[b].param_offset[2] >= 0) cols.push_back(problem.primitives[b].param_offset[2]);
  }
  for (int offset : {root_block.rotation_offset, root_block.translation_offset,
                     term.free_vertex >= 0 ? problem.free_vertices[term.free_vertex].offset : -1}) {
    if (offset < 0) continue;
    for (int i = 0; i < 3; ++i) cols.push_back(offset + i);
  }
  return cols;
}

std::array<int, 11> CameraParameterColumns(const CameraBlock& camera) {
  std::array<int, 11> cols;
  cols.fill(-1);
  auto set = [&](int first, int offset, int count) {
    if (offset < 0) return;
    for (int i = 0; i < count; ++i) cols[first + i] = offset + i;
  };
  set(0, camera.focal_offset, 1);
  set(1, camera.principal_point_offset, 2);
  set(3, camera.rotation_offset, 3);
  set(6, camera.center_offset, 3);
  set(9, camera.distortion_offset, 2);
  return cols;
}

// Adds a parameter column to a block (unique) and returns its position in the block.
int AddColumn(ResidualBlock* block, int parameter) {
  for (size_t i = 0; i < block->cols.size(); ++i) {
    if (block->cols[i] == parameter) return static_cast<int>(i);
  }
  block->cols.push_back(parameter);
  return static_cast<int>(block->cols.size()) - 1;
}

// with_centre false: a segment, which the camera centre does not move.
void AddCameraColumns(const CameraBlock& camera, bool with_centre, ResidualBlock* block) {
  const std::array<int, 11> params = CameraParameterColumns(camera);
  for (int i = 0; i < 11; ++i) {
    if (!with_centre && i >= 6 && i < 9) continue;
    block->camera_cols[i] = params[i] >= 0 ? AddColumn(block, params[i]) : -1;
  }
}

void AddVertexColumns(const JointProblem& problem, int vertex, ResidualBlock* block) {
  block->vertices.push_back(vertex);
  std::vector<int> map;
  for (int c : problem.vertices[vertex].cols) map.push_back(AddColumn(block, c));
  block->vertex_cols.push_back(std::move(map));
}

void SizeBlock(ResidualBlock* block) {
  block->residual.setZero(block->num_rows);
  block->jacobian.setZero(block->num_rows, static_cast<Eigen::Index>(block->cols.size()));
  block->raw.setZero(block->num_rows);
  block->points.assign(block->vertices.size(), Eigen::Vector3d::Zero());
  block->d_points.setZero(block->num_rows, 3 * static_cast<Eigen::Index>(block->vertices.size()));
  block->d_camera.setZero(block->num_rows, 11);
}

// Project indices by id, for the pins', segments' and constraints' references.
struct ProjectIndex {
  std::map<Id, int> image_lookup, primitive_lookup;

  explicit ProjectIndex(const Project& project) {
    for (size_t i = 0; i < project.images.size(); ++i) image_lookup[project.images[i].id] = static_cast<int>(i);
    for (size_t i = 0; i < project.primitives.size(); ++i) {
      primitive_lookup[project.primitives[i].id] = static_cast<int>(i);
    }
  }
  int FindImage(Id id) const {
    auto it = image_lookup.find(id);
    return it == image_lookup.end() ? -1 : it->second;
  }
};

// The pins and constraints that take part (project indices), and the images and primitives
// they use (a primitive's bases included).
struct UsedInputs {
  std::vector<int> pins, constraints;
  std::vector<char> image_used, primitive_used;
  // Per project primitive and shape parameter: whether a used pin's vertex moves with it, or a
  // used constraint's residual varies with it (with attachment, a top's footprint is its
  // root's and its bases' heights raise it).
  std::vector<std::array<bool, kMaxPrimitiveParams>> param_seen;
};

// How a shape parameter moves the vertices of one constraint: per vertex its world
// displacement per unit of the parameter.
using ParamKey = std::pair<int, int>;  // project primitive, parameter
using Displacements = std::map<ParamKey, std::vector<Eigen::Vector3d>>;

Displacements ConstraintDisplacements(const Project& project, const ProjectIndex& index, const Constraint& c) {
  Displacements out;
  const size_t n = c.vertices.size();
  for (size_t i = 0; i < n; ++i) {
    const int p = index.primitive_lookup.at(c.vertices[i].primitive_id);
    const std::vector<int> chain = BaseChain(project, p);
    const int root = chain.empty() ? p : chain.back();
    const Eigen::Matrix3d r = RotationFromAngleAxis(project.primitives[root].shape.rotation);
    auto add = [&](int primitive, int k, const Eigen::Vector3d& d) {
      std::vector<Eigen::Vector3d>& v = out[{primitive, k}];
      if (v.empty()) v.assign(n, Eigen::Vector3d::Zero());
      v[i] += d;
    };
    for (int b : chain) add(b, 2, r.col(2));
    const ParamCoefficients coefficients = project.FindVertex(c.vertices[i])->local.Collapsed();
    for (int k = 0; k < kMaxPrimitiveParams; ++k) {
      if (!coefficients.col(k).isZero()) add(!chain.empty() && k < 2 ? root : p, k, r * coefficients.col(k));
    }
  }
  return out;
}

// Whether the constraint's residual varies, to first order at a configuration that meets it,
// with a parameter that moves its vertices by `d` (per vertex). Moving vertices within what
// the constraint allows does not count: the back corners of a box's base slide within the
// ground plane as its depth changes, so a ground constraint over them does not see the depth
// (it did, and with a residual that varies off the plane it pulled an unpinned depth to zero
// and below, solve after solve). The plane (line) is fitted to the constraint's vertices on
// the primitives the parameter moves (`own`, when they span one), since they meet it however
// far the others are off it before the solve; else to all of them.
bool ConstraintSeesDisplacement(const Constraint& c, const std::vector<Eigen::Vector3d>& x,
                                const std::vector<char>& own, const std::vector<Eigen::Vector3d>& d) {
  // Relative to the largest displacement.
  constexpr double kTolerance = 1e-6;
  const size_t n = x.size();
  double largest = 0.0;
  for (const Eigen::Vector3d& v : d) largest = std::max(largest, v.norm());
  if (!(largest > 0.0)) return false;
  const double tol = kTolerance * largest;
  auto spread = [&](const std::vector<Eigen::Vector3d>& v) {
    double s = 0.0;
    for (size_t i = 1; i < v.size(); ++i) s = std::max(s, (v[i] - v[0]).norm());
    return s;
  };
  // Principal axes of a subset of the vertices, and whether it spans `dims` dimensions.
  auto fit = [&](bool only_own, int dims, Eigen::Matrix3d* axes) {
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    int count = 0;
    for (size_t i = 0; i < n; ++i) {
      if (only_own && !own[i]) continue;
      centroid += x[i];
      ++count;
    }
    if (count <= dims) return false;
    centroid /= count;
    Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
    for (size_t i = 0; i < n; ++i) {
      if (!only_own || own[i]) scatter += (x[i] - centroid) * (x[i] - centroid).transpose();
    }
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);
    *axes = eig.eigenvectors();
    const Eigen::Vector3d values = eig.eigenvalues();
    return values(3 - dims) > 1e-12 * values(2);
  };
  Eigen::Matrix3d axes;
  switch (c.kind) {
    case ConstraintKind::kCoplanar:
    case ConstraintKind::kCollinear: {
      const int dims = c.kind == ConstraintKind::kCoplanar ? 2 : 1;
      if (!fit(true, dims, &axes) && !fit(false, dims, &axes)) return true;
      // Motion out of the plane (off the line) counts unless every vertex makes the same: the
      // whole set moving.
      std::vector<Eigen::Vector3d> off;
      for (const Eigen::Vector3d& v : d) {
        Eigen::Vector3d o = v;
        for (int k = 3 - dims; k < 3; ++k) o -= axes.col(k).dot(v) * axes.col(k);
        off.push_back(o);
      }
      return spread(off) > tol;
    }
    case ConstraintKind::kParallel:
    case ConstraintKind::kPerpendicular:
    case ConstraintKind::kEqualLength:
    case ConstraintKind::kDistance:
    case ConstraintKind::kAlongAxis:
      // Edges: only a change of an edge vector counts (moving both ends alike does not).
      for (size_t e = 0; e + 1 < n; e += 2) {
        if ((d[e + 1] - d[e]).norm() > tol) return true;
      }
      return false;
    case ConstraintKind::kFixedPoint:
    case ConstraintKind::kEdgeOnImageLine: return true;
  }
  return true;
}

void MarkSeenByConstraint(const Project& project, const ProjectIndex& index, const Constraint& c, UsedInputs* used) {
  std::vector<Eigen::Vector3d> x;
  std::vector<int> primitive;
  for (const VertexRef& v : c.vertices) {
    x.push_back(project.FindVertex(v)->position);
    primitive.push_back(index.primitive_lookup.at(v.primitive_id));
  }
  for (const auto& [key, d] : ConstraintDisplacements(project, index, c)) {
    std::vector<char> own(x.size(), 0);
    for (size_t i = 0; i < x.size(); ++i) {
      if (d[i].isZero()) continue;
      for (size_t j = 0; j < x.size(); ++j) own[j] = own[j] || primitive[j] == primitive[i];
    }
    if (ConstraintSeesDisplacement(c, x, own, d)) used->param_seen[key.first][key.second] = true;
  }
}

UsedInputs SelectUsedInputs(const Project& project, const ProjectIndex& index, JointProblem* problem) {
  UsedInputs used;
  used.image_used.assign(project.images.size(), 0);
  used.primitive_used.assign(project.primitives.size(), 0);
  used.param_seen.assign(project.primitives.size(), {false, false, false, false});
  // A pin sees every parameter that moves its vertex; a constraint only those its residual
  // varies with (MarkSeenByConstraint).
  auto use_vertex = [&](const VertexRef& ref, bool by_pin) {
    const int p = index.primitive_lookup.at(ref.primitive_id);
    used.primitive_used[p] = 1;
    const std::vector<int> chain = BaseChain(project, p);
    for (int b : chain) {
      used.primitive_used[b] = 1;
      if (by_pin) used.param_seen[b][2] = true;
    }
    if (!by_pin) return;
    const ParamCoefficients coefficients = project.FindVertex(ref)->local.Collapsed();
    for (int k = 0; k < kMaxPrimitiveParams; ++k) {
      if (!coefficients.col(k).isZero()) used.param_seen[!chain.empty() && k < 2 ? chain.back() : p][k] = true;
    }
  };
  for (size_t i = 0; i < project.pins.size(); ++i) {
    const Pin& pin = project.pins[i];
    const int im = index.FindImage(pin.image_id);
    std::string why;
    if (im < 0)
      why = "names a missing image";
    else if (!project.images[im].camera_calibrated)
      why = "is in an uncalibrated image";
    else if (project.FindVertex(pin.vertex) == nullptr)
      why = "names a missing vertex";
    else if (!pin.uv_px.allFinite())
      why = "has a non-finite pixel";
    if (!why.empty()) {
      ++problem->num_skipped_pins;
      problem->warnings.push_back("pin " + std::to_string(pin.id) + " " + why + "; skipped");
      continue;
    }
    used.pins.push_back(static_cast<int>(i));
    used.image_used[im] = 1;
    use_vertex(pin.vertex, true);
  }
  for (size_t i = 0; i < project.constraints.size(); ++i) {
    const Constraint& c = project.constraints[i];
    std::string why;
    if (!ValidConstraintShape(c, &why)) {
    } else if (std::any_of(c.vertices.begin(), c.vertices.end(),
                           [&](const VertexRef& v) { return project.FindVertex(v) == nullptr; })) {
      why = "names a missing vertex";
    } else if (c.kind == ConstraintKind::kEdgeOnImageLine) {
      const int im = index.FindImage(c.image_id);
      if (im < 0 || !project.images[im].camera_calibrated) why = "is in a missing or uncalibrated image";
    }
    if (!why.empty()) {
      problem->warnings.push_back(std::string("constraint ") + std::to_string(c.id) + " (" +
                                  ConstraintKindName(c.kind) + ") " + why + "; skipped");
      continue;
    }
    used.constraints.push_back(static_cast<int>(i));
    if (c.kind == ConstraintKind::kEdgeOnImageLine) used.image_used[index.FindImage(c.image_id)] = 1;
    for (const VertexRef& v : c.vertices) use_vertex(v, false);
    MarkSeenByConstraint(project, index, c, &used);
  }
  return used;
}

// A camera block per calibrated image that a pin or constraint uses or whose segments can
// move it; numbers its free parameters from *next. Returns the problem camera of each
// project image (-1: none).
std::vector<int> AddCameraBlocks(const Project& project, const BuildOptions& options,
                                 const std::vector<char>& image_used, JointProblem* problem, JointState* state,
                                 int* next) {
  std::vector<int> camera_of_image(project.images.size(), -1);
  std::map<int, std::array<int, 3>> shared_intrinsics;  // per lens group: focal, principal point, k columns
  for (size_t i = 0; i < project.images.size(); ++i) {
    const Image& image = project.images[i];
    if (!image.camera_calibrated) continue;
    const bool intrinsics_or_rotation_free =
        !image.pose_locked || (options.refine_intrinsics &&
                               (!image.focal_locked || !image.principal_point_locked || !image.distortion_locked));
    bool has_segments = false;
    if (options.use_segments && intrinsics_or_rotation_free) {
      for (const Segment& s : project.segments) has_segments = has_segments || s.image_id == image.id;
    }
    if (!image_used[i] && !has_segments) continue;
    CameraBlock block;
    block.image_index = static_cast<int>(i);
    block.lens_group = image.lens_group;
    // A free intrinsic of a shared lens is numbered by the group's first camera that frees it;
    // the others reuse its columns, so one step moves the whole group's lens.
    std::array<int, 3>* shared = nullptr;
    if (image.lens_group > 0) {
      shared = &shared_intrinsics.try_emplace(image.lens_group, std::array<int, 3>{-1, -1, -1}).first->second;
    }
    const auto intrinsic_offset = [&](int which, int count) {
      if (shared && (*shared)[which] >= 0) return (*shared)[which];
      const int offset = *next;
      *next += count;
      if (shared) (*shared)[which] = offset;
      return offset;
    };
    if (options.refine_intrinsics && !image.focal_locked) block.focal_offset = intrinsic_offset(0, 1);
    if (options.refine_intrinsics && !image.principal_point_locked)
      block.principal_point_offset = intrinsic_offset(1, 2);
    if (!image.pose_locked) {
      block.rotation_offset = *next;
      block.center_offset = *next + 3;
      *next += 6;
    }
    if (options.refine_intrinsics && !image.distortion_locked) block.distortion_offset = intrinsic_offset(2, 2);
    camera_of_image[i] = static_cast<int>(problem->cameras.size());
    problem->cameras.push_back(block);
    const Camera& cam = image.camera;
    CameraState cs;
    cs.focal_px = cam.focal_px;
    cs.principal_point_px = cam.principal_point_px;
    cs.cam_from_world_rotation = cam.cam_from_world_rotation;
    cs.center_in_world = cam.CenterInWorld();
    cs.k1 = cam.k1;
    cs.k2 = cam.k2;
    state->cameras.push_back(cs);
  }
  // One parameter stands for each shared intrinsic, so the cameras sharing it start from one
  // value: the mean of what calibration gave each.
  for (int which = 0; which < 3; ++which) {  // focal, principal point, k1 k2
    const auto offset = [&](const CameraBlock& cb) {
      return which == 0 ? cb.focal_offset : which == 1 ? cb.principal_point_offset : cb.distortion_offset;
    };
    const auto value = [&](const CameraState& cs) -> Eigen::Vector2d {
      if (which == 0) return {cs.focal_px, 0.0};
      return which == 1 ? cs.principal_point_px : Eigen::Vector2d(cs.k1, cs.k2);
    };
    std::map<int, std::pair<Eigen::Vector2d, int>> sums;  // per column: sum, count
    for (size_t c = 0; c < problem->cameras.size(); ++c) {
      const int col = offset(problem->cameras[c]);
      if (col < 0) continue;
      auto& [sum, count] = sums.try_emplace(col, Eigen::Vector2d::Zero(), 0).first->second;
      sum += value(state->cameras[c]);
      ++count;
    }
    for (size_t c = 0; c < problem->cameras.size(); ++c) {
      const int col = offset(problem->cameras[c]);
      if (col < 0 || sums.at(col).second < 2) continue;
      const Eigen::Vector2d mean = sums.at(col).first / static_cast<double>(sums.at(col).second);
      CameraState& cs = state->cameras[c];
      if (which == 0) cs.focal_px = mean.x();
      if (which == 1) cs.principal_point_px = mean;
      if (which == 2) {
        cs.k1 = mean.x();
        cs.k2 = mean.y();
      }
    }
  }
  return camera_of_image;
}

// The segments (project indices) of cameras whose intrinsics or rotation are free.
std::vector<int> SelectUsedSegments(const Project& project, const BuildOptions& options, const ProjectIndex& index,
                                    const std::vector<int>& camera_of_image, const JointProblem& problem) {
  std::vector<int> used_segments;
  if (!options.use_segments) return used_segments;
  for (size_t i = 0; i < project.segments.size(); ++i) {
    const int im = index.FindImage(project.segments[i].image_id);
    if (im < 0 || camera_of_image[im] < 0) continue;
    const CameraBlock& cb = problem.cameras[camera_of_image[im]];
    if (cb.focal_offset < 0 && cb.principal_point_offset < 0 && cb.rotation_offset < 0 && cb.distortion_offset < 0) {
      continue;
    }
    if ((project.segments[i].b_px - project.segments[i].a_px).norm() <= 0.0) continue;
    used_segments.push_back(static_cast<int>(i));
  }
  return used_segments;
}

// A primitive block per used primitive; numbers its free parameters from *next. Returns the
// problem primitive of each project primitive (-1: none).
// A shape parameter that no used vertex moves with (a box's height when only its bottom
// corners are pinned) is held at its value, as the geometry solve holds it
// (core/solve/scene_solve_internal.h): as a parameter its Jacobian column would be zero, and
// the solvers would be free to move it anywhere (it drifted solve after solve, to negative
// sizes).
std::vector<int> AddPrimitiveBlocks(const Project& project, const UsedInputs& used, JointProblem* problem,
                                    JointState* state, int* next) {
  const std::vector<char>& primitive_used = used.primitive_used;
  std::vector<int> problem_primitive(project.primitives.size(), -1);
  for (size_t i = 0; i < project.primitives.size(); ++i) {
    if (!primitive_used[i]) continue;
    problem_primitive[i] = static_cast<int>(problem->primitives.size());
    problem->primitives.emplace_back();
    problem->primitives.back().primitive_index = static_cast<int>(i);
  }
  for (PrimitiveBlock& block : problem->primitives) {
    const Primitive& p = project.primitives[block.primitive_index];
    for (int b : BaseChain(project, block.primitive_index)) block.bases.push_back(problem_primitive[b]);
    block.root = block.bases.empty() ? problem_primitive[block.primitive_index] : block.bases.back();
    const bool attached = !block.bases.empty();
    for (int k = attached ? 2 : 0; k < NumShapeParams(p.shape.kind); ++k) {
      if (p.param_locked[k]) continue;
      if (!used.param_seen[block.primitive_index][k]) {
        problem->held_parameters.push_back({PrimitiveLabel(p) + ": " +
                                                kParamNames[KindIndex(p.shape.kind)][std::min(k, 2)] + " (parameter " +
                                                std::to_string(k) + ")",
                                            p.shape.params(k)});
        continue;
      }
      block.param_offset[k] = (*next)++;
    }
    if (!attached && !p.rotation_locked) {
      block.rotation_offset = *next;
      *next += 3;
    }
    if (!attached && !p.translation_locked) {
      block.translation_offset = *next;
      *next += 3;
    }
    PrimitiveState ps;
    ps.params = p.shape.params;
    ps.world_from_primitive = RotationFromAngleAxis(p.shape.rotation);
    ps.translation = p.shape.translation;
    state->primitives.push_back(ps);
  }
  return problem_primitive;
}

using VertexLookup = std::map<std::pair<Id, VertexId>, int>;

// One vertex term per vertex the used pins and constraints read, shared by the blocks that
// read it; a free vertex's offset is numbered from *next. Returns the term of each vertex.
VertexLookup AddVertexTerms(const Project& project, const ProjectIndex& index, const UsedInputs& used,
                            const std::vector<int>& problem_primitive, JointProblem* problem, JointState* state,
                            int* next) {
  VertexLookup vertex_lookup;
  auto vertex_term = [&](const VertexRef& ref) {
    const auto key = std::make_pair(ref.primitive_id, ref.vertex);
    if (vertex_lookup.count(key) > 0) return;
    VertexTerm term;
    term.ref = ref;
    term.primitive = problem_primitive[index.primitive_lookup.at(ref.primitive_id)];
    const MeshVertex& v = *project.FindVertex(ref);
    term.coefficients = v.local.Collapsed();
    if (v.local.free) {
      term.free_vertex = static_cast<int>(problem->free_vertices.size());
      FreeVertexBlock fb;
      fb.ref = ref;
      fb.offset = *next;
      *next += 3;
      problem->free_vertices.push_back(fb);
      state->free_offsets.push_back(v.local.offset);
    } else {
      term.fixed_offset = v.local.offset;
    }
    vertex_lookup[key] = static_cast<int>(problem->vertices.size());
    problem->vertices.push_back(term);
  };
  for (int i : used.pins) vertex_term(project.pins[i].vertex);
  for (int i : used.constraints) {
    for (const VertexRef& v : project.constraints[i].vertices) vertex_term(v);
  }
  return vertex_lookup;
}

// Model size: RMS spread of the used vertices (the scale of every length residual); the
// largest camera distance when they coincide, 1 when that fails too.
double ModelSize(const JointProblem& problem, const JointState& state) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const VertexTerm& t : problem.vertices) centroid += t.position;
  double spread = 0.0;
  if (!problem.vertices.empty()) {
    centroid /= static_cast<double>(problem.vertices.size());
    for (const VertexTerm& t : problem.vertices) spread += (t.position - centroid).squaredNorm();
    spread = std::sqrt(spread / static_cast<double>(problem.vertices.size()));
  }
  if (!(spread > 0.0)) {
    for (const CameraState& c : state.cameras) spread = std::max(spread, (c.center_in_world - centroid).norm());
  }
  return spread > 0.0 && std::isfinite(spread) ? spread : 1.0;
}

void AddPinBlocks(const Project& project, const ProjectIndex& index, const std::vector<int>& used_pins,
                  const std::vector<int>& camera_of_image, const VertexLookup& vertex_lookup, JointProblem* problem) {
  for (int i : used_pins) {
    const Pin& pin = project.pins[i];
    ResidualBlock block;
    block.kind = BlockKind::kPin;
    block.source = i;
    block.camera = camera_of_image[index.FindImage(pin.image_id)];
    block.num_rows = 2;
    block.uv_px = pin.uv_px;
    AddCameraColumns(problem->cameras[block.camera], true, &block);
    AddVertexColumns(*problem, vertex_lookup.at({pin.vertex.primitive_id, pin.vertex.vertex}), &block);
    SizeBlock(&block);
    problem->blocks.push_back(std::move(block));
  }
}

void AddSegmentBlocks(const Project& project, const ProjectIndex& index, const std::vector<int>& used_segments,
                      const std::vector<int>& camera_of_image, JointProblem* problem) {
  for (int i : used_segments) {
    const Segment& seg = project.segments[i];
    ResidualBlock block;
    block.kind = BlockKind::kSegment;
    block.source = i;
    block.camera = camera_of_image[index.FindImage(seg.image_id)];
    block.num_rows = 2;
    // The family's world axis: x and y swap on an image turned by an odd quarter turn.
    block.axis =
        WorldAxisOfFamily(static_cast<int>(seg.axis), project.images[index.FindImage(seg.image_id)].axis_quarter_turns);
    const Eigen::Vector2d mid = 0.5 * (seg.a_px + seg.b_px);
    block.segment_g = Eigen::Vector3d(seg.a_px.x(), seg.a_px.y(), 1.0).cross(Eigen::Vector3d(mid.x(), mid.y(), 1.0));
    block.segment_m << 0.0, -1.0, mid.y(), 1.0, 0.0, -mid.x();
    block.segment_a_px = seg.a_px;
    block.segment_b_px = seg.b_px;
    AddCameraColumns(problem->cameras[block.camera], false, &block);
    SizeBlock(&block);
    problem->blocks.push_back(std::move(block));
  }
}

// The kind-specific part of a constraint term: the spanning vertices, kept components, scale,
// point or image line. Returns why the constraint is degenerate at the start, or "".
std::string SetUpConstraintTerm(const Constraint& c, const std::vector<Eigen::Vector3d>& p, int camera,
                                const JointProblem& problem, const JointState& state, ConstraintTerm* term) {
  const int n = static_cast<int>(p.size());
  std::string degenerate;
  const double tiny = 1e-12 * problem.model_size;
  switch (c.kind) {
    case ConstraintKind::kCoplanar:
    case ConstraintKind::kCollinear: {
      int i1 = 1;
      for (int k = 1; k < n; ++k) {
        if ((p[k] - p[0]).norm() > (p[i1] - p[0]).norm()) i1 = k;
      }
      if ((p[i1] - p[0]).norm() <= tiny) degenerate = "its vertices coincide";
      if (c.kind == ConstraintKind::kCollinear) {
        term->span = {0, i1, -1};
        term->kept_components = OtherComponents(LargestComponent(p[i1] - p[0]));
        break;
      }
      int i2 = -1;
      double best = 0.0;
      for (int k = 1; k < n; ++k) {
        const double area = (p[i1] - p[0]).cross(p[k] - p[0]).norm();
        if (k != i1 && area > best) {
          best = area;
          i2 = k;
        }
      }
      if (i2 < 0 || best <= tiny * problem.model_size) degenerate = "its vertices are collinear";
      term->span = {0, i1, std::max(i2, 0)};
      break;
    }
    case ConstraintKind::kParallel:
    case ConstraintKind::kPerpendicular:
    case ConstraintKind::kEqualLength:
      if ((p[1] - p[0]).norm() <= tiny || (p[3] - p[2]).norm() <= tiny) degenerate = "an edge has zero length";
      term->kept_components = OtherComponents(LargestComponent(p[1] - p[0]));
      break;
    case ConstraintKind::kDistance:
      if ((p[1] - p[0]).norm() <= tiny) degenerate = "its vertices coincide";
      term->scale = c.value;
      break;
    case ConstraintKind::kFixedPoint: term->point = c.point; break;
    case ConstraintKind::kAlongAxis:
      if ((p[1] - p[0]).norm() <= tiny) degenerate = "its vertices coincide";
      term->kept_components = OtherComponents(static_cast<int>(c.axis));
      break;
    case ConstraintKind::kEdgeOnImageLine: {
      const Eigen::Vector3d a(c.line_a_px.x(), c.line_a_px.y(), 1.0);
      const Eigen::Vector3d b(c.line_b_px.x(), c.line_b_px.y(), 1.0);
      const Eigen::Vector3d line = a.cross(b);
      term->line_px = line / line.head<2>().norm();
      term->line_a_px = c.line_a_px;
      term->line_b_px = c.line_b_px;
      term->camera = camera;
      term->undistort_line = problem.cameras[term->camera].distortion_offset >= 0;
      term->scale = state.cameras[term->camera].focal_px;
      break;
    }
  }
  return degenerate;
}

void AddConstraintBlocks(const Project& project, const ProjectIndex& index, const std::vector<int>& used_constraints,
                         const std::vector<int>& camera_of_image, const VertexLookup& vertex_lookup,
                         const JointState& state, JointProblem* problem) {
  for (int i : used_constraints) {
    const Constraint& c = project.constraints[i];
    ConstraintTerm term;
    term.constraint_index = i;
    term.kind = c.kind;
    for (const VertexRef& v : c.vertices) term.vertices.push_back(vertex_lookup.at({v.primitive_id, v.vertex}));
    std::vector<Eigen::Vector3d> p;
    for (int v : term.vertices) p.push_back(problem->vertices[v].position);
    term.scale = problem->model_size;
    term.num_rows = ConstraintRows(c.kind, static_cast<int>(term.vertices.size()));
    const int camera = c.kind == ConstraintKind::kEdgeOnImageLine ? camera_of_image[index.FindImage(c.image_id)] : -1;
    const std::string degenerate = SetUpConstraintTerm(c, p, camera, *problem, state, &term);
    if (!degenerate.empty()) {
      problem->warnings.push_back(std::string("constraint ") + std::to_string(c.id) + " (" +
                                  ConstraintKindName(c.kind) + ") is degenerate (" + degenerate + "); skipped");
      continue;
    }
    term.multiplier.setZero(term.num_rows);
    ResidualBlock block;
    block.kind = BlockKind::kConstraint;
    block.source = static_cast<int>(problem->constraints.size());
    block.num_rows = term.num_rows;
    if (term.camera >= 0) {
      block.camera = term.camera;
      AddCameraColumns(problem->cameras[term.camera], true, &block);
    }
    for (int v : term.vertices) AddVertexColumns(*problem, v, &block);
    SizeBlock(&block);
    problem->constraints.push_back(std::move(term));
    problem->blocks.push_back(std::move(block));
  }
}

// Names for diagnostics, one per parameter.
void NameParameters(const Project& project, JointProblem* problem) {
  problem->parameter_names.assign(problem->num_parameters, "");
  const char* const kCamera[11] = {"focal length",     "principal point u", "principal point v", "rotation about x",
                                   "rotation about y", "rotation about z",  "position x",        "position y",
                                   "position z",       "distortion k1",     "distortion k2"};
  std::vector<int> cameras_of_column(problem->num_parameters, 0);
  for (const CameraBlock& cb : problem->cameras) {
    for (int col : CameraParameterColumns(cb)) {
      if (col >= 0) ++cameras_of_column[col];
    }
  }
  for (const CameraBlock& cb : problem->cameras) {
    const std::array<int, 11> cols = CameraParameterColumns(cb);
    for (int i = 0; i < 11; ++i) {
      if (cols[i] < 0) continue;
      problem->parameter_names[cols[i]] =
          (cameras_of_column[cols[i]] > 1 ? "the lens of group " + std::to_string(cb.lens_group)
                                          : ImageLabel(project.images[cb.image_index])) +
          ": " + kCamera[i];
    }
  }
  const char* const kPose[6] = {"rotation about x", "rotation about y", "rotation about z",
                                "position x",       "position y",       "position z"};
  for (const PrimitiveBlock& pb : problem->primitives) {
    const Primitive& p = project.primitives[pb.primitive_index];
    const std::string label = PrimitiveLabel(p);
    for (int k = 0; k < kMaxPrimitiveParams; ++k) {
      if (pb.param_offset[k] < 0) continue;
      problem->parameter_names[pb.param_offset[k]] = label + ": " +
                                                     kParamNames[KindIndex(p.shape.kind)][std::min(k, 2)] +
                                                     " (parameter " + std::to_string(k) + ")";
    }
    for (int i = 0; i < 3; ++i) {
      if (pb.rotation_offset >= 0) problem->parameter_names[pb.rotation_offset + i] = label + ": " + kPose[i];
      if (pb.translation_offset >= 0) problem->parameter_names[pb.translation_offset + i] = label + ": " + kPose[3 + i];
    }
  }
  for (const FreeVertexBlock& fb : problem->free_vertices) {
    const Primitive& p = *project.FindPrimitive(fb.ref.primitive_id);
    for (int i = 0; i < 3; ++i) {
      problem->parameter_names[fb.offset + i] =
          "the free vertex " + std::to_string(fb.ref.vertex) + " of " + PrimitiveLabel(p) + ": offset " + "xyz"[i];
    }
  }
}

}  // namespace

JointProblem BuildJointProblem(const Project& project, const BuildOptions& options, JointState* state) {
  JointProblem problem;
  const ProjectIndex index(project);
  const UsedInputs used = SelectUsedInputs(project, index, &problem);

  // Parameters numbered cameras first (SchurEquations relies on it), then primitives, then
  // free vertices.
  int next = 0;
  const std::vector<int> camera_of_image = AddCameraBlocks(project, options, used.image_used, &problem, state, &next);
  const std::vector<int> used_segments = SelectUsedSegments(project, options, index, camera_of_image, problem);
  const std::vector<int> problem_primitive = AddPrimitiveBlocks(project, used, &problem, state, &next);
  const VertexLookup vertex_lookup = AddVertexTerms(project, index, used, problem_primitive, &problem, state, &next);
  problem.num_parameters = next;
  for (VertexTerm& term : problem.vertices) {
    term.cols = VertexColumns(problem, term);
    term.jacobian.setZero(3, static_cast<Eigen::Index>(term.cols.size()));
    EvaluateVertex(problem, *state, &term);
  }
  problem.model_size = ModelSize(problem, *state);

  AddPinBlocks(project, index, used.pins, camera_of_image, vertex_lookup, &problem);
  AddSegmentBlocks(project, index, used_segments, camera_of_image, &problem);
  AddConstraintBlocks(project, index, used.constraints, camera_of_image, vertex_lookup, *state, &problem);
  problem.num_residuals = 0;
  for (const ResidualBlock& b : problem.blocks) problem.num_residuals += b.num_rows;
  NameParameters(project, &problem);
  return problem;
}

bool EvaluateBlocks(JointProblem* problem, const JointState& state, bool with_jacobian) {
  for (VertexTerm& term : problem->vertices) EvaluateVertex(*problem, state, &term);
  const double weight = problem->constraint_weight;
  bool ok = true;
  for (ResidualBlock& block : problem->blocks) {
    if (with_jacobian) block.jacobian.setZero();
    switch (block.kind) {
      case BlockKind::kPin: {
        const VertexTerm& v = problem->vertices[block.vertices[0]];
        Eigen::Vector2d r;
        Eigen::Matrix<double, 2, 3> d_point;
        Eigen::Matrix<double, 2, 9> d_cam;
        Eigen::Matrix<double, 2, 2> d_k;
        const bool k_free = block.camera_cols[9] >= 0 || block.camera_cols[10] >= 0;
        if (!PinResidual(state.cameras[block.camera], v.position, block.uv_px, &r, &d_point,
                         with_jacobian ? &d_cam : nullptr, with_jacobian && k_free ? &d_k : nullptr)) {
          ok = false;
          block.residual.setZero();
          block.raw.setZero(2);
          continue;
        }
        block.raw = r;
        block.residual = block.weight * r;
        if (with_jacobian) {
          for (int i = 0; i < 9; ++i) {
            if (block.camera_cols[i] >= 0) block.jacobian.col(block.camera_cols[i]) = d_cam.col(i);
          }
          for (int i = 0; i < 2 && k_free; ++i) {
            if (block.camera_cols[9 + i] >= 0) block.jacobian.col(block.camera_cols[9 + i]) = d_k.col(i);
          }
          const std::vector<int>& map = block.vertex_cols[0];
          for (size_t j = 0; j < map.size(); ++j) block.jacobian.col(map[j]).noalias() += d_point * v.jacobian.col(j);
          if (block.weight != 1.0) block.jacobian *= block.weight;
        }
        break;
      }
      case BlockKind::kSegment: {
        const CameraState& camera = state.cameras[block.camera];
        if (camera.k1 != 0.0 || camera.k2 != 0.0 || block.camera_cols[9] >= 0) {
          Eigen::Matrix<double, 1, 8> d_cam;
          const double r = DistortedSegmentResidual(camera, block.segment_a_px, block.segment_b_px, block.axis,
                                                    with_jacobian ? &d_cam : nullptr);
          block.residual << r, -r;
          if (with_jacobian) {
            for (int i = 0; i < 8; ++i) {
              const int col = block.camera_cols[i < 6 ? i : i + 3];
              if (col < 0) continue;
              block.jacobian(0, col) = d_cam(i);
              block.jacobian(1, col) = -d_cam(i);
            }
          }
          break;
        }
        Eigen::Matrix<double, 1, 6> d_cam;
        const double r =
            SegmentResidual(camera, block.segment_g, block.segment_m, block.axis, with_jacobian ? &d_cam : nullptr);
        block.residual << r, -r;
        if (with_jacobian) {
          for (int i = 0; i < 6; ++i) {
            if (block.camera_cols[i] < 0) continue;
            block.jacobian(0, block.camera_cols[i]) = d_cam(i);
            block.jacobian(1, block.camera_cols[i]) = -d_cam(i);
          }
        }
        break;
      }
      case BlockKind::kConstraint: {
        const ConstraintTerm& term = problem->constraints[block.source];
        for (size_t i = 0; i < block.vertices.size(); ++i)
          block.points[i] = problem->vertices[block.vertices[i]].position;
        const CameraState* camera = term.camera >= 0 ? &state.cameras[term.camera] : nullptr;
        if (!ConstraintResidual(term, block.points, camera, &block.raw, with_jacobian ? &block.d_points : nullptr,
                                with_jacobian ? &block.d_camera : nullptr)) {
          ok = false;
          block.residual.setZero();
          continue;
        }
        block.residual = weight * block.raw + term.multiplier / weight;
        if (with_jacobian) {
          for (size_t i = 0; i < block.vertices.size(); ++i) {
            const VertexTerm& v = problem->vertices[block.vertices[i]];
            const std::vector<int>& map = block.vertex_cols[i];
            for (size_t j = 0; j < map.size(); ++j) {
              block.jacobian.col(map[j]).noalias() += block.d_points.middleCols<3>(3 * i) * v.jacobian.col(j);
            }
          }
          if (camera != nullptr) {
            for (int i = 0; i < 11; ++i) {
              if (block.camera_cols[i] >= 0) block.jacobian.col(block.camera_cols[i]) += block.d_camera.col(i);
            }
          }
          block.jacobian *= weight;
        }
        break;
      }
    }
  }
  return ok;
}

void ApplyStep(const JointProblem& problem, const Eigen::VectorXd& delta, const JointState& state,
               JointState* stepped) {
  *stepped = state;
  for (size_t c = 0; c < problem.cameras.size(); ++c) {
    const CameraBlock& cb = problem.cameras[c];
    CameraState& cs = stepped->cameras[c];
    if (cb.focal_offset >= 0) cs.focal_px += delta(cb.focal_offset);
    if (cb.principal_point_offset >= 0) cs.principal_point_px += delta.segment<2>(cb.principal_point_offset);
    if (cb.rotation_offset >= 0) {
      cs.cam_from_world_rotation =
          RotationFromAngleAxis(delta.segment<3>(cb.rotation_offset)) * cs.cam_from_world_rotation;
    }
    if (cb.center_offset >= 0) cs.center_in_world += delta.segment<3>(cb.center_offset);
    if (cb.distortion_offset >= 0) {
      cs.k1 += delta(cb.distortion_offset);
      cs.k2 += delta(cb.distortion_offset + 1);
    }
  }
  for (size_t p = 0; p < problem.primitives.size(); ++p) {
    const PrimitiveBlock& pb = problem.primitives[p];
    PrimitiveState& ps = stepped->primitives[p];
    for (int k = 0; k < kMaxPrimitiveParams; ++k) {
      if (pb.param_offset[k] >= 0) ps.params(k) += delta(pb.param_offset[k]);
    }
    if (pb.rotation_offset >= 0) {
      ps.world_from_primitive = RotationFromAngleAxis(delta.segment<3>(pb.rotation_offset)) * ps.world_from_primitive;
    }
    if (pb.translation_offset >= 0) ps.translation += delta.segment<3>(pb.translation_offset);
  }
  for (size_t v = 0; v < problem.free_vertices.size(); ++v) {
    stepped->free_offsets[v] += delta.segment<3>(problem.free_vertices[v].offset);
  }
}

void DenseJacobian(const JointProblem& problem, Eigen::MatrixXd* jacobian, Eigen::VectorXd* residual) {
  jacobian->setZero(problem.num_residuals, problem.num_parameters);
  residual->setZero(problem.num_residuals);
  int row = 0;
  for (const ResidualBlock& block : problem.blocks) {
    residual->segment(row, block.num_rows) = block.residual;
    for (size_t j = 0; j < block.cols.size(); ++j) {
      jacobian->block(row, block.cols[j], block.num_rows, 1) += block.jacobian.col(j);
    }
    row += block.num_rows;
  }
}

void WriteState(const JointProblem& problem, const JointState& state, Project* project) {
  for (size_t c = 0; c < problem.cameras.size(); ++c) {
    Camera& cam = project->images[problem.cameras[c].image_index].camera;
    const CameraState& cs = state.cameras[c];
    cam.focal_px = cs.focal_px;
    cam.principal_point_px = cs.principal_point_px;
    cam.SetPose(cs.cam_from_world_rotation, cs.center_in_world);
    cam.k1 = cs.k1;
    cam.k2 = cs.k2;
  }
  for (size_t p = 0; p < problem.primitives.size(); ++p) {
    const PrimitiveBlock& pb = problem.primitives[p];
    PrimitiveShape& shape = project->primitives[pb.primitive_index].shape;
    for (int k = 0; k < kMaxPrimitiveParams; ++k) {
      if (pb.param_offset[k] >= 0) shape.params(k) = state.primitives[p].params(k);
    }
    if (pb.rotation_offset >= 0) shape.rotation = AngleAxisFromRotation(state.primitives[p].world_from_primitive);
    if (pb.translation_offset >= 0) shape.translation = state.primitives[p].translation;
  }
  for (size_t v = 0; v < problem.free_vertices.size(); ++v) {
    const VertexRef& ref = problem.free_vertices[v].ref;
    Primitive* primitive = project->FindPrimitive(ref.primitive_id);
    primitive->mesh.vertex(ref.vertex).local.offset = state.free_offsets[v];
  }
  RefreshAllPrimitives(project);
}

double NaturalConstraintResidual(const JointProblem& problem, const ConstraintTerm& term, const Eigen::VectorXd& scaled,
                                 std::string* unit) {
  const double norm = scaled.size() > 0 ? scaled.cwiseAbs().maxCoeff() : 0.0;
  constexpr double kDeg = 180.0 / M_PI;
  switch (term.kind) {
    case ConstraintKind::kParallel:
    case ConstraintKind::kPerpendicular:
    case ConstraintKind::kAlongAxis:
      if (unit) *unit = "deg";
      return std::asin(std::min(1.0, term.kind == ConstraintKind::kPerpendicular ? norm : scaled.norm())) * kDeg;
    case ConstraintKind::kEdgeOnImageLine:
      if (unit) *unit = "px";
      return norm * term.scale;
    case ConstraintKind::kFixedPoint:
      if (unit) *unit = "length";
      return scaled.norm() * term.scale;
    default:
      if (unit) *unit = "length";
      return norm * term.scale;
  }
}

}  // namespace facet::joint_solve_internal

namespace facet {

bool PinsSeeLength(const Project& project, const VertexRef& a, const VertexRef& b) {
  using namespace joint_solve_internal;
  if (project.FindVertex(a) == nullptr || project.FindVertex(b) == nullptr) return false;
  Project pins_only = project;
  pins_only.constraints.clear();
  const ProjectIndex index(pins_only);
  JointProblem scratch;
  const UsedInputs used = SelectUsedInputs(pins_only, index, &scratch);
  Constraint length;
  length.kind = ConstraintKind::kDistance;
  length.vertices = {a, b};
  const std::vector<Eigen::Vector3d> x = {project.FindVertex(a)->position, project.FindVertex(b)->position};
  const std::vector<char> own(2, 1);
  for (const auto& [key, d] : ConstraintDisplacements(pins_only, index, length)) {
    if (used.param_seen[key.first][key.second] && ConstraintSeesDisplacement(length, x, own, d)) return true;
  }
  return false;
}

}  // namespace facet
