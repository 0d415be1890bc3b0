// Helpers of the scene parser tests: scenes written inline, and the check that a scene is refused
// at the right line and column with a message and a hint.
#pragma once

#include "libpd/io/scene.hpp"

#include <gtest/gtest.h>
#include <string>

namespace scene_test {

/// Scenes are written as R"(<newline>...)": dropping that first newline makes line 1 the first
/// line shown, so the expected line numbers can be read off the source.
inline std::string yaml(const char* text) {
  return text[0] == '\n' ? std::string(text + 1) : text;
}

/// Checks that parsing fails at LINE:COLUMN with a message containing `fragment` and a hint.
inline ::testing::AssertionResult fails_at(const std::string& text, int line, int column,
                                           const std::string& fragment) {
  try {
    pd::parse_scene(text, "s.yaml");
  } catch (const pd::SceneError& e) {
    const std::string message = e.what();
    const std::string where =
        "s.yaml:" + std::to_string(line) + ":" + std::to_string(column) + ": error: ";
    if (message.rfind(where, 0) != 0) {
      return ::testing::AssertionFailure() << "expected '" << where << "', got:\n" << message;
    }
    if (e.file() != "s.yaml" || e.mark().line != line || e.mark().column != column) {
      return ::testing::AssertionFailure() << "SceneError::mark() disagrees with:\n" << message;
    }
    if (message.find(fragment) == std::string::npos) {
      return ::testing::AssertionFailure() << "expected '" << fragment << "' in:\n" << message;
    }
    const auto hint = message.find("\n  hint: ");
    if (hint == std::string::npos || message.size() <= hint + 10) {
      return ::testing::AssertionFailure() << "no hint in:\n" << message;
    }
    return ::testing::AssertionSuccess();
  } catch (const std::exception& e) {
    return ::testing::AssertionFailure() << "threw something else than SceneError: " << e.what();
  }
  return ::testing::AssertionFailure() << "parsed without error:\n" << text;
}

} // namespace scene_test

using scene_test::fails_at;
using scene_test::yaml;
