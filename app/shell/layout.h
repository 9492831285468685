// The docking-like panel layout built on ImGui 1.86 (which has no docking): every panel has
// a fixed slot in a tree of splits; a docked panel is tiled into its slot, a floating panel
// is a free ImGui window, a hidden panel takes no space. Split ratios, visibility, floating
// state and floating rectangles persist in a small JSON file under the user's config folder.
// Rectangles are in screen pixels, origin at the top-left of the window, y down.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "app/state/rect.h"

namespace facet::app {

enum class PanelId { kTools = 0, kImage, kViewport, kProperties, kHistory, kLog };
constexpr int kNumPanels = 6;
constexpr int kNumSplits = 5;
// Window titles; "Image" and "3D" are what tests and the render report look for.
const char* PanelTitle(PanelId panel);
std::optional<PanelId> PanelFromTitle(const std::string& title);

struct PanelPlacement {
  bool visible = true;
  bool floating = false;
  Rect floating_rect;  // screen px; used while floating
};

struct Layout {
  // Fraction of each split's extent given to its first child (left or top), in (0, 1).
  std::array<float, kNumSplits> split_ratio{};
  std::array<PanelPlacement, kNumPanels> panels{};

  PanelPlacement& placement(PanelId panel) { return panels[static_cast<int>(panel)]; }
  const PanelPlacement& placement(PanelId panel) const { return panels[static_cast<int>(panel)]; }
};

// Tools left, image and 3D side by side in the centre, properties right, history and log
// along the bottom; everything docked and visible.
Layout DefaultLayout();

// A draggable bar between the two children of a split.
struct Splitter {
  int split = 0;          // index into Layout::split_ratio
  bool side_by_side = 0;  // true: children left/right, the bar is vertical
  Rect bar;               // screen rectangle of the bar
  Rect extent;            // the split's whole rectangle (ratio is relative to it)
};

struct TiledLayout {
  std::array<std::optional<Rect>, kNumPanels> docked_rects;  // set for visible docked panels
  std::vector<Splitter> splitters;                           // only between non-empty children
};

// Tiles the visible docked panels into `work_area`. A subtree with no visible docked panel
// takes no space, so its sibling grows into it.
TiledLayout ComputeTiledLayout(const Layout& layout, const Rect& work_area);
// The new ratio of `splitter`'s split for a bar dragged to mouse coordinate (x, y), clamped
// so that both sides keep a minimum size.
float SplitRatioForMouse(const Splitter& splitter, float mouse_x, float mouse_y);
constexpr float kSplitterThicknessPx = 6.0f;

// Layout file: JSON. Unknown or malformed content gives false with *error set; *layout is
// then untouched.
std::string LayoutToJson(const Layout& layout);
bool LayoutFromJson(const std::string& text, Layout* layout, std::string* error);
// $XDG_CONFIG_HOME/facet, else $HOME/.config/facet; empty when neither is set.
std::string ConfigDirectory();
// ConfigDirectory()/layout.json (empty when there is no config directory).
std::string LayoutFilePath();
bool LoadLayoutFile(const std::string& path, Layout* layout, std::string* error);
bool SaveLayoutFile(const std::string& path, const Layout& layout, std::string* error);

}  // namespace facet::app
