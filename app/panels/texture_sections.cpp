#include "app/panels/texture_sections.h"

#include <algorithm>
#include <cstdio>
#include <string>

#include "app/panels/widgets.h"
#include "app/state/texture_choices.h"

namespace facet::app {
namespace {

ImU32 ToImColour(const std::array<std::uint8_t, 3>& c, std::uint8_t alpha = 255) {
  return IM_COL32(c[0], c[1], c[2], alpha);
}

// A small filled square in the photo's colour, inline with the text that follows.
void Swatch(size_t image_index) {
  const float side = ImGui::GetTextLineHeight();
  const ImVec2 p = ImGui::GetCursorScreenPos();
  const float y = p.y + 0.5f * (ImGui::GetFrameHeight() - side);
  ImGui::GetWindowDrawList()->AddRectFilled(ImVec2(p.x, y), ImVec2(p.x + side, y + side),
                                            ToImColour(TextureSourceColour(image_index)));
  ImGui::Dummy(ImVec2(side, ImGui::GetFrameHeight()));
  ImGui::SameLine();
}

}  // namespace

void DrawFaceTextureSection(AppState* state, const Primitive& primitive, FaceId face) {
  const Project& project = state->document.project();
  if (project.images.empty()) return;
  if (!ImGui::CollapsingHeader("Face texture", ImGuiTreeNodeFlags_DefaultOpen)) return;
  ImGui::PushID("face_texture");
  // Copies: the edits below replace the project these would point into.
  const FaceTextureOverride* found = FindFaceTextureOverride(primitive, face);
  const FaceTextureOverride current = found != nullptr ? *found : FaceTextureOverride{};
  const std::vector<Image> images = project.images;
  auto index_of = [&](Id id) {
    for (size_t i = 0; i < images.size(); ++i) {
      if (images[i].id == id) return static_cast<int>(i);
    }
    return -1;
  };

  // What the last bake did with this face.
  if (const FaceTextureReport* report = BakedFaceSources(*state, primitive.id, face)) {
    if (report->sources.empty()) {
      LabelValue("Textured by", "no photo");
    } else {
      ImGui::TextColored(kDimText, "Textured by");
      for (const TextureSourceShare& s : report->sources) {
        const int i = index_of(s.image_id);
        if (i < 0) continue;
        ImGui::Indent(8.0f);
        Swatch(static_cast<size_t>(i));
        ImGui::Text("%s  %.0f %%", PhotoLabel(project, static_cast<size_t>(i)).c_str(), 100.0 * s.share);
        ImGui::Unindent(8.0f);
      }
      LabelValue("Texels", "%d x %d", report->width_texels, report->height_texels);
    }
    if (report->forced_unavailable) {
      WrappedColored(kWarningText,
                     "The chosen photo cannot texture this face (not calibrated, excluded or not "
                     "facing it): chosen automatically.");
    } else if (report->forced_fallback_texels > 0) {
      WrappedColored(kWarningText, std::to_string(report->forced_fallback_texels) +
                                       " texels the chosen photo does not see come from the next view.");
    }
  }

  // The forced source.
  const int forced = current.source_image == kNoId ? -1 : index_of(current.source_image);
  const std::string preview = forced < 0 ? std::string("auto") : PhotoLabel(project, static_cast<size_t>(forced));
  ImGui::AlignTextToFramePadding();
  ImGui::TextColored(kDimText, "Texture from");
  ImGui::SameLine();
  ImGui::SetNextItemWidth(-FLT_MIN);
  const bool open = ImGui::BeginCombo("##source", preview.c_str());
  RecordItem(state, "texture.source");
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("auto: the photos that see the face, blended; a photo: that photo alone where it sees the face");
  Id chosen = current.source_image;
  bool choose = false;
  if (open) {
    if (ImGui::Selectable("auto", forced < 0)) chosen = kNoId, choose = true;
    RecordItem(state, "texture.source/auto");
    for (size_t i = 0; i < images.size(); ++i) {
      const bool usable = images[i].camera_calibrated && images[i].use_for_texture;
      ImGui::BeginDisabled(!usable);
      if (ImGui::Selectable(PhotoLabel(project, i).c_str(), static_cast<int>(i) == forced)) {
        chosen = images[i].id;
        choose = true;
      }
      ImGui::EndDisabled();
      RecordItem(state, "texture.source/" + std::to_string(i));
    }
    ImGui::EndCombo();
  }
  if (choose && chosen != current.source_image) SetFaceTextureSourceEdit(state, primitive.id, face, chosen);

  // Per-photo exclusions for this face.
  for (size_t i = 0; i < images.size(); ++i) {
    const Id id = images[i].id;
    bool excluded = std::binary_search(current.excluded_images.begin(), current.excluded_images.end(), id);
    ImGui::PushID(static_cast<int>(i));
    Swatch(i);
    const std::string label = "Exclude " + PhotoLabel(project, i);
    if (ImGui::Checkbox(label.c_str(), &excluded)) SetFaceTextureExcludedEdit(state, primitive.id, face, id, excluded);
    RecordItem(state, "texture.exclude." + std::to_string(i));
    if (ImGui::IsItemHovered())
      ImGui::SetTooltip("This photo gives this face no colour (e.g. something stands in front of it there)");
    ImGui::PopID();
  }
  ImGui::PopID();
}

void DrawPhotoTextureOption(AppState* state, const Image& image) {
  const Project& project = state->document.project();
  size_t index = 0;
  while (index < project.images.size() && project.images[index].id != image.id) ++index;
  bool used = image.use_for_texture;
  Swatch(index);
  if (ImGui::Checkbox("Use for texture", &used)) SetPhotoUsedForTextureEdit(state, image.id, used);
  RecordItem(state, "texture.use_photo");
  if (ImGui::IsItemHovered())
    ImGui::SetTooltip("Off: this photo still calibrates and pins, but textures no face (e.g. a passer-by in it)");
}

void DrawTextureSourceLegend(ImDrawList* draw, const AppState& state, ImVec2 origin, ImVec2 size) {
  const std::vector<TextureLegendRow> rows = TextureLegend(state);
  const float line = ImGui::GetTextLineHeightWithSpacing();
  const float swatch = ImGui::GetTextLineHeight();
  const float pad = 6.0f;
  std::vector<std::string> texts;
  float text_w = ImGui::CalcTextSize("Texture sources").x;
  for (const TextureLegendRow& row : rows) {
    char buffer[256];
    if (row.used) {
      std::snprintf(buffer, sizeof(buffer), "%s: %d face%s", row.label.c_str(), row.faces, row.faces == 1 ? "" : "s");
    } else {
      std::snprintf(buffer, sizeof(buffer), "%s: not used for texture", row.label.c_str());
    }
    texts.emplace_back(buffer);
  }
  texts.emplace_back(rows.empty() && state.last_bake.faces_textured == 0 ? "no face textured" : "untextured");
  for (const std::string& t : texts) text_w = std::max(text_w, swatch + pad + ImGui::CalcTextSize(t.c_str()).x);
  const float w = text_w + 2 * pad;
  const float h = line * (1 + static_cast<float>(texts.size())) + 2 * pad;
  const ImVec2 top_left(origin.x + size.x - w - pad, origin.y + pad);
  draw->AddRectFilled(top_left, ImVec2(top_left.x + w, top_left.y + h), IM_COL32(20, 22, 26, 215), 4.0f);
  float y = top_left.y + pad;
  draw->AddText(ImVec2(top_left.x + pad, y), IM_COL32(235, 235, 235, 255), "Texture sources");
  y += line;
  for (size_t k = 0; k < texts.size(); ++k) {
    const bool photo = k < rows.size();
    const ImU32 colour = photo ? ToImColour(rows[k].colour, rows[k].used ? 255 : 90) : IM_COL32(179, 181, 184, 255);
    draw->AddRectFilled(ImVec2(top_left.x + pad, y + 1), ImVec2(top_left.x + pad + swatch, y + 1 + swatch), colour);
    if (photo && !rows[k].used) {
      draw->AddLine(ImVec2(top_left.x + pad, y + 1), ImVec2(top_left.x + pad + swatch, y + 1 + swatch),
                    IM_COL32(235, 235, 235, 255), 1.5f);
    }
    draw->AddText(ImVec2(top_left.x + 2 * pad + swatch, y), IM_COL32(235, 235, 235, 255), texts[k].c_str());
    y += line;
  }
}

}  // namespace facet::app
