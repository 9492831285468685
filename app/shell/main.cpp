// facet: one executable for the GUI and the command line (calibrate, relate, solve, export,
// render).
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <iostream>
#include <string>

#include <unistd.h>
#include <CLI/CLI.hpp>

#include "app/shell/app.h"
#include "app/shell/cameras_command.h"
#include "app/shell/cli_commands.h"

namespace {

// The bundled sample, what a new user sees first: the Leuven street the tutorial builds
// (assets/samples/leuven/tutorial.txt), next to the executable in an install, else in the
// source tree.
std::string SampleProjectPath() {
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  const std::filesystem::path candidates[] = {
      exe.parent_path() / "../share/facet/samples/leuven/street.facet",
      std::filesystem::path(FACET_SOURCE_DIR) / "assets/samples/leuven/street.facet",
  };
  for (const auto& c : candidates)
    if (std::filesystem::exists(c, ec)) return std::filesystem::weakly_canonical(c, ec).string();
  return {};
}

bool ParseSize(const std::string& text, int* width, int* height) {
  const size_t x = text.find('x');
  if (x == std::string::npos) return false;
  try {
    *width = std::stoi(text.substr(0, x));
    *height = std::stoi(text.substr(x + 1));
  } catch (...) {
    return false;
  }
  return *width >= 64 && *height >= 64 && *width <= 16384 && *height <= 16384;
}

int Run(int argc, char** argv) {
  CLI::App cli{
      "Facet: interactive image-based modeling. Turn ordinary photos into a textured 3D model.\n"
      "Without a command, opens the GUI on PROJECT (or the bundled sample)."};
  cli.require_subcommand(0, 1);

  std::string gui_project;
  cli.add_option("project", gui_project, "Project file (*.facet) to open in the GUI");

  auto* calibrate = cli.add_subcommand(
      "calibrate",
      "Calibrate one camera from line families, from the lines detected on a photo, or from known 3D points; prints "
      "the camera as JSON");
  std::string lines_path, points_path;
  auto* lines_option =
      calibrate
          ->add_option("--lines", lines_path,
                       "LINES.json: {\"image_size\": [w, h], \"families\": [{\"axis\": \"x\", \"segments\": "
                       "[[x1, y1, x2, y2], ...]}, ...], \"principal_point\": \"solve\" | \"center\" | [cx, cy]}")
          ->check(CLI::ExistingFile);
  auto* points_option =
      calibrate
          ->add_option("--points", points_path,
                       "POINTS.json: {\"image_size\": [w, h], \"points\": [{\"xyz\": [X, Y, Z], \"uv\": [u, v]}, "
                       "...], \"distortion\": 0 | 1 | 2, \"focal_px\": F (optional: a known focal length, pose only)} "
                       "(6+ points, or 4+ on one plane)")
          ->check(CLI::ExistingFile);
  std::string image_path, principal_point = "solve", focal_prior = "exif";
  double known_focal_px = 0.0;
  auto* image_option =
      calibrate
          ->add_option("--image", image_path,
                       "PHOTO.jpg: detect the line families on the photo and calibrate them; prints the --lines "
                       "camera JSON plus the families found (\"lines\", a LINES.json)")
          ->check(CLI::ExistingFile);
  auto* pp_option =
      calibrate->add_option("--principal-point", principal_point, "With --image: solve | center | CX,CY (px)")
          ->capture_default_str();
  auto* prior_option =
      calibrate
          ->add_option("--focal-prior", focal_prior,
                       "With --image: exif (the photo's EXIF focal length, +- ~3 %) | none | F,STD (px)")
          ->capture_default_str();
  auto* focal_option =
      calibrate->add_option("--focal", known_focal_px, "With --image: a known focal length in px (not solved)");
  lines_option->excludes(points_option);
  image_option->excludes(lines_option)->excludes(points_option);
  for (auto* option : {pp_option, prior_option, focal_option}) option->needs(image_option);
  focal_option->excludes(prior_option);
  calibrate->require_option(1, 4);

  auto* relate = cli.add_subcommand(
      "relate", "Two-view geometry from matches: fundamental matrix, and relative pose when K is known; prints JSON");
  std::string matches_path;
  relate
      ->add_option("--matches", matches_path,
                   "MATCHES.json: {\"image_sizes\": [[w, h], [w, h]], \"matches\": [[u1, v1, u2, v2], ...], "
                   "\"K\": [K1, K2] (optional)}")
      ->required()
      ->check(CLI::ExistingFile);

  auto* solve =
      cli.add_subcommand("solve", "Re-calibrate and re-solve a project; writes the result and prints a JSON summary");
  std::string solve_project, solve_out;
  solve->add_option("project", solve_project, "Project file (*.facet)")->required()->check(CLI::ExistingFile);
  solve->add_option("-o,--output", solve_out, "Where to write the solved project")->required();

  auto* exporter = cli.add_subcommand(
      "export",
      "Export the textured model as binary glTF (.glb) or OBJ + MTL + PNG, or the calibrated cameras as a COLMAP "
      "text model or a nerfstudio / instant-ngp transforms.json");
  std::string export_project, export_out, export_format;
  exporter->add_option("project", export_project, "Project file (*.facet)")->required()->check(CLI::ExistingFile);
  exporter
      ->add_option("-o,--output", export_out,
                   "FILE.glb or FILE.obj (the model); transforms.json (any NAME.json: the cameras for nerfstudio, "
                   "photo paths relative to its folder); FOLDER/ (the cameras as COLMAP's cameras.txt, images.txt "
                   "and points3D.txt: the model's vertices, their pins as tracks; the folder is created)")
      ->required();
  exporter
      ->add_option("--format", export_format,
                   "glb | obj | colmap | transforms (default: from the output's name: .glb, .obj, .json, a "
                   "folder)")
      ->check(CLI::IsMember({"glb", "obj", "colmap", "transforms"}));
  std::string blender_script;
  exporter->add_option("--blender-script", blender_script,
                       "Also write a Blender Python script: imports the model, adds each photo's camera "
                       "(focal length, principal-point shift, pose) with the photo as background");
  double texels_per_unit = 0.0;
  exporter
      ->add_option("--texels-per-unit", texels_per_unit,
                   "Texture resolution in texels per project unit (per metre for a project in m), capped by the "
                   "8192 atlas page; 0 (default): from the photos, one texel per photo pixel of the face's best view")
      ->check(CLI::NonNegativeNumber);

  auto* render_glb = cli.add_subcommand(
      "render-glb", "Render a .glb through one of its camera nodes offscreen (EGL) to an RGBA PNG, as a glTF viewer "
                    "looking through it shows it (the principal point from the camera's extras when there)");
  std::string render_glb_path, render_glb_out;
  int render_glb_camera = 0;
  render_glb->add_option("model", render_glb_path, "FILE.glb")->required()->check(CLI::ExistingFile);
  render_glb->add_option("-o,--output", render_glb_out, "SHOT.png (alpha 0 where no triangle is)")->required();
  render_glb->add_option("--camera", render_glb_camera, "Camera node, 0-based in node order")->capture_default_str();

  auto* render = cli.add_subcommand("render", "Render the application offscreen (EGL, no display needed) to a PNG");
  facet::app::RenderOptions render_options;
  std::string render_size = "1600x900";
  render
      ->add_option("project", render_options.project_path,
                   "Project file (*.facet); without it, the bundled sample the GUI opens")
      ->check(CLI::ExistingFile);
  render->add_option("-o,--output", render_options.output_png, "SHOT.png")->required();
  render->add_option("--size", render_size, "Window size WxH in pixels")->capture_default_str();
  render
      ->add_option("--script", render_options.script_path,
                   "Input script: mouse, keys and app commands, one per line (see README)")
      ->check(CLI::ExistingFile);
  render->add_option("--report", render_options.report_path,
                     "Also write a JSON report: panel rectangles, image view transform, history, project");
  render->add_flag("--autosave", render_options.autosave,
                   "Autosave to a recovery file and offer recovery at start, as the GUI does (default: off, so "
                   "renders never write beside a project)");
  render->add_flag("--no-snap", [&](std::int64_t) { render_options.snapping = false; },
                   "Start with the image panel's Snap option off (points land where the mouse goes)");
  render
      ->add_option("--panel", render_options.panel,
                   "Write only this panel, with its overlays, its canvas --size large: image | 3d (File > Export "
                   "view)")
      ->check(CLI::IsMember({"image", "3d"}));
  render->add_option("--config-dir", render_options.config_dir,
                     "Read and keep recent files in this folder (default: none, so renders never touch the "
                     "user's settings)");

  facet::app::CamerasCommandArgs cameras_args;
  auto* cameras = facet::app::AddCamerasSubcommand(&cli, &cameras_args);

  CLI11_PARSE(cli, argc, argv);

  if (*calibrate && !image_path.empty())
    return facet::app::RunCalibrateImageCommand(image_path, principal_point, focal_prior, known_focal_px);
  if (*calibrate) return facet::app::RunCalibrateCommand(lines_path, points_path);
  if (*relate) return facet::app::RunRelateCommand(matches_path);
  if (*solve) return facet::app::RunSolveCommand(solve_project, solve_out);
  if (*exporter)
    return facet::app::RunExportCommand(export_project, export_out, export_format, blender_script, texels_per_unit);
  if (*cameras)
    return facet::app::RunCamerasCommand(cameras_args.project_path, cameras_args.output_path, cameras_args.options);
  if (*render_glb) return facet::app::RunRenderGlbCommand(render_glb_path, render_glb_camera, render_glb_out);
  if (*render) {
    if (render_options.project_path.empty()) render_options.project_path = SampleProjectPath();
    if (render_options.project_path.empty()) {
      std::cerr << "facet render: no project given and the bundled sample is not installed\n";
      return 1;
    }
    if (!ParseSize(render_size, &render_options.width, &render_options.height)) {
      std::cerr << "facet render: --size must be WxH, e.g. 1600x900 (64..16384 each)\n";
      return 1;
    }
    return facet::app::RunOffscreen(render_options);
  }

  facet::app::GuiOptions gui;
  gui.project_path = gui_project.empty() ? SampleProjectPath() : gui_project;
  if (!gui_project.empty() && !std::filesystem::exists(gui_project)) {
    std::cerr << "facet: no such project file: " << gui_project << "\n";
    return 1;
  }
  return facet::app::RunGui(gui);
}

// The last line of defence: an exception that escaped every layer (nlohmann's error 316 on a
// path that is not UTF-8 did) becomes a message and exit code 1, never an abort. Layers below
// still turn bad input into messages themselves; reaching this is a bug to report.
void ExitOnUncaught() {
  std::string what = "an unknown exception";
  if (const std::exception_ptr current = std::current_exception()) {
    try {
      std::rethrow_exception(current);
    } catch (const std::exception& e) {
      what = e.what();
    } catch (...) {
    }
  }
  std::cerr << "facet: internal error (please report it): " << what << "\n";
  std::cout.flush();
  std::_Exit(1);
}

}  // namespace

int main(int argc, char** argv) {
  std::set_terminate(ExitOnUncaught);  // exceptions escaping a worker thread, too
  try {
    return Run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "facet: internal error (please report it): " << e.what() << "\n";
  } catch (...) {
    std::cerr << "facet: internal error (please report it): an unknown exception\n";
  }
  return 1;
}
