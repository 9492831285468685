// Single-image calibration from vanishing points of user-drawn line families (the paper's
// "three orthogonal vanishing points"). Each vanishing point is fitted by least squares over
// all segments of its family (2 or more); the focal length and principal point follow from
// the orthocentre construction with three vanishing points, or the focal length alone from
// two with the principal point given; the rotation from the vanishing directions. That
// closed form then starts a joint least-squares fit of focal length, principal point (with
// a weak, noise-weighted prior at the image centre) and rotation to all segments, which
// keeps the three directions orthogonal.
// Reference: Hartley & Zisserman, Multiple View Geometry, 2nd ed., sections 8.6 and 8.8.
#pragma once

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/project.h"

namespace facet {

struct VpCalibrationOptions {
  int width_px = 0;  // image size (principal point "center" is (w - 1) / 2, (h - 1) / 2)
  int height_px = 0;
  // kSolve needs three families; with two families kSolve falls back to kImageCenter and
  // says so in the warnings.
  PrincipalPointMode principal_point_mode = PrincipalPointMode::kSolve;
  Eigen::Vector2d fixed_principal_point_px = Eigen::Vector2d::Zero();  // for kFixed

  bool Check(std::string* error) const;
};

struct VpCalibrationSummary {
  bool success = false;
  std::string message;                // why it failed, or a one-line result
  std::vector<std::string> warnings;  // usable result, but the user should know
  double focal_px = 0.0;
  Eigen::Vector2d principal_point_px = Eigen::Vector2d::Zero();
  // Columns: world x, y, z axes in the camera frame (core/conventions.h: z up). The world
  // z axis points up in the image; x and y point towards their vanishing points' side in
  // front of the camera; det = +1.
  Eigen::Matrix3d cam_from_world_rotation = Eigen::Matrix3d::Identity();
  // Homogeneous vanishing point per axis (x, y, z) of the fitted camera (K R e_axis), unit
  // norm, third coordinate >= 0; zero when the family is absent.
  std::array<Eigen::Vector3d, 3> vanishing_points{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(),
                                                   Eigen::Vector3d::Zero()};
  // A family whose segments are parallel in the image (within ~1e-5 rad at the camera).
  std::array<bool, 3> vanishing_point_at_infinity = {false, false, false};
  // RMS over a family's segments of segment_residuals_px; zero when the family is absent.
  std::array<double, 3> vanishing_point_rms_px = {0.0, 0.0, 0.0};
  // Largest deviation from 90 deg between two fitted vanishing directions before the
  // rotation is made orthonormal (zero by construction with three points and kSolve).
  double max_orthogonality_error_deg = 0.0;
  // The three-point closed form (kSolve with three families) before the joint fit of the
  // camera to all segments; zero when it gave no real focal length.
  double closed_form_focal_px = 0.0;
  Eigen::Vector2d closed_form_principal_point_px = Eigen::Vector2d::Zero();
  int joint_fit_iterations = 0;
  double rms_residual_px = 0.0;  // RMS of segment_residuals_px
  std::array<int, 3> segments_per_axis = {0, 0, 0};
  // Per input segment (same order): distance in px of its endpoints to the line through its
  // midpoint and its family's vanishing point (RMS of the two).
  std::vector<double> segment_residuals_px;
  double time_ms = 0.0;

  bool IsUsable() const { return success; }
};

// Calibrates from the segments of one image (their `axis` names the family). Degenerate
// input (a family with fewer than 2 segments, parallel or coincident segments where a
// finite vanishing point is needed, an obtuse vanishing-point triangle, fewer than two
// families) gives success = false and a message that says which.
VpCalibrationSummary CalibrateFromVanishingLines(const std::vector<Segment>& segments,
                                                 const VpCalibrationOptions& options);

}  // namespace facet
