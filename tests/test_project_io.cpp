// The project file: exact round-trips of every field, validation errors that name their
// location, atomic saves, path resolution and the frozen version-1 fixture.
#include <doctest/doctest.h>

#include <signal.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <sys/stat.h>

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/camera.h"
#include "core/project.h"
#include "core/project_io.h"
#include "tests/synthetic_scene.h"

namespace fs = std::filesystem;
using facet::Axis;
using facet::Box;
using facet::Id;
using facet::Image;
using facet::Pin;
using facet::PrincipalPointMode;
using facet::Project;
using facet::Segment;

namespace {

struct TempDir {
  fs::path path;
  TempDir() {
    std::string templ = (fs::temp_directory_path() / "facet_project_io_XXXXXX").string();
    REQUIRE(::mkdtemp(templ.data()) != nullptr);
    path = templ;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  std::string operator/(const std::string& name) const { return (path / name).string(); }
};

std::set<std::string> ListDir(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) names.insert(entry.path().filename().string());
  return names;
}

std::string ReadFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

void WriteFile(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
}

std::uint64_t Bits(double v) {
  std::uint64_t b;
  std::memcpy(&b, &v, sizeof(b));
  return b;
}

// Every field away from its default, several images, segments on each axis, boxes with all
// 32 lock combinations, pins on every corner.
Project MakeFullProject() {
  Project p;
  p.units = "ft";
  const char* paths[] = {"photos/front.jpg", "../other/side view.png", "/abs/top.JPG"};
  for (int i = 0; i < 3; ++i) {
    Image im;
    im.id = p.NewId();
    im.path = paths[i];
    im.width_px = 4000 + i;
    im.height_px = 3000 - i;
    im.camera.width_px = 2000 + i;
    im.camera.height_px = 1500 - i;
    im.camera.focal_px = 3123.456789012345 + i;
    im.camera.principal_point_px = {1999.75 + 0.1 * i, 1499.125 - 0.3 * i};
    im.camera.cam_from_world_rotation = facet::RotationFromAngleAxis(Eigen::Vector3d(0.3 + 0.1 * i, -0.7, 1.1));
    im.camera.cam_from_world_translation = {1.5, -2.25 + i, 7.0 / 3.0};
    im.camera_calibrated = i != 1;
    im.principal_point_mode = static_cast<PrincipalPointMode>(i);
    im.fixed_principal_point_px = {12.5 + i, 8.25};
    im.pose_locked = i == 2;
    p.images.push_back(im);
  }
  for (int i = 0; i < 3; ++i) {
    for (int a = 0; a < 3; ++a) {
      for (int k = 0; k < 2; ++k) {
        Segment s;
        s.id = p.NewId();
        s.image_id = p.images[i].id;
        s.axis = static_cast<Axis>(a);
        s.a_px = {0.1 * (i + 1) + a, -3.7 * k};
        s.b_px = {1e4 / 3.0 + a, 2.0 / 7.0 + k};
        p.segments.push_back(s);
      }
    }
  }
  for (int mask = 0; mask < 32; ++mask) {
    Box b;
    b.id = p.NewId();
    b.name = mask == 5 ? "Turm \xC3\xBC \"quoted\" \\ tab\t \xE2\x98\x83" : "box " + std::to_string(mask);
    b.size = {1.0 + 0.1 * mask, 2.5, 0.75};
    b.rotation = {0.01 * mask, -0.2, 0.3};
    b.translation = {static_cast<double>(mask), -0.5 * mask, 0.125};
    b.size_locked = {(mask & 1) != 0, (mask & 2) != 0, (mask & 4) != 0};
    b.rotation_locked = (mask & 8) != 0;
    b.translation_locked = (mask & 16) != 0;
    p.boxes.push_back(b);
  }
  for (int c = 0; c < 10; ++c) {
    Pin pin;
    pin.id = p.NewId();
    pin.image_id = p.images[c % 3].id;
    pin.box_id = p.boxes[c * 3].id;
    pin.corner = c % 8;
    pin.uv_px = {100.5 * c + 0.1, -17.25 + 1.0 / (c + 3)};
    p.pins.push_back(pin);
  }
  p.next_id += 17;
  return p;
}

// A small valid project for loops over many variants of its text.
Project MakeSmallProject() {
  Project p;
  Image im;
  im.id = p.NewId();
  im.path = "a.jpg";
  im.width_px = 640;
  im.height_px = 480;
  im.camera.focal_px = 500.25;
  p.images.push_back(im);
  Segment s;
  s.id = p.NewId();
  s.image_id = im.id;
  s.axis = Axis::kZ;
  s.a_px = {1.5, 2.5};
  s.b_px = {3.5, 400.125};
  p.segments.push_back(s);
  Box b;
  b.id = p.NewId();
  b.name = "b";
  p.boxes.push_back(b);
  Pin pin;
  pin.id = p.NewId();
  pin.image_id = im.id;
  pin.box_id = b.id;
  pin.corner = 6;
  pin.uv_px = {10.0, 20.0};
  p.pins.push_back(pin);
  return p;
}

void CheckRoundTrip(const Project& p) {
  const std::string text = facet::ProjectToJson(p);
  const facet::ProjectLoadResult r = facet::ProjectFromJson(text);
  INFO("error: " << r.error);
  REQUIRE(r.ok());
  CHECK(r.warnings.empty());
  CHECK(r.project == p);
  CHECK(facet::ProjectToJson(r.project) == text);
}

// Loads `text` and requires an error that contains `location`.
void CheckErrorNames(const std::string& text, const std::string& location) {
  const facet::ProjectLoadResult r = facet::ProjectFromJson(text);
  INFO("expected an error naming '" << location << "', got: '" << r.error << "'");
  CHECK_FALSE(r.ok());
  CHECK(r.error.find(location) != std::string::npos);
}

using Json = nlohmann::json;

Json SmallJson() { return Json::parse(facet::ProjectToJson(MakeSmallProject())); }

}  // namespace

TEST_CASE("every field round-trips exactly and re-saving is byte-identical") {
  const Project p = MakeFullProject();
  CheckRoundTrip(p);

  TempDir dir;
  const std::string path = dir / "full.facet";
  REQUIRE(facet::SaveProject(p, path) == "");
  const std::string first = ReadFile(path);
  CHECK(first == facet::ProjectToJson(p));
  const facet::ProjectLoadResult loaded = facet::LoadProject(path);
  INFO("error: " << loaded.error);
  REQUIRE(loaded.ok());
  CHECK(loaded.project == p);
  REQUIRE(facet::SaveProject(loaded.project, path) == "");
  CHECK(ReadFile(path) == first);
  CHECK(ListDir(dir.path) == std::set<std::string>{"full.facet"});
}

TEST_CASE("each single field is written and read back") {
  // A field the writer forgot would read back as its default; changing each field alone
  // and requiring both a different text and an equal project catches that.
  const Project base = MakeFullProject();
  const std::string base_text = facet::ProjectToJson(base);
  std::vector<std::pair<const char*, std::function<void(Project&)>>> edits = {
      {"units", [](Project& p) { p.units = "mm"; }},
      {"next_id", [](Project& p) { p.next_id += 1; }},
      {"image.path", [](Project& p) { p.images[0].path = "x/y.png"; }},
      {"image.width_px", [](Project& p) { p.images[0].width_px += 1; }},
      {"image.height_px", [](Project& p) { p.images[0].height_px += 1; }},
      {"camera.width_px", [](Project& p) { p.images[0].camera.width_px += 1; }},
      {"camera.height_px", [](Project& p) { p.images[0].camera.height_px += 1; }},
      {"camera.focal_px", [](Project& p) { p.images[0].camera.focal_px *= 1.5; }},
      {"camera.pp.x", [](Project& p) { p.images[0].camera.principal_point_px.x() += 0.5; }},
      {"camera.pp.y", [](Project& p) { p.images[0].camera.principal_point_px.y() += 0.5; }},
      {"camera.rotation", [](Project& p) {
         p.images[1].camera.cam_from_world_rotation = facet::RotationFromAngleAxis(Eigen::Vector3d(0.1, 0.2, 0.3));
       }},
      {"camera.translation", [](Project& p) { p.images[1].camera.cam_from_world_translation.z() = -4.0; }},
      {"image.camera_calibrated", [](Project& p) { p.images[1].camera_calibrated = true; }},
      {"image.principal_point_mode", [](Project& p) { p.images[0].principal_point_mode = PrincipalPointMode::kFixed; }},
      {"image.fixed_principal_point_px", [](Project& p) { p.images[2].fixed_principal_point_px.y() = 99.0; }},
      {"image.pose_locked", [](Project& p) { p.images[0].pose_locked = true; }},
      {"segment.id", [](Project& p) { p.segments[1].id = p.NewId(); }},
      {"segment.image_id", [](Project& p) { p.segments[0].image_id = p.images[2].id; }},
      {"segment.axis", [](Project& p) { p.segments[0].axis = Axis::kY; }},
      {"segment.a_px", [](Project& p) { p.segments[0].a_px.y() = 0.5; }},
      {"segment.b_px", [](Project& p) { p.segments[0].b_px.x() = 0.5; }},
      {"box.name", [](Project& p) { p.boxes[3].name = "renamed"; }},
      {"box.size", [](Project& p) { p.boxes[3].size.z() = 9.0; }},
      {"box.rotation", [](Project& p) { p.boxes[3].rotation.x() = 1.0; }},
      {"box.translation", [](Project& p) { p.boxes[3].translation.y() = 1.0; }},
      {"box.size_locked[0]", [](Project& p) { p.boxes[0].size_locked[0] = true; }},
      {"box.size_locked[1]", [](Project& p) { p.boxes[0].size_locked[1] = true; }},
      {"box.size_locked[2]", [](Project& p) { p.boxes[0].size_locked[2] = true; }},
      {"box.rotation_locked", [](Project& p) { p.boxes[0].rotation_locked = true; }},
      {"box.translation_locked", [](Project& p) { p.boxes[0].translation_locked = true; }},
      {"pin.image_id", [](Project& p) { p.pins[0].image_id = p.images[2].id; }},
      {"pin.box_id", [](Project& p) { p.pins[0].box_id = p.boxes[31].id; }},
      {"pin.corner", [](Project& p) { p.pins[0].corner = 7; }},
      {"pin.uv_px", [](Project& p) { p.pins[0].uv_px.x() = -1.0; }},
  };
  for (const auto& [name, edit] : edits) {
    CAPTURE(name);
    Project changed = base;
    edit(changed);
    REQUIRE_FALSE(changed == base);
    const std::string text = facet::ProjectToJson(changed);
    CHECK(text != base_text);
    const facet::ProjectLoadResult r = facet::ProjectFromJson(text);
    INFO("error: " << r.error);
    REQUIRE(r.ok());
    CHECK(r.project == changed);
  }
}

TEST_CASE("the synthetic box scene round-trips") {
  CheckRoundTrip(facet::testing::MakeBoxScene().project);
  facet::testing::SyntheticSceneOptions o;
  o.noise_px = 0.7;
  o.scale = 1e-3;
  o.seed = 42;
  CheckRoundTrip(facet::testing::MakeBoxScene(o).project);
}

TEST_CASE("doubles round-trip bit-exactly") {
  const std::vector<double> awkward = {0.1 + 0.2,
                                       1e-310,  // subnormal
                                       -0.0,
                                       0.1,
                                       1.0 / 3.0,
                                       123456789.12345678,
                                       0.30000000000000004,
                                       5e-324,
                                       DBL_MAX,
                                       -DBL_MAX,
                                       DBL_MIN,
                                       std::nextafter(1.0, 2.0),
                                       std::nextafter(1.0, 0.0),
                                       M_PI * 1e20,
                                       -2.5e-300,
                                       9007199254740993.0,
                                       1e23,
                                       4.35,
                                       2.0};
  std::mt19937_64 rng(7);
  std::vector<double> values = awkward;
  while (values.size() < awkward.size() + 2000) {
    const std::uint64_t bits = rng();
    double v;
    std::memcpy(&v, &bits, sizeof(v));
    if (std::isfinite(v)) values.push_back(v);
  }

  Project p = MakeSmallProject();
  p.pins.clear();
  const Segment model = p.segments[0];
  p.segments.clear();
  for (size_t i = 0; i + 1 < values.size(); i += 2) {
    Segment s = model;
    s.id = p.NewId();
    s.a_px = {values[i], values[i + 1]};
    s.b_px = {values[i + 1], values[i]};
    p.segments.push_back(s);
  }
  p.boxes[0].size = {std::abs(values[1]), std::abs(values[7]), DBL_MAX};  // sizes are >= 0
  p.boxes[0].translation = {values[2], values[5], values[14]};

  const std::string text = facet::ProjectToJson(p);
  const facet::ProjectLoadResult r = facet::ProjectFromJson(text);
  INFO("error: " << r.error);
  REQUIRE(r.ok());
  REQUIRE(r.project.segments.size() == p.segments.size());
  int mismatches = 0;
  for (size_t i = 0; i < p.segments.size(); ++i) {
    for (int k = 0; k < 2; ++k) {
      if (Bits(p.segments[i].a_px(k)) != Bits(r.project.segments[i].a_px(k)) ||
          Bits(p.segments[i].b_px(k)) != Bits(r.project.segments[i].b_px(k))) {
        ++mismatches;
        MESSAGE("mismatch: " << p.segments[i].a_px(k) << " -> " << r.project.segments[i].a_px(k));
      }
    }
  }
  CHECK(mismatches == 0);
  // -0.0 == 0.0, so check the sign bit on its own: segment 1 holds values[2] = -0.0.
  CHECK(std::signbit(r.project.segments[1].a_px.x()));
  CHECK(std::signbit(r.project.boxes[0].translation.x()));
  for (int k = 0; k < 3; ++k) {
    CHECK(Bits(r.project.boxes[0].size(k)) == Bits(p.boxes[0].size(k)));
    CHECK(Bits(r.project.boxes[0].translation(k)) == Bits(p.boxes[0].translation(k)));
  }
  CHECK(r.project == p);
}

TEST_CASE("NaN and infinity are refused with the field's path, and nothing is written") {
  TempDir dir;
  const std::string path = dir / "p.facet";
  {
    Project p = MakeFullProject();
    p.images[1].camera.focal_px = std::numeric_limits<double>::quiet_NaN();
    const std::string error = facet::SaveProject(p, path);
    INFO(error);
    CHECK(error.find("images[1].camera.focal_px") != std::string::npos);
    CHECK(error.find("NaN") != std::string::npos);
    CHECK(facet::CheckProjectSavable(p).find("images[1].camera.focal_px") != std::string::npos);
  }
  {
    Project p = MakeFullProject();
    p.boxes[4].translation.z() = -std::numeric_limits<double>::infinity();
    const std::string error = facet::SaveProject(p, path);
    INFO(error);
    CHECK(error.find("boxes[4].translation[2]") != std::string::npos);
    CHECK(error.find("infinity") != std::string::npos);
  }
  {
    Project p = MakeFullProject();
    p.images[0].camera.cam_from_world_rotation(1, 2) = std::numeric_limits<double>::quiet_NaN();
    const std::string error = facet::SaveProject(p, path);
    INFO(error);
    CHECK(error.find("images[0].camera.rotation[5]") != std::string::npos);
  }
  CHECK(ListDir(dir.path).empty());
  CHECK(facet::CheckProjectSavable(MakeFullProject()) == "");
}

TEST_CASE("a project that would not load back is not saved, and the old file stays") {
  TempDir dir;
  const std::string path = dir / "p.facet";
  WriteFile(path, "old contents");
  Project p = MakeFullProject();
  p.pins[2].box_id = p.next_id + 100;
  const std::string error = facet::SaveProject(p, path);
  INFO(error);
  CHECK(error.find("pins[2].box_id") != std::string::npos);
  Project q = MakeFullProject();
  q.boxes[1].name = "bad \xFF utf-8";
  const std::string error2 = facet::SaveProject(q, path);
  INFO(error2);
  CHECK(error2.find("boxes[1].name") != std::string::npos);
  CHECK(ReadFile(path) == "old contents");
  CHECK(ListDir(dir.path) == std::set<std::string>{"p.facet"});
}

TEST_CASE("every truncation of a valid file is an error with a line and column") {
  const std::string text = facet::ProjectToJson(MakeSmallProject());
  REQUIRE(text.size() > 500);
  REQUIRE(text.substr(text.size() - 2) == "}\n");
  // Cutting only the final newline leaves valid JSON; every shorter cut must fail.
  for (size_t length = 0; length + 1 < text.size(); ++length) {
    const std::string cut = text.substr(0, length);
    const facet::ProjectLoadResult r = facet::ProjectFromJson(cut);
    CAPTURE(length);
    INFO("error: " << r.error);
    REQUIRE_FALSE(r.ok());
    // The error is at the end of the input: its line is the last line of the prefix.
    const size_t lines = 1 + static_cast<size_t>(std::count(cut.begin(), cut.end(), '\n'));
    const size_t last_line_start = cut.rfind('\n') == std::string::npos ? 0 : cut.rfind('\n') + 1;
    CHECK(r.error.rfind("line " + std::to_string(lines) + ", column ", 0) == 0);
    if (cut.find_first_not_of(" \t\r\n") != std::string::npos && cut.back() != '\n') {
      // End of input: the column just past the last character.
      const size_t column = cut.size() - last_line_start + 1;
      CHECK(r.error.rfind("line " + std::to_string(lines) + ", column " + std::to_string(column) + ":", 0) == 0);
    }
    CHECK(r.project == Project());
  }
  // Truncated files on disk too, at a few cut points.
  TempDir dir;
  for (size_t length : {size_t{0}, size_t{1}, text.size() / 3, text.size() / 2, text.size() - 2}) {
    const std::string path = dir / "cut.facet";
    WriteFile(path, text.substr(0, length));
    const facet::ProjectLoadResult r = facet::LoadProject(path);
    INFO("length " << length << ": " << r.error);
    CHECK_FALSE(r.ok());
    CHECK(r.error.find(path) != std::string::npos);
    CHECK(r.error.find("line ") != std::string::npos);
  }
}

TEST_CASE("syntax errors report the line and column of the offending character") {
  const std::string text = "{\n  \"format\": \"facet-project\",\n  \"version\": 1,\n  oops: 3\n}\n";
  const facet::ProjectLoadResult r = facet::ProjectFromJson(text);
  INFO(r.error);
  CHECK(r.error.rfind("line 4, column 3:", 0) == 0);
  const facet::ProjectLoadResult r2 = facet::ProjectFromJson("{\"a\": [1, 2,, 3]}");
  INFO(r2.error);
  CHECK(r2.error.rfind("line 1, column 13:", 0) == 0);
}

TEST_CASE("files that are not projects at all are errors, never crashes") {
  CheckErrorNames("", "the file is empty");
  CheckErrorNames(" \n\t \n", "the file is empty");
  CheckErrorNames("hello world", "line 1, column 1");
  CheckErrorNames(std::string("\x89PNG\r\n\x1a\n\0\0\0\rIHDR", 16), "line 1, column 1");
  CheckErrorNames("[1, 2, 3]", "(top level): expected a JSON object");
  CheckErrorNames("null", "(top level)");
  CheckErrorNames("42", "(top level)");
  CheckErrorNames("{}", "format: missing field");
  CheckErrorNames("{\"format\": \"something-else\", \"version\": 1}", "format: expected \"facet-project\"");
  CheckErrorNames(std::string(100000, '['), "line 1");
  CheckErrorNames(std::string(50000, '{'), "line 1");
  CheckErrorNames("{\"format\": \"facet-project\", \"version\": 1, \"units\": \"\xFF\xFE\"}", "line 1");
  std::mt19937 rng(3);
  for (int trial = 0; trial < 200; ++trial) {
    std::string garbage(rng() % 300, '\0');
    for (char& c : garbage) c = static_cast<char>(rng() & 0xFF);
    if (trial % 2) garbage = "{" + garbage;
    const facet::ProjectLoadResult r = facet::ProjectFromJson(garbage);
    CAPTURE(trial);
    CHECK_FALSE(r.ok());
  }
}

TEST_CASE("version: newer files are refused clearly, bad versions are errors") {
  Json j = SmallJson();
  j["version"] = 7;
  const facet::ProjectLoadResult r = facet::ProjectFromJson(j.dump());
  CHECK(r.error == "version: written by a newer Facet: version 7, this build reads up to 1");
  j["version"] = 0;
  CheckErrorNames(j.dump(), "version: expected a positive integer");
  j["version"] = -3;
  CheckErrorNames(j.dump(), "version: expected a positive integer");
  j["version"] = "1";
  CheckErrorNames(j.dump(), "version: expected a positive integer");
  j["version"] = 1.0;
  CheckErrorNames(j.dump(), "version: expected a positive integer");
  j["version"] = 18446744073709551615ull;
  CheckErrorNames(j.dump(), "written by a newer Facet");
  j.erase("version");
  CheckErrorNames(j.dump(), "version: missing field");
}

namespace {
// Every value in the tree with its path as the loader names it ("boxes[0].size[1]").
void CollectPaths(const Json& j, const Json::json_pointer& ptr, const std::string& name,
                  std::vector<std::pair<Json::json_pointer, std::string>>* out) {
  if (!name.empty()) out->push_back({ptr, name});
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end(); ++it)
      CollectPaths(it.value(), ptr / it.key(), name.empty() ? it.key() : name + "." + it.key(), out);
  } else if (j.is_array()) {
    for (size_t i = 0; i < j.size(); ++i)
      CollectPaths(j[i], ptr / i, name + "[" + std::to_string(i) + "]", out);
  }
}
}  // namespace

TEST_CASE("every missing field and every wrong type is an error naming its path") {
  const Json good = SmallJson();
  REQUIRE(facet::ProjectFromJson(good.dump()).ok());
  std::vector<std::pair<Json::json_pointer, std::string>> paths;
  CollectPaths(good, Json::json_pointer(), "", &paths);
  REQUIRE(paths.size() > 50);
  int missing_cases = 0, type_cases = 0;
  for (const auto& [ptr, name] : paths) {
    CAPTURE(name);
    const bool in_object = good.at(ptr.parent_pointer()).is_object();
    if (in_object) {
      Json removed = good;
      removed.at(ptr.parent_pointer()).erase(ptr.back());
      CheckErrorNames(removed.dump(), name + ": missing field");
      ++missing_cases;
    }
    // A value of the wrong kind: text where text is not expected, a number where it is.
    Json wrong = good;
    wrong.at(ptr) = good.at(ptr).is_string() ? Json(12345) : Json("oops");
    CheckErrorNames(wrong.dump(), name);
    // Booleans and integers are strict: 1 is not true, 1.5 is not an integer.
    if (good.at(ptr).is_boolean()) {
      wrong.at(ptr) = 1;
      CheckErrorNames(wrong.dump(), name + ": expected true or false");
    }
    if (good.at(ptr).is_number_integer()) {
      wrong.at(ptr) = 1.5;
      CheckErrorNames(wrong.dump(), name);
    }
    if (good.at(ptr).is_array() && !good.at(ptr).empty() && good.at(ptr)[0].is_primitive()) {
      wrong.at(ptr) = good.at(ptr);
      wrong.at(ptr).push_back(good.at(ptr)[0]);
      CheckErrorNames(wrong.dump(), name + ": expected an array of");
    }
    ++type_cases;
  }
  MESSAGE(missing_cases << " missing-field cases, " << type_cases << " wrong-type cases");
}

TEST_CASE("out-of-range values and bad references name their location") {
  const Json base = Json::parse(facet::ProjectToJson(MakeFullProject()));
  auto with = [&](const std::function<void(Json&)>& edit) {
    Json j = base;
    edit(j);
    return j.dump(2);
  };
  CheckErrorNames(with([](Json& j) { j["pins"][3]["corner"] = 8; }),
                  "pins[3].corner: expected an integer from 0 to 7, found 8");
  CheckErrorNames(with([](Json& j) { j["pins"][3]["corner"] = -1; }), "pins[3].corner");
  CheckErrorNames(with([](Json& j) { j["boxes"][2]["size"][1] = -0.5; }),
                  "boxes[2].size[1]: a size cannot be negative");
  CheckErrorNames(with([](Json& j) { j["boxes"][2]["size"] = {1.0, 2.0}; }),
                  "boxes[2].size: expected an array of 3 numbers");
  CheckErrorNames(with([](Json& j) { j["segments"][4]["axis"] = "w"; }), "segments[4].axis");
  CheckErrorNames(with([](Json& j) { j["segments"][4]["axis"] = "X"; }), "segments[4].axis");
  CheckErrorNames(with([](Json& j) { j["images"][1]["principal_point_mode"] = "auto"; }),
                  "images[1].principal_point_mode");
  CheckErrorNames(with([](Json& j) { j["boxes"][7]["id"] = j["boxes"][2]["id"]; }), "boxes[7].id: duplicate id");
  CheckErrorNames(with([](Json& j) { j["pins"][0]["id"] = j["images"][0]["id"]; }), "pins[0].id: duplicate id");
  CheckErrorNames(with([](Json& j) { j["segments"][3]["image_id"] = 9999; }),
                  "segments[3].image_id: refers to a missing image");
  CheckErrorNames(with([](Json& j) { j["pins"][5]["image_id"] = j["boxes"][0]["id"]; }),
                  "pins[5].image_id: refers to a missing image");
  CheckErrorNames(with([](Json& j) { j["pins"][5]["box_id"] = j["images"][0]["id"]; }),
                  "pins[5].box_id: refers to a missing box");
  CheckErrorNames(with([](Json& j) { j["next_id"] = j["pins"].back()["id"]; }), "next_id: must be greater");
  CheckErrorNames(with([](Json& j) { j["boxes"][0]["id"] = 0; }), "boxes[0].id: expected a positive integer id");
  CheckErrorNames(with([](Json& j) { j["boxes"][0]["id"] = -4; }), "boxes[0].id");
  CheckErrorNames(with([](Json& j) { j["images"][0]["width_px"] = -1; }), "images[0].width_px");
  CheckErrorNames(with([](Json& j) { j["images"][0]["width_px"] = 3000000000ull; }), "images[0].width_px");
  CheckErrorNames(with([](Json& j) { j["images"][2]["camera"]["focal_px"] = 0.0; }),
                  "images[2].camera.focal_px: must be positive");
  CheckErrorNames(with([](Json& j) { j["images"][2]["camera"]["rotation"][0] = 2.0; }),
                  "images[2].camera.rotation: not a rotation matrix");
  CheckErrorNames(with([](Json& j) {  // a reflection is orthonormal but not a rotation
                    for (int k = 0; k < 3; ++k) j["images"][2]["camera"]["rotation"][k] = -j["images"][2]["camera"]["rotation"][k].get<double>();
                  }),
                  "images[2].camera.rotation: not a rotation matrix");
  {  // a number beyond the range of a double
    std::string text = with([](Json& j) { j["segments"][0]["a_px"][1] = 123.25; });
    REQUIRE(text.find("123.25") != std::string::npos);
    text.replace(text.find("123.25"), 6, "-1e400");
    const size_t at = text.find("-1e400");
    const size_t line = 1 + static_cast<size_t>(std::count(text.begin(), text.begin() + at, '\n'));
    const size_t column = at - text.rfind('\n', at);
    CheckErrorNames(text, "line " + std::to_string(line) + ", column " + std::to_string(column) +
                              ": number out of range '-1e400'");
  }
}

TEST_CASE("unknown fields are warnings, not errors") {
  Json j = SmallJson();
  j["boxes"][0]["colour"] = "red";
  j["future_section"] = Json::array();
  const facet::ProjectLoadResult r = facet::ProjectFromJson(j.dump());
  INFO(r.error);
  REQUIRE(r.ok());
  CHECK(r.project == MakeSmallProject());
  REQUIRE(r.warnings.size() == 2);
  const std::string all = r.warnings[0] + "\n" + r.warnings[1];
  INFO(all);
  CHECK(all.find("boxes[0].colour: unknown field ignored") != std::string::npos);
  CHECK(all.find("future_section: unknown field ignored") != std::string::npos);
}

TEST_CASE("LoadProject: missing files are errors, missing images are warnings") {
  TempDir dir;
  const facet::ProjectLoadResult missing = facet::LoadProject(dir / "nope.facet");
  INFO(missing.error);
  CHECK_FALSE(missing.ok());
  CHECK(missing.error.find("nope.facet") != std::string::npos);
  CHECK(missing.error.find("No such file") != std::string::npos);

  const facet::ProjectLoadResult folder = facet::LoadProject(dir.path.string());
  INFO(folder.error);
  CHECK_FALSE(folder.ok());

  const facet::ProjectLoadResult empty = (WriteFile(dir / "empty.facet", ""), facet::LoadProject(dir / "empty.facet"));
  CHECK(empty.error.find("empty") != std::string::npos);

  Project p = MakeSmallProject();
  Image second = p.images[0];
  second.id = p.NewId();
  second.path = "photos/missing.jpg";
  p.images.push_back(second);
  p.images[0].path = "photos/present.jpg";
  fs::create_directories(dir.path / "project" / "photos");
  WriteFile((dir.path / "project" / "photos" / "present.jpg").string(), "not really a jpeg");
  const std::string path = (dir.path / "project" / "p.facet").string();
  REQUIRE(facet::SaveProject(p, path) == "");
  const facet::ProjectLoadResult r = facet::LoadProject(path);
  INFO(r.error);
  REQUIRE(r.ok());
  CHECK(r.project == p);
  REQUIRE(r.warnings.size() == 1);
  CHECK(r.warnings[0].find("images[1]") != std::string::npos);
  CHECK(r.warnings[0].find("missing.jpg") != std::string::npos);
}

TEST_CASE("atomic save: missing folder, replacing a file, failures leave no trace") {
  TempDir dir;
  const Project p = MakeFullProject();

  SUBCASE("a path in a missing folder fails and creates nothing") {
    const std::string error = facet::SaveProject(p, dir / "no/such/folder/p.facet");
    INFO(error);
    CHECK_FALSE(error.empty());
    CHECK(ListDir(dir.path).empty());
  }
  SUBCASE("saving over an existing file replaces it and keeps its permissions") {
    const std::string path = dir / "p.facet";
    WriteFile(path, "old contents");
    ::chmod(path.c_str(), 0640);
    REQUIRE(facet::SaveProject(p, path) == "");
    CHECK(ReadFile(path) == facet::ProjectToJson(p));
    CHECK((fs::status(path).permissions() & fs::perms::all) ==
          (fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read));
    CHECK(ListDir(dir.path) == std::set<std::string>{"p.facet"});
  }
  SUBCASE("a new file gets the usual 0644, not mkstemp's 0600") {
    const std::string path = dir / "new.facet";
    REQUIRE(facet::SaveProject(p, path) == "");
    CHECK((fs::status(path).permissions() & fs::perms::all) ==
          (fs::perms::owner_read | fs::perms::owner_write | fs::perms::group_read | fs::perms::others_read));
  }
  SUBCASE("saving through a symlink replaces the file it points to and keeps the link") {
    fs::create_directory(dir.path / "real");
    const std::string target = dir / "real/p.facet";
    WriteFile(target, "old contents");
    fs::create_symlink(target, dir.path / "link.facet");
    REQUIRE(facet::SaveProject(p, dir / "link.facet") == "");
    CHECK(fs::is_symlink(dir.path / "link.facet"));
    CHECK(ReadFile(target) == facet::ProjectToJson(p));
    CHECK(ListDir(dir.path / "real") == std::set<std::string>{"p.facet"});
  }
  SUBCASE("a target that is a folder fails; the folder stays and no temp file remains") {
    fs::create_directory(dir.path / "taken.facet");
    WriteFile(dir / "taken.facet/inside.txt", "keep me");
    const std::string error = facet::SaveProject(p, dir / "taken.facet");
    INFO(error);
    CHECK_FALSE(error.empty());
    CHECK(fs::is_directory(dir.path / "taken.facet"));
    CHECK(ReadFile(dir / "taken.facet/inside.txt") == "keep me");
    CHECK(ListDir(dir.path) == std::set<std::string>{"taken.facet"});
  }
  SUBCASE("a write that fails midway leaves the old file intact and no temp file") {
    // Permissions do not stop root, but a file-size limit does: write() fails with EFBIG.
    const std::string path = dir / "p.facet";
    const std::string old_text = facet::ProjectToJson(MakeSmallProject());
    WriteFile(path, old_text);
    const std::string new_text = facet::ProjectToJson(p);
    REQUIRE(new_text.size() > 4 * old_text.size());
    rlimit saved{};
    REQUIRE(::getrlimit(RLIMIT_FSIZE, &saved) == 0);
    auto* old_handler = ::signal(SIGXFSZ, SIG_IGN);
    rlimit limited = saved;
    limited.rlim_cur = static_cast<rlim_t>(2 * old_text.size());
    REQUIRE(::setrlimit(RLIMIT_FSIZE, &limited) == 0);
    const std::string error = facet::WriteFileAtomically(path, new_text);
    ::setrlimit(RLIMIT_FSIZE, &saved);
    ::signal(SIGXFSZ, old_handler);
    INFO(error);
    CHECK(error.find("writing") != std::string::npos);
    CHECK(ReadFile(path) == old_text);
    CHECK(ListDir(dir.path) == std::set<std::string>{"p.facet"});
  }
}

TEST_CASE("image paths resolve against the project file's folder") {
  CHECK(facet::ResolveImagePath("/a/b/p.facet", "img/x.jpg") == "/a/b/img/x.jpg");
  CHECK(facet::ResolveImagePath("/a/b/p.facet", "../c/./x.jpg") == "/a/c/x.jpg");
  CHECK(facet::ResolveImagePath("/a/b/p.facet", "/abs/dir/../x.jpg") == "/abs/x.jpg");
  CHECK(facet::ResolveImagePath("/a/b/p.facet", "/abs/x.jpg") == "/abs/x.jpg");
  CHECK(facet::ResolveImagePath("p.facet", "x.jpg") == "x.jpg");
  CHECK(facet::ResolveImagePath("rel/dir/p.facet", "x.jpg") == "rel/dir/x.jpg");

  CHECK(facet::RelativeImagePath("/a/b/p.facet", "/a/b/img/x.jpg") == "img/x.jpg");
  CHECK(facet::RelativeImagePath("/a/b/p.facet", "/a/c/x.jpg") == "../c/x.jpg");

  Project p = MakeFullProject();  // paths: photos/front.jpg, ../other/side view.png, /abs/top.JPG
  std::vector<std::string> before;
  for (const Image& im : p.images) before.push_back(facet::ResolveImagePath("/a/b/p.facet", im.path));
  facet::RebaseImagePaths("/a/b/p.facet", "/a/d/e/q.facet", &p);
  CHECK(p.images[0].path == "../../b/photos/front.jpg");
  CHECK(p.images[1].path == "../../other/side view.png");
  for (size_t i = 0; i < p.images.size(); ++i)
    CHECK(facet::ResolveImagePath("/a/d/e/q.facet", p.images[i].path) == before[i]);
}

TEST_CASE("the version-1 fixture keeps loading") {
  // tests/fixtures/project_v1.facet is frozen: never regenerate it. If it stops loading,
  // a migration step is missing.
  const std::string path = std::string(FACET_SOURCE_DIR) + "/tests/fixtures/project_v1.facet";
  const facet::ProjectLoadResult r = facet::LoadProject(path);
  INFO(r.error);
  REQUIRE(r.ok());
  const Project& p = r.project;
  CHECK(p.units == "m");
  CHECK(p.next_id == 12);
  REQUIRE(p.images.size() == 2);
  CHECK(p.images[0].id == 1);
  CHECK(p.images[0].path == "photos/facade.jpg");
  CHECK(p.images[0].width_px == 4032);
  CHECK(p.images[0].height_px == 3024);
  CHECK(p.images[0].camera.focal_px == 3105.25);
  CHECK(p.images[0].camera.principal_point_px == Eigen::Vector2d(2015.5, 1511.5));
  CHECK(p.images[0].camera.cam_from_world_rotation(1, 2) == -1.0);
  CHECK(p.images[0].camera.cam_from_world_translation == Eigen::Vector3d(0.5, 1.25, 12.0));
  CHECK(p.images[0].camera_calibrated);
  CHECK(p.images[0].principal_point_mode == PrincipalPointMode::kImageCenter);
  CHECK(p.images[1].principal_point_mode == PrincipalPointMode::kFixed);
  CHECK(p.images[1].fixed_principal_point_px == Eigen::Vector2d(960.0, 540.0));
  CHECK(p.images[1].pose_locked);
  CHECK_FALSE(p.images[1].camera_calibrated);
  REQUIRE(p.segments.size() == 3);
  CHECK(p.segments[0].axis == Axis::kX);
  CHECK(p.segments[1].axis == Axis::kY);
  CHECK(p.segments[2].axis == Axis::kZ);
  CHECK(p.segments[2].b_px == Eigen::Vector2d(1800.0, 2900.75));
  REQUIRE(p.boxes.size() == 2);
  CHECK(p.boxes[0].name == "building");
  CHECK(p.boxes[0].size == Eigen::Vector3d(12.0, 8.5, 6.25));
  CHECK(p.boxes[0].size_locked == std::array<bool, 3>{false, false, true});
  CHECK(p.boxes[1].rotation == Eigen::Vector3d(0.0, 0.0, 0.7853981633974483));
  CHECK_FALSE(p.boxes[1].rotation_locked);
  CHECK_FALSE(p.boxes[1].translation_locked);
  REQUIRE(p.pins.size() == 3);
  CHECK(p.pins[2].box_id == 7);
  CHECK(p.pins[2].corner == 7);
  CHECK(p.pins[2].uv_px == Eigen::Vector2d(1234.5, 876.25));
  // The photos are not in the repository: the project still opens, with warnings.
  CHECK(r.warnings.size() == 2);
}
