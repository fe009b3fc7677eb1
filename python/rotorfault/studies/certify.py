"""A controllability certificate for a real vehicle: for every single and double rotor failure,
can it still hover with all axes, only by giving up yaw, or not at all (``rotorfault certify``),
where the hover wrench lies (inside, on the boundary, outside and how far), and whether the
required axes remain (``--require-axes``; default all four: thrust, roll, pitch, yaw);
and, asked for (``spinning=True``), beside that static verdict, whether it survives by spinning:
the best relaxed hover (Mueller and D'Andrea, :func:`rotorfault.analysis.relaxed_hover`) with its
thrust margin, spin rate and the rotors that carry it, and whether that spin can be entered from
hover after the failure (:func:`rotorfault.analysis.entry_from_hover`: an obstruction proving that
the tilt passes 90 degrees before the spin is reached; where it holds, certify says "spinning
solution exists, not reachable from hover" and the case is not survivable).

The JSON certificate names the hover classes ``all-axes``, ``give-up-yaw`` and ``no`` and the
ACAI fields ``acai`` and ``acai_give_up_yaw`` (the facet margin, labelled ``ACAI facet-margin``
wherever printed); before issue 26 they read ``without-yaw`` and ``acai_without_yaw``. The same
case reads the same in ``rotorfault failures`` and the report: the hover wrench columns come from
one function (:func:`rotorfault.analysis.hover_wrench_text`) and one distance
(:func:`rotorfault.allocation.hover_wrench_distance`).

"On the boundary" (an ACAI of exactly 0: a static hover with no margin at all, e.g. hexa-pnpnpn
with any rotor failed) is reported apart from "outside" (no static hover: the distance of the
hover wrench to the attainable set). Neither keeps all four axes: a vehicle there survives only
by giving up yaw (spinning), which ``--require-axes thrust,roll,pitch`` allows and the default
does not.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field, fields
from typing import Any, ClassVar, Literal, get_args

from .._typing import AcaiFormula, CertifiedAxis, HoverPoint
from .._util.convert import count
from .._util.core_result import FieldsResult
from .._util.deprecation import renamed_attribute
from .._util.tables import Column, Tabular
from ..allocation.attainable import hover_distances, hover_thrust_margin
from ..analysis.airframe import Airframe, require_airframe, rotor_labels
from ..analysis.acai import GIVE_UP_YAW, acai_label, hover_wrench_text
from ..analysis.controllability import FailureCase, failure_table
from ..analysis.relaxed_hover import RelaxedHoverSettings, RelaxedHoverSolution, relaxed_hover
from ..analysis.relaxed_hover import _vehicle_settings as vehicle_settings
from ..analysis.spin_entry import EntryFromHover, entry_from_hover
from ..flight.models import Drag, FixedPitchActuator

#: ``all-axes``: hovers with thrust, roll, pitch and yaw; ``give-up-yaw``: only by giving up yaw
#: (spinning); ``no``: cannot hover.
Hover = Literal["all-axes", "give-up-yaw", "no"]
FAILURE_CLASSES = {"none": 0, "single": 1, "double": 2}
#: The ACAI a certificate reports: the facet margin (how far outside, where hover is infeasible).
FORMULA: AcaiFormula = "facet-margin"
#: The axes a certificate can require to remain: all four (the default) ...
ALL_AXES: tuple[CertifiedAxis, ...] = get_args(CertifiedAxis)
#: ... or thrust, roll and pitch (giving up yaw: the vehicle may spin).
GIVE_UP_YAW_AXES: tuple[CertifiedAxis, ...] = ("thrust", "roll", "pitch")


def parse_axes(field: str, value: str | tuple[str, ...] | list[str]) -> tuple[CertifiedAxis, ...]:
    """The axes a certificate must keep, from ``"thrust,roll,pitch"`` or a sequence of names:
    all four, or thrust, roll and pitch (the two questions rotorfault answers: Du's test with four
    axes or with three). Anything else is a ``ValueError`` naming ``field`` and the rule."""
    names = [p.strip() for p in value.split(",")] if isinstance(value, str) else [str(p).strip() for p in value]
    unknown = [n for n in names if n not in ALL_AXES]
    if unknown:
        raise ValueError(f"{field}: unknown axis {', '.join(map(repr, unknown))}; axes are {', '.join(ALL_AXES)}")
    chosen = set(names)
    if chosen == set(ALL_AXES):
        return ALL_AXES
    if chosen == set(GIVE_UP_YAW_AXES):
        return GIVE_UP_YAW_AXES
    raise ValueError(
        f"{field}: a certificate requires thrust, roll, pitch and yaw, or thrust, roll and pitch (giving up yaw); "
        f"got {', '.join(names) or 'none'}"
    )


#: The version of certify's survival rule (:func:`survives`), recorded with stored verdicts (a
#: deciding campaign's dataset: :func:`rotorfault.studies.deciding.read_deciding` warns about
#: verdicts of another rule). 1: a spinning relaxed hover a linear feedback holds, entered from
#: hover; 2: only a steady one (without rotational damping, not at the search's spin-rate limit);
#: 3: without rotational damping, not within :data:`SPIN_RATE_LIMIT_MARGIN` of that limit either;
#: 4: without rotational damping a best spin at (or within :data:`SPIN_RATE_LIMIT_MARGIN` of) the
#: limit is searched again with the limit lowered to :data:`FREE_SPIN_RATE_LIMIT_SHARE` of it, and a
#: spinning solution found there is the verdict (steady: ``spin_rate_free``); rule 3's premise (a
#: best spin at the limit is no equilibrium) was refuted by the deciding campaign (101 PX4 x500
#: draws certified not survivable under rule 3, best spins 192.96-200 rad/s, held by INDI at 4-43
#: rad/s, median 19).
SURVIVAL_RULE = 4
#: Without rotational damping a spin within this share of the search's spin-rate limit counts as
#: at the limit (not steady). Why: there the thrust margin still grows with the rate but is flat
#: to 1e-4 N over the last percent, so the search's optimum over the spin axis stops short of the
#: limit. Measured on the deciding campaign's PX4 x500 draws (seed 0): best spins at 192.96 to
#: 199.99 rad/s of a 200 rad/s limit moved to the new limit (or past 250 rad/s) when the search
#: was repeated with 400 and 800 rad/s; the interior spins found (150-172 rad/s) stayed. 5 %
#: covers the 3.5 % shortfall measured.
SPIN_RATE_LIMIT_MARGIN = 0.05
#: Rule 4: without rotational damping (``k_r = 0``) the yaw balance of a relaxed hover is ``n .
#: tau(f) = 0`` at any rate, so its solutions form a family parameterised by the spin rate whose
#: thrust margin grows with the rate; the search returns the member at its limit, but the slower
#: members are equilibria too, which a spin-rate loop holds. When the best spin is at (or near) the
#: limit, the search is repeated with the limit lowered to this share of it (a quarter: 50 rad/s of
#: the default 200 rad/s, above the 4-43 rad/s INDI flew the PX4 x500's one-rotor draws at and far
#: below the simulator's 200 rad/s body-rate limit), and a spinning solution found there is the
#: verdict: a member of the family taken from below the limit.
FREE_SPIN_RATE_LIMIT_SHARE = 0.25


#: ``static``: the best relaxed hover is static hover; ``spinning``: a constant spin about a
#: body-fixed axis; ``no``: no relaxed hover that a linear feedback can hold.
SpinningHover = Literal["static", "spinning", "no"]


@dataclass(frozen=True)
class RelaxedHoverVerdict:
    """The best relaxed hover of one failure case (the one with the most thrust margin among those
    a linear feedback can hold): ``hover`` (:data:`SpinningHover`), ``spin_rate_rad_s`` (0 when
    static), ``thrust_margin_n`` (headroom: the smallest distance of a carrying rotor's thrust to
    its upper bound), ``carrying`` (1-based rotor numbers), ``at_spin_rate_limit`` (the margin still
    grew at the searched limit: with no rotational damping a faster spin always helps). For
    ``no`` the numbers are NaN and ``carrying`` is empty. ``solution``: the relaxed hover itself
    (:class:`rotorfault.analysis.relaxed_hover.RelaxedHoverSolution`, with its linear model: what
    a feedback about it is designed on, so the search is not run twice; ``None`` for ``no``); not
    compared, not in :meth:`Certificate.to_dict` (the numbers above say it). ``entry_from_hover``:
    for a spinning solution, whether it can be entered from hover after the failure, with the
    numbers that decide it (:class:`rotorfault.analysis.EntryFromHover`; ``None`` otherwise)."""

    hover: SpinningHover
    spin_rate_rad_s: float
    thrust_margin_n: float
    carrying: tuple[int, ...]
    at_spin_rate_limit: bool
    solution: RelaxedHoverSolution | None = field(default=None, compare=False, repr=False)
    entry_from_hover: EntryFromHover | None = None
    #: The vehicle has rotational damping (``k_r > 0``): the yaw balance ``n . tau = k_r s``
    #: pins the spin rate (without it, nothing does).
    damped: bool = True
    #: The spin is within :data:`SPIN_RATE_LIMIT_MARGIN` of the search's spin-rate limit (where
    #: the search's optimum stops short of a limit it is heading for).
    near_spin_rate_limit: bool = False
    #: Rule 4: no rotational damping, so the spin rate is free (``n . tau(f) = 0`` at any rate);
    #: the best spin of the full search was at (or near) its limit and this verdict is the best
    #: spin of the search repeated with the limit lowered to :data:`FREE_SPIN_RATE_LIMIT_SHARE` of
    #: it (its spin, margin, carrying rotors, entry from hover and linear feedback check): a
    #: member of the family taken from below the limit, an equilibrium a spin-rate loop holds.
    spin_rate_free: bool = False

    @property
    def reachable_from_hover(self) -> bool:
        """Survivable by this relaxed hover: static, or spinning and not excluded from hover by
        :func:`rotorfault.analysis.entry_from_hover`."""
        if self.hover == "spinning":
            return self.entry_from_hover is None or self.entry_from_hover.reachable
        return self.hover == "static"

    @property
    def steady(self) -> bool:
        """A steady state the vehicle can settle in: static, or a spin whose rate the physics
        pins. With rotational damping (:attr:`damped`) the yaw balance ``n . tau(f) = k_r s``
        pins it, also at the search's limit. Without (``k_r = 0``) the balance is ``n . tau(f) =
        0`` whatever the rate, and a best spin at the limit (``at_spin_rate_limit``, or within
        :data:`SPIN_RATE_LIMIT_MARGIN` of it: ``near_spin_rate_limit``) is the search's bound, not
        an equilibrium: its margin still grows with the rate and nothing holds the rate (the yaw
        rate runs up to the limit, also the simulator's body-rate limit); not steady. A spin taken
        from below the limit by the lowered search (:attr:`spin_rate_free`, rule 4) is steady:
        without damping every member of the family is an equilibrium, held by a spin-rate loop."""
        if self.spin_rate_free:
            return self.hover == "spinning"
        at_limit = self.at_spin_rate_limit or self.near_spin_rate_limit
        return self.hover == "static" or (self.hover == "spinning" and not (at_limit and not self.damped))

    @property
    def survivable(self) -> bool:
        """Survivable by this relaxed hover: a steady state (:attr:`steady`) not excluded from
        hover (:attr:`reachable_from_hover`)."""
        return self.steady and self.reachable_from_hover


@dataclass(frozen=True, repr=False, eq=False)
class CertificateCase(FieldsResult):
    """One row of a :class:`Certificate`: the 1-based ``failed`` rotors and whether the vehicle
    still hovers with them failed (``hover``: ``"all-axes"``, ``"give-up-yaw"`` or ``"no"``), with
    the margins that say so.

    It holds the failure-table row it is derived from (``failure_case``:
    :class:`rotorfault.analysis.FailureCase`) and reads ``failed``, the ACAIs and where the hover
    wrench lies through it (issue 26: no copied fields); the rest is certify's own verdict. Its
    repr, equality and hash are over :attr:`FIELDS`, the fields it had as a dataclass
    (:class:`~rotorfault._util.core_result.FieldsResult`).

    Examples:

        >>> import rotorfault as rf
        >>> from rotorfault.studies import certify
        >>> case = certify(rf.Airframe.preset("hexa-ppnnpn"), max_failed=1).cases[1]
        >>> case.failed, case.hover, round(case.acai, 4), case.hover_wrench
        ((1,), 'all-axes', 0.7221, 'inside')
    """

    #: The failure-table row (failed rotors, ACAIs, hover points) this case is derived from.
    failure_case: FailureCase
    hover: Hover
    #: Largest balanced upward thrust over the weight with the axes kept (0 when it cannot hover).
    thrust_to_weight: float
    #: What an allocator must let go (``"lateral-force"`` only for fully actuated frames whose
    #: 6-D wrench is lost; ``None``: nothing helps).
    drop_axes: tuple[str, ...] | None
    #: The distance of the hover wrench to the attainable set (N / N m, 0 when attained), with all
    #: four axes and giving up yaw (:func:`rotorfault.allocation.hover_wrench_distance`).
    distance: float = 0.0
    distance_give_up_yaw: float = 0.0
    #: Beside the static verdict: the best relaxed hover (``None``: not asked for).
    relaxed_hover: RelaxedHoverVerdict | None = None

    #: What the repr, equality, hash and :meth:`Certificate.to_dict` show, in order.
    FIELDS: ClassVar[tuple[str, ...]] = (
        "failed", "hover", "acai", "acai_give_up_yaw", "thrust_to_weight", "drop_axes", "hover_wrench",
        "hover_wrench_give_up_yaw", "distance", "distance_give_up_yaw", "relaxed_hover",
    )

    #: The name before issue 26, for one release.
    acai_without_yaw = renamed_attribute("acai_without_yaw", "acai_give_up_yaw")

    @property
    def failed(self) -> tuple[int, ...]:
        """The failed rotors, numbered from 1."""
        return self.failure_case.failed

    @property
    def acai(self) -> float:
        """The ACAI with all four axes (N / N m; the facet margin, negative where hover is
        infeasible, -inf: rank deficient)."""
        return self.failure_case.acai

    @property
    def acai_give_up_yaw(self) -> float:
        """The ACAI giving up yaw (N / N m; the facet margin)."""
        return self.failure_case.acai_give_up_yaw

    @property
    def hover_wrench(self) -> HoverPoint:
        """Where the hover wrench lies with all four axes (``inside``, ``boundary``: ACAI exactly
        0, no margin; ``outside``; ``rank-deficient``)."""
        return self.failure_case.hover

    @property
    def hover_wrench_give_up_yaw(self) -> HoverPoint:
        """Where the hover wrench lies giving up yaw."""
        return self.failure_case.hover_give_up_yaw

    def __setstate__(self, state: dict[str, Any]) -> None:
        # A case pickled before it held its row lacks what the row holds (the core's reports):
        # refused rather than rebuilt with guesses.
        if "failure_case" not in state:
            raise TypeError("CertificateCase: a case pickled before certify kept its failure-table row "
                            "cannot be read; make it again with certify()")
        for name, value in state.items():
            object.__setattr__(self, name, value)

    def keeps(self, axes: tuple[CertifiedAxis, ...] = ALL_AXES) -> bool:
        """Hovers at rest with ``axes`` controllable (with all four: ``hover == "all-axes"``;
        giving up yaw: anything but ``"no"``)."""
        return self.hover == "all-axes" if "yaw" in axes else self.hover != "no"


@dataclass(frozen=True)
class Certificate(Tabular):
    """The verdicts of :func:`certify`, one case per failure combination; ``to_arrow()`` /
    ``to_pandas()`` give one row per case, :meth:`to_dict` the JSON document.

    Examples:

        >>> import rotorfault as rf
        >>> from rotorfault.studies import certify
        >>> certificate = certify(rf.Airframe.preset("quad-x"), max_failed=1)
        >>> certificate.rotor_count, len(certificate.failing("single")), certificate.to_arrow().num_rows
        (4, 4, 5)
    """

    airframe: str
    rotor_count: int
    fully_actuated: bool
    cases: tuple[CertificateCase, ...]

    def failing(self, required: str, *, axes: tuple[CertifiedAxis, ...] | str = ALL_AXES) -> list[CertificateCase]:
        """The cases up to the ``required`` class (``none``, ``single``, ``double``) that do not
        hover with ``axes`` kept (default all four: a case that hovers only by giving up yaw, or
        whose hover wrench is on the boundary, fails; ``("thrust", "roll", "pitch")`` allows
        spinning)."""
        if required not in FAILURE_CLASSES:
            raise ValueError(f"required: must be one of {', '.join(FAILURE_CLASSES)}, got {required!r}")
        kept = parse_axes("axes", axes)
        k = FAILURE_CLASSES[required]
        return [c for c in self.cases if len(c.failed) <= k and not c.keeps(kept)]

    def _table_columns(self) -> list[Column]:
        acai_ = f"acai_{FORMULA.replace('-', '_')}"
        cases = self.cases
        return [
            ("failed_rotors", "list<int64>", [list(c.failed) for c in cases]),
            ("failed_count", "int64", [len(c.failed) for c in cases]),
            ("hover", "string", [c.hover for c in cases]),
            (acai_, "float64", [c.acai for c in cases]),
            (f"{acai_}_give_up_yaw", "float64", [c.acai_give_up_yaw for c in cases]),
            ("thrust_to_weight", "float64", [c.thrust_to_weight for c in cases]),
            ("drop_axes", "list<string>", [None if c.drop_axes is None else list(c.drop_axes) for c in cases]),
            ("hover_wrench", "string", [c.hover_wrench for c in cases]),
            ("hover_wrench_give_up_yaw", "string", [c.hover_wrench_give_up_yaw for c in cases]),
            ("hover_wrench_distance", "float64", [c.distance for c in cases]),
            ("hover_wrench_distance_give_up_yaw", "float64", [c.distance_give_up_yaw for c in cases]),
        ]

    def _table_title(self) -> str:
        kind = "fully actuated" if self.fully_actuated else "not fully actuated"
        return f"certificate of {self.airframe}: {self.rotor_count} rotors, {kind}"

    def _table_metadata(self) -> dict[str, Any]:
        return {"kind": "certificate", "airframe": self.airframe, "rotor_count": self.rotor_count, "fully_actuated": self.fully_actuated, "formula": FORMULA}

    def failing_spinning(self, required: str) -> list[CertificateCase]:
        """The cases up to the ``required`` class that certify does not call survivable
        (:func:`survives`: neither a static hover with all four axes nor a steady spin entered from
        hover; a spinning solution not reachable from hover fails, and so does one at the search's
        spin-rate limit without rotational damping when the search repeated below
        :data:`FREE_SPIN_RATE_LIMIT_SHARE` of the limit finds no spin;
        ``ValueError`` if the certificate was made without ``spinning=True``)."""
        k = FAILURE_CLASSES[required]
        cases = [c for c in self.cases if len(c.failed) <= k]
        if any(c.relaxed_hover is None for c in cases):
            raise ValueError("spinning: the certificate was made without the relaxed hover (certify(..., spinning=True))")
        return [c for c in cases if not survives(c.hover, c.relaxed_hover)]

    def to_dict(self) -> dict[str, Any]:
        # The solutions stay out (a Rust object, not data): their numbers are the verdict's.
        cases = tuple(given._as_dict() | {"relaxed_hover": None} for given in self.cases)
        out = {"airframe": self.airframe, "rotor_count": self.rotor_count, "fully_actuated": self.fully_actuated, "cases": cases}
        for case, given in zip(cases, self.cases):
            for key in ("acai", "acai_give_up_yaw", "thrust_to_weight"):
                if math.isinf(case[key]):
                    case[key] = None  # JSON has no infinity: rank deficient / undefined
            spin = given.relaxed_hover
            if spin is not None:
                verdict = {f.name: getattr(spin, f.name) for f in fields(spin) if f.name != "solution"}
                if spin.hover == "no":
                    verdict |= {"spin_rate_rad_s": None, "thrust_margin_n": None}  # JSON has no NaN
                if spin.entry_from_hover is not None:
                    # JSON has no infinity: inf means the bound never reaches the limit
                    verdict["entry_from_hover"] = {k: None if isinstance(v, float) and math.isinf(v) else v
                                                   for k, v in asdict(spin.entry_from_hover).items()}
                case["relaxed_hover"] = verdict
        return out


def certify(
    airframe: Airframe,
    *,
    max_failed: int = 2,
    spinning: bool = False,
    settings: RelaxedHoverSettings | None = None,
    drag: Drag | None = None,
    actuator: FixedPitchActuator | None = None,
) -> Certificate:
    """Every combination of up to ``max_failed`` (default 2) fully failed rotors. ``spinning``:
    also the best relaxed hover of each case (:class:`RelaxedHoverVerdict`), computed with
    ``settings``, ``drag`` and ``actuator`` as :func:`rotorfault.analysis.relaxed_hover` takes
    them (the vehicle's rotational damping decides the spin rate: without it the best spin is the
    search limit, and rule 4 certifies the best spin below :data:`FREE_SPIN_RATE_LIMIT_SHARE` of
    it instead), and for a spinning one whether it is reachable from hover
    (:func:`rotorfault.analysis.entry_from_hover`, with the same rotor parameters). Checked before
    any work.

    Examples:

        >>> import rotorfault as rf
        >>> from rotorfault.studies import certify
        >>> certificate = certify(rf.Airframe.preset("hexa-ppnnpn"), max_failed=1)
        >>> len(certificate.cases), [case.failed for case in certificate.failing("single")]
        (7, [(5,), (6,)])
    """
    airframe = require_airframe(airframe)
    max_failed = count("max_failed", max_failed)
    if not isinstance(spinning, bool):
        raise TypeError(f"spinning: expected True or False, got {type(spinning).__name__}")
    if not spinning and (settings is not None or drag is not None or actuator is not None):
        raise ValueError("settings, drag, actuator: describe the relaxed hover; give them with spinning=True")
    # Checks settings, drag and actuator before any work; it is the healthy case's verdict below.
    healthy = _relaxed_hover_verdict(airframe, settings, drag, actuator) if spinning else None
    table = failure_table(airframe, max_failed=max_failed, formula=FORMULA)
    distances = hover_distances(airframe, [row.failed for row in table])
    full = airframe.is_fully_actuated
    cases = []
    for row in table:
        hover = _static_class(row)
        drop: tuple[str, ...] | None
        if hover == "no":
            drop, ratio = None, 0.0
        else:
            drop = () if hover == "all-axes" else ("yaw",)
            if full and not row.controllable_wrench:
                drop = ("lateral-force", *drop)
            margin = hover_thrust_margin(airframe.with_failed_rotors(row.failed), give_up_yaw=hover == "give-up-yaw")
            ratio = margin.thrust_to_weight
        distance, distance_give_up_yaw = distances[row.failed]
        verdict = healthy
        if spinning and row.failed:
            verdict = _relaxed_hover_verdict(airframe.with_failed_rotors(row.failed), settings, drag, actuator)
        cases.append(CertificateCase(row, hover, ratio, drop, distance, distance_give_up_yaw, verdict))
    return Certificate(airframe.name, airframe.rotor_count, full, tuple(cases))


def _static_class(row: FailureCase) -> Hover:
    """A failure-table row's static hover class: with all four axes, only by giving up yaw, or not."""
    return "all-axes" if row.controllable else ("give-up-yaw" if row.controllable_give_up_yaw else "no")


def _relaxed_hover_verdict(
    airframe: Airframe, settings: RelaxedHoverSettings | None, drag: Drag | None, actuator: FixedPitchActuator | None
) -> RelaxedHoverVerdict:
    best = relaxed_hover(airframe, settings, drag=drag, actuator=actuator, best_only=True).best
    if best is None:
        return RelaxedHoverVerdict("no", math.nan, math.nan, (), False)
    kind: SpinningHover = "spinning" if best.kind == "spinning" else "static"
    entry = entry_from_hover(airframe, best, settings, drag=drag, actuator=actuator) if kind == "spinning" else None
    resolved = vehicle_settings(settings, drag, actuator)
    damped = resolved.rotational_drag_n_m_s > 0.0
    near = kind == "spinning" and abs(float(best.spin_rate_rad_s)) >= (1.0 - SPIN_RATE_LIMIT_MARGIN) * resolved.max_spin_rate_rad_s
    if not damped and (near or bool(best.at_spin_rate_limit)) and kind == "spinning":
        # Rule 4: the rate is free without damping; take the family's member from below the limit.
        free = _free_spin_verdict(airframe, resolved)
        if free is not None:
            return free
    return RelaxedHoverVerdict(
        kind, float(best.spin_rate_rad_s), float(best.thrust_margin_n), tuple(best.carrying), bool(best.at_spin_rate_limit), best, entry,
        damped, near,
    )


def _free_spin_verdict(airframe: Airframe, resolved: RelaxedHoverSettings) -> RelaxedHoverVerdict | None:
    """Rule 4 (:data:`FREE_SPIN_RATE_LIMIT_SHARE`): the best spinning relaxed hover of an undamped
    vehicle searched with the spin-rate limit lowered to that share of ``resolved``'s (the vehicle's
    settings, its rotor parameters filled in), as a steady verdict (``spin_rate_free``); ``None``
    where that search finds no spinning solution (rule 3's answer stands)."""
    values = {name: getattr(resolved, name) for name in RelaxedHoverSettings.FIELDS}
    values["max_spin_rate_rad_s"] = FREE_SPIN_RATE_LIMIT_SHARE * resolved.max_spin_rate_rad_s
    lower = RelaxedHoverSettings(**values)
    best = relaxed_hover(airframe, lower, best_only=True).best
    if best is None or best.kind != "spinning":
        return None
    entry = entry_from_hover(airframe, best, lower)
    near = abs(float(best.spin_rate_rad_s)) >= (1.0 - SPIN_RATE_LIMIT_MARGIN) * lower.max_spin_rate_rad_s
    return RelaxedHoverVerdict(
        "spinning", float(best.spin_rate_rad_s), float(best.thrust_margin_n), tuple(best.carrying), bool(best.at_spin_rate_limit), best, entry,
        False, near, True,
    )


#: How a vehicle as it is (its efficiencies: a failed rotor's drawn share of thrust) survives:
#: ``static-hover`` (hovers at rest: with all four axes, or its best relaxed hover is static),
#: ``spinning`` (a steady relaxed hover a linear feedback can hold, its entry from hover not
#: excluded; without rotational damping a spin at the search's limit, or within :data:`SPIN_RATE_LIMIT_MARGIN` of it, is replaced by the best spin below :data:`FREE_SPIN_RATE_LIMIT_SHARE` of the limit, rule 4) or ``not-survivable`` (a static hover that only gives up yaw
#: included: :func:`survives` says why).
Survival = Literal["static-hover", "spinning", "not-survivable"]


@dataclass(frozen=True)
class SurvivalVerdict:
    """:func:`certify_survival`'s answer: ``survival`` (:data:`Survival`), the static class of the
    vehicle as it is (``hover``: ``all-axes``, ``give-up-yaw``, ``no``) and the relaxed hover
    verdict that decided a vehicle without all-axes static hover (``None`` where static hover
    with all four axes decided: the search is not run)."""

    survival: Survival
    hover: Hover
    relaxed_hover: RelaxedHoverVerdict | None

    @property
    def survivable(self) -> bool:
        return self.survival != "not-survivable"


def certify_survival(
    airframe: Airframe,
    *,
    settings: RelaxedHoverSettings | None = None,
    drag: Drag | None = None,
    actuator: FixedPitchActuator | None = None,
) -> SurvivalVerdict:
    """Certify's verdict on one vehicle as it is, with its efficiencies (a partial loss: the
    rotor's efficiency; a total one: 0), not a list of failure combinations: static hover with
    all four axes (Du's ACAI facet margin > 0) is ``static-hover`` and ends there; otherwise the
    best relaxed hover (as :func:`certify` with ``spinning=True`` computes it, same ``settings``,
    ``drag``, ``actuator``) decides: static, or a steady spin (with rotational damping; without it,
    below the search's spin-rate limit, or the best spin of the search repeated below
    :data:`FREE_SPIN_RATE_LIMIT_SHARE` of it: rule 4) not excluded from hover (:func:`rotorfault.analysis.entry_from_hover`); failing both,
    ``not-survivable``, also where a static hover gives up yaw (``hover`` says ``give-up-yaw``):
    the yaw moment left settles only in a steady spin, which the search finds where one exists.
    The survivable set is certify's one rule, the one :meth:`Certificate.failing_spinning` and
    :func:`rotorfault.studies.certify_against_flights` apply (:func:`survives`).

    Examples:

        >>> import rotorfault as rf
        >>> from rotorfault.studies.certify import certify_survival
        >>> quad = rf.Airframe.preset("ke-quadcopter")
        >>> certify_survival(quad.with_efficiency([1, 0.9, 1, 1])).survival
        'static-hover'
        >>> verdict = certify_survival(quad.with_failed_rotors([1]), drag=rf.Drag(rotational_n_m_s=2.8e-3))
        >>> verdict.survival, verdict.hover, round(verdict.relaxed_hover.spin_rate_rad_s, 2)
        ('spinning', 'no', 15.22)
    """
    airframe = require_airframe(airframe)
    # Checked before any work, also where static hover decides and the search does not run.
    vehicle_settings(settings, drag, actuator)
    row = failure_table(airframe, max_failed=0, formula=FORMULA)[0]
    hover = _static_class(row)
    if hover == "all-axes":
        return SurvivalVerdict("static-hover", hover, None)
    verdict = _relaxed_hover_verdict(airframe, settings, drag, actuator)
    survival: Survival = "not-survivable"
    if verdict.hover == "static":
        survival = "static-hover"
    elif verdict.survivable:
        survival = "spinning"
    return SurvivalVerdict(survival, hover, verdict)


def survives(hover: Hover | str, relaxed_hover: RelaxedHoverVerdict | None) -> bool:
    """Certify's one rule for "survivable": a static hover with all four axes (``hover ==
    "all-axes"``), or a relaxed hover a linear feedback can hold that is a steady state and whose
    entry from hover is not excluded (:attr:`RelaxedHoverVerdict.survivable`: static, or a steady
    spin: with rotational damping; without it, below the search's spin-rate limit, or the best spin
    of the search repeated below :data:`FREE_SPIN_RATE_LIMIT_SHARE` of it, rule 4).

    A static hover that only exists by giving up yaw (``"give-up-yaw"``) is not survivable by
    itself: it leaves a yaw moment ``tau_z`` that nothing balances at rest, so the yaw rate grows
    until the rotational damping balances it (``k_r r = tau_z``): that steady spin is a relaxed
    hover (about the thrust axis, with the same thrusts), which the search finds on a damped
    vehicle; without damping (``k_r = 0``, e.g. a model imported without it) the yaw rate grows
    without bound unless a controller holds a spin rate, and the case survives only if the search
    finds another steady relaxed hover (rule 4: without damping the spin rate is free, and a spin
    at the search's limit is replaced by the best one below :data:`FREE_SPIN_RATE_LIMIT_SHARE` of
    it, which a spin-rate loop holds)."""
    return hover == "all-axes" or (relaxed_hover is not None and relaxed_hover.survivable)


def describe_relaxed_hover(verdict: RelaxedHoverVerdict | None) -> str:
    """One cell of the table: ``spinning 15.22 rad/s, margin 6.04 N, rotors 2, 3, 4``; a spin
    that cannot be entered from hover says so, with the numbers that decide it."""
    if verdict is None:
        return "-"
    if verdict.hover == "no":
        return "no"
    spin = f" {verdict.spin_rate_rad_s:.2f} rad/s{' (search limit)' if verdict.at_spin_rate_limit else ''}," if verdict.hover == "spinning" else ","
    text = f"{spin} margin {verdict.thrust_margin_n:.2f} N, rotors {rotor_labels(verdict.carrying)}"
    entry = verdict.entry_from_hover
    if entry is None or entry.reachable:
        return verdict.hover + text
    return (f"spinning solution exists, not reachable from hover:{text.rstrip(',')}; tilt >= {math.degrees(entry.tilt_before_spin_rad):.0f} deg "
            f"before the {entry.spin_rate_needed_rad_s:.2f} rad/s spin, at most {entry.spin_rate_at_tilt_limit_rad_s:.2f} rad/s by "
            f"{math.degrees(entry.tilt_limit_rad):.0f} deg (roll/yaw {entry.roll_to_yaw_ratio:.2f})")


def rows_for_display(cert: Certificate) -> tuple[list[str], list[list[str]]]:
    acai_ = acai_label(FORMULA)
    headers = ["failed", "hover", "hover wrench", acai_, f"hover wrench {GIVE_UP_YAW}", f"{acai_} {GIVE_UP_YAW}", "T/W",
               "allocator drops"]
    spinning = any(c.relaxed_hover is not None for c in cert.cases)
    if spinning:
        headers.append("relaxed hover")

    def number(x: float) -> str:
        return "undefined" if math.isinf(x) else f"{x:.4f}"

    rows = [
        [
            rotor_labels(c.failed), c.hover, hover_wrench_text(c.hover_wrench, c.distance), number(c.acai),
            hover_wrench_text(c.hover_wrench_give_up_yaw, c.distance_give_up_yaw), number(c.acai_give_up_yaw),
            f"{c.thrust_to_weight:.2f}" if c.hover != "no" else "-",
            "-" if c.drop_axes is None else (", ".join(c.drop_axes) or "nothing"),
            *([describe_relaxed_hover(c.relaxed_hover)] if spinning else []),
        ]
        for c in cert.cases
    ]
    return headers, rows


__all__ = ["ALL_AXES", "FAILURE_CLASSES", "FORMULA", "FREE_SPIN_RATE_LIMIT_SHARE", "GIVE_UP_YAW_AXES", "SPIN_RATE_LIMIT_MARGIN", "SURVIVAL_RULE", "Certificate", "CertificateCase", "Hover", "certify",
           "parse_axes", "rows_for_display"]
