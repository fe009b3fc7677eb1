"""The full deciding campaign's record for the report (issue 30): the per-cell counts of a
flown ``rotorfault campaign --suite deciding --runs 1000 --out DIR`` dataset and the decision
over the runs certify calls survivable, as one bench result
(``python/rotorfault/papers/bench_results/deciding_full_run.json``, schema ``rotorfault-bench/1``
with a ``campaign`` object), so the report shows the full run beside its live ``--quick`` table.

Run (after the flight; the lead's idle machine):

    rotorfault campaign --suite deciding --runs 1000 --out DIR --format json > out.json
    python benches/deciding_record.py DIR --out-json out.json --commit $(git rev-parse --short HEAD) \\
        --json python/rotorfault/papers/bench_results/deciding_full_run.json

Each run's ``holds`` is judged again by the current hold rule (``deciding.rejudge_holds``: the
stored window values and the seeded draws, no flying; ``holds_judged`` counts what changed).
A dataset flown with certify's verdict per run is read as it is; one without it (flown before
the verdict existed, or ``--no-certify``) is certified here, after the fact, per draw
(``rotorfault.studies.deciding.certify_rows``). ``--certified FILE`` (JSON lines ``vehicle``,
``fault_class``, ``index``, ``certified``, ``static_hover``, ``spin``, ``note``, ``seconds``) takes
verdicts computed earlier (the same ``certify_run``) and restricts the decision to the run
indices certified for every vehicle and fault class: the record then says it is a sample.

A suite flown on sensors (``--sensing mocap``) is recorded to its own file
(``deciding_full_run_mocap.json``); ``--against-truth TRUTH_DIR``, the same suite flown on the
truth, adds the run-for-run comparison: per cell, the runs held on both, on the truth only, on the
sensors only and on neither (the same draws, the same controller), how many of those held on the
truth only and on both spin past the gyro's range there, and per missed cell how many of its missed
runs the same controller holds on the truth (what the sensing costs it).
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import sys
import time
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

import numpy as np  # noqa: E402
from _results import add_json_option, figure, write  # noqa: E402

import rotorfault as rf  # noqa: E402
from rotorfault.analysis import RelaxedHoverSettings  # noqa: E402
from rotorfault.papers.campaign import RECORD_CELL_KEYS  # noqa: E402  (the record's keys, checked there)
from rotorfault.studies import deciding as D  # noqa: E402
from rotorfault.studies.certify import SPIN_RATE_LIMIT_MARGIN  # noqa: E402
from rotorfault.studies.storage import iter_tables, pyarrow_module, read_manifest  # noqa: E402
from rotorfault.studies.summaries import numpy_columns  # noqa: E402



def _ranges(indices: list[int]) -> list[list[int]]:
    out: list[list[int]] = []
    for i in indices:
        if out and out[-1][1] == i:
            out[-1][1] = i + 1
        else:
            out.append([i, i + 1])
    return out


def _finite(value: object) -> object:
    """JSON has no NaN: a share over no runs is null."""
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_finite(v) for v in value]
    if isinstance(value, (float, np.floating)):
        return None if math.isnan(value) else float(value)
    if isinstance(value, np.integer):
        return int(value)
    return value


SPIN_LIMIT_RAD_S = RelaxedHoverSettings().max_spin_rate_rad_s  # certify's search limit
EFFICIENCY_BINS = ((0.0, 0.0), (0.0, 0.25), (0.25, 0.5), (0.5, 0.75), (0.75, 1.0))


def misses(c: dict, decision: list[dict], why: dict[str, str], truth: dict | None = None) -> list[dict]:
    """For every cell that misses the target: the survivable runs its best controller does not
    hold, by outcome, by efficiency (a total loss apart), by wind, when lost and how far tilted,
    which other controller holds them, and (``truth``: the same suite flown on the truth, row for
    row) how many of them the same controller holds on the truth."""
    if truth is not None:
        _same_rows(c, truth)
    out = []
    for d in decision:
        if not d["survivable"] or D.target_verdict(d) == "met":
            continue
        pair = (c["vehicle"] == d["vehicle"]) & (c["fault_class"] == d["fault_class"])
        best = pair & (c["controller"] == d["controller"]) & np.isin(c["certified"], D.SURVIVABLE)
        missed = best & ~c["holds"].astype(bool)
        eff = c["efficiency"]
        bins = []
        for lo, hi in EFFICIENCY_BINS:
            inside = (eff == 0.0) if hi == 0.0 else ((eff > lo) & (eff <= hi) if lo == 0.0 else (eff > lo) & (eff <= hi))
            bins.append({"efficiency": "0 (total)" if hi == 0.0 else f"({lo:g}, {hi:g}]", "survivable": int(np.sum(best & inside)),
                         "missed": int(np.sum(missed & inside))})
        lost_after = (c["lost_at_s"] - c["fault_time_s"])[missed]
        lost_after = lost_after[np.isfinite(lost_after)]
        tilt = c["peak_tilt_rad"][missed]
        tilt = tilt[np.isfinite(tilt)]
        alive = missed & np.isfinite(c["hold_altitude_error_m"])
        wind = c["wind_speed_m_s"]
        others = {}
        index = set(c["index"][missed].tolist())
        for name in dict.fromkeys(c["controller"][pair].tolist()):
            if name != d["controller"]:
                rows = pair & (c["controller"] == name) & np.isin(c["index"], list(index)) & c["holds"].astype(bool)
                others[name] = int(np.sum(rows))
        outcomes: dict[str, int] = {}
        for o in c["outcome"][missed].tolist():
            outcomes[o] = outcomes.get(o, 0) + 1
        static: dict[str, int] = {}
        for o in c["certified_static_hover"][missed].tolist():
            static[o or "-"] = static.get(o or "-", 0) + 1
        out.append({
            "vehicle": d["vehicle"], "fault_class": d["fault_class"], "controller": d["controller"], "missed": int(np.sum(missed)),
            "survivable": int(np.sum(best)), "outcomes": outcomes, "static_hover": static,
            "spinning": int(np.sum(missed & (c["certified"] == "spinning"))), "by_efficiency": bins,
            # certify's spin at the search's limit on an undamped vehicle (no rotational damping: the
            # margin still grows there), with certify's own margin (studies.certify.SPIN_RATE_LIMIT_MARGIN);
            # a damped spin near the limit is pinned by k_r, not counted
            "spin_at_search_limit": int(np.sum(missed & (np.abs(c["certified_spin_rad_s"]) >= (1.0 - SPIN_RATE_LIMIT_MARGIN) * SPIN_LIMIT_RAD_S)))
            if D.vehicle(d["vehicle"]).rotational_drag_n_m_s == 0.0 else 0,
            "wind_median_m_s": float(np.median(wind[missed])) if missed.any() else None,
            "wind_median_all_m_s": float(np.median(wind[best])) if best.any() else None,
            "lost_after_failure_median_s": float(np.median(lost_after)) if len(lost_after) else None,
            "peak_tilt_median_deg": float(np.degrees(np.median(tilt))) if len(tilt) else None,
            "not_lost": int(np.sum(alive)),
            "not_lost_altitude_error_median_m": float(np.median(c["hold_altitude_error_m"][alive])) if alive.any() else None,
            "not_lost_horizontal_error_median_m": float(np.median(c["hold_horizontal_error_m"][alive])) if alive.any() else None,
            "held_by_another": others, "why": why.get(f"{d['vehicle']}/{d['fault_class']}", ""),
            **({} if truth is None else {"held_on_truth": int(np.sum(missed & truth["holds"].astype(bool)))}),
        })
    return out


def _command(suite: D.DecidingCampaign) -> str:
    """The command that flies ``suite``; a sensing the command line cannot give is written out."""
    sensing = ""
    if suite.sensing is not None:
        sensing = f" --sensing {suite.sensing.suite}"
        if suite.sensing != rf.Sensing(suite=suite.sensing.suite):
            sensing += f" (in Python: DecidingCampaign(sensing={suite.sensing!r}))"
    return f"rotorfault campaign --suite deciding --runs {suite.runs}{sensing} --out DIR --format json"


def _same_rows(sensed: dict, truth: dict) -> None:
    """Refuses a truth dataset whose rows are not ``sensed``'s, row for row."""
    if any(len(sensed[k]) != len(truth[k]) or not np.array_equal(sensed[k], truth[k]) for k in ("vehicle", "fault_class", "controller", "index")):
        raise SystemExit("--against-truth: the truth dataset's rows are not the sensed suite's (vehicle, fault class, controller, index)")


def against_truth(sensed: dict, truth: dict, gyro_range_rad_s: float) -> list[dict]:
    """Per cell of ``sensed`` (rows of a suite flown on sensors), its runs held on both, on the truth
    only, on the sensors only and on neither, against ``truth`` (the same suite on the truth: the same
    draws, row for row); and of those held on the truth only and on both, how many spin past the
    gyro's range (``gyro_range_rad_s``) on the truth (the window's last 5 s mean yaw rate)."""
    _same_rows(sensed, truth)
    past = np.abs(truth["hold_final_spin_rad_s"]) > gyro_range_rad_s  # NaN (lost) compares False
    out = []
    for cell in dict.fromkeys(zip(sensed["vehicle"].tolist(), sensed["fault_class"].tolist(), sensed["controller"].tolist())):
        rows = (sensed["vehicle"] == cell[0]) & (sensed["fault_class"] == cell[1]) & (sensed["controller"] == cell[2]) & sensed["applicable"]
        s, t, fast = sensed["holds"].astype(bool)[rows], truth["holds"].astype(bool)[rows], past[rows]
        out.append({"vehicle": cell[0], "fault_class": cell[1], "controller": cell[2], "runs": int(rows.sum()), "both": int(np.sum(s & t)),
                    "truth_only": int(np.sum(t & ~s)), "sensed_only": int(np.sum(s & ~t)), "neither": int(np.sum(~s & ~t)),
                    "truth_only_past_gyro_range": int(np.sum(t & ~s & fast)), "both_past_gyro_range": int(np.sum(s & t & fast))})
    return out


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("dataset", help="the suite's --out directory")
    parser.add_argument("--out-json", required=True, help="the flight's `--format json` output (its time)")
    parser.add_argument("--commit", required=True, help="the commit the campaign was flown on")
    parser.add_argument("--flown", default=None, help="when it was flown (ISO 8601; default: the manifest's modification time)")
    parser.add_argument("--flown-on", default="idle 2-core machine, fat LTO", help="the machine it was flown on")
    parser.add_argument("--certified", nargs="*", default=[], help="JSON lines of verdicts computed earlier (module notes)")
    parser.add_argument("--why", default=None, help="JSON: {\"vehicle/fault_class\": reason} for the cells that miss the target")
    parser.add_argument("--certify-commit", default=None, help="the commit that certified the runs (default: --commit)")
    parser.add_argument("--against-truth", default=None, help="a suite flown on sensors: the same suite's dataset flown on the truth (the run-for-run comparison)")
    add_json_option(parser)
    args = parser.parse_args()

    flight = json.loads(Path(args.out_json).read_text(encoding="utf-8"))
    manifest_path = Path(args.dataset) / "_rotorfault.json"
    flown = args.flown or datetime.datetime.fromtimestamp(manifest_path.stat().st_mtime, datetime.timezone.utc).isoformat(timespec="seconds")
    suite = D.DecidingCampaign.from_dict(read_manifest(args.dataset)["arguments"]["suite"])
    columns = numpy_columns(pyarrow_module().concat_tables(list(iter_tables(args.dataset))))
    # The holds judged again by the current hold rule (the one place: rotorfault.studies.deciding_hold),
    # from the stored window values and the seeded draws, without flying; the flight's verdicts kept.
    columns = D.rejudge_holds(suite, columns)
    flown_held, held = int(np.sum(columns["holds_as_flown"])), int(np.sum(columns["holds"]))
    changed = columns["holds"] != columns["holds_as_flown"]
    comparison = truth_columns = None
    if args.against_truth is not None:
        if suite.sensing is None:
            raise SystemExit("--against-truth: the dataset was flown on the truth; it compares a suite flown on sensors with it")
        truth_manifest = read_manifest(args.against_truth)["arguments"]
        truth = D.read_deciding(args.against_truth, certify=False)  # holds judged by the current rule
        truth_suite = truth.suite
        # The rows do not depend on the chunking or on certify's column; everything else must match,
        # the controllers' revision included (a truth flown by other controllers is no pair).
        if truth_suite.sensing is not None or replace(suite, sensing=None, certify=truth_suite.certify, chunk_size=truth_suite.chunk_size) != truth_suite:
            raise SystemExit("--against-truth: not the same suite flown on the truth (runs, seed, vehicles, fault classes, controllers)")
        revision = read_manifest(args.dataset)["arguments"].get("controllers_revision")
        if truth_manifest.get("controllers_revision") != revision:
            raise SystemExit(f"--against-truth: flown by controllers revision {truth_manifest.get('controllers_revision')}, the dataset by {revision}")
        truth_columns = dict(truth.columns)
        comparison = against_truth(columns, truth_columns, suite.sensing.gyro_range_in_effect_rad_s)
    full = D.DecidingResult(suite, columns, seconds=float(flight["seconds"]))
    cells = [{k: r[k] for k in RECORD_CELL_KEYS} for r in full.cell_rows()]

    keys = list(zip(columns["vehicle"].tolist(), columns["fault_class"].tolist(), columns["index"].tolist()))
    cached: dict[tuple[str, str, int], dict] = {}
    for name in args.certified:
        for line in Path(name).read_text(encoding="utf-8").splitlines():
            r = json.loads(line)
            cached[(r["vehicle"], r["fault_class"], int(r["index"]))] = r
    if "certified" in columns and suite.certify:
        rows, indices, seconds, timed = columns, list(range(suite.runs)), 0.0, 0
        note = "certified while flying"
    else:
        pairs = sorted({k[:2] for k in keys})
        indices = sorted(set.intersection(*({i for (v, f, i) in cached if (v, f) == p} for p in pairs))) if cached else list(range(suite.runs))
        mask = np.isin(columns["index"], indices)
        subset = {k: v[mask] for k, v in columns.items()}
        if truth_columns is not None:  # the misses pair the certified rows with the truth's same rows
            truth_columns = {k: v[mask] for k, v in truth_columns.items()}
        def from_cache(s: D.DecidingCampaign, cell: D.Cell, index: int) -> D.RunCertificate:
            r = cached[(cell.vehicle, cell.fault_class, index)]
            return D.RunCertificate(r["certified"], r["static_hover"], math.nan if r["spin"] is None else float(r["spin"]), r["note"])

        start = time.perf_counter()
        rows = D.certify_rows(suite, subset, verdict_of=from_cache if cached else None)
        seconds = sum(r["seconds"] for r in cached.values()) if cached else time.perf_counter() - start
        timed = len(cached) if cached else len(indices) * len(pairs)
        note = "certified after the fact" + (f", a sample: run indices {_ranges(indices)} of every vehicle and fault class" if len(indices) < suite.runs else "")
    result = D.DecidingResult(suite, rows)
    decision = result.decision()
    why = json.loads(Path(args.why).read_text(encoding="utf-8")) if args.why else {}
    per_draw = seconds / timed if timed else math.nan
    figures = [
        figure("deciding campaign, 1,000 runs per cell: flight wall time", float(flight["seconds"]), "s", target="< 900"),
        figure("deciding campaign: flown runs/s", suite.total_runs / float(flight["seconds"]), "runs/s"),
    ]
    if timed:
        figures.append(figure("certify per run after the fact: time per draw", per_draw, "s"))
    record_extra = {
        "campaign": {
            "command": _command(suite),
            "commit": args.commit, "flown": flown, "flown_on": args.flown_on, "flight_seconds": float(flight["seconds"]),
            "suite": suite.to_dict(), "cells": cells,
            "certified": {"how": note, "commit": args.certify_commit or args.commit, "indices": _ranges(indices),
                          "draws": len(indices) * len({k[:2] for k in keys}), "seconds": seconds, "draws_timed": timed},
            "holds_judged": {"rule": f"deciding_hold: growth <= max({D.SPIN_GROWTH_MIN_RAD_S:g} rad/s, {1 + D.SPIN_SETTLE_MARGIN:g} x the "
                                      "growth share of a first-order settle from the failure with the run's I_zz / k_r x final, "
                                      f"min({D.SPIN_SETTLED_SHARE:g} x (e^(5 s / tau) - 1), {D.SPIN_SETTLED_CAP_SHARE:g}) x final), and a first-order end below "
                                      f"{D.SPIN_END_LIMIT_RAD_S:g} rad/s; k_r = 0: the minimum",
                             "held_as_flown": flown_held, "held": held, "now_held": int(np.sum(changed & columns["holds"])),
                             "no_longer_held": int(np.sum(changed & ~columns["holds"]))},
            "decision": decision, "contradictions": result.contradictions(), "contradictions_why": why.get("contradictions", ""),
            "misses": misses(rows, decision, why, truth_columns),
        }
    }
    if comparison is not None:
        record_extra["campaign"]["against_truth"] = comparison
        record_extra["campaign"]["against_truth_why"] = why.get("against_truth", "")
    print(result.decision_table())
    if args.json_path:
        on = "" if suite.sensing is None else f" on {suite.sensing.suite} sensors"
        write(args.json_path, "deciding_full_run" + ("" if suite.sensing is None else f"_{suite.sensing.suite}"),
              f"The full deciding campaign (issue 30){on}: per-cell counts and the decision", figures,
              reduced=None if len(indices) == suite.runs else f"the decision over a sample of certified runs ({len(indices)} of {suite.runs} per cell)")
        path = Path(args.json_path)
        data = json.loads(path.read_text(encoding="utf-8"))
        data.update(_finite(record_extra))
        # One writer, atomic: the campaign part replaces the file whole, never half written.
        partial = path.with_name(path.name + ".partial")
        partial.write_text(json.dumps(data, indent=2, allow_nan=False, default=float) + "\n", encoding="utf-8")
        os.replace(partial, path)


if __name__ == "__main__":
    main()
