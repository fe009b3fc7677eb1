"""Every figure the package draws (issue 21, items 9 and 10): saved without touching global
matplotlib state (backend and pyplot's figure list unchanged), titled with what it shows, axes
labelled, no text below 8 pt, legends outside the data, series distinguishable without colour,
nothing outside the canvas. Each was also rendered and inspected by eye when written."""

from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np
import pytest
from matplotlib.figure import Figure

import rotorfault as rf
from rotorfault.plotting.style import MIN_FONT_PT
from rotorfault.allocation import plot_attainable_slices
from rotorfault.papers import ke as ke_paper


def texts(fig: Figure) -> list[matplotlib.text.Text]:
    return [t for t in fig.findobj(matplotlib.text.Text) if t.get_visible() and t.get_text().strip()]


def check_figure(fig: Figure, path: Path, *, title_has: tuple[str, ...]) -> None:
    fig.canvas.draw()  # type: ignore[no-untyped-call]
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    title = (fig._suptitle.get_text() if fig._suptitle else "") + " ".join(ax.get_title() for ax in fig.axes)
    for fragment in title_has:
        assert fragment in title, (fragment, title)
    small = [(t.get_text(), t.get_fontsize()) for t in texts(fig) if t.get_fontsize() < MIN_FONT_PT]
    assert not small, small
    # Everything drawn lies on the canvas (1 px tolerance for anti-aliasing at the edge).
    canvas, drawn = fig.bbox, fig.get_tightbbox(renderer).transformed(fig.dpi_scale_trans)
    assert drawn.x0 >= -1 and drawn.y0 >= -1 and drawn.x1 <= canvas.x1 + 1 and drawn.y1 <= canvas.y1 + 1, (drawn, canvas)
    for ax in fig.axes:
        if ax.get_label() == "<colorbar>":
            continue
        # Stacked panels sharing the time axis label it once, on the bottom panel.
        siblings = ax.get_shared_x_axes().get_siblings(ax)
        assert ax.get_ylabel() and any(other.get_xlabel() for other in siblings), ax.get_title()
    assert path.stat().st_size > 10_000
    assert path.read_bytes()[:4] == b"\x89PNG"


def check_greyscale_safe(ax: matplotlib.axes.Axes) -> None:
    """Lines in one panel's legend differ in line style or marker, not only in colour."""
    lines = [line for line in ax.get_lines() if not line.get_label().startswith("_")]
    keys = {(str(line.get_linestyle()), str(line.get_marker()), str(getattr(line, "_dash_pattern", ""))) for line in lines}
    assert len(keys) == len(lines), [line.get_label() for line in lines]


@pytest.fixture(autouse=True)
def global_state_untouched():  # type: ignore[no-untyped-def]
    import matplotlib.pyplot as plt

    backend = matplotlib.get_backend()
    figures = plt.get_fignums()
    yield
    assert matplotlib.get_backend() == backend
    assert plt.get_fignums() == figures


def test_trajectory_figure(tmp_path: Path) -> None:
    run = ke_paper.run_scenario("tracking-one-failure")
    fig = run.plot(str(tmp_path / "track.png"))
    check_figure(fig, tmp_path / "track.png", title_has=("tracking-one-failure", "law feedforward", "setpoint", "from 20 s"))
    position = fig.axes[0]
    assert any("setpoint" in line.get_label() for line in position.get_lines())
    for ax in fig.axes:
        check_greyscale_safe(ax)
        legend = ax.get_legend()
        # outside the plotting area, to the right
        assert legend is not None and legend.get_window_extent().x0 >= ax.get_window_extent().x1
    # Yaw of the spinning vehicle has its own panel, unwrapped; roll and pitch are not hidden.
    roll_pitch = fig.axes[1]
    assert {line.get_label() for line in roll_pitch.get_lines() if not line.get_label().startswith("_")} == {"roll", "pitch"}
    assert np.ptp(roll_pitch.get_ylim()) < 200


def test_round_off_is_not_magnified(tmp_path: Path) -> None:
    """Fault-free hover: thrust constant to 1e-11 N, angles to 1e-8 deg: the axes show at least
    0.2 N and 2 deg."""
    fig = ke_paper.run_scenario("fault-free").plot(str(tmp_path / "hover.png"))
    assert np.ptp(fig.axes[4].get_ylim()) >= 0.2 and np.ptp(fig.axes[1].get_ylim()) >= 2.0


def test_lost_run_figure_says_when(tmp_path: Path) -> None:
    fig = ke_paper.run_scenario("one-failure", law="baseline").plot(str(tmp_path / "lost.png"))
    check_figure(fig, tmp_path / "lost.png", title_has=("one-failure", "law baseline", "lost at t = 2.37 s"))


def test_primary_axis_figure(tmp_path: Path) -> None:
    runs = [ke_paper.run_scenario("one-failure"), ke_paper.run_scenario("one-failure", law="baseline")]
    fig = ke_paper.plot_primary_axis(runs, str(tmp_path / "pa.png"))
    check_figure(fig, tmp_path / "pa.png", title_has=("primary axis", "one-failure (feedforward)", "lost at 2.37 s"))
    assert [t.get_text() for t in fig.legends[0].get_texts()] == ["whole flight", "last 10 s", "start", "lost"]


@pytest.mark.parametrize("give_up_yaw", [False, True])
def test_scan_figure(tmp_path: Path, give_up_yaw: bool) -> None:
    scan = rf.efficiency_scan(rf.Airframe.preset("hexa-pnpnpn"), (1, 2, 5), 0.1, give_up_yaw=give_up_yaw)
    fig = scan.plot(str(tmp_path / "scan.png"))
    check_figure(fig, tmp_path / "scan.png", title_has=("hexa-pnpnpn", "giving up yaw" if give_up_yaw else "with yaw"))
    if give_up_yaw:
        assert all("giving up yaw" in ax.get_title() for ax in fig.axes if ax.get_title())
    # The colour scale spans the values that occur; "uncontrollable" is a hatched patch, not a colour.
    from matplotlib.collections import QuadMesh

    meshes = [c for ax in fig.axes for c in ax.collections if isinstance(c, QuadMesh) and ax.get_label() != "<colorbar>"]
    assert len(meshes) == 3
    data = np.concatenate([np.ma.compressed(np.ma.masked_invalid(m.get_array())) for m in meshes])
    for mesh in meshes:
        assert mesh.norm.vmin == pytest.approx(data.min(), abs=1e-12) or data.min() == data.max()
        assert mesh.norm.vmax == pytest.approx(data.max(), abs=1e-12) or data.min() == data.max()


def test_attainable_slices_figure(tmp_path: Path) -> None:
    fig = plot_attainable_slices(rf.Airframe.preset("hexa-pnpnpn"), path=str(tmp_path / "slices.png"))
    check_figure(fig, tmp_path / "slices.png", title_has=("hexa-pnpnpn", "attainable set"))
    check_greyscale_safe(fig.axes[0])


def test_plot_does_not_switch_the_backend(tmp_path: Path) -> None:
    """Item 9: the user's backend stays whatever it was (checked by the fixture); the figure is
    returned and not in pyplot's list."""
    import matplotlib.pyplot as plt

    fig = rf.Simulator(rf.Airframe.preset("quad-x")).run(rf.State(position=(0, 0, -10)), 0.1).plot(str(tmp_path / "x.png"))
    assert isinstance(fig, Figure)
    assert fig not in [plt.figure(n) for n in plt.get_fignums()]
