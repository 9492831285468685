#include "core/optim/solver_summary.h"

namespace facet {

const char* SolverTerminationName(SolverTermination termination) {
  switch (termination) {
    case SolverTermination::kConverged: return "converged";
    case SolverTermination::kMaxIterations: return "max iterations";
    case SolverTermination::kNothingToSolve: return "nothing to solve";
    case SolverTermination::kFailed: return "failed";
    case SolverTermination::kInvalidInput: return "invalid input";
  }
  return "?";
}

}  // namespace facet
