// The ground-truth cameras of Strecha's fountain-P11 (FACET_SHARED_DATA/strecha-fountain-p11-subset,
// PROVENANCE.md there), read once for the suites that compare against them. Camera files:
// K (3 rows), "0 0 0", R (camera -> world, 3 rows), C (centre), "w h"; P = K [R^T | -R^T C].
#pragma once

#include <filesystem>
#include <fstream>
#include <string>

#include <doctest/doctest.h>
#include <Eigen/Core>

namespace facet::testing {

inline const std::filesystem::path& StrechaFountainDir() {
  static const std::filesystem::path dir = std::filesystem::path(FACET_SHARED_DATA) / "strecha-fountain-p11-subset";
  return dir;
}

struct GroundTruthCamera {
  Eigen::Matrix3d K;  // full-resolution pixels (3072 x 2048)
  Eigen::Matrix3d cam_from_world_rotation;
  Eigen::Vector3d cam_from_world_translation;
  Eigen::Vector3d CenterInWorld() const { return -cam_from_world_rotation.transpose() * cam_from_world_translation; }
};

// The camera of photo `name` ("0004" ... "0007"); fails the test when the file is missing or short.
inline GroundTruthCamera ReadStrechaCamera(const std::string& name) {
  const std::filesystem::path path = StrechaFountainDir() / "gt_dense_cameras" / (name + ".jpg.camera");
  std::ifstream in(path);
  REQUIRE_MESSAGE(in.good(), "cannot open " << path);
  double v[3 * 3 + 3 + 3 * 3 + 3];
  for (double& x : v) REQUIRE_MESSAGE(static_cast<bool>(in >> x), "short camera file " << path);
  GroundTruthCamera cam;
  Eigen::Matrix3d world_from_cam;
  Eigen::Vector3d center;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      cam.K(r, c) = v[3 * r + c];
      world_from_cam(r, c) = v[12 + 3 * r + c];
    }
  center << v[21], v[22], v[23];
  cam.cam_from_world_rotation = world_from_cam.transpose();
  cam.cam_from_world_translation = -world_from_cam.transpose() * center;
  return cam;
}

}  // namespace facet::testing
