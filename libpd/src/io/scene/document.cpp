// Reading a scene file: the YAML document is scanned (one document, a map), then read section by
// section (sections.hpp); every failure, including malformed YAML, becomes a SceneError with the
// file, line and column and a hint.
#include "libpd/core/file_input.hpp"
#include "libpd/core/text.hpp"
#include "sections.hpp"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <yaml-cpp/eventhandler.h>

namespace pd {

namespace {

/// Messages quote the scene's text (and yaml-cpp quotes the offending character verbatim, e.g.
/// "unknown escape character: \0"); a NUL, newline or other control byte would cut or garble the
/// one-line message on a terminal, so it is shown as \xHH.
std::string printable(const std::string& text) {
  std::string out;
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (c < 0x20 || c == 0x7f) {
      out += fmt::format("\\x{:02x}", c);
    } else {
      out += ch;
    }
  }
  return out;
}

std::string format_error(const std::string& file, SourceMark mark, const std::string& what,
                         const std::string& hint) {
  std::string out = file;
  if (mark.line > 0) {
    out += fmt::format(":{}:{}", mark.line, mark.column);
  }
  out += ": error: " + printable(what);
  if (!hint.empty()) {
    out += "\n  hint: " + printable(hint);
  }
  return out;
}

} // namespace

/// Longest word of a scene error message: any real path or key fits.
constexpr std::size_t max_echoed_word = 400;

SceneError::SceneError(std::string file, SourceMark mark, const std::string& what,
                       const std::string& hint)
    // A scene's values may be megabytes long or hold any bytes: each word of the message is
    // cut and escaped, once, here.
    : std::runtime_error(format_error(printable(file, max_echoed_word), mark,
                                      printable_words(what, max_echoed_word),
                                      printable_words(hint, max_echoed_word))),
      file_(std::move(file)), mark_(mark) {}

namespace scene {

namespace {

/// Records where the root node of each document starts.
class DocumentScan : public YAML::EventHandler {
public:
  std::vector<YAML::Mark> roots;

  void OnDocumentStart(const YAML::Mark&) override { pending_ = true; }
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& m, YAML::anchor_t) override { root(m); }
  void OnAlias(const YAML::Mark& m, YAML::anchor_t) override { root(m); }
  void OnScalar(const YAML::Mark& m, const std::string&, YAML::anchor_t,
                const std::string&) override {
    root(m);
  }
  void OnSequenceStart(const YAML::Mark& m, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {
    root(m);
  }
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark& m, const std::string&, YAML::anchor_t,
                  YAML::EmitterStyle::value) override {
    root(m);
  }
  void OnMapEnd() override {}

private:
  bool pending_ = false;
  void root(const YAML::Mark& m) {
    if (pending_) {
      roots.push_back(m);
      pending_ = false;
    }
  }
};

struct TextPosition {
  int line = 0; ///< 0: none
  int column = 0;
  char c = 0;
};

/// The first character outside comments, white space and document markers ('---', '...'),
/// 1-based, if any.
TextPosition first_content(const std::string& text) {
  std::istringstream lines(text);
  std::string l;
  for (int line = 1; std::getline(lines, l); ++line) {
    const std::size_t at = l.find_first_not_of(" \t\r");
    if (at == std::string::npos || l[at] == '#' || l.compare(at, 3, "---") == 0 ||
        l.compare(at, 3, "...") == 0) {
      continue;
    }
    return {line, static_cast<int>(at) + 1, l[at]};
  }
  return {};
}

std::string malformed_hint(const std::string& msg, const std::string& text, int line) {
  // yaml-cpp reports a tab as "illegal map value" or the like; the line itself tells.
  std::istringstream lines(text);
  std::string current;
  for (int i = 0; i <= line && std::getline(lines, current); ++i) {
    if (i >= line - 1 && current.find('\t') != std::string::npos) {
      return fmt::format("line {} contains a tab: YAML indentation must use spaces only", i + 1);
    }
  }
  // yaml-cpp's depth guard reports runaway nesting as "bad file".
  if (msg.find("bad file") != std::string::npos) {
    return "the brackets nest too deeply; a scene needs at most three levels ([[[x], [x]]])";
  }
  if (msg.find("sequence flow") != std::string::npos) {
    return "a '[' is not closed by a matching ']'";
  }
  if (msg.find("map flow") != std::string::npos) {
    return "a '{' is not closed by a matching '}'";
  }
  if (msg.find("anchor") != std::string::npos) {
    return "define an anchor with '&name' before referring to it with '*name'";
  }
  if (msg.find("tab") != std::string::npos || msg.find("block entry") != std::string::npos) {
    return "indent with spaces only, and align list items '-' under their key";
  }
  if (msg.find("map value") != std::string::npos) {
    return "check the indentation of this line, and quote values that contain ': '";
  }
  if (msg.find("quote") != std::string::npos || msg.find("end of") != std::string::npos) {
    return "close the quoted string or bracket that starts here";
  }
  return "check the indentation (spaces only) and that every bracket and quote is closed";
}

} // namespace

Scene parse(const std::string& text, const std::string& name) {
  Scene scene;
  std::vector<std::string> warnings;
  Reader r(name, warnings);
  try {
    // Not YAML::LoadAll: yaml-cpp 0.7 loops forever on some malformed streams (one starting
    // with ',', jbeder/yaml-cpp#1040, fixed upstream by PR #1319), appending empty documents
    // until memory runs out. Scan at most two documents with the event parser instead.
    std::istringstream stream(text);
    YAML::Parser parser(stream);
    DocumentScan scan;
    for (int documents = 0; documents < 2 && parser.HandleNextDocument(scan); ++documents) {
    }
    const YAML::Node root = YAML::Load(text);
    if (root.IsNull()) {
      const auto [line, column, c] = first_content(text);
      if (line > 0) {
        throw SceneError(
            name, {line, column},
            fmt::format("malformed YAML: unexpected '{}' where the scene should start", c),
            "a scene is a map of 'key: value' lines; remove the stray character");
      }
      throw SceneError(name, {1, 1}, "the scene is empty",
                       "start from the template printed by 'pd run --print-defaults'");
    }
    if (scan.roots.size() > 1) {
      const YAML::Mark& m = scan.roots[1];
      throw SceneError(name, {m.line + 1, m.column + 1},
                       "a scene file holds one YAML document, found a second one",
                       "remove the '---' separator and everything after it, or split the file");
    }
    scene = read_scene(root, r);
  } catch (const SceneError&) {
    throw;
  } catch (const YAML::Exception& e) {
    const SourceMark mark =
        e.mark.is_null() ? SourceMark{} : SourceMark{e.mark.line + 1, e.mark.column + 1};
    throw SceneError(name, mark, "malformed YAML: " + e.msg,
                     malformed_hint(e.msg, text, e.mark.line));
  } catch (const std::exception& e) {
    // Only a defect of the checks above gets here; still report it in the promised form.
    throw SceneError(name, {}, fmt::format("internal error while reading the scene: {}", e.what()),
                     "please report this scene to the libpd developers");
  }
  scene.warnings = std::move(warnings);
  return scene;
}

} // namespace scene

Scene parse_scene(const std::string& text, const std::string& name) {
  return scene::parse(text, name);
}

Scene load_scene(const std::string& path) {
  std::string text;
  try {
    text = read_regular_file(path, max_scene_bytes);
  } catch (const FileInputError& e) {
    throw SceneError(
        path, {}, fmt::format("the scene file {}", e.what()),
        fmt::format("give the path of a .yaml scene file (at most {} MiB)", max_scene_bytes >> 20));
  }
  Scene scene = scene::parse(text, path);
  scene.path = path;
  return scene;
}

} // namespace pd
