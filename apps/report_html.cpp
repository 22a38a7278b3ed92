#include "report_html.hpp"

#include "app_support.hpp"
#include "output_file.hpp"
#include "report/page_files.hpp"

#include "nbv/errors.hpp"
#include "nbv/grid/map_io.hpp"
#include "nbv/sensor/pinhole_camera.hpp"
#include "nbv/sensor/depth_camera.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>

namespace nbv::apps {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr std::size_t kMaxPointsPerScan = 4000;

std::string readFile(const fs::path& path, const std::string& what_if_missing) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FileError(path, "cannot read: " + what_if_missing);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

/// Rounds to 0.1 mm: the page's points need no more, and the file stays small.
double mm(double metres) { return std::round(metres * 1e4) / 1e4; }

json pageData(const Report& report) {
  const sensor::PinholeCamera camera;
  json data;
  data["title"] = report.title;
  // Half the image's extent at unit depth, for the frusta (SEMANTICS.md "Views and rays").
  data["frustum"] = {camera.cx / camera.fx, camera.cy / camera.fy};
  json views = json::array();
  for (const planner::View& v : report.views) {
    const Eigen::Vector3d p = v.T_world_camera.translation();
    const Eigen::Matrix3d r = v.T_world_camera.linear();
    views.push_back({mm(p.x()), mm(p.y()), mm(p.z()), r(0, 0), r(0, 1), r(0, 2), r(1, 0), r(1, 1), r(1, 2), r(2, 0), r(2, 1), r(2, 2)});
  }
  data["views"] = std::move(views);
  json scans = json::object();
  for (const auto& [view, points] : report.scans) {
    json flat = json::array();
    for (const Eigen::Vector3f& q : points) {
      flat.push_back(mm(q.x()));
      flat.push_back(mm(q.y()));
      flat.push_back(mm(q.z()));
    }
    scans[std::to_string(view)] = std::move(flat);
  }
  data["scans"] = std::move(scans);
  json runs = json::array();
  for (const ReportRun& run : report.runs) {
    json iterations = json::array();
    for (const planner::IterationRecord& it : run.iterations) {
      json gains = json::array();
      for (double g : it.gains) gains.push_back(std::isfinite(g) ? json(g) : json(nullptr));
      iterations.push_back({{"view", it.view}, {"coverage", it.coverage}, {"entropy_bits", it.entropy_bits},
                            {"gains", std::move(gains)}});
    }
    runs.push_back({{"label", run.label}, {"max_entropy_bits", run.max_entropy_bits}, {"iterations", std::move(iterations)}});
  }
  data["runs"] = std::move(runs);
  json voxels = json::array();
  for (const VoxelClass& c : report.voxels) {
    json flat = json::array();
    for (const Eigen::Vector3f& q : c.centres) {
      for (int a = 0; a < 3; ++a) flat.push_back(mm(q[a]));
    }
    voxels.push_back({{"name", c.name}, {"meaning", c.meaning}, {"color", {c.color[0], c.color[1], c.color[2]}},
                      {"centres", std::move(flat)}});
  }
  data["voxels"] = std::move(voxels);
  data["voxel_size"] = report.voxel_size_m;
  return data;
}

/// Text safe inside a <script> element: no "</" can close it early.
std::string scriptSafe(std::string text) {
  for (std::size_t at = text.find("</"); at != std::string::npos; at = text.find("</", at + 3)) text.replace(at, 2, "<\\/");
  return text;
}

std::string htmlEscaped(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '&') out += "&amp;";
    else if (c == '"') out += "&quot;";
    else out += c;
  }
  return out;
}

/// page.html with each {{name}} replaced by values' text for it (values are not searched again).
/// \throws std::logic_error for a name without a value: the embedded page and this file disagree.
std::string filledPage(const std::map<std::string, std::string>& values) {
  const std::string_view page = report_files::kPageHtml;
  std::string out;
  std::size_t from = 0;
  for (std::size_t at = page.find("{{"); at != std::string_view::npos; at = page.find("{{", from)) {
    const std::size_t end = page.find("}}", at);
    const std::string name(page.substr(at + 2, end == std::string_view::npos ? 0 : end - at - 2));
    const auto value = values.find(name);
    if (end == std::string_view::npos || value == values.end()) throw std::logic_error("report page: no value for {{" + name + "}}");
    out.append(page.substr(from, at - from)).append(value->second);
    from = end + 2;
  }
  return out.append(page.substr(from));
}

}  // namespace

std::string runLabel(const std::string& metric, std::uint64_t seed) { return metric + ", seed " + std::to_string(seed); }

std::string runTitle(const std::string& model, const std::string& metric, std::uint64_t seed, const std::string& scene) {
  return modelLabels({model}).front() + ": " + runLabel(metric, seed) + " (" + scene + ")";
}

namespace {

/// Adds the scan of every view the report's runs visit, `points_of(view)` giving its points,
/// thinned to every k-th so that at most kMaxPointsPerScan remain.
template <class PointsOf>
void addScansFrom(Report& report, PointsOf points_of) {
  for (const ReportRun& run : report.runs) {
    for (const planner::IterationRecord& it : run.iterations) {
      if (report.scans.count(it.view) != 0) continue;
      const std::vector<Eigen::Vector3f> all = points_of(it.view);
      const std::size_t step = all.size() / kMaxPointsPerScan + 1;
      std::vector<Eigen::Vector3f>& kept = report.scans[it.view];
      for (std::size_t i = 0; i < all.size(); i += step) kept.push_back(all[i]);
    }
  }
}

}  // namespace

void addScans(Report& report, const planner::SimulatedObject& object) {
  addScansFrom(report, [&](std::size_t view) { return object.scan(view).points_world; });
}

void addScans(Report& report, const sensor::TriangleMesh& mesh, const planner::ReconstructionConfig& config) {
  const sensor::RayScene scene(mesh, sensor::SceneOptions{config.scene.ground_plane});
  const sensor::DepthCamera camera(config.camera);
  addScansFrom(report, [&](std::size_t view) {
    const Eigen::Isometry3d& T_world_camera = report.views.at(view).T_world_camera;
    return planner::scanPoints(camera.render(scene, T_world_camera), T_world_camera, config).integrated;
  });
}

namespace {

const fs::path kThreeDir = NBV_THREE_JS_DIR;
const char* const kThreeMissing = "three.js comes from Debian's libjs-three (make deps installs it)";

}  // namespace

void requireThreeJs() {
  for (const fs::path& file : {kThreeDir / "three.min.js", kThreeDir / "examples/js/controls/OrbitControls.js"}) {
    std::error_code ec;
    if (!fs::is_regular_file(file, ec)) throw FileError(file, std::string("missing: ") + kThreeMissing);
  }
}

void writeReportHtml(const fs::path& path, const Report& report) {
  const fs::path& three_dir = kThreeDir;
  const std::string missing = kThreeMissing;
  const std::string three = readFile(three_dir / "three.min.js", missing);
  const std::string orbit = readFile(three_dir / "examples/js/controls/OrbitControls.js", missing);
  const std::string page = filledPage({{"title", htmlEscaped(report.title)},
                                       {"style", std::string(report_files::kPageCss)},
                                       {"three", scriptSafe(three)},
                                       {"orbit_controls", scriptSafe(orbit)},
                                       {"voxel_note", report.voxels.empty() ? std::string()
                                                                            : "; the map's voxels at their centres, by "
                                                                              "class (tick a class to show it)"},
                                       {"data", scriptSafe(pageData(report).dump())},
                                       {"script", std::string(report_files::kPageJs)}});
  std::ofstream out(path, std::ios::binary);
  if (!out) throw FileError(path, "cannot write");
  out << page;
  if (!out.flush()) throw FileError(path, "write failed");
}

namespace {

struct ReportCommand {
  std::string json_path;
  std::string map;
  std::string model;
  std::string viewspace;
  std::string html;
};

/// What a run's JSON holds that a report draws.
struct LoadedRun {
  ReportRun run;
  std::string model, metric, title_scene;
  std::uint64_t seed = 0;
  std::string up = "z";
  planner::SceneConditions scene;
};

/// The views of a run: its inline poses ("views", a run made in Python on an array of poses),
/// --viewspace, or its "viewspace" (dome48, or a view file found as findRunFile() says).
std::vector<planner::View> runViews(const json& run, const ReportCommand& c, const fs::path& json_dir) {
  if (!c.viewspace.empty()) return viewspace(c.viewspace);
  if (run.contains("views")) {
    std::vector<planner::View> views;
    for (const json& v : run.at("views")) {
      const std::vector<double> x = v.get<std::vector<double>>();
      if (x.size() != 7) throw InvalidArgument("views: each view is x y z qx qy qz qw");
      views.push_back(planner::viewFromPose(x[0], x[1], x[2], x[3], x[4], x[5], x[6]));
    }
    if (views.empty()) throw InvalidArgument("views: the run holds no view");
    return views;
  }
  const std::string name = run.at("viewspace").get<std::string>();
  if (name == "dome48") return viewspace(name);
  const fs::path file = findRunFile(name, json_dir);
  if (file.empty()) {
    throw FileError(c.json_path, "the run's viewspace '" + name + "' is not found (as given, beside the run, or " +
                                     "in the working folder): give it with --viewspace FILE");
  }
  return viewspace(file.string());
}

/// The run of a `nbv reconstruct --json` (or nbv.save_run) file and its views.
LoadedRun loadRun(const ReportCommand& c, std::vector<planner::View>& views) {
  json run;
  try {
    std::ifstream in(c.json_path);
    if (!in) throw FileError(c.json_path, "cannot read");
    run = json::parse(in);
  } catch (const json::exception& e) {
    throw FileError(c.json_path, std::string("not JSON: ") + e.what());
  }
  const fs::path json_dir = fs::absolute(c.json_path).parent_path();
  LoadedRun r;
  try {
    r.model = run.at("model").get<std::string>();
    const json& scene = run.at("scene");
    r.scene.ground_plane = scene.at("ground_plane").get<bool>();
    r.scene.no_return = planner::noReturnFromName(scene.at("no_return").get<std::string>());
    if (!scene.at("crop").is_null()) {
      const std::vector<double> box = scene.at("crop").get<std::vector<double>>();
      if (box.size() != 6) throw InvalidArgument("scene.crop: 6 numbers expected");
      r.scene.crop = Eigen::AlignedBox3d(Eigen::Vector3d(box[0], box[2], box[4]), Eigen::Vector3d(box[1], box[3], box[5]));
    }
    r.up = scene.at("up").get<std::string>();
    r.title_scene = scene.value("name", "bare");
    views = runViews(run, c, json_dir);
    r.metric = run.at("metric").get<std::string>();
    r.seed = run.at("seed").get<std::uint64_t>();
    r.run.label = runLabel(r.metric, r.seed);
    r.run.max_entropy_bits = run.at("max_entropy_bits").get<double>();
    for (const json& it : run.at("iterations")) {
      planner::IterationRecord record;
      record.iteration = it.at("iteration").get<std::size_t>();
      record.view = it.at("view").get<std::size_t>();
      if (record.view >= views.size()) throw InvalidArgument("view " + std::to_string(record.view) + " is outside the viewspace");
      record.coverage = it.at("coverage").get<double>();
      record.entropy_bits = it.at("entropy_bits").get<double>();
      for (const json& g : it.at("gains")) record.gains.push_back(g.is_null() ? std::nan("") : g.get<double>());
      r.run.iterations.push_back(std::move(record));
    }
  } catch (const json::exception& e) {
    throw FileError(c.json_path, std::string("not a run of nbv reconstruct --json: ") + e.what());
  } catch (const InvalidArgument& e) {
    throw FileError(c.json_path, e.what());
  }
  if (!c.model.empty()) {
    r.model = c.model;
  } else if (!isStandardModel(r.model)) {
    const fs::path file = r.model == "mesh" ? fs::path() : findRunFile(r.model, json_dir);
    if (file.empty()) {
      throw FileError(c.json_path, r.model == "mesh"
                                       ? "the run was made on an nbv.Mesh of arrays, which it cannot name: give the "
                                         "mesh file with --model PATH (placed as nbv places models, up '" + r.up + "')"
                                       : "the run's model '" + r.model + "' is not found (as given, beside the run, "
                                         "or in the working folder): give it with --model NAME|PATH");
    }
    r.model = file.string();
  }
  return r;
}

void runReport(const ReportCommand& c) {
  if (c.json_path.empty() && c.map.empty()) throw InvalidArgument("give a run's JSON, a map (--map MAP), or both");
  if (c.json_path.empty() && !c.model.empty()) throw InvalidArgument("--model re-renders a run's scans: give the run's JSON");
  checkWritable(c.html);
  requireThreeJs();
  Report report;
  std::optional<LoadedRun> run;
  if (!c.json_path.empty()) {
    run = loadRun(c, report.views);
    report.title = runTitle(run->model, run->metric, run->seed, run->title_scene);
    report.runs.push_back(run->run);
  } else if (!c.viewspace.empty()) {
    report.views = viewspace(c.viewspace);
  }
  if (!c.map.empty()) {
    const grid::OccupancyMap map = readMap(c.map);
    report.voxels = voxelClasses(map);
    report.voxel_size_m = map.lattice().resolution();
    const std::string what = "map " + fs::path(c.map).filename().string() + " (" + std::to_string(map.measuredCount()) +
                             " measured voxels)";
    report.title = report.title.empty() ? what : report.title + ", " + what;
  }
  if (run) {
    planner::ReconstructionConfig config;
    config.scene = run->scene;
    addScans(report, placedModel(run->model, run->up), config);
  }
  writeAtomically(c.html, [&](const fs::path& temporary) { writeReportHtml(temporary, report); });
  std::printf("wrote %s\n", c.html.c_str());
}

}  // namespace

void addReportCommand(CLI::App& app) {
  auto c = std::make_shared<ReportCommand>();
  CLI::App* report = app.add_subcommand(
      "report",
      "Draw a run (the JSON of nbv reconstruct --json or of Python's nbv.save_run) and/or a map as one self-contained "
      "HTML page: the scans, the candidate views coloured by their gain with a slider over the iterations, the path, "
      "the curves; a map's voxels by class.");
  report->add_option("run", c->json_path, "The run's JSON (its model and viewspace are found by name, as absolute "
                                          "paths, or beside the JSON)");
  report->add_option("--map", c->map, "A map (.vdb, .ot, .bt) whose voxels to draw by class: occupied, uncertain, free, "
                                      "marked, frontier");
  report->add_option("--model", c->model, "The run's model, instead of the one its JSON names (a standard name or a mesh file)");
  report->add_option("--viewspace,--views", c->viewspace, "The run's views instead of those its JSON names, or the views "
                                                          "to draw with --map: dome48 or a view file");
  report->add_option("--html", c->html, "Output HTML (opens from a file:// URL, no network; -: standard output)")->required();
  report->callback([c] { runReport(*c); });
}

}  // namespace nbv::apps
