"""Start-up cost of ``import rotorfault`` and of one CLI call, against baselines in the same run.

Baselines: the interpreter alone, ``import numpy`` (the floor: rotorfault needs it), and the eager
import the package did before issue 15 (rotorfault plus scipy.signal, python-control and
matplotlib.pyplot, which it imported at start-up). Each figure is the median wall time of fresh
interpreters (``--repeats``, default 15). ``python -X importtime -c "import rotorfault"`` shows
the per-module breakdown.

    python benches/startup.py [--repeats N] [--json PATH]
"""

from __future__ import annotations

import argparse
import shutil
import statistics
import subprocess
import sys
import time


def wall(args: list[str], repeats: int) -> float:
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        subprocess.run(args, check=True, capture_output=True)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    from _results import add_json_option, figure, write

    parser.add_argument("--repeats", type=int, default=15)
    add_json_option(parser)
    args = parser.parse_args()
    repeats = args.repeats
    py = sys.executable
    rows = [
        ("python -c pass", wall([py, "-c", "pass"], repeats)),
        ("import numpy (floor)", wall([py, "-c", "import numpy"], repeats)),
        ("import rotorfault", wall([py, "-c", "import rotorfault"], repeats)),
        (
            "eager: rotorfault + scipy.signal + control + pyplot (before)",
            wall([py, "-c", "import rotorfault, scipy.signal, control, matplotlib.pyplot"], repeats),
        ),
    ]
    cli = shutil.which("rotorfault")
    if cli is not None:
        rows.append(("rotorfault acai -a hexa-pnpnpn", wall([cli, "acai", "-a", "hexa-pnpnpn"], repeats)))
    width = max(len(name) for name, _ in rows)
    for name, seconds in rows:
        print(f"{name:<{width}}  {seconds * 1e3:8.1f} ms")
    lazy, eager = rows[2][1], rows[3][1]
    print(f"import rotorfault: {eager / lazy:.1f}x faster than the eager import (targets: < 300 ms; CLI < 600 ms)")
    figures = [figure("import rotorfault", lazy * 1e3, "ms", baseline="the eager import before issue 15",
                      baseline_value=eager * 1e3, ratio=eager / lazy, target="< 300 ms"),
               figure("import numpy (the floor)", rows[1][1] * 1e3, "ms")]
    if cli is not None:
        figures.append(figure("CLI call: rotorfault acai -a hexa-pnpnpn", rows[4][1] * 1e3, "ms", target="< 600 ms"))
    write(args.json_path, "startup", f"start-up: median wall time of {repeats} fresh interpreters", figures,
          reduced=None if repeats == 15 else f"{repeats} repeats instead of 15")


if __name__ == "__main__":
    main()
