// What every solver reports, and the early return of one that could not run.
#pragma once

#include <chrono>
#include <string>
#include <utility>

#include "core/util/timer.h"

namespace facet::internal {

// The early return of a solver that could not run: success = false, the message, and the time
// so far, on the summary as filled in up to then.
template <typename Summary>
Summary FailedSummary(Summary summary, std::string message, std::chrono::steady_clock::time_point start) {
  summary.success = false;
  summary.message = std::move(message);
  summary.time_ms = MsSince(start);
  return summary;
}

}  // namespace facet::internal
