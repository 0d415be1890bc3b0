"""Every option of every subcommand, with hostile values (issue 18: a CLI-option fuzzer).

The options are read from `pd SUB --help`, so a new option is fuzzed without editing this file.
Each call must end within a few seconds with a documented exit code (0-5), never by a signal,
and must not echo a 100 kB value back whole. Commands whose real work is slow are given an input
that fails fast after parsing (a missing scene, `verify --list`), so what is fuzzed is the
parsing and validation, which is where values used to wrap or hang.
"""
import re

import pdcli

VALUES = ["-1", "0", "-0", "1e308", "18446744073709551616", "nan", "inf", "-inf", "", "abc",
          "x" * 100_000, "1.5", "-9223372036854775809", "a\nb", "\x1b[2J"]
DOCUMENTED_EXIT_CODES = {0, 1, 2, 3, 4, 5}
LONGEST_LINE = 2000


def options_of(help_text):
    """Options that take a value: lines like '  --steps UINT=100  ...' or '-o,--output TEXT'."""
    found = []
    for line in help_text.splitlines():
        m = re.match(r"\s+(?:-\w,)?(--[\w-]+)\s+([A-Z]+)", line)
        if m and m.group(1) != "--help":
            found.append(m.group(1))
    return found


class OptionFuzz(pdcli.TestCase):
    def base_args(self, sub):
        missing = self.path("missing.yaml")
        return {
            "run": [self.scene(end_time="2e-5"), "-o", self.path("out")],
            "info": [self.scene()],
            "bench": [missing],
            "verify": ["--list"],
            "stability": [missing],
            "compare": ["dynamic", "--scenes", self.path("no-scenes")],
            "section": [self.scene()],
        }[sub]

    def test_every_option_with_hostile_values(self):
        subs = re.findall(r"^\s{2}(\w+)\s", self.pd("--help").stdout, re.M)
        self.assertIn("run", subs)
        calls = 0
        for sub in subs:
            opts = options_of(self.pd(sub, "--help").stdout)
            self.assertTrue(opts or sub in ("info",), f"no options found for {sub}")
            for opt in opts:
                for value in VALUES:
                    args = [sub, *self.base_args(sub), opt, value]
                    label = f"pd {sub} {opt} {value[:20]!r}"
                    try:
                        r = self.pd(*args, timeout=15)
                    except Exception as e:  # subprocess.TimeoutExpired
                        self.fail(f"{label}: {e}")
                    calls += 1
                    self.assertIn(r.returncode, DOCUMENTED_EXIT_CODES, f"{label}: {r.stderr[-500:]}")
                    for line in (r.stdout + r.stderr).splitlines():
                        self.assertLess(len(line), LONGEST_LINE, f"{label}: echoed {len(line)} chars")
        self.assertGreater(calls, 100)


if __name__ == "__main__":
    pdcli.main()
