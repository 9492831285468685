// File > Export view and `facet render --panel image|3d` (issue 15, figures for slides): the
// image panel or the 3D panel, with its overlays, alone in a PNG of a chosen size. The panel is
// drawn by its own code into an offscreen framebuffer in extra frames between two frames of
// the app (ImGui draws one frame at a time): a fresh copy of the panel showing the live one's
// view (the image panel's zoom and pan scaled to the new size, the 3D panel's orbit), alone in
// a window as large as the picture plus the panel's own bars, cropped to its canvas, and
// written through the atomic file writer (core/util/file_write.h). The live panels, the
// document and the layout are not touched.
#pragma once

#include <optional>
#include <string>

#include "app/shell/frame.h"

namespace facet::app {

struct ExportViewRequest {
  PanelId panel = PanelId::kImage;  // kImage or kViewport
  int width_px = 1920;
  int height_px = 1080;
  std::string path;  // a .png
};

// `export-view image|3d WxH PATH` (the input script, `facet render --panel`) or `export-view
// PATH` (File > Export view's browser: the panel and size chosen in the dialog). "" on
// success, else what is wrong.
std::string ParseExportViewArgs(const std::string& args, const ShellState& shell, ExportViewRequest* request);

// Renders and writes the picture now. Must run between frames (not inside ImGui::NewFrame ..
// Render) with the GL context current. Waits for the texture bake first. "" on success, else
// why it failed (nothing written then).
std::string ExportView(AppState* state, ShellState* shell, const ExportViewRequest& request, double time_s);

// Runs shell->pending_export_view, if any (the frame loops call it after each frame), and logs
// the outcome. "" when there was none or it succeeded, else why it failed.
std::string RunPendingExportView(AppState* state, ShellState* shell, double time_s);

}  // namespace facet::app
