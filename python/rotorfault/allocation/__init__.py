"""Constrained control allocation: rotor commands for a desired virtual control.

The problem (Ke et al. eq. (33), generalised)::

    minimise  1/2 (u_c - M T)^T W (u_c - M T) + gamma/2 |T - T_pref|^2
    subject   T_min <= T <= T_max

``M`` is an airframe's effectiveness matrix (rows thrust N, roll, pitch, yaw torque N m; see
:meth:`rotorfault.Airframe.effectiveness_matrix`) or any n x m matrix, ``W = diag(weights)``.

Methods (one problem type, one answer type):

- ``"active-set"`` (default): exact, about a microsecond, in Rust; what runs in closed loops.
- ``"clarabel"``: the Clarabel interior-point solver, the reference; also solves prioritised
  allocations (``priorities=[[0, 1, 2], [3]]``: thrust and roll/pitch first, yaw with the rest).
- ``"pinv"``: the unconstrained weighted pseudo-inverse (Ke eqs. (34)/(35)); bounds ignored.

When several command vectors are optimal (more rotors than weighted axes, or a zero weight),
``"active-set"`` and ``"pinv"`` return the one closest to ``preferred`` (zero by default), also
with bounds active: for ``"pinv"`` that is exactly ``M^+ u_c`` (eq. (34)) or ``(E_1 M)^+ u_c1``
with a zero yaw weight (eq. (35)). ``"clarabel"`` polishes its answer with the active set from the
bounds it identifies, so it agrees with ``"active-set"`` in the commands when that certifies.

Evidence: every :class:`Allocation` carries a :class:`Certificate`, the KKT residuals
(stationarity, complementarity, bound violation) of its commands, each normalised in the
problem's own scaling (invariant to scaling the matrix, the virtual control, the weights or one
rotor's gain), and the ``tolerance`` they are held to (default :data:`DEFAULT_TOLERANCE`, from
the core). ``status == "optimal"`` only when ``certificate.holds``. Where the active set cannot
certify its answer it falls back to Clarabel on the internally scaled problem, polished, and says
so: ``solved_by`` is ``"clarabel"`` (``"active-set"`` otherwise, ``"pinv"`` for the pseudo-inverse)
and ``fallbacks`` counts those answers.

Settings (on :class:`Allocator` and :func:`allocate`, keyword-only, defaults from the core):
``tolerance`` the certificate tolerance; ``max_iterations`` the iteration bound of each active-set
phase (default ``4 m + 20``) and Clarabel's iteration limit (default 200), at most 10,000 (a
solve does not poll Ctrl-C, so the ceiling bounds how long it can keep it waiting: about 0.15 s);
``clarabel_tolerance`` Clarabel's own duality-gap and feasibility tolerance, read by
``method="clarabel"`` (the active set's own fallback to Clarabel keeps fixed settings, 1e-12 and 400
iterations, and does not read it: a known gap, not refused yet). A setting the method does not read
is refused when it allocates, not dropped: ``"pinv"`` and ``"clarabel"`` hold their certificates
to :data:`DEFAULT_TOLERANCE`, and ``"pinv"`` neither iterates nor calls Clarabel.

Accuracy: the active-set solver and the pseudo-inverse solve the scaled least-squares problem
``min |W^(1/2) (M T - u_c)|`` by a Householder QR (never the normal equations ``M^T W M``), with
the rows sorted by size, so a weight of 1e-9 or a rotor 1e-12 times weaker than the others still
counts; columns dependent to ``RANK_TOL = 1e-13`` of their own norm share the load by the
closest-to-``preferred`` rule.

The room (mirrors the core's ``allocation``): :mod:`~rotorfault.allocation.allocator` (the
problem, the three methods, the certificate) and :mod:`~rotorfault.allocation.attainable` (the
attainable set: directional limits, hover thrust margin, slices through hover). May import:
``rotorfault.analysis`` (the airframe), ``rotorfault._typing``, ``rotorfault._util`` and, on
first use, ``rotorfault.plotting``; never ``flight`` or ``control`` (a controller uses an
allocator, not the other way round).
"""


from .allocator import (
    CLARABEL_TOLERANCE,
    DEFAULT_TOLERANCE,
    METHODS,
    Allocation,
    Allocator,
    Certificate,
    allocate,
)
from .attainable import (
    AXIS_LABELS,
    DirectionalLimit,
    HoverMargin,
    attainable_slice,
    hover_distances,
    hover_thrust_margin,
    hover_wrench_distance,
    max_virtual_control,
    plot_attainable_slices,
)

__all__ = [
    "AXIS_LABELS",
    "CLARABEL_TOLERANCE",
    "DEFAULT_TOLERANCE",
    "METHODS",
    "Allocation",
    "Allocator",
    "Certificate",
    "DirectionalLimit",
    "HoverMargin",
    "allocate",
    "attainable_slice",
    "hover_distances",
    "hover_thrust_margin",
    "hover_wrench_distance",
    "max_virtual_control",
    "plot_attainable_slices",
]
