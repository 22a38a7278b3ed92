#include "sensor_commands.hpp"

#include "app_support.hpp"
#include "output_file.hpp"

#include "nbv/errors.hpp"
#include "nbv/planner/reconstruction.hpp"
#include "nbv/planner/viewspace.hpp"
#include "nbv/sensor/depth_camera.hpp"
#include "nbv/sensor/depth_io.hpp"
#include "nbv/sensor/mesh.hpp"
#include "nbv/sensor/models.hpp"
#include "nbv/sensor/point_cloud_io.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace nbv::apps {

namespace {

namespace fs = std::filesystem;


/// 8-bit grey picture of a depth image: near = bright (255), far = dim (32), no hit = black.
void writeDepthPicture(const fs::path& path, const sensor::DepthScan& scan) {
  float near = 0.0f, far = 0.0f;
  bool any = false;
  for (const float d : scan.depth_m) {
    if (d <= 0.0f) continue;
    near = any ? std::min(near, d) : d;
    far = any ? std::max(far, d) : d;
    any = true;
  }
  std::vector<std::uint8_t> pixels(scan.depth_m.size(), 0);
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const float d = scan.depth_m[i];
    if (d <= 0.0f) continue;
    const float t = far > near ? (d - near) / (far - near) : 0.0f;
    pixels[i] = static_cast<std::uint8_t>(255.0f - t * (255.0f - 32.0f));
  }
  sensor::writeGreyPng8(path, scan.width, scan.height, pixels);
}

/// The 16-bit depth image of a scan: 5000 values per metre (TUM RGB-D), 0 where no hit.
sensor::DepthPng depth16(const sensor::DepthScan& scan) {
  constexpr double kScale = 5000.0;
  sensor::DepthPng image{scan.width, scan.height, std::vector<std::uint16_t>(scan.depth_m.size(), 0)};
  for (std::size_t i = 0; i < scan.depth_m.size(); ++i) {
    if (scan.depth_m[i] > 0.0f) {
      image.values[i] = static_cast<std::uint16_t>(std::min(65535.0, std::round(scan.depth_m[i] * kScale)));
    }
  }
  return image;
}

struct RenderOptions {
  std::string model;
  std::optional<int> view_index;
  std::string viewspace = "dome48";
  std::string out;
  std::string depth_png;
  std::string depth_png16;
  std::string tum_out;
  SceneFlags scene;
};

void runRender(const RenderOptions& o) {
  if (o.tum_out.empty() == !o.view_index.has_value()) {
    throw InvalidArgument("give --view-index I (one view, --out) or --tum-out DIR (every view of --viewspace)");
  }
  if (o.view_index && o.out.empty()) throw InvalidArgument("--view-index needs --out");
  for (const std::string& path : {o.out, o.depth_png, o.depth_png16}) {
    if (!path.empty()) checkWritable(path);
  }
  const auto views = viewspace(o.viewspace);
  if (o.view_index && (*o.view_index < 0 || static_cast<std::size_t>(*o.view_index) >= views.size())) {
    throw InvalidArgument("--view-index " + std::to_string(*o.view_index) + " is outside the viewspace's " +
                          std::to_string(views.size()) + " views");
  }
  const fs::path mesh_path = sensor::resolveModel(o.model);
  sensor::MeshLoadReport report;
  sensor::TriangleMesh mesh = sensor::loadMesh(mesh_path, &report);
  sensor::normalizeMesh(mesh, {sensor::upAxisFor(o.model, upOf(o.scene))});
  planner::ReconstructionConfig config;  // the camera and the scene a reconstruction would use
  config.scene = sceneOf(o.scene);
  const sensor::RayScene scene(mesh, sensor::SceneOptions{config.scene.ground_plane});
  const sensor::DepthCamera camera(config.camera);
  if (!o.tum_out.empty()) {  // every view, as a TUM RGB-D folder
    std::vector<sensor::DepthPng> depths;
    std::vector<Eigen::Isometry3d> poses;
    for (const planner::View& view : views) {
      depths.push_back(depth16(camera.render(scene, view.T_world_camera)));
      poses.push_back(view.T_world_camera);
    }
    sensor::writeTumSequence(o.tum_out, depths, poses);
    std::cout << mesh_path.string() << ": " << views.size() << " views -> " << o.tum_out
              << " (depth.txt, groundtruth.txt, depth/*.png at 5000 per metre)\n";
    return;
  }
  const Eigen::Isometry3d& T_world_camera = views[static_cast<std::size_t>(*o.view_index)].T_world_camera;
  const sensor::DepthScan scan = camera.render(scene, T_world_camera);
  // The cloud integrates into the map a reconstruction would build: cropped, with no-return points.
  const planner::ScanPoints points = planner::scanPoints(scan, T_world_camera, config);
  writeAtomically(o.out, [&](const fs::path& temporary) { sensor::writePlyCloud(temporary, points.integrated); });
  if (!o.depth_png.empty()) {
    writeAtomically(o.depth_png, [&](const fs::path& temporary) { writeDepthPicture(temporary, scan); });
  }
  if (!o.depth_png16.empty()) {
    const sensor::DepthPng image = depth16(scan);
    writeAtomically(o.depth_png16, [&](const fs::path& temporary) {
      sensor::writeDepthPng16(temporary, image.width, image.height, image.values);
    });
  }
  const Eigen::Vector3d origin = T_world_camera.translation();
  const Eigen::Quaterniond q(T_world_camera.linear());
  std::cout << mesh_path.string() << ": " << mesh.triangles.size() << " triangles ("
            << report.degenerate_dropped << " degenerate dropped), view " << *o.view_index << ": "
            << points.integrated.size() << " points (" << points.on_object.size() << " on the object) -> " << o.out << '\n'
            << "origin: " << origin.x() << ' ' << origin.y() << ' ' << origin.z() << '\n'
            << "pose: " << origin.x() << ' ' << origin.y() << ' ' << origin.z() << ' ' << q.x() << ' ' << q.y() << ' '
            << q.z() << ' ' << q.w() << '\n';
}

struct ViewspaceOptions {
  std::string kind;
  std::size_t count = 48;
  double radius = 0.6;
  std::vector<double> target{0.0, 0.0, 0.25};
  std::optional<double> min_z;
  std::string out;
};

void runViewspace(const ViewspaceOptions& o) {
  checkWritable(o.out);
  std::vector<planner::View> views;
  if (o.kind == "dome48") {
    views = planner::dome48();
  } else {
    views = planner::fibonacciSphere(o.count, o.radius, Eigen::Vector3d(o.target[0], o.target[1], o.target[2]));
  }
  if (o.min_z) views = planner::viewsAbove(views, *o.min_z);
  if (views.empty()) throw InvalidArgument("--min-z " + nbv::numberText(*o.min_z) + " leaves no view");
  writeAtomically(o.out, [&](const fs::path& temporary) { planner::saveViews(temporary, views); });
  std::cout << views.size() << " views -> " << o.out << '\n';
}

struct ModelsOptions {
  std::string dir;
  std::string from;
};

/// `nbv models`: each standard model and the file it resolves to, or that it is missing, and
/// where models are looked for.
void listModels() {
  const std::vector<fs::path> search = sensor::modelSearchPath();
  std::size_t missing = 0;
  for (const sensor::StandardModel& model : sensor::standardModels()) {
    std::string where;
    try {
      where = sensor::resolveModel(model.name, search).string();
    } catch (const MeshFileError&) {
      where = "missing (" + model.file + ")";
      ++missing;
    }
    std::printf("%-16s %s\n", model.name.c_str(), where.c_str());
  }
  std::printf("looked for in:");
  for (const fs::path& dir : search) std::printf(" %s", dir.c_str());
  std::printf("%s\n", std::getenv("NBV_MODELS_DIR") != nullptr ? " (NBV_MODELS_DIR)" : "");
  if (missing > 0) std::printf("%zu missing: `nbv models fetch` puts them in %s\n", missing, sensor::userModelsDir().c_str());
}

void fetchModels(const ModelsOptions& o) {
  const fs::path dir = o.dir.empty() ? sensor::userModelsDir() : fs::path(o.dir);
  std::error_code ec;
  const auto missing = std::count_if(sensor::standardModels().begin(), sensor::standardModels().end(),
                                     [&](const sensor::StandardModel& m) { return !fs::is_regular_file(dir / m.file, ec); });
  if (missing > 0) {
    std::printf("fetching %td standard models from Debian's libcgal-demo (its data archive; nothing is installed)\n", missing);
    std::fflush(stdout);
  }
  const sensor::FetchReport report = sensor::fetchStandardModels({dir, o.from});
  if (report.written.empty()) {
    std::printf("every standard model is in %s\n", report.dir.c_str());
  } else {
    std::printf("wrote %zu models to %s (from %s)\n", report.written.size(), report.dir.c_str(), report.source.c_str());
  }
}

}  // namespace

void addSensorCommands(CLI::App& app) {
  auto m = std::make_shared<ModelsOptions>();
  CLI::App* models = app.add_subcommand(
      "models", "List the standard models and where they are found; `nbv models fetch` fetches them.");
  CLI::App* fetch = models->add_subcommand(
      "fetch", "Put the 11 standard meshes in the user's data folder ($XDG_DATA_HOME/nbv/models, or NBV_MODELS_DIR) "
               "from the data archive of Debian's libcgal-demo (downloaded with apt-get download, not installed)");
  fetch->add_option("--dir", m->dir, "The folder to write instead (then point NBV_MODELS_DIR at it)");
  fetch->add_option("--from", m->from, "A libcgal-demo .deb or its data.tar.gz already at hand (no download)");
  fetch->callback([m] { fetchModels(*m); });
  models->callback([models] {
    if (models->get_subcommands().empty()) listModels();
  });

  auto render_options = std::make_shared<RenderOptions>();
  CLI::App* render = app.add_subcommand(
      "render", "Render what the ideal depth camera sees of a model from one view (world-frame cloud).");
  render->add_option("--model", render_options->model,
                     "A standard model (" + standardModelNames() + ") or a mesh file (OFF, PLY, OBJ, STL)")
      ->required();
  render->add_option("--view-index", render_options->view_index, "Index of the view in the viewspace");
  render->add_option("--viewspace,--views", render_options->viewspace, "dome48 (default) or a view file");
  render->add_option("--out", render_options->out, "Output cloud (binary PLY) of --view-index");
  render->add_option("--depth-png", render_options->depth_png, "Also write the depth image as a picture (near = bright)");
  render->add_option("--depth-png16", render_options->depth_png16,
                     "Also write the depth image as a 16-bit PNG, 5000 per metre (TUM RGB-D), 0 where no hit");
  render->add_option("--tum-out", render_options->tum_out,
                     "Instead of one view: every view of --viewspace as a TUM RGB-D folder (depth.txt, groundtruth.txt, "
                     "depth/*.png), the input of `nbv integrate --tum`");
  addSceneOptions(*render, render_options->scene, false);
  render->callback([render_options] { runRender(*render_options); });

  auto v = std::make_shared<ViewspaceOptions>();
  CLI::App* viewspace_cmd =
      app.add_subcommand("viewspace", "Write a viewspace as a view file (N, then x y z qx qy qz qw per view).");
  viewspace_cmd->add_option("--kind", v->kind, "dome48 (the paper's 48 views) or fibonacci (a sphere of --count views)")
      ->required()
      ->check(CLI::IsMember({"dome48", "fibonacci"}));
  viewspace_cmd->add_option("--count", v->count, "fibonacci: number of views on the sphere")
      ->check(CLI::Range(std::size_t{1}, nbv::planner::kMaxFibonacciViews))
      ->capture_default_str();
  viewspace_cmd->add_option("--radius", v->radius, "fibonacci: sphere radius [m]")->check(positiveNumber())->capture_default_str();
  viewspace_cmd->add_option("--target", v->target, "fibonacci: the point every view looks at, X Y Z [m]")
      ->expected(3)
      ->check(finiteNumber())
      ->capture_default_str();
  viewspace_cmd->add_option("--min-z", v->min_z, "Leave out views whose position lies below this height [m] "
                                                  "(e.g. 0: none below the object's base)")
      ->check(finiteNumber());
  viewspace_cmd->add_option("--out", v->out, "Output view file (-: standard output)")->required();
  viewspace_cmd->callback([v] { runViewspace(*v); });
}

}  // namespace nbv::apps
