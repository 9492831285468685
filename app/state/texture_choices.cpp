#include "app/state/texture_choices.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <sstream>

#include "app/state/app_state.h"

namespace facet::app {
namespace {

// Photo colours: hues in golden-ratio steps (each photo's hue 0.618 of the usable circle on
// from the one before), which never repeat and leave any number of photos spread evenly, the
// gaps at most ~2.6 times apart. The circle leaves out the band of the selection's orange
// (hues 29-34 deg) with a margin; saturation is high, so that no photo's colour is the grey of
// untextured faces, and the value alternates, so neighbouring hues of many photos still differ
// in brightness. Photo 1 keeps the blue it had.
constexpr double kGoldenStep = 0.6180339887498949;
constexpr double kOrangeBandLoDeg = 15.0;
constexpr double kOrangeBandHiDeg = 50.0;
constexpr double kFirstHueDeg = 217.4;  // {66, 133, 244}
constexpr double kSaturation = 0.73;
constexpr double kValues[2] = {0.957, 0.78};

std::array<std::uint8_t, 3> FromHsv(double hue_deg, double saturation, double value) {
  const double h = std::fmod(hue_deg, 360.0) / 60.0;
  const double c = value * saturation;
  const double x = c * (1.0 - std::abs(std::fmod(h, 2.0) - 1.0));
  double r = 0.0, g = 0.0, b = 0.0;
  switch (static_cast<int>(h)) {
    case 0: r = c, g = x; break;
    case 1: r = x, g = c; break;
    case 2: g = c, b = x; break;
    case 3: g = x, b = c; break;
    case 4: r = x, b = c; break;
    default: r = c, b = x; break;
  }
  const double m = value - c;
  auto byte = [m](double channel) { return static_cast<std::uint8_t>(std::lround(255.0 * (channel + m))); };
  return {byte(r), byte(g), byte(b)};
}

// Commits a texture choice: no geometry changes, so no re-solve; one history entry.
bool CommitTextureChoice(AppState* state, const std::string& label, const Project& edited) {
  if (!state->document.Commit(label, edited)) return false;
  state->Log(LogLevel::kInfo, label);
  return true;
}

bool Refuse(AppState* state, const std::string& message) {
  state->Log(LogLevel::kError, message);
  return false;
}

// The primitive of a live face in `project`, or null after logging why not.
Primitive* FaceOwner(AppState* state, Project* project, Id primitive_id, FaceId face, const char* what) {
  Primitive* primitive = project->FindPrimitive(primitive_id);
  if (primitive == nullptr || !primitive->mesh.IsFace(face)) {
    Refuse(state,
           std::string(what) + ": no face " + std::to_string(face) + " of primitive " + std::to_string(primitive_id));
    return nullptr;
  }
  return primitive;
}

std::string FaceText(const Primitive& primitive, FaceId face) {
  return primitive.name + " face " + std::to_string(face);
}

size_t ImageIndex(const Project& project, Id image_id) {
  for (size_t i = 0; i < project.images.size(); ++i) {
    if (project.images[i].id == image_id) return i;
  }
  return project.images.size();
}

bool ParseIndex(const std::string& word, size_t count, size_t* out) {
  char* end = nullptr;
  errno = 0;
  const long value = std::strtol(word.c_str(), &end, 10);
  if (word.empty() || *end != '\0' || errno != 0 || value < 0 || static_cast<size_t>(value) >= count) return false;
  *out = static_cast<size_t>(value);
  return true;
}

}  // namespace

std::array<std::uint8_t, 3> TextureSourceColour(size_t image_index) {
  const double usable_deg = 360.0 - (kOrangeBandHiDeg - kOrangeBandLoDeg);
  // The turn of photo i, exact in the index (no accumulated steps), from photo 1's hue.
  const double turn = std::fmod(static_cast<double>(image_index) * kGoldenStep, 1.0);
  const double along = std::fmod(kFirstHueDeg - kOrangeBandHiDeg + turn * usable_deg, usable_deg);
  return FromHsv(kOrangeBandHiDeg + along, kSaturation, kValues[image_index % 2]);
}

std::string PhotoLabel(const Project& project, size_t image_index) {
  std::string text = "photo " + std::to_string(image_index + 1);
  if (image_index < project.images.size()) {
    const std::string name = std::filesystem::path(project.images[image_index].path).filename().string();
    if (!name.empty()) text += " (" + name + ")";
  }
  return text;
}

const FaceTextureReport* BakedFaceSources(const AppState& state, Id primitive_id, FaceId face) {
  for (const FaceTextureReport& report : state.last_bake.faces) {
    if (report.primitive_id == primitive_id && report.face == face) return &report;
  }
  return nullptr;
}

std::vector<TextureLegendRow> TextureLegend(const AppState& state) {
  const Project& project = state.document.project();
  std::map<Id, int> dominant;
  for (const FaceTextureReport& report : state.last_bake.faces) {
    if (!report.sources.empty()) ++dominant[report.sources.front().image_id];
  }
  std::vector<TextureLegendRow> rows;
  for (size_t i = 0; i < project.images.size(); ++i) {
    const Image& image = project.images[i];
    const auto it = dominant.find(image.id);
    if (it == dominant.end() && image.use_for_texture) continue;
    TextureLegendRow row;
    row.image_index = i;
    row.colour = TextureSourceColour(i);
    row.label = PhotoLabel(project, i);
    row.faces = it == dominant.end() ? 0 : it->second;
    row.used = image.use_for_texture;
    rows.push_back(std::move(row));
  }
  return rows;
}

bool SetFaceTextureSourceEdit(AppState* state, Id primitive_id, FaceId face, Id image_id) {
  Project edited = state->document.project();
  Primitive* primitive = FaceOwner(state, &edited, primitive_id, face, "Texture from");
  if (primitive == nullptr) return false;
  if (image_id != kNoId && edited.FindImage(image_id) == nullptr) {
    return Refuse(state, "Texture from: no image " + std::to_string(image_id));
  }
  const FaceTextureOverride* current = FindFaceTextureOverride(*primitive, face);
  FaceTextureOverride entry = current != nullptr ? *current : FaceTextureOverride{};
  entry.face = face;
  entry.source_image = image_id;
  std::erase(entry.excluded_images, image_id);  // a forced photo is admitted
  const std::string label =
      "Texture " + FaceText(*primitive, face) + " from " +
      (image_id == kNoId ? std::string("auto") : PhotoLabel(edited, ImageIndex(edited, image_id)));
  SetFaceTextureOverride(primitive, std::move(entry));
  return CommitTextureChoice(state, label, edited);
}

bool SetFaceTextureExcludedEdit(AppState* state, Id primitive_id, FaceId face, Id image_id, bool excluded) {
  Project edited = state->document.project();
  Primitive* primitive = FaceOwner(state, &edited, primitive_id, face, "Exclude photo");
  if (primitive == nullptr) return false;
  if (edited.FindImage(image_id) == nullptr)
    return Refuse(state, "Exclude photo: no image " + std::to_string(image_id));
  const FaceTextureOverride* current = FindFaceTextureOverride(*primitive, face);
  FaceTextureOverride entry = current != nullptr ? *current : FaceTextureOverride{};
  entry.face = face;
  std::erase(entry.excluded_images, image_id);
  if (excluded) {
    entry.excluded_images.push_back(image_id);
    if (entry.source_image == image_id) entry.source_image = kNoId;  // excluding the forced photo: automatic
  }
  const std::string label = std::string(excluded ? "Exclude " : "Admit ") +
                            PhotoLabel(edited, ImageIndex(edited, image_id)) + (excluded ? " from " : " for ") +
                            FaceText(*primitive, face);
  SetFaceTextureOverride(primitive, std::move(entry));
  return CommitTextureChoice(state, label, edited);
}

bool SetPhotoUsedForTextureEdit(AppState* state, Id image_id, bool used) {
  Project edited = state->document.project();
  Image* image = edited.FindImage(image_id);
  if (image == nullptr) return Refuse(state, "Use for texture: no image " + std::to_string(image_id));
  image->use_for_texture = used;
  const std::string label =
      std::string(used ? "Use " : "Do not use ") + PhotoLabel(edited, ImageIndex(edited, image_id)) + " for texture";
  return CommitTextureChoice(state, label, edited);
}

bool MeshForExport(AppState* state, TexturedMesh* mesh, std::string* message) {
  FinishBake(state);
  if (!(state->texture.export_texels_per_unit > 0.0)) {
    *mesh = state->mesh;
    return true;
  }
  const Project& project = state->document.project();
  std::vector<const ImageRgba8*> photos;
  for (const Image& image : project.images) {
    const auto it = state->photos.find(image.id);
    photos.push_back(it == state->photos.end() || it->second.empty() ? nullptr : &it->second);
  }
  TextureBakeOptions options;
  options.texels_per_unit = state->texture.export_texels_per_unit;
  options.max_atlas_pages = kExportAtlasPages;
  const TextureBakeSummary summary = BakeTexturedMesh(project, photos, options, mesh);
  *message = summary.message;
  return summary.IsUsable();
}

bool RunTextureCommand(AppState* state, const std::string& arg, std::string* error) {
  std::vector<std::string> w;
  std::istringstream in(arg);
  for (std::string word; in >> word;) w.push_back(word);
  const Project& project = state->document.project();
  const size_t image_count = project.images.size();
  auto on_off = [&](const std::string& word, bool* on) {
    if (word != "on" && word != "off") return false;
    *on = word == "on";
    return true;
  };
  // A refusal logs an error; an edit that changes nothing (the choice is already so) is fine.
  const size_t log_before = state->log.size();
  auto done = [&](bool edited) {
    if (edited) return true;
    for (size_t i = std::min(log_before, state->log.size()); i < state->log.size(); ++i) {
      if (state->log[i].level == LogLevel::kError) {
        *error = "texture: " + state->log[i].text;
        return false;
      }
    }
    return true;
  };
  const ElementRef face = state->selection.element;
  const bool face_selected = face.kind == ElementKind::kFace && ElementExists(project, face);
  size_t index = 0;
  bool on = false;
  if (w.size() == 2 && w[0] == "source") {
    if (!face_selected) {
      *error = "texture source: select a face first";
      return false;
    }
    if (w[1] == "auto") return done(SetFaceTextureSourceEdit(state, face.primitive_id, face.element, kNoId));
    if (!ParseIndex(w[1], image_count, &index)) {
      *error = "texture source: expected auto or an image index below " + std::to_string(image_count);
      return false;
    }
    return done(SetFaceTextureSourceEdit(state, face.primitive_id, face.element, project.images[index].id));
  }
  if (w.size() == 3 && (w[0] == "exclude" || w[0] == "use")) {
    if (!ParseIndex(w[1], image_count, &index) || !on_off(w[2], &on)) {
      *error = "texture " + w[0] + ": expected IMAGE_INDEX (below " + std::to_string(image_count) + ") on|off";
      return false;
    }
    const Id image_id = project.images[index].id;
    if (w[0] == "use") return done(SetPhotoUsedForTextureEdit(state, image_id, on));
    if (!face_selected) {
      *error = "texture exclude: select a face first";
      return false;
    }
    return done(SetFaceTextureExcludedEdit(state, face.primitive_id, face.element, image_id, on));
  }
  if (w.size() == 2 && w[0] == "sources" && on_off(w[1], &on)) {
    state->texture.show_sources = on;
    return true;
  }
  if (w.size() == 2 && w[0] == "export-resolution") {
    char* end = nullptr;
    const double value = std::strtod(w[1].c_str(), &end);
    if (*end != '\0' || !std::isfinite(value) || value < 0.0) {
      *error = "texture export-resolution: expected texels per project unit >= 0 (0: from the photos)";
      return false;
    }
    state->texture.export_texels_per_unit = value;
    return true;
  }
  *error =
      "texture: expected 'source auto|IMAGE_INDEX', 'exclude IMAGE_INDEX on|off', 'use IMAGE_INDEX on|off', "
      "'sources on|off' or 'export-resolution N'";
  return false;
}

}  // namespace facet::app
