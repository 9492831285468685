#include "app/state/reference_edits.h"

#include <algorithm>
#include <filesystem>
#include <limits>
#include <system_error>

#include "core/io/project_io.h"

namespace facet::app {
namespace {

// As photos are stored: relative to the project file's folder, absolute while unsaved.
std::string StoredPath(const std::string& project_path, const std::string& file_path) {
  std::error_code ec;
  const std::filesystem::path absolute = std::filesystem::absolute(file_path, ec);
  if (ec) return file_path;
  if (project_path.empty()) return absolute.lexically_normal().generic_string();
  return RelativeImagePath(project_path, absolute.string());
}

std::string ResolvedPath(const AppState& state, const Reference& reference) {
  return state.project_path.empty() ? reference.path : ResolveImagePath(state.project_path, reference.path);
}

}  // namespace

bool AddReferenceEdit(AppState* state, const std::string& file_path, bool y_up) {
  ReferenceMesh mesh;
  const std::string error = ReadReferenceMesh(file_path, y_up, &mesh);
  if (!error.empty()) {
    state->Log(LogLevel::kError, "Add reference: " + error);
    return false;
  }
  Project after = state->document.project();
  Reference reference;
  reference.id = after.NewId();
  reference.path = StoredPath(state->project_path, file_path);
  reference.y_up = y_up;
  after.references.push_back(reference);
  const std::string name = std::filesystem::path(file_path).filename().string();
  // Not part of the model: nothing to re-solve, so the edit is committed as it is.
  if (!state->document.Commit("Add reference " + name, after)) return false;
  LoadedReference loaded;
  loaded.file = ResolvedPath(*state, reference);
  loaded.y_up = y_up;
  loaded.mesh = std::move(mesh);
  const size_t triangles = loaded.mesh.triangles.size();
  state->references[reference.id] = std::move(loaded);
  ++state->reference_revision;
  state->Log(LogLevel::kInfo, "Add reference " + name + " (" + std::to_string(triangles) + " triangles)");
  return true;
}

bool RemoveReferenceEdit(AppState* state, Id id) {
  Project after = state->document.project();
  const auto it = std::find_if(after.references.begin(), after.references.end(),
                               [&](const Reference& r) { return r.id == id; });
  if (it == after.references.end()) {
    state->Log(LogLevel::kError, "Remove reference: there is no reference " + std::to_string(id));
    return false;
  }
  const std::string label = "Remove reference " + std::filesystem::path(it->path).filename().string();
  after.references.erase(it);
  if (!state->document.Commit(label, after)) return false;
  state->Log(LogLevel::kInfo, label);
  return true;
}

bool SetReferenceVisibleEdit(AppState* state, Id id, bool visible) {
  Project after = state->document.project();
  Reference* reference = after.FindReference(id);
  if (reference == nullptr) {
    state->Log(LogLevel::kError, "Show reference: there is no reference " + std::to_string(id));
    return false;
  }
  if (reference->visible == visible) return true;
  reference->visible = visible;
  const std::string label =
      std::string(visible ? "Show" : "Hide") + " reference " + std::filesystem::path(reference->path).filename().string();
  if (state->document.Commit(label, after)) state->Log(LogLevel::kInfo, label);
  return true;
}

void SyncReferenceMeshes(AppState* state) {
  const Project& project = state->document.project();
  for (auto it = state->references.begin(); it != state->references.end();) {
    if (project.FindReference(it->first) == nullptr) {
      it = state->references.erase(it);
      ++state->reference_revision;
    } else {
      ++it;
    }
  }
  for (const Reference& reference : project.references) {
    const std::string file = ResolvedPath(*state, reference);
    const auto found = state->references.find(reference.id);
    if (found != state->references.end() && found->second.file == file && found->second.y_up == reference.y_up)
      continue;
    LoadedReference loaded;
    loaded.file = file;
    loaded.y_up = reference.y_up;
    loaded.error = ReadReferenceMesh(file, reference.y_up, &loaded.mesh);
    if (!loaded.error.empty())
      state->Log(LogLevel::kWarning, "Reference not drawn: " + loaded.error + " (it stays in the project)");
    state->references[reference.id] = std::move(loaded);
    ++state->reference_revision;
  }
}

bool NearestReferenceVertex(const AppState& state, const PickRay& ray, double radius_px, Eigen::Vector3d* p_in_world) {
  const Project& project = state.document.project();
  double best = radius_px;
  bool found = false;
  for (const auto& [id, loaded] : state.references) {
    const Reference* reference = project.FindReference(id);
    if (reference == nullptr || !reference->visible) continue;
    for (const Eigen::Vector3d& p : loaded.mesh.positions) {
      Eigen::Vector2d px;
      if (!ProjectToPanel(ray, p, &px)) continue;
      const double d = (px - ray.mouse_px).norm();
      if (d < best) {
        best = d;
        *p_in_world = p;
        found = true;
      }
    }
  }
  return found;
}

}  // namespace facet::app
