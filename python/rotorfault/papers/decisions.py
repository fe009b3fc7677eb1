"""The decisions on the papers' gaps and misprints: the README's table ("Decisions on the
paper's gaps") read as data, each decision linked to the code files where it is made. The README
is the one source of the text; :data:`DECISION_CODE` adds the links (a test checks that every row
of the table has links and that every linked file exists).

From a source tree the README beside the package is read; from an installed wheel, the copy in
the package's metadata (``readme = "README.md"`` in pyproject.toml puts it there).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

#: The README heading of the table.
HEADING = "## Decisions on the paper's gaps"

_ACAI = "crates/rfcore/src/analysis/acai.rs"
_CONTROLLABILITY = "crates/rfcore/src/analysis/controllability.rs"
_ACTUATOR = "crates/rfcore/src/flight/actuator.rs"
_VEHICLE = "crates/rfcore/src/flight/vehicle.rs"
_SIMULATION = "crates/rfcore/src/flight/simulation"
_SIM_STEP = f"{_SIMULATION}/step.rs"
_SIM_CONFIG = f"{_SIMULATION}/config.rs"
_SIM_NOISE = f"{_SIMULATION}/noise.rs"
_ALLOCATION = "crates/rfcore/src/allocation/mod.rs"
_ACTIVE_SET = "crates/rfcore/src/allocation/active_set.rs"
_SCALING = "crates/rfcore/src/allocation/scaling.rs"
_FACTORISATION = "crates/rfcore/src/allocation/factorisation.rs"
_KE_RS = "crates/rfcore/src/control/ke.rs"
_KE_PY = "python/rotorfault/control/ke.py"
_LQR = "python/rotorfault/control/lqr.py"
_RICCATI = "python/rotorfault/control/riccati.py"
_KE_PRESET = "python/rotorfault/presets/ke-quadcopter.toml"
_LANZON_PY = "python/rotorfault/control/lanzon.py"
_LANZON_RS = "crates/rfcore/src/control/lanzon.rs"
_LANZON_PAPER = "python/rotorfault/papers/lanzon.py"

#: Where each decision is made: the README's "gap" cell -> repository paths.
DECISION_CODE: dict[str, tuple[str, ...]] = {
    "Du uses `+-10^6` for infinity": (_ACAI,),
    "Du eq. (13) for G outside the attainable set": (_ACAI, "python/rotorfault/analysis/acai.py"),
    "numerical zero, rank, units": (_ACAI, "crates/rfcore/src/analysis/mod.rs", _CONTROLLABILITY),
    "the hover verdict": (_ACAI, "python/rotorfault/analysis/acai.py", "python/rotorfault/studies/scan.py"),
    "null vectors": (_ACAI,),
    '"give up yaw"': (_CONTROLLABILITY, _ACAI),
    "Ke's yaw row `c[1, -1, 1, -1]` is rank 3 with Remark 2's angles; `l = 0.0125`": (_KE_PRESET, "python/rotorfault/presets/README.md"),
    "Ke gives no g; Lanzon prints `d` in kg m^2": (_KE_PRESET, "python/rotorfault/presets/lanzon-quadrotor.toml"),
    "actuator integration": (_ACTUATOR, _SIM_STEP),
    "time grid": (_SIM_CONFIG,),
    "rotor efficiency": (_VEHICLE,),
    "Wang's \"10 Hz\" actuator": (_ACTUATOR,),
    "Wang's \"15 dB SNR noise\"": (_SIM_NOISE,),
    "gyroscopic moment (Lanzon eq. (5))": (_VEHICLE,),
    "drag, `k_r`, `I_R`": (_VEHICLE,),
    "fault timing": ("crates/rfcore/src/flight/fault_schedule.rs",),
    "actuator start": (f"{_SIMULATION}/driver.rs", "python/rotorfault/flight/simulator.py"),
    "divergence": (f"{_SIMULATION}/divergence.rs", _SIM_STEP),
    "the ground (no paper models one)": (_SIM_CONFIG, f"{_SIMULATION}/divergence.rs"),
    "altitudes the papers do not print": (
        "python/rotorfault/papers/ke.py",
        "python/rotorfault/studies/campaign.py",
        _LANZON_PAPER,
        "python/rotorfault/papers/wang.py",
    ),
    "noise on zero signals": (_SIM_NOISE,),
    "run size": (_SIM_CONFIG,),
    "several optimal allocations (more rotors than weighted axes, a zero weight)": (_ACTIVE_SET, _ALLOCATION),
    "allocation rank": (_ALLOCATION, _SCALING, _FACTORISATION),
    "Ke's w_r -> 0 \"continuity\" (eq. (36))": (_ACTIVE_SET, "tests/allocation/test_allocation.py"),
    "Ke's printed command law (18)": (_KE_RS, _KE_PY),
    "Ke's filters": (_KE_RS,),
    "spin damping, drag": ("python/rotorfault/presets/ftc", _KE_PY),
    "Ke's rotor numbering": (_KE_PRESET, "python/rotorfault/papers/ke.py"),
    "Table IV experiment column (`k_rotor = 1.3`)": (_KE_PY, "python/rotorfault/presets/ftc"),
    "Wang: no inertias, no drag, one lag for speed and pitch, printed B of Sec. 3.2": (
        "python/rotorfault/presets/vpp/wang.toml",
        "python/rotorfault/control/vpp.py",
        _ACTUATOR,
    ),
    "Lanzon's `k_r`, `k_t`, `I_R` (not in the paper)": (_LANZON_PY, "python/rotorfault/presets/lanzon-quadrotor.toml"),
    "Lanzon eq. (24) without the arm length": (_LANZON_PY, _LANZON_RS),
    "Lanzon eq. (32)": (_LANZON_RS,),
    "Lanzon Table 1 `I_zz = 1.16e-3`": ("python/rotorfault/presets/lanzon-quadrotor.toml", _LANZON_PAPER),
    "Lanzon's loop-shape weight": ("python/rotorfault/control/robust.py", _LANZON_PY),
    "loop-shaping realisations and norms (python-control converts and reduces with slycot when installed, otherwise with scipy)": (
        "python/rotorfault/control/robust.py", "python/rotorfault/control/realisation.py", "python/rotorfault/control/norms.py"),
    "Lanzon design (a) \"without limits\"": (_LANZON_PAPER,),
    "Lanzon's outer loop gains (not in the paper)": (_LANZON_PY, _LANZON_RS),
    "hover trim (`hover_trim`)": (_LQR,),
    "linear models at a bound (`linearize`)": (_LQR,),
    "what LQR refuses (`lqr_hover`, `lqr_hover_allocated`)": (_LQR, _RICCATI),
    "what an LQR design checks (`design_lqr`)": (_RICCATI,),
    "stabilisability and detectability (PBH)": ("python/rotorfault/control/stabilisability.py", "python/rotorfault/control/vpp.py"),
    "Wang's fixed-pitch comparison": (
        "python/rotorfault/papers/wang.py",
        "python/rotorfault/presets/wang-standard-fixed-pitch.toml",
    ),
    "Euler singularity": (_LQR,),
    "limits": (_ACAI, _CONTROLLABILITY, "python/rotorfault/studies/scan.py"),
}


@dataclass(frozen=True)
class Decision:
    """One row of the README's table: the gap, the decision (both Markdown, as written) and the
    files where it is made (repository paths; empty when the table has a row no link names yet)."""

    gap: str
    decision: str
    code: tuple[str, ...]


def _is_source_tree(root: Path) -> bool:
    return (root / "README.md").is_file() and (root / "crates" / "rfcore").is_dir() and (root / "python" / "rotorfault").is_dir()


def source_root() -> Path | None:
    """The repository root: the source tree the package runs from (editable install or
    checkout), else the current directory when it is a rotorfault clone (``pip install . &&
    rotorfault reproduce`` run in the clone), else None."""
    root = Path(__file__).resolve().parents[3]
    if _is_source_tree(root):
        return root
    cwd = Path.cwd().resolve()
    return cwd if _is_source_tree(cwd) else None


def readme_text() -> str:
    root = source_root()
    if root is not None:
        return (root / "README.md").read_text(encoding="utf-8")
    from importlib.metadata import PackageNotFoundError, metadata

    try:
        text = metadata("rotorfault").get_payload()  # type: ignore[attr-defined]
    except PackageNotFoundError:  # pragma: no cover - neither a source tree nor installed
        text = None
    if not text:
        raise ValueError("README: not found beside the package nor in its metadata")
    return str(text)


def _cells(line: str) -> list[str]:
    # Split on '|' outside backticks (a decision may quote `|x_i|`).
    cells: list[str] = []
    current: list[str] = []
    code = False
    for ch in line.strip()[1:-1] if line.strip().endswith("|") else line.strip()[1:]:
        if ch == "`":
            code = not code
        if ch == "|" and not code:
            cells.append("".join(current).strip())
            current = []
        else:
            current.append(ch)
    cells.append("".join(current).strip())
    return cells


def decisions(readme: str | None = None) -> list[Decision]:
    """The rows of the README's decisions table, in order, with their code links."""
    text = readme_text() if readme is None else readme
    lines = text.splitlines()
    try:
        start = next(i for i, line in enumerate(lines) if line.strip() == HEADING)
    except StopIteration:
        raise ValueError(f"README: no {HEADING!r} section") from None
    rows: list[Decision] = []
    for line in lines[start + 1 :]:
        if line.startswith("## "):
            break
        if not line.startswith("|"):
            if rows:
                break
            continue
        cells = _cells(line)
        if len(cells) < 2 or cells[0] == "gap" or set(cells[0]) <= {"-", ":"}:
            continue
        rows.append(Decision(cells[0], " | ".join(cells[1:]), DECISION_CODE.get(cells[0], ())))
    if not rows:
        raise ValueError(f"README: the {HEADING!r} section holds no table rows")
    return rows


__all__ = ["DECISION_CODE", "HEADING", "Decision", "decisions", "readme_text", "source_root"]
