#!/usr/bin/env python3
"""Render the synthetic data set (no Chromium needed) and run test_compare.py on its report.json,
so the 10 % injection is also tested on the real report.json layout the renderer writes."""
from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
work = Path(sys.argv[1]) if len(sys.argv) > 1 else Path("report-rendered-compare")
if work.exists():
    shutil.rmtree(work)
subprocess.run([sys.executable, str(HERE / "make_synthetic.py"), str(work)], check=True, capture_output=True)
subprocess.run([sys.executable, str(HERE.parent / "pd_report.py"), "--render-only", "--data", str(work / "data"),
                "-o", str(work / "out")], check=True)
sys.exit(subprocess.run([sys.executable, str(HERE / "test_compare.py"), str(work / "out" / "report.json")]).returncode)
