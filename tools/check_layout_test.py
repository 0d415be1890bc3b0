#!/usr/bin/env python3
"""Tests of tools/check_layout.py: small trees written to a temporary folder, each with one
offence the checker must name (or none, and it must pass).

    python3 tools/check_layout_test.py        (ctest: layout.check_test, label unit)
"""
from __future__ import annotations

import contextlib
import io
import sys
import tempfile
import textwrap
import unittest
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import check_layout  # noqa: E402


def body(lines: int, indent: str = "  ") -> str:
    """`lines` statement lines for a C++ function body."""
    return "".join(f"{indent}x += {k};\n" for k in range(lines))


def cpp_function(name: str, total_lines: int, before: str = "") -> str:
    """A function `name` spanning `total_lines` lines from its `{` line to its `}` line."""
    return f"int {name}(int x) {{{before}\n" + body(total_lines - 3) + "  return x;\n}\n"


def python_function(name: str, total_lines: int) -> str:
    return f"def {name}(x):\n" + "".join("    x += 1\n" for _ in range(total_lines - 2)) + \
        "    return x\n"


class LayoutTest(unittest.TestCase):
    def setUp(self):
        self._tmp = tempfile.TemporaryDirectory()
        self.root = Path(self._tmp.name)
        # The smallest valid tree: two layers, one public header, a program, a case, an FE file.
        self.write("libpd/include/libpd/core/a.hpp", "#pragma once\nint a();\n")
        self.write("libpd/src/core/a.cpp", '#include "libpd/core/a.hpp"\nint a() { return 1; }\n')
        self.write("libpd/include/libpd/time/t.hpp",
                   '#pragma once\n#include "libpd/core/a.hpp"\nint t();\n')
        self.write("libpd/src/time/private.hpp", "#pragma once\nint p();\n")
        self.write("libpd/CMakeLists.txt", "add_library(libpd src/core/a.cpp)\n")
        self.write("verification/runner/verification.hpp", "#pragma once\nint v();\n")
        self.write("verification/runner/verification.cpp",
                   '#include "verification.hpp"\n#include "libpd/time/t.hpp"\n'
                   "int v() { return 2; }\n")
        self.write("fem_reference/src/fe.cc",
                   '#include <deal.II/base/point.h>\n#include "libpd/core/a.hpp"\n'
                   "int fe() { return 3; }\n")
        self.write("libpd/cli/main.cpp",
                   '#include "verification.hpp"\n#include "libpd/time/t.hpp"\n'
                   "int main() { return v(); }\n")
        self.write("libpd/cli/CMakeLists.txt",
                   "target_link_libraries(pd PRIVATE libpd pd_verification)\n")
        self.write("reports/pdreport/stages.py", python_function("stage", 20))

    def tearDown(self):
        self._tmp.cleanup()

    def write(self, rel: str, text: str) -> None:
        path = self.root / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)

    def run_checker(self, *args: str) -> tuple[int, str]:
        out = io.StringIO()
        with contextlib.redirect_stdout(out):
            code = check_layout.main(["--root", str(self.root), *args])
        return code, out.getvalue()

    def assert_passes(self):
        code, out = self.run_checker()
        self.assertEqual(code, 0, out)
        self.assertIn(" 0 problems", out)

    def assert_flags(self, *fragments: str, problems: int = 1):
        code, out = self.run_checker()
        self.assertEqual(code, 1, out)
        self.assertIn(f" {problems} problems", out)
        for fragment in fragments:
            self.assertIn(fragment, out)
        return out

    # ---- trees that pass ----------------------------------------------------------------------

    def test_valid_tree_passes(self):
        self.assert_passes()

    def test_program_in_top_level_pd_folder_passes(self):
        # After libpd/cli/ moves to pd/, the program may still use verification.
        (self.root / "libpd/cli/main.cpp").rename(self.root / "libpd/cli/gone.txt")
        (self.root / "libpd/cli/CMakeLists.txt").unlink()
        self.write("pd/main.cpp", '#include "verification.hpp"\n#include "libpd/app/x.hpp"\n'
                   "int main() { return v(); }\n")
        self.write("libpd/include/libpd/app/x.hpp", "#pragma once\n")
        self.write("pd/CMakeLists.txt", "target_link_libraries(pd PRIVATE pd_verification)\n")
        self.assert_passes()

    def test_function_at_the_limit_passes(self):
        self.write("libpd/src/core/b.cpp", cpp_function("exactly", 120))
        self.write("reports/pdreport/cases.py", python_function("exactly", 80))
        self.assert_passes()

    def test_literals_that_look_like_code_pass(self):
        # Quotes and braces in comments and literals invent no block and hide no function.
        self.write("libpd/src/core/lit.cpp", textwrap.dedent("""\
            // a comment with a quote ' and a brace {
            /* a block comment with "a string" and { and ' */
            const char* s = "a \\" quote and a { brace";
            const char* u = u8"x'{";
            const wchar_t* w = L"}";
            const char* r = R"({"key": "value"})";
            const char q = '\\'';
            const char b = '{';
            const char8_t e = u8'x';
            long big = 1'000'000'000;
            int f() { return 0x7fff'ffff > 1'000.5e3 ? 1 : 0; }
            """) + cpp_function("fine", 120))
        self.assert_passes()

    def test_test_bodies_and_test_files_are_not_sized(self):
        # A GoogleTest body is one input and its assertions; its file follows one component.
        self.write("tests/unit/core/a_test.cpp",
                   "TEST(A, Long) {\n" + body(200) + "}\n" + "// filler\n" * 700)
        self.assert_passes()

    # ---- trees that fail ----------------------------------------------------------------------

    def test_function_hidden_after_digit_separators_is_flagged(self):
        # The old reader took 1'000 for a character literal and lost the function after it.
        self.write("libpd/src/time/q.cpp",
                   "constexpr long limit = 1'000'000'000;\n" + cpp_function("hidden", 125))
        self.assert_flags("libpd/src/time/q.cpp:2: function hidden has 125 lines")

    def test_function_after_digit_separator_inside_it_is_flagged(self):
        self.write("libpd/src/time/q.cpp", cpp_function("run", 121, before=" long n = 1'000;"))
        self.assert_flags("function run has 121 lines")

    def test_raw_string_with_braces_and_quotes_is_read_whole(self):
        # Unbalanced braces and stray quotes inside a raw string with a delimiter and a prefix.
        self.write("libpd/src/io/r.cpp", textwrap.dedent('''\
            const char* scene = R"yaml(
            a: "}}}"
            b: '{'
            c: ")"
            )yaml";
            const char* other = u8R"({ " ')";
            ''') + cpp_function("after_raw", 130))
        self.assert_flags("libpd/src/io/r.cpp:7: function after_raw has 130 lines")

    def test_long_function_in_verification_and_fem_reference_is_flagged(self):
        self.write("verification/cases/c.cpp", cpp_function("run_case", 121))
        self.write("fem_reference/src/f.cc", cpp_function("solve", 122))
        self.assert_flags("verification/cases/c.cpp:1: function run_case has 121 lines",
                          "fem_reference/src/f.cc:1: function solve has 122 lines", problems=2)

    def test_long_test_helper_is_flagged(self):
        self.write("tests/unit/core/a_test.cpp", cpp_function("make_input", 121))
        self.assert_flags("function make_input has 121 lines")

    def test_upward_include_is_flagged(self):
        self.write("libpd/src/core/up.cpp", '#include "libpd/time/t.hpp"\n')
        self.assert_flags("libpd/src/core/up.cpp:1: layer 'core' includes libpd/time/t.hpp")

    def test_include_in_a_comment_or_raw_string_is_not_an_include(self):
        self.write("libpd/src/core/c.cpp", '// #include "libpd/time/t.hpp"\n'
                   'const char* s = R"(\n#include "libpd/time/t.hpp"\n)";\n')
        self.assert_passes()

    def test_include_cycle_is_flagged(self):
        self.write("libpd/include/libpd/core/b.hpp", '#include "libpd/core/c.hpp"\n')
        self.write("libpd/include/libpd/core/c.hpp", '#include "libpd/core/b.hpp"\n')
        self.assert_flags("include cycle: libpd/core/b → libpd/core/c → libpd/core/b")

    def test_libpd_including_a_verification_header_is_flagged(self):
        self.write("libpd/src/app/v.cpp", '#include "verification.hpp"\n')
        self.assert_flags("libpd/src/app/v.cpp:1: includes verification.hpp "
                          "(verification/runner/verification.hpp)")

    def test_libpd_linking_verification_is_flagged(self):
        self.write("libpd/CMakeLists.txt", "# pd_verification in a comment is fine\n"
                   "target_link_libraries(libpd PRIVATE pd_verification)\n")
        self.assert_flags("libpd/CMakeLists.txt:2: names pd_verification")

    def test_deal_ii_outside_fem_reference_is_flagged(self):
        self.write("libpd/src/core/d.cpp", "#include <deal.II/base/point.h>\n")
        self.write("verification/cases/d.cpp", "#  include <deal.II/base/point.h>\n")
        self.assert_flags("libpd/src/core/d.cpp:1: includes deal.II",
                          "verification/cases/d.cpp:1: includes deal.II", problems=2)

    def test_fem_reference_including_libpd_src_is_flagged(self):
        self.write("fem_reference/src/g.cc", "#include <time/private.hpp>\n")
        self.write("fem_reference/CMakeLists.txt",
                   "target_include_directories(fe PRIVATE ${PROJECT_SOURCE_DIR}/libpd/src)\n")
        self.assert_flags("fem_reference/src/g.cc:1: includes time/private.hpp "
                          "(libpd/src/time/private.hpp), a private header",
                          "fem_reference/CMakeLists.txt:1: puts libpd/src on the include path",
                          problems=2)

    def test_including_a_libpd_path_that_is_not_public_is_flagged(self):
        self.write("verification/cases/e.cpp", '#include "libpd/time/private.hpp"\n')
        self.assert_flags("verification/cases/e.cpp:1: includes libpd/time/private.hpp, which "
                          "is not a public header")

    def test_python_function_of_81_lines_in_reports_is_flagged(self):
        self.write("reports/pdreport/long.py", "import os\n\n\n" + python_function("render", 81))
        self.assert_flags("reports/pdreport/long.py:4: function render has 81 lines (at most 80)")

    def test_long_python_file_and_long_cpp_file_are_flagged(self):
        self.write("tools/big.py", "x = 1\n" * 801)
        self.write("verification/cases/big.cpp", "int x;\n" * 801)
        self.assert_flags("tools/big.py: 801 lines", "verification/cases/big.cpp: 801 lines",
                          problems=2)


class LexerTest(unittest.TestCase):
    def blank(self, text: str) -> str:
        return check_layout.CppText(text).code

    def test_digit_separators_stay_in_the_number(self):
        self.assertEqual(self.blank("x = 1'000'000 + 0x7fff'ffff + 1'000.5e3;"),
                         "x = 1'000'000 + 0x7fff'ffff + 1'000.5e3;")

    def test_literals_are_blanked_and_lines_kept(self):
        text = 'a = "s\\"{"; b = \'\\\'\'; c = u8\'x\'; d = L"}";\ne = R"d(\n)"\n)d"; f;'
        self.assertEqual(self.blank(text), "a = \"\"; b = ''; c = ''; d = \"\";\ne = \"\"\n\n; f;")

    def test_identifier_ending_in_r_is_not_a_raw_string(self):
        self.assertEqual(self.blank('FOOR"(x"; y;'), 'FOOR""; y;')

    def test_includes_are_read_from_directives(self):
        cpp = check_layout.CppText('#include "a.hpp" // b.hpp\n  # include <c/d.hpp>\n'
                                   '/* #include "e.hpp" */\n')
        self.assertEqual(cpp.includes, [(1, '"', "a.hpp"), (2, "<", "c/d.hpp")])

    def test_constructor_initialiser_braces_stay_in_the_function(self):
        text = "A::A(int x) : a_{x}, b_{2} {\n" + body(125) + "}\n"
        self.assertEqual(check_layout.long_functions(self.blank(text), 120), [("A::A", 1, 127)])


if __name__ == "__main__":
    unittest.main()
