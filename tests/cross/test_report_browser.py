"""The reproduce-all report as a person sees it: ``rotorfault reproduce --quick`` is built once,
opened from disk in headless Chromium (Debian's ``chromium``; ``.ci/run`` installs it), and
checked in the browser: the page renders, every image loads (``naturalWidth > 0``), nothing is
written to the console as an error and no resource fails, every table has the rows the data says
(printed numbers, decisions, benches), and a screenshot is saved.

How: a copy of the page gets a check script (the report itself carries none) that records errors
from the start and, once the page has loaded, writes a JSON summary into the DOM; Chromium's
``--dump-dom`` (with ``--virtual-time-budget`` so images finish loading) returns it. Chromium
runs without network (nothing in the page is remote: checked) and within a time limit.

Without Chromium the test is skipped, unless ``ROTORFAULT_REQUIRE_BROWSER=1`` (``.ci/run``).
"""

from __future__ import annotations

import html as html_lib
import json
import math
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from quick_report import QuickReport

from rotorfault.papers import du as du_paper
from rotorfault.papers import ke as ke_paper
from rotorfault.papers import reproduce
from rotorfault.studies.deciding import DecidingCampaign
from rotorfault.papers.decisions import decisions

ROOT = Path(__file__).resolve().parents[2]
#: Seconds Chromium may take for one page (it takes 1-3 s here).
BROWSER_TIMEOUT_S = 90
#: Where the screenshot is saved (beside the test's report unless set).
SCREENSHOT_ENV = "ROTORFAULT_REPORT_SCREENSHOT"

CHECK_HEAD = """<script>
window.__errors = [];
window.addEventListener('error', function (e) {
  var t = e.target || {};
  window.__errors.push(t.tagName ? ('resource failed: ' + t.tagName + ' ' + (t.src || t.href)) : ('error: ' + e.message));
}, true);
(function () { var original = console.error; console.error = function () {
  window.__errors.push('console.error: ' + Array.prototype.join.call(arguments, ' ')); original.apply(console, arguments); }; })();
</script>"""
CHECK_TAIL = """<script>
window.addEventListener('load', function () {
  var images = Array.prototype.map.call(document.images, function (img) {
    return {src: img.getAttribute('src'), complete: img.complete, naturalWidth: img.naturalWidth}; });
  var tables = Array.prototype.map.call(document.querySelectorAll('table'), function (t) {
    return {id: t.id, rows: t.tBodies.length ? t.tBodies[0].rows.length : 0}; });
  var pre = document.createElement('pre');
  pre.id = 'browser-check';
  pre.textContent = JSON.stringify({title: document.title, bodyHeight: document.body.scrollHeight,
    sections: document.querySelectorAll('section').length, images: images, tables: tables, errors: window.__errors});
  document.body.appendChild(pre);
});
</script>"""


def _chromium() -> str:
    found = shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")
    if found is None:
        if os.environ.get("ROTORFAULT_REQUIRE_BROWSER") == "1":
            pytest.fail("chromium not found (ROTORFAULT_REQUIRE_BROWSER=1): apt-get install -y chromium")
        pytest.skip("chromium not installed (apt-get install -y chromium)")
    return found


def _browser(chromium: str, profile: Path, *args: str) -> subprocess.CompletedProcess[str]:
    flags = [
        "--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage", f"--user-data-dir={profile}",
        "--no-first-run", "--no-default-browser-check", "--disable-background-networking", "--disable-sync",
        "--disable-component-update", "--disable-default-apps", "--disable-extensions", "--mute-audio",
        "--allow-file-access-from-files", "--virtual-time-budget=10000",
    ]
    return subprocess.run([chromium, *flags, *args], capture_output=True, text=True, timeout=BROWSER_TIMEOUT_S, check=False)


@pytest.fixture(scope="module")
def report(quick_report: QuickReport) -> Path:
    assert quick_report.document["out"] == str(quick_report.out / "index.html")
    # The per-paper scores count the reproduced rows only (Du's and Ke's are all reproduced).
    scores = {s["key"]: (s["passed"], s["reproduced"]) for s in quick_report.document["sections"]}
    assert scores["du"] == (14, 14) and scores["ke"] == (33, 33), scores
    return quick_report.out


@pytest.fixture(scope="module")
def browser_check(report: Path, tmp_path_factory: pytest.TempPathFactory) -> dict[str, object]:
    chromium = _chromium()
    page = (report / "index.html").read_text(encoding="utf-8")
    checked = report / "browser-check.html"  # beside the page, so relative figure paths resolve
    checked.write_text(page.replace("<head>", "<head>\n" + CHECK_HEAD, 1).replace("</body>", CHECK_TAIL + "\n</body>", 1),
                       encoding="utf-8")
    try:
        done = _browser(chromium, tmp_path_factory.mktemp("chromium-profile"), "--dump-dom", checked.as_uri())
    finally:
        checked.unlink()
    assert done.returncode == 0, done.stderr[-2000:]
    found = re.search(r'<pre id="browser-check">(.*?)</pre>', done.stdout, re.S)
    assert found, f"the check script did not run; DOM starts {done.stdout[:500]!r}"
    result: dict[str, object] = json.loads(html_lib.unescape(found.group(1)))
    return result


def test_the_page_is_static_and_offline(report: Path) -> None:
    page = (report / "index.html").read_text(encoding="utf-8")
    assert not re.search(r'(src|href)="(https?:)?//', page), "the report must not load anything from the network"
    assert "<script" not in page  # a static page: nothing to run
    for src in re.findall(r'<img src="([^"]+)"', page):
        assert (report / src).is_file(), src


def test_page_renders_with_every_image_loaded_and_no_errors(browser_check: dict[str, object]) -> None:
    assert browser_check["title"] == "rotorfault: the four papers reproduced"
    assert browser_check["errors"] == []
    images = browser_check["images"]
    assert isinstance(images, list) and len(images) >= 8
    broken = [i for i in images if not (i["complete"] and i["naturalWidth"] > 0)]
    assert not broken, broken
    assert isinstance(browser_check["bodyHeight"], int) and browser_check["bodyHeight"] > 2000


def test_every_table_has_the_expected_rows(browser_check: dict[str, object]) -> None:
    tables = {t["id"]: t["rows"] for t in browser_check["tables"]}  # type: ignore[union-attr]
    assert tables["summary"] == len(reproduce.PAPERS) + len(reproduce.STUDIES)
    # The deciding campaign: one row per cell, one per (vehicle, fault class) for the best controller.
    assert tables["campaign-table-1"] == len(DecidingCampaign(runs=1).cells) == 65
    assert tables["campaign-table-2"] == 13
    assert tables["du-numbers"] == len(du_paper.printed_numbers()) == 14
    assert tables["ke-numbers"] == len(ke_paper.printed_numbers()) == 33
    # eq. (26) closed loop at both I_zz and the achieved loop shape (scored), and the 13 Jacobian-at-0
    # entries beside them (consistency, not scored).
    assert tables["lanzon-numbers"] == 2 + 4 + 13
    assert tables["decisions-table"] == len(decisions())
    # Du's failure tables: no failure, 6 single and 15 double failures each.
    assert tables["du-table-1"] == tables["du-table-2"] == 22
    assert tables["ke-table-1"] == 11  # stability checks, one row per Table II health matrix
    assert tables["ke-table-2"] == len(ke_paper.QUICK_SCENARIOS) + 2
    # The papers' flight claims: Ke's five quick scenarios and the overshoot; Wang's scenarios.
    assert tables["ke-claims"] == len(ke_paper.KE_CLAIMS) + 1
    assert tables["wang-claims"] > 0
    for bench in reproduce.bench_results(reproduce.default_bench_directory()):
        assert tables[f"bench-{bench.bench}"] == len(bench.figures)
    assert all(rows > 0 for rows in tables.values()), tables


def test_screenshot(report: Path, tmp_path_factory: pytest.TempPathFactory) -> None:
    chromium = _chromium()
    target = Path(os.environ.get(SCREENSHOT_ENV) or report.parent / "report.png")
    for _ in range(2):  # on a loaded machine Chromium has once exited 0 without writing the file
        done = _browser(chromium, tmp_path_factory.mktemp("chromium-profile"), f"--screenshot={target}",
                        "--window-size=1280,2400", "--hide-scrollbars", (report / "index.html").as_uri())
        if target.is_file():
            break
    assert done.returncode == 0, done.stderr[-2000:]
    assert target.is_file() and target.stat().st_size > 20_000, (done.stdout[-500:], done.stderr[-1500:])
    assert target.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def _differences(main: dict[str, Any], here: dict[str, Any]) -> list[str]:
    """Field-by-field differences between two reports' ``numbers.json``: numbers to 1e-9 relative
    (a NaN equals only a NaN), every table cell exactly (they are the printed text)."""
    found: list[str] = []
    if set(main["sections"]) != set(here["sections"]):
        return [f"sections differ: {sorted(main['sections'])} vs {sorted(here['sections'])}"]
    for key, a in main["sections"].items():
        b = here["sections"][key]
        if len(a["numbers"]) != len(b["numbers"]):
            found.append(f"{key}: {len(a['numbers'])} numbers vs {len(b['numbers'])}")
        for x, y in zip(a["numbers"], b["numbers"]):
            name = f"{key}: {x['where']} {x['quantity']}"
            for field in ("where", "quantity", "printed", "tolerance", "status"):
                if x[field] != y[field]:
                    found.append(f"{name}: {field} {x[field]!r} vs {y[field]!r}")
            p, q = x["ours"], y["ours"]
            same = (math.isnan(p) and math.isnan(q)) or p == q or abs(p - q) <= 1e-9 * max(abs(p), abs(q))
            if not same:
                found.append(f"{name}: ours {p!r} vs {q!r}")
        if len(a["tables"]) != len(b["tables"]):
            found.append(f"{key}: {len(a['tables'])} tables vs {len(b['tables'])}")
        for t, u in zip(a["tables"], b["tables"]):
            if t != u:
                rows = [f"{r} vs {s}" for r, s in zip(t["rows"], u["rows"]) if r != s]
                found.append(f"{key}: table {t['caption']!r} differs: {rows or (t['columns'], u['columns'])}")
    return found


def test_the_main_jobs_report_has_the_numbers_of_the_test_environment(report: Path) -> None:
    """One answer on every install: the README's main job, run by CI in a fresh environment
    without the test extras (no slycot, no Dask, no pyarrow), printed the same numbers and tables
    as this environment. ``.ci/run`` sets ``ROTORFAULT_MAIN_JOB_REPORT`` to its report."""
    main_job = os.environ.get("ROTORFAULT_MAIN_JOB_REPORT")
    if not main_job:
        if os.environ.get("ROTORFAULT_REQUIRE_MAIN_JOB") == "1":
            pytest.fail("ROTORFAULT_MAIN_JOB_REPORT is not set (ROTORFAULT_REQUIRE_MAIN_JOB=1)")
        pytest.skip("no main-job report to compare with (.ci/run sets ROTORFAULT_MAIN_JOB_REPORT)")
    main = json.loads((Path(main_job) / "numbers.json").read_text(encoding="utf-8"))
    here = json.loads((report / "numbers.json").read_text(encoding="utf-8"))
    assert main["schema"] == here["schema"] == reproduce.NUMBERS_SCHEMA
    assert _differences(main, here) == []


def test_the_comparison_sees_a_changed_number_and_a_changed_cell(report: Path) -> None:
    """The comparison above can fail: a number moved by 1e-6 relative and one changed table cell
    are both reported."""
    here = json.loads((report / "numbers.json").read_text(encoding="utf-8"))
    changed = json.loads(json.dumps(here))
    number = changed["sections"]["du"]["numbers"][0]
    number["ours"] = number["ours"] * (1 + 1e-6) + 1e-12
    changed["sections"]["wang"]["tables"][0]["rows"][0][0] += "x"
    found = _differences(here, changed)
    assert len(found) == 2 and "du:" in found[0] and "wang: table" in found[1]
