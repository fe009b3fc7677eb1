"""Scans keep the user's vehicle (issue 27): every row of a parameter scan is the user's airframe
with only the scanned parameter changed (3-D positions, tilted axes, reversible rotors, each
rotor's k_mu, PX4 imports kept), checked row by row against an airframe built independently for
that row; overlapping axes are refused; a grid's size is exact (no int64 wrap) and bounded; a
10^12-point plan takes constant memory."""

from __future__ import annotations

import math
import tracemalloc
from pathlib import Path
from typing import Any, Callable

import numpy as np
import pytest

import rotorfault as rf
from rotorfault.studies.design import design_search
from rotorfault.studies.scan import acai_scan

pytest.importorskip("pyarrow")

DATA = Path(__file__).resolve().parents[1] / "data"
ANGLES_DEG = (30.0, 90.0, 150.0, 210.0, 270.0, 330.0)
TILT = 0.2  # rad, alternating sideways tilt (a tilted hexacopter, fully actuated)


def tilted_toml(*, mass: float = 2.0, radius: float = 0.3, k_mu: float = 0.02, max_thrust: float = 9.0,
                max_thrust_2: float | None = None, spins: str = "PNPNPN") -> str:
    """A tilted hexacopter written by hand: general rotors with heights, tilted axes, their own
    k_mu, rotor 6 reversible."""
    lines = [f'name = "tilted"', f"mass_kg = {mass!r}", "inertia_kg_m2 = [0.03, 0.03, 0.05]", "drag_torque_ratio_m = 0.015"]
    for i, deg in enumerate(ANGLES_DEG):
        phi = math.radians(deg)
        side = TILT if i % 2 == 0 else -TILT
        axis = [-math.sin(phi) * math.sin(side), math.cos(phi) * math.sin(side), -math.cos(side)]
        top = max_thrust_2 if (i == 1 and max_thrust_2 is not None) else max_thrust
        lines += [
            "", "[[rotor]]",
            f"position_m = [{radius * math.cos(phi)!r}, {radius * math.sin(phi)!r}, -0.02]",
            f"thrust_axis = [{axis[0]!r}, {axis[1]!r}, {axis[2]!r}]",
            f'spin = "{"cw" if spins[i] == "P" else "ccw"}"',
            f"drag_torque_ratio_m = {k_mu!r}",
            f"max_thrust_n = {top!r}",
            f"min_thrust_n = {-top if i == 5 else 0.0!r}",
        ]
    return "\n".join(lines) + "\n"


def px4_text(*, ct: float | None = None, km: float | None = None) -> str:
    """The PX4 hexa-x test file, rotor 1 tilted and reversible, rotor 2 raised (so no planar frame
    is the same vehicle), with every CT (and |KM|) replaced."""
    out = []
    for line in (DATA / "px4-hexa-x.params").read_text().splitlines():
        fields = line.split("\t")
        if len(fields) == 5 and fields[2].endswith("_KM") and km is not None:
            fields[3] = repr(math.copysign(km, float(fields[3])))
        out.append("\t".join(fields))
    text = "\n".join(out) + "\n"
    text += "1\t1\tCA_ROTOR0_AX\t0.3\t9\n1\t1\tCA_ROTOR1_PZ\t-0.05\t9\n1\t1\tCA_R_REV\t1\t6\n"
    if ct is not None:
        text += "".join(f"1\t1\tCA_ROTOR{n}_CT\t{ct!r}\t9\n" for n in range(6))
    return text


def from_px4(tmp: Path, text: str, **kwargs: Any) -> rf.Airframe:
    path = tmp / f"frame{abs(hash(text))}.params"
    path.write_text(text)
    return rf.Airframe.from_px4_params(path, **kwargs)


def check_rows(scan: Any, frame_for: Callable[[float], rf.Airframe], parameter: str, base_efficiency: np.ndarray[Any, Any]) -> None:
    """Every row against the airframe built for it, at the row's efficiency of rotor 1."""
    columns = {name: scan.column(name) for name in scan.table.column_names}
    assert len(columns[parameter]) == scan.total > 0
    for row in range(scan.total):
        frame = frame_for(float(columns[parameter][row]))
        eta = base_efficiency.copy()
        eta[0] = columns["efficiency_1"][row]
        report = rf.controllability(frame, eta)
        assert columns["controllability_rank"][row] == report.controllability_rank, row
        assert columns["controllable"][row] == report.controllable, row
        for formula in ("eq13", "facet-margin"):
            expected = float(rf.acai(frame, eta, formula=formula))
            got = columns[f"acai_{formula.replace('-', '_')}"][row]
            np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-12, err_msg=f"row {row} {formula}")


EFF = {"efficiency_1": [0.0, 0.6, 1.0]}


@pytest.mark.parametrize(
    ("parameter", "values", "build"),
    [
        ("mass_kg", [1.5, 2.5, 3.5], lambda v: tilted_toml(mass=v)),
        ("max_thrust_n", [6.0, 9.0], lambda v: tilted_toml(max_thrust=v)),
        ("max_thrust_n_2", [4.0, 12.0], lambda v: tilted_toml(max_thrust_2=v)),
        ("arm_length_m", [0.2, 0.45], lambda v: tilted_toml(radius=v)),
        ("drag_torque_ratio_m", [0.01, 0.05], lambda v: tilted_toml(k_mu=v)),
    ],
)
def test_tilted_frame_rows(parameter: str, values: list[float], build: Callable[[float], str]) -> None:
    base = rf.Airframe.from_toml_str(tilted_toml())
    assert not base.is_planar and base.min_thrust_n[5] < 0
    scan = acai_scan(base, {parameter: values, **EFF})
    check_rows(scan, lambda v: rf.Airframe.from_toml_str(build(v)), parameter, base.efficiency)


@pytest.mark.parametrize(
    ("parameter", "values", "kwargs"),
    [("mass_kg", [0.8, 1.6], lambda v: {"mass_kg": v}), ("max_thrust_n", [4.0, 8.0], None), ("drag_torque_ratio_m", [0.02, 0.08], None)],
)
def test_px4_import_rows(tmp_path: Path, parameter: str, values: list[float], kwargs: Any) -> None:
    base = from_px4(tmp_path, px4_text(), mass_kg=1.2)

    def frame_for(v: float) -> rf.Airframe:
        if parameter == "mass_kg":
            return from_px4(tmp_path, px4_text(), mass_kg=v)
        if parameter == "max_thrust_n":
            return from_px4(tmp_path, px4_text(ct=v), mass_kg=1.2)
        return from_px4(tmp_path, px4_text(km=v), mass_kg=1.2)

    scan = acai_scan(base, {parameter: values, **EFF})
    check_rows(scan, frame_for, parameter, base.efficiency)


def test_planar_preset_rows() -> None:
    base = rf.Airframe.preset("hexa-pnpnpn")

    def frame_for(v: float) -> rf.Airframe:
        return rf.Airframe(base.arm_angle_rad, base.arm_length_m, base.spin, base.max_thrust_n, base.mass_kg,
                           base.inertia_kg_m2, v, gravity_m_s2=base.gravity_m_s2, name=base.name)

    scan = acai_scan(base, {"drag_torque_ratio_m": [0.05, 0.1, 0.2], **EFF})
    check_rows(scan, frame_for, "drag_torque_ratio_m", base.efficiency)


def test_design_search_keeps_the_tilted_vehicle() -> None:
    base = rf.Airframe.from_toml_str(tilted_toml())
    result = design_search(base, formula="facet-margin")
    assert len(result.designs) == 2**6  # tilted: no symmetry classes, every assignment ranked
    for design in result.designs[:12]:
        frame = rf.Airframe.from_toml_str(tilted_toml(spins=design.spins))
        np.testing.assert_allclose(design.nominal, float(rf.acai(frame, formula="facet-margin")), rtol=1e-12, atol=1e-12)
    by_mass = design_search(base, parameter="mass_kg", values=[3.0], formula="facet-margin")
    best = by_mass.best(3.0)
    frame = rf.Airframe.from_toml_str(tilted_toml(mass=3.0, spins=best.spins))
    np.testing.assert_allclose(best.nominal, float(rf.acai(frame, formula="facet-margin")), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("axes", [
    {"max_thrust_n": [5.0, 6.0], "max_thrust_n_2": [5.0, 7.0]},
    {"arm_length_m_2": [0.2], "arm_length_m": [0.3]},
    {"efficiency_2": [0.5], "efficiency_02": [1.0]},
])
def test_overlapping_axes_are_refused(axes: dict[str, list[float]]) -> None:
    with pytest.raises(ValueError, match=r"axes: .* both set"):
        acai_scan(rf.Airframe.preset("quad-x"), axes)


def test_a_grid_past_int64_is_refused_with_its_count(tmp_path: Path) -> None:
    """16 axes of 16 levels: 2^64 points, 0 in int64 (main wrote 0 rows and marked them complete)."""
    frame = rf.Airframe.preset("octo-x")
    levels = list(np.linspace(0.5, 1.0, 16))
    axes = {f"efficiency_{r}": levels for r in range(1, 9)}
    axes |= {f"max_thrust_n_{r}": list(np.linspace(5.0, 7.0, 16)) for r in range(1, 9)}
    out = tmp_path / "huge"
    with pytest.raises(ValueError, match="18,446,744,073,709,551,616 grid points exceed"):
        acai_scan(frame, axes, out=out)
    assert not out.exists()
    with pytest.raises(ValueError, match=r"^axes: 18,446,744,073,709,551,616 rows of 147 bytes .* exceed the in-memory limit .* more than a streamed scan takes too"):
        acai_scan(frame, axes)


class _Stop(Exception):
    pass


def test_planning_a_10_to_the_12_grid_takes_constant_memory(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """10^12 points in chunks of 2^20 (953,675 chunks): the plan is made one chunk at a time, so
    starting the scan (lock, checks, manifest, first chunk handed out) allocates a few MB."""
    from rotorfault.studies import scan as scan_module

    def stop(self: Any, spec: Any) -> Any:
        raise _Stop

    monkeypatch.setattr(scan_module._ScanTask, "__call__", stop)
    frame = rf.Airframe.preset("hexa-pnpnpn")
    axes = {f"efficiency_{r}": np.linspace(0.0, 1.0, 100) for r in range(1, 7)}
    tracemalloc.start()
    try:
        with pytest.raises(_Stop):
            acai_scan(frame, axes, out=tmp_path / "plan")
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 8 * 2**20, f"peak {peak / 2**20:.1f} MiB"
