"""The attainable set of virtual controls: how far it reaches along a direction
(:func:`max_virtual_control`, a linear program solved by Clarabel), how much balanced thrust is
left (:func:`hover_thrust_margin`) and a 2-D slice through hover (:func:`attainable_slice`, with
its figure :func:`plot_attainable_slices`)."""

from __future__ import annotations

import numbers
from collections.abc import Iterable, Sequence
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from .. import _rfcore
from .._typing import ControlAxes
from .._util.convert import FloatArray, control_axes, flag, float_array, real, rotor_numbers
from .._util.numeric import scaled_norm
from ..analysis.airframe import Airframe, require_airframe
from .allocator import CLARABEL_TOLERANCE, Allocator

if TYPE_CHECKING:
    from matplotlib.figure import Figure


#: The largest ``scale`` with ``base + scale * direction`` attainable, the rotor ``commands``
#: (float array, N for thrust) that attain it and the linear program's ``status``
#: (:func:`max_virtual_control`): the core's result, used directly (issue 26: no Python copy).
DirectionalLimit = _rfcore.DirectionalLimit


def max_virtual_control(
    target: Airframe | npt.ArrayLike,
    direction: npt.ArrayLike,
    *,
    bounds: tuple[npt.ArrayLike, npt.ArrayLike] | None = None,
    base: npt.ArrayLike | None = None,
    give_up_yaw: bool = False,
    tolerance: float = CLARABEL_TOLERANCE,
) -> DirectionalLimit | None:
    """The attainable set along a direction: the largest ``s`` such that some bounded commands
    produce ``base + s * direction`` (``base`` zero by default). ``None`` when no point of that
    line is attainable; ``s`` is negative when ``base`` is not attainable but points behind it
    are. Solved as a linear program by Clarabel.

    Examples:

        >>> import rotorfault as rf
        >>> limit = rf.max_virtual_control(rf.Airframe.preset("quad-x"), [1, 0, 0, 0])
        >>> round(limit.scale, 3), limit.status
        (24.5, 'optimal')
    """
    allocator = Allocator(target, bounds=bounds, give_up_yaw=give_up_yaw)
    n = allocator.virtual_dimension
    d = float_array("direction", direction, 1)
    b = np.zeros(n) if base is None else float_array("base", base, 1)
    result = _rfcore.max_along_direction(
        allocator.matrix, allocator.lower, allocator.upper, d, b, real("tolerance", tolerance)
    )
    return result


#: :func:`hover_thrust_margin`: the largest total thrust with the controlled torques at zero
#: (``max_thrust_n``, N), the weight (``weight_n``, N), their difference (``margin_n``, N; negative:
#: cannot hover in balance) and ``thrust_to_weight``; ``commands`` (rotor thrusts, N) attain the
#: maximum, ``None`` (and ``-inf`` thrust) when zero torque is unattainable at any thrust. The
#: core's result, used directly (issue 26: no Python copy).
HoverMargin = _rfcore.HoverMargin


def hover_thrust_margin(
    airframe: Airframe,
    efficiency: npt.ArrayLike | None = None,
    *,
    give_up_yaw: bool = False,
    tolerance: float = CLARABEL_TOLERANCE,
    axes: ControlAxes | None = None,
) -> HoverMargin:
    """How much balanced thrust an airframe has left, with rotor ``efficiency`` (default the
    airframe's own) applied; ``give_up_yaw`` lets the yaw torque be anything (a spinning vehicle,
    Ke / Lanzon).

    Examples:

        >>> import rotorfault as rf
        >>> margin = rf.hover_thrust_margin(rf.Airframe.preset("quad-x"))
        >>> round(margin.max_thrust_n, 3), round(margin.weight_n, 3), round(margin.margin_n, 3)
        (24.5, 15.043, 9.457)
    """
    if not isinstance(airframe, Airframe):
        raise TypeError(f"airframe: expected an Airframe, got {type(airframe).__name__}")
    frame = airframe if efficiency is None else airframe.with_efficiency(efficiency)
    names = control_axes(give_up_yaw, axes)
    return _rfcore.hover_thrust_margin(frame._core, names, real("tolerance", tolerance))


def hover_wrench_distance(airframe: Airframe, efficiency: npt.ArrayLike | None = None, *, give_up_yaw: bool = False) -> float:
    """How far the hover wrench ``G = [m g, 0, 0(, 0)]`` lies from the attainable set, with rotor
    ``efficiency`` (default the airframe's own): the Euclidean distance in the ACAI's units (N on
    the thrust axis, N m on the torque axes, Du eq. (9)), ``0.0`` when hover is attainable (inside
    or on the boundary). It is the optimum of the allocation QP with unit weights (Ke eq. (33)),
    whose KKT certificate is checked; the facet margin (``formula="facet-margin"``) is a lower
    bound on it, equal when the nearest point lies inside one facet.

    Examples:

        >>> import rotorfault as rf
        >>> quad = rf.Airframe.preset("quad-x")
        >>> rf.hover_wrench_distance(quad), round(rf.hover_wrench_distance(quad, [0, 1, 1, 1]), 4)
        (0.0, 1.2132)
    """
    if not isinstance(airframe, Airframe):
        raise TypeError(f"airframe: expected an Airframe, got {type(airframe).__name__}")
    frame = airframe if efficiency is None else airframe.with_efficiency(efficiency)
    n = 3 if flag("give_up_yaw", give_up_yaw) else 4
    goal = np.zeros(n)
    goal[0] = frame.mass_kg * frame.gravity_m_s2
    from .allocator import allocate

    answer = allocate(frame, goal, weights=np.ones(n), give_up_yaw=give_up_yaw)
    certificate = answer.certificate
    assert not isinstance(certificate, tuple)  # one wrench, one certificate
    if not certificate.holds:
        raise ValueError(
            f"airframe: the distance of {frame.name}'s hover wrench to its attainable set could not be certified "
            f"(allocation status {answer.status}); report this case"
        )
    distance = scaled_norm(np.asarray(answer.achieved) - goal)
    # Attained up to the solver's rounding: within the certificate's tolerance of the wrench's size.
    return 0.0 if distance <= certificate.tolerance * max(1.0, float(goal[0])) else distance


def hover_distances(airframe: Airframe, failed: Iterable[Sequence[int]]) -> dict[tuple[int, ...], tuple[float, float]]:
    """:func:`hover_wrench_distance` with all four axes and giving up yaw, for each set of failed
    rotors (numbered from 1) of ``airframe``: what failure tables and certificates print beside
    "outside" (:func:`rotorfault.analysis.acai.hover_wrench_text`).

    Examples:

        >>> import rotorfault as rf
        >>> from rotorfault.allocation import hover_distances
        >>> distances = hover_distances(rf.Airframe.preset("quad-x"), [(1,)])
        >>> {failed: tuple(round(d, 4) for d in pair) for failed, pair in distances.items()}
        {(1,): (1.2132, 0.7406)}
    """
    airframe = require_airframe(airframe)
    if isinstance(failed, (str, bytes)) or not isinstance(failed, Iterable):
        raise TypeError(f"failed: expected a sequence of failed-rotor sets (numbered from 1), got {type(failed).__name__}")
    out = {}
    for k, rotors in enumerate(failed):
        # By name (int('x') was a ValueError naming nothing).
        key = rotor_numbers(f"failed[{k}]", rotors, airframe.rotor_count)
        frame = airframe.with_failed_rotors(list(key)) if key else airframe
        out[key] = (hover_wrench_distance(frame), hover_wrench_distance(frame, give_up_yaw=True))
    return out


AXIS_LABELS = ("thrust T (N)", "roll torque L (N m)", "pitch torque M (N m)", "yaw torque N (N m)")


def attainable_slice(
    airframe: Airframe,
    axes: tuple[int, int] = (1, 2),
    efficiency: npt.ArrayLike | None = None,
    *,
    give_up_yaw: bool = False,
    directions: int = 90,
) -> FloatArray | None:
    """The boundary of a 2-D slice of the attainable virtual-control set through hover: in the
    plane of ``axes`` (indices into thrust, roll, pitch, yaw), from the hover wrench ``[m g, 0, 0,
    0]``, the farthest attainable point along ``directions`` evenly spaced directions (one LP
    each). Returns a (directions, 2) array of boundary points, or ``None`` when hover itself is
    unattainable (:func:`hover_thrust_margin` negative). With ``give_up_yaw`` the yaw torque is
    free (and ``axes`` may not include 3).

    Examples:

        >>> import rotorfault as rf
        >>> from rotorfault.allocation import attainable_slice
        >>> boundary = attainable_slice(rf.Airframe.preset("quad-x"), directions=8)
        >>> boundary.shape
        (8, 2)
    """
    if not isinstance(airframe, Airframe):
        raise TypeError(f"airframe: expected an Airframe, got {type(airframe).__name__}")
    frame = airframe if efficiency is None else airframe.with_efficiency(efficiency)
    n = 3 if flag("give_up_yaw", give_up_yaw) else 4
    if (
        not isinstance(axes, (tuple, list))
        or len(axes) != 2
        or not all(isinstance(a, numbers.Integral) and not isinstance(a, bool) for a in axes)
    ):
        raise TypeError("axes: expected a pair of axis indices, e.g. (1, 2) for roll and pitch")
    axes = (int(axes[0]), int(axes[1]))
    if not all(0 <= a < n for a in axes) or axes[0] == axes[1]:
        raise ValueError(f"axes: two different indices in 0..{n - 1}, got {axes}")
    if not isinstance(directions, numbers.Integral) or isinstance(directions, bool):
        raise TypeError(f"directions: expected an integer, got {type(directions).__name__}")
    count = int(directions)
    if not 3 <= count <= 100_000:
        raise ValueError(f"directions: must be between 3 and 100000, got {count}")
    base = np.zeros(n)
    base[0] = frame.hover_thrust_n
    if hover_thrust_margin(frame, give_up_yaw=give_up_yaw).margin_n < 0:
        return None
    points = np.empty((count, 2))
    for k, angle in enumerate(np.linspace(0.0, 2 * np.pi, count, endpoint=False)):
        d = np.zeros(n)
        d[axes[0]], d[axes[1]] = np.cos(angle), np.sin(angle)
        limit = max_virtual_control(frame, d, base=base, give_up_yaw=give_up_yaw)
        if limit is None or limit.status == "failed":
            raise RuntimeError(f"attainable_slice: the LP along direction {k} failed although hover is attainable")
        points[k] = base[list(axes)] + max(limit.scale, 0.0) * d[list(axes)]
    return points


def plot_attainable_slices(
    airframe: Airframe,
    cases: dict[str, npt.ArrayLike | None] | None = None,
    *,
    axes: tuple[int, int] = (1, 2),
    give_up_yaw: bool = False,
    path: str | None = None,
) -> Figure:
    """Overlays :func:`attainable_slice` for several rotor-efficiency cases (``{label: efficiency}``,
    default: healthy and each single rotor failure) and returns the matplotlib figure, saved to
    ``path`` (``.png``, ``.pdf`` or ``.svg``, written atomically) if given; the figure is not
    registered with pyplot. A case whose hover is unattainable is listed in the legend as such.
    Cases differ in line style and marker as well as colour (readable in greyscale).

    Examples:

        >>> import matplotlib
        >>> matplotlib.use("Agg")
        >>> import rotorfault as rf
        >>> from rotorfault.allocation import plot_attainable_slices
        >>> figure = plot_attainable_slices(rf.Airframe.preset("quad-x"), {"healthy": None, "rotor 1 at 0.5": [0.5, 1, 1, 1]})
        >>> len(figure.axes)
        1
    """
    from ..plotting.attainable import plot_slices

    if cases is None:
        cases = {"healthy": None}
        for rotor in range(airframe.rotor_count):
            failed = np.ones(airframe.rotor_count)
            failed[rotor] = 0.0
            cases[f"rotor {rotor + 1} failed"] = failed
    slices = {label: attainable_slice(airframe, axes, efficiency, give_up_yaw=give_up_yaw) for label, efficiency in cases.items()}
    bold = [label for label, efficiency in cases.items() if efficiency is None]
    held = "yaw given up" if give_up_yaw else "other torques held at 0"
    return plot_slices(
        slices, (AXIS_LABELS[axes[0]], AXIS_LABELS[axes[1]]), title=f"{airframe.name}: attainable set at hover thrust ({held})",
        bold=bold, path=path,
    )

__all__ = [
    "AXIS_LABELS",
    "DirectionalLimit",
    "HoverMargin",
    "attainable_slice",
    "hover_distances",
    "hover_thrust_margin",
    "hover_wrench_distance",
    "max_virtual_control",
    "plot_attainable_slices",
]
