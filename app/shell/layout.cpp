#include "app/shell/layout.h"

#include "core/util/file_read.h"

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/io/project_io.h"

namespace facet::app {
namespace {

constexpr std::array<const char*, kNumPanels> kTitles = {"Tools", "Image", "3D", "Properties", "History", "Log"};
constexpr std::array<const char*, kNumPanels> kKeys = {"tools", "image", "3d", "properties", "history", "log"};
constexpr float kMinPanelExtentPx = 80.0f;

// The slot tree. A node is a leaf (one panel) or a split of two child nodes.
struct Node {
  bool leaf;
  PanelId panel;
  bool side_by_side;  // split: children left/right (else top/bottom)
  int split;          // split: index into Layout::split_ratio
  int a, b;           // split: child node indices
};
// 0: top | bottom; 1: tools | rest; 2: centre | properties; 3: image | 3D; 4: history | log.
constexpr std::array<Node, 11> kTree = {{
    {false, PanelId::kTools, false, 0, 1, 2},
    {false, PanelId::kTools, true, 1, 3, 4},
    {false, PanelId::kTools, true, 4, 9, 10},
    {true, PanelId::kTools, false, 0, 0, 0},
    {false, PanelId::kTools, true, 2, 5, 6},
    {false, PanelId::kTools, true, 3, 7, 8},
    {true, PanelId::kProperties, false, 0, 0, 0},
    {true, PanelId::kImage, false, 0, 0, 0},
    {true, PanelId::kViewport, false, 0, 0, 0},
    {true, PanelId::kHistory, false, 0, 0, 0},
    {true, PanelId::kLog, false, 0, 0, 0},
}};

bool NodeHasDocked(const Layout& layout, int node) {
  const Node& n = kTree[node];
  if (n.leaf) {
    const PanelPlacement& p = layout.placement(n.panel);
    return p.visible && !p.floating;
  }
  return NodeHasDocked(layout, n.a) || NodeHasDocked(layout, n.b);
}

void Tile(const Layout& layout, int node, const Rect& r, TiledLayout* out) {
  const Node& n = kTree[node];
  if (n.leaf) {
    out->docked_rects[static_cast<int>(n.panel)] = r;
    return;
  }
  const bool has_a = NodeHasDocked(layout, n.a);
  const bool has_b = NodeHasDocked(layout, n.b);
  if (!has_a && !has_b) return;
  if (!has_a || !has_b) {
    Tile(layout, has_a ? n.a : n.b, r, out);
    return;
  }
  const float ratio = layout.split_ratio[n.split];
  const float extent = n.side_by_side ? r.w : r.h;
  const float first = std::round((extent - kSplitterThicknessPx) * ratio);
  Rect ra = r, rb = r;
  Splitter s;
  s.split = n.split;
  s.side_by_side = n.side_by_side;
  s.extent = r;
  if (n.side_by_side) {
    ra.w = first;
    rb.x = r.x + first + kSplitterThicknessPx;
    rb.w = r.w - first - kSplitterThicknessPx;
    s.bar = {r.x + first, r.y, kSplitterThicknessPx, r.h};
  } else {
    ra.h = first;
    rb.y = r.y + first + kSplitterThicknessPx;
    rb.h = r.h - first - kSplitterThicknessPx;
    s.bar = {r.x, r.y + first, r.w, kSplitterThicknessPx};
  }
  out->splitters.push_back(s);
  Tile(layout, n.a, ra, out);
  Tile(layout, n.b, rb, out);
}

bool ReadFile(const std::string& path, std::string* text) {
  std::string error;
  return ReadRegularFile(path, kMaxTextFileBytes, text, &error);
}

}  // namespace

const char* PanelTitle(PanelId panel) { return kTitles[static_cast<int>(panel)]; }

std::optional<PanelId> PanelFromTitle(const std::string& title) {
  for (int i = 0; i < kNumPanels; ++i) {
    if (title == kTitles[i]) return static_cast<PanelId>(i);
  }
  return std::nullopt;
}

Layout DefaultLayout() {
  Layout layout;
  layout.split_ratio = {0.76f, 0.12f, 0.80f, 0.56f, 0.45f};
  for (int i = 0; i < kNumPanels; ++i) layout.panels[i] = PanelPlacement{};
  return layout;
}

TiledLayout ComputeTiledLayout(const Layout& layout, const Rect& work_area) {
  TiledLayout out;
  Tile(layout, 0, work_area, &out);
  return out;
}

float SplitRatioForMouse(const Splitter& s, float mouse_x, float mouse_y) {
  const float start = s.side_by_side ? s.extent.x : s.extent.y;
  const float extent = (s.side_by_side ? s.extent.w : s.extent.h) - kSplitterThicknessPx;
  if (extent <= 2 * kMinPanelExtentPx) return 0.5f;
  const float first = (s.side_by_side ? mouse_x : mouse_y) - start - kSplitterThicknessPx / 2;
  return std::clamp(first, kMinPanelExtentPx, extent - kMinPanelExtentPx) / extent;
}

std::string LayoutToJson(const Layout& layout) {
  nlohmann::json j;
  j["format"] = "facet-layout";
  j["version"] = 1;
  j["split_ratio"] = layout.split_ratio;
  for (int i = 0; i < kNumPanels; ++i) {
    const PanelPlacement& p = layout.panels[i];
    const Rect& r = p.floating_rect;
    j["panels"][kKeys[i]] = {{"visible", p.visible}, {"floating", p.floating}, {"rect", {r.x, r.y, r.w, r.h}}};
  }
  return j.dump(2);
}

bool LayoutFromJson(const std::string& text, Layout* layout, std::string* error) {
  const nlohmann::json j = nlohmann::json::parse(text, nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded() || !j.is_object()) {
    *error = "layout file is not valid JSON";
    return false;
  }
  try {
    if (j.value("version", 0) != 1) {
      *error = "layout file has an unknown version";
      return false;
    }
    Layout parsed = DefaultLayout();
    const auto& ratios = j.at("split_ratio");
    if (!ratios.is_array() || ratios.size() != kNumSplits) {
      *error = "layout file: split_ratio must hold " + std::to_string(kNumSplits) + " numbers";
      return false;
    }
    for (int i = 0; i < kNumSplits; ++i) {
      const float r = ratios[i].get<float>();
      if (!(r > 0.02f && r < 0.98f)) {
        *error = "layout file: split ratio out of range";
        return false;
      }
      parsed.split_ratio[i] = r;
    }
    const auto& panels = j.at("panels");
    for (int i = 0; i < kNumPanels; ++i) {
      if (!panels.contains(kKeys[i])) continue;
      const auto& p = panels.at(kKeys[i]);
      PanelPlacement& out = parsed.panels[i];
      out.visible = p.value("visible", true);
      out.floating = p.value("floating", false);
      const auto& r = p.at("rect");
      out.floating_rect = {r.at(0).get<float>(), r.at(1).get<float>(), r.at(2).get<float>(), r.at(3).get<float>()};
      if (out.floating && (out.floating_rect.w < 40 || out.floating_rect.h < 40)) out.floating = false;
    }
    *layout = parsed;
    return true;
  } catch (const std::exception& e) {
    *error = std::string("layout file: ") + e.what();
    return false;
  }
}

std::string ConfigDirectory() {
  if (const char* xdg = std::getenv("XDG_CONFIG_HOME"); xdg && *xdg) return std::string(xdg) + "/facet";
  if (const char* home = std::getenv("HOME"); home && *home) return std::string(home) + "/.config/facet";
  return {};
}

std::string LayoutFilePath() {
  const std::string dir = ConfigDirectory();
  return dir.empty() ? std::string() : dir + "/layout.json";
}

bool LoadLayoutFile(const std::string& path, Layout* layout, std::string* error) {
  std::string text;
  if (!ReadFile(path, &text)) {
    *error = "cannot read " + path;
    return false;
  }
  return LayoutFromJson(text, layout, error);
}

bool SaveLayoutFile(const std::string& path, const Layout& layout, std::string* error) {
  std::error_code ec;
  std::filesystem::create_directories(std::filesystem::path(path).parent_path(), ec);
  if (ec) {
    *error = "cannot create " + std::filesystem::path(path).parent_path().string() + ": " + ec.message();
    return false;
  }
  *error = WriteFileAtomically(path, LayoutToJson(layout));
  return error->empty();
}

}  // namespace facet::app
