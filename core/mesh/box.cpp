#include "core/mesh/box.h"

namespace facet {

Eigen::Vector3d BoxCornerLocal(const Eigen::Vector3d& size, int corner) {
  return {(corner & 1) ? size.x() : 0.0, (corner & 2) ? size.y() : 0.0, (corner & 4) ? size.z() : 0.0};
}

const std::array<std::array<int, 4>, 6>& BoxFaces() {
  static const std::array<std::array<int, 4>, 6> kFaces = {{
      {0, 4, 6, 2},  // -X
      {1, 3, 7, 5},  // +X
      {0, 1, 5, 4},  // -Y
      {2, 6, 7, 3},  // +Y
      {0, 2, 3, 1},  // -Z
      {4, 5, 7, 6},  // +Z
  }};
  return kFaces;
}

const std::array<std::array<int, 2>, 12>& BoxEdges() {
  static const std::array<std::array<int, 2>, 12> kEdges = {{
      {0, 1},
      {2, 3},
      {4, 5},
      {6, 7},  // along x
      {0, 2},
      {1, 3},
      {4, 6},
      {5, 7},  // along y
      {0, 4},
      {1, 5},
      {2, 6},
      {3, 7},  // along z
  }};
  return kEdges;
}

}  // namespace facet
