// Shared by the scene-file tests of every simulator: the message a loader throws, and the check that it names
// a file's line and the problem.
#pragma once

#include <gtest/gtest.h>

#include <string>

namespace rc::test {

/// What `parse()` throws as Error (empty if it does not throw).
template <class Error, class Parse>
std::string sceneParseError(Parse&& parse) {
  try {
    parse();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

/// `message` starts with "<source>:<line>:" and contains `words`.
inline void expectMessageAt(const std::string& message, const std::string& source, int line,
                            const std::string& words) {
  EXPECT_EQ(message.rfind(source + ":" + std::to_string(line) + ":", 0), 0u) << message;
  EXPECT_NE(message.find(words), std::string::npos) << message;
}

}  // namespace rc::test
