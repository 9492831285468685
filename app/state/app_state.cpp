#include "app/state/app_state.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <system_error>

#include "core/io/project_io.h"

namespace facet::app {
namespace {

// After undo, redo or a cancelled drag the project is one the solver already produced; the
// panels still need its vanishing points and residuals, so they are recomputed for display
// without touching the project.
void RefreshDiagnostics(AppState* state) {
  Project unused;
  state->last_update = UpdateModel(state->document.project(), CommitUpdateOptions(), &unused, &state->update_cache);
}

bool Contains(const std::vector<std::string>& list, const std::string& text) {
  return std::find(list.begin(), list.end(), text) != list.end();
}

// Logs what changed since the previous update: a message that update already logged is still
// shown by the properties panel and is not appended again. Failures are warnings; progress
// (an unfinished drawing, e.g. a family with one line so far) and notes (what the update
// decided, e.g. a photo's world axes turned) are information.
void LogUpdate(AppState* state, const ModelUpdateSummary& previous, const ModelUpdateSummary& summary) {
  for (const std::string& m : summary.messages) {
    if (!Contains(previous.messages, m)) state->Log(LogLevel::kWarning, m);
  }
  for (const std::string& m : summary.progress) {
    if (!Contains(previous.progress, m)) state->Log(LogLevel::kInfo, m);
  }
  for (const std::string& n : summary.notes) state->Log(LogLevel::kInfo, n);
  for (const std::string& w : summary.warnings) {
    if (!Contains(previous.warnings, w)) state->Log(LogLevel::kWarning, w);
  }
}

}  // namespace

const char* ToolName(Tool tool) {
  switch (tool) {
    case Tool::kSelect: return "Select";
    case Tool::kLineX: return "Line X";
    case Tool::kLineY: return "Line Y";
    case Tool::kLineZ: return "Line Z";
    case Tool::kPin: return "Pin";
    case Tool::kAddPrimitive: return "Add primitive";
    case Tool::kSplitEdge: return "Split edge";
    case Tool::kDeleteVertex: return "Delete vertex";
    case Tool::kConnectVertices: return "Connect vertices";
    case Tool::kDeleteEdge: return "Delete edge";
    case Tool::kPushPull: return "Push/pull";
    case Tool::kMove: return "Move";
    case Tool::kLinePin: return "Line pin";
    case Tool::kMeasure: return "Measure";
  }
  return "?";
}

const char* ElementKindName(ElementKind kind) {
  switch (kind) {
    case ElementKind::kNone: return "none";
    case ElementKind::kVertex: return "vertex";
    case ElementKind::kEdge: return "edge";
    case ElementKind::kFace: return "face";
  }
  return "?";
}

bool ElementExists(const Project& project, const ElementRef& ref) {
  const Primitive* primitive = project.FindPrimitive(ref.primitive_id);
  if (primitive == nullptr) return false;
  switch (ref.kind) {
    case ElementKind::kNone: return true;
    case ElementKind::kVertex: return primitive->mesh.IsVertex(ref.element);
    case ElementKind::kEdge: return primitive->mesh.IsEdge(ref.element);
    case ElementKind::kFace: return primitive->mesh.IsFace(ref.element);
  }
  return false;
}

std::string DescribeElement(const Project& project, const ElementRef& ref) {
  const Primitive* primitive = project.FindPrimitive(ref.primitive_id);
  std::string text = primitive ? primitive->name : std::string("?");
  if (ref.kind != ElementKind::kNone)
    text += std::string(" ") + ElementKindName(ref.kind) + " " + std::to_string(ref.element);
  return text;
}

Selection Selection::Of(const ElementRef& element) {
  Selection selection;
  selection.primitive_id = element.primitive_id;
  selection.element = element;
  return selection;
}

std::vector<ElementRef> SelectedElements(const Selection& selection) {
  std::vector<ElementRef> all;
  if (!selection.element.Empty()) all.push_back(selection.element);
  for (const ElementRef& e : selection.extra) {
    if (!e.Empty()) all.push_back(e);
  }
  return all;
}

bool IsSelected(const Selection& selection, const ElementRef& ref) {
  if (ref.Empty()) return false;
  return selection.element == ref ||
         std::find(selection.extra.begin(), selection.extra.end(), ref) != selection.extra.end();
}

void ToggleSelected(Selection* selection, const ElementRef& ref) {
  if (ref.Empty()) return;
  if (selection->element.Empty()) {
    *selection = Selection::Of(ref);
    return;
  }
  if (selection->element == ref) {
    if (selection->extra.empty()) {
      *selection = Selection();
      return;
    }
    selection->element = selection->extra.front();
    selection->extra.erase(selection->extra.begin());
    selection->primitive_id = selection->element.primitive_id;
    return;
  }
  auto it = std::find(selection->extra.begin(), selection->extra.end(), ref);
  if (it != selection->extra.end()) {
    selection->extra.erase(it);
  } else {
    selection->extra.push_back(ref);
  }
}

bool AddSelected(Selection* selection, const ElementRef& ref) {
  if (ref.Empty() || IsSelected(*selection, ref)) return false;
  ToggleSelected(selection, ref);
  return true;
}

void AppState::Log(LogLevel level, std::string text) {
  if (level != LogLevel::kInfo) std::fprintf(stderr, "facet: %s\n", text.c_str());
  log.push_back({level, std::move(text), time_s});
  constexpr size_t kMaxLogEntries = 2000;
  if (log.size() > kMaxLogEntries) log.erase(log.begin(), log.begin() + (log.size() - kMaxLogEntries));
}

const Image* AppState::ActiveImage() const {
  const Image* image = document.project().FindImage(active_image_id);
  if (image) return image;
  return document.project().images.empty() ? nullptr : &document.project().images.front();
}

namespace {
// Everything that belongs to one document: its history, selection, photos and derived mesh.
void ResetDocument(AppState* state, Project project, const std::string& path) {
  state->document.Reset(std::move(project));
  state->line_proposals.reset();  // image ids start again in another project
  DropLineDetection(state);
  state->project_path = path;
  ++state->document_generation;
  state->selection = {};
  state->active_image_id = kNoId;
  // What the tools remember refers to the old project's elements, or is a choice made for
  // it: a new document starts with a box to add and no half-built constraint or measure.
  state->add_kind = PrimitiveKind::kBox;
  state->add_on_top = true;
  state->push_pull_face = {};
  state->measure_pair = {};
  state->constraint_first_edge = {};
  state->constraint_first_kind.reset();
  state->pointer_in_image_px.reset();
  state->pointer_image_id = kNoId;
  state->drag_start.reset();
  if (state->bake_job) {
    state->retired_photos.merge(state->photos);  // the worker may still read them
  }
  state->photos.clear();
  state->photo_errors.clear();
  state->photo_paths.clear();
  state->last_update = {};
  state->mesh_primitives.clear();
  state->hover = {};
  state->hover_panel = 0;
  state->mesh_images.clear();
  state->mesh_photo_count = 0;
  state->mesh_inputs_known = false;
  ++state->bake_input_revision;  // a bake of the previous document is dropped on arrival
  state->mesh = {};
  ++state->mesh_revision;
  ++state->atlas_revision;
}
}  // namespace

void NewProject(AppState* state) {
  ResetDocument(state, Project{}, "");
  ResetProjectGuard(&state->project_guard);  // releases the lock
  state->Log(LogLevel::kInfo, "New project");
}

bool OpenProject(AppState* state, const std::string& path, OpenAccess access) {
  ProjectGuard& guard = state->project_guard;
  // The lock first, so that what is read is what the holder of the lock may write. The lock
  // this session already holds on the same file is kept (a second flock from this process
  // would fail against it).
  const bool already_locked = guard.lock.Covers(path);
  ProjectLock lock;
  std::string read_only_reason;
  if (access != OpenAccess::kReadOnly && !already_locked && guard.lock_on_open) {
    ProjectLockResult taken = TryLockProject(path);
    if (taken.holder) {
      const std::string holder = DescribeLockHolder(path, *taken.holder);
      if (access == OpenAccess::kEdit) {
        state->Log(LogLevel::kError, "Cannot open " + path + " for editing: " + holder);
        guard.question = GuardQuestion::kOpenLocked;
        guard.question_path = path;
        guard.question_text = holder;
        return false;
      }
      read_only_reason = holder;
    } else if (!taken.ok()) {
      // A read-only folder, say: nothing here can be saved anyway, and the save will say so.
      state->Log(LogLevel::kInfo, "Opened without a lock (" + taken.error + "): another Facet could open it too");
    }
    lock = std::move(taken.lock);
  }
  if (access == OpenAccess::kReadOnly) {
    ProjectLockResult probe = TryLockProject(path);  // only to name the holder
    read_only_reason = probe.holder ? DescribeLockHolder(path, *probe.holder) : "as asked";
  }
  ProjectLoadResult loaded = LoadProject(path);
  if (!loaded.ok()) {
    state->Log(LogLevel::kError, "Cannot open " + path + ": " + loaded.error);
    return false;  // the new lock, if any, goes with `lock`
  }
  const FileIdentity known = IdentifyFile(path);
  for (const std::string& w : loaded.warnings) state->Log(LogLevel::kWarning, w);
  ResetDocument(state, std::move(loaded.project), path);
  ProjectLock kept = already_locked && read_only_reason.empty() ? std::move(guard.lock) : std::move(lock);
  ResetProjectGuard(&guard);  // the previous project's lock is released here
  guard.lock = std::move(kept);
  guard.read_only = !read_only_reason.empty();
  guard.read_only_reason = read_only_reason;
  guard.known = known;
  const Project& project = state->document.project();
  state->active_image_id = project.images.empty() ? kNoId : project.images.front().id;
  RefreshDiagnostics(state);  // the stored solution stays as saved
  if (guard.read_only) {
    state->Log(LogLevel::kInfo, "Opened " + path + " read-only (" + read_only_reason +
                                    "): nothing is written to it or its recovery file; Save writes a copy");
  } else {
    state->Log(LogLevel::kInfo, "Opened " + path);
  }
  return true;
}

bool SaveNeedsName(const AppState& state) { return state.project_path.empty() || state.project_guard.read_only; }

void RestoreDocument(AppState* state, Document document, const std::string& path) {
  // Another file than the one open (an unsaved project's recovery): its lock goes.
  if (path != state->project_path) ResetProjectGuard(&state->project_guard);
  ResetDocument(state, Project{}, path);
  state->document = std::move(document);
  const Project& project = state->document.project();
  state->active_image_id = project.images.empty() ? kNoId : project.images.front().id;
  RefreshDiagnostics(state);
}

namespace {
// Whether `a` and `b` name one file (both there), or the same path (neither there yet).
bool SameFile(const std::string& a, const std::string& b) {
  std::error_code ec;
  if (std::filesystem::equivalent(a, b, ec)) return true;
  return std::filesystem::absolute(a, ec).lexically_normal() == std::filesystem::absolute(b, ec).lexically_normal();
}
}  // namespace

bool SaveProjectAs(AppState* state, const std::string& path, bool overwrite_changed) {
  const std::string target = path.empty() ? state->project_path : path;
  if (target.empty()) {
    state->Log(LogLevel::kError, "Save: the project has no file name yet");
    return false;
  }
  ProjectGuard& guard = state->project_guard;
  // The target's lock: the one held already, or taken now (and kept once the save is done).
  ProjectLock lock;
  if (!guard.lock.Covers(target)) {
    ProjectLockResult taken = TryLockProject(target);
    if (taken.holder) {
      state->Log(LogLevel::kError, "Cannot save " + target + ": " + DescribeLockHolder(target, *taken.holder) +
                                       "; save it under another name");
      return false;
    }
    if (!taken.ok()) state->Log(LogLevel::kWarning, "Saving without a lock (" + taken.error + ")");
    lock = std::move(taken.lock);
  }
  // The project's own file, written by something else since it was read or written here: not
  // overwritten unless the user says so. (A file removed meanwhile holds nothing to lose.)
  std::error_code exists_ec;
  const bool own_file = !state->project_path.empty() && SameFile(target, state->project_path);
  if (own_file && !overwrite_changed && !FileUnchangedSince(target, guard.known) &&
      std::filesystem::exists(target, exists_ec)) {
    const std::string what =
        std::filesystem::path(target).filename().string() + " changed on disk since it was opened or saved here";
    state->Log(LogLevel::kError, "Cannot save " + target + ": " + what +
                                     " (another program wrote it); not overwritten: save it under another name, "
                                     "or overwrite it");
    guard.question = GuardQuestion::kSaveChanged;
    guard.question_path = target;
    guard.question_text = what;
    return false;
  }
  // Into another folder, the photos' relative paths must start from the new file's folder,
  // in the file and, once it is written, in the document (history included).
  const std::string old_path = state->project_path;
  std::error_code ec;
  const bool moves = !old_path.empty() && std::filesystem::absolute(old_path, ec).parent_path().lexically_normal() !=
                                              std::filesystem::absolute(target, ec).parent_path().lexically_normal();
  Project saved = state->document.project();
  if (moves) RebaseImagePaths(old_path, target, &saved);
  const std::string error = SaveProject(saved, target);
  if (!error.empty()) {
    state->Log(LogLevel::kError, "Cannot save " + target + ": " + error);
    return false;
  }
  if (moves) {
    state->document.RewriteImagePaths([&](const std::string& path) {
      if (path.empty()) return path;
      return RelativeImagePath(target, std::filesystem::absolute(ResolveImagePath(old_path, path), ec).string());
    });
  }
  state->project_path = target;
  state->document.MarkClean();
  if (lock.held() || !guard.lock.Covers(target)) guard.lock = std::move(lock);  // the old file's lock goes
  guard.read_only = false;
  guard.read_only_reason.clear();
  guard.known = IdentifyFile(target);
  state->Log(LogLevel::kInfo, "Saved " + target);
  return true;
}

void CommitEdit(AppState* state, const std::string& label, Project after) {
  Project updated;
  const ModelUpdateSummary previous = std::move(state->last_update);
  state->last_update = UpdateModel(after, CommitUpdateOptions(), &updated, &state->update_cache);
  LogUpdate(state, previous, state->last_update);
  if (state->document.Commit(label, updated)) state->Log(LogLevel::kInfo, label);
}

void BeginDrag(AppState* state, const std::string& label) {
  if (state->drag_start) return;
  state->drag_start = state->document.project();
  state->drag_start_update = state->last_update;
  state->drag_label = label;
}

void UpdateDrag(AppState* state, Project edited) {
  if (!state->drag_start) return;
  Project updated;
  state->last_update = UpdateModel(edited, DragFrameUpdateOptions(), &updated, &state->update_cache);
  *state->document.MutableProjectForPreview() = std::move(updated);
}

void EndDrag(AppState* state) {
  if (!state->drag_start) return;
  Project updated;
  // The drag frames' updates logged nothing: compare with the state before the drag.
  const ModelUpdateSummary previous = std::move(state->drag_start_update);
  state->last_update = UpdateModel(state->document.project(), CommitUpdateOptions(), &updated, &state->update_cache);
  LogUpdate(state, previous, state->last_update);
  *state->document.MutableProjectForPreview() = std::move(updated);
  if (state->document.CommitFrom(state->drag_label, *state->drag_start)) state->Log(LogLevel::kInfo, state->drag_label);
  state->drag_start.reset();
}

void CancelDrag(AppState* state) {
  if (!state->drag_start) return;
  state->document.CancelPreview(*state->drag_start);
  state->drag_start.reset();
  RefreshDiagnostics(state);
}

void Undo(AppState* state) {
  if (state->drag_start) CancelDrag(state);
  if (state->document.Undo()) {
    state->Log(LogLevel::kInfo, "Undo");
    ValidateSelection(state);
    RefreshDiagnostics(state);
  }
}

void Redo(AppState* state) {
  if (state->drag_start) return;
  if (state->document.Redo()) {
    state->Log(LogLevel::kInfo, "Redo");
    ValidateSelection(state);
    RefreshDiagnostics(state);
  }
}

void ValidateSelection(AppState* state) {
  const Project& project = state->document.project();
  Selection& s = state->selection;
  if (s.segment_id != kNoId && !project.FindSegment(s.segment_id)) {
    s.segment_id = kNoId;
    s.segment_endpoint = -1;
  }
  if (s.pin_id != kNoId && !project.FindPin(s.pin_id)) s.pin_id = kNoId;
  if (s.primitive_id != kNoId && !project.FindPrimitive(s.primitive_id)) s.primitive_id = kNoId;
  if (!s.element.Empty() && !ElementExists(project, s.element)) s.element = {};
  std::erase_if(s.extra, [&](const ElementRef& e) { return e.Empty() || !ElementExists(project, e); });
  if (s.element.Empty() && !s.extra.empty()) {
    // The main element went with an undo: the next one takes its place.
    s.element = s.extra.front();
    s.extra.erase(s.extra.begin());
    s.primitive_id = s.element.primitive_id;
  }
  if (!s.connect_from.Empty() && !ElementExists(project, s.connect_from)) s.connect_from = {};
  if (!state->hover.Empty() && !ElementExists(project, state->hover)) state->hover = {};
  // The builder's pending first edge: gone with its element, or with the selection.
  if (state->constraint_first_kind &&
      (!ElementExists(project, state->constraint_first_edge) || (s.Empty() && s.element.Empty()))) {
    state->constraint_first_kind.reset();
    state->constraint_first_edge = {};
  }
  if (!state->constraint_first_kind) state->constraint_first_edge = {};
}

namespace {

double MsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

// The mesh follows an edit at once. When the faces are the same ones (a move, a solve) they
// keep their place in the atlas, so the previous UVs stay valid, stretched by the move until
// the new bake arrives; otherwise the new mesh is untextured until then.
void ShowGeometry(AppState* state, const Project& project) {
  TexturedMesh geometry = BuildUntexturedMesh(project);
  ++state->mesh_revision;
  if (!state->mesh.atlas.empty() && geometry.positions.size() == state->mesh.positions.size() &&
      geometry.triangle_primitive == state->mesh.triangle_primitive &&
      geometry.triangle_face == state->mesh.triangle_face) {
    state->mesh.positions = std::move(geometry.positions);
    state->mesh.normals = std::move(geometry.normals);
    return;
  }
  state->mesh = std::move(geometry);
  ++state->atlas_revision;
}

BakeResult Bake(const Project& project, const std::vector<const ImageRgba8*>& photos) {
  BakeResult result;
  result.summary = BakeTexturedMesh(project, photos, TextureBakeOptions{}, &result.mesh);
  return result;
}

// Starts the bake of the current project on a worker thread. The worker gets its own copy of
// the project (small next to the photos) and pointers to the loaded photos, which RefreshDerived
// and ResetDocument keep alive (retired_photos) until the job is collected.
void StartBake(AppState* state) {
  const Project& project = state->document.project();
  std::vector<const ImageRgba8*> photos;
  photos.reserve(project.images.size());
  for (const Image& image : project.images) {
    const auto it = state->photos.find(image.id);
    photos.push_back(it == state->photos.end() || it->second.empty() ? nullptr : &it->second);
  }
  BakeJob job;
  job.input_revision = state->bake_input_revision;
  try {
    job.result = std::async(std::launch::async,
                            [snapshot = project, photos = std::move(photos)]() { return Bake(snapshot, photos); });
  } catch (const std::system_error& e) {
    // No thread to be had: bake here rather than leave the model untextured.
    state->Log(LogLevel::kWarning, std::string("Texture: baking on the main thread (") + e.what() + ")");
    std::promise<BakeResult> done;
    done.set_value(Bake(project, photos));
    job.result = done.get_future();
  }
  state->bake_job = std::move(job);
  ++state->bake_stats.started;
}

// Swaps a finished bake in, or drops it when the inputs changed since it started. With
// `wait`, blocks until the bake in flight finishes; otherwise returns at once when it has not.
void CollectBake(AppState* state, bool wait) {
  if (!state->bake_job) return;
  std::future<BakeResult>& future = state->bake_job->result;
  if (wait) {
    const auto start = std::chrono::steady_clock::now();
    future.wait();
    state->bake_stats.last_wait_ms = MsSince(start);
  } else if (future.wait_for(std::chrono::seconds(0)) != std::future_status::ready) {
    return;
  } else {
    state->bake_stats.last_wait_ms = 0.0;
  }
  const std::uint64_t input_revision = state->bake_job->input_revision;
  BakeResult result;
  try {
    result = future.get();
  } catch (const std::exception& e) {
    result.summary.termination = SolverTermination::kFailed;
    result.summary.message = std::string("the bake failed: ") + e.what();
    result.mesh = BuildUntexturedMesh(state->document.project());
  }
  state->bake_job.reset();
  WaitForLineDetectionPhotoCopy(*state);  // a photo retired meanwhile may be the one it copies
  state->retired_photos.clear();          // the bake's worker is done with them
  if (input_revision != state->bake_input_revision) {
    ++state->bake_stats.dropped;
    return;
  }
  ++state->bake_stats.collected;
  state->last_bake = std::move(result.summary);
  if (!state->last_bake.IsUsable()) state->Log(LogLevel::kWarning, "Texture: " + state->last_bake.message);
  state->mesh = std::move(result.mesh);  // the untextured mesh when the bake failed
  state->baked_input_revision = input_revision;
  ++state->mesh_revision;
  ++state->atlas_revision;
}

}  // namespace

bool BakeInFlight(const AppState& state) { return state.bake_job.has_value(); }

bool TexturePending(const AppState& state) { return state.baked_input_revision != state.bake_input_revision; }

std::string PhotoFilePath(const AppState& state, const Image& image) {
  return state.project_path.empty() ? image.path : ResolveImagePath(state.project_path, image.path);
}

void AdoptDecodedPhoto(AppState* state, Id image_id, ImageRgba8 photo) {
  const Image* image = state->document.project().FindImage(image_id);
  if (image == nullptr || state->photos.count(image_id)) return;
  state->photo_errors.erase(image_id);
  state->photo_paths[image_id] = PhotoFilePath(*state, *image);
  state->photos.emplace(image_id, std::move(photo));
}

void RefreshDerived(AppState* state) {
  const auto start = std::chrono::steady_clock::now();
  const Project& project = state->document.project();

  // Photos: load the new ones once, forget the ones that left the project (after the bake in
  // flight, which may read them, and the line detection's copy).
  auto photo_path = [&](const Image& image) { return PhotoFilePath(*state, image); };
  auto still_valid = [&](Id id) {
    const Image* image = project.FindImage(id);
    const auto path = state->photo_paths.find(id);
    return image != nullptr && path != state->photo_paths.end() && path->second == photo_path(*image);
  };
  for (auto it = state->photo_errors.begin(); it != state->photo_errors.end();)
    it = still_valid(it->first) ? std::next(it) : state->photo_errors.erase(it);
  for (auto it = state->photos.begin(); it != state->photos.end();) {
    const bool valid = still_valid(it->first);
    if (!valid) WaitForLineDetectionPhotoCopy(*state);
    if (valid) {
      ++it;
    } else if (state->bake_job) {
      const auto next = std::next(it);
      state->retired_photos.insert(state->photos.extract(it));
      it = next;
    } else {
      it = state->photos.erase(it);
    }
  }
  for (const Image& image : project.images) {
    if (state->photos.count(image.id) || state->photo_errors.count(image.id)) continue;
    const std::string path = photo_path(image);
    state->photo_paths[image.id] = path;
    ImageReadResult read = ReadImage(path);
    // A photo replaced by one of another size is not this image's: shown as a photo that
    // cannot be used (as a missing one), the pins stay in the image's pixels.
    if (read.ok()) read.error = WhyPhotoIsNotTheImages(image, path, read.image.width, read.image.height);
    if (read.ok()) {
      state->photos.emplace(image.id, std::move(read.image));
    } else {
      state->photo_errors[image.id] = read.error;
      state->Log(LogLevel::kError, read.error);
    }
  }

  ValidateSelection(state);
  ValidateLineProposals(state);

  // The mesh depends on the primitives, the cameras and the loaded photos only.
  const bool inputs_unchanged = state->mesh_inputs_known && state->mesh_primitives == project.primitives &&
                                state->mesh_images == project.images && state->mesh_photo_count == state->photos.size();
  if (!inputs_unchanged) {
    state->mesh_inputs_known = true;
    state->mesh_primitives = project.primitives;
    state->mesh_images = project.images;
    state->mesh_photo_count = state->photos.size();
    ++state->bake_input_revision;
    ShowGeometry(state, project);
  }

  // Before starting a bake, so that a result whose inputs were just edited is dropped.
  const bool had_job = state->bake_job.has_value();
  CollectBake(state, state->bake_mode == BakeMode::kFinishNextFrame);
  const double waited_ms = had_job && !state->bake_job ? state->bake_stats.last_wait_ms : 0.0;

  // While a pin is dragged only the geometry follows: the bake starts on release.
  if (!state->drag_start && !state->bake_job && TexturePending(*state)) {
    StartBake(state);
    state->bake_stats.start_refresh_ms = MsSince(start) - waited_ms;
  }
}

void FinishBake(AppState* state) {
  RefreshDerived(state);
  while (state->bake_job) {
    CollectBake(state, /*wait=*/true);
    if (!state->drag_start && TexturePending(*state)) StartBake(state);
  }
}

}  // namespace facet::app
