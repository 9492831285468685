// The texture bake off the main thread, in the real application offscreen (`facet render`
// with an input script and `bake-status` snapshots): an edit's frame returns with the new
// geometry and the bake still in flight, the result that arrives is bit-identical to a
// synchronous bake of the same project and photo, an edit made while a bake runs drops that
// bake's result, and a screenshot waits for the texture.
#include <doctest/doctest.h>

#include <cstdint>
#include <cstdio>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/image/image_io.h"
#include "core/io/project_io.h"
#include "core/texture/textured_mesh.h"
#include "tests/app/app_test_util.h"
#include "tests/synthetic_scene.h"

using namespace facet::testing;

namespace {

// Deliberately large, so that a bake takes far longer than the frame that starts it.
constexpr int kPhotoWidthPx = 3072;
constexpr int kPhotoHeightPx = 2048;
// The frame that starts a bake (snapshot, untextured geometry, thread start) against the bake
// itself: a frame that waited for the bake would cost at least the bake.
constexpr double kMaxStartToBakeRatio = 0.25;

// Same fingerprint as the app's `bake-status` (FNV-1a, 64 bit, over the raw bytes).
template <typename T>
std::string Fingerprint(const std::vector<T>& values) {
  std::uint64_t hash = 14695981039346656037ull;
  const auto* p = reinterpret_cast<const unsigned char*>(values.data());
  for (size_t i = 0; i < values.size() * sizeof(T); ++i) hash = (hash ^ p[i]) * 1099511628211ull;
  char text[24];
  std::snprintf(text, sizeof(text), "%016llx", static_cast<unsigned long long>(hash));
  return text;
}

// A synchronous bake of a project the app saved, from the same photo file, compared with
// what the app showed.
void CheckMatchesSynchronousBake(const std::string& project_path, const std::string& photo_path,
                                 const nlohmann::json& status) {
  const facet::ProjectLoadResult loaded = facet::LoadProject(project_path);
  REQUIRE_MESSAGE(loaded.ok(), loaded.error);
  facet::ImageReadResult photo = facet::ReadImage(photo_path);
  REQUIRE_MESSAGE(photo.ok(), photo.error);
  REQUIRE(loaded.project.images.size() == 1);
  facet::TexturedMesh mesh;
  const facet::TextureBakeSummary summary =
      facet::BakeTexturedMesh(loaded.project, {&photo.image}, facet::TextureBakeOptions{}, &mesh);
  REQUIRE_MESSAGE(summary.IsUsable(), summary.message);
  REQUIRE(summary.faces_textured > 0);
  INFO("status: " << status.dump());
  CHECK(status.at("triangles").get<size_t>() == mesh.indices.size() / 3);
  CHECK(status.at("faces_textured").get<int>() == summary.faces_textured);
  CHECK(status.at("atlas_width").get<int>() == mesh.atlas.width);
  CHECK(status.at("atlas_height").get<int>() == mesh.atlas.height);
  CHECK(status.at("atlas_fnv").get<std::string>() == Fingerprint(mesh.atlas.pixels));
  CHECK(status.at("uvs_fnv").get<std::string>() == Fingerprint(mesh.uvs));
  CHECK(status.at("positions_fnv").get<std::string>() == Fingerprint(mesh.positions));
}

}  // namespace

TEST_CASE("texture bake in the background: the edit's frame does not wait, the result matches, a newer edit wins") {
  TempDir dir("bake_async");
  SyntheticSceneOptions options;
  options.width_px = kPhotoWidthPx;
  options.height_px = kPhotoHeightPx;
  options.focal_px *= static_cast<double>(kPhotoWidthPx) / 1024.0;
  SyntheticScene scene = MakeBoxScene(options);
  facet::Project project = scene.project;
  project.images[0].path = "photo.png";
  // A texture with detail everywhere, so that any texel out of place changes the atlas.
  cv::Mat photo(kPhotoHeightPx, kPhotoWidthPx, CV_8UC3);
  cv::randu(photo, cv::Scalar::all(0), cv::Scalar::all(256));
  REQUIRE(cv::imwrite(dir / "photo.png", photo));
  const std::string project_path = dir / "scene.facet";
  REQUIRE(facet::SaveProject(project, project_path) == "");

  std::ostringstream s;
  s << "frames 2\n";
  s << "command bake-status " << (dir / "s0.json") << "\n";
  // Edit 1 (a second box): its frame starts the bake; the next step looks before waiting.
  s << "command add box\n";
  s << "command bake-status " << (dir / "s1.json") << "\n";
  s << "command bake-status " << (dir / "s2.json") << "\n";
  s << "command save " << (dir / "after1.facet") << "\n";
  // Edit 2 starts a bake; edit 3 comes before it is collected, so its result is stale.
  s << "command add box\n";
  s << "command add box\n";
  s << "command bake-status " << (dir / "s3.json") << "\n";
  s << "command bake-status " << (dir / "s4.json") << "\n";
  s << "command save " << (dir / "after3.facet") << "\n";
  // A screenshot right after an edit shows the finished texture.
  s << "command add box\n";
  s << "screenshot " << (dir / "shot.png") << "\n";
  s << "command bake-status " << (dir / "s5.json") << "\n";
  WriteText(dir / "script.txt", s.str());
  const RunResult run = RunRender(dir, "'" + project_path + "' -o '" + (dir / "out.png") + "' --script '" +
                                           (dir / "script.txt") + "' --report '" + (dir / "report.json") + "'");
  INFO("stderr: " << run.stderr_text);
  REQUIRE(run.exit_code == 0);

  const nlohmann::json s0 = ReadJson(dir / "s0.json");
  const nlohmann::json s1 = ReadJson(dir / "s1.json");
  const nlohmann::json s2 = ReadJson(dir / "s2.json");
  const nlohmann::json s3 = ReadJson(dir / "s3.json");
  const nlohmann::json s4 = ReadJson(dir / "s4.json");
  const nlohmann::json s5 = ReadJson(dir / "s5.json");
  INFO("s0: " << s0.dump());
  INFO("s1: " << s1.dump());
  INFO("s2: " << s2.dump());

  // The opened project is baked and shown before the first edit.
  REQUIRE_FALSE(s0.at("in_flight").get<bool>());
  REQUIRE_FALSE(s0.at("texture_pending").get<bool>());
  REQUIRE(s0.at("faces_textured").get<int>() > 0);
  const size_t one_box_triangles = s0.at("triangles").get<size_t>();

  // After the edit's frame: the second box is in the mesh while its texture is still baking.
  CHECK(s1.at("in_flight").get<bool>());
  CHECK(s1.at("texture_pending").get<bool>());
  CHECK(s1.at("triangles").get<size_t>() == 2 * one_box_triangles);
  CHECK(s1.at("input_revision").get<std::uint64_t>() > s1.at("baked_input_revision").get<std::uint64_t>());
  CHECK(s1.at("started").get<int>() == s0.at("started").get<int>() + 1);
  // And that frame did not wait for it: starting costs a fraction of the bake.
  const double start_ms = s1.at("start_refresh_ms").get<double>();
  const double bake_ms = s2.at("bake_ms").get<double>();
  CAPTURE(start_ms);
  CAPTURE(bake_ms);
  CHECK(start_ms < kMaxStartToBakeRatio * bake_ms);

  // The next frame collected it: the texture of the edited project, as a synchronous bake.
  CHECK_FALSE(s2.at("in_flight").get<bool>());
  CHECK_FALSE(s2.at("texture_pending").get<bool>());
  CHECK(s2.at("collected").get<int>() == s1.at("collected").get<int>() + 1);
  CHECK(s2.at("dropped").get<int>() == 0);
  CHECK(s2.at("baked_input_revision") == s1.at("input_revision"));
  CheckMatchesSynchronousBake(dir / "after1.facet", dir / "photo.png", s2);

  // Edits 2 and 3: edit 2's bake was overtaken, dropped, and edit 3's baked instead.
  INFO("s3: " << s3.dump());
  INFO("s4: " << s4.dump());
  CHECK(s3.at("dropped").get<int>() == 1);
  CHECK(s3.at("collected").get<int>() == s2.at("collected").get<int>());
  CHECK(s3.at("in_flight").get<bool>());
  CHECK(s3.at("started").get<int>() == s2.at("started").get<int>() + 2);
  CHECK(s3.at("triangles").get<size_t>() == 4 * one_box_triangles);
  CHECK_FALSE(s4.at("in_flight").get<bool>());
  CHECK_FALSE(s4.at("texture_pending").get<bool>());
  CHECK(s4.at("collected").get<int>() == s3.at("collected").get<int>() + 1);
  CHECK(s4.at("baked_input_revision") == s3.at("input_revision"));
  CheckMatchesSynchronousBake(dir / "after3.facet", dir / "photo.png", s4);

  // The screenshot's frame finished the bake of the edit just before it.
  INFO("s5: " << s5.dump());
  CHECK_FALSE(s5.at("in_flight").get<bool>());
  CHECK_FALSE(s5.at("texture_pending").get<bool>());
  CHECK(s5.at("triangles").get<size_t>() == 5 * one_box_triangles);
  CHECK(s5.at("started").get<int>() == s4.at("started").get<int>() + 1);
}
