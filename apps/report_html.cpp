#include "report_html.hpp"

#include "app_support.hpp"
#include "output_file.hpp"

#include "nbv/errors.hpp"
#include "nbv/grid/map_io.hpp"
#include "nbv/kernels/pinhole_camera.hpp"
#include "nbv/sensor/depth_camera.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <memory>
#include <set>
#include <sstream>
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
  const kernels::PinholeCamera camera;
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

// The page: a three.js view (orbit with the mouse), a run selector, a slider over the
// iterations, and a canvas of the curves. Iteration k shows the scans 1..k, the path through
// their views, and each candidate coloured by the gain it was given after scan k (visited views
// grey); the view chosen next carries a sphere. #status reads "rendered" once the first frame
// is drawn, or the error that stopped the page.
constexpr const char* kPageScript = R"JS(
(function () {
  'use strict';
  const status = document.getElementById('status');
  window.addEventListener('error', function (e) { status.textContent = 'error: ' + e.message; });
  const data = NBV_DATA;
  const viridis = [[68, 1, 84], [59, 82, 139], [33, 145, 140], [94, 201, 98], [253, 231, 37]];
  function colormap(t) {
    t = Math.min(1, Math.max(0, t)) * 4;
    const k = Math.min(3, Math.floor(t)), f = t - k;
    return viridis[k].map(function (c, i) { return (c + f * (viridis[k + 1][i] - c)) / 255; });
  }
  const canvas = document.getElementById('view');
  const renderer = new THREE.WebGLRenderer({canvas: canvas, antialias: true, preserveDrawingBuffer: true});
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0xf7f7f7);
  const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 50);
  camera.up.set(0, 0, 1);
  camera.position.set(1.3, -1.5, 1.2);
  const controls = new THREE.OrbitControls(camera, canvas);
  controls.target.set(0, 0, 0.2);
  controls.update();
  const grid = new THREE.GridHelper(1.2, 12, 0xbbbbbb, 0xdddddd);
  grid.rotation.x = Math.PI / 2;
  scene.add(grid);

  // Frusta of every view: 8 segments each, coloured per iteration.
  const [fx, fy] = data.frustum, depth = 0.07;
  const frustumPositions = [], apexes = [];
  data.views.forEach(function (v) {
    const p = new THREE.Vector3(v[0], v[1], v[2]);
    const axes = [new THREE.Vector3(v[3], v[6], v[9]), new THREE.Vector3(v[4], v[7], v[10]), new THREE.Vector3(v[5], v[8], v[11])];
    const corners = [[-1, -1], [1, -1], [1, 1], [-1, 1]].map(function (s) {
      return p.clone().addScaledVector(axes[0], s[0] * fx * depth).addScaledVector(axes[1], s[1] * fy * depth).addScaledVector(axes[2], depth);
    });
    for (let k = 0; k < 4; ++k) {
      frustumPositions.push(p, corners[k], corners[k], corners[(k + 1) % 4]);
    }
    apexes.push(p);
  });
  const frustumGeometry = new THREE.BufferGeometry().setFromPoints(frustumPositions);
  const frustumColors = new Float32Array(frustumPositions.length * 3).fill(0.55);
  frustumGeometry.setAttribute('color', new THREE.BufferAttribute(frustumColors, 3));
  scene.add(new THREE.LineSegments(frustumGeometry, new THREE.LineBasicMaterial({vertexColors: THREE.VertexColors})));

  // A map's voxels by class: a point cloud and a checkbox each (free space starts hidden).
  let voxelCount = 0;
  data.voxels.forEach(function (c) {
    if (c.centres.length === 0) return;
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.Float32BufferAttribute(c.centres, 3));
    const color = new THREE.Color(c.color[0] / 255, c.color[1] / 255, c.color[2] / 255);
    const cloud = new THREE.Points(g, new THREE.PointsMaterial({size: data.voxel_size, color: color}));
    cloud.visible = c.name !== 'free';
    scene.add(cloud);
    voxelCount += c.centres.length / 3;
    const label = document.createElement('label');
    const box = document.createElement('input');
    box.type = 'checkbox';
    box.checked = cloud.visible;
    box.addEventListener('change', function () { cloud.visible = box.checked; render(); });
    label.style.color = '#' + color.getHexString();
    label.appendChild(box);
    label.appendChild(document.createTextNode(' ' + c.name + ' (' + c.meaning + '): ' + c.centres.length / 3 + ' \u00a0 '));
    document.getElementById('classes').appendChild(label);
  });

  const pathMaterial = new THREE.LineBasicMaterial({color: 0x111111});
  let path = null, points = null;
  const next = new THREE.Mesh(new THREE.SphereGeometry(0.018, 16, 12), new THREE.MeshBasicMaterial({color: 0x111111}));
  scene.add(next);

  const runSelect = document.getElementById('run');
  data.runs.forEach(function (run, i) {
    const option = document.createElement('option');
    option.value = i;
    option.textContent = run.label;
    runSelect.appendChild(option);
  });
  const slider = document.getElementById('iteration');
  const info = document.getElementById('info');

  function show() {
    const run = data.runs[+runSelect.value];
    const its = run.iterations;
    slider.max = its.length;
    const k = Math.min(+slider.value, its.length);
    // The scans 1..k, each in its own hue.
    const positions = [], colors = [];
    for (let i = 0; i < k; ++i) {
      const scan = data.scans[its[i].view] || [];
      const c = new THREE.Color().setHSL((0.55 + i * 0.137) % 1, 0.65, 0.45);
      for (let j = 0; j < scan.length; j += 3) {
        positions.push(scan[j], scan[j + 1], scan[j + 2]);
        colors.push(c.r, c.g, c.b);
      }
    }
    if (points) scene.remove(points);
    const g = new THREE.BufferGeometry();
    g.setAttribute('position', new THREE.Float32BufferAttribute(positions, 3));
    g.setAttribute('color', new THREE.Float32BufferAttribute(colors, 3));
    points = new THREE.Points(g, new THREE.PointsMaterial({size: 0.006, vertexColors: THREE.VertexColors}));
    scene.add(points);
    // The path through the views scanned so far.
    if (path) scene.remove(path);
    path = new THREE.Line(new THREE.BufferGeometry().setFromPoints(its.slice(0, k).map(function (it) { return apexes[it.view]; })), pathMaterial);
    scene.add(path);
    // Candidates by the gains after scan k; visited views grey.
    const gains = k >= 1 ? its[k - 1].gains : [];
    const finite = gains.filter(function (x) { return x !== null; });
    const lo = Math.min.apply(null, finite), hi = Math.max.apply(null, finite);
    const visited = new Set(its.slice(0, k).map(function (it) { return it.view; }));
    for (let v = 0; v < data.views.length; ++v) {
      const g = gains[v];
      const c = visited.has(v) || g === null || g === undefined ? [0.55, 0.55, 0.55] : colormap(hi > lo ? (g - lo) / (hi - lo) : 1);
      for (let j = 0; j < 16; ++j) frustumColors.set(c, (v * 16 + j) * 3);
    }
    frustumGeometry.attributes.color.needsUpdate = true;
    next.visible = k < its.length;
    if (next.visible) next.position.copy(apexes[its[k].view]);
    const now = its[k - 1];
    info.textContent = 'scan ' + k + ' of ' + its.length + ': view ' + now.view + ', coverage ' + now.coverage.toFixed(3) +
        ', entropy ' + (now.entropy_bits / run.max_entropy_bits).toFixed(4) + ' of the empty map' +
        (k < its.length ? '; next view ' + its[k].view : '');
    drawCurves(run, k);
    render();
  }

  function drawCurves(run, k) {
    const c = document.getElementById('curves'), ctx = c.getContext('2d');
    const w = c.width, h = c.height, m = 30;
    ctx.clearRect(0, 0, w, h);
    ctx.strokeStyle = '#999';
    ctx.strokeRect(m, 10, w - m - 10, h - m - 10);
    const n = run.iterations.length;
    const x = function (i) { return m + (w - m - 10) * i / n; };
    const y = function (v) { return 10 + (h - m - 10) * (1 - v); };
    function curve(values, color, label, row) {
      ctx.strokeStyle = color;
      ctx.beginPath();
      values.forEach(function (v, i) { if (i === 0) ctx.moveTo(x(i), y(v)); else ctx.lineTo(x(i), y(v)); });
      ctx.stroke();
      ctx.fillStyle = color;
      ctx.fillText(label, m + 8, 24 + 14 * row);
    }
    curve([0].concat(run.iterations.map(function (it) { return it.coverage; })), '#1f77b4', 'coverage', 0);
    // Entropy on its own scale, from its lowest value (bottom) to the empty map's (top).
    const entropy = [1].concat(run.iterations.map(function (it) { return it.entropy_bits / run.max_entropy_bits; }));
    const low = Math.min.apply(null, entropy);
    curve(entropy.map(function (e) { return low < 1 ? (e - low) / (1 - low) : 1; }), '#ff7f0e',
          'entropy, from ' + low.toFixed(4) + ' (bottom) to the empty map (top)', 1);
    ctx.strokeStyle = '#d62728';
    ctx.beginPath();
    ctx.moveTo(x(k), 10);
    ctx.lineTo(x(k), h - m);
    ctx.stroke();
    ctx.fillStyle = '#333';
    ctx.fillText('scans', w / 2, h - 8);
    ctx.fillText('0', m - 4, h - m + 12);
    ctx.fillText(String(n), w - 20, h - m + 12);
  }

  function resize() {
    const w = canvas.clientWidth, h = canvas.clientHeight;
    renderer.setSize(w, h, false);
    camera.aspect = w / h;
    camera.updateProjectionMatrix();
  }
  function render() {
    renderer.render(scene, camera);
  }
  controls.addEventListener('change', render);
  window.addEventListener('resize', function () { resize(); render(); });
  slider.addEventListener('input', show);
  // Start at the last scan a decision followed, so that the candidates show their gains.
  function lastDecision() {
    const its = data.runs[+runSelect.value].iterations;
    slider.max = its.length;
    let k = its.length;
    while (k > 1 && its[k - 1].gains.length === 0) --k;
    return k;
  }
  resize();
  if (data.runs.length > 0) {
    runSelect.addEventListener('change', function () { slider.value = lastDecision(); show(); });
    slider.value = lastDecision();
    show();
  } else {  // a map alone: no iterations to walk
    document.getElementById('controls').style.display = 'none';
    document.getElementById('curves').style.display = 'none';
    next.visible = false;
    render();
  }
  status.textContent = 'rendered ' + data.views.length + ' views, ' + Object.keys(data.scans).length + ' scans and ' +
      voxelCount + ' voxels';
})();
)JS";

constexpr const char* kPageStyle = R"CSS(
body { font: 14px sans-serif; margin: 0; color: #222; }
header { padding: 8px 12px; background: #eee; }
#view { width: 100%; height: 62vh; display: block; }
#controls { padding: 6px 12px; }
#iteration { width: 40%; vertical-align: middle; }
#curves { display: block; margin: 0 12px; }
#status { color: #777; font-size: 12px; padding: 4px 12px; }
#classes { padding: 2px 12px; font-size: 13px; }
)CSS";

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
  std::ofstream out(path, std::ios::binary);
  if (!out) throw FileError(path, "cannot write");
  out << "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" << htmlEscaped(report.title)
      << "</title>\n<style>" << kPageStyle << "</style>\n"
      << "<script>" << scriptSafe(three) << "</script>\n<script>" << scriptSafe(orbit) << "</script>\n</head><body>\n"
      << "<header><b>" << htmlEscaped(report.title) << "</b></header>\n<canvas id=\"view\"></canvas>\n"
      << "<div id=\"controls\">run <select id=\"run\"></select> &nbsp; scans <input type=\"range\" id=\"iteration\" min=\"1\" "
         "step=\"1\"> <span id=\"info\"></span></div>\n<div id=\"classes\"></div>\n"
      << "<canvas id=\"curves\" width=\"640\" height=\"180\"></canvas>\n"
      << "<div id=\"status\">loading</div>\n"
      << "<p style=\"padding:0 12px;font-size:12px;color:#555\">Drag to turn, scroll to zoom. Frusta: the candidate views, "
         "coloured by the gain each was given after the scan shown (dark low, yellow high; grey: visited). Black: the path "
         "so far and the view chosen next (the sphere). Points: the scans, one hue each"
      << (report.voxels.empty() ? "" : "; the map's voxels at their centres, by class (tick a class to show it)") << ".</p>\n"
      << "<script>const NBV_DATA = " << scriptSafe(pageData(report).dump()) << ";</script>\n<script>" << kPageScript
      << "</script>\n</body></html>\n";
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
    const grid::OccupancyMap map = grid::loadMap(c.map);
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
