#include "app/state/ghost_pins.h"

#include <algorithm>
#include <cstdlib>

#include "app/state/app_state.h"
#include "app/state/model_edits.h"

namespace facet::app {
namespace {

const GrayImage* GrayPhoto(AppState* state, Id image_id) {
  const auto photo = state->photos.find(image_id);
  if (photo == state->photos.end() || photo->second.empty()) return nullptr;
  GhostPinsState::Gray& gray = state->ghost_pins.grays[image_id];
  if (gray.pixels != photo->second.pixels.data() || gray.image.empty()) {
    const int side = std::max(photo->second.width, photo->second.height);
    const int shrink = std::max(1, (side + kGhostPinsMaxSidePx - 1) / kGhostPinsMaxSidePx);
    gray.image = GrayFromRgba(photo->second, shrink);
    gray.pixels = photo->second.pixels.data();
  }
  return &gray.image;
}

std::uint64_t PhotosKey(const AppState& state) {
  std::uint64_t key = 1469598103934665603ull;
  for (const auto& [id, photo] : state.photos) {
    key = (key ^ id) * 1099511628211ull;
    key = (key ^ reinterpret_cast<std::uintptr_t>(photo.pixels.data())) * 1099511628211ull;
  }
  return key;
}

bool Refuse(AppState* state, const std::string& message) {
  state->Log(LogLevel::kError, "Accept proposed pins: " + message);
  return false;
}

}  // namespace

int ProposedGhostPins(const PinProposalSummary& summary) {
  return static_cast<int>(std::count_if(summary.proposals.begin(), summary.proposals.end(),
                                        [](const PinProposal& p) { return p.Proposed(); }));
}

// Whether a pin in another calibrated image could be proposed here (else nothing is computed,
// not even the grey photos).
bool PinnedElsewhere(const Project& project, Id image_id) {
  for (const Pin& pin : project.pins) {
    const Image* image = project.FindImage(pin.image_id);
    if (pin.image_id != image_id && image != nullptr && image->camera_calibrated) return true;
  }
  return false;
}

const PinProposalSummary* GhostPinsFor(AppState* state, Id image_id) {
  if (state->drag_start) return nullptr;
  const Image* image = state->document.project().FindImage(image_id);
  if (image == nullptr || !image->camera_calibrated || !PinnedElsewhere(state->document.project(), image_id))
    return nullptr;
  GhostPinsState& ghosts = state->ghost_pins;
  const std::uint64_t photos_key = PhotosKey(*state);
  if (!ghosts.computed || ghosts.revision != state->document.revision() || ghosts.epoch != state->document.epoch() ||
      ghosts.image_id != image_id || ghosts.photos_key != photos_key) {
    for (auto it = ghosts.grays.begin(); it != ghosts.grays.end();) {  // photos gone or replaced
      const auto photo = state->photos.find(it->first);
      it = photo == state->photos.end() || photo->second.pixels.data() != it->second.pixels ? ghosts.grays.erase(it)
                                                                                            : std::next(it);
    }
    ghosts.summary = ProposePins(state->document.project(), image_id, [state](Id id) { return GrayPhoto(state, id); });
    ghosts.computed = true;
    ghosts.revision = state->document.revision();
    ghosts.epoch = state->document.epoch();
    ghosts.image_id = image_id;
    ghosts.photos_key = photos_key;
    ++ghosts.computations;
  }
  return ghosts.summary.IsUsable() ? &ghosts.summary : nullptr;
}

bool AcceptGhostPinsEdit(AppState* state, Id image_id) {
  const PinProposalSummary* summary = GhostPinsFor(state, image_id);
  if (summary == nullptr || ProposedGhostPins(*summary) == 0) return Refuse(state, "no pin is proposed in this photo");
  Project edited = state->document.project();
  int pinned = 0;
  for (const PinProposal& p : summary->proposals) {
    if (!p.Proposed()) continue;
    PinVertex(&edited, image_id, p.vertex, p.match.uv_px);
    ++pinned;
  }
  const std::string label = "Accept " + std::to_string(pinned) + " proposed pin" + (pinned == 1 ? "" : "s");
  state->Log(LogLevel::kInfo, label + " in " + std::to_string(image_id));
  CommitEdit(state, label, std::move(edited));
  return true;
}

bool AcceptGhostPinEdit(AppState* state, Id image_id, size_t index) {
  const PinProposalSummary* summary = GhostPinsFor(state, image_id);
  if (summary == nullptr || index >= summary->proposals.size() || !summary->proposals[index].Proposed())
    return Refuse(state, "no such proposed pin");
  const PinProposal proposal = summary->proposals[index];
  Project edited = state->document.project();
  const Id pin_id = PinVertex(&edited, image_id, proposal.vertex, proposal.match.uv_px);
  state->selection = Selection();
  state->selection.pin_id = pin_id;
  CommitEdit(state, "Accept proposed pin", std::move(edited));
  return true;
}

bool RunPinProposalsCommand(AppState* state, const std::string& arg, std::string* error) {
  const Id image_id = state->active_image_id;
  bool done = false;
  if (arg == "accept") {
    done = AcceptGhostPinsEdit(state, image_id);
  } else if (arg.rfind("accept ", 0) == 0) {
    char* end = nullptr;
    const long nth = std::strtol(arg.c_str() + 7, &end, 10);
    const PinProposalSummary* summary = GhostPinsFor(state, image_id);
    if (*end != '\0' || nth < 0 || summary == nullptr) {
      *error = "pin-proposals: expected 'accept' or 'accept I' (I from 0)";
      return false;
    }
    long seen = -1;
    for (size_t k = 0; k < summary->proposals.size(); ++k) {
      if (summary->proposals[k].Proposed() && ++seen == nth) {
        done = AcceptGhostPinEdit(state, image_id, k);
        break;
      }
    }
    if (seen < nth) {
      *error = "pin-proposals: only " + std::to_string(seen + 1) + " pins are proposed";
      return false;
    }
  } else {
    *error = "pin-proposals: expected 'accept' or 'accept I' (I from 0)";
    return false;
  }
  if (!done) *error = state->log.empty() ? "refused" : state->log.back().text;
  return done;
}

}  // namespace facet::app
