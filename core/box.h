// Geometry of the box primitive (core/project.h, Box): corners, faces and edges in world
// coordinates, in the Facade style of local coordinates times the primitive's pose.
#pragma once

#include <array>

#include <Eigen/Core>

#include "core/project.h"

namespace facet {

// Corner i of a box of the given size in box-local coordinates (bit 0: x, 1: y, 2: z).
Eigen::Vector3d BoxCornerLocal(const Eigen::Vector3d& size, int corner);
Eigen::Vector3d BoxCornerInWorld(const Box& box, int corner);
std::array<Eigen::Vector3d, 8> BoxCornersInWorld(const Box& box);

// The six faces as corner indices, counter-clockwise seen from outside, in the order
// -X, +X, -Y, +Y, -Z, +Z. Face f's first edge (corner 0 -> 1) is its texture u axis and
// (corner 0 -> 3) its v axis.
const std::array<std::array<int, 4>, 6>& BoxFaces();
// The twelve edges as corner pairs.
const std::array<std::array<int, 2>, 12>& BoxEdges();
// Outward unit normal of face f in world.
Eigen::Vector3d BoxFaceNormalInWorld(const Box& box, int face);

}  // namespace facet
