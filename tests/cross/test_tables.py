"""Results as tables (issue 31): every tabular result has ``to_arrow()``, ``to_pandas()`` and a
notebook view, one row per case, units in the column names; what is written to Parquet reads back
with the same schema and rows; without pandas, ``to_pandas()`` names the extra to install and
everything else works."""

from __future__ import annotations

import json
import math
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import rotorfault as rf
from rotorfault._util.tables import HTML_ROWS, Records, Tabular
from rotorfault.flight.trajectory import ERROR_STATE_COLUMNS, STATE_COLUMNS
from rotorfault.papers import _numbers, du, ke as ke_paper, lanzon as lanzon_paper, wang
from rotorfault.studies import Campaign, read_campaign, run_campaign
from rotorfault.studies.certify import certify
from rotorfault.studies.scan import scan_schema

from without_packages import run_without

pa = pytest.importorskip("pyarrow")
pq = pytest.importorskip("pyarrow.parquet")
pd = pytest.importorskip("pandas")

HEXA = rf.Airframe.preset("hexa-ppnnpn")
QUAD = rf.Airframe.preset("quad-x")


def _flight() -> rf.Trajectory:
    sim = rf.Simulator(QUAD, noise=rf.Noise(snr_db=30.0, seed=1))
    lqr = rf.lqr_hover(sim, position=(0, 0, -10))
    return sim.run(rf.State(position=(0, 0, -10)), 2.0, controller=lqr, faults=[rf.RotorFault(1, 1.0)])


def _sensed_flight() -> rf.Trajectory:
    """The hover LQR on motion capture losing rotor 1: the estimate beside the truth."""
    sim = rf.Simulator(QUAD, sensing=rf.Sensing(seed=3))
    lqr = rf.lqr_hover(rf.Simulator(QUAD), position=(0, 0, -10))
    return sim.run(rf.State(position=(0, 0, -10)), 0.5, controller=lqr, faults=[rf.RotorFault(1, 0.25)])


def _ke_rows() -> Any:
    from dataclasses import replace

    short = replace(ke_paper.scenario("one-failure"), duration_s=6.0)
    return ke_paper.report_rows([ke_paper.run_scenario(short)])


def _monte_carlo() -> lanzon_paper.MonteCarloResult:
    return lanzon_paper.MonteCarloResult("ke", 3, 0.2, 15.0, 20.0, 1.16e-3, ("holds-position", "crashed", "off-station"),
                                         np.array([0.1, math.nan, 3.0]), np.ones((3, 5)))


#: name -> (how to make it, rows expected, columns that must be there)
RESULTS: dict[str, tuple[Callable[[], Tabular], int, tuple[str, ...]]] = {
    "failure table": (lambda: rf.failure_table(HEXA, max_failed=2), 22, ("failed_rotors", "acai_eq13", "controllable_give_up_yaw")),
    "6-D failure table": (lambda: rf.failure_table(_tilted(), max_failed=1), 7, ("acai_eq13_wrench", "controllable_wrench")),
    "certificate": (lambda: certify(HEXA), 22, ("failed_rotors", "hover", "acai_facet_margin", "thrust_to_weight", "drop_axes")),
    "efficiency scan": (lambda: rf.efficiency_scan(HEXA, (1, 2, 5), 0.25), 125, ("efficiency_1", "efficiency_5", "acai_eq13", "hover_code")),
    "acai scan": (lambda: rf.acai_scan(HEXA, {"mass_kg": [1.2, 1.5], "efficiency_1": [0, 1]}, give_up_yaw=True), 4,
                  ("mass_kg", "acai_facet_margin_give_up_yaw", "controllable")),
    "acai batch": (lambda: rf.acai_batch(QUAD, np.ones((3, 4)), with_hover=True), 3, ("acai_eq13", "hover_code")),
    "design search": (lambda: rf.design_search(QUAD), 4, ("rank", "spins", "acai_facet_margin", "worst_single_acai_facet_margin")),
    "design search with a parameter": (lambda: rf.design_search(QUAD, parameter="arm_length_m", values=[0.2, 0.3]), 8,
                                       ("arm_length_m", "rank")),
    "trajectory": (_flight, 801, ("t_s", "north_m", "yaw_rate_rad_s", "rotor_1_command_n", "rotor_4_thrust_n", "rotor_1_efficiency",
                                  "measured_down_m")),
    "sensed trajectory": (_sensed_flight, 201, ("t_s", "north_m", "estimate_north_m", "estimate_yaw_rate_rad_s",
                                                "estimate_quaternion_w", "estimate_std_down_m",
                                                "estimate_std_attitude_down_rad", "estimate_std_accel_bias_down_m_s2",
                                                "gyro_saturated", "accel_saturated")),
    "allocation batch": (lambda: rf.allocate(rf.Airframe.preset("ke-quadcopter"), [[7.0, 0, 0, 0], [40.0, 0, 0, 1.0]]), 2,
                         ("virtual_control_1", "achieved_4", "rotor_1_command", "status", "stationarity")),
    "Ke report rows": (_ke_rows, 1, ("scenario", "outcome", "r_rad_s", "max_altitude_loss_m")),
    "Lanzon Monte Carlo": (_monte_carlo, 3, ("run", "mass_scale", "outcome", "final_error_m")),
    "Wang comparison rows": (wang.comparison_rows, 6, ("vehicle", "failed_rotors", "controllability_rank", "acai_eq13")),
    "printed numbers": (lambda: _numbers.number_rows(du.printed_numbers()), len(du.printed_numbers()), ("printed", "ours", "status")),
}


def _tilted() -> rf.Airframe:
    phi = np.radians(np.arange(6) * 60.0)
    side = np.array([-1.0, 1.0] * 3)[:, None]
    axis = np.cos(np.radians(20)) * np.array([0, 0, -1.0]) + np.sin(np.radians(20)) * side * np.stack(
        [-np.sin(phi), np.cos(phi), 0 * phi], axis=1)
    return rf.Airframe.from_rotors(position_m=0.275 * np.stack([np.cos(phi), np.sin(phi), 0 * phi], axis=1), thrust_axis=axis,
                                   spin=["cw", "ccw"] * 3, max_thrust_n=[6.125] * 6, mass_kg=1.535,
                                   inertia_kg_m2=[0.0411, 0.0478, 0.0599], drag_torque_ratio_m=0.1)


@pytest.fixture(scope="module", params=sorted(RESULTS))
def result(request: pytest.FixtureRequest) -> tuple[str, Tabular, int, tuple[str, ...]]:
    make, rows, columns = RESULTS[request.param]
    return request.param, make(), rows, columns


def test_one_row_per_case_with_named_columns(result: tuple[str, Tabular, int, tuple[str, ...]]) -> None:
    name, value, rows, columns = result
    table = value.to_arrow()
    assert isinstance(table, pa.Table), name
    assert table.num_rows == rows, name
    for column in columns:
        assert column in table.column_names, (name, column)
    # snake_case names, each once: they are DataFrame columns and Parquet fields
    assert all(re.fullmatch(r"[a-z][a-z0-9_]*", c) for c in table.column_names), table.column_names
    assert len(set(table.column_names)) == len(table.column_names)


def test_to_pandas_is_the_arrow_table(result: tuple[str, Tabular, int, tuple[str, ...]]) -> None:
    name, value, rows, _ = result
    frame = value.to_pandas()
    assert isinstance(frame, pd.DataFrame)
    assert list(frame.columns) == value.to_arrow().column_names
    assert len(frame) == rows
    pd.testing.assert_frame_equal(frame, value.to_arrow().to_pandas())


def test_parquet_reads_back_the_same_schema_and_rows(result: tuple[str, Tabular, int, tuple[str, ...]], tmp_path: Path) -> None:
    name, value, _, _ = result
    table = value.to_arrow()
    path = tmp_path / "rows.parquet"
    pq.write_table(table, path)
    back = pq.read_table(path)
    assert back.schema.equals(table.schema, check_metadata=True), name
    assert back.to_pylist() == table.to_pylist() or _equal_nan(back, table), name


def _equal_nan(a: Any, b: Any) -> bool:
    for column in a.column_names:
        x, y = a.column(column).to_pylist(), b.column(column).to_pylist()
        for u, v in zip(x, y, strict=True):
            if not (u == v or (isinstance(u, float) and isinstance(v, float) and math.isnan(u) and math.isnan(v))):
                return False
    return True


def test_the_notebook_view_shows_the_rows(result: tuple[str, Tabular, int, tuple[str, ...]]) -> None:
    name, value, rows, _ = result
    page = value._repr_html_()
    assert page.startswith('<table class="rotorfault-table">') and page.endswith("</table>")
    assert f"{rows:,} row" in page
    assert page.count("<tr>") == 1 + min(rows, HTML_ROWS) + (rows > HTML_ROWS)


def test_the_notebook_view_escapes_every_cell() -> None:
    hostile = "<script>alert('x')</script> & co"
    rows = Records([{"name": hostile, "value_m": 1.0}], [("name", "string"), ("value_m", "float64")], title=f"a {hostile}")
    page = rows._repr_html_()
    assert "<script>" not in page
    assert "&lt;script&gt;" in page and "&amp; co" in page


def test_records_keep_their_rows_and_refuse_other_keys() -> None:
    rows = Records([{"a_m": 1.0, "b": "x"}, {"a_m": None, "b": "y"}], [("a_m", "float64"), ("b", "string")])
    assert list(rows) == [{"a_m": 1.0, "b": "x"}, {"a_m": None, "b": "y"}] and rows[1]["b"] == "y"
    assert rows.to_arrow().column("a_m").null_count == 1  # None is a null, not NaN
    with pytest.raises(ValueError, match=r"rows\[0\]: keys differ"):
        Records([{"a_m": 1.0}], [("a_m", "float64"), ("b", "string")])
    with pytest.raises(ValueError, match="unknown column type"):
        Records([], [("a", "float16")])


def test_a_batch_is_every_runs_trajectory_with_its_run_number() -> None:
    sim = rf.Simulator(QUAD)
    lqr = rf.lqr_hover(sim, position=(0, 0, -10))
    batch = rf.simulate_batch(sim, [rf.State(position=(0.1 * i, 0, -10)) for i in range(3)], 0.5, controllers=lqr,
                              faults=[[], [rf.RotorFault(1, 0.1)], []], record_every=10)
    table = batch.to_arrow()
    assert table.column_names[0] == "run"
    for k, run in enumerate(batch.trajectories):
        mine = table.filter(pa.compute.equal(table.column("run"), k))
        assert mine.drop(["run"]).equals(run.to_arrow().replace_schema_metadata(None))
    assert table.num_rows == sum(len(run.t) for run in batch.trajectories)


def test_a_sensed_flight_keeps_the_estimate_beside_the_truth(tmp_path: Path) -> None:
    """Every estimate column is the recorded estimate (the same numbers as ``Trajectory.estimate``),
    the flags are booleans, the metadata says what the controller flew on with the run's counts,
    and a Parquet file of it reads back with that schema; a run on the truth has no estimate
    columns."""
    run = _sensed_flight()
    e = run.estimate
    assert e is not None
    table = run.to_arrow()
    estimated = np.column_stack([table.column(f"estimate_{name}").to_numpy() for name in STATE_COLUMNS])
    np.testing.assert_array_equal(estimated, e.vector)
    truth = np.column_stack([table.column(name).to_numpy() for name in STATE_COLUMNS])
    np.testing.assert_array_equal(truth, np.hstack([run.position, run.velocity, run.euler, run.omega]))
    np.testing.assert_array_equal(np.column_stack([table.column(f"estimate_quaternion_{c}").to_numpy() for c in "wxyz"]),
                                  e.quaternion)
    np.testing.assert_array_equal(np.column_stack([table.column(f"estimate_std_{name}").to_numpy()
                                                   for name in ERROR_STATE_COLUMNS]), e.std)
    assert table.schema.field("gyro_saturated").type == pa.bool_()
    np.testing.assert_array_equal(table.column("accel_saturated").to_numpy(zero_copy_only=False), e.accel_saturated)
    meta = json.loads(table.schema.metadata[b"rotorfault"])
    assert meta["sensed"] == "mocap"
    assert meta["sensing_counts"]["imu_samples"] == e.counts.imu_samples == 0.5 * 500 + 1
    assert meta["sensing_counts"]["fused_measurements"] == e.counts.fused_measurements > 0
    path = tmp_path / "sensed.parquet"
    pq.write_table(table, path)
    back = pq.read_table(path)
    assert back.schema.equals(table.schema, check_metadata=True)
    assert back.equals(table)
    # A batch flown on sensing stacks each run's estimate columns with its run number.
    sim = rf.Simulator(QUAD, sensing=rf.Sensing(seed=1))
    lqr = rf.lqr_hover(rf.Simulator(QUAD), position=(0, 0, -10))
    batch = rf.simulate_batch(sim, [rf.State(position=(0.1 * i, 0, -10)) for i in range(2)], 0.2, controllers=lqr, record_every=10)
    stacked = batch.to_arrow()
    for k, one in enumerate(batch.trajectories):
        mine = stacked.filter(pa.compute.equal(stacked.column("run"), k)).drop(["run"])
        assert "estimate_north_m" in mine.column_names and mine.equals(one.to_arrow().replace_schema_metadata(None))
    plain = _flight().to_arrow()
    assert not any(c.startswith("estimate_") or c.endswith("_saturated") for c in plain.column_names)
    assert json.loads(plain.schema.metadata[b"rotorfault"])["sensed"] == "paper-noise"


def test_a_variable_pitch_flight_names_speed_and_pitch_commands() -> None:
    w = rf.vpp.preset()
    at = rf.vpp.trim(w, failed=(1,), speeds={3: 9000})
    run = w.simulator(failed=(1,)).run(rf.State(position=(0, 0, -10)), 0.05, controller=rf.vpp.lqr(w, at))
    names = run.to_arrow().column_names
    assert "rotor_2_speed_command" in names and "rotor_2_pitch_command_rad" in names and "rotor_2_thrust_n" in names


def test_streamed_scan_reads_back_as_the_scan_in_memory(tmp_path: Path) -> None:
    axes = {"efficiency_1": [0, 0.5, 1], "efficiency_2": [0, 0.5, 1], "max_thrust_n": [6.0, 7.0]}
    memory = rf.acai_scan(HEXA, axes, give_up_yaw=True)
    out = tmp_path / "scan.parquet"
    rf.acai_scan(HEXA, axes, give_up_yaw=True, out=out, chunk_points=5)
    schema = scan_schema(tuple(axes), ("eq13", "facet-margin"), True)
    direct = pq.read_table(out)  # any Parquet reader takes the directory
    assert direct.schema.remove_metadata().equals(schema)
    assert memory.to_arrow().schema.equals(schema)
    assert _equal_nan(direct, memory.to_arrow())
    back = rf.read_scan(out).to_arrow()
    assert back.schema.equals(memory.to_arrow().schema, check_metadata=True)
    assert _equal_nan(back, memory.to_arrow())


def test_streamed_campaign_reads_back_as_the_campaign_in_memory(tmp_path: Path) -> None:
    c = Campaign(runs=4, chunk_size=2, duration_s=3.0, failures=((1,),), fault_time_s=(1.0, 1.0))
    memory = run_campaign(c)
    out = tmp_path / "campaign.parquet"
    run_campaign(c, out=out)
    table = memory.to_arrow()
    assert table.num_rows == 4 and "max_altitude_loss_m" in table.column_names
    direct = pq.read_table(out)
    assert direct.schema.remove_metadata().equals(table.schema)
    assert _equal_nan(direct, table)
    back = read_campaign(out).to_arrow()
    assert back.schema.equals(table.schema, check_metadata=True) and _equal_nan(back, table)
    survival = memory.survival_table()
    assert survival[0]["by"] == "all" and survival[0]["runs"] == 4
    assert survival.to_arrow().column_names == ["by", "group", "held", "runs", "rate", "low", "high"]


def test_without_pandas_to_pandas_names_the_extra_and_arrow_still_works() -> None:
    result = run_without(("pandas",), """
        import json
        import rotorfault as rf
        table = rf.failure_table(rf.Airframe.preset("quad-x"), max_failed=1)
        rows = table.to_arrow().num_rows
        html = table._repr_html_().startswith("<table")
        try:
            table.to_pandas()
        except ImportError as exc:
            message = str(exc)
        else:
            message = None
        print(json.dumps({"rows": rows, "html": html, "message": message}))
    """)
    assert result["rows"] == 5 and result["html"]
    assert result["message"] == 'to_pandas() needs pandas, which is not installed: pip install "rotorfault[pandas]"'
