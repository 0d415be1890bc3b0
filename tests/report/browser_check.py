#!/usr/bin/env python3
"""Open a rendered report in headless Chromium and check it.

    python3 tests/report/browser_check.py --synthetic WORKDIR      # render synthetic data, check it
    python3 tests/report/browser_check.py --report DIR [--build-dir build]   # check a real report
    options: --chromium PATH, --screenshot PNG

Checks (on the DOM Chromium produced after running the page's inline script, in a window 1280 px
wide):
  * the page's own image check ran (body data-check) and every <img> loaded
    (img.complete && naturalWidth > 0), at least one image on the page;
  * the page opens with the scorecard, which has one row per verification case, in their order,
    as does the summary table (synthetic: the cases its meta lists, as `pd verify --list` would;
    real report: the cases of `pd verify --list`);
  * nothing scrolls sideways at 1280 px: the document is no wider than the window
    (documentElement.scrollWidth <= clientWidth, with innerWidth = 1280 proving the window size
    took effect), and the scorecard is no wider than the box it sits in;
  * every section is present; a failed stage is shown as a failed box (synthetic data has one).
Exit code 0 = pass, 1 = a check failed, 77 = Chromium not installed (ctest SKIP).
"""
from __future__ import annotations

import argparse
import re
import shutil
import subprocess
import sys
import tempfile
import time
from html.parser import HTMLParser
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


class Dom(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.body: dict[str, str] = {}
        self.ids: set[str] = set()
        self.failed_boxes: list[str] = []
        self.summary_cases: list[str] = []
        self.scorecard_cases: list[str] = []
        self.sections: list[str] = []
        self._table = ""
        self.imgs: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = {k: v or "" for k, v in attrs}
        if tag == "body":
            self.body = a
        if "id" in a:
            self.ids.add(a["id"])
        if "data-failed" in a:
            self.failed_boxes.append(a["data-failed"])
        if tag == "section" and "id" in a:
            self.sections.append(a["id"])
        if tag == "table" and a.get("id") in ("summary-table", "scorecard-table"):
            self._table = a["id"]
        if tag == "tr" and "data-case" in a:
            if self._table == "summary-table":
                self.summary_cases.append(a["data-case"])
            elif self._table == "scorecard-table":
                self.scorecard_cases.append(a["data-case"])
        if tag == "img":
            self.imgs.append(a.get("src", ""))

    def handle_endtag(self, tag: str) -> None:
        if tag == "table":
            self._table = ""


def find_chromium(explicit: str | None) -> str | None:
    if explicit:
        return explicit
    for name in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable"):
        p = shutil.which(name)
        if p:
            return p
    return None


def chromium_args(chromium: str, profile: str) -> list[str]:
    return [chromium, "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
            "--disable-background-networking", "--disable-component-update", "--disable-sync",
            "--disable-dev-shm-usage", f"--user-data-dir={profile}", "--virtual-time-budget=5000",
            "--hide-scrollbars"]


WIDTH = 1280   # the window the scorecard must fit without sideways scrolling (issue 14)


def dump_dom(chromium: str, page: Path) -> str:
    with tempfile.TemporaryDirectory(prefix="pd-report-chromium-") as profile:
        cmd = chromium_args(chromium, profile) + [f"--window-size={WIDTH},900", "--dump-dom",
                                                  page.resolve().as_uri()]
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=180)
        if p.returncode != 0 or "<body" not in p.stdout:
            raise RuntimeError(f"chromium --dump-dom failed (exit {p.returncode}):\n{p.stderr[-1500:]}")
        return p.stdout


def screenshot(chromium: str, page: Path, png: Path) -> None:
    with tempfile.TemporaryDirectory(prefix="pd-report-chromium-") as profile:
        cmd = chromium_args(chromium, profile) + [f"--window-size={WIDTH},4200",
                                                  f"--screenshot={png.resolve()}", page.resolve().as_uri()]
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=180)
        if p.returncode != 0 or not png.exists():
            raise RuntimeError(f"chromium --screenshot failed (exit {p.returncode}):\n{p.stderr[-1500:]}")


def check(dom_text: str, expected_cases: list[str], expect_failed_box: bool) -> list[str]:
    dom = Dom()
    dom.feed(dom_text)
    problems = []
    b = dom.body
    if b.get("data-check") not in ("images-ok", "images-broken"):
        problems.append(f"the page's image check did not run (body data-check={b.get('data-check')!r})")
    total, loaded = int(b.get("data-images-total", "0") or 0), int(b.get("data-images-loaded", "0") or 0)
    if total == 0:
        problems.append("no <img> on the page")
    if loaded != total or b.get("data-images-broken"):
        problems.append(f"{total - loaded} of {total} images did not load: {b.get('data-images-broken')}")
    if len(dom.imgs) != total:
        problems.append(f"DOM has {len(dom.imgs)} <img> but the script counted {total}")
    if dom.summary_cases != expected_cases:
        problems.append(f"summary table rows {dom.summary_cases} != cases {expected_cases}")
    if b.get("data-summary-rows") != str(len(expected_cases)):
        problems.append(f"in-page row count {b.get('data-summary-rows')} != {len(expected_cases)}")
    problems += check_scorecard(dom, expected_cases)
    for sec in ("scorecard", "environment", "summary", "convergence", "old-pairs", "deflections", "accuracy",
                "integrators", "performance", "fracture", "cases", "stages"):
        if sec not in dom.ids:
            problems.append(f"section #{sec} missing")
    if expect_failed_box and not dom.failed_boxes:
        problems.append("the failed stage is not shown as a failed box")
    print(f"images {loaded}/{total} loaded; summary rows {len(dom.summary_cases)}, scorecard rows "
          f"{len(dom.scorecard_cases)} (expected {len(expected_cases)}); window {b.get('data-viewport-width')} "
          f"px, document {b.get('data-document-width')} px of {b.get('data-client-width')}, scorecard "
          f"{b.get('data-scorecard-width')} px of {b.get('data-scorecard-room')}; failed-stage boxes: "
          f"{dom.failed_boxes or 'none'}")
    return problems


def check_scorecard(dom: Dom, expected_cases: list[str]) -> list[str]:
    """The scorecard opens the page, has a row per case and fits the window."""
    b, problems = dom.body, []
    if not dom.sections or dom.sections[0] != "scorecard":
        problems.append(f"the page does not open with the scorecard (sections {dom.sections[:3]})")
    if dom.scorecard_cases != expected_cases:
        problems.append(f"scorecard rows {dom.scorecard_cases} != cases {expected_cases}")
    if b.get("data-scorecard-rows") != str(len(expected_cases)):
        problems.append(f"in-page scorecard row count {b.get('data-scorecard-rows')} != {len(expected_cases)}")

    def px(name: str) -> int:
        try:
            return int(b.get(name, ""))
        except ValueError:
            return -1
    if px("data-viewport-width") != WIDTH:
        problems.append(f"the window is {px('data-viewport-width')} px wide, not {WIDTH}: the width "
                        "checks would prove nothing")
    if not 0 < px("data-document-width") <= px("data-client-width"):
        problems.append(f"the page scrolls sideways at {WIDTH} px: document {px('data-document-width')} px "
                        f"wide, window {px('data-client-width')} px")
    if not 0 < px("data-scorecard-width") <= px("data-scorecard-room"):
        problems.append(f"the scorecard ({px('data-scorecard-width')} px) is wider than its box "
                        f"({px('data-scorecard-room')} px)")
    return problems


def main() -> int:
    ap = argparse.ArgumentParser()
    g = ap.add_mutually_exclusive_group(required=True)
    g.add_argument("--synthetic", metavar="WORKDIR")
    g.add_argument("--report", metavar="DIR")
    ap.add_argument("--build-dir", default=str(ROOT / "build"))
    ap.add_argument("--chromium")
    ap.add_argument("--screenshot", metavar="PNG")
    ap.add_argument("--python", default=sys.executable, help="interpreter for pd_report.py")
    a = ap.parse_args()
    chromium = find_chromium(a.chromium)
    if not chromium:
        print("SKIP: Chromium not found (apt-get install chromium); the page was not checked in a browser")
        return 77
    if a.synthetic:
        work = Path(a.synthetic)
        if work.exists():
            shutil.rmtree(work)
        p = subprocess.run([a.python, str(ROOT / "reports" / "tests" / "make_synthetic.py"), str(work)],
                           capture_output=True, text=True, check=True)
        n_cases = int(p.stdout.strip().splitlines()[-1])
        r = subprocess.run([a.python, str(ROOT / "reports" / "pd_report.py"), "--render-only", "--data",
                            str(work / "data"), "-o", str(work / "out")], capture_output=True, text=True)
        if r.returncode != 0:
            print(r.stdout, r.stderr)
            return 1
        page = work / "out" / "index.html"
        import json
        expected = [c for c, _ in json.loads((work / "data" / "_meta.json").read_text())["cases"]]
        assert len(expected) == n_cases, (expected, n_cases)
        expect_failed = True
    else:
        page = Path(a.report) / "index.html"
        if not page.exists():
            print(f"FAIL: {page} does not exist (run python3 reports/pd_report.py -o {a.report} first)")
            return 1
        pd = Path(a.build_dir) / "bin" / "pd"
        lst = subprocess.run([str(pd), "verify", "--list"], capture_output=True, text=True, check=True)
        expected = [m.group(1) for m in (re.match(r"^(\S+)\s", l) for l in lst.stdout.splitlines()) if m]
        expect_failed = False
    t0 = time.time()
    dom_text = dump_dom(chromium, page)
    print(f"chromium --dump-dom: {time.time() - t0:.1f} s")
    problems = check(dom_text, expected, expect_failed)
    if a.screenshot:
        screenshot(chromium, page, Path(a.screenshot))
        print(f"screenshot: {a.screenshot}")
    for pr in problems:
        print("FAIL:", pr)
    if not problems:
        print(f"PASS: every image loaded, the scorecard opens the page with one row per case and "
              f"fits {WIDTH} px, one summary row per case, all sections present")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
