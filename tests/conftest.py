"""Shared fixtures. Tests live in one folder per room (``analysis/``, ``flight/``, ``allocation/``,
``control/``, ``studies/``, ``plotting/``, ``cli/``), plus ``papers/`` (every number a paper
prints) and ``cross/`` (independent checks, properties, bad input, the architecture, the browser,
the wheel). Helper modules shared by tests (``without_slycot.py``) sit here, in ``tests/``, which
is put on ``sys.path`` so any test folder can import them."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from hypothesis import settings

import rotorfault as rf

#: ``tests/``: helper modules shared by the test folders are imported from here.
TESTS = Path(__file__).resolve().parent
if str(TESTS) not in sys.path:
    sys.path.insert(0, str(TESTS))

from quick_report import QuickReport, build_quick_report  # noqa: E402  (a helper module of tests/)

#: The pre-release run of the hostile-input harness (``--hypothesis-profile=long``, DEVELOPERS.md):
#: many examples, no deadline; ``tests/cross/hostile/hostile_runner.py`` spreads them over every
#: target within ``ROTORFAULT_HOSTILE_SECONDS`` per target.
settings.register_profile("long", max_examples=100_000, deadline=None)


@pytest.fixture(scope="session")
def pnpnpn() -> rf.Airframe:
    return rf.Airframe.preset("hexa-pnpnpn")


@pytest.fixture(scope="session")
def ppnnpn() -> rf.Airframe:
    return rf.Airframe.preset("hexa-ppnnpn")



@pytest.fixture(scope="session")
def quick_report(tmp_path_factory: pytest.TempPathFactory) -> QuickReport:
    """The quick report, built once per test session and shared by the tests that read it (the
    browser check, the JSON schema): each build flies every paper's quick flights."""
    return build_quick_report(tmp_path_factory.mktemp("reproduce") / "report")
