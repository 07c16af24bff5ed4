// Test models beside the checkout (../shared/data, never copied into the repository; the build passes its
// folder as RC_SHARED_DATA_DIR). A test that needs one skips visibly without it: the skip message holds
// "needs
// ../shared/data", which scripts/test_summary.py lists, and counts as a failure where the data is expected
// (CI).
#pragma once

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

namespace rc {
namespace test {

/// The path of a shared test model, e.g. sharedDataPath("bunny.ply").
inline std::string sharedDataPath(const std::string& name) {
  return std::string(RC_SHARED_DATA_DIR) + "/" + name;
}

inline bool sharedDataPresent(const std::string& name) {
  return std::filesystem::exists(sharedDataPath(name));
}

}  // namespace test
}  // namespace rc

/// Skips the current test (visibly) when the shared model `name` is missing.
#define RC_SKIP_WITHOUT_SHARED_DATA(name)                                                            \
  do {                                                                                               \
    if (!::rc::test::sharedDataPresent(name))                                                        \
      GTEST_SKIP() << "needs ../shared/data: " << ::rc::test::sharedDataPath(name) << " is missing"; \
  } while (false)
