// Topology of the box primitive (core/mesh/primitives.h): its corners' bit code, faces and
// edges. A box primitive's mesh vertex i is corner i (until K-ops add vertices).
#pragma once

#include <array>

#include <Eigen/Core>

namespace facet {

// Corner i of a box of the given size in box-local coordinates (bit 0: x, 1: y, 2: z).
Eigen::Vector3d BoxCornerLocal(const Eigen::Vector3d& size, int corner);

// The six faces as corner indices, counter-clockwise seen from outside, in the order
// -X, +X, -Y, +Y, -Z, +Z. Face f's first edge (corner 0 -> 1) is its texture u axis and
// (corner 0 -> 3) its v axis.
const std::array<std::array<int, 4>, 6>& BoxFaces();
// The twelve edges as corner pairs.
const std::array<std::array<int, 2>, 12>& BoxEdges();

}  // namespace facet
