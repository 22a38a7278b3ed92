#pragma once
// The one check of a refused file: `load(path)` throws `Error`, whose path() is `path` and
// whose message names the file (and contains `fragment`, when given).

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace nbv::test {

template <class Error, class Load>
void expectFileError(const std::filesystem::path& path, Load&& load, const std::string& fragment = "") {
  try {
    load(path);
    ADD_FAILURE() << "no error for " << path;
  } catch (const Error& e) {
    EXPECT_EQ(e.path(), path);
    const std::string what = e.what();
    EXPECT_NE(what.find(path.string()), std::string::npos) << what;
    EXPECT_NE(what.find(fragment), std::string::npos) << what;
  }
}

}  // namespace nbv::test
