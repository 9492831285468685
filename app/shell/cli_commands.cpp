#include "app/shell/cli_commands.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include <nlohmann/json.hpp>

#include "app/platform/egl_context.h"
#include "app/platform/gltf_camera_render.h"
#include "app/state/calgui_exif_prior.h"
#include "app/state/texture_choices.h"
#include "core/image/image_io.h"
#include "core/io/blender_script.h"
#include "core/io/calibrate_io.h"
#include "core/io/calibrate_points_io.h"
#include "core/io/colmap_model_write.h"
#include "core/io/export.h"
#include "core/io/gltf_read.h"
#include "core/io/project_io.h"
#include "core/io/relate_io.h"
#include "core/io/transforms_json.h"
#include "core/solve/joint_solve.h"
#include "core/solve/model_update.h"
#include "core/texture/textured_mesh.h"
#include "core/util/project_lock.h"

namespace facet::app {
namespace {

bool LoadForCli(const std::string& path, Project* project) {
  ProjectLoadResult loaded = LoadProject(path);
  if (!loaded.ok()) {
    std::cerr << "facet: cannot open " << path << ": " << loaded.error << "\n";
    return false;
  }
  for (const std::string& w : loaded.warnings) std::cerr << "facet: warning: " << w << "\n";
  *project = std::move(loaded.project);
  return true;
}

// "A,B": two finite numbers.
bool ParsePair(const std::string& text, double* a, double* b) {
  const size_t comma = text.find(',');
  if (comma == std::string::npos) return false;
  try {
    size_t used_a = 0, used_b = 0;
    *a = std::stod(text.substr(0, comma), &used_a);
    *b = std::stod(text.substr(comma + 1), &used_b);
    return used_a == comma && used_b == text.size() - comma - 1 && std::isfinite(*a) && std::isfinite(*b);
  } catch (...) {
    return false;
  }
}

// Pretty JSON for stdout. Messages may quote paths, which are bytes: one that is not UTF-8
// is printed with U+FFFD instead of making dump() throw (nlohmann's error 316).
template <typename Json>
std::string DumpForPrinting(const Json& doc) {
  return doc.dump(2, ' ', false, Json::error_handler_t::replace);
}

// JSON has no NaN: pins that took no part in the solve are written as null.
nlohmann::json NumberOrNull(double value) { return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(); }

}  // namespace

int RunCalibrateCommand(const std::string& lines_path, const std::string& points_path) {
  const CalibrateIoResult result =
      lines_path.empty() ? CalibratePointsFile(points_path) : CalibrateLinesFile(lines_path);
  if (!result.ok()) {
    std::cerr << "facet calibrate: " << result.error << "\n";
    return 1;
  }
  std::cout << result.json << "\n";
  return 0;
}

int RunCalibrateImageCommand(const std::string& photo_path, const std::string& principal_point,
                             const std::string& focal_prior, double focal_px) {
  CalibrateImageOptions options;
  if (principal_point == "solve") {
    options.principal_point_mode = PrincipalPointMode::kSolve;
  } else if (principal_point == "center") {
    options.principal_point_mode = PrincipalPointMode::kImageCenter;
  } else if (double cx, cy; ParsePair(principal_point, &cx, &cy)) {
    options.principal_point_mode = PrincipalPointMode::kFixed;
    options.fixed_principal_point_px = {cx, cy};
  } else {
    std::cerr << "facet calibrate: --principal-point must be solve, center or CX,CY, got '" << principal_point << "'\n";
    return 1;
  }
  if (focal_px != 0.0 && !(focal_px > 0.0 && std::isfinite(focal_px))) {
    std::cerr << "facet calibrate: --focal must be a positive number of px\n";
    return 1;
  }
  options.focal_px = focal_px;
  if (focal_px > 0.0 || focal_prior == "none") {
    // no prior
  } else if (focal_prior == "exif") {
    int width = 0, height = 0;
    std::string error;
    if (!ReadImageSize(photo_path, &width, &height, &error)) {
      std::cerr << "facet calibrate: " << error << "\n";
      return 1;
    }
    const ExifFocalPrior prior = ExifFocalPriorFrom(ReadExifFocalFromFile(photo_path, width, height));
    if (prior.found) {
      options.focal_prior_px = prior.focal_px;
      options.focal_prior_std_px = prior.std_px;
    }
    options.focal_prior_source = prior.message;  // says "No EXIF focal length: ..." when there is none
  } else if (double f, std_px; ParsePair(focal_prior, &f, &std_px) && f > 0.0 && std_px > 0.0) {
    options.focal_prior_px = f;
    options.focal_prior_std_px = std_px;
    options.focal_prior_source = "given on the command line";
  } else {
    std::cerr << "facet calibrate: --focal-prior must be exif, none or F,STD (px, both positive), got '" << focal_prior
              << "'\n";
    return 1;
  }
  const CalibrateIoResult result = CalibrateImageFile(photo_path, options);
  if (!result.ok()) {
    std::cerr << "facet calibrate: " << result.error << "\n";
    return 1;
  }
  std::cout << result.json << "\n";
  return 0;
}

int RunRelateCommand(const std::string& matches_path) {
  const RelateIoResult result = RelateMatchesFile(matches_path);
  if (!result.ok()) {
    std::cerr << "facet relate: " << result.error << "\n";
    return 1;
  }
  std::cout << result.json << "\n";
  return 0;
}

int RunSolveCommand(const std::string& project_path, const std::string& output_path) {
  if (output_path.empty()) {
    std::cerr << "facet solve: the output path (-o) is empty\n";
    return 1;
  }
  // A project open in a Facet is that Facet's to write (core/util/project_lock.h): refused
  // before solving. The lock is held until the file is written.
  ProjectLockResult output_lock = TryLockProject(output_path);
  if (output_lock.holder) {
    std::cerr << "facet solve: cannot write " << output_path << ": "
              << DescribeLockHolder(output_path, *output_lock.holder) << "; close it there or write another file\n";
    return 1;
  }
  Project project;
  if (!LoadForCli(project_path, &project)) return 1;
  ModelUpdateOptions options;
  options.solve.warm_start = false;  // a command-line solve starts from the linear initialisation
  Project updated;
  const ModelUpdateSummary update = UpdateModel(project, options, &updated);
  const SceneSolveSummary& geometry = update.solve;
  const JointSolveSummary& joint = update.joint;
  // The joint solve, when it ran, made the saved result (cameras and geometry together, as the
  // app's status shows); the geometry solve before it only gave it a start. The top level
  // gives the figures of the solve whose result is saved, "solver" says which, and both
  // solves' figures follow under their own names.
  const bool joint_ran = joint.termination != SolverTermination::kInvalidInput || !joint.message.empty();
  auto figures = [](const SolverSummary& summary, double rms_px, double max_px, int num_residuals,
                    int num_parameters) {
    return nlohmann::json{{"termination", SolverTerminationName(summary.termination)},
                          {"message", summary.message},
                          {"iterations", summary.iterations},
                          {"initial_cost", summary.initial_cost},
                          {"final_cost", summary.final_cost},
                          {"reprojection_rms_px", rms_px},
                          {"reprojection_max_px", max_px},
                          {"num_residuals", num_residuals},
                          {"num_parameters", num_parameters},
                          {"time_ms", summary.time_ms}};
  };
  const nlohmann::json geometry_figures =
      figures(geometry, geometry.reprojection_rms_px, geometry.reprojection_max_px, geometry.num_residuals,
              geometry.num_parameters);
  const nlohmann::json joint_figures = figures(joint, joint.reprojection_rms_px, joint.reprojection_max_px,
                                               joint.num_residuals, joint.num_parameters);
  nlohmann::json out = joint_ran ? joint_figures : geometry_figures;
  out["solver"] = joint_ran ? "joint" : "geometry";
  out["update_time_ms"] = update.time_ms;
  nlohmann::json pins = nlohmann::json::array();
  if (joint_ran) {
    for (const PinDiagnostic& pin : joint.pins) pins.push_back(NumberOrNull(pin.error_px));
  } else {
    for (double r : geometry.pin_residuals_px) pins.push_back(NumberOrNull(r));
  }
  out["pin_residuals_px"] = pins;
  out["warnings"] = joint_ran ? joint.warnings : geometry.warnings;
  out["held_parameters"] = geometry.held_parameters;
  if (joint_ran) {
    out["undetermined"] = joint.undetermined;
    out["conflicts"] = joint.conflicts;
  }
  out["geometry_solve"] = geometry_figures;
  if (joint_ran) out["joint_solve"] = joint_figures;
  nlohmann::json calibration = nlohmann::json::array();
  for (const auto& [image_id, vp] : update.calibration) {
    calibration.push_back({{"image_id", image_id},
                           {"success", vp.IsUsable()},
                           {"message", vp.message},
                           {"incomplete", vp.incomplete},
                           {"focal_px", vp.focal_px},
                           {"principal_point", {vp.principal_point_px.x(), vp.principal_point_px.y()}},
                           {"warnings", vp.warnings}});
  }
  out["calibration"] = calibration;
  out["messages"] = update.messages;
  out["progress"] = update.progress;

  // The figures printed at the top level are the saved result's: a joint solve that failed
  // (its message says the model is unchanged) is a failed command whatever the geometry solve
  // gave, so nothing is written and the exit code says so.
  const bool joint_failed = joint_ran && joint.termination == SolverTermination::kFailed;
  const bool usable = update.ok && !joint_failed;
  if (usable) {
    // Image paths are relative to the project file: keep them valid for the output's folder
    // (with error codes: a path the OS refuses is reported by the save, not thrown).
    RebaseImagePaths(project_path, output_path, &updated);
    const std::string error = SaveProject(updated, output_path);
    if (!error.empty()) {
      std::cerr << "facet solve: cannot write " << output_path << ": " << error << "\n";
      return 1;
    }
  }
  std::cout << DumpForPrinting(out) << "\n";
  if (!usable) {
    std::cerr << "facet solve: the solve failed; " << output_path << " was not written\n";
    return 1;
  }
  return 0;
}

namespace {

// What `facet export` writes: --format, else the output's name tells.
std::string ExportFormatOf(const std::string& format, const std::string& output_path, std::string* error) {
  std::string ext = std::filesystem::path(output_path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if ((format == "glb" || format == "obj") && ext != "." + format) {
    *error = "--format " + format + " writes FILE." + format + ", not '" + output_path + "'";
    return "";
  }
  if (!format.empty()) return format;
  if (ext == ".glb") return "glb";
  if (ext == ".obj") return "obj";
  if (ext == ".json") return "transforms";
  std::error_code ec;
  if ((!output_path.empty() && output_path.back() == '/') || std::filesystem::is_directory(output_path, ec))
    return "colmap";
  *error = "cannot tell the format from '" + output_path +
           "': use FILE.glb or FILE.obj (the model), transforms.json (the cameras for nerfstudio), or a folder "
           "FOLDER/ or --format colmap (the cameras as a COLMAP text model)";
  return "";
}

// The calibrated cameras, without the texture: nothing to bake, no photo read.
int ExportCameras(const Project& project, const std::string& project_path, const std::string& output_path,
                  const std::string& format) {
  if (format == "colmap") {
    ColmapModel model;
    std::string error = ColmapModelFromProject(project, {}, &model);
    if (!error.empty()) error += "; nothing written";
    if (error.empty()) error = WriteColmapModelText(output_path, model);  // says what it wrote on failure
    if (!error.empty()) {
      std::cerr << "facet export: " << error << "\n";
      return 1;
    }
    const std::filesystem::path folder(output_path);
    for (const char* file : {"cameras.txt", "images.txt", "points3D.txt"})
      std::cout << (folder / file).string() << "\n";
    return 0;
  }
  const std::string error = WriteTransformsJson(project, project_path, output_path);
  if (!error.empty()) {
    std::cerr << "facet export: " << error << "; nothing written\n";
    return 1;
  }
  std::cout << output_path << "\n";
  return 0;
}

}  // namespace

int RunExportCommand(const std::string& project_path, const std::string& output_path, const std::string& format_option,
                     const std::string& blender_script_path, double texels_per_unit) {
  std::string format_error;
  const std::string format = ExportFormatOf(format_option, output_path, &format_error);
  if (format.empty()) {
    std::cerr << "facet export: " << format_error << "\n";
    return 1;
  }
  const bool cameras_only = format == "colmap" || format == "transforms";
  if (cameras_only && (!blender_script_path.empty() || texels_per_unit > 0.0)) {
    std::cerr << "facet export: --blender-script and --texels-per-unit go with a model (.glb, .obj), not with the "
                 "cameras alone ("
              << format << ")\n";
    return 1;
  }
  Project project;
  if (!LoadForCli(project_path, &project)) return 1;
  if (cameras_only) return ExportCameras(project, project_path, output_path, format);
  // Each photo is read once and baked in place (the bake takes pointers, copies no pixels).
  std::vector<ImageRgba8> photos(project.images.size());
  std::vector<const ImageRgba8*> photo_pointers(project.images.size(), nullptr);
  for (size_t i = 0; i < project.images.size(); ++i) {
    const std::string photo_path = ResolveImagePath(project_path, project.images[i].path);
    ImageReadResult read = ReadImage(photo_path);
    if (!read.ok()) {
      std::cerr << "facet export: warning: " << read.error << " (its faces stay untextured)\n";
      continue;
    }
    // Another photo under the image's name (open warned): its pixels are not the camera's.
    const std::string other_photo =
        WhyPhotoIsNotTheImages(project.images[i], photo_path, read.image.width, read.image.height);
    if (!other_photo.empty()) {
      std::cerr << "facet export: warning: " << other_photo << " (its faces stay untextured)\n";
      continue;
    }
    photos[i] = std::move(read.image);
    photo_pointers[i] = &photos[i];
  }
  TexturedMesh mesh;
  // The exporters write every atlas page (the 3D panel draws one page, so the app keeps one):
  // faces that overflow an 8192 page go to more pages before any is shrunk.
  TextureBakeOptions bake_options;
  bake_options.max_atlas_pages = kExportAtlasPages;
  bake_options.texels_per_unit = texels_per_unit;
  std::string option_error;
  if (!bake_options.Check(&option_error)) {
    std::cerr << "facet export: --texels-per-unit: " << option_error << "\n";
    return 1;
  }
  const TextureBakeSummary bake = BakeTexturedMesh(project, photo_pointers, bake_options, &mesh);
  if (!bake.IsUsable()) {
    std::cerr << "facet export: texture: " << bake.message << "\n";
    mesh = BuildUntexturedMesh(project);
  } else if (texels_per_unit > 0.0) {
    std::cerr << "facet export: texture: " << bake.message << "\n";
  }
  const ExportSummary exported = format == "glb" ? ExportGlb(mesh, project, output_path) : ExportObj(mesh, output_path);
  if (!exported.success) {
    std::cerr << "facet export: " << exported.message << "\n";
    return 1;
  }
  for (const std::string& f : exported.files_written) std::cout << f << "\n";
  if (!blender_script_path.empty()) {
    std::error_code ec;
    const std::string model = std::filesystem::absolute(output_path, ec).lexically_normal().string();
    const std::string error =
        WriteFileAtomically(blender_script_path, BlenderSetupScript(project, project_path, ec ? output_path : model));
    if (!error.empty()) {
      std::cerr << "facet export: " << error << "\n";
      return 1;
    }
    std::cout << blender_script_path << "\n";
  }
  return 0;
}

int RunRenderGlbCommand(const std::string& glb_path, int camera_index, const std::string& output_png) {
  GltfScene scene;
  const std::string read_error = ReadGlb(glb_path, GltfReadOptions(), &scene);
  if (!read_error.empty()) {
    std::cerr << "facet render-glb: " << read_error << "\n";
    return 1;
  }
  if (scene.cameras.empty()) {
    std::cerr << "facet render-glb: " << glb_path << " has no camera node to look through\n";
    return 1;
  }
  EglContext egl;
  std::string error;
  if (!egl.Create(&error)) {
    std::cerr << "facet render-glb: " << error << "\n";
    return 1;
  }
  ImageRgba8 shot;
  if (!RenderGltfThroughCamera(scene, camera_index, &shot, &error)) {
    std::cerr << "facet render-glb: " << glb_path << ": " << error << "\n";
    return 1;
  }
  error = WritePng(output_png, shot);
  if (!error.empty()) {
    std::cerr << "facet render-glb: " << error << "\n";
    return 1;
  }
  const GltfCamera& camera = scene.cameras[camera_index];
  nlohmann::ordered_json out = {
      {"output", output_png},
      {"camera", camera_index},
      {"name", camera.name},
      {"size_px", {shot.width, shot.height}},
      {"focal_px", camera.camera.focal_px},
      {"principal_point_px", {camera.camera.principal_point_px.x(), camera.camera.principal_point_px.y()}},
      {"principal_point_from_extras", camera.has_principal_point}};
  std::cout << DumpForPrinting(out) << "\n";
  return 0;
}

}  // namespace facet::app
