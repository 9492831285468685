// The one shape of every solver's summary, as in Ceres: how it ended, the cost before and
// after, the iterations and the time, and whether the result may be used.
#pragma once

#include <chrono>
#include <string>
#include <utility>
#include <vector>

#include "core/util/timer.h"

namespace facet {

enum class SolverTermination {
  kConverged,       // a stop test of the solver was met: the result is a minimum
  kMaxIterations,   // the iteration budget ran out: the result is better than the start, usable
  kNothingToSolve,  // e.g. no pins in calibrated images, no free parameters
  kFailed,          // diverged, degenerate or numerically failed: the result must not be used
  kInvalidInput,    // options or input rejected before solving; see the message
};
const char* SolverTerminationName(SolverTermination termination);  // "converged", "max iterations", ...

struct SolverSummary {
  SolverTermination termination = SolverTermination::kInvalidInput;
  std::string message;                // one sentence for the log or the status bar
  std::vector<std::string> warnings;  // what the user may want to fix, one sentence each
  int iterations = 0;
  double initial_cost = 0.0;  // the solver's own objective (its header says which), at the start
  double final_cost = 0.0;
  double time_ms = 0.0;

  bool IsUsable() const {
    return termination == SolverTermination::kConverged || termination == SolverTermination::kMaxIterations;
  }
};

namespace internal {

// The early return of a solver that could not run: kFailed (or the termination given), the
// message, and the time so far, on the summary as filled in up to then.
template <typename Summary>
Summary FailedSummary(Summary summary, std::string message, std::chrono::steady_clock::time_point start,
                      SolverTermination termination = SolverTermination::kFailed) {
  summary.termination = termination;
  summary.message = std::move(message);
  summary.time_ms = MsSince(start);
  return summary;
}

}  // namespace internal
}  // namespace facet
