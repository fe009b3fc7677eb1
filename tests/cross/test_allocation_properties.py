"""Property-based tests (hypothesis, derandomized) of the active-set allocation's invariants.

- renumbering the actuators (columns, bounds, preferred) leaves the optimal objective unchanged
  (1e-12 of its scale) and the answer optimal (KKT residual 1e-9 of the bounds);
- widening the bounds never raises the optimal objective (it is a minimum over a larger set);
- scaling the virtual control and the bounds by s > 0 scales the commands by s (units: N -> kN);
- scaling every weight by the same factor changes nothing.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rotorfault.allocation import Allocator

SETTINGS = settings(derandomize=True, max_examples=150, deadline=None)


@st.composite
def problems(draw: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    m = draw(st.integers(4, 8))
    n = draw(st.integers(3, 6))
    seed = draw(st.integers(0, 2**32 - 1))
    rng = np.random.default_rng(seed)
    matrix = rng.uniform(-1, 1, size=(n, m))
    if draw(st.booleans()):  # rank deficient
        rank = int(rng.integers(1, min(n, m)))
        matrix = rng.uniform(-1, 1, size=(n, rank)) @ rng.uniform(-1, 1, size=(rank, m))
    weights = 10 ** rng.uniform(-2, 2, size=n)
    lower = rng.uniform(-2, 1, size=m)
    upper = lower + rng.uniform(0.1, 5, size=m)
    u_c = draw(st.floats(0.5, 4.0)) * (matrix @ rng.uniform(lower, upper)) + rng.uniform(-1, 1, size=n)
    return matrix, weights, lower, upper, u_c


def solve(matrix: np.ndarray, weights: np.ndarray, lower: np.ndarray, upper: np.ndarray, u_c: np.ndarray) -> tuple[np.ndarray, float, float, Allocator]:
    allocator = Allocator(matrix, weights=weights, bounds=(lower, upper))
    result = allocator.allocate(u_c)
    assert result.status == "optimal"
    value, kkt = allocator.objective(u_c, result.commands)
    return result.commands, value, kkt, allocator


def scale_of(u_c: np.ndarray, weights: np.ndarray) -> float:
    return max(0.5 * float(u_c @ (weights * u_c)), 1e-300)


@SETTINGS
@given(problems(), st.randoms(use_true_random=False))
def test_renumbering_actuators(problem: Any, random: Any) -> None:
    matrix, weights, lower, upper, u_c = problem
    _, value, _, _ = solve(matrix, weights, lower, upper, u_c)
    perm = list(range(matrix.shape[1]))
    random.shuffle(perm)
    commands, permuted_value, kkt, _ = solve(matrix[:, perm], weights, lower[perm], upper[perm], u_c)
    assert abs(permuted_value - value) <= 1e-12 * scale_of(u_c, weights)
    assert kkt <= 1e-9 * np.abs(np.r_[lower, upper]).max()


@SETTINGS
@given(problems(), st.floats(0.0, 2.0), st.floats(0.0, 2.0))
def test_wider_bounds_never_raise_the_objective(problem: Any, below: float, above: float) -> None:
    matrix, weights, lower, upper, u_c = problem
    _, value, _, _ = solve(matrix, weights, lower, upper, u_c)
    _, wider, _, _ = solve(matrix, weights, lower - below, upper + above, u_c)
    assert wider <= value + 1e-12 * scale_of(u_c, weights)


@SETTINGS
@given(problems(), st.sampled_from([1e-3, 0.5, 3.0, 1e3]))
def test_unit_scaling(problem: Any, s: float) -> None:
    matrix, weights, lower, upper, u_c = problem
    commands, value, _, _ = solve(matrix, weights, lower, upper, u_c)
    scaled, scaled_value, _, _ = solve(matrix, weights, s * lower, s * upper, s * u_c)
    assert abs(scaled_value - s**2 * value) <= 1e-11 * s**2 * scale_of(u_c, weights)
    # Commands themselves are unique only where the solution is; compare the produced virtual
    # control, which is unique whenever the weights are positive.
    np.testing.assert_allclose(matrix @ scaled, s * (matrix @ commands), rtol=0, atol=1e-9 * s * np.abs(u_c).max())


@SETTINGS
@given(problems(), st.sampled_from([1e-4, 0.1, 10.0, 1e4]))
def test_common_weight_factor_changes_nothing(problem: Any, k: float) -> None:
    matrix, weights, lower, upper, u_c = problem
    commands, _, _, _ = solve(matrix, weights, lower, upper, u_c)
    again, _, _, _ = solve(matrix, k * weights, lower, upper, u_c)
    np.testing.assert_allclose(matrix @ again, matrix @ commands, rtol=0, atol=1e-9 * np.abs(u_c).max())
