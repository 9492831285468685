// The project file (core/io/project_io.h): any bytes either load or are refused with a
// message and an empty project. A project that loads must be savable, the saved text must
// load back equal (the format promises exact round trips), and saving that again must give
// the same text.
#include <cstddef>
#include <cstdint>
#include <string>

#include "core/io/project_io.h"
#include "tests/fuzz/fuzz_check.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using facet::fuzz::Fail;
  constexpr const char* kTarget = "fuzz_project";
  const std::string text(reinterpret_cast<const char*>(data), size);
  const facet::ProjectLoadResult loaded = facet::ProjectFromJson(text);
  if (!loaded.ok()) {
    if (!(loaded.project == facet::Project())) Fail(kTarget, "a refused file left a project: " + loaded.error);
    return 0;
  }
  const std::string unsavable = facet::CheckProjectSavable(loaded.project);
  if (!unsavable.empty()) Fail(kTarget, "a loaded project cannot be saved: " + unsavable);
  const std::string saved = facet::ProjectToJson(loaded.project);
  const facet::ProjectLoadResult reloaded = facet::ProjectFromJson(saved);
  if (!reloaded.ok()) Fail(kTarget, "the saved text does not load: " + reloaded.error + "\n" + saved);
  if (!(reloaded.project == loaded.project)) Fail(kTarget, "the saved text loads back different:\n" + saved);
  if (facet::ProjectToJson(reloaded.project) != saved) Fail(kTarget, "saving the reloaded project changes the text");
  return 0;
}
