"""Which modes can the inputs move? The PBH (Popov-Belevitch-Hautus) tests for stabilisability and
detectability, decided scale-free, with the modes that fail named in the model's own states.

``(A, B)`` is stabilisable when ``rank [A - lambda I, B] = n`` at every eigenvalue ``lambda`` of
``A`` that is not stable (``Re lambda >= 0``, or ``|lambda| >= 1`` in discrete time). Where the
rank drops, the left null vectors ``w`` (``w^H [A - lambda I, B] = 0``) are the modes no input
can move: ``w^H x`` evolves as ``exp(lambda t)`` whatever the input does. ``(A, C)`` is
detectable when ``(A^T, C^T)`` is stabilisable; there the null vectors are state directions the
output ``C x`` does not see.

Scale-free (README decisions, "stabilisability"):

- ``A`` is balanced first (a diagonal similarity by powers of two, ``scipy.linalg.matrix_balance``):
  eigenvalues, the stability margin and the choice of each named mode's leading state do not
  depend on the states' units;
- the rank of ``[A - lambda I, B]`` is decided like every rank in rotorfault
  (:data:`rotorfault.RANK_RTOL`, the core's ``scale_free_rank``): rows and columns equilibrated by
  powers of two, then singular values above ``RANK_RTOL`` of the largest. A state that an input
  reaches with a gain of 1e-12 of the others is reached;
- an eigenvalue needs an input unless it is stable by a margin: ``Re lambda < -STABLE_RTOL ||A||``
  (``|lambda| < 1 - STABLE_RTOL`` discrete), ``||A||`` the balanced matrix's norm. Repeated
  eigenvalues (the rigid body's integrators) come out of the eigensolver scattered by
  ``eps^(1/k) ||A||`` for a Jordan block of size ``k`` (1.5e-8 for ``k = 2``, 6e-6 for ``k = 3``), so
  eigenvalues closer than ``STABLE_RTOL ||A||`` are one cluster, tested once at its mean.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from .._util.convert import FloatArray, float_array, frozen_array
from ..analysis.acai import RANK_RTOL

ComplexArray = npt.NDArray[np.complex128]

#: An eigenvalue is stable only with ``Re lambda < -STABLE_RTOL ||A||`` (discrete:
#: ``|lambda| < 1 - STABLE_RTOL max(1, ||A||)``); eigenvalues closer than this are one cluster
#: (module notes).
STABLE_RTOL = 1e-6

#: Coefficients of a named mode below this fraction of its largest (in balanced units) are
#: round-off and printed as absent.
COEFFICIENT_RTOL = 1e-9


@dataclass(frozen=True)
class Direction:
    """A linear combination of the states, ``coefficients`` in the model's own units (the leading
    one is +-1), and ``text`` in state names (``"0.132 p + 0.132 q - r"``; with labels,
    ``"yaw rate r together with p and q: 0.132 p + 0.132 q - r"``)."""

    coefficients: FloatArray
    text: str


@dataclass(frozen=True)
class Mode:
    """One eigenvalue (cluster) of ``A`` the test had to check: ``eigenvalue`` (the cluster's
    mean), ``multiplicity`` (computed eigenvalues in the cluster), ``rank`` of the PBH matrix
    there and, when it is below the state count, the ``directions`` no input moves
    (stabilisability: functionals ``w^T x``) or no output sees (detectability: state directions)."""

    eigenvalue: complex
    multiplicity: int
    rank: int
    directions: tuple[Direction, ...]


@dataclass(frozen=True)
class PbhTest:
    """The result of :func:`stabilisability` or :func:`detectability`: every mode that is not
    stable by the margin (least stable first), with its rank; ``holds`` when each has full rank.

    Examples:

        >>> import numpy as np
        >>> from rotorfault.control import stabilisability
        >>> test = stabilisability(np.diag([1.0, -1.0]), np.array([[1.0], [0.0]]))
        >>> test.kind, test.state_count, test.holds
        ('stabilisability', 2, True)
    """

    kind: Literal["stabilisability", "detectability"]
    discrete: bool
    state_count: int
    modes: tuple[Mode, ...]

    @property
    def holds(self) -> bool:
        return all(m.rank == self.state_count for m in self.modes)

    @property
    def failing(self) -> tuple[Mode, ...]:
        return tuple(m for m in self.modes if m.rank < self.state_count)

    def describe(self) -> str:
        """The failing modes in words (empty when the test holds)."""
        what = "no input moves" if self.kind == "stabilisability" else "the weight does not see the state along"
        parts = []
        for m in self.failing:
            directions = "; ".join(d.text for d in m.directions)
            if len(m.directions) > 1:
                directions = f"any combination of {directions}"
            parts.append(
                f"at eigenvalue {_format_eigenvalue(m.eigenvalue)} {what} {directions} "
                f"(PBH rank {m.rank} of {self.state_count})"
            )
        return "; ".join(parts)


def system_matrices(system: Any, second: str) -> tuple[FloatArray, FloatArray, tuple[str, ...] | None, tuple[str, ...] | None]:
    """``(A, B)`` (``second="B"``) or ``(A, C)`` of a python-control system, with its state names
    and, for a :class:`rotorfault.control.systems.LinearModel`, the states' descriptions."""
    if not (hasattr(system, "A") and hasattr(system, second)):
        raise TypeError(f"a: expected a matrix and {second.lower()}, or a python-control StateSpace, got {type(system).__name__}")
    names = getattr(system, "state_labels", None)
    descriptions = getattr(system, "state_descriptions", None)
    return (
        float_array("system.A", system.A, 2), float_array(f"system.{second}", getattr(system, second), 2),
        None if names is None else tuple(names), None if descriptions is None else tuple(descriptions),
    )


def _from_system(a: Any, other: Any, second: str, names: Sequence[str] | None, labels: Sequence[str] | None) -> tuple[Any, Any, Sequence[str] | None, Sequence[str] | None]:
    """``(a, other, names, labels)`` with a python-control system given as ``a`` (and ``other``
    None) unpacked: its matrices, and its state names and descriptions unless given."""
    if other is not None:
        return a, other, names, labels
    am, om, own_names, own_labels = system_matrices(a, second)
    return am, om, own_names if names is None else names, own_labels if labels is None else labels


def stabilisability(
    a: npt.ArrayLike | Any,
    b: npt.ArrayLike | None = None,
    *,
    discrete: bool = False,
    state_names: Sequence[str] | None = None,
    state_labels: Sequence[str] | None = None,
) -> PbhTest:
    """The PBH stabilisability test of ``(a, b)``, or of a python-control ``StateSpace`` given as
    ``a`` alone (its ``A``, ``B`` and state names) (module notes). ``state_names`` (default
    ``x1 .. xn``) name the states in the failing modes; ``state_labels`` (optional, e.g.
    ``"yaw rate r"``) describe a mode's leading state.

    Examples:

        >>> import numpy as np
        >>> from rotorfault.control import stabilisability
        >>> test = stabilisability(np.diag([1.0, -1.0]), np.array([[0.0], [1.0]]))
        >>> test.holds, [mode.eigenvalue for mode in test.failing]
        (False, [(1+0j)])
    """
    a, b, state_names, state_labels = _from_system(a, b, "B", state_names, state_labels)
    am, bm = _pair(a, b, "b")
    names, labels = _names(am.shape[0], state_names, state_labels)
    return PbhTest("stabilisability", discrete, am.shape[0], _pbh(am, bm, discrete, names, labels))


def detectability(
    a: npt.ArrayLike | Any,
    c: npt.ArrayLike | None = None,
    *,
    discrete: bool = False,
    state_names: Sequence[str] | None = None,
    state_labels: Sequence[str] | None = None,
) -> PbhTest:
    """The PBH detectability test of ``(a, c)`` (or of a python-control ``StateSpace`` given as
    ``a`` alone: its ``A``, ``C`` and state names): ``(a^T, c^T)`` stabilisable; a failing mode's
    directions are the states ``v`` with ``(a - lambda I) v = 0`` and ``c v = 0``.

    Examples:

        >>> import numpy as np
        >>> from rotorfault.control import detectability
        >>> detectability(np.diag([1.0, -1.0]), np.array([[1.0, 0.0]])).holds
        True
    """
    a, c, state_names, state_labels = _from_system(a, c, "C", state_names, state_labels)
    am = float_array("a", a, 2)
    cm = float_array("c", c, 2)
    if cm.shape[1:] != am.shape[:1]:
        raise ValueError(f"c: expected {am.shape[0]} columns (one per state), got shape {cm.shape}")
    at, ct = _pair(am.T, cm.T, "c")
    names, labels = _names(at.shape[0], state_names, state_labels)
    return PbhTest("detectability", discrete, at.shape[0], _pbh(at, ct, discrete, names, labels))


def _pair(a: npt.ArrayLike, b: npt.ArrayLike, b_name: str) -> tuple[FloatArray, FloatArray]:
    am = float_array("a", a, 2)
    bm = float_array(b_name, b, 2)
    n = am.shape[0]
    if am.shape != (n, n) or n == 0:
        raise ValueError(f"a: expected a non-empty square matrix, got shape {am.shape}")
    if bm.shape[0] != n or bm.shape[1] == 0:
        raise ValueError(f"{b_name}: expected {n} rows and at least one column, got shape {bm.shape}")
    for name, m in (("a", am), (b_name, bm)):
        if not np.all(np.isfinite(m)):
            raise ValueError(f"{name}: must be finite")
        # The scale-free rank scales by at most 2^+-1000, which cannot lift a subnormal entry to
        # the others' level: C = [0, 1e-310] of an oscillator read as not detectable (it is).
        tiny = m[(m != 0) & (np.abs(m) < np.finfo(np.float64).tiny)]
        if tiny.size:
            raise ValueError(f"{name}: an entry of {tiny[0]:.3g} is subnormal (nonzero and below "
                             f"{np.finfo(np.float64).tiny:.3g}, the smallest normal double): rescale the states or write 0")
    return am, bm


def _names(n: int, names: Sequence[str] | None, labels: Sequence[str] | None) -> tuple[tuple[str, ...], tuple[str, ...] | None]:
    out = tuple(f"x{i + 1}" for i in range(n)) if names is None else tuple(str(s) for s in names)
    if len(out) != n:
        raise ValueError(f"state_names: expected {n} names, got {len(out)}")
    if labels is None:
        return out, None
    lab = tuple(str(s) for s in labels)
    if len(lab) != n:
        raise ValueError(f"state_labels: expected {n} labels, got {len(lab)}")
    return out, lab


def balance(a: FloatArray) -> tuple[FloatArray, FloatArray]:
    """``(T^-1 A T, t)`` with ``T = diag(t)`` powers of two (no permutation): the balanced
    matrix and the state scale (``x = T x_balanced``)."""
    from scipy.linalg import matrix_balance  # type: ignore[import-untyped]

    # scipy casts its permutation (unused: permute=False) to int; on entries near 1e-282 that cast
    # sees a non-finite value and warns. The scaling we use is not affected.
    with np.errstate(invalid="ignore"):
        balanced, (scale, _) = matrix_balance(a, permute=False, separate=True)
    return np.asarray(balanced, dtype=np.float64), np.asarray(scale, dtype=np.float64)


def equilibrate(matrix: npt.NDArray[np.generic]) -> tuple[npt.NDArray[np.generic], FloatArray, FloatArray]:
    """``(D_r M D_c, d_r, d_c)``: rows then columns brought to unit norm by powers of two, up to
    eight rounds (the core's ``scale_free_rank`` rule, so the scaling adds no rounding)."""
    scaled = np.array(matrix, copy=True)
    rows = np.ones(scaled.shape[0])
    cols = np.ones(scaled.shape[1])
    for _ in range(8):
        r = _bounded(rows, _inverse_power_of_two(_norms(scaled, 1)))
        scaled *= r[:, None]
        c = _bounded(cols, _inverse_power_of_two(_norms(scaled, 0)))
        scaled *= c[None, :]
        rows *= r
        cols *= c
        if np.all(r == 1.0) and np.all(c == 1.0):
            break
    return scaled, rows, cols


def _norms(matrix: npt.NDArray[np.generic], axis: int) -> FloatArray:
    """Euclidean norms along ``axis``, each taken on its vector scaled to entries below 1 by a
    power of two: no overflow for entries of 1e300 (squares would be inf, and the scaling would
    zero the row), none for subnormal ones."""
    peak = np.max(np.abs(matrix), axis=axis, initial=0.0)
    # Divided by the power of two at or above the peak, by exponent (exact): a complex entry divided
    # by a subnormal peak overflowed inside numpy's complex division (long run, 2026-11-28).
    _, exponent = np.frexp(np.where(peak > 0, peak, 1.0))
    shift = -np.expand_dims(exponent, axis)
    if np.iscomplexobj(matrix):
        unit = np.ldexp(matrix.real, shift) + 1j * np.ldexp(matrix.imag, shift)
    else:
        unit = np.ldexp(np.asarray(matrix, dtype=np.float64), shift)
    return np.asarray(np.ldexp(np.linalg.norm(unit, axis=axis), exponent), dtype=np.float64)


def _bounded(total: FloatArray, step: FloatArray) -> FloatArray:
    """``step`` (powers of two) cut so that ``total * step`` stays within 2^-1000..2^1000: rounds
    of scaling a subnormal entry next to a unit one would otherwise push the product past the
    float range (an overflow the hostile harness found)."""
    exponent_total = np.log2(total)
    wanted = np.clip(exponent_total + np.log2(step), -1000, 1000)
    return np.asarray(np.exp2(wanted - exponent_total), dtype=np.float64)


def _rows_divided(b: FloatArray, scale: FloatArray) -> FloatArray:
    """``diag(scale)^-1 b`` for powers of two ``scale``, with a column whose quotient would overflow
    shifted down by a power of two first: a column scale of ``B`` changes neither the rank of
    ``[A - lambda I, B]`` nor its left null space, and balancing an ``A`` with entries near 1e300
    can divide a row of ``B`` by 2^-1000 (an overflow the hostile harness found). Exact, and the
    plain quotient wherever nothing overflows."""
    mantissa, exponent = np.frexp(b)
    exponent = exponent - np.round(np.log2(scale)).astype(exponent.dtype)[:, None]
    peak = np.max(np.where(mantissa != 0, exponent, np.iinfo(exponent.dtype).min), axis=0)
    shift = np.where(peak > _MAX_EXPONENT, peak - _MAX_EXPONENT, 0)
    return np.asarray(np.ldexp(mantissa, exponent - shift[None, :]), dtype=np.float64)


#: Largest binary exponent a column of the divided ``B`` may reach (2^1000, well inside float range,
#: so the pencil's norms stay finite).
_MAX_EXPONENT = 1000


def _inverse_power_of_two(norms: FloatArray) -> FloatArray:
    out = np.ones_like(norms)
    ok = (norms > 0) & np.isfinite(norms)
    out[ok] = np.exp2(-np.clip(np.round(np.log2(norms[ok])), -1000, 1000))
    return out


def left_null_space(matrix: npt.NDArray[np.generic]) -> tuple[int, npt.NDArray[np.generic]]:
    """``(rank, W)``: the scale-free rank of ``matrix`` (:func:`equilibrate`, singular values above
    ``RANK_RTOL`` of the largest) and the columns of ``W`` spanning its left null space
    (``W^H matrix = 0``), in the matrix's own row units."""
    scaled, rows, _ = equilibrate(matrix)
    u, s, _ = np.linalg.svd(np.asarray(scaled, dtype=np.complex128 if np.iscomplexobj(scaled) else np.float64))
    largest = float(s[0]) if s.size else 0.0
    rank = 0 if largest == 0.0 else int(np.count_nonzero(s > RANK_RTOL * largest))
    return rank, rows[:, None] * u[:, rank:]


def _clusters(values: ComplexArray, tol: float) -> list[ComplexArray]:
    """Eigenvalues grouped when closer than ``tol`` (single linkage)."""
    remaining = list(values)
    groups: list[ComplexArray] = []
    while remaining:
        group = [remaining.pop(0)]
        grown = True
        while grown:
            grown = False
            for v in list(remaining):
                if min(abs(v - g) for g in group) <= tol:
                    group.append(v)
                    remaining.remove(v)
                    grown = True
        groups.append(np.array(group, dtype=np.complex128))
    return groups


def _pbh(
    a: FloatArray, b: FloatArray, discrete: bool, names: tuple[str, ...], labels: tuple[str, ...] | None
) -> tuple[Mode, ...]:
    n = a.shape[0]
    balanced, scale = balance(a)
    b_balanced = _rows_divided(b, scale)
    size = float(np.linalg.norm(balanced, 1))
    tol = STABLE_RTOL * (max(1.0, size) if discrete else size)
    eigenvalues = np.linalg.eigvals(balanced).astype(np.complex128)
    modes = []
    for group in _clusters(eigenvalues, tol):
        centre = complex(np.mean(group))
        if abs(centre.imag) <= tol:
            centre = complex(centre.real, 0.0)
        if centre.imag < 0:
            continue  # the conjugate cluster is tested
        if discrete:
            if abs(abs(centre) - 1.0) <= tol and centre.imag == 0.0:
                centre = complex(math.copysign(1.0, centre.real), 0.0)
            stable = abs(centre) < 1.0 - tol
        else:
            if abs(centre) <= tol:
                centre = 0j
            stable = centre.real < -tol
        if stable:
            continue
        pencil = np.hstack([balanced - centre * np.eye(n), b_balanced.astype(np.complex128)])
        if centre.imag == 0.0:
            pencil = pencil.real
        rank, null = left_null_space(pencil)
        directions: tuple[Direction, ...] = ()
        if rank < n:
            vectors = np.hstack([null.real, null.imag]) if np.iscomplexobj(null) else null
            directions = describe_directions(vectors.T, 1.0 / scale, names, labels)
        modes.append(Mode(centre, int(group.size), rank, directions))
    return tuple(sorted(modes, key=lambda m: (-m.eigenvalue.real, m.eigenvalue.imag)))


def describe_directions(
    vectors: npt.ArrayLike,
    to_user: npt.ArrayLike,
    names: Sequence[str],
    labels: Sequence[str] | None = None,
) -> tuple[Direction, ...]:
    """A canonical basis of the span of the rows of ``vectors`` (in scaled units; ``to_user``
    multiplies each coefficient into the model's units), each as a :class:`Direction`.

    Canonical: reduced echelon form with complete pivoting in the scaled units (each row leads
    with its largest coefficient, which no other row contains), so a span of single states
    prints as those states and the choice does not depend on the units."""
    w = float_array("vectors", vectors, 2)
    factor = float_array("to_user", to_user, 1)
    if w.size == 0:
        return ()
    q, s, _ = np.linalg.svd(w.T, full_matrices=False)
    basis = q[:, s > RANK_RTOL * s[0]].T if s.size and s[0] > 0 else np.zeros((0, w.shape[1]))
    rows = basis.copy()
    pivots: list[int] = []
    for k in range(rows.shape[0]):
        sub = np.abs(rows[k:])
        sub[:, pivots] = 0.0
        # Ties (within rounding) go to the first state, so equal coefficients lead in state order.
        near = np.argwhere(sub >= (1.0 - 1e-9) * np.max(sub))
        i, j = min(near.tolist(), key=lambda ij: (ij[1], ij[0]))
        i += k
        rows[[k, i]] = rows[[i, k]]
        rows[k] /= rows[k, j]
        for other in range(rows.shape[0]):
            if other != k:
                rows[other] -= rows[other, j] * rows[k]
        pivots.append(int(j))
    out = []
    for row, j in zip(rows, pivots):
        row = np.where(np.abs(row) <= COEFFICIENT_RTOL * np.max(np.abs(row)), 0.0, row)
        user = row * factor
        user = user / abs(user[j])
        first = int(np.flatnonzero(user)[0])
        if user[first] < 0:
            user = -user
        user[user == 0.0] = 0.0  # no -0.0
        out.append(Direction(frozen_array("coefficients", user, 1), _text(user, j, names, labels)))
    order = sorted(range(len(out)), key=lambda k: pivots[k])
    return tuple(out[k] for k in order)


def _text(coefficients: FloatArray, lead: int, names: Sequence[str], labels: Sequence[str] | None) -> str:
    terms = []
    for i, c in enumerate(coefficients):
        if c == 0.0:
            continue
        magnitude = "" if abs(abs(c) - 1.0) < 5e-4 else f"{abs(c):.3g} "
        sign = "-" if c < 0 else "+"
        terms.append((sign, f"{magnitude}{names[i]}"))
    expression = " ".join(f"{s} {t}" for s, t in terms).removeprefix("+ ")
    if expression.startswith("- "):
        expression = "-" + expression[2:]
    head = labels[lead] if labels is not None else names[lead]
    if len(terms) == 1:
        return head
    others = [names[int(i)] for i in np.flatnonzero(coefficients) if i != lead]
    together = others[0] if len(others) == 1 else ", ".join(others[:-1]) + " and " + others[-1]
    return f"{head} together with {together}: {expression}"


def _format_eigenvalue(value: complex) -> str:
    if value.imag == 0.0:
        return f"{value.real:.6g}"
    return f"{value.real:.6g} +- {abs(value.imag):.6g}j"


__all__ = [
    "COEFFICIENT_RTOL",
    "STABLE_RTOL",
    "Direction",
    "Mode",
    "PbhTest",
    "balance",
    "describe_directions",
    "detectability",
    "equilibrate",
    "left_null_space",
    "stabilisability",
]
