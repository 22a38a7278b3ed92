#include "nbv/sensor/models.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <sstream>

extern char** environ;

namespace nbv::sensor {

namespace {

namespace fs = std::filesystem;

/// The archive of CGAL's data set inside libcgal-demo, and its meshes' folder.
constexpr const char* kDataArchive = "usr/share/doc/libcgal-dev/data.tar.gz";
constexpr const char* kMeshesInArchive = "data/meshes/";

std::string environment(const char* name) {
  const char* value = std::getenv(name);
  return value != nullptr ? value : "";
}

/// A folder the program makes and removes again, whatever happens in between.
class TemporaryFolder {
 public:
  TemporaryFolder() {
    std::string pattern = (fs::temp_directory_path() / "nbv-models-XXXXXX").string();
    if (::mkdtemp(pattern.data()) == nullptr) throw FileError(pattern, "cannot make a temporary folder");
    path_ = pattern;
  }
  ~TemporaryFolder() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  TemporaryFolder(const TemporaryFolder&) = delete;
  TemporaryFolder& operator=(const TemporaryFolder&) = delete;
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

/// Runs `argv` in `cwd`, waiting for it, its output and errors in `log`. True if it exited 0.
bool runTool(const std::vector<std::string>& argv, const fs::path& cwd, const fs::path& log) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  posix_spawn_file_actions_addchdir_np(&actions, cwd.c_str());
  pid_t pid = 0;
  const int spawned = ::posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) {
    std::ofstream(log) << argv[0] << ": cannot be run (is it installed?)";
    return false;
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return false;
  }
  return WIFEXITED(status) && WEXITSTATUS(status) == 0;
}

/// The last lines a tool printed, for an error message.
std::string logTail(const fs::path& log) {
  std::ifstream in(log);
  std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
  if (text.size() > 600) text = "..." + text.substr(text.size() - 600);
  for (char& c : text) {
    if (c == '\n') c = ' ';
  }
  return text.empty() ? "(it printed nothing)" : text;
}

/// Runs a tool; \throws FileError on `about` with what it printed if it fails.
void runOrThrow(const std::vector<std::string>& argv, const fs::path& cwd, const fs::path& about) {
  const fs::path log = cwd / ".tool.log";
  if (!runTool(argv, cwd, log)) {
    std::string command;
    for (const std::string& a : argv) command += (command.empty() ? "" : " ") + a;
    throw FileError(about, "`" + command + "` failed: " + logTail(log));
  }
}

/// A libcgal-demo .deb in apt's cache, if one is there.
fs::path cachedDeb() {
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator("/var/cache/apt/archives", ec)) {
    const std::string name = entry.path().filename().string();
    if (name.starts_with("libcgal-demo_") && name.ends_with(".deb")) return entry.path();
  }
  return {};
}

/// Downloads libcgal-demo's .deb into `work` (as root, after `apt-get update` if the package
/// lists are stale). \returns its path.
fs::path downloadDeb(const fs::path& work) {
  const fs::path log = work / ".apt.log";
  bool ok = runTool({"apt-get", "download", "-qq", "libcgal-demo"}, work, log);
  if (!ok && ::geteuid() == 0) {
    runOrThrow({"apt-get", "update", "-qq"}, work, "libcgal-demo");
    ok = runTool({"apt-get", "download", "-qq", "libcgal-demo"}, work, log);
  }
  if (!ok) {
    throw FileError("libcgal-demo", "`apt-get download libcgal-demo` failed: " + logTail(log) +
                                        (::geteuid() == 0 ? "" : " (run `sudo apt-get update` first)") +
                                        "; or download the .deb yourself and give it with --from");
  }
  for (const fs::directory_entry& entry : fs::directory_iterator(work)) {
    if (entry.path().extension() == ".deb") return entry.path();
  }
  throw FileError(work, "`apt-get download libcgal-demo` wrote no .deb");
}

/// The data archive of CGAL's data set, unpacked into `work` from wherever it can be had.
fs::path dataArchive(const fs::path& source, const fs::path& work, std::string& from) {
  std::error_code ec;
  fs::path deb;
  if (!source.empty()) {
    if (!fs::is_regular_file(source, ec)) throw FileError(source, "no such file (give libcgal-demo's .deb or its data.tar.gz)");
    if (source.extension() != ".deb") {
      from = source.string();
      return source;
    }
    deb = source;
  } else if (const fs::path installed = fs::path("/") / kDataArchive; fs::is_regular_file(installed, ec)) {
    from = installed.string();
    return installed;
  } else {
    deb = cachedDeb();
    if (deb.empty()) deb = downloadDeb(work);
  }
  from = deb.parent_path() == work ? deb.filename().string() + ", downloaded" : deb.string();
  const fs::path unpacked = work / "deb";
  runOrThrow({"dpkg-deb", "-x", fs::absolute(deb).string(), unpacked.string()}, work, deb);
  const fs::path archive = unpacked / kDataArchive;
  if (!fs::is_regular_file(archive, ec)) throw FileError(deb, std::string("holds no ") + kDataArchive + ": not libcgal-demo's .deb");
  return archive;
}

/// Copies `file` into `dir` under a temporary name, then renames it into place.
void placeFile(const fs::path& file, const fs::path& dir) {
  const fs::path target = dir / file.filename();
  const fs::path temporary = dir / ("." + file.filename().string() + ".part-" + std::to_string(::getpid()));
  std::error_code ec;
  fs::copy_file(file, temporary, fs::copy_options::overwrite_existing, ec);
  if (!ec) fs::rename(temporary, target, ec);
  if (ec) {
    fs::remove(temporary, ec);
    throw FileError(target, "cannot write: " + ec.message());
  }
}

}  // namespace

const std::vector<StandardModel>& standardModels() {
  static const std::vector<StandardModel> models = {
      {"bunny", "bunny00.off", UpAxis::Y},
      {"armadillo", "armadillo.off", UpAxis::Y},
      {"dragon", "ChineseDragon-10kv.off", UpAxis::Y},
      {"dino", "dino.off", UpAxis::Z},
      {"head", "head.off", UpAxis::Y},
      {"bull", "bull.off", UpAxis::Y},
      {"mannequin-devil", "mannequin-devil.off", UpAxis::Z},
      {"nefertiti", "nefertiti.off", UpAxis::Y},
      {"elk", "elk.off", UpAxis::Z},
      {"pig", "pig.off", UpAxis::Y},
      {"diplodocus", "diplodocus.off", UpAxis::Y}};
  return models;
}

fs::path userModelsDir() {
  if (const std::string dir = environment("NBV_MODELS_DIR"); !dir.empty()) return dir;
  // XDG Base Directory: $XDG_DATA_HOME, else ~/.local/share.
  if (const std::string data = environment("XDG_DATA_HOME"); !data.empty() && fs::path(data).is_absolute()) {
    return fs::path(data) / "nbv" / "models";
  }
  if (const std::string home = environment("HOME"); !home.empty()) return fs::path(home) / ".local/share/nbv/models";
  throw InvalidArgument("no folder for the models: set NBV_MODELS_DIR, XDG_DATA_HOME or HOME");
}

std::vector<fs::path> modelSearchPath() {
  if (const std::string dir = environment("NBV_MODELS_DIR"); !dir.empty()) return {dir};
  std::vector<fs::path> search = {userModelsDir()};
  std::string shared = environment("XDG_DATA_DIRS");
  if (shared.empty()) shared = "/usr/local/share:/usr/share";
  std::stringstream list(shared);
  for (std::string dir; std::getline(list, dir, ':');) {
    if (fs::path(dir).is_absolute()) search.push_back(fs::path(dir) / "nbv" / "models");
  }
  return search;
}

fs::path resolveModel(const std::string& name_or_path, const std::vector<fs::path>& search) {
  std::string standard;
  for (const StandardModel& model : standardModels()) {
    if (name_or_path == model.name) {
      std::string folders;
      for (const fs::path& dir : search) {
        std::error_code ec;
        if (fs::is_regular_file(dir / model.file, ec)) return dir / model.file;
        folders += (folders.empty() ? "" : ", ") + dir.string();
      }
      throw MeshFileError(model.file, "the standard model '" + model.name + "' is not in " + folders +
                                          ": run `nbv models fetch` (Python: nbv.fetch_models()), or point "
                                          "NBV_MODELS_DIR at a folder that has it");
    }
    standard += (standard.empty() ? "" : ", ") + model.name;
  }
  std::error_code ec;
  if (!fs::exists(name_or_path, ec)) {
    throw MeshFileError(name_or_path, "no such file, and not a standard model name (" + standard + ")");
  }
  return name_or_path;
}

FetchReport fetchStandardModels(const FetchOptions& options) {
  FetchReport report;
  report.dir = options.dir.empty() ? userModelsDir() : options.dir;
  std::error_code ec;
  fs::create_directories(report.dir, ec);
  if (!fs::is_directory(report.dir, ec)) throw FileError(report.dir, "cannot make the models folder");
  std::vector<std::string> missing;
  for (const StandardModel& model : standardModels()) {
    if (!fs::is_regular_file(report.dir / model.file, ec)) missing.push_back(model.file);
  }
  if (missing.empty()) return report;

  const TemporaryFolder work;
  const fs::path archive = dataArchive(options.source, work.path(), report.source);
  std::vector<std::string> tar = {"tar", "-xzf", fs::absolute(archive).string(), "-C", work.path().string()};
  for (const std::string& file : missing) tar.push_back(kMeshesInArchive + file);
  runOrThrow(tar, work.path(), archive);
  for (const std::string& file : missing) {
    const fs::path extracted = work.path() / kMeshesInArchive / file;
    if (!fs::is_regular_file(extracted, ec)) throw FileError(archive, "holds no " + std::string(kMeshesInArchive) + file);
    placeFile(extracted, report.dir);
    report.written.push_back(file);
  }
  return report;
}

}  // namespace nbv::sensor
