"""Types that cross the Rust/Python boundary once (issue 26): the settings Python users make
(``KeGains``, ``Drag``, ``DivergenceLimits``) are the extension's classes themselves, validated
once, by the core, with the core's messages; no Python mirror copies them field by field."""

from __future__ import annotations

import dataclasses
import math
import pickle

import pytest

import rotorfault as rf
from rotorfault import _rfcore
from rotorfault.control import ke

SETTINGS = [
    (ke.KeGains, "k_v", 0.5),
    (rf.Drag, "linear_n_s_m", 0.3),
    (rf.DivergenceLimits, "max_tilt_rad", 1.0),
]


def test_the_public_names_are_the_extension_classes() -> None:
    assert ke.KeGains is _rfcore.KeGains and rf.Drag is _rfcore.Drag and rf.DivergenceLimits is _rfcore.DivergenceLimits
    # A preset's gains come out of the core's TOML parser as they are: no conversion.
    assert type(ke.preset("ke-hil").gains) is _rfcore.KeGains
    assert ke.preset("ke-hil").gains == ke.KeGains()  # the core's Default is the ke-hil preset


@pytest.mark.parametrize(("cls", "field", "value"), SETTINGS)
def test_settings_behave_like_frozen_records(cls: type, field: str, value: float) -> None:
    default = cls()
    changed = default.replace(**{field: value})  # type: ignore[attr-defined]
    assert getattr(changed, field) == value and changed != default and changed == cls(**{field: value})
    assert hash(changed) == hash(cls(**{field: value})) and len({default, cls()}) == 1
    assert pickle.loads(pickle.dumps(changed)) == changed
    assert repr(changed).startswith(f"{cls.__name__}({cls.FIELDS[0]}=") and f"{field}={value!r}" in repr(changed)  # type: ignore[attr-defined]
    assert [getattr(default, f) for f in cls.FIELDS] == [getattr(cls(), f) for f in cls.FIELDS]  # type: ignore[attr-defined]
    with pytest.raises(AttributeError):
        setattr(default, field, value)
    with pytest.raises(TypeError, match=f"^k_q: not a field of {cls.__name__}"):
        default.replace(k_q=1.0)  # type: ignore[attr-defined]


def test_values_are_checked_once_by_the_core_with_its_messages() -> None:
    """The same messages as when the Python mirror forwarded them: the core's, naming the field."""
    with pytest.raises(ValueError, match=r"^k_omega: must be > 0.5 \(Theorem 1\), got 0.4"):
        ke.KeGains(k_omega=0.4)
    with pytest.raises(ValueError, match=r"^weights\[2\]"):
        ke.KeGains(weights=(1.0, 20.0, 0.0, 0.01))
    with pytest.raises(ValueError, match="^drag.linear_n_s_m: must be finite"):
        rf.Drag(linear_n_s_m=math.nan)
    with pytest.raises(ValueError, match="^drag.rotational_n_m_s: must be >= 0"):
        rf.Drag(rotational_n_m_s=-1.0)


def test_types_are_checked_at_the_boundary_naming_the_field() -> None:
    with pytest.raises(TypeError, match="^k_p: expected a real number, got str"):
        ke.KeGains(k_p="1")  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="^drag.linear_n_s_m: expected a real number, got bool"):
        rf.Drag(linear_n_s_m=True)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="^limits.max_speed_m_s: expected a real number, got list"):
        rf.DivergenceLimits(max_speed_m_s=[1.0])  # type: ignore[arg-type]
    with pytest.raises(ValueError, match=r"^weights: expected 4 entries \(w_f, w_p, w_q, w_r\), got 3"):
        ke.KeGains(weights=(1.0, 2.0, 3.0))
    import numpy as np

    assert ke.KeGains(k_p=np.float64(0.5), weights=np.array([1.0, 20.0, 20.0, 0.01])).weights == (1.0, 20.0, 20.0, 0.01)


def test_the_dataclass_functions_still_work_with_a_warning() -> None:
    gains = ke.KeGains()
    with pytest.warns(DeprecationWarning, match=r"KeGains\.replace\(\.\.\.\)"):
        changed = dataclasses.replace(gains, k_v=0.5)
    assert changed == gains.replace(k_v=0.5)
    with pytest.warns(DeprecationWarning):
        assert [f.name for f in dataclasses.fields(rf.Drag())] == list(rf.Drag.FIELDS)


def test_a_campaign_with_its_gains_travels_to_a_worker() -> None:
    """Campaigns are pickled to Dask workers with their gains (the chunk task)."""
    from rotorfault.studies import Campaign

    c = Campaign(runs=2, gains=ke.KeGains(k_v=0.25))
    back = pickle.loads(pickle.dumps(c))
    assert back == c and back.gains == ke.KeGains(k_v=0.25)
    assert Campaign.from_dict(c.to_dict()) == c
