// Every file of the bad-input corpus (tests/bad_inputs/MANIFEST) is refused by the library
// reader of its kind with that reader's typed exception, naming the file and the problem.
#include "expect_file_error.hpp"

#include "nbv/errors.hpp"
#include "nbv/grid/map_io.hpp"
#include "nbv/planner/viewspace.hpp"
#include "nbv/errors.hpp"
#include "nbv/sensor/depth_io.hpp"
#include "nbv/sensor/mesh.hpp"
#include "nbv/sensor/point_cloud_io.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;

const fs::path kCorpus = NBV_TEST_BAD_INPUTS_DIR;

struct BadInput {
  std::string kind;  // mesh, cloud, cloud_points, views, map
  std::string path;  // relative to kCorpus
  std::string fragment;
};

// Test listings name the file, not the bytes of the struct.
void PrintTo(const BadInput& c, std::ostream* out) { *out << c.kind << ' ' << c.path; }

std::vector<BadInput> readManifest() {
  std::vector<BadInput> cases;
  std::ifstream in(kCorpus / "MANIFEST");
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    const auto tab1 = line.find('\t');
    const auto tab2 = line.find('\t', tab1 + 1);
    if (tab1 == std::string::npos || tab2 == std::string::npos) continue;
    cases.push_back({line.substr(0, tab1), line.substr(tab1 + 1, tab2 - tab1 - 1), line.substr(tab2 + 1)});
  }
  return cases;
}

TEST(BadInputCorpus, ManifestCoversEveryReader) {
  const std::vector<BadInput> cases = readManifest();
  ASSERT_GE(cases.size(), 100u) << "MANIFEST missing or short: run tests/bad_inputs/generate.py";
  for (const char* kind : {"mesh", "cloud", "views", "map", "depth", "tum", "frames"}) {
    EXPECT_GE(std::count_if(cases.begin(), cases.end(), [&](const BadInput& c) { return c.kind == kind; }), 10)
        << kind;
  }
}

class BadInputs : public ::testing::TestWithParam<BadInput> {};

TEST_P(BadInputs, RefusedWithATypedErrorNamingTheFile) {
  const BadInput& c = GetParam();
  const fs::path path = kCorpus / c.path;
  using nbv::test::expectFileError;
  if (c.kind == "mesh") {
    expectFileError<nbv::MeshFileError>(path, [](const fs::path& p) { nbv::sensor::loadMesh(p); }, c.fragment);
  } else if (c.kind == "cloud") {
    expectFileError<nbv::CloudFileError>(path, [](const fs::path& p) { nbv::sensor::readPlyCloud(p); },
                                                 c.fragment);
  } else if (c.kind == "cloud_points") {
    // Readable, and nothing in it to integrate: `nbv integrate` refuses it (bad_inputs_test.sh).
    const std::vector<Eigen::Vector3f> points = nbv::sensor::readPlyCloud(path);
    EXPECT_TRUE(std::none_of(points.begin(), points.end(), [](const Eigen::Vector3f& p) { return p.allFinite(); }));
  } else if (c.kind == "views") {
    expectFileError<nbv::ViewFileError>(path, [](const fs::path& p) { nbv::planner::loadViews(p); },
                                                 c.fragment);
  } else if (c.kind == "map") {
    expectFileError<nbv::MapFileError>(path, [](const fs::path& p) { nbv::grid::loadMap(p); }, c.fragment);
  } else if (c.kind == "depth") {
    expectFileError<nbv::FileError>(path, [](const fs::path& p) { nbv::sensor::readDepthPng16(p); }, c.fragment);
  } else if (c.kind == "depth_frame") {
    // Readable, and not of the camera's size: `nbv integrate --depth` refuses it (bad_inputs_test.sh).
    EXPECT_NE(nbv::sensor::readDepthPng16(path).width, 752);
  } else if (c.kind == "tum") {
    try {  // the error names the file of the folder at fault (depth.txt, groundtruth.txt, an image)
      nbv::sensor::readTumSequence(path);
      for (const nbv::sensor::TumFrame& frame : nbv::sensor::readTumSequence(path)) nbv::sensor::readDepthPng16(frame.depth_file);
      ADD_FAILURE() << "no error for " << path;
    } catch (const nbv::FileError& e) {
      EXPECT_EQ(e.path().parent_path().string().rfind(path.string(), 0), 0u) << e.what();
      EXPECT_NE(std::string(e.what()).find(c.fragment), std::string::npos) << e.what();
    }
  } else if (c.kind == "frames") {
    try {  // the error names the folder or a file of it
      for (const nbv::sensor::TumFrame& frame : nbv::sensor::readFrameFolder(path, path / "poses.txt")) {
        nbv::sensor::readDepthPng16(frame.depth_file);
      }
      ADD_FAILURE() << "no error for " << path;
    } catch (const nbv::FileError& e) {
      EXPECT_TRUE(e.path() == path || e.path().parent_path() == path) << e.what();
      EXPECT_NE(std::string(e.what()).find(c.fragment), std::string::npos) << e.what();
    }
  } else {
    ADD_FAILURE() << "unknown kind '" << c.kind << "' in MANIFEST";
  }
}

std::string caseName(const ::testing::TestParamInfo<BadInput>& info) {
  std::string name = info.param.path;
  for (char& ch : name) {
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  }
  return name;
}

INSTANTIATE_TEST_SUITE_P(Corpus, BadInputs, ::testing::ValuesIn(readManifest()), caseName);

}  // namespace
