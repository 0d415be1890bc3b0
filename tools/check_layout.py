#!/usr/bin/env python3
"""Check libpd's layout rules; exit 1 and name every offence.

    python3 tools/check_layout.py [--max-file-lines 800] [--max-function-lines 120]

1. Dependencies point down. libpd's folders are layers, in this order:
       core → physics → discretisation → kernel → time → io → app → cli
   A file in layer L (libpd/include/libpd/L/ or libpd/src/L/; libpd/cli/ is `cli`) may include
   `libpd/M/...` only for M at or below L.
2. No include cycle among libpd's components (a component is a header with its source file, so
   a.cpp including b.hpp while b.hpp includes a.hpp is a cycle).
3. libpd never includes deal.II.
4. No source file in libpd/ over --max-file-lines lines, no function over --max-function-lines
   lines (a function: a brace block opened after `)` at namespace or class scope; its lambdas
   count towards it).
ctest runs this as `layout.check` (label unit), so an upward include fails CI.
"""
from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
LIBPD = ROOT / "libpd"
LAYERS = ["core", "physics", "discretisation", "kernel", "time", "io", "app", "cli"]
INCLUDE = re.compile(r'^\s*#\s*include\s*[<"](libpd/[^>"]+)[>"]', re.M)
SOURCES = (".hpp", ".cpp", ".h")


def layer_of(path: Path) -> str | None:
    rel = path.relative_to(LIBPD).parts
    if rel[0] == "cli":
        return "cli"
    if rel[0] == "bench":
        return "cli"  # benchmarks sit on top, like the CLI
    if rel[:2] == ("include", "libpd") and len(rel) > 3:
        return rel[2]
    if rel[0] == "src" and len(rel) > 2:
        return rel[1]
    return None


def component_of(path: Path) -> str | None:
    """'libpd/discretisation/model' for include/libpd/discretisation/model.hpp and
    src/discretisation/model.cpp."""
    rel = path.relative_to(LIBPD).parts
    if rel[:2] == ("include", "libpd"):
        return str(Path(*rel[1:]).with_suffix(""))
    if rel[0] == "src":
        return str(Path("libpd", *rel[1:]).with_suffix(""))
    return None


def strip_comments_and_strings(text: str) -> str:
    """Blank out comments, string and character literals, keeping line breaks."""
    out, i, n = [], 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append("\n" * text.count("\n", i, j))
            i = j
        elif c == "R" and text.startswith('R"', i):
            m = re.match(r'R"([^(\s]*)\(', text[i:])
            if m:
                end = text.find(")" + m.group(1) + '"', i)
                end = n if end < 0 else end + len(m.group(1)) + 2
                out.append('""' + "\n" * text.count("\n", i, end))
                i = end
            else:
                out.append(c)
                i += 1
        elif c in "\"'":
            j = i + 1
            while j < n and text[j] != c:
                j += 2 if text[j] == "\\" else 1
            out.append(c + c)
            i = j + 1
        else:
            out.append(c)
            i += 1
    return "".join(out)


def long_functions(path: Path, limit: int):
    """(name, first line, length) of function bodies longer than `limit` lines."""
    text = strip_comments_and_strings(path.read_text())
    stack: list[tuple[str, int, str]] = []  # (kind, line, name)
    line, i, n = 1, 0, len(text)
    head_start = 0  # start of the text since the last ; { or } at this level
    found = []
    while i < n:
        c = text[i]
        if c == "\n":
            line += 1
        elif c == "{":
            head = text[head_start:i]
            scope = stack[-1][0] if stack else "namespace"
            kind = "other"
            name = ""
            if scope in ("namespace", "class"):
                if re.search(r"\b(namespace)\b[^;]*$", head):
                    kind = "namespace"
                elif re.search(r"\b(class|struct|union)\b[^()]*$", head):
                    kind = "class"
                elif re.search(r"\)\s*(const\s*)?(noexcept\s*)?(override\s*)?(final\s*)?"
                               r"(->\s*[\w:<>,\s*&]+)?\s*(:[^{]*)?$", head, re.S):
                    kind = "function"
                    m = re.search(r"([\w:~]+)\s*\([^{]*$", head, re.S)
                    name = m.group(1) if m else "?"
            stack.append((kind, line, name))
            head_start = i + 1
        elif c == "}":
            if stack:
                kind, start, name = stack.pop()
                if kind == "function" and line - start + 1 > limit:
                    found.append((name, start, line - start + 1))
            head_start = i + 1
        elif c == ";":
            head_start = i + 1
        i += 1
    return found


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-file-lines", type=int, default=800)
    parser.add_argument("--max-function-lines", type=int, default=120)
    args = parser.parse_args()

    problems: list[str] = []
    files = sorted(p for p in LIBPD.rglob("*") if p.suffix in SOURCES)
    headers = {}
    for f in files:
        rel = f.relative_to(ROOT)
        text = f.read_text()
        layer = layer_of(f)
        if layer is None:
            problems.append(f"{rel}: not inside a layer folder ({', '.join(LAYERS)})")
        elif layer not in LAYERS:
            problems.append(f"{rel}: unknown layer '{layer}'")
        includes = INCLUDE.findall(text)
        for inc in includes:
            parts = inc.split("/")
            target = parts[1] if len(parts) > 2 else None
            if target is None or target not in LAYERS:
                problems.append(f"{rel}: includes {inc}, which is not in a layer folder")
            elif layer in LAYERS and LAYERS.index(target) > LAYERS.index(layer):
                problems.append(f"{rel}: layer '{layer}' includes {inc} from the higher layer "
                                f"'{target}'")
        if re.search(r"#\s*include\s*[<\"]deal\.II/", text):
            problems.append(f"{rel}: includes deal.II (libpd must not)")
        lines = text.count("\n")
        if lines > args.max_file_lines:
            problems.append(f"{rel}: {lines} lines (at most {args.max_file_lines})")
        for name, start, length in long_functions(f, args.max_function_lines):
            problems.append(f"{rel}:{start}: function {name} has {length} lines "
                            f"(at most {args.max_function_lines})")
        component = component_of(f)
        if component:
            headers.setdefault(component, set()).update(
                inc[: -len(".hpp")] for inc in includes if inc.endswith(".hpp"))

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

    for p in problems:
        print(p)
    print(f"{len(files)} files checked, {len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
