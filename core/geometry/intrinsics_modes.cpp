#include "core/geometry/intrinsics_modes.h"

namespace facet {

const char* FocalModeName(FocalMode mode) {
  switch (mode) {
    case FocalMode::kSolve: return "solve";
    case FocalMode::kFixed: return "fixed";
    case FocalMode::kPrior: return "prior";
  }
  return "?";
}

std::optional<FocalMode> FocalModeFromName(const std::string& name) {
  if (name == "solve") return FocalMode::kSolve;
  if (name == "fixed") return FocalMode::kFixed;
  if (name == "prior") return FocalMode::kPrior;
  return std::nullopt;
}

}  // namespace facet
