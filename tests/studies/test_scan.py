"""Efficiency-grid scans (Du Fig. 4) and their plot."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import rotorfault as rf


def test_scan_matches_batch_and_grid_layout(pnpnpn: rf.Airframe) -> None:
    scan = rf.efficiency_scan(pnpnpn, rotors=(2, 5), step=0.25)
    np.testing.assert_array_equal(scan.levels, [0, 0.25, 0.5, 0.75, 1])
    assert scan.points.shape == (25, 2)
    np.testing.assert_array_equal(scan.points[1], [0.0, 0.25])  # last rotor varies fastest
    etas = np.ones((25, 6))
    etas[:, [1, 4]] = scan.points
    np.testing.assert_array_equal(scan.acai, rf.acai_batch(pnpnpn, etas))


def test_scan_keeps_other_rotors_efficiency(pnpnpn: rf.Airframe) -> None:
    worn = pnpnpn.with_efficiency([1, 1, 0.5, 1, 1, 1])
    scan = rf.efficiency_scan(worn, rotors=(1,), step=0.5)
    assert scan.acai[-1] == rf.acai(worn)


def test_scan_progress_bar_path(pnpnpn: rf.Airframe) -> None:
    scan = rf.efficiency_scan(pnpnpn, rotors=(1, 2), step=0.5, progress=True)
    assert scan.acai.shape == (9,)


def test_plot_writes_png(tmp_path: Path, pnpnpn: rf.Airframe) -> None:
    import matplotlib.pyplot as plt

    scan = rf.efficiency_scan(pnpnpn, rotors=(1, 2, 5), step=0.1)
    path = tmp_path / "fig4.png"
    fig = scan.plot(str(path))
    assert path.stat().st_size > 10_000
    assert len(fig.axes) >= 4
    plt.close(fig)


@pytest.mark.parametrize(
    ("kwargs", "error", "message"),
    [
        ({"rotors": (1, 1)}, ValueError, "each rotor may be swept once"),
        ({"rotors": ()}, ValueError, "at least one rotor"),
        ({"rotors": (7,)}, ValueError, "rotor numbers run from 1 to 6"),
        ({"rotors": ("1",)}, TypeError, "1-based rotor numbers"),
        ({"step": 0.0}, ValueError, r"step: must lie in \[1e-9, 1\]"),
        ({"step": 0.07}, ValueError, "step: must divide 1 evenly"),
        ({"step": "0.1"}, TypeError, "step: expected a real number"),
    ],
)
def test_scan_bad_input(pnpnpn: rf.Airframe, kwargs: dict[str, object], error: type[Exception], message: str) -> None:
    with pytest.raises(error, match=message):
        rf.efficiency_scan(pnpnpn, **kwargs)  # type: ignore[arg-type]


def test_plot_needs_three_rotors(pnpnpn: rf.Airframe) -> None:
    with pytest.raises(ValueError, match="three swept rotors"):
        rf.efficiency_scan(pnpnpn, rotors=(1, 2), step=0.5).plot()
