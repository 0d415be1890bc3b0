// The case folders' reader (verification/runner/case_folders.hpp): a code folder's run without a
// registered function, and a registered function no folder lists, are errors naming the folder or
// the run; a data-only folder needs no code.
#include "case_folders.hpp"

#include <filesystem>
#include <fstream>
#include <gtest/gtest.h>
#include <map>
#include <stdexcept>
#include <string>

namespace {

namespace fs = std::filesystem;
using pd::verification::discover_cases;

pd::Json passing(const pd::verification::Context&) {
  pd::Json out;
  out["passed"] = true;
  return out;
}

fs::path folder_with(const std::string& test, const std::string& folder, const std::string& yaml) {
  const fs::path root = fs::temp_directory_path() / ("pd_case_folders_" + test);
  fs::remove_all(root);
  fs::create_directories(root / folder);
  std::ofstream(root / folder / "case.yaml") << yaml;
  return root;
}

const char* code_case = R"(summary: "s"
kind: code
runs:
  - name: listed-run
    summary: "a run"
    label: verification
    cpu_seconds: 1
    timeout: 60
    gate: "g"
)";

std::string error_of(const fs::path& dir,
                     const std::map<std::string, pd::verification::RunFunction>& r) {
  try {
    discover_cases(dir, r);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return {};
}

TEST(CaseFolders, ListedRunWithoutFunctionNamesTheFolder) {
  const fs::path dir = folder_with("unlisted", "my-case", code_case);
  const std::string e = error_of(dir, {});
  EXPECT_NE(e.find("my-case"), std::string::npos) << e;
  EXPECT_NE(e.find("listed-run"), std::string::npos) << e;
}

TEST(CaseFolders, RegisteredFunctionWithoutEntryNamesTheRun) {
  const fs::path dir = folder_with("unregistered", "my-case", code_case);
  const std::string e = error_of(dir, {{"listed-run", passing}, {"orphan-run", passing}});
  EXPECT_NE(e.find("orphan-run"), std::string::npos) << e;
}

TEST(CaseFolders, MatchingCodeFolderAndMetadata) {
  const fs::path dir = folder_with("matching", "my-case", code_case);
  const auto set = discover_cases(dir, {{"listed-run", passing}});
  ASSERT_EQ(set.cases.size(), 1u);
  EXPECT_EQ(set.cases[0].name, "listed-run");
  EXPECT_EQ(set.cases[0].info->timeout, 60);
  EXPECT_FALSE(set.cases[0].info->threads.has_value());
  EXPECT_EQ(set.cases[0].folder->path.filename(), "my-case");
}

TEST(CaseFolders, MissingKeyNamesTheFile) {
  const fs::path dir = folder_with("missing", "bad-case",
                                   "summary: \"s\"\nkind: code\nruns:\n"
                                   "  - name: r\n    summary: \"x\"\n");
  const std::string e = error_of(dir, {{"r", passing}});
  EXPECT_NE(e.find("bad-case"), std::string::npos) << e;
  EXPECT_NE(e.find("label"), std::string::npos) << e;
}

} // namespace
