// Issue 25, "slow, not infinite": inputs past the limits of core/util/input_limits.h are
// refused by name where they enter (the project reader, K_create), and inputs at a limit are
// built and read correctly. Timing at the limits is a manual measurement (issue 25's report),
// not asserted here; these inputs are the cheapest that reach each limit.
#include <doctest/doctest.h>

#include <algorithm>
#include <string>

#include <nlohmann/json.hpp>

#include "core/io/project_io.h"
#include "core/mesh/primitives.h"
#include "core/scene/project.h"
#include "core/util/input_limits.h"

namespace facet {
namespace {

using Json = nlohmann::json;

// A project with one photo and a chain of `boxes` boxes, each on the one before (AttachOnTop),
// the first on the ground; heights 1, 2, 3, ... so that each level's bottom is the sum below.
Project MakeChain(int boxes) {
  Project p;
  Image image;
  image.id = p.NewId();
  image.path = "a.jpg";
  image.width_px = 640;
  image.height_px = 480;
  image.camera.focal_px = 500.0;
  p.images.push_back(image);
  Id below = kNoId;
  for (int k = 0; k < boxes; ++k) {
    Id id = kNoId;
    REQUIRE(AddPrimitiveToProject(&p, MakeBox(kNoId, {2.0, 3.0, 1.0 + k}), "box " + std::to_string(k), &id, nullptr));
    p.primitives.back().attached_to = below;
    below = id;
  }
  return p;
}

TEST_CASE("a prism or cylinder has at most kMaxPrimitiveSides sides: more are refused by name") {
  for (const bool cylinder : {false, true}) {
    const char* kind = cylinder ? "cylinder" : "prism";
    CAPTURE(kind);
    auto make = [&](int sides) { return cylinder ? MakeCylinder(1, sides, 0.5, 2.0) : MakePrism(1, sides, 0.5, 2.0); };
    PolyMesh at_limit;
    const AddPrimitiveResult ok = AddPrimitive(&at_limit, make(kMaxPrimitiveSides));
    REQUIRE_MESSAGE(ok.ok, ok.message);
    CHECK(ok.vertices.size() == 2u * kMaxPrimitiveSides);
    CHECK(ok.faces.size() == kMaxPrimitiveSides + 2u);

    PolyMesh over;
    const AddPrimitiveResult refused = AddPrimitive(&over, make(100000));
    CHECK_FALSE(refused.ok);
    CHECK(refused.message == std::string("a ") + kind + " may have at most " + std::to_string(kMaxPrimitiveSides) +
                                 " sides; this one has 100000");
    CHECK(over.VertexIdEnd() == 0);  // refused before anything was added
  }
}

TEST_CASE("the project reader refuses a primitive over kMaxPrimitiveSides by name and reads one at it") {
  Project p = MakeChain(1);
  Id id = kNoId;
  REQUIRE(AddPrimitiveToProject(&p, MakeCylinder(kNoId, 8, 0.5, 2.0), "drum", &id, nullptr));
  Json j = Json::parse(ProjectToJson(p));
  Json& drum = j["primitives"][1];
  drum["mesh"] = "from_shape";  // how a few hundred bytes asked for 100,000 sides

  drum["segments"] = kMaxPrimitiveSides;
  const ProjectLoadResult at_limit = ProjectFromJson(j.dump());
  REQUIRE_MESSAGE(at_limit.ok(), at_limit.error);
  CHECK(at_limit.project.primitives[1].mesh.NumVertices() == 2 * kMaxPrimitiveSides);

  drum["segments"] = 100000;
  const ProjectLoadResult over = ProjectFromJson(j.dump());
  CHECK_FALSE(over.ok());
  CHECK(over.error.find("primitives[1].segments: a cylinder may have at most " + std::to_string(kMaxPrimitiveSides) +
                        " sides; this one has 100000") != std::string::npos);
  drum["segments"] = 3000000000ull;  // past an int: still a refusal, not a wrap
  CHECK(ProjectFromJson(j.dump()).error.find("primitives[1].segments") != std::string::npos);
}

TEST_CASE("attachment chains: kMaxAttachmentDepth bases load and refresh bottom-up; one more is refused by name") {
  const Project at_limit = MakeChain(kMaxAttachmentDepth + 1);  // the top sits on kMaxAttachmentDepth boxes
  const ProjectLoadResult loaded = ProjectFromJson(ProjectToJson(at_limit));
  REQUIRE_MESSAGE(loaded.ok(), loaded.error);
  Project refreshed = loaded.project;
  // Listed top first: RefreshAllPrimitives must still place the bases before their tops.
  std::reverse(refreshed.primitives.begin(), refreshed.primitives.end());
  RefreshAllPrimitives(&refreshed);
  double bottom = 0.0;
  for (int k = 0; k <= kMaxAttachmentDepth; ++k) {
    const Primitive& box = refreshed.primitives[kMaxAttachmentDepth - k];
    CAPTURE(k);
    CHECK(AttachmentDepth(refreshed, box) == k);
    CHECK(box.shape.translation.z() == doctest::Approx(bottom).epsilon(1e-12));
    bottom += box.shape.params[2];
  }

  const Project over = MakeChain(kMaxAttachmentDepth + 2);
  const ProjectLoadResult refused = ProjectFromJson(ProjectToJson(over));
  CHECK_FALSE(refused.ok());
  CHECK(refused.error.find("primitives[" + std::to_string(kMaxAttachmentDepth + 1) +
                           "].attached_to: a primitive may sit on at most " + std::to_string(kMaxAttachmentDepth) +
                           " others") != std::string::npos);
}

TEST_CASE("a photo with more than kMaxCalibrationSegments line segments is refused by name") {
  Project p = MakeChain(1);
  for (size_t i = 0; i <= kMaxCalibrationSegments; ++i) {
    Segment s;
    s.id = p.NewId();
    s.image_id = p.images[0].id;
    s.axis = static_cast<Axis>(i % 3);
    s.a_px = {1.0 + i % 600, 2.0};
    s.b_px = {3.0 + i % 600, 400.0};
    p.segments.push_back(s);
  }
  const ProjectLoadResult over = ProjectFromJson(ProjectToJson(p));
  CHECK_FALSE(over.ok());
  CHECK(over.error.find("segments[" + std::to_string(kMaxCalibrationSegments) +
                        "].image_id: a photo may have at most " + std::to_string(kMaxCalibrationSegments) +
                        " line segments") != std::string::npos);
  p.segments.pop_back();
  const ProjectLoadResult at_limit = ProjectFromJson(ProjectToJson(p));
  REQUIRE_MESSAGE(at_limit.ok(), at_limit.error);
  CHECK(at_limit.project.segments.size() == kMaxCalibrationSegments);
}

}  // namespace
}  // namespace facet
