"""Controllers for :class:`rotorfault.Simulator` and their design: design in Python, run in Rust.

- :mod:`~rotorfault.control.linear`: :class:`OpenLoop`, :class:`LinearFeedback`, :class:`Lti`;
- :mod:`~rotorfault.control.tracking`: :class:`TrackingFeedback` (state feedback on a moving
  reference with a saturated error: reference shaping);
- :mod:`~rotorfault.control.allocated`: :class:`Allocated` (a virtual-control law plus
  constrained allocation);
- :mod:`~rotorfault.control.ke`: Ke et al.'s :class:`UniformPassiveFtc`, its gains and presets,
  and the N-matrix stability analysis;
- :mod:`~rotorfault.control.indi`: :class:`IndiController` (incremental nonlinear dynamic
  inversion fault-tolerant control after Sun et al.) and its :class:`IndiGains`;
- :mod:`~rotorfault.control.lanzon`: Lanzon et al.'s :class:`LanzonController` (robust feedback
  linearisation, H-infinity loop shaping, yaw-synchronised outer loop) and its design;
- :mod:`~rotorfault.control.lqr`: hover trim, linearisation and LQR hover controllers;
- :mod:`~rotorfault.control.systems`: the linear models as python-control systems
  (:class:`LinearModel`: a ``control.StateSpace`` with named signals and its operating point;
  :func:`lanzon_plant`);
- :mod:`~rotorfault.control.riccati`: :func:`design_lqr`, the one LQR (continuous and discrete
  Riccati equations, scipy's solvers on every install) and its checked :class:`LqrDesign`;
- :mod:`~rotorfault.control.stabilisability`: the scale-free PBH tests that name the modes no
  input moves (:func:`stabilisability`, :func:`detectability`);
- :mod:`~rotorfault.control.robust`: :func:`ncfsyn` (Glover-McFarlane H-infinity loop shaping)
  and the loop-shape weight;
- :mod:`~rotorfault.control.realisation`: state-space realisations built here (transfer
  functions, series, balancing, minimal and balanced realisations), the same on every install;
- :mod:`~rotorfault.control.norms`: the H-infinity norm (:func:`hinf_norm`, continuous and
  discrete).

Anything with ``core(dt_s)`` returning one of the extension's controller objects is a
:class:`Controller` the simulator runs in Rust; a plain Python callable ``f(t, x) -> commands``
is the slow path. The Rust controllers are declared once, in the bindings, and listed by
:mod:`~rotorfault.control.registry` (``docs/adding-a-controller.md``).

May import: ``rotorfault.flight`` (a design linearises the simulator's model),
``rotorfault.allocation``, ``rotorfault.analysis``, ``rotorfault._typing``, ``rotorfault._util``
and, on first use, ``rotorfault.plotting``; never ``studies``, ``papers`` or ``cli``.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from .._typing import Controller
from . import indi, ke, lqr
from .allocated import Allocated
from .indi import IndiController, IndiGains
from .ke import KeGains, UniformPassiveFtc
from .linear import LinearFeedback, Lti, OpenLoop
from .lqr import HoverTrim, hover_trim, linearize, lqr_hover, lqr_hover_allocated
from .riccati import LqrDesign, design_lqr
from .stabilisability import PbhTest, detectability, stabilisability
from .tracking import TrackingFeedback

if TYPE_CHECKING:
    from . import lanzon, norms, realisation, registry, robust, systems
    from .lanzon import LanzonController
    from .robust import NcfsynResult, ncfsyn
    from .systems import LinearModel, lanzon_plant

#: Names whose modules import python-control and scipy (about 1.5 s): loaded on first use, so
#: ``import rotorfault`` stays light (tests/cross/test_architecture.py); and the registry, so that
#: ``python -m rotorfault.control.registry`` runs it fresh.
_LAZY = {
    "registry": ("registry", None),
    "lanzon": ("lanzon", None),
    "robust": ("robust", None),
    "systems": ("systems", None),
    "LinearModel": ("systems", "LinearModel"),
    "lanzon_plant": ("systems", "lanzon_plant"),
    "norms": ("norms", None),
    "realisation": ("realisation", None),
    "LanzonController": ("lanzon", "LanzonController"),
    "NcfsynResult": ("robust", "NcfsynResult"),
    "ncfsyn": ("robust", "ncfsyn"),
}


def __getattr__(name: str) -> Any:
    if name not in _LAZY:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    module_name, attribute = _LAZY[name]
    module = importlib.import_module(f"{__name__}.{module_name}")
    value = module if attribute is None else getattr(module, attribute)
    globals()[name] = value
    return value

__all__ = [
    "Allocated",
    "Controller",
    "HoverTrim",
    "IndiController",
    "IndiGains",
    "KeGains",
    "LanzonController",
    "LinearFeedback",
    "LinearModel",
    "LqrDesign",
    "NcfsynResult",
    "Lti",
    "OpenLoop",
    "PbhTest",
    "TrackingFeedback",
    "UniformPassiveFtc",
    "design_lqr",
    "detectability",
    "hover_trim",
    "indi",
    "ke",
    "lanzon",
    "lanzon_plant",
    "linearize",
    "lqr",
    "lqr_hover",
    "lqr_hover_allocated",
    "ncfsyn",
    "norms",
    "realisation",
    "registry",
    "robust",
    "stabilisability",
    "systems",
]
