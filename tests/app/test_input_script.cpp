// The input script's parser (app/state/input_script.h): `drop` (words or double-quoted paths
// become one step's dropped files), the forms of a mouse point (screen, image, vertex, item),
// drags anchored at their start, and the count of UI events a script stands for.
#include <doctest/doctest.h>

#include <string>
#include <vector>

#include <Eigen/Core>

#include "app/state/input_script.h"
#include "app/state/model_edits.h"
#include "core/mesh/box.h"
#include "core/scene/project.h"

using facet::app::ParseScript;
using facet::app::PointSpace;
using facet::app::Script;
using facet::app::ScriptStep;

TEST_CASE("drop: plain and quoted paths in one step, in order") {
  Script script;
  std::string error;
  REQUIRE_MESSAGE(ParseScript("frames 1\ndrop /a/b.png \"/c d/e f.facet\" rel/x.jpg  # three\n", &script, &error),
                  error);
  REQUIRE(script.steps.size() == 2);
  CHECK(script.steps[0].dropped_paths.empty());
  CHECK(script.steps[1].dropped_paths == std::vector<std::string>{"/a/b.png", "/c d/e f.facet", "rel/x.jpg"});
  CHECK(script.steps[1].line == 2);
}

TEST_CASE("drop: nothing to drop or an unclosed quote is refused with the line") {
  Script script;
  std::string error;
  CHECK_FALSE(ParseScript("frames 1\ndrop\n", &script, &error));
  CHECK(error == "line 2: 'drop PATH [PATH...]' needs at least one path");
  CHECK_FALSE(ParseScript("drop \"/a b.png\n", &script, &error));
  CHECK(error == "line 1: 'drop': a quoted path is not closed");
}

TEST_CASE("points: screen, image, vertex and item points; a drag's end takes its start's space") {
  Script script;
  std::string error;
  REQUIRE_MESSAGE(ParseScript("click left image 10.5 20\n"
                              "click right item image.accept_lines\n"
                              "drag left vertex 1 4 image 318 258 4\n"
                              "drag left 10 20 30 40 2\n"
                              "move vertex 0 7\n",
                              &script, &error),
                  error);
  // click: hover, press, release; drag: anchor, press, one step per fraction, release.
  REQUIRE(script.steps.size() == 3 + 3 + (2 + 4 + 1) + (2 + 2 + 1) + 1);
  const ScriptStep& image_click = script.steps[0];
  CHECK(image_click.mouse_space == PointSpace::kImage);
  CHECK((*image_click.mouse_pos)[0] == 10.5f);
  CHECK((*image_click.mouse_pos)[1] == 20.0f);
  CHECK(script.steps[3].mouse_space == PointSpace::kItem);
  CHECK(script.steps[3].mouse_item == "image.accept_lines");

  const ScriptStep& anchor = script.steps[6];
  CHECK(anchor.drag_anchor);
  CHECK(anchor.mouse_space == PointSpace::kVertex);
  CHECK(anchor.mouse_vertex == std::array<int, 2>{1, 4});
  CHECK(script.steps[7].mouse_down[0] == std::optional<bool>(true));
  for (int k = 1; k <= 4; ++k) {
    const ScriptStep& m = script.steps[7 + k];
    CHECK(m.mouse_space == PointSpace::kImage);  // the end point named its own space
    CHECK((*m.mouse_pos)[0] == 318.0f);
    REQUIRE(m.drag_fraction.has_value());
    CHECK(*m.drag_fraction == doctest::Approx(k / 4.0));
  }
  CHECK(script.steps[12].mouse_down[0] == std::optional<bool>(false));

  const ScriptStep& screen_anchor = script.steps[13];
  CHECK(screen_anchor.mouse_space == PointSpace::kScreen);
  CHECK(script.steps[15].mouse_space == PointSpace::kScreen);  // no prefix: the start's space
  CHECK((*script.steps[16].mouse_pos)[1] == 40.0f);
  CHECK(script.steps.back().mouse_space == PointSpace::kVertex);
}

TEST_CASE("points: a malformed point is refused with the line and the forms a point takes") {
  Script script;
  std::string error;
  CHECK_FALSE(ParseScript("click left image 10\n", &script, &error));
  CHECK(error.find("line 1: 'click BUTTON POINT'") == 0);
  CHECK(error.find("image U V, vertex P V or item NAME") != std::string::npos);
  CHECK_FALSE(ParseScript("frames 1\ndrag left vertex 0 -1 image 1 2 3\n", &script, &error));
  CHECK(error.find("line 2: 'drag BUTTON POINT1 POINT2 STEPS'") == 0);
  CHECK_FALSE(ParseScript("move item\n", &script, &error));
  CHECK(error.find("line 1: 'move POINT'") == 0);
}

TEST_CASE("ui_events counts what a user does by hand, not waiting, hovering or test hooks") {
  Script script;
  std::string error;
  REQUIRE_MESSAGE(ParseScript("frames 5\n"
                              "move image 1 2\n"                   // hover: not an event
                              "click left item image.detect_lines\n"  // 1
                              "drag left image 1 2 3 4 5\n"        // 2
                              "key b\n"                            // 3
                              "type 12.5\n"                        // 4
                              "command add-photo /x.jpg\n"         // 5: a menu entry
                              "command wait-bake\n"                // test hook
                              "command bake-status /tmp/s.json\n"  // test hook
                              "screenshot /tmp/a.png\n"            // not an event
                              "hold shift\nclick left 1 1\nrelease shift\n",  // 6, 7
                              &script, &error),
                  error);
  CHECK(script.ui_events == 7);
}

// Fuzzing (tests/fuzz/fuzz_input_script): 580 lines of `frames 100000`, 8 KB, expanded to 58
// million steps and asked for gigabytes. The whole script is now bounded, not only each line.
TEST_CASE("regression: a short script cannot expand past kMaxScriptSteps (fuzz_input_script)") {
  std::string text;
  for (int i = 0; i < 580; ++i) text += "frames 100000\n";
  Script script;
  std::string error;
  CHECK_FALSE(ParseScript(text, &script, &error));
  CHECK(error == "line 2: the script is longer than 100000 frame steps");
  CHECK(script.steps.empty());

  // At the bound a script still parses: one line of 100000 frames.
  REQUIRE_MESSAGE(ParseScript("frames 100000\n", &script, &error), error);
  CHECK(script.steps.size() == facet::app::kMaxScriptSteps);
  // One step more, from a second line, does not.
  CHECK_FALSE(ParseScript("frames 100000\nmove 1 2\n", &script, &error));
  CHECK(error == "line 2: the script is longer than 100000 frame steps");
}

// Script names for primitives (app/state/model_edits.h, ResolvePrimitiveToken): ids count every
// object made, lines and pins included, so the same box has another id when the user drew more
// lines first; @N and last name it the same way in both.
TEST_CASE("primitives named by @N and last do not depend on how many lines came before") {
  auto make = [](int lines_before) {
    facet::Project project;
    for (int i = 0; i < lines_before; ++i) {
      facet::Segment line;
      line.id = project.NewId();
      project.segments.push_back(line);
    }
    for (int k = 0; k < 3; ++k) {
      facet::Id id = facet::kNoId;
      REQUIRE(facet::AddPrimitiveToProject(&project, facet::MakeBox(facet::kNoId, Eigen::Vector3d(1.0, 2.0, 3.0)),
                                           "box", &id, nullptr));
    }
    return project;
  };
  const facet::Project few = make(2), many = make(900);
  REQUIRE(few.primitives[1].id != many.primitives[1].id);  // what made scripts break
  std::string error;
  for (const facet::Project* project : {&few, &many}) {
    facet::Id id = facet::kNoId;
    CHECK(facet::app::ResolvePrimitiveToken(*project, "@2", &id, &error));
    CHECK(id == project->primitives[1].id);
    CHECK(facet::app::ResolvePrimitiveToken(*project, "last", &id, &error));
    CHECK(id == project->primitives[2].id);
    CHECK(facet::app::ResolvePrimitiveToken(*project, std::to_string(project->primitives[0].id), &id, &error));
    CHECK(id == project->primitives[0].id);
  }
  facet::Id id = facet::kNoId;
  CHECK_FALSE(facet::app::ResolvePrimitiveToken(few, "@4", &id, &error));
  CHECK(error == "no primitive @4 (the project has 3)");
  CHECK_FALSE(facet::app::ResolvePrimitiveToken(few, "@0", &id, &error));
  CHECK_FALSE(facet::app::ResolvePrimitiveToken(few, "1", &id, &error));  // a line's id, not a primitive's
  CHECK(error == "no primitive 1");
  CHECK_FALSE(facet::app::ResolvePrimitiveToken(few, "box", &id, &error));
  CHECK(error == "'box' is no primitive: expected its id, @N or last");
  CHECK_FALSE(facet::app::ResolvePrimitiveToken(few, "@99999999999999999999999", &id, &error));
  CHECK_FALSE(facet::app::ResolvePrimitiveToken(facet::Project(), "last", &id, &error));
  CHECK(error == "no primitive yet ('last')");
}
