from __future__ import annotations

import pytest

import rotorfault as rf


@pytest.fixture(scope="session")
def pnpnpn() -> rf.Airframe:
    return rf.Airframe.preset("hexa-pnpnpn")


@pytest.fixture(scope="session")
def ppnnpn() -> rf.Airframe:
    return rf.Airframe.preset("hexa-ppnnpn")
