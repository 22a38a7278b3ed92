#include "sensor_commands.hpp"

#include "app_support.hpp"
#include "output_file.hpp"

#include "nbv/errors.hpp"
#include "nbv/planner/reconstruction.hpp"
#include "nbv/planner/viewspace.hpp"
#include "nbv/sensor/depth_camera.hpp"
#include "nbv/sensor/mesh.hpp"
#include "nbv/sensor/point_cloud_io.hpp"

#include <CLI/CLI.hpp>
#include <png.h>

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace nbv::apps {

namespace {

namespace fs = std::filesystem;


/// 8-bit grey PNG of a depth image: near = bright (255), far = dim (32), no hit = black.
void writeDepthPng(const fs::path& path, const sensor::DepthScan& scan) {
  float near = 0.0f, far = 0.0f;
  bool any = false;
  for (const float d : scan.depth_m) {
    if (d <= 0.0f) continue;
    near = any ? std::min(near, d) : d;
    far = any ? std::max(far, d) : d;
    any = true;
  }
  std::vector<png_byte> pixels(scan.depth_m.size(), 0);
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const float d = scan.depth_m[i];
    if (d <= 0.0f) continue;
    const float t = far > near ? (d - near) / (far - near) : 0.0f;
    pixels[i] = static_cast<png_byte>(255.0f - t * (255.0f - 32.0f));
  }
  std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "wb"), &std::fclose);
  if (!file) throw nbv::FileError(path, "cannot open for writing");
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png != nullptr ? png_create_info_struct(png) : nullptr;
  if (png == nullptr || info == nullptr || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    throw nbv::FileError(path, "cannot write PNG");
  }
  png_init_io(png, file.get());
  png_set_IHDR(png, info, static_cast<png_uint_32>(scan.width), static_cast<png_uint_32>(scan.height), 8,
               PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int v = 0; v < scan.height; ++v) {
    png_write_row(png, pixels.data() + static_cast<std::size_t>(v) * static_cast<std::size_t>(scan.width));
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
}

struct RenderOptions {
  std::string model;
  int view_index = 0;
  std::string viewspace = "dome48";
  std::string out;
  std::string depth_png;
  SceneFlags scene;
};

void runRender(const RenderOptions& o) {
  checkWritable(o.out);
  if (!o.depth_png.empty()) checkWritable(o.depth_png);
  const auto views = viewspace(o.viewspace);
  if (o.view_index < 0 || static_cast<std::size_t>(o.view_index) >= views.size()) {
    throw InvalidArgument("--view-index " + std::to_string(o.view_index) + " is outside the viewspace's " +
                                std::to_string(views.size()) + " views");
  }
  const fs::path mesh_path = sensor::resolveModel(o.model, modelsDir());
  sensor::MeshLoadReport report;
  sensor::TriangleMesh mesh = sensor::loadMesh(mesh_path, &report);
  sensor::normalizeMesh(mesh, {sensor::upAxisFor(o.model, o.scene.up)});
  planner::ReconstructionConfig config;  // the camera and the scene a reconstruction would use
  config.scene = sceneOf(o.scene);
  const Eigen::Isometry3d& T_world_camera = views[static_cast<std::size_t>(o.view_index)].T_world_camera;
  const sensor::RayScene scene(mesh, sensor::SceneOptions{config.scene.ground_plane});
  const sensor::DepthScan scan = sensor::DepthCamera(config.camera).render(scene, T_world_camera);
  // The cloud integrates into the map a reconstruction would build: cropped, with no-return points.
  const planner::ScanPoints points = planner::scanPoints(scan, T_world_camera, config);
  writeAtomically(o.out, [&](const fs::path& temporary) { sensor::writePlyCloud(temporary, points.integrated); });
  if (!o.depth_png.empty()) {
    writeAtomically(o.depth_png, [&](const fs::path& temporary) { writeDepthPng(temporary, scan); });
  }
  const Eigen::Vector3d origin = views[static_cast<std::size_t>(o.view_index)].T_world_camera.translation();
  std::cout << mesh_path.string() << ": " << mesh.triangles.size() << " triangles ("
            << report.degenerate_dropped << " degenerate dropped), view " << o.view_index << ": "
            << points.integrated.size() << " points (" << points.on_object.size() << " on the object) -> " << o.out << '\n'
            << "origin: " << origin.x() << ' ' << origin.y() << ' ' << origin.z() << '\n';
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
  if (views.empty()) throw InvalidArgument("--min-z " + std::to_string(*o.min_z) + " leaves no view");
  writeAtomically(o.out, [&](const fs::path& temporary) { planner::saveViews(temporary, views); });
  std::cout << views.size() << " views -> " << o.out << '\n';
}

}  // namespace

void addSensorCommands(CLI::App& app) {
  auto render_options = std::make_shared<RenderOptions>();
  CLI::App* render = app.add_subcommand(
      "render", "Render what the ideal depth camera sees of a model from one view (world-frame cloud).");
  render->add_option("--model", render_options->model,
                     "A standard model (" + standardModelNames() + ") or a mesh file (OFF, PLY, OBJ, STL)")
      ->required();
  render->add_option("--view-index", render_options->view_index, "Index of the view in the viewspace")->required();
  render->add_option("--viewspace", render_options->viewspace, "dome48 (default) or a view file");
  render->add_option("--out", render_options->out, "Output cloud (binary PLY)")->required();
  render->add_option("--depth-png", render_options->depth_png, "Also write the depth image (near = bright)");
  addSceneOptions(*render, render_options->scene, false);
  render->callback([render_options] { runRender(*render_options); });

  auto v = std::make_shared<ViewspaceOptions>();
  CLI::App* viewspace_cmd =
      app.add_subcommand("viewspace", "Write a viewspace as a view file (N, then x y z qx qy qz qw per view).");
  viewspace_cmd->add_option("--kind", v->kind, "dome48 (the paper's 48 views) or fibonacci (a sphere of --count views)")
      ->required()
      ->check(CLI::IsMember({"dome48", "fibonacci"}));
  viewspace_cmd->add_option("--count", v->count, "fibonacci: number of views on the sphere")
      ->check(CLI::Range(std::size_t{1}, std::size_t{10000000}))
      ->capture_default_str();
  viewspace_cmd->add_option("--radius", v->radius, "fibonacci: sphere radius [m]")->check(positiveNumber())->capture_default_str();
  viewspace_cmd->add_option("--target", v->target, "fibonacci: the point every view looks at, X Y Z [m]")
      ->expected(3)
      ->check(finiteNumber())
      ->capture_default_str();
  viewspace_cmd->add_option("--min-z", v->min_z, "Leave out views whose position lies below this height [m] "
                                                  "(e.g. 0: none below the object's base)")
      ->check(finiteNumber());
  viewspace_cmd->add_option("--out", v->out, "Output view file")->required();
  viewspace_cmd->callback([v] { runViewspace(*v); });
}

}  // namespace nbv::apps
