#include "app/state/input_script.h"

#include "core/util/file_read.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#define GLFW_INCLUDE_NONE
#include <GLFW/glfw3.h>

namespace facet::app {
namespace {

std::string Trim(const std::string& s) {
  size_t a = 0, b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
  return s.substr(a, b - a);
}

std::vector<std::string> Split(const std::string& s) {
  std::istringstream in(s);
  std::vector<std::string> out;
  for (std::string t; in >> t;) out.push_back(t);
  return out;
}

std::string Lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

bool ParseFloat(const std::string& s, float* v) {
  const char* end = s.data() + s.size();
  auto [ptr, ec] = std::from_chars(s.data(), end, *v);
  return ec == std::errc() && ptr == end && std::isfinite(*v);
}

bool ParseInt(const std::string& s, int* v) {
  const char* end = s.data() + s.size();
  auto [ptr, ec] = std::from_chars(s.data(), end, *v);
  return ec == std::errc() && ptr == end;
}

int ButtonIndex(const std::string& name) {
  if (name == "left") return 0;
  if (name == "right") return 1;
  if (name == "middle") return 2;
  return -1;
}

// Everything after the first `words` words of the line (paths may contain spaces).
std::string Rest(const std::string& line, int words) {
  size_t i = 0;
  for (int w = 0; w < words; ++w) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
  }
  return Trim(line.substr(i));
}

// Argument counts of the app commands: {min, max}.
const std::map<std::string, std::pair<int, int>>& CommandArity() {
  static const std::map<std::string, std::pair<int, int>> arity = {
      {"undo", {0, 0}},        {"redo", {0, 0}},           {"save", {0, 1}},        {"open", {1, 1}},
      {"tool", {1, 1}},        {"select-image", {1, 1}},   {"fit", {0, 0}},         {"export", {1, 1}},
      {"add", {1, 1}},         {"select", {1, 1}},         {"free-vertex", {0, 0}}, {"planar-face", {0, 0}},
      {"constrain", {1, 1}},   {"select-add", {1, 1}},     {"line-pin", {1, 1}},    {"line-pin-move", {1, 1}},
      {"calibration", {1, 1}}, {"move-selection", {1, 1}}, {"add-photo", {1, 1}},   {"wait-bake", {0, 0}},
      {"bake-status", {1, 1}}, {"lines", {1, 1}},          {"ridge", {1, 1}},       {"relink-photo", {1, 1}},
      {"recover", {1, 1}},     {"wait-autosave", {0, 0}},  {"new", {0, 0}},         {"teach", {1, 1}},
      {"texture", {1, 1}},
      {"reference", {1, 1}},   {"add-reference", {1, 1}},
      {"export-view", {1, 1}},
      {"export-colmap", {1, 1}}, {"export-transforms", {1, 1}},
      {"advance-clock", {1, 1}}, {"wait-removed", {1, 1}},
      {"colmap", {1, 1}},
      {"pin-proposals", {1, 1}},
  };
  return arity;
}

}  // namespace

int KeyCodeFromName(const std::string& raw) {
  const std::string name = Lower(raw);
  if (name.size() == 1) {
    const char c = name[0];
    if (c >= 'a' && c <= 'z') return GLFW_KEY_A + (c - 'a');
    if (c >= '0' && c <= '9') return GLFW_KEY_0 + (c - '0');
  }
  static const std::map<std::string, int> named = {
      {"delete", GLFW_KEY_DELETE},  {"backspace", GLFW_KEY_BACKSPACE},
      {"escape", GLFW_KEY_ESCAPE},  {"esc", GLFW_KEY_ESCAPE},
      {"enter", GLFW_KEY_ENTER},    {"return", GLFW_KEY_ENTER},
      {"tab", GLFW_KEY_TAB},        {"space", GLFW_KEY_SPACE},
      {"left", GLFW_KEY_LEFT},      {"right", GLFW_KEY_RIGHT},
      {"up", GLFW_KEY_UP},          {"down", GLFW_KEY_DOWN},
      {"home", GLFW_KEY_HOME},      {"end", GLFW_KEY_END},
      {"pageup", GLFW_KEY_PAGE_UP}, {"pagedown", GLFW_KEY_PAGE_DOWN},
      {"insert", GLFW_KEY_INSERT},  {"minus", GLFW_KEY_MINUS},
      {"equal", GLFW_KEY_EQUAL},    {"plus", GLFW_KEY_EQUAL},
      {"period", GLFW_KEY_PERIOD},  {"comma", GLFW_KEY_COMMA},
  };
  if (auto it = named.find(name); it != named.end()) return it->second;
  if (name.size() >= 2 && name[0] == 'f') {
    int n = 0;
    if (ParseInt(name.substr(1), &n) && n >= 1 && n <= 12) return GLFW_KEY_F1 + n - 1;
  }
  return -1;
}

namespace {

using Steps = std::vector<ScriptStep>;

// Each Parse* below reads one script line already split into words t (t[0] the command, n
// = t.size() - 1 arguments), appends its steps (each a copy of `step`, which carries the line
// number) and returns "" or what is wrong with the line.

std::string ParseFrames(const std::vector<std::string>& t, const ScriptStep& step, Steps* steps) {
  const int n = static_cast<int>(t.size()) - 1;
  int count = 0;
  if (n != 1 || !ParseInt(t[1], &count) || count < 0 || count > 100000) {
    return "'frames N' needs a count from 0 to 100000";
  }
  for (int i = 0; i < count; ++i) steps->push_back(step);
  return "";
}

// A mouse position in a script: screen px, a photo pixel, a model vertex or a widget.
struct Point {
  PointSpace space = PointSpace::kScreen;
  std::array<float, 2> xy{0.0f, 0.0f};
  std::string item;
  std::array<int, 2> vertex{0, 0};
};

// Reads one POINT from t starting at *i: `X Y`, `image U V`, `vertex P V` or `item NAME`;
// advances *i. Without a prefix the point keeps p->space (screen, or a drag's first space).
bool ParsePoint(const std::vector<std::string>& t, size_t* i, Point* p) {
  const std::string prefix = *i < t.size() ? Lower(t[*i]) : std::string();
  if (prefix == "item") {
    if (*i + 1 >= t.size()) return false;
    p->space = PointSpace::kItem;
    p->item = t[*i + 1];
    *i += 2;
    return true;
  }
  if (prefix == "vertex") {
    if (*i + 2 >= t.size() || !ParseInt(t[*i + 1], &p->vertex[0]) || !ParseInt(t[*i + 2], &p->vertex[1]) ||
        p->vertex[0] < 0 || p->vertex[1] < 0) {
      return false;
    }
    p->space = PointSpace::kVertex;
    *i += 3;
    return true;
  }
  if (prefix == "image") {
    p->space = PointSpace::kImage;
    ++*i;
  }
  if (p->space != PointSpace::kScreen && p->space != PointSpace::kImage) return false;
  if (*i + 1 >= t.size() || !ParseFloat(t[*i], &p->xy[0]) || !ParseFloat(t[*i + 1], &p->xy[1])) return false;
  *i += 2;
  return true;
}

void SetPoint(const Point& p, ScriptStep* step) {
  step->mouse_pos = p.xy;
  step->mouse_space = p.space;
  step->mouse_item = p.item;
  step->mouse_vertex = p.vertex;
}

constexpr const char* kPointHelp = "a point is X Y, image U V, vertex P V or item NAME";

// Hover first, so the press lands on the item under the cursor; then press and release.
std::string ParseClick(const std::vector<std::string>& t, ScriptStep step, Steps* steps) {
  const int b = t.size() >= 2 ? ButtonIndex(Lower(t[1])) : -1;
  size_t i = 2;
  Point p;
  if (b < 0 || !ParsePoint(t, &i, &p) || i != t.size()) {
    return std::string("'click BUTTON POINT' needs left|right|middle and a point; ") + kPointHelp;
  }
  SetPoint(p, &step);
  steps->push_back(step);
  ScriptStep press;
  press.line = step.line;
  press.mouse_down[b] = true;
  steps->push_back(press);
  ScriptStep release;
  release.line = step.line;
  release.mouse_down[b] = false;
  steps->push_back(release);
  return "";
}

std::string ParseDrag(const std::vector<std::string>& t, ScriptStep step, Steps* steps) {
  const int b = t.size() >= 2 ? ButtonIndex(Lower(t[1])) : -1;
  size_t i = 2;
  Point from, to;
  int count = 0;
  const bool from_ok = b >= 0 && ParsePoint(t, &i, &from);
  // Without a prefix the second point is in the first one's space (a vertex start: image).
  to.space = from.space == PointSpace::kVertex ? PointSpace::kImage : from.space;
  if (!from_ok || !ParsePoint(t, &i, &to) || i + 1 != t.size() || !ParseInt(t[i], &count) || count < 1 ||
      count > 10000) {
    return std::string("'drag BUTTON POINT1 POINT2 STEPS' needs a button, two points and 1..10000 steps; ") +
           kPointHelp;
  }
  SetPoint(from, &step);
  step.drag_anchor = true;
  steps->push_back(step);
  ScriptStep press;
  press.line = step.line;
  press.mouse_down[b] = true;
  steps->push_back(press);
  for (int k = 1; k <= count; ++k) {
    ScriptStep m;
    m.line = step.line;
    SetPoint(to, &m);
    m.drag_fraction = static_cast<float>(k) / count;
    steps->push_back(m);
  }
  ScriptStep release;
  release.line = step.line;
  release.mouse_down[b] = false;
  steps->push_back(release);
  return "";
}

// move, down, up, click, drag, wheel.
std::string ParseMouse(const std::string& cmd, const std::vector<std::string>& t, ScriptStep step, Steps* steps) {
  const int n = static_cast<int>(t.size()) - 1;
  if (cmd == "move") {
    size_t i = 1;
    Point p;
    if (!ParsePoint(t, &i, &p) || i != t.size()) return std::string("'move POINT' needs a point; ") + kPointHelp;
    SetPoint(p, &step);
    steps->push_back(step);
  } else if (cmd == "down" || cmd == "up") {
    const int b = n == 1 ? ButtonIndex(Lower(t[1])) : -1;
    if (b < 0) return "'" + cmd + "' needs a button: left, right or middle";
    step.mouse_down[b] = cmd == "down";
    steps->push_back(step);
  } else if (cmd == "click") {
    return ParseClick(t, step, steps);
  } else if (cmd == "double-click" || cmd == "up-then-move") {
    const int b = t.size() >= 2 ? ButtonIndex(Lower(t[1])) : -1;
    size_t i = 2;
    Point p;
    if (b < 0 || !ParsePoint(t, &i, &p) || i != t.size()) {
      return "'" + cmd + " BUTTON POINT' needs left|right|middle and a point; " + kPointHelp;
    }
    SetPoint(p, &step);
    step.burst = cmd == "double-click" ? Burst::kDoubleClick : Burst::kReleaseThenMove;
    step.burst_button = b;
    steps->push_back(step);
  } else if (cmd == "drag") {
    return ParseDrag(t, step, steps);
  } else {  // wheel
    float dy;
    if (n < 1 || !ParseFloat(t[1], &dy)) return "'wheel DY [POINT]' needs a number";
    if (n > 1) {
      size_t i = 2;
      Point p;
      if (!ParsePoint(t, &i, &p) || i != t.size()) return std::string("'wheel DY POINT': ") + kPointHelp;
      ScriptStep m;
      m.line = step.line;
      SetPoint(p, &m);
      steps->push_back(m);
    }
    step.wheel = dy;
    steps->push_back(step);
  }
  return "";
}

// key [ctrl+][shift+][alt+]KEY: a press and, one frame later, the release.
std::string ParseKey(const std::vector<std::string>& t, ScriptStep step, Steps* steps) {
  if (t.size() != 2) return "'" + Lower(t[0]) + " [ctrl+][shift+][alt+]KEY' needs one key";
  std::string spec = Lower(t[1]);
  ScriptKey key;
  for (;;) {
    const size_t plus = spec.find('+');
    if (plus == std::string::npos || plus == 0 || plus + 1 == spec.size()) break;
    const std::string mod = spec.substr(0, plus);
    if (mod == "ctrl" || mod == "control")
      key.ctrl = true;
    else if (mod == "shift")
      key.shift = true;
    else if (mod == "alt")
      key.alt = true;
    else
      return "unknown modifier '" + mod + "' (ctrl, shift, alt)";
    spec = spec.substr(plus + 1);
  }
  key.key_code = KeyCodeFromName(spec);
  if (key.key_code < 0) return "unknown key '" + spec + "'";
  if (!key.ctrl && !key.alt && spec.size() == 1) {
    const char c = spec[0];
    key.character = static_cast<unsigned>(key.shift && c >= 'a' && c <= 'z' ? std::toupper(c) : c);
  } else if (!key.ctrl && !key.alt && spec == "space") {
    key.character = ' ';
  }
  step.key_press = key;
  if (Lower(t[0]) == "tap") {
    step.burst = Burst::kTap;
    steps->push_back(step);
    return "";
  }
  steps->push_back(step);
  ScriptStep release;
  release.line = step.line;
  steps->push_back(release);
  return "";
}

// hold|release shift|ctrl|alt.
std::string ParseModifier(const std::string& cmd, const std::vector<std::string>& t, ScriptStep step, Steps* steps) {
  const bool down = cmd == "hold";
  const std::string mod = t.size() == 2 ? Lower(t[1]) : std::string();
  if (mod == "shift")
    step.hold_shift = down;
  else if (mod == "ctrl" || mod == "control")
    step.hold_ctrl = down;
  else if (mod == "alt")
    step.hold_alt = down;
  else
    return "'" + cmd + "' needs shift, ctrl or alt";
  steps->push_back(step);
  return "";
}

// command NAME [ARGS]: checked against CommandArity; the arguments stay one string.
std::string ParseAppCommand(const std::string& line, const std::vector<std::string>& t, ScriptStep step, Steps* steps) {
  if (t.size() < 2) return "'command NAME [ARGS]' needs a name";
  step.command = Lower(t[1]);
  const auto& arity = CommandArity();
  const auto it = arity.find(step.command);
  if (it == arity.end()) {
    std::string known;  // from the table, so the message cannot fall behind it
    for (const auto& entry : arity) known += (known.empty() ? "" : ", ") + entry.first;
    return "unknown app command '" + t[1] + "' (" + known + ")";
  }
  const std::string rest = Rest(line, 2);
  if (!rest.empty()) step.command_args.push_back(rest);
  const int args = static_cast<int>(step.command_args.size());
  if (args < it->second.first || args > it->second.second) {
    return "command '" + step.command + "' takes " +
           (it->second.second == 0 ? std::string("no argument") : std::string("one argument"));
  }
  steps->push_back(step);
  return "";
}

// drop PATH [PATH...]: words, or "double-quoted paths" with spaces.
std::string ParseDrop(const std::string& line, ScriptStep step, Steps* steps) {
  const std::string rest = Rest(line, 1);
  for (size_t i = 0; i < rest.size();) {
    if (std::isspace(static_cast<unsigned char>(rest[i]))) {
      ++i;
    } else if (rest[i] == '"') {
      const size_t end = rest.find('"', i + 1);
      if (end == std::string::npos) return "'drop': a quoted path is not closed";
      step.dropped_paths.push_back(rest.substr(i + 1, end - i - 1));
      i = end + 1;
    } else {
      size_t end = i;
      while (end < rest.size() && !std::isspace(static_cast<unsigned char>(rest[end]))) ++end;
      step.dropped_paths.push_back(rest.substr(i, end - i));
      i = end;
    }
  }
  if (step.dropped_paths.empty()) return "'drop PATH [PATH...]' needs at least one path";
  steps->push_back(step);
  return "";
}

// Whether a script line of this kind is something a user does by hand (Script::ui_events).
// The test-only commands (wait-bake, bake-status, wait-autosave, advance-clock, wait-removed)
// are not.
bool IsUiEvent(const std::vector<std::string>& t) {
  const std::string cmd = Lower(t[0]);
  if (cmd == "command")
    return t.size() < 2 ||
           (Lower(t[1]) != "wait-bake" && Lower(t[1]) != "bake-status" && Lower(t[1]) != "wait-autosave" &&
            Lower(t[1]) != "advance-clock" && Lower(t[1]) != "wait-removed");
  return cmd == "click" || cmd == "drag" || cmd == "key" || cmd == "type" || cmd == "wheel" || cmd == "drop" ||
         cmd == "down" || cmd == "hold" || cmd == "tap" || cmd == "double-click";
}

// One non-empty line (comment stripped).
std::string ParseLine(const std::string& line, int line_no, Steps* steps) {
  const std::vector<std::string> t = Split(line);
  const std::string cmd = Lower(t[0]);
  ScriptStep step;
  step.line = line_no;
  if (cmd == "frames") return ParseFrames(t, step, steps);
  if (cmd == "move" || cmd == "down" || cmd == "up" || cmd == "click" || cmd == "drag" || cmd == "wheel" ||
      cmd == "double-click" || cmd == "up-then-move") {
    return ParseMouse(cmd, t, step, steps);
  }
  if (cmd == "key" || cmd == "tap") return ParseKey(t, step, steps);
  if (cmd == "type") {
    step.text = Rest(line, 1);
    if (step.text.empty()) return "'type TEXT' needs text";
    steps->push_back(step);
    return "";
  }
  if (cmd == "hold" || cmd == "release") return ParseModifier(cmd, t, step, steps);
  if (cmd == "command") return ParseAppCommand(line, t, step, steps);
  if (cmd == "drop") return ParseDrop(line, step, steps);
  if (cmd == "screenshot") {
    step.screenshot_path = Rest(line, 1);
    if (step.screenshot_path.empty()) return "'screenshot PATH' needs a path";
    step.command = "wait-bake";  // the picture shows the finished texture of every edit so far
    steps->push_back(step);
    return "";
  }
  return "unknown command '" + t[0] + "'";
}

}  // namespace

bool ParseScript(const std::string& text, Script* script, std::string* error) {
  Script out;
  std::istringstream in(text);
  std::string raw;
  int line_no = 0;
  while (std::getline(in, raw)) {
    ++line_no;
    const std::string line = Trim(raw.substr(0, raw.find('#')));
    if (line.empty()) continue;
    const std::string line_error = ParseLine(line, line_no, &out.steps);
    if (!line_error.empty()) {
      *error = "line " + std::to_string(line_no) + ": " + line_error;
      return false;
    }
    if (out.steps.size() > kMaxScriptSteps) {
      *error = "line " + std::to_string(line_no) + ": the script is longer than " + std::to_string(kMaxScriptSteps) +
               " frame steps";
      return false;
    }
    if (IsUiEvent(Split(line))) ++out.ui_events;
  }
  *script = std::move(out);
  return true;
}

bool LoadScript(const std::string& path, Script* script, std::string* error) {
  std::string text, read_error;
  if (!ReadRegularFile(path, kMaxTextFileBytes, &text, &read_error)) {
    *error = "cannot read script " + read_error;
    return false;
  }
  if (!ParseScript(text, script, error)) {
    *error = path + ": " + *error;
    return false;
  }
  return true;
}

}  // namespace facet::app
