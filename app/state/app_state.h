// What the running application holds: the document (project + undo history, from core),
// the UI state that is not undoable (selection, tool, active image), loaded photos, the
// derived textured mesh and the log. Panels read this and change the project only through
// the edit functions below, so that every change is one undoable history entry followed
// by the re-solve of cameras and geometry (the paper's state machine).
#pragma once

#include <array>
#include <cstdint>
#include <future>
#include <map>
#include <set>
#include <optional>
#include <string>
#include <vector>

#include "app/state/autosave.h"
#include "app/state/colmap_cameras.h"
#include "app/state/ghost_pins.h"
#include "app/state/line_proposals.h"
#include "app/state/project_guard.h"
#include "app/state/rect.h"
#include "app/state/teach.h"
#include "app/state/texture_choices.h"
#include "core/estimators/calibrate_vp.h"
#include "core/image/image_io.h"
#include "core/io/reference_mesh.h"
#include "core/mesh/primitives.h"
#include "core/scene/document.h"
#include "core/solve/model_update.h"
#include "core/texture/textured_mesh.h"

namespace facet::app {

enum class Tool {
  kSelect,  // pick vertices, edges, faces; drag segment endpoints and pins
  kLineX,   // draw a segment of the x family
  kLineY,
  kLineZ,
  kPin,              // click a model vertex, then click in the image: V_proj
  kAddPrimitive,     // K_create of AppState::add_kind (an action: it adds at once)
  kSplitEdge,        // E_split: click on an edge, split at the clicked point
  kDeleteVertex,     // V_delete: click on a vertex made by E_split
  kConnectVertices,  // V_connect: click two vertices of one face
  kDeleteEdge,       // E_delete: click on an edge between two faces
  kPushPull,         // push/pull: extrude the selected face by a typed distance
  kMove,             // V_op: drag a vertex or a primitive in the 3D panel (app/state/move_tool.h)
  kLinePin,          // pin the selected edge to a line drawn in the image (kEdgeOnImageLine)
  kMeasure,          // click two vertices, type their distance: a known length (kDistance)
};
const char* ToolName(Tool tool);

// A vertex, edge or face of a primitive's mesh, by stable ids (core/mesh/mesh.h).
enum class ElementKind { kNone, kVertex, kEdge, kFace };
const char* ElementKindName(ElementKind kind);  // "vertex", "edge", "face"
struct ElementRef {
  ElementKind kind = ElementKind::kNone;
  Id primitive_id = kNoId;
  std::uint32_t element = kNoElement;  // VertexId, EdgeId or FaceId by kind
  bool Empty() const { return kind == ElementKind::kNone; }
  friend bool operator==(const ElementRef&, const ElementRef&) = default;
};
// Whether the primitive and its (live) element exist in the project.
bool ElementExists(const Project& project, const ElementRef& ref);
// "box 1 vertex 9" for the log and tooltips.
std::string DescribeElement(const Project& project, const ElementRef& ref);

// What the user picked; not part of the document, so not undoable. Ids that an undo removes
// are cleared by ValidateSelection.
struct Selection {
  Id segment_id = kNoId;
  int segment_endpoint = -1;  // 0 = a, 1 = b, -1 = whole segment
  Id pin_id = kNoId;
  Id primitive_id = kNoId;  // the primitive the properties panel edits
  ElementRef element;       // a vertex, edge or face of it (the pin tool pins a vertex)
  // Multi-selection (Shift+click, `select-add`): further vertices, edges or faces, of any
  // primitives, in the order they were added; never `element` itself, never twice. The
  // constraint builder reads element + extra (SelectedElements).
  std::vector<ElementRef> extra;
  ElementRef connect_from;  // V_connect: the first vertex clicked
  // The selected line pin (a kEdgeOnImageLine constraint) and the edge it pins, which is
  // `element`: it holds while the selection is exactly that edge (the image panel checks).
  Id line_pin_id = kNoId;
  ElementRef line_pin_edge;
  bool Empty() const { return segment_id == kNoId && pin_id == kNoId && primitive_id == kNoId; }
  // Selects an element and its primitive, clearing segment, pin and the multi-selection.
  static Selection Of(const ElementRef& element);
};

// The selected elements: `element` (when set) first, then `extra`.
std::vector<ElementRef> SelectedElements(const Selection& selection);
// Whether `ref` is the selection's element or one of its extra elements.
bool IsSelected(const Selection& selection, const ElementRef& ref);
// Shift+click: adds `ref` to the selection, or removes it when it is selected already (the
// first extra element then becomes the main one). A selection without an element (none, a
// segment, a pin, a whole primitive) becomes Selection::Of(ref). An empty ref does nothing.
void ToggleSelected(Selection* selection, const ElementRef& ref);
// `select-add`: adds `ref` unless it is selected already. Returns whether it added.
bool AddSelected(Selection* selection, const ElementRef& ref);

enum class LogLevel { kInfo, kWarning, kError };
struct LogEntry {
  LogLevel level = LogLevel::kInfo;
  std::string text;
  double time_s = 0.0;  // since start
};

// How RefreshDerived runs the texture bake. Both bake on a worker thread, so the frame that
// starts a bake returns at once with the new geometry and the previous (or no) texture.
enum class BakeMode {
  kBackground,       // GUI: the first frame after the result arrives swaps it in
  kFinishNextFrame,  // offscreen: the next frame waits for it, so a script gives the same
                     // pictures however fast the machine is
};

// A texture bake on a worker thread, for one revision of the bake's inputs (AppState::
// bake_input_revision). The worker reads its own copy of the project and the photos in
// AppState::photos / retired_photos, which stay alive and unchanged until it is collected.
struct BakeResult {
  TexturedMesh mesh;
  TextureBakeSummary summary;
};
struct BakeJob {
  std::uint64_t input_revision = 0;
  std::future<BakeResult> result;
};

// Counters and main-thread timings of the background bake, for the `bake-status` command.
struct BakeStats {
  int started = 0;
  int collected = 0;  // results swapped in
  int dropped = 0;    // results that arrived after a newer edit and were thrown away
  // Main-thread time of the RefreshDerived call that started the latest bake (new geometry,
  // project snapshot, thread start), without any wait for an earlier bake in the same call.
  double start_refresh_ms = 0.0;
  double last_wait_ms = 0.0;  // main thread blocked on the latest collected or dropped bake
};

// A reference's mesh as read for drawing and snapping (app/state/reference_edits.h), or why it
// could not be.
struct LoadedReference {
  std::string file;    // the resolved file it was read from
  bool y_up = true;    // the axes it was read with
  ReferenceMesh mesh;  // empty when error is set
  std::string error;
};

struct AppState {
  Document document;
  std::string project_path;  // empty for an unsaved project
  // Increments whenever another document replaces this one (new, open, a restored recovery):
  // the panels then start their views afresh (fitted photo, framed model).
  std::uint64_t document_generation = 0;
  Selection selection;
  Tool tool = Tool::kSelect;
  PrimitiveKind add_kind = PrimitiveKind::kBox;  // what kAddPrimitive adds
  bool add_on_top = true;                        // a wedge, pyramid or plane goes on top of the selected box
  // Push/pull: the distance field's value (project units) and the face it was defaulted for;
  // a newly selected face gets the default again (and the field the keyboard focus).
  double push_pull_distance = 0.0;
  ElementRef push_pull_face;
  // Constraint builder (properties panel): the known-length field (project units), and the
  // first edge of a two-edge kind (parallel, perpendicular, equal length) awaiting its second.
  double constraint_length = 1.0;
  // The Measure tool's length field (project units) and the vertex pair it was defaulted for
  // (a new pair gets their current distance and the keyboard focus).
  double measure_length = 1.0;
  std::array<ElementRef, 2> measure_pair;
  ElementRef constraint_first_edge;
  std::optional<ConstraintKind> constraint_first_kind;
  Id active_image_id = kNoId;
  // The element under the mouse in the image or 3D panel (both highlight it), and which
  // panel set it (0 none, 1 image, 2 3D): a panel clears only its own hover.
  ElementRef hover;
  int hover_panel = 0;
  // The pointer over the image panel, in px of the image it shows (pointer_image_id); empty
  // elsewhere. The image panel sets it each frame; Add primitive aims there.
  std::optional<Eigen::Vector2d> pointer_in_image_px;
  Id pointer_image_id = kNoId;
  // Screen rectangles of the panels' main widgets in this frame by name (e.g. "tool.Pin",
  // "primitive.name"): per-frame UI introspection for the render report and tests, cleared
  // by DrawFrame, filled by RecordItem (app/panels/widgets.h).
  std::map<std::string, Rect> item_rects;
  // Of those, the ones whose centre is outside their panel's visible part (scrolled away).
  std::set<std::string> clipped_items;

  // Photos by image id, loaded once (core type; each panel makes its own GL textures). An
  // entry is never changed in place once loaded, so the bake's worker thread reads the pixels
  // without a copy; an entry removed while a bake is in flight moves to retired_photos (the
  // same node, so the same address) until that bake is collected.
  std::map<Id, ImageRgba8> photos;
  std::multimap<Id, ImageRgba8> retired_photos;
  std::map<Id, std::string> photo_errors;
  // The file each entry of photos or photo_errors was read from: when an image's path changes
  // (Relink photo, its undo), the photo is read again.
  std::map<Id, std::string> photo_paths;
  // Reference meshes by reference id, read from their files (SyncReferenceMeshes);
  // reference_revision increments whenever one is read or dropped.
  std::map<Id, LoadedReference> references;
  std::uint64_t reference_revision = 0;

  // Derived from the project after each change (RefreshDerived).
  TexturedMesh mesh;
  std::uint64_t mesh_revision = 0;   // increments whenever mesh changes
  std::uint64_t atlas_revision = 0;  // increments when mesh.atlas changes (a subset of the above)
  ModelUpdateSummary last_update;    // calibration and solve figures of the last change
  // Calibration results reused while an image's inputs are unchanged (core/solve/model_update.h):
  // drag frames then skip the vanishing-point and plumb-line fits of untouched images.
  ModelUpdateCache update_cache;
  TextureBakeSummary last_bake;
  // What the current mesh was built from, to rebuild it only when that changes.
  std::vector<Primitive> mesh_primitives;
  std::vector<Image> mesh_images;
  size_t mesh_photo_count = 0;
  bool mesh_inputs_known = false;  // false until the first build of a document
  // Increments whenever the bake's inputs (primitives, images, loaded photos) change; the
  // texture shown comes from baked_input_revision, behind it while a bake is pending.
  std::uint64_t bake_input_revision = 0;
  std::uint64_t baked_input_revision = 0;
  BakeMode bake_mode = BakeMode::kBackground;
  BakeStats bake_stats;

  // Lines detected on a photo, awaiting the user's accept (app/state/line_proposals.h), the
  // detection on its worker thread, and the Add photo option that detects them on every added
  // photo.
  std::optional<LineProposals> line_proposals;
  LineDetectionWork line_detection;
  bool detect_lines_on_add = true;  // ticked from the start, as the tutorial's first step expects
  // Pins proposed in the shown photo from the other photos' pins (app/state/ghost_pins.h).
  GhostPinsState ghost_pins;
  // The image panel's Snap option (app/panels/image_snapping.h): points placed in a photo snap
  // to corners, segments and the model nearby; Alt turns it off for one placement.
  bool snapping = true;

  // The recovery file kept while there are unsaved changes (app/state/autosave.h).
  AutosaveState autosave;
  // The project's lock and its file's identity when last read or written (app/state/project_guard.h).
  ProjectGuard project_guard;
  // Teach mode's overlays (View > Teach, app/state/teach.h): view settings, not in the project.
  TeachView teach;
  // View > Texture sources and File > Export's resolution (app/state/texture_choices.h).
  TextureView texture;

  std::vector<LogEntry> log;
  double time_s = 0.0;
  bool request_quit = false;
  // An in-progress interactive drag: the project as it was when the drag began.
  std::optional<Project> drag_start;
  ModelUpdateSummary drag_start_update;  // last_update when the drag began (what was logged)
  std::string drag_label;

  // File > Cameras from all photos: COLMAP on its worker thread, its window and its last outcome
  // (app/state/colmap_cameras.h).
  ColmapWork colmap;

  // The bake in flight, if any. Declared last so that it is destroyed first: the future of
  // std::async waits for the worker before the photos it reads are freed.
  std::optional<BakeJob> bake_job;

  void Log(LogLevel level, std::string text);
  const Image* ActiveImage() const;
};

// Starts an empty, unsaved project (clears history) and releases the project's lock.
void NewProject(AppState* state);
// Loads a project file into the state (clears history), taking its lock as `access` says
// (app/state/project_guard.h); the previous project's lock is released once it has opened.
// Returns false and logs on failure, leaving the state as it was; when another Facet holds
// the lock (kEdit), project_guard.question is kOpenLocked.
bool OpenProject(AppState* state, const std::string& path, OpenAccess access = OpenAccess::kEdit);
// Saves atomically to `path` (or project_path when empty), taking its lock. Logs and returns
// false on failure: another Facet holds the target's lock; or the target is the project's
// file and it changed on disk since it was read or written here (unless `overwrite_changed`),
// then project_guard.question is kSaveChanged.
bool SaveProjectAs(AppState* state, const std::string& path, bool overwrite_changed = false);
// Whether Save must ask for a name (Save as): an unsaved project, or one opened read-only.
bool SaveNeedsName(const AppState& state);
// Replaces the whole document, history included (a restored recovery file), as opening a
// project does: selection, photos and derived state start again.
void RestoreDocument(AppState* state, Document document, const std::string& path);

// The one way panels change the project: `after` is the edited copy of the current project.
// Re-solves (calibration and geometry) and commits edit + solve as one history entry.
// The file an image's photo is read from: its stored path resolved against the project file
// (as stored while the project is unsaved).
std::string PhotoFilePath(const AppState& state, const Image& image);
// Gives the photo cache a photo decoded elsewhere (Add photo, Relink photo validate by
// decoding), so it is not read twice; ignored when the cache already holds one for the image.
void AdoptDecodedPhoto(AppState* state, Id image_id, ImageRgba8 photo);

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

// Drops selected ids that are no longer in the project (after undo, redo, a delete),
// including the multi-selection's; forgets the constraint builder's stored first edge when
// its element is gone or nothing is selected any more.
void ValidateSelection(AppState* state);

// Loads missing photos and follows project changes: called once per frame before drawing.
// When the primitives, images or loaded photos changed since the last call, the mesh shows
// the new geometry at once (keeping the previous texture when the faces are the same ones,
// else untextured) and the texture is re-baked on a worker thread: one bake in flight; a
// result whose inputs were edited since is dropped and the newest inputs baked next. A
// finished bake is swapped in here, on the main thread (the 3D panel then uploads its atlas).
// During a drag only the geometry follows; the bake waits for the release.
void RefreshDerived(AppState* state);

// Whether a bake runs on the worker thread; whether the texture shown is behind the geometry
// (a bake in flight or still to start, e.g. during a drag).
bool BakeInFlight(const AppState& state);
bool TexturePending(const AppState& state);

// Blocks until the texture matches the current project (refreshes first, so an edit since
// the last frame is baked too), unless a drag defers the bake: for screenshots, exports and
// scripts that need the finished model.
void FinishBake(AppState* state);

}  // namespace facet::app
