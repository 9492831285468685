// Placeholder until the 3D panel lands.
#include "app/viewport_panel.h"

namespace facet::app {
void DrawViewportPanel(AppState*) {}
void ShutdownViewportPanel() {}
}  // namespace facet::app
