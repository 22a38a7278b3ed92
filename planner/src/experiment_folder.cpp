#include "nbv/planner/experiment_folder.hpp"

#include "nbv/errors.hpp"
#include "nbv/planner/utility.hpp"

#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <set>
#include <string_view>
#include <type_traits>

namespace nbv::planner {

namespace {

namespace fs = std::filesystem;
using json = nlohmann::ordered_json;

constexpr const char* kSweepFile = "sweep.json";
constexpr const char* kRunsFolder = "runs";

/// A double as JSON holds it: NaN as null.
json number(double value) { return std::isnan(value) ? json(nullptr) : json(value); }
/// A field of an iteration in a run file: an integer as it is, a number as number() writes it.
json jsonValue(std::uint64_t value) { return value; }
json jsonValue(double value) { return number(value); }
double numberOf(const json& value) {
  return value.is_null() ? std::numeric_limits<double>::quiet_NaN() : value.get<double>();
}

/// A field of an iteration read from a run file as a T; a Gap's null is none (NaN).
template <class T>
T fieldOf(const json& value, bool gap) {
  if constexpr (std::is_floating_point_v<T>) {
    return gap ? numberOf(value) : value.get<T>();
  } else {
    return value.get<T>();
  }
}

/// `text` written to `path` in full and on disk before it takes that name: a temporary beside
/// it, flushed and synced, renamed, and the folder synced, so that a kill or a power cut leaves
/// the old file or the new one, never a part.
void writeDurably(const fs::path& path, const std::string& text) {
  std::string name = path.filename().string();  // hidden: ".<name>.part-<pid>"
  name.insert(0, 1, '.');
  name += ".part-" + std::to_string(::getpid());
  const fs::path temporary = path.parent_path() / name;
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw FileError(path, std::string("cannot write: ") + std::strerror(errno));
  std::size_t written = 0;
  while (written < text.size()) {
    const ssize_t n = ::write(fd, text.data() + written, text.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    written += static_cast<std::size_t>(n);
  }
  const bool ok = written == text.size() && ::fsync(fd) == 0;
  const int error = errno;
  ::close(fd);
  if (!ok || ::rename(temporary.c_str(), path.c_str()) != 0) {
    ::unlink(temporary.c_str());
    throw FileError(path, std::string("cannot write: ") + std::strerror(ok ? errno : error));
  }
  const int folder = ::open(path.parent_path().empty() ? "." : path.parent_path().c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (folder >= 0) {
    ::fsync(folder);
    ::close(folder);
  }
}

json readJson(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw FileError(path, "cannot read");
  try {
    return json::parse(in);
  } catch (const json::exception& e) {
    throw FileError(path, std::string("not JSON: ") + e.what());
  }
}

json sweepJson(const Sweep& s) {
  const ReconstructionConfig& c = s.config;
  json crop = nullptr;
  if (c.scene.crop) {
    crop = json::array();
    for (int a = 0; a < 3; ++a) crop.insert(crop.end(), {c.scene.crop->min()[a], c.scene.crop->max()[a]});
  }
  json anytime = nullptr;
  if (c.anytime) {
    anytime = json::object();
    for (const DecideOption& o : decideOptions()) {
      const std::optional<double> value = o.get(*c.anytime);
      anytime[o.name] = value ? json(*value) : json(nullptr);
    }
  }
  // Every field that decides the results; sweepFields() gives their order.
  json j{{"models", s.models},
         {"labels", s.labels},
         {"metrics", s.metrics},
         {"seeds", s.seeds},
         {"iterations", c.max_iterations},
         {"rays", s.rays},
         {"viewspace", s.viewspace},
         {"weighting", weightingName(c.weighting)},
         {"scene",
          {{"name", s.scene},
           {"ground_plane", c.scene.ground_plane},
           {"no_return", c.scene.no_return == NoReturn::Clear ? "clear" : "drop"},
           {"crop", crop},
           {"up", s.up}}},
         {"visibility", kernels::visibilityName(c.snapshot.visibility)},
         {"anytime", anytime},
         {"timings", s.timings},
         {"shard", std::to_string(s.shard) + "/" + std::to_string(s.shards)},
         {"version", s.version}};
  for (const ReconstructionOption& o : reconstructionOptions()) {
    const std::optional<double> value = o.get(c);
    j[o.name] = value ? json(*value) : json(nullptr);
  }
  return j;
}

/// The order of sweepJson()'s fields, for messages (differenceFrom() names the first that differs).
const std::vector<std::string>& sweepFields() {
  static const std::vector<std::string> fields = [] {
    std::vector<std::string> f = {"models", "labels", "metrics", "seeds", "iterations", "rays", "viewspace", "weighting"};
    for (const ReconstructionOption& o : reconstructionOptions()) f.push_back(o.name);
    f.insert(f.end(), {"scene", "visibility", "anytime", "timings", "version"});
    return f;
  }();
  return fields;
}

/// The options a sweep.json of the first version holds (gamma, g_thresh, max_ray_depth); a
/// later one may be absent and reads as its default.
constexpr std::size_t kFirstSweepOptions = 3;

Sweep sweepFrom(const json& j, const fs::path& path) {
  Sweep s;
  try {
    s.models = j.at("models").get<std::vector<std::string>>();
    s.labels = j.at("labels").get<std::vector<std::string>>();
    s.metrics = j.at("metrics").get<std::vector<std::string>>();
    s.seeds = j.at("seeds").get<std::vector<std::uint64_t>>();
    ReconstructionConfig& c = s.config;
    c.max_iterations = j.at("iterations").get<std::size_t>();
    s.rays = j.at("rays").get<std::string>();
    c.rays = sensor::PixelSampling::fromName(s.rays);
    s.viewspace = j.at("viewspace").get<std::string>();
    c.weighting = weightingFromName(j.at("weighting").get<std::string>());
    const auto options = reconstructionOptions();
    for (std::size_t i = 0; i < options.size(); ++i) {
      if (i >= kFirstSweepOptions && !j.contains(options[i].name)) continue;
      const json& value = j.at(options[i].name);
      options[i].set(c, value.is_null() ? std::nullopt : std::optional<double>(value.get<double>()));
    }
    const json& scene = j.at("scene");
    s.scene = scene.at("name").get<std::string>();
    c.scene.ground_plane = scene.at("ground_plane").get<bool>();
    c.scene.no_return = noReturnFromName(scene.at("no_return").get<std::string>());
    if (!scene.at("crop").is_null()) {
      const auto box = scene.at("crop").get<std::vector<double>>();
      if (box.size() != 6) throw InvalidArgument("scene.crop: 6 numbers expected");
      c.scene.crop = Eigen::AlignedBox3d(Eigen::Vector3d(box[0], box[2], box[4]), Eigen::Vector3d(box[1], box[3], box[5]));
    }
    s.up = scene.at("up").get<std::string>();
    c.snapshot.visibility = kernels::visibilityFromName(j.at("visibility").get<std::string>());
    if (const json& anytime = j.at("anytime"); !anytime.is_null()) {
      DecideOptions d;
      for (const DecideOption& o : decideOptions()) {
        const json& value = anytime.at(o.name);
        o.set(d, value.is_null() ? std::nullopt : std::optional<double>(value.get<double>()));
      }
      c.anytime = d;
    }
    s.timings = j.at("timings").get<bool>();
    const std::string shard = j.at("shard").get<std::string>();
    if (std::sscanf(shard.c_str(), "%zu/%zu", &s.shard, &s.shards) != 2 || s.shard < 1 || s.shard > s.shards) {
      throw InvalidArgument("shard '" + shard + "' is not K/N");
    }
    s.version = j.at("version").get<std::string>();
    if (s.labels.size() != s.models.size()) throw InvalidArgument("models and labels differ in number");
  } catch (const json::exception& e) {
    throw FileError(path, std::string("not a sweep record of nbv experiment: ") + e.what());
  } catch (const InvalidArgument& e) {
    throw FileError(path, e.what());
  }
  return s;
}

json runJson(const KeptRun& kept, const Sweep& sweep) {
  json iterations = json::array();
  for (const IterationRecord& it : kept.result.iterations) {
    json gains = json::array();
    for (double g : it.gains) gains.push_back(number(g));
    json& record = iterations.emplace_back(json::object());
#define NBV_RUN_JSON_FIELD(name, type, kind, help) NBV_ITERATION_IF_RECORD(kind, record[#name] = jsonValue(it.name);)
    NBV_ITERATION_FIELDS(NBV_RUN_JSON_FIELD)
#undef NBV_RUN_JSON_FIELD
    record["gains"] = std::move(gains);
  }
  const ReconstructionResult& r = kept.result;
  return json{{"run", kept.index},
              {"model", sweep.labels.at(kept.run.model)},
              {"metric", kept.run.metric},
              {"seed", kept.run.trial},
              {"stop", stopReasonName(r.stop)},
              {"max_entropy_bits", r.max_entropy_bits},
              {"auc_coverage", r.auc_coverage},
              {"auc_entropy", r.auc_entropy},
              {"iterations", std::move(iterations)}};
}

StopReason stopReasonFrom(const std::string& name) {
  for (const StopReason reason :
       {StopReason::MaxIterations, StopReason::BelowThreshold, StopReason::NoViewsLeft, StopReason::TimeLimit}) {
    if (name == stopReasonName(reason)) return reason;
  }
  throw InvalidArgument("stop '" + name + "' is not a reason a run stops for");
}

/// Run `index` of `sweep` from its file, checked to be that run.
KeptRun runFrom(const fs::path& path, std::size_t index, const Sweep& sweep, const std::vector<ExperimentRun>& all) {
  const json j = readJson(path);
  KeptRun kept;
  kept.index = index;
  kept.run = all.at(index);
  try {
    if (j.at("run").get<std::size_t>() != index || j.at("model").get<std::string>() != sweep.labels.at(kept.run.model) ||
        j.at("metric").get<std::string>() != kept.run.metric || j.at("seed").get<std::uint64_t>() != kept.run.trial) {
      throw InvalidArgument("it is not run " + std::to_string(index) + " of the sweep (" + sweep.labels[kept.run.model] +
                            " " + kept.run.metric + " seed " + std::to_string(kept.run.trial) + ")");
    }
    ReconstructionResult& r = kept.result;
    r.stop = stopReasonFrom(j.at("stop").get<std::string>());
    r.max_entropy_bits = j.at("max_entropy_bits").get<double>();
    r.auc_coverage = j.at("auc_coverage").get<double>();
    r.auc_entropy = j.at("auc_entropy").get<double>();
    for (const json& it : j.at("iterations")) {
      IterationRecord& record = r.iterations.emplace_back();
      // Every field of the record, a Gap's null as none (NaN); a field added after the first
      // version may be missing (a file of an earlier version) and keeps its initial value.
      std::size_t field = 0;
#define NBV_RUN_JSON_READ(name, type, kind, help)                                                             \
  if (field++ < kFirstIterationFields || it.contains(#name)) {                                                \
    NBV_ITERATION_IF_RECORD(kind, record.name = fieldOf<type>(it.at(#name), NBV_ITERATION_IS_GAP(kind));) \
  }
      NBV_ITERATION_FIELDS(NBV_RUN_JSON_READ)
#undef NBV_RUN_JSON_READ
      for (const json& g : it.at("gains")) record.gains.push_back(numberOf(g));
    }
    if (r.iterations.empty()) throw InvalidArgument("the run has no iteration");
  } catch (const json::exception& e) {
    throw FileError(path, std::string("not a run of nbv experiment: ") + e.what());
  } catch (const InvalidArgument& e) {
    throw FileError(path, e.what());
  }
  return kept;
}

std::string runFileName(std::size_t index) {
  char name[32];
  std::snprintf(name, sizeof name, "%06zu.json", index);
  return name;
}

/// The index a run file's name holds, if it is one ("000042.json").
std::optional<std::size_t> runFileIndex(const fs::path& file) {
  const std::string name = file.filename().string();
  if (name.size() != 11 || !name.ends_with(".json")) return std::nullopt;
  std::size_t index = 0;
  for (std::size_t i = 0; i < 6; ++i) {
    if (name[i] < '0' || name[i] > '9') return std::nullopt;
    index = index * 10 + static_cast<std::size_t>(name[i] - '0');
  }
  return index;
}

/// The runs kept in `dir`/runs of `sweep`, checked to be runs of that sweep and of its shard.
std::map<std::size_t, KeptRun> keptRuns(const fs::path& dir, const Sweep& sweep) {
  const std::vector<ExperimentRun> all = sweep.allRuns();
  const std::vector<std::size_t> mine = sweep.shardRuns();
  const std::set<std::size_t> shard(mine.begin(), mine.end());
  std::map<std::size_t, KeptRun> kept;
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir / kRunsFolder, ec)) {
    const auto index = runFileIndex(entry.path());
    if (!index) continue;  // a temporary of a run that was being written
    if (shard.count(*index) == 0) {
      throw FileError(entry.path(), "is not a run of shard " + std::to_string(sweep.shard) + "/" +
                                        std::to_string(sweep.shards) + " of the sweep " + (dir / kSweepFile).string() +
                                        " records");
    }
    kept.emplace(*index, runFrom(entry.path(), *index, sweep, all));
  }
  return kept;
}

std::string shortText(const json& value) {
  std::string text = value.dump();
  return text.size() <= 60 ? text : text.substr(0, 57) + "...";
}

}  // namespace

std::vector<ExperimentRun> Sweep::allRuns() const {
  std::vector<ExperimentRun> runs;
  for (std::size_t model = 0; model < models.size(); ++model) {
    for (const std::string& metric : metrics) {
      for (const std::uint64_t seed : seeds) runs.push_back({model, metric, seed});
    }
  }
  return runs;
}

std::vector<std::size_t> Sweep::shardRuns() const {
  std::vector<std::size_t> mine;
  const std::size_t count = models.size() * metrics.size() * seeds.size();
  for (std::size_t i = shard - 1; i < count; i += shards) mine.push_back(i);
  return mine;
}

std::string Sweep::differenceFrom(const Sweep& other) const {
  const json a = sweepJson(*this), b = sweepJson(other);
  for (const std::string& field : sweepFields()) {
    if (a.at(field) != b.at(field)) return field + " (" + shortText(a.at(field)) + " against " + shortText(b.at(field)) + ")";
  }
  if (shards != other.shards) return "shards (" + std::to_string(shards) + " against " + std::to_string(other.shards) + ")";
  return {};
}

bool ExperimentFolder::hasSweep(const fs::path& dir) {
  std::error_code ec;
  return fs::is_regular_file(dir / kSweepFile, ec);
}

Sweep ExperimentFolder::readSweep(const fs::path& dir) { return sweepFrom(readJson(dir / kSweepFile), dir / kSweepFile); }

ExperimentFolder::ExperimentFolder(const fs::path& dir, const Sweep& sweep, bool resume, bool force)
    : dir_(dir), sweep_(sweep) {
  std::error_code ec;
  if (fs::exists(dir, ec) && !fs::is_directory(dir, ec)) throw FileError(dir, "is a file, not a folder");
  if (hasSweep(dir) && force && !resume) {
    fs::remove_all(dir / kRunsFolder, ec);  // --force: this sweep replaces whatever ran there
  } else if (hasSweep(dir)) {
    const Sweep recorded = readSweep(dir);
    const std::string difference = sweep.differenceFrom(recorded);
    if (!difference.empty() || recorded.shard != sweep.shard) {
      const std::string what = difference.empty() ? "shard (" + std::to_string(sweep.shard) + " against " +
                                                        std::to_string(recorded.shard) + ")"
                                                  : difference;
      throw FileError(dir, resume ? "holds another sweep, which only it resumes: " + what + " differ from its sweep.json"
                                  : "the --out folder is not empty: it holds another sweep (" + what +
                                        " differ); give --force to replace it, or another folder");
    }
    if (!resume) {
      const std::size_t kept = keptRuns(dir, recorded).size(), all = recorded.shardRuns().size();
      throw FileError(dir, "holds this sweep already, " + std::to_string(kept) + " of its " + std::to_string(all) +
                               " runs kept: `--resume` finishes it (or give --force to start it again)");
    }
  } else if (fs::exists(dir, ec) && !fs::is_empty(dir, ec) && !force) {
    throw FileError(dir, "the --out folder is not empty and holds no sweep (give --force to write into it anyway)");
  }
  fs::create_directories(dir / kRunsFolder, ec);
  if (ec) throw FileError(dir, "cannot make the folder: " + ec.message());
  // A run file a kill cut short stays a hidden temporary: drop those of earlier processes.
  for (const fs::directory_entry& entry : fs::directory_iterator(dir / kRunsFolder, ec)) {
    if (entry.path().filename().string().starts_with(".")) fs::remove(entry.path(), ec);
  }
  writeDurably(dir / kSweepFile, sweepJson(sweep).dump(2) + "\n");
}

std::map<std::size_t, KeptRun> ExperimentFolder::kept() const { return keptRuns(dir_, sweep_); }

void ExperimentFolder::keep(std::size_t index, const ReconstructionResult& result) const {
  KeptRun run;
  run.index = index;
  run.run = sweep_.allRuns().at(index);
  run.result = result;
  writeDurably(dir_ / kRunsFolder / runFileName(index), runJson(run, sweep_).dump() + "\n");
}

MergedSweep mergeShards(const std::vector<fs::path>& folders, bool allow_partial) {
  if (folders.empty()) throw InvalidArgument("--merge names no folder");
  MergedSweep merged;
  std::map<std::size_t, fs::path> shard_folder;  // K -> its folder
  std::vector<std::string> problems;
  for (const fs::path& dir : folders) {
    if (!ExperimentFolder::hasSweep(dir)) {
      throw FileError(dir, "holds no sweep.json: not the folder of an nbv experiment or of one of its shards");
    }
    const Sweep sweep = ExperimentFolder::readSweep(dir);
    if (shard_folder.empty()) {
      merged.sweep = sweep;
    } else if (const std::string difference = sweep.differenceFrom(merged.sweep); !difference.empty()) {
      throw FileError(dir, "is a shard of another sweep than " + shard_folder.begin()->second.string() + ": " + difference);
    }
    if (const auto [at, fresh] = shard_folder.emplace(sweep.shard, dir); !fresh) {
      throw FileError(dir, "is shard " + std::to_string(sweep.shard) + "/" + std::to_string(sweep.shards) + " again (" +
                               at->second.string() + " is that shard too)");
    }
    std::map<std::size_t, KeptRun> runs = keptRuns(dir, sweep);
    if (const std::size_t want = sweep.shardRuns().size(); runs.size() < want) {
      problems.push_back(dir.string() + " (shard " + std::to_string(sweep.shard) + "/" + std::to_string(sweep.shards) +
                         ") holds " + std::to_string(runs.size()) + " of its " + std::to_string(want) + " runs");
    }
    merged.runs.merge(runs);
  }
  for (std::size_t k = 1; k <= merged.sweep.shards; ++k) {
    if (shard_folder.count(k) == 0) {
      Sweep missing = merged.sweep;
      missing.shard = k;
      problems.push_back("shard " + std::to_string(k) + "/" + std::to_string(merged.sweep.shards) + " (" +
                         std::to_string(missing.shardRuns().size()) + " runs) is not among the folders");
    }
  }
  if (!problems.empty() && !allow_partial) {
    std::string text;
    for (const std::string& p : problems) text += (text.empty() ? "" : "; ") + p;
    throw InvalidArgument("the folders are not the whole sweep: " + text +
                          " (`--resume --out FOLDER` finishes a shard; --allow-partial merges what is there)");
  }
  merged.missing = problems;
  merged.sweep.shard = 1;
  merged.sweep.shards = 1;
  return merged;
}

}  // namespace nbv::planner
