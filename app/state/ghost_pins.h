// Ghost pins (issue 26): the pins core/solve/pin_proposals.h proposes in the photo shown, for
// the vertices pinned in other calibrated photos. They are view state, not the project's: the
// image panel draws them hollow with their score, computes them when a calibrated photo is
// shown and again only when the document or the loaded photos change (cached by the
// document's revision, the image and the photos), and turns them into pins on request: all of
// them as ONE undoable edit, or one by one, through PinVertex as the Pin tool does.
#pragma once

#include <cstdint>
#include <map>
#include <string>

#include "core/image/gray_image.h"
#include "core/solve/pin_proposals.h"

namespace facet::app {

struct AppState;

// The photos are matched in grey at a working resolution: at most this many px on the long side.
constexpr int kGhostPinsMaxSidePx = 2048;

struct GhostPinsState {
  // What the proposals were computed for, and them.
  bool computed = false;
  std::uint64_t revision = 0;
  std::uint64_t epoch = 0;  // the document's: another project may reach the same revision
  Id image_id = kNoId;
  std::uint64_t photos_key = 0;
  PinProposalSummary summary;
  int computations = 0;  // how often they were computed (the report: not every frame)
  // Grey photos by image id, with the RGBA pixels they were made from.
  struct Gray {
    const std::uint8_t* pixels = nullptr;
    GrayImage image;
  };
  std::map<Id, Gray> grays;
};

// The proposals in image `image_id`, computed now when the document, the image or the loaded
// photos changed since the last call; null when there are none to show (the image is not
// calibrated, its photo not loaded, a drag is previewing).
const PinProposalSummary* GhostPinsFor(AppState* state, Id image_id);
// How many of them are proposed (not refused).
int ProposedGhostPins(const PinProposalSummary& summary);
// Pins every proposed ghost of the image as ONE undoable edit, "Accept N proposed pins", with the
// re-solve. False (logged) when there is none.
bool AcceptGhostPinsEdit(AppState* state, Id image_id);
// Pins one: proposal `index` of the summary (proposed ones only), "Accept proposed pin".
bool AcceptGhostPinEdit(AppState* state, Id image_id, size_t index);

// The script command `pin-proposals ARGS` on the active image: `accept` (all), `accept I`
// (the I-th proposed, from 0, in the report's order).
bool RunPinProposalsCommand(AppState* state, const std::string& arg, std::string* error);

}  // namespace facet::app
