// The input-script driver of the offscreen mode: a small text format, one command per line,
// '#' starts a comment. Parsing expands every command into frame steps; each step's input
// is applied at the start of one frame, so ImGui sees every press and release.
//
//   frames N                      N frames with no new input
//   move POINT                    mouse position
//   down|up left|right|middle     press / release a button
//   click BUTTON POINT            move and press (1 frame), release (1 frame)
//   drag BUTTON POINT1 POINT2 STEPS  press at 1, move in STEPS frames to 2, release
//   wheel DY [POINT]              vertical wheel (positive: away from the user), optional move
//                                 A POINT is `X Y` (screen px), `image U V` (pixel (U, V) of
//                                 the photo shown in the image panel), `vertex P V` (where
//                                 vertex V of the P-th primitive, 0 the first added, is drawn
//                                 over that photo: a corner the user grabs; V is the mesh's
//                                 vertex id: a box's corners 0-7 (bit 0 x, bit 1 y, bit 2 z),
//                                 and a vertex Split edge adds takes the next id, never
//                                 reused: 8, 9, ... on a box) or `item NAME`
//                                 (the centre of the widget the UI recorded as NAME, e.g.
//                                 image.accept_lines: the report's "items"). Image, vertex and
//                                 item points are mapped through what the frame before showed,
//                                 so a script stays valid when the layout or the model moves.
//                                 A drag's second point takes the first one's space unless it
//                                 names its own (drag left image U1 V1 U2 V2 8; drag left
//                                 vertex 0 4 image U V 8); its start is fixed when it begins.
//   key [ctrl+][shift+][alt+]KEY  press (1 frame), release (1 frame); e.g. key ctrl+z
//   tap [ctrl+][shift+][alt+]KEY  press and release delivered within one frame (a short key
//                                 press during a slow frame); the app still sees both
//   double-click BUTTON POINT     move, press, release, press, release, all delivered within
//                                 one frame
//   up-then-move BUTTON POINT     release the button, then move to POINT, both within one
//                                 frame: the release counts where it happened
//   type TEXT                     text characters for the active text field (1 frame)
//   hold|release shift|ctrl|alt   keep a modifier down / let it go
//   command NAME [ARGS]           new, undo, redo, save PATH, open PATH, tool NAME,
//                                 select-image INDEX, fit, export PATH, and for the model:
//                                   add KIND [on-top]  K_create (box, wedge, prism, pyramid,
//                                                      cylinder, plane), on the selected box;
//                                   add KIND at U V    standing on the ground under image px
//                                                      (U, V) of the active image
//                                   select vertex|edge|face PRIMITIVE ELEMENT_ID,
//                                   select primitive PRIMITIVE, select none
//                                                      PRIMITIVE: its id, @N (the N-th
//                                                      primitive, from 1, in the order made)
//                                                      or last; @N and last do not change
//                                                      with how many lines or pins came
//                                                      before (ResolvePrimitiveToken)
//                                   ridge x|y          the selected wedge's ridge direction
//                                                      (SetWedgeRidgeEdit)
//                                   free-vertex        toggle the selected vertex's freedom
//                                   planar-face        toggle the selected face's coplanarity
//                                   constrain KIND [VALUE]  a spatial constraint on the
//                                                      selection: along-x|y|z, length VALUE
//                                                      (edge); parallel, perpendicular,
//                                                      equal-length (first call stores the
//                                                      edge, second adds; with two edges
//                                                      selected, at once); coplanar (4+
//                                                      vertices or two faces), collinear
//                                                      (3+ vertices), parallel-faces;
//                                                      fix (vertex); remove ID. Dispatched by
//                                                      RunConstrainCommand (app/state/model_edits.h)
//                                   add-photo PATH     a new image (app/state/add_photo.h)
//                                   relink-photo PATH  the active image's photo file (RelinkPhotoEdit)
//                                   reference add|add-z-up PATH, reference remove|show|hide INDEX
//                                                      reference geometry (.obj, .glb, .gltf), one
//                                                      undoable edit each (app/state/reference_edits.h)
//                                   select-add vertex|edge|face PRIMITIVE ELEMENT_ID
//                                                      add to the selection (RunSelectAddCommand)
//                                   line-pin IMAGE_INDEX X1 Y1 X2 Y2  the selected edge on the
//                                                      image line through (X1, Y1), (X2, Y2)
//                                                      (RunLinePinCommand, app/state/model_edits.h)
//                                   line-pin-move IMAGE_INDEX PIN_INDEX END X Y  one end (0|a,
//                                                      1|b) of the image's PIN_INDEX-th line
//                                                      pin to (X, Y) (RunLinePinMoveCommand)
//                                   calibration KEY VALUE  the active image's calibration
//                                                      modes, each one undoable edit
//                                                      (RunCalibrationCommand,
//                                                      app/panels/camera_sections.h):
//                                                      principal-point solve|center|
//                                                      fixed X Y; focal solve|fixed F|
//                                                      prior F STD|exif (px); horizon
//                                                      off|level V|X1 Y1 X2 Y2 (px);
//                                                      distortion on|off (estimate from
//                                                      lines); distortion-lock,
//                                                      focal-lock, principal-point-lock
//                                                      on|off (what the joint solve keeps);
//                                                      lens-group N (photos of one group
//                                                      > 0 share f, c, k; 0: own lens)
//                                   move-selection ARGS  V_op on the selected vertex or
//                                                      primitive (RunMoveCommand,
//                                                      app/state/move_tool.h)
//                                   lines ARGS         detected line proposals: detect
//                                                      [IMAGE_INDEX], wait, remove I,
//                                                      assign I x|y|z, select I, accept,
//                                                      discard, on-add on|off, hold on|off
//                                                      (RunLinesCommand,
//                                                      app/state/line_proposals.h)
//                                   colmap ARGS        File > Cameras from all photos
//                                                      (RunColmapCommand,
//                                                      app/state/colmap_cameras.h): start,
//                                                      cancel, wait (for the run in
//                                                      flight, then apply it), wait-stage
//                                                      STAGE (tests), open|close
//                                                      (its window), single-camera on|off
//                                   pin-proposals accept [I]  the ghost pins of the active
//                                                      image: all as one edit, or the I-th
//                                                      proposed (app/state/ghost_pins.h)
//                                   wait-bake          block until the texture bake of the
//                                                      current project is swapped in
//                                   bake-status PATH   the background bake's state as JSON
//                                                      (in flight, revisions, counters,
//                                                      main-thread ms, mesh fingerprints)
//                                   recover restore|discard  the answer to the offered
//                                                      recovery file (app/state/autosave.h)
//                                   wait-autosave      block until the recovery file holds
//                                                      the document as it is now (render
//                                                      --autosave)
//                                   advance-clock S    the offscreen clock jumps S seconds
//                                                      ahead (what the autosave's 30 s
//                                                      timers read), without S s of frames
//                                   wait-removed PATH  block (at most 120 s) until PATH
//                                                      no longer exists: a test outside
//                                                      removes what made a write fail
//                                   teach NAME on|off  View > Teach's overlays: vanishing,
//                                                      epipolar, numbers, state, steps
//                                                      (app/state/teach.h); teach
//                                                      second-image INDEX: F's second photo;
//                                                      teach step, teach reset: the Solver
//                                                      steps window's buttons; teach start
//                                                      perturbed|as-is, teach perturbation
//                                                      AMOUNT (0.2 = 20 %): where it starts;
//                                                      teach residual-scale S: the vectors
//                                                      drawn S times as long; teach subject
//                                                      joint|vanishing|two-view: what the
//                                                      window steps
//                                   texture ARGS       the user's texture choices
//                                                      (RunTextureCommand,
//                                                      app/state/texture_choices.h): source
//                                                      auto|IMAGE_INDEX and exclude
//                                                      IMAGE_INDEX on|off on the selected
//                                                      face; use IMAGE_INDEX on|off (a
//                                                      photo's Use for texture); sources
//                                                      on|off (View > Texture sources);
//                                                      export-resolution N (texels per
//                                                      project unit of File > Export, 0:
//                                                      from the photos)
//                                   export-view image|3d WxH PATH  File > Export view: the
//                                                      panel alone, its canvas W x H px, as
//                                                      a PNG (after this step's frame;
//                                                      app/shell/export_view.h)
//                                   export-colmap PATH  File > Export cameras (COLMAP): the
//                                                      model into folder PATH (or PATH's
//                                                      folder when it names cameras.txt)
//                                   export-transforms PATH  File > Export cameras
//                                                      (transforms.json)
//                                 Tool names: select, line-x, line-y, line-z, pin,
//                                 add-primitive (adds at once), split-edge, delete-vertex,
//                                 connect-vertices, delete-edge, push-pull, move, line-pin,
//                                 measure (click two vertices, type the length, Enter)
//   drop PATH [PATH...]           files dropped onto the window, as from the desktop (the
//                                 same handler: app/shell/file_actions.h); a path with
//                                 spaces goes in double quotes
//   screenshot PATH               write a PNG of the frame just rendered; that frame first
//                                 waits for the texture bake (wait-bake), so the picture never
//                                 depends on how fast the worker thread was
// A line detection in flight (the Detect lines button, the Add photo option) is waited for
// before every step that presses a button or key, types, drops or takes a screenshot, and at
// the end of the script; the `frames` and `move` steps between go on while it runs.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

namespace facet::app {

// Key codes are GLFW's (letters are their upper-case ASCII codes) in both modes, so panels
// can test io.KeysDown the same way with and without a window.
struct ScriptKey {
  int key_code = 0;
  bool ctrl = false, shift = false, alt = false;
  unsigned character = 0;  // text input sent along with the key (0: none)
};

// Platform events a step delivers within its one frame, in this order; the input queue
// (app/state/input_queue.h) hands them to the UI over as many frames as it needs.
enum class Burst {
  kNone,
  kTap,             // key_press goes down and up
  kDoubleClick,     // mouse_pos, then burst_button down, up, down, up
  kReleaseThenMove  // burst_button up, then mouse_pos
};

// What a step's mouse position is measured in (see POINT above).
enum class PointSpace { kScreen, kImage, kVertex, kItem };

struct ScriptStep {
  int line = 0;  // source line, for error messages
  std::optional<std::array<float, 2>> mouse_pos;
  PointSpace mouse_space = PointSpace::kScreen;
  std::string mouse_item;                  // PointSpace::kItem: the widget's recorded name
  std::array<int, 2> mouse_vertex{0, 0};   // PointSpace::kVertex: primitive index, vertex id
  // A drag: its first step is the anchor (its screen position is kept); each later step moves
  // to anchor + fraction * (mouse_pos - anchor), so a model that moves under the drag does not
  // move its start.
  bool drag_anchor = false;
  std::optional<float> drag_fraction;
  std::array<std::optional<bool>, 3> mouse_down;  // left, right, middle: press / release
  float wheel = 0.0f;
  std::optional<ScriptKey> key_press;  // held during this step only
  Burst burst = Burst::kNone;
  int burst_button = 0;  // kDoubleClick, kReleaseThenMove: 0 left, 1 right, 2 middle
  std::string text;      // characters typed this step
  std::optional<bool> hold_shift, hold_ctrl, hold_alt;
  std::string command;  // app command name; empty for none
  std::vector<std::string> command_args;
  std::vector<std::string> dropped_paths;  // `drop`: handed to the frame as a window drop
  std::string screenshot_path;             // written after this step's frame is rendered
};

struct Script {
  std::vector<ScriptStep> steps;
  // What a user does by hand to perform the script: clicks, drags, key presses, typed texts,
  // wheel turns, drops, button presses (down) and app commands (each a menu entry or a
  // field); hovering (move), waiting (frames), releases and screenshots do not count.
  int ui_events = 0;
};

// The most frame steps a script may expand to: 100,000 frames is half an hour of the offscreen
// loop. Each line is bounded (frames 100000, drag 10000 steps); without a bound on the whole,
// an 8 KB script of `frames 100000` lines asked for gigabytes (found by tests/fuzz).
constexpr size_t kMaxScriptSteps = 100000;

// Returns false with "line N: what is wrong" in *error for unknown commands or bad arguments,
// and for a script longer than kMaxScriptSteps.
bool ParseScript(const std::string& text, Script* script, std::string* error);
bool LoadScript(const std::string& path, Script* script, std::string* error);

// The GLFW key code for a key name ("a".."z", "0".."9", "delete", "escape", "f1", ...), or
// -1 for an unknown name.
int KeyCodeFromName(const std::string& name);

}  // namespace facet::app
