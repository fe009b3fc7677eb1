"""The hostile-input harness's targets: for every public callable of ``rotorfault`` and its rooms, a
strategy that draws a call (the function and hostile arguments) and a check of what it returns.

A call passes when it raises ``ValueError``/``TypeError``/``OSError`` whose message names a field
(``field: rule``, or the name of an argument or field the call was given) or returns a result that
passes its own consistency checks: no NaN anywhere, certificates that hold when the status says
so, sizes that match the request. Result types that users receive rather than build are covered
through the call that makes them (:data:`PRODUCED_BY`); a Protocol is implemented, not called
(:data:`NOT_CALLED`). ``test_hostile_api.py`` fails when a public callable is in none of these."""

from __future__ import annotations

import atexit
import functools
import math
import shutil
import tempfile
import unicodedata
from collections.abc import Callable
from dataclasses import dataclass, field, fields, is_dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from hostile_values import (
    EDGE_INTS,
    HOSTILE_NAMES,
    PRESETS,
    WRONG_TYPES,
    airframe_args,
    airframe_toml,
    airframes,
    upright_airframes,
    edge_float,
    efficiencies,
    hostile,
    names,
    number,
    positive,
    ring_fields,
    rotorpy_params,
    scenario_toml,
    vector,
)
from hypothesis import strategies as st

import rotorfault as rf
from rotorfault import allocation, analysis, control, flight, papers, studies

#: Words every field-naming message may use besides the call's own argument names.
FIELD_WORDS = frozenset({
    "airframe", "efficiency", "rotor", "rotors", "mass_kg", "inertia_kg_m2", "arm_length_m", "arm_angle_rad", "spin", "max_thrust_n",
    "min_thrust_n", "drag_torque_ratio_m", "gravity_m_s2", "position_m", "thrust_axis",
    "formula", "axes", "bounds", "weights", "state", "controller", "gains", "duration_s", "dt_s", "substeps", "runs", "campaign",
})


@dataclass
class Call:
    """One hostile call: ``fn(*args, **kwargs)``; ``words`` are the fields its refusal may name."""

    fn: Callable[..., Any]
    args: tuple[Any, ...] = ()
    kwargs: dict[str, Any] = field(default_factory=dict)
    words: frozenset[str] = frozenset()

    def __repr__(self) -> str:
        name = getattr(self.fn, "__qualname__", repr(self.fn))
        shown = [_short(a) for a in self.args] + [f"{k}={_short(v)}" for k, v in self.kwargs.items()]
        return f"{name}({', '.join(shown)})"


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 300 else text[:300] + "..."


@dataclass
class Target:
    """A public callable's strategy and the check of its result."""

    calls: st.SearchStrategy[Call]
    check: Callable[[Any, Call], None] = lambda result, call: no_nan(result)
    #: Regression cases: calls the harness found wrong (fixed since), made first in every run.
    examples: tuple[Call, ...] = ()


# --- consistency checks --------------------------------------------------------------------------


def no_nan(value: Any, where: str = "result", depth: int = 0, allow: frozenset[str] = frozenset()) -> None:
    """No NaN anywhere in a result (arrays, floats, dataclass fields, tuples, dicts); ``allow``
    names fields where NaN is documented (a time that never came)."""
    if depth > 6:
        return
    if isinstance(value, float):
        assert not math.isnan(value), f"{where} is NaN"
    elif isinstance(value, np.ndarray) and value.dtype.kind in "fc":
        assert not np.isnan(value).any(), f"{where} has NaN"
    elif isinstance(value, (list, tuple)):
        for i, item in enumerate(value[:50]):
            no_nan(item, f"{where}[{i}]", depth + 1, allow)
    elif isinstance(value, dict):
        for k, item in list(value.items())[:50]:
            if k not in allow:
                no_nan(item, f"{where}[{k!r}]", depth + 1, allow)
    elif is_dataclass(value) and not isinstance(value, type):
        # The library's dataclasses list their fields in FIELDS (dataclasses.fields is deprecated on them).
        names = getattr(type(value), "FIELDS", None) or [f.name for f in fields(value)]
        for key in names:
            if key not in allow:
                no_nan(getattr(value, key), f"{where}.{key}", depth + 1, allow)


def acai_value(value: float) -> None:
    assert isinstance(value, float) and not math.isnan(value) and value != math.inf, value


def check_acai_batch(result: Any, call: Call) -> None:
    values = np.asarray(getattr(result, "acai", result))
    assert not np.isnan(values).any() and not (values == np.inf).any()
    etas = np.asarray(call.args[1], dtype=float)
    assert values.shape == (etas.shape[0],)


def check_allocation(result: Any, call: Call) -> None:
    statuses = result.status if isinstance(result.status, tuple) else (result.status,)
    certificates = result.certificate if isinstance(result.certificate, tuple) else (result.certificate,)
    assert np.isfinite(result.commands).all(), result.commands
    for status, certificate in zip(statuses, certificates, strict=False):
        if status == "optimal":
            assert certificate.holds, (status, certificate)


def check_by_simulator(keyword: str) -> Callable[[Any, Call], None]:
    """A flight option's values are checked once, by the core, when a simulator is built with it
    (flight/models.py): the option must be accepted there or refused naming its field."""

    def check(result: Any, call: Call) -> None:
        frame = rf.Airframe.preset("wang-vpp" if keyword == "actuator" and isinstance(result, rf.VariablePitchActuator) else "quad-x")
        try:
            rf.Simulator(frame, **{keyword: result})
        except (ValueError, TypeError) as exc:
            from hostile_runner import names_a_field

            assert names_a_field(str(exc), call), f"Simulator({keyword}=...) refused it naming no field: {exc}"

    return check


def check_by_flight(result: Any, call: Call) -> None:
    """A rotor fault's values are checked by the core when a flight applies it (flight/faults.py):
    a short flight accepts it or refuses it naming the fault's field."""
    from hostile_runner import names_a_field

    simulator = rf.Simulator(rf.Airframe.preset("quad-x"), ground=False)
    try:
        simulator.run(rf.State(position=(0.0, 0.0, -10.0)), 0.05, faults=[result])
    except (ValueError, TypeError) as exc:
        assert names_a_field(str(exc), call) and "faults[0]" in str(exc), f"the flight refused it naming no field: {exc}"


def check_trim(result: Any, call: Call) -> None:
    assert np.isfinite(result.state).all() and np.isfinite(result.command).all() and math.isfinite(result.residual)


def check_lqr(result: Any, call: Call) -> None:
    design = result.design if hasattr(result, "design") else result
    gain = np.asarray(getattr(result, "gain", design.gain))
    assert np.isfinite(gain).all()
    eig = np.asarray(design.closed_loop_eigenvalues)
    assert (eig.real < 0).all() if not design.discrete else (abs(eig) < 1).all()


def check_batch(result: Any, call: Call) -> None:
    assert np.isfinite(result.t).all()
    for run in range(result.diverged.shape[0]):
        if not result.diverged[run]:
            assert np.isfinite(result.position[run]).all(), f"run {run}: position not finite but not diverged"


def check_scan(result: Any, call: Call) -> None:
    table = result.table
    assert table.num_rows == result.total
    for name in table.column_names:
        column = table.column(name).to_numpy(zero_copy_only=False)
        if column.dtype.kind == "f":
            assert not np.isnan(column).any(), name


def check_failure_table(result: Any, call: Call) -> None:
    m = call.args[0].rotor_count
    k = call.kwargs.get("max_failed", 1)
    assert len(result) == sum(math.comb(m, i) for i in range(0, k + 1))
    for value in result.to_arrays()["acai"]:
        acai_value(float(value))


#: A campaign row's columns that are NaN exactly where a value does not exist (docs/cli.md: null):
#: the loss times of a run never lost, the window values of a lost run (flight.outcomes), the
#: first fault time of a run whose pattern fails no rotor; the steady values of a run that never
#: settled.
_LOSS_COLUMNS = ("lost_at_s",)
_WINDOW_COLUMNS = ("window_horizontal_error_m", "window_altitude_error_m", "window_speed_m_s", "window_mean_horizontal_speed_m_s")
_UNSETTLED_COLUMNS = ("steady_spin_rad_s", "steady_n3z", "time_to_loss_s")


def check_campaign(result: Any, call: Call) -> None:
    campaign = call.args[0]
    columns = result.columns
    for name, column in columns.items():
        assert len(column) == campaign.runs, name
    lost = np.isin(columns["verdict"], ("crashed", "diverged"))
    no_fault = columns["failure_count"] == 0
    for name, column in columns.items():
        if column.dtype.kind != "f":
            continue
        missing = np.isnan(column)
        if name in _LOSS_COLUMNS:
            assert np.array_equal(missing, ~lost), (name, column, columns["verdict"])
        elif name in _WINDOW_COLUMNS:
            assert np.array_equal(missing, lost), (name, column, columns["verdict"])
        elif name == "first_fault_s":
            assert np.array_equal(missing, no_fault), (name, column, columns["failure_count"])
        elif name not in _UNSETTLED_COLUMNS:
            assert not missing.any(), name
        if name == "time_to_loss_s":
            assert missing[~lost].all(), (name, column, columns["verdict"])


# --- call strategies ---------------------------------------------------------------------------


def calls(fn: Callable[..., Any], *args: st.SearchStrategy[Any], **kwargs: st.SearchStrategy[Any]) -> st.SearchStrategy[Call]:
    """Calls of ``fn`` with positional and keyword arguments drawn from the strategies; each keyword
    is left out (its default used) one time in four."""
    optional = {k: st.one_of(v, v, v, st.just(_DEFAULT)) for k, v in kwargs.items()}

    def build(drawn: tuple[tuple[Any, ...], dict[str, Any]]) -> Call:
        positional, named = drawn
        named = {k: v for k, v in named.items() if v is not _DEFAULT}
        return Call(fn, tuple(positional), named, frozenset(kwargs))

    return st.tuples(st.tuples(*args), st.fixed_dictionaries(optional)).map(build)


_DEFAULT = object()


@st.composite
def with_airframe(draw: st.DrawFn, build: Callable[[st.DrawFn, rf.Airframe], Call]) -> Call:
    """A call that needs a valid airframe (drawn first) to size its other arguments."""
    return build(draw, draw(airframes()))


def formula() -> st.SearchStrategy[Any]:
    return hostile(st.sampled_from(("eq13", "facet-margin")), "eq14", "")


def valid_simulators() -> st.SearchStrategy[rf.Simulator]:
    return upright_airframes().map(rf.Simulator)


def states() -> st.SearchStrategy[Any]:
    return st.builds(
        rf.State,
        position=vector(3, hostile(number(-100, 100))),
        velocity=vector(3, hostile(number(-10, 10))),
        omega=vector(3, hostile(number(-5, 5))),
    )


def valid_states() -> st.SearchStrategy[rf.State]:
    return st.builds(rf.State, position=st.tuples(number(-5, 5), number(-5, 5), number(-20, -5)))


def hover(frame: rf.Airframe) -> list[float]:
    return [frame.mass_kg * frame.gravity_m_s2, 0.0, 0.0, 0.0]


def _allocate(draw: st.DrawFn, frame: rf.Airframe) -> Call:
    m = frame.rotor_count
    v = draw(vector(4, hostile(number(-50, 50), 1e300)))
    kwargs: dict[str, Any] = {}
    if draw(st.booleans()):
        kwargs["method"] = draw(hostile(st.sampled_from(allocation.METHODS), "simplex"))
    if draw(st.booleans()):
        kwargs["weights"] = draw(vector(m, hostile(positive(0.1, 10.0))))
    if draw(st.booleans()):
        kwargs["preferred"] = draw(vector(m, hostile(number(0.0, 5.0))))
    if draw(st.booleans()):
        kwargs["regularization"] = draw(hostile(positive(1e-9, 1.0)))
    if draw(st.booleans()):
        kwargs["priorities"] = draw(st.one_of(st.just([[0], [1, 2, 3]]), st.just([[0, 1, 2, 3]]), st.just([[5]]), st.just([[0], [0]]), st.just([])))
    if draw(st.booleans()):
        kwargs["max_iterations"] = draw(hostile(st.integers(1, 100), *EDGE_INTS))
    if draw(st.booleans()):
        kwargs["give_up_yaw"] = True
    return Call(rf.allocate, (frame, v), kwargs, frozenset(kwargs) | {"virtual_control", "target"})


def _scan_axes(draw: st.DrawFn, frame: rf.Airframe) -> Call:
    m = frame.rotor_count
    axes: dict[str, Any] = {}
    for r in draw(st.lists(st.integers(1, m + 1), min_size=1, max_size=3, unique=True)):
        axes[f"efficiency_{r}"] = draw(st.one_of(
            st.just(np.linspace(0, 1, 3)), vector(2, hostile(number(0.0, 1.0))),
        ))
    if draw(st.integers(0, 3)) == 0:
        # A huge grid, refused by its exact size before any work: 10**10 points in memory. (Valid
        # grids stay small: 10**8 points is a valid request of many minutes, not hostile input.)
        axes.update({f"efficiency_{r}": np.linspace(0, 1, 10**5) for r in (1, 2)})
    if draw(st.booleans()):
        name = draw(st.sampled_from(("mass_kg", "arm_length_m", "max_thrust_n", "drag_torque_ratio_m", "k_mu", "efficiency_1", "nonsense", "")))
        axes[name] = draw(vector(2, hostile(positive(0.05, 3.0))))
    kwargs: dict[str, Any] = {}
    if draw(st.booleans()):
        kwargs["chunk_points"] = draw(hostile(st.integers(1, 50), *EDGE_INTS))
    if draw(st.booleans()):
        kwargs["formulas"] = draw(st.one_of(st.just(("eq13",)), st.just(()), st.just(("x",)), st.just("eq13")))
    if draw(st.booleans()):
        kwargs["backend"] = draw(st.sampled_from(("local", "threads", "")))
    return Call(rf.acai_scan, (frame, axes), kwargs, frozenset(kwargs) | set(axes))


def _campaign_kwargs(draw: st.DrawFn) -> dict[str, Any]:
    kwargs: dict[str, Any] = {
        "runs": draw(hostile(st.integers(1, 3), *EDGE_INTS)),
        "duration_s": draw(hostile(number(0.5, 2.0), 1e9)),
        "fault_time_s": draw(st.one_of(st.just((0.2, 0.4)), st.tuples(hostile(number(0, 1)), hostile(number(0, 1))))),
        "gap_s": (0.2, 0.3),
    }
    if draw(st.booleans()):
        kwargs["substeps"] = draw(hostile(st.integers(1, 4), *EDGE_INTS))
    if draw(st.booleans()):
        kwargs["dt_s"] = draw(hostile(positive(1e-3, 5e-3)))
    if draw(st.booleans()):
        kwargs["mass_rel"] = draw(hostile(number(0.0, 0.3), 1.5))
    if draw(st.booleans()):
        kwargs["failures"] = draw(st.sampled_from((((1,),), ((1, 2),), ((9,),), ((),), ())))
    if draw(st.booleans()):
        kwargs["efficiency"] = draw(st.tuples(hostile(number(0, 1)), hostile(number(0, 1))))
    if draw(st.booleans()):
        kwargs["chunk_size"] = draw(hostile(st.integers(1, 3), *EDGE_INTS))
    if draw(st.booleans()):
        kwargs["controller"] = draw(st.sampled_from(("ke-hil", "indi", "lqr", "x")))
    return kwargs


def _campaign_call(draw: st.DrawFn) -> Call:
    kwargs = _campaign_kwargs(draw)
    return Call(studies.Campaign, (), kwargs, frozenset(kwargs) | {"fault_time_s", "gap_s", "failures"})


def _run_campaign(draw: st.DrawFn) -> Call:
    kwargs = _campaign_kwargs(draw)
    try:
        campaign = studies.Campaign(**kwargs)
    except (ValueError, TypeError):
        campaign = studies.Campaign(runs=2, duration_s=1.0, fault_time_s=(0.2, 0.4), gap_s=(0.2, 0.3))
    # A valid campaign of 10**9 runs is long work, not hostile input: flown ones stay small.
    campaign = replace(campaign, runs=min(campaign.runs, 3), duration_s=min(campaign.duration_s, 2.0))
    extra: dict[str, Any] = {}
    if draw(st.booleans()):
        extra["backend"] = draw(st.sampled_from(("local", "dask-ish", "")))
    return Call(studies.run_campaign, (campaign,), extra, frozenset(extra) | {"campaign"})


#: Every file and directory the harness makes, removed when the test process ends.
SCRATCH = Path(tempfile.mkdtemp(prefix="rotorfault-hostile-"))
atexit.register(shutil.rmtree, SCRATCH, ignore_errors=True)


def scratch_file(text: str | bytes, suffix: str) -> Path:
    handle = tempfile.NamedTemporaryFile("wb", suffix=suffix, delete=False, dir=SCRATCH)
    with handle:
        handle.write(text.encode("utf-8", "surrogatepass") if isinstance(text, str) else text)
    return Path(handle.name)


def file_calls(fn: Callable[..., Any], texts: st.SearchStrategy[str], suffix: str, **kwargs: st.SearchStrategy[Any]) -> st.SearchStrategy[Call]:
    """Calls of ``fn`` on a temporary file holding the drawn text (or on a missing file, a directory)."""
    paths = st.one_of(
        texts.map(lambda t: str(scratch_file(t, suffix))), texts.map(lambda t: str(scratch_file(t, suffix))),
        st.just("/nonexistent/x" + suffix), st.just(str(SCRATCH)),
    )
    return calls(fn, paths, **kwargs)


def _small_matrix(n: int, m: int) -> st.SearchStrategy[Any]:
    return st.one_of(
        st.lists(st.lists(hostile(number(-5, 5), wrong_types=False), min_size=m, max_size=m), min_size=n, max_size=n).map(np.array),
        st.just(np.zeros((n, m))), st.just(np.eye(n, m)), st.just(np.full((n, m), np.nan)), st.just(np.zeros((0, m))),
    )


def _plant() -> st.SearchStrategy[Any]:
    import control as ct

    @st.composite
    def build(draw: st.DrawFn) -> Any:
        n = draw(st.integers(1, 3))
        a = draw(_small_matrix(n, n))
        b = draw(_small_matrix(n, 1))
        c = draw(_small_matrix(1, n))
        try:
            return ct.ss(a, b, c, np.zeros((1, 1)))
        except Exception:
            return ct.ss(-np.eye(1), np.ones((1, 1)), np.ones((1, 1)), np.zeros((1, 1)))

    return st.one_of(build(), st.sampled_from(WRONG_TYPES))


def _first_order() -> Any:
    import control as ct

    return ct.ss(-np.eye(1), np.ones((1, 1)), np.ones((1, 1)), np.zeros((1, 1)))


def _barely_moved_unstable() -> Any:
    """An unstable mode the input barely moves (B = 1e-10): gamma_min 2.3e10, above the limit."""
    import control as ct

    return ct.ss(np.array([[1.0, 0.0], [0.0, -2.0]]), np.array([[1e-10], [1.0]]), np.array([[1.0, 1.0]]), np.zeros((1, 1)))


def _hidden_first_order() -> Any:
    """A stable mode nothing moves and nothing sees (B = C = 0)."""
    import control as ct

    return ct.ss(-np.eye(1), np.zeros((1, 1)), np.zeros((1, 1)), np.zeros((1, 1)))


def _lanzon_design() -> Any:
    return control.lanzon.design(control.lanzon.LanzonVehicle(), crossover_rad_s=30.0)


_LANZON: list[Any] = []


def lanzon_design() -> Any:
    if not _LANZON:
        _LANZON.append(_lanzon_design())
    return _LANZON[0]


def _paper_number() -> st.SearchStrategy[Call]:
    return calls(
        papers.PaperNumber, st.just("du"), st.just("Table 1"), st.just("ACAI"),
        hostile(number(-10, 10)), hostile(number(-10, 10)), hostile(positive(1e-6, 1.0)),
    )


def _acai_batch(draw: st.DrawFn, frame: rf.Airframe) -> Call:
    m = frame.rotor_count
    n = draw(st.sampled_from((0, 1, 5)))
    etas = draw(st.one_of(
        st.just(np.ones((n, m))), st.just(np.full((n, m), 0.5)), st.just(np.ones((n, m + 1))),
        st.lists(vector(m, hostile(number(0, 1), 2.0, wrong_types=False)), min_size=1, max_size=3),
    ))
    return Call(rf.acai_batch, (frame, etas), {"formula": draw(formula()), "with_hover": draw(st.booleans())}, frozenset({"efficiencies", "formula"}))


def _simulate(draw: st.DrawFn, frame: rf.Airframe) -> Call:
    frame = draw(upright_airframes())
    # Sometimes on sensors and the estimator (the sensors' loop checks for Ctrl-C on its own).
    sensing = draw(st.none() | st.builds(rf.Sensing, suite=st.sampled_from(("mocap", "gnss", "rtk")),
                                         imu_rate_hz=positive(100, 2000), seed=st.integers(0, 100)))
    sim = rf.Simulator(frame, ground=draw(st.booleans()), sensing=sensing)
    x0s = draw(st.lists(valid_states(), min_size=1, max_size=2))
    kwargs: dict[str, Any] = {}
    if draw(st.booleans()):
        kwargs["faults"] = [[rf.RotorFault(draw(st.integers(1, frame.rotor_count)), draw(number(0, 0.5)), draw(number(0, 1)))] for _ in x0s]
    if draw(st.booleans()):
        kwargs["record_every"] = draw(hostile(st.integers(1, 50), *EDGE_INTS))
    if draw(st.booleans()):
        kwargs["initial_command"] = draw(vector(frame.rotor_count, hostile(number(0, 5))))
    if draw(st.booleans()):
        kwargs["memory_budget_bytes"] = draw(hostile(st.integers(10**3, 10**8), *EDGE_INTS))
    if draw(st.booleans()):
        kwargs["dtype"] = draw(hostile(st.sampled_from(("float64", "float32")), "float16", "", "FLOAT32"))
    if draw(st.booleans()):
        kwargs["lanes"] = draw(hostile(st.sampled_from(("auto", "portable", "scalar")), "simd", "", "AUTO", 4))
        # Four runs or more make a group of SIMD lanes (equal fault times: one list for all).
        x0s = x0s + draw(st.lists(valid_states(), min_size=3, max_size=4))
        if "faults" in kwargs:
            kwargs["faults"] = [kwargs["faults"][0]] * len(x0s)
    duration = draw(hostile(number(0.0, 1.0), 1e9, 1e300))
    return Call(rf.simulate_batch, (sim, x0s, duration), kwargs, frozenset(kwargs) | {"duration_s", "x0s"})


_RECORDINGS = iter(range(10**9))


def _record_batch(draw: st.DrawFn, frame: rf.Airframe) -> Call:
    frame = draw(upright_airframes())
    sim = rf.Simulator(frame)
    x0s = draw(st.lists(valid_states(), min_size=0, max_size=2))
    fresh = SCRATCH / f"recording-{next(_RECORDINGS)}"
    kwargs: dict[str, Any] = {"out": draw(st.sampled_from((fresh, fresh, "/nonexistent/dir/runs", 3, None)))}
    if draw(st.booleans()):
        kwargs["record_every"] = draw(hostile(st.integers(1, 50), *EDGE_INTS))
    if draw(st.booleans()):
        kwargs["dtype"] = draw(hostile(st.sampled_from(("float64", "float32")), "float16", ""))
    if draw(st.booleans()):
        kwargs["chunk_runs"] = draw(hostile(st.integers(1, 3), *EDGE_INTS))
    duration = draw(hostile(number(0.0, 0.5), 1e9, 1e300))
    return Call(studies.record_batch, (sim, x0s, duration), kwargs, frozenset(kwargs) | {"duration_s", "x0s"})


def check_recording(result: Any, call: Call) -> None:
    import pyarrow.parquet as pq

    assert result.total_rows == len(call.args[1])
    if result.total_rows:
        table = pq.read_table(result.out)
        assert table.num_rows == result.total_rows
        assert np.isfinite(np.concatenate(table.column("t_s").to_numpy())).all()


def _linear_model() -> st.SearchStrategy[Call]:
    return calls(
        control.LinearModel, _small_matrix(12, 12), _small_matrix(12, 4),
        inputs=st.just(["T1", "T2", "T3", "T4"]), x_trim=vector(12, hostile(number(-1, 1))), u_trim=vector(4, hostile(number(0, 5))),
        command_columns=st.just([0, 1, 2, 3]), name=names(),
    )


def _targets() -> dict[str, Target]:
    t: dict[str, Target] = {}
    # analysis
    t["Airframe"] = Target(st.one_of(ring_fields(hostile_fields=True), ring_fields()).map(lambda f: Call(rf.Airframe, (), f, frozenset(f))), lambda r, c: _check_frame(r))
    t["acai"] = Target(with_airframe(lambda d, f: Call(rf.acai, (f,), {"efficiency": d(efficiencies(f.rotor_count)), "formula": d(formula()), "give_up_yaw": d(st.booleans())}, frozenset({"efficiency", "formula"}))), lambda r, c: acai_value(float(r)))
    t["acai_batch"] = Target(with_airframe(_acai_batch), check_acai_batch)
    t["acai_from_matrix"] = Target(calls(rf.acai_from_matrix, _small_matrix(4, 4), vector(4, hostile(number(0, 1))), vector(4, hostile(number(1, 10))), vector(4, hostile(number(-10, 10))), formula=formula()), lambda r, c: acai_value(float(r)))
    t["controllability"] = Target(with_airframe(lambda d, f: Call(rf.controllability, (f,), {"efficiency": d(efficiencies(f.rotor_count)), "formula": d(formula())}, frozenset({"efficiency", "formula"}))), lambda r, c: acai_value(r.acai))
    t["efficiency_scan"] = Target(with_airframe(lambda d, f: Call(rf.efficiency_scan, (f,), {"rotors": d(st.lists(hostile(st.integers(1, f.rotor_count), 0, 99), min_size=0, max_size=4)), "step": d(hostile(st.sampled_from((0.25, 0.5, 1.0)), 1e-9, 0.3)), "progress": False}, frozenset({"rotors", "step"}))))
    t["failure_table"] = Target(with_airframe(lambda d, f: Call(rf.failure_table, (f,), {"max_failed": d(hostile(st.integers(1, 2), *EDGE_INTS))}, frozenset({"max_failed"}))), check_failure_table)
    t["plot_efficiency_scan"] = Target(st.one_of(st.sampled_from(WRONG_TYPES), st.just("/nonexistent/scan")).map(lambda s: Call(rf.plot_efficiency_scan, (s,), {}, frozenset({"scan"}))))
    t["acai_label"] = Target(calls(analysis.acai_label, hostile(st.sampled_from(("eq13", "facet-margin")), "")), lambda r, c: None)
    t["format_acai"] = Target(calls(analysis.format_acai, hostile(number(-10, 10)), hover=st.sampled_from(("inside", "outside", "x", ""))), lambda r, c: None)
    # allocation
    t["allocate"] = Target(with_airframe(_allocate), check_allocation)
    t["Allocator"] = Target(with_airframe(lambda d, f: Call(rf.Allocator, (f,), {"regularization": d(hostile(positive(1e-9, 1.0))), "weights": d(vector(f.rotor_count, hostile(positive(0.1, 10.0))))}, frozenset({"regularization", "weights"}))), lambda r, c: None)
    t["hover_thrust_margin"] = Target(with_airframe(lambda d, f: Call(rf.hover_thrust_margin, (f,), {"efficiency": d(efficiencies(f.rotor_count)), "tolerance": d(hostile(positive(1e-12, 1e-6)))}, frozenset({"efficiency", "tolerance"}))))
    t["max_virtual_control"] = Target(with_airframe(lambda d, f: Call(rf.max_virtual_control, (f, d(vector(4, hostile(number(-1, 1))))), {"base": d(vector(4, hostile(number(-1, 20))))}, frozenset({"direction", "base"}))))
    t["attainable_slice"] = Target(with_airframe(lambda d, f: Call(allocation.attainable_slice, (f,), {"axes": d(st.sampled_from(((1, 2), (0, 3), (2, 2), (7, 1), (1,)))), "directions": d(hostile(st.integers(3, 40), *EDGE_INTS))}, frozenset({"axes", "directions"}))))
    t["plot_attainable_slices"] = Target(with_airframe(lambda d, f: Call(allocation.plot_attainable_slices, (f,), {"cases": d(st.one_of(st.none(), st.just({"x": [2.0] * f.rotor_count}), st.just({"\n": None}))), "axes": d(st.sampled_from(((1, 2), (0, 9))))}, frozenset({"cases", "axes", "efficiency"}))), lambda r, c: _close(r))
    # flight
    t["Simulator"] = Target(with_airframe(lambda d, f: Call(rf.Simulator, (f,), {"dt_s": d(hostile(positive(1e-4, 0.01))), "substeps": d(hostile(st.integers(1, 8), *EDGE_INTS)), "wind": d(vector(3, hostile(number(-10, 10)))), "ground_z_m": d(hostile(number(-1, 1)))}, frozenset({"dt_s", "substeps", "wind", "ground_z_m"}))), lambda r, c: None)
    t["simulate_batch"] = Target(with_airframe(_simulate), check_batch)  # flies an upright frame (the simulator's rule)
    t["State"] = Target(calls(rf.State, position=vector(3, hostile(number(-100, 100))), velocity=vector(3, hostile(number(-10, 10))), quaternion=st.one_of(st.none(), vector(4, hostile(number(-1, 1)))), omega=vector(3, hostile(number(-5, 5)))))
    t["RotorFault"] = Target(calls(rf.RotorFault, hostile(st.integers(1, 8), *EDGE_INTS), hostile(number(0, 10)), hostile(number(0, 1), 1.5, -0.1)), check_by_flight)
    t["Drag"] = Target(calls(rf.Drag, linear_n_s_m=hostile(positive(1e-3, 1)), quadratic_n_s2_m2=hostile(positive(1e-3, 1)), rotational_n_m_s=hostile(positive(1e-4, 1)), rotor_inertia_kg_m2=hostile(positive(1e-7, 1e-3))), check_by_simulator("drag"))
    t["Noise"] = Target(calls(rf.Noise, snr_db=hostile(number(-10, 60)), seed=hostile(st.integers(0, 100), *EDGE_INTS)), check_by_simulator("noise"))
    t["DivergenceLimits"] = Target(calls(rf.DivergenceLimits, max_tilt_rad=hostile(positive(0.1, 3.0)), max_altitude_loss_m=hostile(positive(0.1, 100)), max_speed_m_s=hostile(positive(1, 100)), max_rate_rad_s=hostile(positive(1, 100))), check_by_simulator("limits"))
    t["FixedPitchActuator"] = Target(calls(rf.FixedPitchActuator, time_constant_s=hostile(positive(1e-3, 0.1)), rate_limit_n_s=hostile(positive(1, 1000)), thrust_coefficient_n_s2=hostile(positive(1e-7, 1e-4))), check_by_simulator("actuator"))
    t["VariablePitchActuator"] = Target(calls(rf.VariablePitchActuator, k=st.tuples(*[hostile(number(-1, 1))] * 4), speed_bounds=st.tuples(hostile(number(0, 100)), hostile(number(100, 2000))), pitch_bounds=st.tuples(hostile(number(-0.5, 0)), hostile(number(0, 0.5))), speed_to_rad_s=hostile(positive(0.1, 10))), check_by_simulator("actuator"))
    t["OpenLoop"] = Target(with_airframe(lambda d, f: Call(rf.OpenLoop, (d(st.one_of(st.just([0.0, 1.0]), vector(2, hostile(number(0, 2))))), d(st.one_of(st.just([[1.0] * f.rotor_count] * 2), _small_matrix(2, f.rotor_count)))), {}, frozenset({"times", "commands"}))))
    t["hover_trim"] = Target(st.tuples(valid_simulators(), vector(3, hostile(number(-10, 0))), hostile(number(-3, 3))).map(lambda a: Call(rf.hover_trim, (a[0],), {"position": a[1], "yaw": a[2]}, frozenset({"position", "yaw"}))), check_trim)
    t["linearize"] = Target(st.tuples(valid_simulators(), st.booleans(), hostile(positive(1e-8, 1e-3))).map(lambda a: _linearize(*a)), lambda r, c: no_nan(r))
    t["lqr_hover"] = Target(st.tuples(valid_simulators(), st.one_of(st.none(), vector(12, hostile(positive(0.1, 10)))), st.one_of(st.none(), vector(4, hostile(positive(0.1, 10))))).map(lambda a: Call(rf.lqr_hover, (a[0],), {"q": a[1], "r": a[2]}, frozenset({"q", "r"}))), check_lqr)
    t["lqr_hover_allocated"] = Target(valid_simulators().map(lambda s: Call(rf.lqr_hover_allocated, (s, rf.Allocator(s.airframe)), {}, frozenset({"q", "r"}))), lambda r, c: None)
    t["LinearFeedback"] = Target(calls(rf.LinearFeedback, _small_matrix(4, 12), vector(12, hostile(number(-1, 1))), vector(4, hostile(number(0, 5)))))
    t["TrackingFeedback"] = Target(calls(rf.TrackingFeedback, _small_matrix(4, 12), vector(4, hostile(number(0, 5))), times_s=vector(2, hostile(number(0, 5))), references=_small_matrix(2, 12)))
    t["Lti"] = Target(calls(rf.Lti, _small_matrix(1, 1), _small_matrix(1, 12), _small_matrix(4, 1), _small_matrix(4, 12), vector(12, hostile(number(-1, 1))), vector(4, hostile(number(0, 5))), dt_s=hostile(positive(1e-3, 0.1))))
    t["Allocated"] = Target(st.sampled_from(("ke-quadcopter", "quad-x", "hexa-pnpnpn")).map(lambda p: rf.Simulator(rf.Airframe.preset(p))).map(lambda s: Call(rf.Allocated, (rf.lqr_hover(s), rf.Allocator(s.airframe)), {}, frozenset())), lambda r, c: None)
    t["UniformPassiveFtc"] = Target(st.tuples(airframe_args(), st.sampled_from(("ke-hil", "ke-experiment", "x", "")), st.sampled_from(("feedforward", "baseline", "literal", "x")), vector(3, hostile(number(-20, 0)))).map(lambda a: Call(rf.UniformPassiveFtc, (a[0],), {"gains": a[1], "law": a[2], "position": a[3]}, frozenset({"gains", "law", "position"}))), lambda r, c: None)
    t["IndiController"] = Target(st.tuples(airframe_args(), st.lists(st.tuples(hostile(st.integers(1, 6), 0, 99), hostile(number(0, 5))), max_size=2), vector(3, hostile(number(-20, 0)))).map(lambda a: Call(rf.IndiController, (a[0],), {"failures": a[1], "position": a[2]}, frozenset({"failures", "position"}))), lambda r, c: None)
    # The failure mode's keyword constructor (pickling's): hostile rotors, thrusts and axes.
    t["IndiFailureMode"] = Target(calls(
        control.indi.IndiFailureMode, failed=st.lists(hostile(st.integers(1, 4), 0, 99), max_size=2),
        healthy=st.lists(hostile(st.integers(1, 4), 0, 99), max_size=4), yaw_controlled=st.booleans(), single_axis=st.booleans(),
        output_direction=st.one_of(st.none(), vector(2, hostile(number(-1, 1)))), primary_axis=vector(3, hostile(number(-1, 1))),
        zero_dynamics_a=st.one_of(st.none(), hostile(number(-2, 2))), zero_dynamics_damping=st.one_of(st.none(), hostile(number(0, 2))),
        hover_thrust_n=vector(4, hostile(number(0, 5)))))
    t["IndiGains"] = Target(calls(rf.IndiGains, k_p_xy=hostile(positive(0.1, 5)), max_tilt_rad=hostile(positive(0.1, 1.5)), filter_frequency_rad_s=hostile(positive(1, 100))))
    t["KeGains"] = Target(calls(control.KeGains, k_p=hostile(positive(0.1, 5)), epsilon_s=hostile(positive(1e-3, 1)), weights=st.one_of(st.none(), vector(3, hostile(positive(0.1, 10))))))
    t["LanzonController"] = Target(st.tuples(vector(3, hostile(number(-5, 0))), st.one_of(st.none(), vector(3, hostile(number(-1, 1))))).map(lambda a: Call(rf.LanzonController, (lanzon_design(),), {"position": a[0], "attitude_reference": a[1]}, frozenset({"position", "attitude_reference"}))), lambda r, c: None)
    # Lanzon's vehicle is the core's class (issue 26): its defaults and checks are the core's.
    t["LanzonVehicle"] = Target(calls(control.lanzon.LanzonVehicle, mass_kg=hostile(positive(0.1, 2)), inertia_zz_kg_m2=hostile(positive(1e-3, 0.1)),
                                      rotor_inertia_kg_m2=hostile(positive(1e-6, 1e-3)), rate_limit_n_s=hostile(positive(1, 100))))
    t["lanzon_plant"] = Target(st.one_of(st.just(control.lanzon.LanzonVehicle()), st.sampled_from(WRONG_TYPES)).map(lambda v: Call(control.lanzon_plant, (v,), {}, frozenset({"vehicle"}))))
    t["ncfsyn"] = Target(st.tuples(_plant(), st.one_of(st.just(np.eye(1)), _small_matrix(1, 1)), hostile(positive(1.01, 2.0), 1.0)).map(lambda a: Call(rf.ncfsyn, (a[0], a[1]), {"factor": a[2]}, frozenset({"plant", "w1", "w2", "factor"}))), lambda r, c: _check_ncfsyn(r))
    t["design_lqr"] = Target(st.tuples(_plant(), st.one_of(st.none(), _small_matrix(1, 1)), hostile(positive(0.1, 10))).map(lambda a: _design_lqr(*a)), check_lqr)
    t["stabilisability"] = Target(calls(control.stabilisability, _small_matrix(2, 2), _small_matrix(2, 1), discrete=st.booleans()))
    t["detectability"] = Target(calls(control.detectability, _small_matrix(2, 2), _small_matrix(1, 2), discrete=st.booleans()))
    t["LinearModel"] = Target(_linear_model())
    # studies
    t["acai_scan"] = Target(with_airframe(_scan_axes), check_scan)
    t["read_scan"] = Target(file_calls(rf.read_scan, st.text(max_size=50), ".json"))
    t["read_campaign"] = Target(file_calls(studies.read_campaign, st.text(max_size=50), ".json"))
    t["failure_samples"] = Target(calls(rf.failure_samples, hostile(st.integers(1, 8), *EDGE_INTS), hostile(st.integers(0, 3), *EDGE_INTS)))
    t["design_search"] = Target(with_airframe(lambda d, f: Call(rf.design_search, (f,), {"parameter": d(st.sampled_from((None, "arm_length_m", "mass_kg", "x", "efficiency_1"))), "values": d(st.one_of(st.none(), vector(2, hostile(positive(0.1, 3.0)))))}, frozenset({"parameter", "values"}))))
    t["certify"] = Target(with_airframe(lambda d, f: Call(studies.certify, (f,), {"max_failed": d(hostile(st.integers(0, 2), *EDGE_INTS))}, frozenset({"max_failed"}))))
    # Valid calls have no vehicles (a full comparison flies minutes); the refusals name their field.
    t["certify_against_flights"] = Target(st.tuples(st.sampled_from(([], (), ["ke-quadcopter"], [None], "ke-quadcopter", 3)), hostile(st.integers(1, 2), *EDGE_INTS), st.sampled_from((None, [], ["pid"], ["linear-feedback"], "linear-feedback", 1))).map(lambda a: Call(studies.certify_against_flights, (a[0],), {"max_failed": a[1], "controllers": a[2]}, frozenset({"vehicles", "max_failed", "controllers"}))))
    t["Campaign"] = Target(st.composite(_campaign_call)())
    t["run_campaign"] = Target(st.composite(_run_campaign)(), check_campaign)
    t["record_batch"] = Target(with_airframe(_record_batch), check_recording)
    t["tuning_campaign"] = Target(calls(studies.tuning_campaign, runs=hostile(st.integers(1, 5), *EDGE_INTS), seed=hostile(st.integers(0, 9), *EDGE_INTS), duration_s=hostile(number(0.5, 2.0))))
    # Small counts or refused ones: maxiter=10**9 is a valid request for a very long search.
    t["tune"] = Target(st.tuples(hostile(st.integers(0, 1), -1, 2**63), hostile(st.integers(1, 2), 0, -1, 2**63), st.sampled_from((None, {"k_p": (0.5, 2.0)}, {"x": (0, 1)}, {"k_p": (2.0, 1.0)}))).map(_tune))
    t["load_scenario"] = Target(file_calls(studies.load_scenario, scenario_toml(), ".toml"))
    # papers
    # ``ours`` may be NaN (what a failed computation gave): it reads "differs", never "pass".
    t["PaperNumber"] = Target(_paper_number(), lambda r, c: (no_nan(r, allow=frozenset({"ours"})), _check_status(r)))
    t["number_rows"] = Target(_paper_number().map(lambda c: c.fn(*c.args, **c.kwargs) if _constructs(c) else None).map(lambda n: Call(papers.number_rows, ([n] if n is not None else [None],), {}, frozenset({"numbers"}))))
    # airframe files and conversions, through the class's own readers
    t["Airframe.from_toml_str"] = Target(airframe_toml().map(lambda s: Call(rf.Airframe.from_toml_str, (s,), {}, frozenset({"toml"}))), lambda r, c: _check_frame(r))
    t["Airframe.from_rotorpy"] = Target(rotorpy_params().map(lambda p: Call(rf.Airframe.from_rotorpy, (p,), {}, frozenset({"quad_params"}))), lambda r, c: _check_frame(r))
    t["Airframe.with_parameters"] = Target(with_airframe(lambda d, f: Call(f.with_parameters, (), {"mass_kg": d(hostile(positive(0.1, 5))), "arm_length_m": d(hostile(positive(0.05, 1))), "name": d(names())}, frozenset({"mass_kg", "arm_length_m", "name"}))), lambda r, c: _check_frame(r))
    t["Airframe.with_efficiency"] = Target(with_airframe(lambda d, f: Call(f.with_efficiency, (d(efficiencies(f.rotor_count)),), {}, frozenset({"efficiency"}))), lambda r, c: _check_frame(r))
    t["Airframe.to_px4_params"] = Target(with_airframe(lambda d, f: Call(f.to_px4_params, (), {"vehicle_id": d(hostile(st.integers(1, 255), *EDGE_INTS))}, frozenset({"vehicle_id"}))), _check_px4_text)
    _newer_targets(t)
    _regressions(t)
    return t


@functools.lru_cache(maxsize=1)
def _spinning() -> tuple[Any, rf.Airframe]:
    """A relaxed hover to build on: Ke's quadcopter without rotor 1, spinning (README)."""
    quad = rf.Airframe.preset("ke-quadcopter").with_failed_rotors([1])
    best = rf.relaxed_hover(quad, drag=rf.Drag(rotational_n_m_s=2.8e-3, linear_n_s_m=0.3)).best
    assert best is not None
    return best, quad


@functools.lru_cache(maxsize=1)
def _adjacent() -> tuple[Any, rf.Airframe]:
    """A relaxed hover that cannot be entered from hover: Ke's quadcopter without rotors 1 and 2."""
    quad = rf.Airframe.preset("ke-quadcopter").with_failed_rotors([1, 2])
    best = rf.relaxed_hover(quad, drag=rf.Drag(rotational_n_m_s=2.8e-3)).best
    assert best is not None
    return best, quad


def _check_entry(result: Any, call: Call) -> None:
    assert isinstance(result.reachable, bool)
    numbers = [result.tilt_limit_rad, result.spin_rate_needed_rad_s, result.spin_up_time_s, result.roll_to_yaw_ratio,
               result.tilt_before_spin_rad, result.spin_rate_at_tilt_limit_rad_s]
    assert not any(math.isnan(x) for x in numbers) and all(x >= 0 for x in numbers), result
    # "Not reachable" only with its proof: the tilt bound past the limit (or no yaw that way at all).
    assert result.reachable or result.tilt_before_spin_rad >= result.tilt_limit_rad or result.spin_up_time_s == math.inf, result


def _check_relaxed_hover(result: Any, call: Call) -> None:
    for solution in result.solutions:
        assert math.isfinite(solution.thrust_margin_n) and math.isfinite(solution.spin_rate_rad_s)
        assert np.isfinite(solution.thrust_n).all()


def _newer_targets(t: dict[str, Target]) -> None:
    """Targets of the API that landed with the relaxed hover, the sensors, the hold tuning and the
    hover-wrench distance (issues 28-30)."""
    t["Sensing"] = Target(calls(rf.Sensing, suite=hostile(st.sampled_from(("mocap", "gnss", "rtk")), "lidar", ""),
                                imu=hostile(st.sampled_from(("icm-42688-p", "mpu-6000")), "x"),
                                imu_rate_hz=hostile(positive(100, 2000)), position_rate_hz=hostile(positive(10, 240)),
                                gyro_range_rad_s=hostile(positive(10, 1000)),
                                seed=hostile(st.integers(0, 100), *EDGE_INTS)), check_by_simulator("sensing"))
    t["RelaxedHoverSettings"] = Target(calls(rf.RelaxedHoverSettings, rotational_drag_n_m_s=hostile(positive(1e-4, 1e-2)),
                                             max_spin_rate_rad_s=hostile(positive(10, 200)), grid_points=hostile(st.sampled_from((11, 13, 21)), *EDGE_INTS),
                                             max_idle_rotors=hostile(st.integers(0, 2), *EDGE_INTS)))
    t["relaxed_hover"] = Target(st.builds(
        lambda frame, failed, drag, grid: Call(rf.relaxed_hover, (frame.with_failed_rotors(failed) if failed else frame,),
                                               {"settings": rf.RelaxedHoverSettings(grid_points=grid, rotational_drag_n_m_s=drag)},
                                               frozenset({"settings", "rotational_drag_n_m_s", "grid_points"})),
        st.sampled_from([rf.Airframe.preset(n) for n in ("quad-x", "ke-quadcopter", "hexa-pnpnpn")]),
        st.sampled_from(((), (1,), (1, 3))), positive(1e-4, 1e-2), st.sampled_from((11, 13)),
    ) | calls(rf.relaxed_hover, airframes(), st.one_of(st.none(), st.just("x")), drag=st.one_of(st.none(), st.just(rf.Drag()), st.just(3.0))),
        _check_relaxed_hover)
    t["RelaxedHoverOuterLoop"] = Target(calls(control.RelaxedHoverOuterLoop, position_gain_s2=hostile(positive(0.1, 5)),
                                              velocity_gain_s=hostile(positive(0.1, 5)), max_tilt_rad=hostile(positive(0.05, 1.5)),
                                              integral_gain_s3=hostile(positive(0.01, 0.2)),
                                              altitude_integral_gain_s=hostile(positive(0.01, 1.0))), lambda r, c: None)
    t["RelaxedHoverFeedback"] = Target(st.builds(
        lambda position, drag: Call(lambda p, d: rf.RelaxedHoverFeedback(*_spinning(), position=p, linear_drag_n_s_m=d), (position, drag), {},
                                    frozenset({"position", "linear_drag_n_s_m"})),
        vector(3, hostile(number(-20, 0))), hostile(number(0.0, 1.0))), lambda r, c: None)
    t["entry_from_hover"] = Target(st.builds(
        lambda which, limit, drag: Call(lambda w, lim, d: analysis.entry_from_hover(*(_spinning() if w == "single" else _adjacent())[::-1],
                                                                                  tilt_limit_rad=lim, drag=d),
                                        (which, limit, drag), {}, frozenset({"tilt_limit_rad", "drag", "solution"})),
        st.sampled_from(("single", "adjacent")), hostile(positive(0.1, 3.1)),
        st.sampled_from((None, rf.Drag(rotational_n_m_s=2.8e-3), rf.Drag(rotor_inertia_kg_m2=1e-6), 3.0)))
        | calls(analysis.entry_from_hover, airframes(), st.sampled_from((None, "x", 1.0))), _check_entry)
    t["periodic_state"] = Target(st.builds(
        lambda position, yaw, drag: Call(lambda p, y, d: rf.periodic_state(*_spinning(), position=p, yaw=y, linear_drag_n_s_m=d),
                                         (position, yaw, drag), {}, frozenset({"position", "yaw", "linear_drag_n_s_m"})),
        vector(3, hostile(number(-20, 0))), hostile(number(-3.2, 3.2)), hostile(number(0.0, 1.0))),
        lambda r, c: no_nan(r.vector if hasattr(r, "vector") else r))
    t["hover_wrench_distance"] = Target(with_airframe(lambda d, f: Call(rf.hover_wrench_distance, (f,), {"efficiency": d(efficiencies(f.rotor_count)), "give_up_yaw": d(st.booleans())}, frozenset({"efficiency"}))),
                                        lambda r, c: None if (math.isfinite(r) and r >= 0) else (_ for _ in ()).throw(AssertionError(r)))
    t["hover_distances"] = Target(with_airframe(lambda d, f: Call(allocation.hover_distances, (f, d(st.sampled_from(([()], [(1,)], [(1, 2)], [(0,)], [(f.rotor_count + 1,)], "x")))), {}, frozenset({"failed"}))))
    t["hover_wrench_text"] = Target(calls(analysis.hover_wrench_text, hostile(st.sampled_from(("inside", "boundary", "outside", "rank-deficient")), "x", ""),
                                          st.one_of(st.none(), hostile(number(0.0, 10.0)))), lambda r, c: None)
    t["FaultCase"] = Target(calls(studies.FaultCase, st.sampled_from(((1,), (1, 3), (), (9,), (0,))), hostile(number(0, 1)),
                                  time_s=hostile(number(0.0, 10.0)), gap_s=hostile(number(0.0, 5.0))), lambda r, c: None)
    t["HoldCriteria"] = Target(calls(studies.HoldCriteria, hold_altitude_m=hostile(positive(0.1, 5)), hold_horizontal_m=hostile(positive(0.1, 10)),
                                     settle_s=hostile(number(0.0, 5.0))), lambda r, c: None)
    t["fault_set"] = Target(calls(studies.fault_set, st.sampled_from(((1, 2), (), (9,), (0,), "x")), st.sampled_from(((0.0, 0.5), (), (1.5,), (math.nan,))),
                                  time_s=hostile(number(0.0, 10.0))), lambda r, c: None)
    # Valid calls stay tiny (one fault, a 1 s flight, one generation of one candidate per gain):
    # a full tuning is long work, not hostile input.
    t["tune_hold"] = Target(st.builds(
        lambda cases, maxiter, popsize, duration: Call(studies.tune_hold, (cases,), {"maxiter": maxiter, "popsize": popsize, "duration_s": duration, "progress": False},
                                                        frozenset({"cases", "maxiter", "popsize", "duration_s"})),
        st.sampled_from(([studies.FaultCase((1,), 0.4, time_s=0.2)], [], "x")), hostile(st.integers(1, 1), *EDGE_INTS),
        hostile(st.integers(1, 1), *EDGE_INTS), hostile(positive(0.5, 1.0), 1e9)), lambda r, c: None)


def _seen_subnormally() -> Any:
    """Two integrators nothing moves, the second seen through 1e-310."""
    import control as ct

    return ct.ss(np.zeros((2, 2)), np.zeros((2, 1)), np.array([[1.0, 1e-310]]), np.zeros((1, 1)))


def _tiny_angle() -> rf.Airframe:
    return rf.Airframe([-1.1125369292536e-309, math.pi / 2, math.pi, 3 * math.pi / 2], [0.2] * 4, ["cw", "ccw", "cw", "ccw"], [8.0] * 4,
                       1.0, [0.01, 0.01, 0.02], 0.02)


def _scenario_with(extra: str) -> str:
    """Wang's scenario 1 (examples/) without its reference, plus ``extra`` TOML."""
    base = (Path(__file__).parents[3] / "examples" / "wang-scenario-1.toml").read_text()
    return base.split("[reference]")[0] + extra


def _by_position() -> rf.Airframe:
    """A hexacopter given by rotor positions (no arm lengths), rotor 1 on the x axis (y = 0)."""
    position = [[0.3 * math.cos(math.pi * i / 3), 0.3 * math.sin(math.pi * i / 3), 0.0] for i in range(6)]
    return rf.Airframe.from_rotors(position_m=position, spin=["ccw", "cw"] * 3, max_thrust_n=[8.0] * 6, mass_kg=1.0,
                                   inertia_kg_m2=[0.03, 0.03, 0.05], drag_torque_ratio_m=0.02, name="by-position")


def _regressions(t: dict[str, Target]) -> None:
    """The harness's findings, each fixed and kept here as an explicit case (issue 27)."""
    quad = rf.Airframe.preset("quad-x")
    quick = studies.Campaign(runs=2, duration_s=1.0, fault_time_s=(0.2, 0.4), gap_s=(0.2, 0.3))
    rotorpy = quad.to_rotorpy()
    found = {
        # A float count: TypeError from combinations() naming nothing; 10**6 rotors: C(n, 2) rows built in memory.
        "failure_samples": (Call(rf.failure_samples, (1, math.nan), {}, frozenset({"max_failed"})), Call(rf.failure_samples, (10**6, 2), {}, frozenset()),
                            Call(rf.failure_samples, (10**9, 10**9), {}, frozenset({"max_failed"}))),  # counted C(1e9, k) for every k
        "periodic_state": (Call(lambda: rf.periodic_state(*_spinning(), yaw=math.inf), (), {}, frozenset({"yaw"})),),  # math domain error
        "format_acai": (Call(analysis.format_acai, ("x",)),),  # float formatting's TypeError, no field
        "lanzon_plant": (Call(control.lanzon_plant, ("x",)),),  # AttributeError
        "plot_efficiency_scan": (Call(rf.plot_efficiency_scan, (None,)),),  # AttributeError
        # numpy's "could not convert string to float"; an empty plant reached LAPACK (dgges: lwork=0).
        "ncfsyn": (Call(rf.ncfsyn, ((1, "a"), np.eye(1)), {}, frozenset()), Call(rf.ncfsyn, ([], np.zeros((0, 1))), {}, frozenset()),
                   # Every state hidden (a zero weight; B = C = 0): LAPACK's bare "dgges: lwork=0".
                   Call(rf.ncfsyn, (_first_order(), np.zeros((1, 1))), {"factor": 1.01}, frozenset()),
                   Call(rf.ncfsyn, (_hidden_first_order(), np.eye(1)), {"factor": 1.01}, frozenset()),
                   # C = [1, 1e-310]: the balancing's ratio 0.5 / 1e-310 overflowed to inf, round(inf) (long run, 2026-11-28).
                   Call(lambda: rf.ncfsyn(_seen_subnormally(),
                                          np.eye(1), factor=1.01), (), {}, frozenset({"plant"})),
                   # gamma = 1e300 * gamma_min: gamma**2 raised a bare OverflowError (long run, 2026-11-28).
                   Call(rf.ncfsyn, (_first_order(), np.eye(1)), {"factor": 1e300}, frozenset({"factor"})),
                   # gamma_min 2.3e10 with a factor of 1e140: the refusal blamed factor, not the plant's gamma_min.
                   Call(rf.ncfsyn, (_barely_moved_unstable(), np.eye(1)), {"factor": 1e140}, frozenset({"gamma_min"}))),
        # An arm angle of 1e-309 rad left a subnormal in the effectiveness matrix, which the allocator
        # refused as "matrix[1, 0]" (a matrix the user never wrote; long run, 2026-11-28).
        "lqr_hover_allocated": (Call(lambda: rf.lqr_hover_allocated(rf.Simulator(_tiny_angle()), rf.Allocator(_tiny_angle())), (), {}, frozenset()),),
        # A string accepted as ``ours`` and ``tolerance``, failing later in number_rows' arithmetic.
        "number_rows": (Call(lambda: papers.number_rows([papers.PaperNumber("du", "Table 1", "ACAI", 0.0, "x", 1e-6)])),),  # type: ignore[arg-type]
        "PaperNumber": (Call(papers.PaperNumber, ("du", "Table 1", "ACAI", 0.0, 0.0, "x")),),
        "Noise": (Call(lambda: rf.Simulator(quad, noise=rf.Noise(snr_db=-1e300)), (), {}, frozenset({"snr_db"})),),  # OverflowError
        # ||Q|| of a 1e-310 weight underflowed to 0: ZeroDivisionError in the Riccati residual.
        "design_lqr": (Call(control.design_lqr, (_first_order(), np.array([[1e-310]]), np.eye(1) * 0.1), {}, frozenset({"q"})),
                       # r = 1e-310: an infinite gain, then NaN in the Riccati residual (a RuntimeWarning);
                       # refused as subnormal now; a plant of 1e300 by the control room's scale rule.
                       Call(control.design_lqr, (_first_order(), np.eye(1), np.array([[1e-310]])), {}, frozenset({"r"})),
                       Call(control.design_lqr, ((np.array([[1e300]]), np.eye(1)), np.eye(1), np.eye(1)), {}, frozenset({"plant A"})),
                       # Q / R = 1e301: a Newton step's X B K overflowed in the residual (a RuntimeWarning; long run, 2026-11-28).
                       Call(control.design_lqr, (_first_order(), np.array([[1e300]]), np.array([[0.1]])), {}, frozenset({"q", "r"}))),
        # Row norms of 1e300 entries overflowed (a RuntimeWarning, and the balancing zeroed the row).
        "detectability": (Call(control.detectability, (np.zeros((2, 2)), np.array([[0.0, 1e300]]))),
                          # The equilibration's cumulative factors overflowed next to a subnormal entry.
                          Call(control.detectability, (np.zeros((2, 2)), np.array([[1.0, 1e-310]]))),
                          # Balancing an A of 1e300 divided a row of C^T by 2^-1000: overflow (long run, 2026-11-28).
                          Call(control.detectability, (np.array([[0.0, 0.0], [1e300, 1.0]]), np.array([[0.0, 1e300]]))),
                          # A complex pencil column divided by its subnormal peak overflowed, and the
                          # subnormal entry (beyond the 2^+-1000 scaling) read as 0: not detectable (long run, 2026-11-28).
                          Call(control.detectability, (np.array([[0.0, 1.0], [-1.0, 0.0]]), np.array([[0.0, 1e-310]])), {}, frozenset({"c"}))),
        # scipy's matrix_balance warned (a cast of its unused permutation) on an entry of 1e-282.
        "stabilisability": (Call(control.stabilisability, (np.array([[0.0, 0.0], [1.0, 9.947778682040334e-282]]), np.zeros((2, 1)))),),
        # A tilted frame's rotors are given by position: arm_length_m = inf scaled 0 * inf (a warning) before the loader refused it (long run, 2026-11-28).
        "design_search": (Call(lambda: rf.design_search(_by_position(), parameter="arm_length_m", values=[math.inf]), (), {}, frozenset({"arm_length_m", "values"})),),
        # A circle of period 0 (ZeroDivisionError) or NaN radius (NaN reference rows), a fault of NaN
        # efficiency carried in the scenario until flown (long run, 2026-11-28).
        "load_scenario": tuple(Call(studies.load_scenario, (str(scratch_file(_scenario_with(extra), ".toml")),), {}, frozenset({word}))
                               for extra, word in (('[reference]\nkind = "circle"\nradius_m = 2.0\nperiod_s = 0.0\n', "period_s"),
                                                   ('[reference]\nkind = "circle"\nradius_m = nan\nperiod_s = 20.0\n', "radius_m"),
                                                   ("[[fault]]\nrotor = 1\ntime_s = 1.0\nefficiency = nan\n", "efficiency"))),
        "tuning_campaign": (Call(studies.tuning_campaign, (), {"runs": "x"}),),  # '>' between str and int

        "tune": (Call(studies.tune, (quick,), {"maxiter": "x"}), Call(studies.tune, (quick,), {"popsize": 0}), Call(studies.tune, (quick,), {"bounds": {}})),
        # python-control's unnamed ControlDimension for a b of 0 rows.
        "LinearModel": (Call(control.LinearModel, (np.zeros((12, 12)), np.zeros((0, 4))), {"inputs": ["a"] * 4, "x_trim": [], "u_trim": [], "command_columns": [0, 1, 2, 3], "name": ""}),
                        # u_trim without channels for the command columns: an IndexError (long run, 2026-11-28).
                        Call(control.LinearModel, (np.zeros((12, 12)), np.zeros((12, 4))), {"inputs": ["a"] * 4, "x_trim": [0.0] * 12, "u_trim": [],
                                                                                            "command_columns": [0, 1, 2, 3], "name": ""},
                             frozenset({"command_columns"}))),
        # float(None) naming nothing; 1e300 rad/s squared: OverflowError.
        # A string distance: '>' between str and float; a list as the hover: unhashable; NaN: KeyError.
        "hover_wrench_text": (Call(analysis.hover_wrench_text, ("outside", "x"), {}, frozenset({"distance"})),
                              Call(analysis.hover_wrench_text, (["x"],), {}, frozenset({"hover"})),
                              Call(analysis.hover_wrench_text, (math.nan,), {}, frozenset({"hover"}))),
        # pyo3's bare OverflowError converting -1 to an unsigned count.
        "RelaxedHoverSettings": (Call(rf.RelaxedHoverSettings, (), {"max_idle_rotors": -1}, frozenset({"max_idle_rotors"})),),
        # The check read NaN as wrong where the campaign documents it (null in docs/cli.md): the
        # first fault time of a pattern failing no rotor, the window values of a lost run. Now
        # each is NaN exactly there; 10**21 substeps reached pyo3 (OverflowError) from Campaign.
        "run_campaign": (Call(studies.run_campaign, (replace(quick, runs=1, failures=((1, 2),)),)),
                         Call(studies.run_campaign, (replace(quick, runs=1, failures=((),)),)),
                         # Timed out once in the long run (60 s of wall time at nice 10, load 24) and
                         # not on replay: the limit is on CPU time now (hostile_runner.py).
                         Call(studies.run_campaign, (replace(quick, failures=((1,), (2,), (3,), (4,))),)),
                         # (0.0, -0.0): NumPy's uniform() refused -0.0 - 0.0 mid-run, naming no field.
                         Call(studies.run_campaign, (replace(quick, runs=1, efficiency=(0.0, -0.0), fault_time_s=(0.0, -0.0)),))),
        "Campaign": (Call(studies.Campaign, (), {"substeps": 10**21}, frozenset({"substeps"})),),
        # int('x'): a ValueError naming nothing; rotor 0 accepted by FaultCase.
        "fault_set": (Call(studies.fault_set, ("x", (0.0, 0.5)), {}, frozenset()), Call(studies.fault_set, ((0,), (0.5,)), {}, frozenset())),
        # int('x') on the failed sets; an infinite duration reached scipy's map (RuntimeError).
        "hover_distances": (Call(allocation.hover_distances, (rf.Airframe.preset("hexa-pnpnpn"), "x"), {}, frozenset({"failed"})),),
        "tune_hold": (Call(studies.tune_hold, ([studies.FaultCase((1,), 0.4, time_s=0.2)],), {"maxiter": 1, "popsize": 1, "duration_s": math.inf, "progress": False},
                           frozenset({"duration_s"})),
                      # A finite duration past the simulator's step limit was refused only inside the search's
                      # threads, where scipy replaced the message with its own (long run, 2026-11-28).
                      Call(studies.tune_hold, ([studies.FaultCase((1,), 0.4, time_s=0.2, gap_s=2.0)],),
                           {"maxiter": 1, "popsize": 1, "duration_s": 1e300, "progress": False}, frozenset({"duration_s"}))),
        # A subnormal rate (an infinite sample period): building the simulator never returned and
        # grew to 20 GB in the long run; refused by name now (a scale, crates/rfcore/src/error.rs).
        "Sensing": (Call(rf.Sensing, (), {"position_rate_hz": 1e-310}, frozenset({"position_rate_hz"})),
                    Call(rf.Sensing, (), {"imu_rate_hz": 1e-310}, frozenset({"imu_rate_hz"}))),
        # An unassigned code point failed the check's isprintable() (the rule accepts it: which
        # code points are unassigned varies by install); a lone surrogate reached the TOML writer
        # (UnicodeEncodeError naming no field).
        "Airframe.with_parameters": (Call(quad.with_parameters, (), {"name": "\u0b45"}, frozenset({"name"})),
                                     Call(quad.with_parameters, (), {"name": "a\ud800b"}, frozenset({"name"}))),
        # Weights of 1e300 and a regularisation of 1e-9: scaled by the largest weight, the
        # regularisation was subnormal and the solver's construction panicked.
        "Allocator": (Call(rf.Allocator, (quad,), {"regularization": 1e-9, "weights": [10.0, 1e300, 1.0, 0.1]}, frozenset({"regularization", "weights"})),),
        # NumPy 2's norm overflowed its squares (a RuntimeWarning) on a quaternion entry of 1e300.
        "State": (Call(rf.State, (), {"quaternion": [0.0, 0.0, 0.0, 1e300]}, frozenset({"quaternion"})),),
        # 1 / 1e-310 overflowed to infinity (OverflowError naming nothing).
        "efficiency_scan": (Call(rf.efficiency_scan, (rf.Airframe.preset("hexa-pnpnpn"),), {"rotors": [1], "step": 1e-310, "progress": False}, frozenset({"step"})),),
        "Airframe.from_rotorpy": (Call(rf.Airframe.from_rotorpy, ({**rotorpy, "mass": None},)), Call(rf.Airframe.from_rotorpy, ({**rotorpy, "rotor_speed_max": 1e300},))),
    }
    for name, cases in found.items():
        t[name] = replace(t[name], examples=cases)


def _constructs(call: Call) -> bool:
    try:
        call.fn(*call.args, **call.kwargs)
    except (ValueError, TypeError):
        return False
    return True


def _linearize(sim: rf.Simulator, as_model: bool, step: float) -> Call:
    def linearize_at_hover(sim: rf.Simulator, step: Any) -> Any:
        return rf.linearize(sim, rf.hover_trim(sim), step=step)

    return Call(linearize_at_hover, (sim, step), {}, frozenset({"step", "trim"}))


def _design_lqr(plant: Any, q: Any, r: float) -> Call:
    n = getattr(plant, "nstates", 1)
    return Call(control.design_lqr, (plant, np.eye(n) if q is None else q, np.eye(1) * r if isinstance(r, float) else r), {}, frozenset({"plant", "q", "r"}))


def _tune(args: tuple[Any, Any, Any]) -> Call:
    maxiter, popsize, bounds = args
    campaign = studies.Campaign(runs=2, duration_s=1.0, fault_time_s=(0.2, 0.4), gap_s=(0.2, 0.3))
    return Call(studies.tune, (campaign,), {"maxiter": maxiter, "popsize": popsize, "bounds": bounds, "progress": False}, frozenset({"maxiter", "popsize", "bounds"}))


def _check_status(number: Any) -> None:
    assert number.status == ("pass" if math.isfinite(number.ours) and abs(number.ours - number.printed) <= number.tolerance else "differs")


def _check_frame(frame: rf.Airframe) -> None:
    assert math.isfinite(frame.mass_kg) and frame.mass_kg > 0
    assert np.isfinite(frame.wrench_matrix()).all() if callable(getattr(frame, "wrench_matrix", None)) else True
    # The name rule (analysis/airframe.py check_label): no control, format, separator or surrogate
    # character; unassigned code points are accepted (which are unassigned varies by install).
    assert not any(unicodedata.category(ch) in ("Cc", "Cf", "Cs", "Zl", "Zp") for ch in frame.name), repr(frame.name)


def _check_px4_text(text: str, call: Call) -> None:
    for line in text.splitlines():
        assert line == "" or line.startswith("#") or len(line.split("\t")) == 5, repr(line)


def _check_ncfsyn(result: Any) -> None:
    assert math.isfinite(result.gamma) and result.gamma >= result.gamma_min > 0


def _close(figure: Any) -> None:
    import matplotlib.pyplot as plt

    plt.close(figure)


#: Every target, by public name (``Class.method`` for the airframe's readers and conversions).
TARGETS: dict[str, Target] = _targets()

#: Result types users receive: covered through the call that makes them (its target's check).
PRODUCED_BY: dict[str, str] = {
    "Allocation": "allocate", "DirectionalLimit": "max_virtual_control", "HoverMargin": "hover_thrust_margin",
    "BatchResult": "simulate_batch", "Divergence": "simulate_batch", "Trajectory": "simulate_batch", "HoverTrim": "hover_trim",
    "ControllabilityReport": "controllability", "EfficiencyScan": "efficiency_scan", "FailureCase": "failure_table",
    "FailureTable": "failure_table", "Scan": "acai_scan", "Design": "design_search", "DesignSearch": "design_search",
    "AcaiBatch": "acai_batch", "AcaiValue": "acai", "Certificate": "certify", "CertificateCase": "certify",
    "CertifyAgreement": "certify_against_flights",
    "LqrDesign": "lqr_hover", "NcfsynResult": "ncfsyn", "PbhTest": "stabilisability", "CampaignResult": "run_campaign",
    "TuningResult": "tune", "Scenario": "load_scenario", "Estimates": "Sensing", "HoldTuningResult": "tune_hold",
    "RelaxedHoverAnalysis": "relaxed_hover", "RelaxedHoverSolution": "relaxed_hover", "EntryFromHover": "entry_from_hover",
}
#: Public callables not called: a Protocol is a type to implement.
NOT_CALLED: dict[str, str] = {"Controller": "a typing.Protocol: controllers implement it; it is not called"}

__all__ = ["FIELD_WORDS", "HOSTILE_NAMES", "NOT_CALLED", "PRESETS", "PRODUCED_BY", "TARGETS", "Call", "Target", "edge_float", "no_nan"]
