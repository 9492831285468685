// The render report's "teach" section (facet render --report): the view settings of teach
// mode and everything its overlays draw (app/state/teach.h), with the clipboard, so that tests
// check the drawn geometry and the copied numbers against the truth.
#pragma once

#include <nlohmann/json.hpp>

#include "app/state/app_state.h"

namespace facet::app {

nlohmann::json TeachReportJson(const AppState& state);

}  // namespace facet::app
