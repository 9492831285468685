// What the running application holds: the document (project + undo history, from core),
// the UI state that is not undoable (selection, tool, active image), loaded photos, the
// derived textured mesh and the log. Panels read this and change the project only through
// the edit functions below, so that every change is one undoable history entry followed
// by the re-solve of cameras and geometry (the paper's state machine).
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/calibrate_vp.h"
#include "core/document.h"
#include "core/image_io.h"
#include "core/model_update.h"
#include "core/textured_mesh.h"

namespace facet::app {

enum class Tool {
  kSelect,     // pick and drag segment endpoints, pins, boxes
  kLineX,      // draw a segment of the x family
  kLineY,
  kLineZ,
  kPin,        // click a box corner, then click in the image: V_proj
  kAddBox,     // K_create box
};
const char* ToolName(Tool tool);

struct Selection {
  Id segment_id = kNoId;
  int segment_endpoint = -1;  // 0 = a, 1 = b, -1 = whole segment
  Id pin_id = kNoId;
  Id box_id = kNoId;
  int box_corner = -1;        // for the pin tool: the corner picked in the 3D or image panel
  bool Empty() const { return segment_id == kNoId && pin_id == kNoId && box_id == kNoId; }
};

enum class LogLevel { kInfo, kWarning, kError };
struct LogEntry {
  LogLevel level = LogLevel::kInfo;
  std::string text;
  double time_s = 0.0;  // since start
};

struct AppState {
  Document document;
  std::string project_path;  // empty for an unsaved project
  Selection selection;
  Tool tool = Tool::kSelect;
  Id active_image_id = kNoId;

  // Photos by image id, loaded once (core type; each panel makes its own GL textures).
  std::map<Id, ImageRgba8> photos;
  std::map<Id, std::string> photo_errors;

  // Derived from the project after each change (RefreshDerived).
  TexturedMesh mesh;
  std::uint64_t mesh_revision = 0;   // increments whenever mesh changes
  std::uint64_t atlas_revision = 0;  // increments when mesh.atlas changes (a subset of the above)
  ModelUpdateSummary last_update;   // calibration and solve figures of the last change
  TextureBakeSummary last_bake;
  // What the current mesh was built from, to rebuild it only when that changes.
  std::vector<Box> mesh_boxes;
  std::vector<Image> mesh_images;
  size_t mesh_photo_count = 0;
  bool mesh_texture_stale = false;  // geometry moved during a drag; texture not re-baked yet

  std::vector<LogEntry> log;
  double time_s = 0.0;
  bool request_quit = false;
  // An in-progress interactive drag: the project as it was when the drag began.
  std::optional<Project> drag_start;
  std::string drag_label;

  void Log(LogLevel level, std::string text);
  const Image* ActiveImage() const;
};

// Starts an empty, unsaved project (clears history).
void NewProject(AppState* state);
// Loads a project file into the state (clears history). Returns false and logs on failure,
// leaving the state as it was.
bool OpenProject(AppState* state, const std::string& path);
// Saves atomically to `path` (or project_path when empty). Logs and returns false on failure.
bool SaveProjectAs(AppState* state, const std::string& path);

// The one way panels change the project: `after` is the edited copy of the current project.
// Re-solves (calibration and geometry) and commits edit + solve as one history entry.
void CommitEdit(AppState* state, const std::string& label, Project after);

// Interactive drags (a pin, a segment endpoint): BeginDrag snapshots the project; each
// UpdateDrag replaces the previewed project by `edited` with a budgeted, warm-started solve
// so the frame never stalls; EndDrag runs the full solve and records the whole drag as one
// history entry; CancelDrag restores the snapshot.
void BeginDrag(AppState* state, const std::string& label);
void UpdateDrag(AppState* state, Project edited);
void EndDrag(AppState* state);
void CancelDrag(AppState* state);

void Undo(AppState* state);
void Redo(AppState* state);

// Loads missing photos and rebuilds the textured mesh when the project changed since the
// last call. Called once per frame before drawing.
void RefreshDerived(AppState* state);

}  // namespace facet::app
