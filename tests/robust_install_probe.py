"""The design results that must not depend on the install (issue 25), as one JSON-able dict:
run in the test process (slycot installed) and in a subprocess where slycot cannot be imported
(tests/without_slycot.py), then compared by tests/cross/test_robust_install.py."""

from __future__ import annotations

from typing import Any

import numpy as np

FREQUENCIES_RAD_S = np.logspace(-2, 4, 25)


def _complex(values: np.ndarray) -> list[list[float]]:
    flat = np.asarray(values, dtype=complex).ravel()
    return [[float(v.real), float(v.imag)] for v in flat]


def _response(system: Any) -> list[list[list[float]]]:
    """The frequency response, one flattened matrix per frequency (compared normwise)."""
    from rotorfault.control.realisation import frequency_response

    return [_complex(m) for m in frequency_response(system, FREQUENCIES_RAD_S)]


def _poles(a: np.ndarray) -> list[list[float]]:
    eig = np.linalg.eigvals(np.asarray(a, dtype=float))
    return _complex(np.array(sorted(eig, key=lambda z: (z.real, z.imag))))


def results() -> dict[str, Any]:
    import control as ct
    import scipy.signal

    from rotorfault.control import lanzon, norms, realisation, robust

    out: dict[str, Any] = {"slycot": bool(ct.exception.slycot_check())}
    for izz in (1.16e-3, 1.16e-2):
        vehicle = lanzon.LanzonVehicle(inertia_zz_kg_m2=izz)
        for crossover in (100.0, 30.0):  # the paper's design (cases a and b) and ours (case c)
            d = lanzon.design(vehicle, crossover_rad_s=crossover)
            e = d.evidence
            ad, bd, cd, dd = d.discretise(1e-3)
            out[f"lanzon izz={izz:g} crossover={crossover:g}"] = {
                "gamma_min": d.gamma_min,
                "gamma": d.gamma,
                "gamma_min_hankel": e.gamma_min_hankel,
                "achieved_norm": e.achieved_norm,
                "states": [e.full_states, e.synthesis_states, d.controller.nstates],
                "controller_response": _response(d.controller),
                "closed_loop_poles": _complex(np.array(sorted(e.closed_loop_poles, key=lambda z: (z.real, z.imag)))),
                "discrete_controller_poles": _poles(ad),
                "discrete_controller_dc_response": [_complex(cd @ np.linalg.solve(np.eye(ad.shape[0]) - ad, bd) + dd)],
            }
    rng = np.random.default_rng(11)
    plants = [ct.tf([1], [1, 0]), ct.tf([[[1, 2], [1]], [[3], [1, 0, 4]]], [[[1, 3, 2], [1, 5]], [[1, 1], [1, 2, 9]]])]
    for n, m in ((3, 2), (5, 3)):
        plants.append(ct.ss(rng.normal(size=(n, n)), rng.normal(size=(n, m)), rng.normal(size=(m, n)), np.zeros((m, m))))
    out["ncf_gamma_min"] = [robust.ncf_gamma_min(g) for g in plants]
    out["hankel_gamma_min"] = [robust.hankel_gamma_min(g) for g in plants]
    systems = [
        ct.tf([1e9], [1, 1e9]),
        ct.tf([1e-9], [1, 1e-9]),
        ct.tf([1, 0.2, 100], [1, 0.02, 100]),
        ct.ss([[0.5, 0.1], [0.0, -0.3]], [[1.0], [1.0]], [[1.0, 0.0]], [[0.2]], 0.01),
        ct.tf([[[1], [2, 1]], [[1, 0], [3]]], [[[1, 1], [1, 4]], [[1, 2, 5], [1, 3]]]),
    ]
    peaks = [norms.peak_gain(s) for s in systems]
    out["hinf_norm"] = [[p.gain, p.frequency_rad_s] for p in peaks]
    wc = 30.0
    a, b, c, d = scipy.signal.tf2ss([wc * 10 * wc], np.polymul([1, wc / 1e3], [1, 10 * wc]))
    plant = lanzon.LanzonVehicle().plant()
    shaped = realisation.series(robust.loop_shape_weight(plant, realisation.state_space(a, b, c, d)), plant)
    minimal = [realisation.minimal_realisation(shaped), realisation.minimal_realisation(systems[4]),
               realisation.realise_transfer_function(systems[1])]
    out["minimal_realisation"] = [
        {"states": g.nstates, "response": _response(g)} for g in minimal
    ]
    return out
