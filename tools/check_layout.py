#!/usr/bin/env python3
"""Check the source tree's layout rules; exit 1 and name every offence.

    python3 tools/check_layout.py [--root DIR] [--max-file-lines 800]
                                  [--max-function-lines 120] [--max-python-function-lines 80]

Where the rules apply: libpd/ (the library, its benchmarks and, until it moves to a top-level
pd/, the `pd` program in libpd/cli/), pd/ (the program), verification/, fem_reference/, tools/,
tests/ and reports/.

1. Dependencies point down. libpd's folders are layers, in this order:
       core → physics → discretisation → kernel → time → io → app → cli
   A file in layer L (libpd/include/libpd/L/ or libpd/src/L/) may include `libpd/M/...` only
   for M at or below L. The program (pd/ or libpd/cli/) and libpd/bench/ are the layer `cli`.
2. No include cycle among libpd's components (a component is a header with its source file, so
   a.cpp including b.hpp while b.hpp includes a.hpp is a cycle).
3. The library (libpd/ outside cli/) never includes or links the verification cases or the
   finite-element reference: no include that resolves to a file in verification/ or
   fem_reference/, no `pd_verification` or `pd_fem` in its CMake files. The program sits above
   both and may use them.
4. deal.II is included only in fem_reference/.
5. fem_reference/, verification/ and the program use libpd through its public headers
   (libpd/include/libpd/...): no include that resolves to a file in libpd/src/, and
   fem_reference's CMake files do not put libpd/src on the include path.
6. Sizes. No C++ source (.hpp .cpp .h .cc) over --max-file-lines lines, no C++ function over
   --max-function-lines lines (a function: a brace block opened after `)` at namespace or class
   scope; its lambdas count towards it). No Python file over --max-file-lines lines, no Python
   function over --max-python-function-lines lines (`end_lineno - lineno + 1` from `ast`, so a
   nested function counts towards its parent and is also checked itself).
   GoogleTest files in tests/ are held to the function limit for their helpers, but neither
   their length nor a TEST body's is limited: a test file mirrors one source file, and a test
   body is one input followed by the assertions on it (a whole scene and every field it fills),
   with no steps to name; cutting either by line count would scatter one component's or one
   input's checks over places chosen by size. Python in tests/ (the harness scripts) is a
   program like tools/ and obeys every limit.
   Generated and build trees (build*/, out/, __pycache__/, hidden folders) are not checked.

The C++ reader blanks comments, string and character literals (with their prefixes u8 u U L,
raw strings R"d(...)d" with any delimiter) and preprocessor lines before it counts braces, and it
reads digit separators (1'000'000, 0x7fff'ffff) as part of the number, so a quote or brace in a
literal neither hides nor invents a function.
ctest runs this as `layout.check` (label unit), and tools/check_layout_test.py as
`layout.check_test`.
"""
from __future__ import annotations

import argparse
import ast
import re
import sys
from pathlib import Path

LAYERS = ["core", "physics", "discretisation", "kernel", "time", "io", "app", "cli"]
CPP_SOURCES = (".hpp", ".cpp", ".h", ".cc")
CHECKED_TREES = ["libpd", "pd", "verification", "fem_reference", "tools", "tests", "reports"]
SKIPPED_DIRS = {"__pycache__", "out", "node_modules"}
# Folders that are the `pd` program: the cli layer, allowed to use verification and fem_reference.
PROGRAM_DIRS = [("pd",), ("libpd", "cli")]
FORBIDDEN_LINKS = re.compile(r"\b(pd_verification|pd_fem\w*)\b")
LIBPD_SRC_ON_PATH = re.compile(r"libpd/src\b")
GTEST_BODIES = {"TEST", "TEST_F", "TEST_P", "TYPED_TEST", "TYPED_TEST_P"}
DIRECTIVE_INCLUDE = re.compile(r'^#\s*include\s*([<"])([^>"]+)[>"]')


# ----------------------------------------------------------------------------------------------
# Reading C++


class CppText:
    """A C++ file with comments, literals and preprocessor lines blanked out (line breaks kept),
    and its #include directives as (line, delimiter, path)."""

    IDENT = re.compile(r"[A-Za-z_]\w*")
    STRING_PREFIXES = {"u8", "u", "U", "L"}
    RAW_PREFIXES = {"R", "u8R", "uR", "UR", "LR"}

    def __init__(self, text: str):
        self.includes: list[tuple[int, str, str]] = []
        self.code = self._blank(text)

    def _blank(self, text: str) -> str:
        out: list[str] = []
        i, n, line = 0, len(text), 1
        at_line_start = True  # only whitespace since the last line break
        while i < n:
            c = text[i]
            if c == "\n":
                out.append(c)
                line += 1
                at_line_start = True
                i += 1
                continue
            if c in " \t\r\f\v":
                out.append(c)
                i += 1
                continue
            if c == "#" and at_line_start:
                j = self._directive_end(text, i)
                directive = self._directive_text(text[i:j])
                m = DIRECTIVE_INCLUDE.match(directive)
                if m:
                    self.includes.append((line, m.group(1), m.group(2)))
                breaks = text.count("\n", i, j)
                out.append("\n" * breaks)
                line += breaks
                i = j
                continue
            at_line_start = False
            if text.startswith("//", i):
                j = self._line_comment_end(text, i)
                breaks = text.count("\n", i, j)
                out.append("\n" * breaks)
                line += breaks
                i = j
            elif text.startswith("/*", i):
                j = text.find("*/", i + 2)
                j = n if j < 0 else j + 2
                breaks = text.count("\n", i, j)
                out.append("\n" * breaks)
                line += breaks
                i = j
            elif c.isdigit() or (c == "." and i + 1 < n and text[i + 1].isdigit()):
                j = self._number_end(text, i)
                out.append(text[i:j])
                i = j
            elif c.isalpha() or c == "_":
                m = self.IDENT.match(text, i)
                word, j = m.group(0), m.end()
                if word in self.RAW_PREFIXES and text.startswith('"', j):
                    end = self._raw_string_end(text, j)
                    if end is not None:
                        breaks = text.count("\n", i, end)
                        out.append('""' + "\n" * breaks)
                        line += breaks
                        i = end
                        continue
                if word in self.STRING_PREFIXES and j < n and text[j] in "\"'":
                    end = self._quoted_end(text, j)
                    out.append(text[j] * 2)
                    line += text.count("\n", i, end)  # only an unterminated literal has one
                    i = end
                    continue
                out.append(word)
                i = j
            elif c in "\"'":
                end = self._quoted_end(text, i)
                out.append(c * 2)
                line += text.count("\n", i, end)
                i = end
            else:
                out.append(c)
                i += 1
        return "".join(out)

    @staticmethod
    def _directive_end(text: str, i: int) -> int:
        """End of a preprocessor directive: its line, with backslash continuations; a block
        comment that starts in it may run over lines."""
        n = len(text)
        while i < n:
            if text.startswith("/*", i):
                j = text.find("*/", i + 2)
                i = n if j < 0 else j + 2
            elif text.startswith("//", i):
                return CppText._line_comment_end(text, i)
            elif text[i] == "\\" and text.startswith("\n", i + 1):
                i += 2
            elif text[i] == "\n":
                return i
            else:
                i += 1
        return n

    @staticmethod
    def _directive_text(directive: str) -> str:
        directive = re.sub(r"/\*.*?\*/", " ", directive, flags=re.S)
        directive = re.sub(r"//.*", "", directive)
        return directive.replace("\\\n", " ").strip()

    @staticmethod
    def _line_comment_end(text: str, i: int) -> int:
        """A // comment ends at a line break not escaped by a backslash."""
        n = len(text)
        while True:
            j = text.find("\n", i)
            if j < 0:
                return n
            if text[j - 1] == "\\" or (text[j - 1] == "\r" and text[j - 2] == "\\"):
                i = j + 1
                continue
            return j

    @staticmethod
    def _number_end(text: str, i: int) -> int:
        """A pp-number: digits, letters, '.', exponent signs and digit separators (a ' between
        two digits or letters, as in 1'000'000 or 0x7fff'ffff)."""
        n = len(text)
        j = i + 1
        while j < n:
            c = text[j]
            if c.isalnum() or c in "._":
                j += 1
            elif c in "+-" and text[j - 1] in "eEpP":
                j += 1
            elif c == "'" and j + 1 < n and (text[j + 1].isalnum() or text[j + 1] == "_"):
                j += 2
            else:
                break
        return j

    @staticmethod
    def _quoted_end(text: str, i: int) -> int:
        """End (one past the closing quote) of a "..." or '...' literal starting at i; an
        unterminated literal ends at the line break, as the compiler would reject it there."""
        quote, n, j = text[i], len(text), i + 1
        while j < n and text[j] != quote:
            if text[j] == "\\":
                j += 2
            elif text[j] == "\n":
                return j
            else:
                j += 1
        return min(j + 1, n)

    @staticmethod
    def _raw_string_end(text: str, i: int) -> int | None:
        """End of a raw string whose opening quote is at i, or None if the delimiter is not
        one (then the quote is an ordinary string)."""
        m = re.compile(r'"([^()\\\s"]{0,16})\(').match(text, i)
        if not m:
            return None
        closing = ")" + m.group(1) + '"'
        end = text.find(closing, m.end())
        return len(text) if end < 0 else end + len(closing)


FUNCTION_HEAD = re.compile(
    r"\)\s*((const|volatile|noexcept|override|final|mutable|&&|&)\s*|noexcept\s*\([^()]*\)\s*)*"
    r"(->\s*[\w:<>,\s*&]+)?\s*(requires\b[^{]*)?(:[^{]*)?$", re.S)
CTOR_INIT = re.compile(r"\)\s*(noexcept\s*)?(?<!:):(?!:)")


def long_functions(code: str, limit: int):
    """(name, first line, length) of function bodies in blanked C++ longer than `limit` lines."""
    stack: list[tuple[str, int, str]] = []  # (kind, line, name)
    line, n = 1, len(code)
    head_start = 0  # start of the text since the last ; { or } at this level
    found = []
    for i in range(n):
        c = code[i]
        if c == "\n":
            line += 1
        elif c == "{":
            # Braces of a constructor's member initialisers (`: a_{1}`) stay in the head.
            raw_head = head = code[head_start:i]
            while True:
                stripped = re.sub(r"\{[^{}]*\}", "", head)
                if stripped == head:
                    break
                head = stripped
            scope = stack[-1][0] if stack else "namespace"
            kind, name = "other", ""
            if scope in ("namespace", "class"):
                if re.search(r"\bnamespace\b[^;]*$", head) or re.search(r'\bextern\s*""\s*$',
                                                                         head):
                    kind = "namespace"
                elif re.search(r"\b(class|struct|union|enum)\b[^()]*$", head):
                    kind = "class"
                elif CTOR_INIT.search(head) and re.search(r"[\w>]\s*$", raw_head):
                    kind = "initialiser"
                elif FUNCTION_HEAD.search(head):
                    kind = "function"
                    m = re.search(r"([\w:~]+)\s*\([^{]*$", head, re.S)
                    name = m.group(1) if m else "?"
            stack.append((kind, line, name))
            if kind != "initialiser":
                head_start = i + 1
        elif c == "}":
            if stack:
                kind, start, name = stack.pop()
                if kind == "function" and line - start + 1 > limit:
                    found.append((name, start, line - start + 1))
                if kind == "initialiser":
                    continue
            head_start = i + 1
        elif c == ";":
            head_start = i + 1
    return found


def long_python_functions(text: str, filename: str, limit: int):
    """(name, first line, length) of Python functions longer than `limit` lines."""
    tree = ast.parse(text, filename=filename)
    found = []
    for node in ast.walk(tree):
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            length = node.end_lineno - node.lineno + 1
            if length > limit:
                found.append((node.name, node.lineno, length))
    return sorted(found, key=lambda f: f[1])


# ----------------------------------------------------------------------------------------------
# The tree


class Tree:
    def __init__(self, root: Path):
        self.root = root
        self.files = sorted(p for top in CHECKED_TREES for p in self._walk(root / top))
        self.rel = {p: p.relative_to(root).parts for p in self.files}
        # Every C++ file by root-relative path, to resolve an include by its path suffix.
        self.cpp_paths = ["/".join(self.rel[p]) for p in self.files if p.suffix in CPP_SOURCES]

    @staticmethod
    def _walk(top: Path):
        if not top.is_dir():
            return
        for p in top.iterdir():
            if p.name.startswith(".") or p.name in SKIPPED_DIRS or (
                    p.is_dir() and p.name.startswith("build")):
                continue
            if p.is_dir():
                yield from Tree._walk(p)
            elif p.is_file():
                yield p

    def resolve(self, include: str) -> list[str]:
        """Root-relative paths of C++ files an include could name (by path suffix)."""
        suffix = "/" + include.lstrip("./")
        return [p for p in self.cpp_paths if ("/" + p).endswith(suffix)]


def is_program(rel: tuple[str, ...]) -> bool:
    return any(rel[: len(d)] == d for d in PROGRAM_DIRS)


def layer_of(rel: tuple[str, ...]) -> str | None:
    """The layer of a root-relative path inside libpd/ or pd/."""
    if is_program(rel) or rel[:2] == ("libpd", "bench"):
        return "cli"  # the program and the benchmarks sit on top
    if rel[:3] == ("libpd", "include", "libpd") and len(rel) > 4:
        return rel[3]
    if rel[:2] == ("libpd", "src") and len(rel) > 3:
        return rel[2]
    return None


def component_of(rel: tuple[str, ...]) -> str | None:
    """'libpd/discretisation/model' for libpd/include/libpd/discretisation/model.hpp and
    libpd/src/discretisation/model.cpp."""
    if rel[:3] == ("libpd", "include", "libpd"):
        return str(Path(*rel[2:]).with_suffix(""))
    if rel[:2] == ("libpd", "src"):
        return str(Path("libpd", *rel[2:]).with_suffix(""))
    return None


def in_library(rel: tuple[str, ...]) -> bool:
    """libpd/ without the program."""
    return rel[0] == "libpd" and not is_program(rel)


def check_libpd_includes(tree: Tree, rel, includes, problems, headers) -> None:
    name = "/".join(rel)
    layer = layer_of(rel)
    if layer is None:
        problems.append(f"{name}: not inside a layer folder ({', '.join(LAYERS)})")
    elif layer not in LAYERS:
        problems.append(f"{name}: unknown layer '{layer}'")
    for line, _, inc in includes:
        if inc.startswith("libpd/"):
            parts = inc.split("/")
            target = parts[1] if len(parts) > 2 else None
            if target is None or target not in LAYERS:
                problems.append(f"{name}:{line}: includes {inc}, which is not in a layer folder")
            elif layer in LAYERS and LAYERS.index(target) > LAYERS.index(layer):
                problems.append(f"{name}:{line}: layer '{layer}' includes {inc} from the higher "
                                f"layer '{target}'")
        if in_library(rel):
            targets = tree.resolve(inc)
            outside = [t for t in targets if t.split("/")[0] in ("verification", "fem_reference")]
            if outside and not any(t.startswith("libpd/") for t in targets):
                problems.append(f"{name}:{line}: includes {inc} ({outside[0]}); libpd must not "
                                f"depend on verification or fem_reference")
    component = component_of(rel)
    if component:
        headers.setdefault(component, set()).update(
            inc[: -len(".hpp")] for _, _, inc in includes
            if inc.startswith("libpd/") and inc.endswith(".hpp"))


def check_public_headers_only(tree: Tree, rel, includes, problems) -> None:
    """fem_reference, verification and the program see libpd only through libpd/include."""
    name = "/".join(rel)
    for line, _, inc in includes:
        targets = tree.resolve(inc)
        if inc.startswith("libpd/"):
            if not (tree.root / "libpd" / "include" / inc).is_file():
                problems.append(f"{name}:{line}: includes {inc}, which is not a public header "
                                f"of libpd (libpd/include/{inc} does not exist)")
            continue
        private = [t for t in targets if t.startswith("libpd/src/")]
        own = [t for t in targets if not t.startswith("libpd/")]
        if private and not own:
            problems.append(f"{name}:{line}: includes {inc} ({private[0]}), a private header "
                            f"of libpd; use libpd/include/libpd/...")


def check_cmake(tree: Tree, path: Path, problems) -> None:
    rel = tree.rel[path]
    name = "/".join(rel)
    text = re.sub(r"#.*", "", path.read_text())  # CMake comments
    if in_library(rel):
        for m in FORBIDDEN_LINKS.finditer(text):
            line = text.count("\n", 0, m.start()) + 1
            problems.append(f"{name}:{line}: names {m.group(1)}; libpd must not link the "
                            f"verification cases or the finite-element reference")
    if rel[0] == "fem_reference":
        for m in LIBPD_SRC_ON_PATH.finditer(text):
            line = text.count("\n", 0, m.start()) + 1
            problems.append(f"{name}:{line}: puts libpd/src on the include path; fem_reference "
                            f"uses libpd's public headers only")


def check(root: Path, max_file: int, max_function: int, max_python_function: int):
    """(problems, number of files checked)."""
    tree = Tree(root)
    problems: list[str] = []
    headers: dict[str, set[str]] = {}
    checked = 0
    for f in tree.files:
        rel = tree.rel[f]
        name = "/".join(rel)
        if f.name == "CMakeLists.txt" or f.suffix == ".cmake":
            check_cmake(tree, f, problems)
            continue
        if f.suffix not in CPP_SOURCES and f.suffix != ".py":
            continue
        checked += 1
        text = f.read_text(encoding="utf-8", errors="replace")
        lines = text.count("\n") + (0 if text.endswith("\n") or not text else 1)
        gtest = rel[0] == "tests" and f.suffix in CPP_SOURCES
        if lines > max_file and not gtest:
            problems.append(f"{name}: {lines} lines (at most {max_file})")
        if f.suffix == ".py":
            try:
                long = long_python_functions(text, name, max_python_function)
            except SyntaxError as e:
                problems.append(f"{name}:{e.lineno}: Python syntax error: {e.msg}")
                continue
            for fn, start, length in long:
                problems.append(f"{name}:{start}: function {fn} has {length} lines "
                                f"(at most {max_python_function})")
            continue
        cpp = CppText(text)
        if rel[0] in ("libpd", "pd"):
            check_libpd_includes(tree, rel, cpp.includes, problems, headers)
        if rel[0] in ("fem_reference", "verification") or is_program(rel):
            check_public_headers_only(tree, rel, cpp.includes, problems)
        if rel[0] != "fem_reference":
            for line, _, inc in cpp.includes:
                if inc.startswith("deal.II/"):
                    problems.append(f"{name}:{line}: includes deal.II, which only fem_reference "
                                    f"may")
        for fn, start, length in long_functions(cpp.code, max_function):
            if gtest and fn in GTEST_BODIES:
                continue
            problems.append(f"{name}:{start}: function {fn} has {length} lines "
                            f"(at most {max_function})")

    # Include cycles among the components (depth-first search).
    state: dict[str, int] = {}
    path: list[str] = []

    def visit(h: str) -> None:
        state[h] = 1
        path.append(h)
        for nxt in sorted(headers.get(h, [])):
            if nxt == h or nxt not in headers:
                continue
            if state.get(nxt) == 1:
                cycle = path[path.index(nxt):] + [nxt]
                problems.append("include cycle: " + " → ".join(cycle))
            elif nxt not in state:
                visit(nxt)
        path.pop()
        state[h] = 2

    for h in sorted(headers):
        if h not in state:
            visit(h)
    return problems, checked


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", type=Path, default=Path(__file__).resolve().parent.parent,
                        help="the tree to check (default: this repository)")
    parser.add_argument("--max-file-lines", type=int, default=800)
    parser.add_argument("--max-function-lines", type=int, default=120)
    parser.add_argument("--max-python-function-lines", type=int, default=80)
    args = parser.parse_args(argv)
    problems, checked = check(args.root.resolve(), args.max_file_lines, args.max_function_lines,
                              args.max_python_function_lines)
    for p in problems:
        print(p)
    print(f"{checked} files checked, {len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
