"""Hostile values for the hostile-input harness: numbers at and past every edge (NaN, infinities,
the subnormal 1e-310, 1e300, negative, zero), wrong types, names with control characters, sizes
that overflow, airframes (presets, rings, tilted 3-D frames, PX4 imports) and the files users
hand the tool (TOML airframes, scenarios and campaigns, PX4 .params, RotorPy parameters), each
well-formed, malformed or hostile.

Every strategy draws a valid value most of the time and a hostile one otherwise, so a call reaches
the work behind its checks as often as it hits the checks themselves."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np
from hypothesis import strategies as st

import rotorfault as rf

#: Numbers at the edges: every one of them is refused where the model divides by it.
EDGE_FLOATS: tuple[float, ...] = (
    math.nan, math.inf, -math.inf, 1e-310, -1e-310, 5e-324, 1e300, -1e300, 0.0, -0.0, -1.0, 1e-300, 1e30,
)
#: Values of the wrong type for any argument.
WRONG_TYPES: tuple[Any, ...] = ("x", None, [], {}, b"\x00", (1, "a"), "nan", object())
#: Names that try to carry more than a name: control characters, a newline with a live PX4 line.
HOSTILE_NAMES: tuple[str, ...] = (
    "", " ", "a\nparam set CBRK_IO_SAFETY 22027", "tab\there", "nul\x00", "esc\x1b[31m", "line\rfeed", "é" * 300,
    "x" * 10_000, "../../etc/passwd", '"quoted"', "[[rotor]]",
)
#: Integers at and past the edges of counts and sizes.
EDGE_INTS: tuple[int, ...] = (0, -1, 1, 2, 10**6, 10**9, 2**31, 2**63, 10**30, -(2**63))

#: The presets users start from.
PRESETS: tuple[str, ...] = tuple(rf.Airframe.presets())
#: The repository's own files: PX4 parameter files and examples.
TESTS = Path(__file__).resolve().parents[2]
PX4_FILES: tuple[Path, ...] = tuple(sorted((TESTS / "data").glob("*.params")))
EXAMPLES: tuple[Path, ...] = tuple(sorted((TESTS.parent / "examples").glob("*.toml")))


def edge_float() -> st.SearchStrategy[float]:
    return st.sampled_from(EDGE_FLOATS)


def hostile(valid: st.SearchStrategy[Any], *extra: Any, wrong_types: bool = True) -> st.SearchStrategy[Any]:
    """``valid`` three times in four; otherwise an edge number, a wrong type or one of ``extra``."""
    bad: list[st.SearchStrategy[Any]] = [edge_float()]
    if wrong_types:
        bad.append(st.sampled_from(WRONG_TYPES))
    if extra:
        bad.append(st.sampled_from(extra))
    return st.one_of(valid, valid, valid, *bad)


def positive(low: float, high: float) -> st.SearchStrategy[float]:
    """A valid positive number in [low, high], with its bounds and a log-uniform spread."""
    return st.one_of(
        st.sampled_from((low, high, math.sqrt(low * high))),
        st.floats(math.log10(low), math.log10(high)).map(lambda e: float(10.0**e)),
    )


def number(low: float, high: float) -> st.SearchStrategy[float]:
    """A valid number: finite and normal (subnormals are among the hostile values)."""
    return st.floats(low, high, allow_nan=False, allow_infinity=False, allow_subnormal=False)


def vector(n: int, element: st.SearchStrategy[Any]) -> st.SearchStrategy[Any]:
    """A list of ``n`` elements; sometimes one too few, one too many, empty or nested."""
    return st.one_of(
        st.lists(element, min_size=n, max_size=n),
        st.lists(element, min_size=n, max_size=n),
        st.lists(element, min_size=n, max_size=n),
        st.lists(element, min_size=0, max_size=n + 2),
        st.lists(element, min_size=n, max_size=n).map(lambda v: [v]),
    )


def efficiencies(m: int) -> st.SearchStrategy[Any]:
    return vector(m, hostile(number(0.0, 1.0), 1.5, -0.5, wrong_types=False))


def names() -> st.SearchStrategy[str]:
    return st.one_of(st.text(max_size=20), st.sampled_from(HOSTILE_NAMES))


# --- airframes ---------------------------------------------------------------------------------

SPINS = ("cw", "ccw")


@st.composite
def ring_fields(draw: st.DrawFn, hostile_fields: bool = False) -> dict[str, Any]:
    """The constructor arguments of a planar ring of 4 to 8 rotors; with ``hostile_fields`` one
    or two of them replaced by a hostile value."""
    m = draw(st.sampled_from((4, 6, 8)))
    angles = [2 * math.pi * i / m + draw(number(-0.2, 0.2)) for i in range(m)]
    fields: dict[str, Any] = {
        "arm_angle_rad": angles,
        "arm_length_m": [draw(positive(0.05, 1.0))] * m,
        "spin": [SPINS[(i + draw(st.integers(0, 1) if i > m - 3 else st.just(0))) % 2] for i in range(m)],
        "max_thrust_n": [draw(positive(2.0, 30.0))] * m,
        "mass_kg": draw(positive(0.2, 5.0)),
        "inertia_kg_m2": [draw(positive(0.005, 0.5)) for _ in range(3)],
        "drag_torque_ratio_m": draw(positive(0.005, 0.1)),
        "name": draw(st.sampled_from(("ring", f"ring-{m}"))),
    }
    if hostile_fields:
        for key in draw(st.lists(st.sampled_from(sorted(fields)), min_size=1, max_size=2, unique=True)):
            value = fields[key]
            if key == "name":
                fields[key] = draw(st.one_of(names(), st.sampled_from(WRONG_TYPES)))
            elif isinstance(value, list):
                fields[key] = draw(st.one_of(
                    vector(len(value), hostile(st.sampled_from(value))),
                    st.just([draw(edge_float())] + value[1:]),
                ))
            else:
                fields[key] = draw(hostile(st.just(value)))
        if draw(st.booleans()):
            fields["min_thrust_n"] = draw(vector(m, hostile(number(0.0, 1.0))))
        if draw(st.booleans()):
            fields["gravity_m_s2"] = draw(hostile(number(1.0, 20.0)))
    return fields


@st.composite
def tilted(draw: st.DrawFn) -> rf.Airframe:
    """A 3-D frame: rotors off the plane with tilted thrust axes (an omnicopter-like frame)."""
    m = draw(st.sampled_from((6, 8)))
    position = [[0.3 * math.cos(2 * math.pi * i / m), 0.3 * math.sin(2 * math.pi * i / m), draw(number(-0.1, 0.1))] for i in range(m)]
    tilt = draw(number(0.0, 0.6))
    axis = [[math.sin(tilt) * (-1) ** i, 0.0, -math.cos(tilt)] for i in range(m)]
    return rf.Airframe.from_rotors(
        position_m=position, spin=[SPINS[i % 2] for i in range(m)], max_thrust_n=[draw(positive(4.0, 15.0))] * m,
        mass_kg=draw(positive(0.5, 3.0)), inertia_kg_m2=[0.03, 0.03, 0.05], drag_torque_ratio_m=0.02, thrust_axis=axis, name="tilted",
    )


@st.composite
def airframes(draw: st.DrawFn) -> rf.Airframe:
    """A valid airframe: a preset, a ring, a tilted 3-D frame or a PX4 import."""
    kind = draw(st.sampled_from(("preset", "preset", "ring", "tilted", "px4")))
    if kind == "preset":
        return rf.Airframe.preset(draw(st.sampled_from(PRESETS)))
    if kind == "ring":
        return rf.Airframe(**draw(ring_fields()))
    if kind == "tilted":
        return draw(tilted())
    return rf.Airframe.load(str(draw(st.sampled_from(PX4_FILES))), mass_kg=draw(positive(0.5, 3.0)))


@st.composite
def upright_airframes(draw: st.DrawFn) -> rf.Airframe:
    """A valid airframe the simulator flies (upright rotors): a preset, a ring or a PX4 import."""
    kind = draw(st.sampled_from(("preset", "preset", "ring", "px4")))
    if kind == "preset":
        return rf.Airframe.preset(draw(st.sampled_from(PRESETS)))
    if kind == "ring":
        return rf.Airframe(**draw(ring_fields()))
    return rf.Airframe.load(str(draw(st.sampled_from(PX4_FILES))), mass_kg=draw(positive(0.5, 3.0)))


def airframe_args() -> st.SearchStrategy[Any]:
    """An airframe argument: a valid airframe, or sometimes something that is not one."""
    return st.one_of(airframes(), airframes(), airframes(), st.sampled_from(WRONG_TYPES))


# --- files -------------------------------------------------------------------------------------


def toml_value(value: Any) -> str:
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n").replace("\x00", "\\u0000") + '"'
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        if math.isnan(value):
            return "nan"
        if math.isinf(value):
            return "inf" if value > 0 else "-inf"
        return repr(value)
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(toml_value(v) for v in value) + "]"
    if value is None or isinstance(value, (dict, bytes, object)) and not isinstance(value, (int, float)):
        return '"?"'
    return repr(value)


@st.composite
def airframe_toml(draw: st.DrawFn) -> str:
    """An airframe TOML: a preset's text, mutated or not; a ring's fields with hostile values;
    deep nesting; text that is not TOML."""
    kind = draw(st.sampled_from(("preset", "mutated", "deep", "garbage", "fields")))
    if kind in ("preset", "mutated"):
        text = rf.Airframe.preset(draw(st.sampled_from(PRESETS))).to_toml()
        if kind == "mutated":
            lines = text.splitlines()
            i = draw(st.integers(0, len(lines) - 1))
            key, sep, _ = lines[i].partition(" = ")
            if sep:
                lines[i] = f"{key} = {toml_value(draw(hostile(st.just(1.0), *HOSTILE_NAMES[:3])))}"
            else:
                lines.insert(i, draw(st.sampled_from(("[[rotor]]", "[rotor]", "x = ", "= 1", "\x00"))))
            text = "\n".join(lines)
        return text
    if kind == "deep":
        depth = draw(st.sampled_from((100, 1000, 5000)))
        return "a = " + "[" * depth + "]" * depth + "\n" if draw(st.booleans()) else "".join(f"[{'t.' * depth}x]\n")
    if kind == "garbage":
        return draw(st.text(max_size=200))
    fields = draw(ring_fields(hostile_fields=True))
    head = [f"{k} = {toml_value(v)}" for k, v in fields.items() if k in ("name", "mass_kg", "inertia_kg_m2", "drag_torque_ratio_m")]
    rotors = []
    count = len(fields["arm_angle_rad"]) if isinstance(fields["arm_angle_rad"], list) else 4
    for i in range(count):
        def pick(key: str, i: int = i) -> Any:
            v = fields[key]
            return v[i] if isinstance(v, list) and i < len(v) else v
        rotors.append(
            "[[rotor]]\n" + "\n".join(f"{k} = {toml_value(pick(k))}" for k in ("arm_angle_rad", "arm_length_m", "spin", "max_thrust_n"))
        )
    return "\n".join(head) + "\n\n" + "\n\n".join(rotors) + "\n"


@st.composite
def px4_params(draw: st.DrawFn) -> str:
    """A PX4 parameter file: one of ours, with a line changed, dropped or added (unknown names,
    hostile values, control characters), or text that is not one."""
    text = draw(st.sampled_from(PX4_FILES)).read_text()
    lines = text.splitlines()
    action = draw(st.sampled_from(("keep", "value", "drop", "add", "garbage")))
    if action == "garbage":
        return draw(st.text(max_size=300))
    i = draw(st.integers(0, len(lines) - 1))
    if action == "value":
        parts = lines[i].split("\t")
        if len(parts) >= 4:
            parts[3] = draw(st.sampled_from(("nan", "inf", "1e-310", "1e300", "-1", "", "x", "0", "99999999999999999999")))
            lines[i] = "\t".join(parts)
    elif action == "drop":
        del lines[i]
    elif action == "add":
        lines.insert(i, "\t".join(("1", "1", draw(st.sampled_from(("CA_ROTOR0_PX", "CA_ROTOR_COUNT", "CBRK_IO_SAFETY", "X\nY", "CA_ROTOR99_KM"))), draw(st.sampled_from(("1", "nan", "1e300", "-5", "200"))), "9")))
    return "\n".join(lines) + "\n"


@st.composite
def rotorpy_params(draw: st.DrawFn) -> Any:
    """A RotorPy ``quad_params`` dictionary: an airframe's own, with one entry hostile, missing or
    of the wrong type; or not a dictionary."""
    if draw(st.integers(0, 7)) == 0:
        return draw(st.sampled_from(WRONG_TYPES))
    frame = draw(airframes())
    try:
        params = dict(frame.to_rotorpy())
    except ValueError:  # a frame RotorPy cannot hold (tilted, unequal rotors): refused by name
        params = dict(rf.Airframe.preset("quad-x").to_rotorpy())
    key = draw(st.sampled_from(sorted(params)))
    action = draw(st.sampled_from(("keep", "value", "drop", "type")))
    if action == "value":
        value = params[key]
        params[key] = draw(edge_float()) if not isinstance(value, (list, np.ndarray)) else [draw(edge_float())] * len(value)
    elif action == "drop":
        del params[key]
    elif action == "type":
        params[key] = draw(st.sampled_from(WRONG_TYPES))
    return params


@st.composite
def scenario_toml(draw: st.DrawFn) -> str:
    """A scenario file: one of the examples, with a line changed to a hostile value, dropped, a
    table nested deeply; or garbage."""
    text = draw(st.sampled_from(EXAMPLES)).read_text()
    lines = text.splitlines()
    action = draw(st.sampled_from(("keep", "value", "value", "drop", "deep", "garbage")))
    if action == "garbage":
        return draw(st.text(max_size=200))
    if action == "deep":
        return text + "\nz = " + "[" * 3000 + "]" * 3000 + "\n"
    candidates = [i for i, line in enumerate(lines) if " = " in line and not line.lstrip().startswith("#")]
    if not candidates:
        return text
    i = draw(st.sampled_from(candidates))
    if action == "drop":
        del lines[i]
    else:
        key = lines[i].partition(" = ")[0]
        lines[i] = f"{key} = {toml_value(draw(hostile(st.just(1.0), *HOSTILE_NAMES[:3], 10**30, -5)))}"
    return "\n".join(lines) + "\n"
