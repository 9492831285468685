// The input script's `drop` command (app/state/input_script.h): words or double-quoted paths
// become one step's dropped files; an empty or unclosed drop is refused with its line.
#include <doctest/doctest.h>

#include <string>
#include <vector>

#include "app/state/input_script.h"

using facet::app::ParseScript;
using facet::app::Script;

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
