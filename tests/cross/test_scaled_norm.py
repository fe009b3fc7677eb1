"""The package's one Euclidean norm safe at every magnitude (``rotorfault._util.numeric.scaled_norm``,
issue 27): NumPy 2's ``np.linalg.norm`` overflows the squares of entries of 1e200 and underflows
those of 1e-200. Where the plain norm is exact the scaled one is the same to the last bit (so
using it changes no result); where the plain one overflows or underflows this one is the true
norm; and a user's file whose axes hold such magnitudes is read as the directions it gives."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import rotorfault as rf
from rotorfault._util.numeric import scaled_norm

DATA = Path(__file__).resolve().parents[1] / "data"


def test_bit_identical_to_numpy_where_numpy_is_exact() -> None:
    rng = np.random.default_rng(27)
    for k in range(600):
        shape = [(3,), (5, 4), (4, 2, 3)][k % 3]
        x = rng.standard_normal(shape) * 10.0 ** rng.uniform(-120, 120)
        if k % 5 == 0:
            x = x + 1j * rng.standard_normal(shape) * 10.0 ** rng.uniform(-120, 120)
        for axis in [None, 0, -1, *([(1, 2)] if len(shape) == 3 else [])]:
            expected = np.linalg.norm(x, axis=axis)
            assert np.array_equal(np.asarray(scaled_norm(x, axis=axis)), np.asarray(expected)), (k, axis)
    assert isinstance(scaled_norm([3.0, 4.0]), float) and scaled_norm([3.0, 4.0]) == 5.0


@pytest.mark.parametrize("scale", [1e-300, 1e-200, 1e200, 1e300, 2.0**-1070])
def test_true_norm_where_numpy_overflows_or_underflows(scale: float) -> None:
    x = np.array([3.0, 4.0, 0.0]) * scale
    assert scaled_norm(x) == pytest.approx(5.0 * scale, rel=1e-15) if scale > 1e-300 else scaled_norm(x) > 0
    rows = np.array([[3.0, 4.0], [6.0, 8.0], [0.0, 0.0]]) * scale
    np.testing.assert_allclose(scaled_norm(rows, axis=1) / scale, [5.0, 10.0, 0.0], rtol=1e-15)
    assert scaled_norm(np.array([1e300, 1e300])) == math.hypot(1e300, 1e300)
    # Non-finite entries as NumPy gives them; empty slices are 0.
    assert scaled_norm([math.inf, 1.0]) == math.inf and math.isnan(scaled_norm([math.nan, 1.0]))
    np.testing.assert_array_equal(scaled_norm(np.zeros((2, 0)), axis=1), [0.0, 0.0])


@pytest.mark.parametrize("scale", [1e-200, 1e200])
def test_px4_thrust_axes_of_any_magnitude_are_their_directions(tmp_path: Path, scale: float) -> None:
    """A PX4 file's ``CA_ROTORn_AX/AY/AZ`` are directions (PX4 normalises them): (0, 0, -1e-200)
    was read as a zero axis and refused, (0, 0, -1e200) as an infinite one."""
    text = (DATA / "px4-quad-x.params").read_text()
    axes = "".join(f"1\t1\tCA_ROTOR{n}_AX\t0\t9\n1\t1\tCA_ROTOR{n}_AY\t0\t9\n1\t1\tCA_ROTOR{n}_AZ\t{-scale!r}\t9\n" for n in range(4))
    path = tmp_path / "scaled-axes.params"
    path.write_text(text + axes)
    scaled = rf.Airframe.from_px4_params(path, name="quad")
    plain = rf.Airframe.from_px4_params(DATA / "px4-quad-x.params", name="quad")
    np.testing.assert_array_equal(scaled.effectiveness_matrix(), plain.effectiveness_matrix())
    np.testing.assert_array_equal(scaled.thrust_axis, plain.thrust_axis)
