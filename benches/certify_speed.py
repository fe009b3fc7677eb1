"""certify per run in the deciding campaign (issue 30): CPU time per draw, and the search it skips.

Run:  python benches/certify_speed.py [--runs N] [--json PATH]

The first ``N`` draws (default 40) of every vehicle and fault class of the deciding suite, each
certified as the campaign does (``studies.deciding``'s per-run verdict: the failed vehicle with its
perturbations, ``certify_survival``, which asks ``relaxed_hover(best_only=True)``), CPU time per
draw (one thread). Baseline in the same run, on the same draws: the relaxed hover search in full
(``best_only=False``, every strategy), the search certify ran before the margin bound; its best
must be certify's (checked for every draw; the bench fails otherwise). The full suite's
certification (13,000 draws) is extrapolated from the per-vehicle means (the draws are the
suite's own, so the share of draws that need the search is the suite's). Target (issue 30,
h39): about 25 ms per draw on average, i.e. <= ~3 min on 2 cores for the suite.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).parent))

from _results import add_json_option, figure, write  # noqa: E402

import rotorfault as rf  # noqa: E402
from rotorfault.analysis.relaxed_hover import relaxed_hover  # noqa: E402
from rotorfault.studies import deciding as D  # noqa: E402
from rotorfault.studies.certify import certify_survival  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("--runs", type=int, default=40, help="draws per vehicle and fault class")
    add_json_option(parser)
    args = parser.parse_args()
    os.environ.setdefault("RAYON_NUM_THREADS", "1")
    print(f"rotorfault {rf.__version__}, {os.cpu_count()} CPUs, load {os.getloadavg()[0]:.1f}")
    suite = D.DecidingCampaign()
    pairs = {(c.vehicle, c.fault_class): c for c in suite.cells}
    per_vehicle: dict[str, list[tuple[float, float]]] = {}
    for (name, _), cell in pairs.items():
        for i in range(args.runs):
            airframe, actuator, drag = suite.draw(cell, i).failed_vehicle(D.vehicle(name))
            t = time.process_time()
            verdict = certify_survival(airframe, drag=drag, actuator=actuator)
            fast = time.process_time() - t
            full = 0.0
            if verdict.relaxed_hover is not None:  # the search ran: time it in full
                t = time.process_time()
                best = relaxed_hover(airframe, drag=drag, actuator=actuator).best
                full = time.process_time() - t + fast
                mine = verdict.relaxed_hover.solution
                if (best is None) != (mine is None) or (best is not None and list(best.thrust_n) != list(mine.thrust_n)):
                    raise SystemExit(f"{name} {cell.fault_class} draw {i}: the full search's best is not certify's")
            else:
                full = fast
            per_vehicle.setdefault(name, []).append((fast, full))
    figures = []
    total_fast = total_full = 0.0
    for name, times in per_vehicle.items():
        fast = sum(t[0] for t in times) / len(times)
        full = sum(t[1] for t in times) / len(times)
        draws = sum(1000 for (v, _) in pairs if v == name)
        total_fast += fast * draws
        total_full += full * draws
        print(f"{name:<18} {len(times):>4} draws: certify {1e3 * fast:6.1f} ms/draw, with the full search {1e3 * full:6.1f} ms/draw "
              f"(ratio {full / fast:.1f})")
        figures.append(figure(f"certify per draw, {name}", fast, "s", baseline="relaxed hover search in full (best_only=False)",
                              baseline_value=full, ratio=full / fast))
    count = sum(1000 for _ in pairs)
    print(f"full suite ({count} draws): certify {total_fast:.0f} s CPU ({1e3 * total_fast / count:.1f} ms/draw, "
          f"{total_fast / 2 / 60:.1f} min on 2 cores), with the full search {total_full:.0f} s (ratio {total_full / total_fast:.1f})")
    figures.append(figure("certify, the deciding suite's 13,000 draws (extrapolated)", total_fast, "s CPU",
                          baseline="relaxed hover search in full", baseline_value=total_full, ratio=total_full / total_fast,
                          target="<= ~3 min on 2 cores (~360 s CPU)"))
    write(args.json_path, "certify_speed", "certify per run in the deciding campaign: CPU time per draw", figures)


if __name__ == "__main__":
    main()
