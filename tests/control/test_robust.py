"""``rotorfault.control.ncfsyn``: Glover-McFarlane loop shaping from two Riccati equations, each
result checked by an independent computation:

- ``gamma_min`` against the Hankel singular values of the normalised left coprime factors
  (two Lyapunov equations), relative tolerance 1e-9;
- the achieved four-block norm ``||[I; K](I + G K)^-1 [I, G]||_inf`` of the central controller is
  <= gamma (bounded-real Hamiltonian test at gamma (1 + 1e-9)) and the loop is stable;
- ``gamma_min`` against python-control's ``hinfsyn`` (SLICOT sb10ad's gamma iteration) on the
  equivalent generalised plant, relative tolerance 1e-3;
- the loop-shape weight makes ``G W1 = diag(L)`` exactly (frequency responses, 1e-9 relative).
"""

from __future__ import annotations

import control as ct
import numpy as np
import pytest

from rotorfault.control import ncfsyn
from rotorfault.control import robust


def _plants() -> list[ct.StateSpace]:
    rng = np.random.default_rng(7)
    plants = []
    for n, p, m, proper in ((3, 2, 2, True), (4, 2, 2, False), (5, 3, 3, True), (2, 1, 1, False)):
        a = rng.normal(size=(n, n))
        plants.append(ct.ss(a, rng.normal(size=(n, m)), rng.normal(size=(p, n)),
                            np.zeros((p, m)) if proper else rng.normal(size=(p, m))))
    # An unstable plant and the paper's double-integrator-like channel.
    plants.append(ct.ss([[0, 1], [2, -1]], [[0], [1]], [[1, 0]], [[0]]))
    return plants


def _generalised(g: ct.StateSpace) -> ct.StateSpace:
    """Inputs [w1 (output disturbance), w2 (input disturbance), u], outputs [y, u, y]: the
    lower LFT with u = K y is the four-block problem."""
    a, b, c, d = (np.asarray(m, dtype=float) for m in (g.A, g.B, g.C, g.D))
    ny, nu = d.shape
    n = a.shape[0]
    b1 = np.hstack([np.zeros((n, ny)), b])
    c1 = np.vstack([c, np.zeros((nu, n))])
    d11 = np.block([[np.eye(ny), d], [np.zeros((nu, ny + nu))]])
    d12 = np.vstack([d, np.eye(nu)])
    d21 = np.hstack([np.eye(ny), d])
    return ct.ss(a, np.hstack([b1, b]), np.vstack([c1, c]), np.block([[d11, d12], [d21, d]]))


@pytest.mark.parametrize("index", range(5))
def test_gamma_min_equals_the_hankel_formula(index: int) -> None:
    g = _plants()[index]
    result = ncfsyn(g, np.eye(g.ninputs))
    assert result.gamma_min == pytest.approx(robust.hankel_gamma_min(g), rel=1e-9)
    assert result.gamma == pytest.approx(1.1 * result.gamma_min, rel=1e-15)
    assert result.stability_margin == pytest.approx(1 / result.gamma)


@pytest.mark.parametrize("index", range(5))
def test_central_controller_achieves_gamma(index: int) -> None:
    g = _plants()[index]
    result = ncfsyn(g, np.eye(g.ninputs), factor=1.05)
    block = robust.four_block(result.shaped_plant, result.shaped_controller)
    assert np.max(np.linalg.eigvals(block.A).real) < 0, "closed loop unstable"
    assert robust.hinf_norm_below(block, result.gamma * (1 + 1e-9))
    # ... and it is not far from it either (the central controller is not the optimum).
    assert robust.hinf_norm(block) > result.gamma_min * (1 - 1e-6)


@pytest.mark.parametrize("index", [0, 1, 2, 4])
def test_gamma_min_agrees_with_hinfsyn(index: int) -> None:
    pytest.importorskip("slycot")
    g = _plants()[index]
    _, _, gamma, _ = ct.hinfsyn(_generalised(g), g.noutputs, g.ninputs)
    assert robust.ncf_gamma_min(g) == pytest.approx(float(gamma), rel=1e-3)


def test_four_block_norm_of_a_known_loop() -> None:
    # G = 1/s, K = 1: the four-block matrix is [1; 1] [s, 1] / (s + 1), of rank one.
    g = ct.ss([[0.0]], [[1.0]], [[1.0]], [[0.0]])
    k = ct.ss(np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0)), [[1.0]])
    block = robust.four_block(g, k)
    # [1; 1] * [s, 1]/(s + 1): the rank-one product of norms sqrt(2) * sqrt(w^2 + 1)/|jw + 1| = sqrt(2).
    assert robust.hinf_norm(block) == pytest.approx(np.sqrt(2), rel=1e-5)
    # The optimum for 1/s: X = Z = 1, gamma_min = sqrt(2).
    assert robust.ncf_gamma_min(g) == pytest.approx(np.sqrt(2), rel=1e-12)


def test_loop_shape_weight_makes_the_target_shape() -> None:
    # A full-relative-degree plant: two double integrators with coupling and a first-order channel.
    a = np.array([[0, 0.5, 1, 0, 0], [-0.5, 0, 0, 1, 0], [0, 0, -1, 2, 0], [0, 0, -2, -1, 0], [0, 0, 0, 0, -3.0]])
    b = np.array([[0, 0, 0], [0, 0, 0], [3, 0, -1], [0, 2, 0], [0, 0, 5.0]])
    c = np.zeros((3, 5))
    c[0, 0] = c[1, 1] = c[2, 4] = 1
    g = ct.ss(a, b, c, 0)
    shape = robust.target_loop_shape(100.0)
    w = np.logspace(-2, 4, 40)
    gr = np.asarray(g(1j * w)).reshape(3, 3, -1)
    ls = np.asarray(shape(1j * w)).reshape(-1)
    gains = np.diag([1.0, 2.0, 0.5])
    # Exact inverse (margin 0: the plant's poles at +-0.5j are cancelled) ...
    w1 = robust.loop_shape_weight(g, shape, channel_gain=[1.0, 2.0, 0.5], margin_rad_s=0.0)
    wr = np.asarray(w1(1j * w)).reshape(3, 3, -1)
    gw = np.einsum("ijk,jlk->ilk", gr, wr)
    for k in range(len(w)):
        np.testing.assert_allclose(gw[:, :, k], gains * ls[k], rtol=1e-9, atol=1e-9 * abs(ls[k]))
    # ... which ncfsyn refuses (the cancelled undamped pair would stay in every closed loop).
    with pytest.raises(ValueError, match="not stabilisable"):
        ncfsyn(g, w1)
    # The default: the inverse of G(s + 1), so G W1 = G(s) G(s + 1)^-1 L.
    w1 = robust.loop_shape_weight(g, shape, channel_gain=[1.0, 2.0, 0.5])
    wr = np.asarray(w1(1j * w)).reshape(3, 3, -1)
    gs = np.asarray(g(1j * w + 1.0)).reshape(3, 3, -1)
    for k in range(len(w)):
        expected = gr[:, :, k] @ np.linalg.solve(gs[:, :, k], gains) * ls[k]
        np.testing.assert_allclose(gr[:, :, k] @ wr[:, :, k], expected, rtol=1e-8, atol=1e-8 * np.max(np.abs(expected)))
    result = ncfsyn(g, w1)
    assert np.max(np.linalg.eigvals(robust.four_block(g, result.controller).A).real) < 0
    # Lanzon's shape: 60 dB at low frequency, about 0 dB at the crossover, -40 dB/decade far above.
    mag = np.abs(ls)
    assert 20 * np.log10(abs(complex(shape(1e-4j)))) == pytest.approx(60, abs=0.01)
    assert abs(complex(shape(100j))) == pytest.approx(1.0, abs=0.01)
    hi = [abs(complex(shape(1j * f))) for f in (1e5, 1e6)]
    assert 20 * np.log10(hi[0] / hi[1]) == pytest.approx(40, abs=0.1)
    assert mag[0] > mag[-1]


def test_bad_input_names_the_field() -> None:
    g = _plants()[0]
    with pytest.raises(ValueError, match="factor: must be > 1"):
        ncfsyn(g, np.eye(2), factor=1.0)
    with pytest.raises(ValueError, match="w1: expected 2 outputs"):
        ncfsyn(g, np.eye(3))
    with pytest.raises(TypeError, match="plant: expected"):
        ncfsyn("G", np.eye(2))
    with pytest.raises(ValueError, match="crossover_rad_s: must be > 0"):
        robust.target_loop_shape(-1.0)
    with pytest.raises(ValueError, match="loop_shape: relative degree must be at least 2"):
        robust.loop_shape_weight(_plants()[4], ct.tf([1], [1, 1]) * 0 + ct.tf([1], [1, 1]))
    with pytest.raises(ValueError, match="plant: the shaped plant W2 G W1 is not stabilisable"):
        ncfsyn(ct.ss([[1.0]], [[0.0]], [[1.0]], [[0.0]]), np.eye(1))
