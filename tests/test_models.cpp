// Where the standard models are looked for, and fetching them from an archive of CGAL's data
// set (a small one made here, so that the test needs no network).
#include "nbv/sensor/models.hpp"

#include "temp_dir.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <optional>
#include <string>

namespace {

namespace fs = std::filesystem;
using nbv::sensor::modelSearchPath;
using nbv::sensor::resolveModel;
using nbv::sensor::standardModels;

/// Sets (or, with nullopt, unsets) an environment variable for the scope, then restores it.
class ScopedEnvironment {
 public:
  ScopedEnvironment(const char* name, const std::optional<std::string>& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    value ? ::setenv(name, value->c_str(), 1) : ::unsetenv(name);
  }
  ~ScopedEnvironment() { old_ ? ::setenv(name_, old_->c_str(), 1) : ::unsetenv(name_); }
  ScopedEnvironment(const ScopedEnvironment&) = delete;
  ScopedEnvironment& operator=(const ScopedEnvironment&) = delete;

 private:
  const char* name_;
  std::optional<std::string> old_;
};

/// Runs a shell command for the test's fixtures; true if it exited 0.
bool shell(const std::string& command) { return std::system(command.c_str()) == 0; }

/// Writes `data/meshes/<file>` for each standard model (a one-triangle OFF each) under `root`,
/// and packs `data/` into `archive` as libcgal-demo's data.tar.gz holds it.
void makeDataArchive(const fs::path& root, const fs::path& archive, const std::string& skip = "") {
  fs::create_directories(root / "data/meshes");
  for (const auto& model : standardModels()) {
    if (model.file == skip) continue;
    nbv::test::writeBytes(root / "data/meshes" / model.file, "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  }
  ASSERT_TRUE(shell("tar -czf '" + archive.string() + "' -C '" + root.string() + "' data"));
}

TEST(Models, SearchPathFollowsTheEnvironment) {
  {
    const ScopedEnvironment models("NBV_MODELS_DIR", "/here/models");
    EXPECT_EQ(modelSearchPath(), std::vector<fs::path>{"/here/models"});  // alone
    EXPECT_EQ(nbv::sensor::userModelsDir(), fs::path("/here/models"));
  }
  const ScopedEnvironment models("NBV_MODELS_DIR", std::nullopt);
  {
    const ScopedEnvironment data("XDG_DATA_HOME", "/data/home");
    const ScopedEnvironment shared("XDG_DATA_DIRS", "/opt/share:relative/ignored:/usr/share");
    EXPECT_EQ(modelSearchPath(),
              (std::vector<fs::path>{"/data/home/nbv/models", "/opt/share/nbv/models", "/usr/share/nbv/models"}));
  }
  const ScopedEnvironment data("XDG_DATA_HOME", std::nullopt);
  const ScopedEnvironment shared("XDG_DATA_DIRS", std::nullopt);
  {
    const ScopedEnvironment home("HOME", "/home/someone");
    EXPECT_EQ(modelSearchPath(), (std::vector<fs::path>{"/home/someone/.local/share/nbv/models",
                                                        "/usr/local/share/nbv/models", "/usr/share/nbv/models"}));
  }
  const ScopedEnvironment home("HOME", std::nullopt);
  EXPECT_THROW(modelSearchPath(), nbv::InvalidArgument);
}

TEST(Models, TheFirstFolderThatHasTheFileWins) {
  const nbv::test::TempDir dir;
  fs::create_directories(dir / "a");
  fs::create_directories(dir / "b");
  nbv::test::writeBytes(dir / "b" / "bunny00.off", "OFF\n");
  EXPECT_EQ(resolveModel("bunny", {dir / "a", dir / "b"}), dir / "b" / "bunny00.off");
  nbv::test::writeBytes(dir / "a" / "bunny00.off", "OFF\n");
  EXPECT_EQ(resolveModel("bunny", {dir / "a", dir / "b"}), dir / "a" / "bunny00.off");
}

TEST(Models, FetchedFromADataArchiveAndKept) {
  const nbv::test::TempDir dir;
  makeDataArchive(dir / "src", dir / "data.tar.gz");
  const nbv::sensor::FetchReport report = nbv::sensor::fetchStandardModels({dir / "models", dir / "data.tar.gz"});
  EXPECT_EQ(report.dir, dir / "models");
  EXPECT_EQ(report.source, (dir / "data.tar.gz").string());
  EXPECT_EQ(report.written.size(), standardModels().size());
  for (const auto& model : standardModels()) {
    EXPECT_EQ(resolveModel(model.name, {dir / "models"}), dir / "models" / model.file);
  }
  // Nothing else is left in the folder (no partial files), and a second fetch writes nothing.
  EXPECT_EQ(static_cast<std::size_t>(std::distance(fs::directory_iterator(dir / "models"), fs::directory_iterator())),
            standardModels().size());
  EXPECT_TRUE(nbv::sensor::fetchStandardModels({dir / "models", dir / "no-such-archive.tar.gz"}).written.empty());
  // A missing file is fetched alone.
  fs::remove(dir / "models" / "pig.off");
  EXPECT_EQ(nbv::sensor::fetchStandardModels({dir / "models", dir / "data.tar.gz"}).written,
            std::vector<std::string>{"pig.off"});
}

TEST(Models, FetchedFromADeb) {
  const nbv::test::TempDir dir;
  const fs::path package = dir / "pkg";
  fs::create_directories(package / "DEBIAN");
  fs::create_directories(package / "usr/share/doc/libcgal-dev");
  makeDataArchive(dir / "src", package / "usr/share/doc/libcgal-dev/data.tar.gz");
  nbv::test::writeBytes(package / "DEBIAN/control", "Package: libcgal-demo\nVersion: 1.0\nArchitecture: all\n"
                                                    "Maintainer: nbv tests <nbv@example.org>\nDescription: test\n");
  ASSERT_TRUE(shell("dpkg-deb --build '" + package.string() + "' '" + (dir / "libcgal-demo_1.0_all.deb").string() +
                    "' >/dev/null"));
  const auto report = nbv::sensor::fetchStandardModels({dir / "models", dir / "libcgal-demo_1.0_all.deb"});
  EXPECT_EQ(report.written.size(), standardModels().size());
  EXPECT_EQ(report.source, (dir / "libcgal-demo_1.0_all.deb").string());
}

TEST(Models, BadSourcesAreRefusedByName) {
  const nbv::test::TempDir dir;
  try {
    nbv::sensor::fetchStandardModels({dir / "models", dir / "missing.deb"});
    FAIL() << "no error";
  } catch (const nbv::FileError& e) {
    EXPECT_EQ(std::string(e.what()), (dir / "missing.deb").string() +
                                         ": no such file (give libcgal-demo's .deb or its data.tar.gz)");
  }
  // An archive without one of the meshes: nothing is half-written, the error names the mesh.
  makeDataArchive(dir / "src", dir / "partial.tar.gz", "elk.off");
  try {
    nbv::sensor::fetchStandardModels({dir / "models", dir / "partial.tar.gz"});
    FAIL() << "no error";
  } catch (const nbv::FileError& e) {
    EXPECT_NE(std::string(e.what()).find("data/meshes/elk.off"), std::string::npos) << e.what();
  }
  nbv::test::writeBytes(dir / "not-a.deb", "garbage");
  EXPECT_THROW(nbv::sensor::fetchStandardModels({dir / "models2", dir / "not-a.deb"}), nbv::FileError);
}

}  // namespace
