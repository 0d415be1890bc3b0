#!/usr/bin/env python3
"""Open a rendered report in headless Chromium and check it.

    python3 tests/report/browser_check.py --synthetic WORKDIR      # render synthetic data, check it
    python3 tests/report/browser_check.py --report DIR [--build-dir build]   # check a real report
    options: --chromium PATH, --screenshot PNG

Checks (on the DOM Chromium produced after running the page's inline script):
  * the page's own image check ran (body data-check) and every <img> loaded
    (img.complete && naturalWidth > 0), at least one image on the page;
  * the summary table has one row per verification case (synthetic: the cases in the data; real
    report: the cases of `pd verify --list`);
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
        self._in_summary = 0
        self.imgs: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = {k: v or "" for k, v in attrs}
        if tag == "body":
            self.body = a
        if "id" in a:
            self.ids.add(a["id"])
        if "data-failed" in a:
            self.failed_boxes.append(a["data-failed"])
        if tag == "table" and a.get("id") == "summary-table":
            self._in_summary = 1
        if tag == "tr" and self._in_summary and "data-case" in a:
            self.summary_cases.append(a["data-case"])
        if tag == "img":
            self.imgs.append(a.get("src", ""))

    def handle_endtag(self, tag: str) -> None:
        if tag == "table" and self._in_summary:
            self._in_summary = 0


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
            "--disable-dev-shm-usage", f"--user-data-dir={profile}", "--virtual-time-budget=5000"]


def dump_dom(chromium: str, page: Path) -> str:
    with tempfile.TemporaryDirectory(prefix="pd-report-chromium-") as profile:
        cmd = chromium_args(chromium, profile) + ["--dump-dom", page.resolve().as_uri()]
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=180)
        if p.returncode != 0 or "<body" not in p.stdout:
            raise RuntimeError(f"chromium --dump-dom failed (exit {p.returncode}):\n{p.stderr[-1500:]}")
        return p.stdout


def screenshot(chromium: str, page: Path, png: Path) -> None:
    with tempfile.TemporaryDirectory(prefix="pd-report-chromium-") as profile:
        cmd = chromium_args(chromium, profile) + ["--hide-scrollbars", "--window-size=1300,4200",
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
    if sorted(dom.summary_cases) != sorted(expected_cases):
        problems.append(f"summary table rows {dom.summary_cases} != cases {expected_cases}")
    if b.get("data-summary-rows") != str(len(expected_cases)):
        problems.append(f"in-page row count {b.get('data-summary-rows')} != {len(expected_cases)}")
    for sec in ("environment", "summary", "deflections", "accuracy", "integrators", "performance", "stages"):
        if sec not in dom.ids:
            problems.append(f"section #{sec} missing")
    if expect_failed_box and not dom.failed_boxes:
        problems.append("the failed stage is not shown as a failed box")
    print(f"images {loaded}/{total} loaded; summary rows {len(dom.summary_cases)} "
          f"(expected {len(expected_cases)}); failed-stage boxes: {dom.failed_boxes or 'none'}")
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
        expected = [json.loads(f.read_text())["name"].split(":", 1)[1]
                    for f in sorted((work / "data").glob("verify_*.json"))]
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
        print("PASS: every image loaded, one summary row per case, all sections present")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
