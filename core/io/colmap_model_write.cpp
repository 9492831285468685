#include "core/io/colmap_model_write.h"

#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <set>
#include <utility>

#include "core/io/camera_export.h"
#include "core/io/colmap_camera.h"
#include "core/util/file_write.h"

namespace facet {
namespace {

std::string Number(double x) {
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.17g", x);
  return buffer;
}

std::string FileNameOf(const std::string& path) { return std::filesystem::path(path).filename().string(); }

// images.txt ends an image's line with its name, the rest of the line with blanks at its ends
// cut (COLMAP's reader and ours): a name must not start or end with one, nor break the line.
bool NameFitsImagesText(const std::string& name) {
  auto blank = [](char c) { return c == ' ' || c == '\t'; };
  if (blank(name.front()) || blank(name.back())) return false;
  for (char c : name)
    if (c == '\n' || c == '\r') return false;
  return true;
}

}  // namespace

std::string ColmapModelFromProject(const Project& project, const ColmapExportOptions& options, ColmapModel* model) {
  *model = {};
  ColmapModel out;
  std::map<Id, size_t> image_index;  // Facet image id -> index into out.images
  std::set<std::string> names;
  std::vector<const Image*> exported;
  const std::string not_exportable = ImagesForCameraExport(project, &exported);
  if (!not_exportable.empty()) return not_exportable;
  for (const Image* exported_image : exported) {
    const Image& image = *exported_image;
    if (image.id > std::numeric_limits<std::uint32_t>::max())
      return "image " + std::to_string(image.id) + ": its id does not fit COLMAP's 32-bit image ids";
    const std::uint32_t id = static_cast<std::uint32_t>(image.id);
    ColmapImage colmap_image;
    colmap_image.image_id = id;
    colmap_image.camera_id = id;
    colmap_image.name = FileNameOf(image.path);
    if (colmap_image.name.empty()) return "image " + std::to_string(image.id) + " has no file name";
    if (!NameFitsImagesText(colmap_image.name))
      return "photo \"" + colmap_image.name +
             "\": its file name starts or ends with a blank or holds a line break, which images.txt cannot hold";
    if (!names.insert(colmap_image.name).second)
      return "two photos are named \"" + colmap_image.name + "\": COLMAP's images are told apart by file name";
    colmap_image.cam_from_world_rotation = Eigen::Quaterniond(image.camera.cam_from_world_rotation);
    colmap_image.cam_from_world_translation = image.camera.cam_from_world_translation;
    out.cameras.push_back(ColmapCameraFromFacet(image.camera, id));
    image_index[image.id] = out.images.size();
    out.images.push_back(std::move(colmap_image));
  }
  if (options.include_points) {
    // Pins by vertex, so that each vertex's track lists them in project order.
    std::map<std::pair<Id, VertexId>, std::vector<const Pin*>> pins_of_vertex;
    for (const Pin& pin : project.pins)
      if (image_index.count(pin.image_id) && project.FindVertex(pin.vertex))
        pins_of_vertex[{pin.vertex.primitive_id, pin.vertex.vertex}].push_back(&pin);
    std::uint64_t next_point_id = 1;
    for (const Primitive& primitive : project.primitives)
      for (VertexId v = 0; v < primitive.mesh.VertexIdEnd(); ++v) {
        if (!primitive.mesh.IsVertex(v)) continue;
        ColmapPoint3D point;
        point.point3d_id = next_point_id++;
        point.position = primitive.mesh.vertex(v).position;
        point.rgb[0] = point.rgb[1] = point.rgb[2] = 200;
        double error_sum = 0.0;
        const auto it = pins_of_vertex.find({primitive.id, v});
        if (it != pins_of_vertex.end())
          for (const Pin* pin : it->second) {
            ColmapImage& colmap_image = out.images[image_index.at(pin->image_id)];
            ColmapPoint2D point2d;
            point2d.xy_px = ColmapPixelFromFacet(pin->uv_px);
            point2d.point3d_id = point.point3d_id;
            point.track.push_back({colmap_image.image_id, static_cast<std::uint32_t>(colmap_image.points2d.size())});
            colmap_image.points2d.push_back(point2d);
            error_sum += (project.FindImage(pin->image_id)->camera.Project(point.position) - pin->uv_px).norm();
          }
        // COLMAP's error of a point is the mean reprojection error over its track.
        point.error_px = point.track.empty() ? -1.0 : error_sum / point.track.size();
        out.points3d.push_back(std::move(point));
      }
  }
  *model = std::move(out);
  return "";
}

std::string FormatColmapCamerasText(const ColmapModel& model) {
  std::string text =
      "# Camera list with one line of data per camera:\n"
      "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
      "# Number of cameras: " +
      std::to_string(model.cameras.size()) + "\n";
  for (const ColmapCamera& camera : model.cameras) {
    text += std::to_string(camera.camera_id) + " " + ColmapCameraModelName(camera.model) + " " +
            std::to_string(camera.width_px) + " " + std::to_string(camera.height_px);
    for (double p : camera.params) text += " " + Number(p);
    text += "\n";
  }
  return text;
}

std::string FormatColmapImagesText(const ColmapModel& model) {
  size_t observations = 0;
  for (const ColmapImage& image : model.images) observations += image.points2d.size();
  std::string text =
      "# Image list with two lines of data per image:\n"
      "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
      "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
      "# Number of images: " +
      std::to_string(model.images.size()) + ", mean observations per image: " +
      std::to_string(model.images.empty() ? 0.0 : static_cast<double>(observations) / model.images.size()) + "\n";
  for (const ColmapImage& image : model.images) {
    const Eigen::Quaterniond& q = image.cam_from_world_rotation;
    const Eigen::Vector3d& t = image.cam_from_world_translation;
    text += std::to_string(image.image_id) + " " + Number(q.w()) + " " + Number(q.x()) + " " + Number(q.y()) + " " +
            Number(q.z()) + " " + Number(t.x()) + " " + Number(t.y()) + " " + Number(t.z()) + " " +
            std::to_string(image.camera_id) + " " + image.name + "\n";
    for (size_t k = 0; k < image.points2d.size(); ++k) {
      const ColmapPoint2D& p = image.points2d[k];
      text += (k ? " " : "") + Number(p.xy_px.x()) + " " + Number(p.xy_px.y()) + " " +
              (p.point3d_id == kColmapNoPoint3D ? std::string("-1") : std::to_string(p.point3d_id));
    }
    text += "\n";
  }
  return text;
}

std::string FormatColmapPoints3DText(const ColmapModel& model) {
  size_t track_elements = 0;
  for (const ColmapPoint3D& point : model.points3d) track_elements += point.track.size();
  std::string text =
      "# 3D point list with one line of data per point:\n"
      "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
      "# Number of points: " +
      std::to_string(model.points3d.size()) + ", mean track length: " +
      std::to_string(model.points3d.empty() ? 0.0 : static_cast<double>(track_elements) / model.points3d.size()) + "\n";
  for (const ColmapPoint3D& point : model.points3d) {
    text += std::to_string(point.point3d_id) + " " + Number(point.position.x()) + " " + Number(point.position.y()) +
            " " + Number(point.position.z()) + " " + std::to_string(point.rgb[0]) + " " + std::to_string(point.rgb[1]) +
            " " + std::to_string(point.rgb[2]) + " " + Number(point.error_px);
    for (const ColmapTrackElement& element : point.track)
      text += " " + std::to_string(element.image_id) + " " + std::to_string(element.point2d_index);
    text += "\n";
  }
  return text;
}

std::string WriteColmapModelText(const std::string& dir, const ColmapModel& model) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return "cannot create the folder " + dir + ": " + ec.message();
  const std::filesystem::path folder(dir);
  // Each file is replaced atomically, not the three together: what would stop the second or
  // third (a folder or a device under its name) is looked for before the first is written.
  for (const char* name : {"cameras.txt", "images.txt", "points3D.txt"}) {
    const std::filesystem::path path = folder / name;
    if (std::filesystem::is_symlink(path, ec)) continue;  // followed by the write, as a user's Save is
    const std::string what = DescribeNonRegular(path.string());
    if (!what.empty()) return path.string() + " is " + what + "; nothing written";
  }
  const std::pair<const char*, std::string (*)(const ColmapModel&)> files[] = {
      {"cameras.txt", FormatColmapCamerasText},
      {"images.txt", FormatColmapImagesText},
      {"points3D.txt", FormatColmapPoints3DText}};
  std::string written;
  for (const auto& [name, format] : files) {
    const std::string error = WriteFileAtomically((folder / name).string(), format(model));
    if (!error.empty())
      return error + (written.empty() ? "; nothing written" : "; only " + written + " written (the model is mixed)");
    written += (written.empty() ? "" : " and ") + std::string(name);
  }
  return "";
}

}  // namespace facet
