// How single-image calibration treats the principal point and the focal length: the choices a
// project stores per image and every estimator takes.
#pragma once

#include <optional>
#include <string>

namespace facet {

enum class PrincipalPointMode { kSolve = 0, kImageCenter = 1, kFixed = 2 };
// Solved from the vanishing points, a known lens (fixed), or solved with a Gaussian prior (e.g.
// from the photo's EXIF, core/image/exif.h).
enum class FocalMode { kSolve = 0, kFixed = 1, kPrior = 2 };
const char* FocalModeName(FocalMode mode);                            // "solve", "fixed", "prior"
std::optional<FocalMode> FocalModeFromName(const std::string& name);  // inverse of FocalModeName

}  // namespace facet
