"""Checks the README main job's report (stdlib only: it runs with any Python).

    python .ci/check_report.py REPORT_DIR

The page must hold every paper's section, landed, with no error text; ``numbers.json`` must be
there (the test suite later compares it, field by field, with the test environment's report:
tests/test_report_browser.py, ROTORFAULT_MAIN_JOB_REPORT). Exit status 1 with the reasons
otherwise.
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

PAPERS = ("du", "ke", "lanzon", "wang")
#: Text that must never appear on the page: a traceback, an error line, a paper left out.
ERROR_TEXT = ("Traceback (most recent call last)", "Error:", "Not landed yet", "paper notlanded")


def problems(report: Path) -> list[str]:
    found: list[str] = []
    page_path = report / "index.html"
    if not page_path.is_file():
        return [f"{page_path} is missing"]
    page = page_path.read_text(encoding="utf-8")
    for key in PAPERS:
        if not re.search(rf'<section id="{key}" class="paper">', page):
            found.append(f"the section of paper {key!r} is missing or not landed")
    for text in ERROR_TEXT:
        if text in page:
            found.append(f"the page contains {text!r}")
    numbers = report / "numbers.json"
    if not numbers.is_file():
        found.append(f"{numbers} is missing")
    else:
        data = json.loads(numbers.read_text(encoding="utf-8"))
        missing = [k for k in PAPERS if k not in data.get("sections", {})]
        if missing:
            found.append(f"numbers.json has no section for {missing}")
    return found


if __name__ == "__main__":
    if len(sys.argv) != 2:
        raise SystemExit("usage: python .ci/check_report.py REPORT_DIR")
    bad = problems(Path(sys.argv[1]))
    for line in bad:
        print(f"report check: {line}", file=sys.stderr)
    if bad:
        raise SystemExit(1)
    print(f"report check: {sys.argv[1]} has all {len(PAPERS)} papers, no error text, numbers.json present")
