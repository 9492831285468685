// A stand-in for the colmap program, for tests that run COLMAP's pipeline (core/io/colmap_run.h,
// the app's File > Cameras from all photos) without COLMAP's minutes: a shell script that
// answers the three stages RunColmap calls. feature_extractor and the matchers succeed at once
// (or sleep first, to leave time for a cancel or a picture of the progress); mapper "writes" a
// prepared text model (cameras.txt, images.txt, points3D.txt, e.g. from WriteColmapModelText)
// into its --output_path as sparse model 0, which ReadColmapModel accepts as COLMAP's own.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>

namespace facet::testing {

struct FakeColmapOptions {
  std::string model_dir;  // the text model the mapper copies into OUTPUT/0
  // The stage that sleeps (feature_extractor, exhaustive_matcher, mapper; "" for none) and
  // for how long, in seconds.
  std::string slow_stage;
  double sleep_s = 0.0;
  int mapper_exit_code = 0;  // non-zero: the mapper fails (nothing written)
};

// Writes the script at `path` (made executable) and returns its path as a string.
inline std::string WriteFakeColmap(const std::filesystem::path& path, const FakeColmapOptions& options) {
  std::ofstream script(path);
  script << "#!/bin/sh\n"
            "# Facet's test stand-in for colmap (tests/fake_colmap.h)\n"
            "stage=\"$1\"\n"
            "echo \"fake colmap: $*\"\n";
  if (!options.slow_stage.empty())
    script << "if [ \"$stage\" = '" << options.slow_stage << "' ]; then sleep " << options.sleep_s << "; fi\n";
  script << "case \"$stage\" in\n"
            "  feature_extractor|exhaustive_matcher|sequential_matcher) exit 0 ;;\n"
            "  mapper)\n"
            "    out=''\n"
            "    while [ $# -gt 0 ]; do\n"
            "      if [ \"$1\" = --output_path ]; then out=\"$2\"; fi\n"
            "      shift\n"
            "    done\n"
            "    [ -n \"$out\" ] || exit 3\n";
  if (options.mapper_exit_code != 0) script << "    exit " << options.mapper_exit_code << "\n";
  script << "    mkdir -p \"$out/0\" || exit 4\n"
            "    cp '"
         << options.model_dir << "/cameras.txt' '" << options.model_dir << "/images.txt' '" << options.model_dir
         << "/points3D.txt' \"$out/0/\" || exit 5\n"
            "    exit 0 ;;\n"
            "  *) echo \"fake colmap: unknown command $stage\" >&2; exit 2 ;;\n"
            "esac\n";
  script.close();
  std::filesystem::permissions(path, std::filesystem::perms::owner_all);
  return path.string();
}

}  // namespace facet::testing
