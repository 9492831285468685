// Placeholder until the image panel lands.
#include "app/image_panel.h"

namespace facet::app {
void DrawImagePanel(AppState*) {}
ImageViewReport LastImageViewReport() { return {}; }
void ShutdownImagePanel() {}
}  // namespace facet::app
