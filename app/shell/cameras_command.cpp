#include "app/shell/cameras_command.h"

#include <filesystem>
#include <iostream>

#include <Eigen/Geometry>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "app/state/colmap_cameras.h"
#include "core/io/colmap_import.h"
#include "core/io/colmap_run.h"
#include "core/io/project_io.h"

namespace facet::app {

nlohmann::json ColmapAlignmentJson(const ColmapAlignmentSummary& alignment) {
  const SimilarityTransform& t = alignment.project_from_reconstruction;
  const Eigen::AngleAxisd turn(t.rotation);
  return {{"message", alignment.message},
          {"warnings", alignment.warnings},
          {"rotation", {{"source", AlignmentSourceName(alignment.rotation_source)}, {"note", alignment.rotation_note}}},
          {"scale", {{"source", AlignmentSourceName(alignment.scale_source)}, {"note", alignment.scale_note}}},
          {"position", {{"source", AlignmentSourceName(alignment.position_source)}, {"note", alignment.position_note}}},
          {"project_from_reconstruction",
           {{"scale", t.scale},
            {"rotation_angle_axis",
             {turn.angle() * turn.axis().x(), turn.angle() * turn.axis().y(), turn.angle() * turn.axis().z()}},
            {"translation", {t.translation.x(), t.translation.y(), t.translation.z()}}}},
          {"common_images", alignment.common_images},
          {"num_line_families", alignment.num_line_families},
          {"num_known_lengths", alignment.num_known_lengths},
          {"center_rms", alignment.center_rms},
          {"rotation_rms_deg", alignment.rotation_rms_deg},
          {"center_fit_rotation_deg", alignment.center_fit_rotation_deg},
          {"chosen_turns", alignment.chosen_turns}};
}

CLI::App* AddCamerasSubcommand(CLI::App* cli, CamerasCommandArgs* args) {
  CLI::App* cameras =
      cli->add_subcommand("cameras",
                          "Cameras for every photo of a project from COLMAP (structure from motion, run on the CPU); "
                          "writes the project with them and prints a JSON summary");
  cameras->add_option("project", args->project_path, "Project file (*.facet)")->required()->check(CLI::ExistingFile);
  cameras->add_option("-o,--output", args->output_path, "Where to write the project with the cameras")->required();
  args->options.colmap = ColmapExecutableFromEnvironment();
  cameras->add_option("--colmap", args->options.colmap, "The colmap program (default: $FACET_COLMAP, else colmap)")
      ->capture_default_str();
  cameras
      ->add_option("--work-dir", args->options.work_dir,
                   "COLMAP's working folder (its database, models and log); default: OUT's folder/OUT-stem.colmap")
      ->capture_default_str();
  cameras
      ->add_option("--max-image-size", args->options.max_image_size_px,
                   "Features are found on the photos scaled to at most this many pixels on the longer side")
      ->check(CLI::Range(64, 20000))
      ->capture_default_str();
  cameras->add_option("--threads", args->options.num_threads, "Threads COLMAP may use (-1: all)")
      ->capture_default_str();
  cameras->add_flag("--single-camera", args->options.single_camera,
                    "All photos were taken with one camera and lens at one focal setting");
  return cameras;
}

int RunCamerasCommand(const std::string& project_path, const std::string& output_path,
                      const CamerasCommandOptions& options) {
  namespace fs = std::filesystem;
  if (output_path.empty()) {
    std::cerr << "facet cameras: the output path (-o) is empty\n";
    return 1;
  }
  ProjectLoadResult loaded = LoadProject(project_path);
  if (!loaded.ok()) {
    std::cerr << "facet cameras: cannot open " << project_path << ": " << loaded.error << "\n";
    return 1;
  }
  for (const std::string& w : loaded.warnings) std::cerr << "facet cameras: warning: " << w << "\n";
  Project project = std::move(loaded.project);

  ColmapRunOptions run;
  run.colmap_executable = options.colmap;
  run.max_image_size_px = options.max_image_size_px;
  run.num_threads = options.num_threads;
  run.single_camera = options.single_camera;
  const fs::path output(output_path);
  run.working_dir = options.work_dir.empty() ? (output.parent_path() / (output.stem().string() + ".colmap")).string()
                                             : options.work_dir;
  for (const Image& image : project.images) run.photo_paths.push_back(ResolveImagePath(project_path, image.path));
  run.progress = [](ColmapStage stage, int step, int num_steps) {
    if (step > 0) std::cerr << "facet cameras: " << step << "/" << num_steps << " " << ColmapStageName(stage) << "\n";
  };
  const ColmapRunSummary summary = RunColmap(run);

  nlohmann::json out{{"termination", SolverTerminationName(summary.termination)},
                     {"message", summary.message},
                     {"warnings", summary.warnings},
                     {"stage_reached", ColmapStageName(summary.stage_reached)},
                     {"num_registered", summary.num_registered},
                     {"num_photos", project.images.size()},
                     {"time_ms", summary.time_ms},
                     {"log", summary.log_path}};
  nlohmann::json stage_times = nlohmann::json::object();
  for (int s = 0; s < kNumColmapStages; ++s)
    stage_times[ColmapStageName(static_cast<ColmapStage>(s))] = summary.stage_time_ms[s];
  out["stage_time_ms"] = stage_times;
  if (!summary.IsUsable()) {
    std::cout << out.dump(2) << "\n";
    std::cerr << "facet cameras: " << summary.message << "; " << output_path << " was not written\n";
    return 1;
  }
  ColmapImportReport report;
  ColmapAlignmentSummary alignment;
  const std::string error =
      ApplyAlignedColmapCameras(summary.model, ColmapAlignmentOptions{}, &project, &report, &alignment);
  if (!error.empty()) {
    std::cout << out.dump(2) << "\n";
    std::cerr << "facet cameras: " << error << "; " << output_path << " was not written\n";
    return 1;
  }
  out["updated_images"] = report.updated_images;
  out["photos_not_placed"] = report.missing_photos;
  out["alignment"] = ColmapAlignmentJson(alignment);
  std::cerr << "facet cameras: aligned to the project: " << alignment.message << "\n";
  for (const std::string& w : alignment.warnings) std::cerr << "facet cameras: warning: " << w << "\n";
  RebaseImagePaths(project_path, output_path, &project);
  const std::string save_error = SaveProject(project, output_path);
  if (!save_error.empty()) {
    std::cerr << "facet cameras: cannot write " << output_path << ": " << save_error << "\n";
    return 1;
  }
  std::cout << out.dump(2) << "\n";
  return 0;
}

}  // namespace facet::app
