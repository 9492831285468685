#include "app/move_tool.h"

namespace facet::app {

bool RunMoveCommand(AppState* /*state*/, const std::string& arg, std::string* error) {
  *error = "move-selection: not available yet ('" + arg + "')";
  return false;
}

}  // namespace facet::app
