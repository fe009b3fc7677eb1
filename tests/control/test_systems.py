"""The linear models as python-control systems (issue 31): ``linearize`` takes the trim object
and returns a ``control.StateSpace`` with named states, inputs and outputs and its operating
point; the VPP and Lanzon models likewise; every design function takes the system; the tuples
of the previous release still come back, with a ``DeprecationWarning``, bit for bit the same."""

from __future__ import annotations

import numpy as np
import pytest

import rotorfault as rf
from rotorfault import vpp
from rotorfault.control import design_lqr, detectability, stabilisability
from rotorfault.control.linear import STATE_LABELS, STATE_NAMES

ct = pytest.importorskip("control")


@pytest.fixture(scope="module")
def sim() -> rf.Simulator:
    return rf.Simulator(rf.Airframe.preset("quad-x"), drag=rf.Drag(linear_n_s_m=0.1), wind=(2.0, 0.0, 0.0))


def test_linearize_takes_the_hover_trim_and_returns_a_named_state_space(sim: rf.Simulator) -> None:
    trim = rf.hover_trim(sim, position=(0, 0, -10))
    model = rf.linearize(sim, trim)
    assert isinstance(model, ct.StateSpace) and model.isctime()
    assert model.state_labels == list(STATE_NAMES) and model.output_labels == list(STATE_NAMES)
    assert model.input_labels == ["thrust_1", "thrust_2", "thrust_3", "thrust_4"]
    np.testing.assert_array_equal(model.C, np.eye(12))
    np.testing.assert_array_equal(model.D, np.zeros((12, 4)))
    np.testing.assert_array_equal(model.x_trim, trim.state)
    np.testing.assert_array_equal(model.u_trim, trim.command)
    assert model.command_columns == (0, 1, 2, 3) and model.state_descriptions == STATE_LABELS
    assert model.find_state("theta") == 7 and model.find_input("thrust_3") == 2
    # A pair (state, command) is an operating point too.
    again = rf.linearize(sim, (trim.state, trim.command))
    np.testing.assert_array_equal(again.A, model.A)


def test_the_tuple_form_warns_and_is_bit_for_bit_the_same(sim: rf.Simulator) -> None:
    trim = rf.hover_trim(sim, position=(0, 0, -10))
    model = rf.linearize(sim, trim)
    with pytest.warns(DeprecationWarning, match=r"linearize\(simulator, x_trim, u_trim\) returning \(A, B\) is deprecated"):
        a, b = rf.linearize(sim, trim.state, trim.command)
    assert np.array_equal(a, model.A) and np.array_equal(b, model.B)


def test_linearize_refuses_what_is_no_operating_point(sim: rf.Simulator) -> None:
    with pytest.raises(TypeError, match="trim: expected a HoverTrim"):
        rf.linearize(sim, np.zeros(12))
    with pytest.raises(ValueError, match="u_trim: expected 4 entries"):
        rf.linearize(sim, (np.zeros(12), np.zeros(3)))


def test_python_control_designs_on_it_agree_with_ours(sim: rf.Simulator) -> None:
    """The system goes straight into python-control (lqr, feedback) and into design_lqr: the same
    gain (to 1e-9, as in test_riccati) and the closed loop python-control builds from it has the
    design's eigenvalues; a LinearFeedback from the model's operating point is lqr_hover's."""
    trim = rf.hover_trim(sim, position=(0, 0, -10))
    model = rf.linearize(sim, trim)
    q = np.diag(1.0 / np.array([1.0] * 6 + [0.1] * 3 + [1.0] * 3) ** 2)
    r = np.eye(4) / (0.1 * sim.airframe.hover_thrust_n / 4) ** 2
    ours = design_lqr(model, q, r, dt_s=sim.dt_s)
    theirs = np.asarray(ct.lqr(model, q, r)[0])
    assert np.linalg.norm(ours.gain - theirs) <= 1e-9 * np.linalg.norm(theirs)
    assert np.array_equal(ours.gain, design_lqr((model.A, model.B), q, r, dt_s=sim.dt_s).gain)
    loop = ct.feedback(model, ct.ss([], [], [], ours.gain), sign=-1)
    np.testing.assert_allclose(np.sort_complex(loop.poles()), np.sort_complex(ours.closed_loop_eigenvalues), rtol=1e-9)
    hover = rf.lqr_hover(sim, position=(0, 0, -10))
    controller = rf.LinearFeedback(ours.gain, model.x_trim, model.u_trim, design=ours)
    assert np.array_equal(controller.gain, hover.gain) and np.array_equal(controller.u_trim, hover.u_trim)


def test_the_checks_name_the_systems_states() -> None:
    """Given the system alone, the PBH tests and design_lqr name its modes in its own state names
    (no state_names argument): the refusal of Wang's Sec. 3.4 layout, as the README prints it."""
    fixed = vpp.fixed_pitch(vpp.preset())
    model = vpp.linearize(fixed, vpp.fixed_pitch_trim(fixed, failed=()), pitch_fixed=True)
    test = stabilisability(model)
    assert not test.holds
    assert test.describe() == stabilisability(model.A, model.B, state_names=STATE_NAMES, state_labels=STATE_LABELS).describe()
    assert "no input moves yaw rate r together with p and q: 0.132 p + 0.132 q - r" in test.describe()
    with pytest.raises(ValueError, match="no input moves yaw rate r together with p and q: 0.132 p"):
        design_lqr(model, np.eye(12), np.eye(4))
    assert detectability(model).holds  # C = I sees every state
    with pytest.raises(TypeError, match="python-control StateSpace"):
        stabilisability(np.eye(2))


def test_the_vpp_model_is_a_state_space_of_the_healthy_channels() -> None:
    wang = vpp.preset()
    at = vpp.trim(wang, failed=(1,), speeds={3: 9000.0})
    model = vpp.linearize(wang, at)
    assert isinstance(model, ct.StateSpace)
    assert model.input_labels == ["omega_2", "alpha_2", "omega_3", "alpha_3", "omega_4", "alpha_4"]
    assert model.command_columns == (2, 3, 4, 5, 6, 7) and model.state_labels == list(STATE_NAMES)
    np.testing.assert_array_equal(model.u_trim, at.command)
    # The previous release's attribute names, for one release, warning.
    with pytest.warns(DeprecationWarning, match="LinearModel.a is deprecated"):
        assert np.array_equal(model.a, model.A)
    with pytest.warns(DeprecationWarning, match="LinearModel.columns is deprecated"):
        assert model.columns == model.command_columns
    old = vpp.VppLinearization(model.A, model.B, tuple(model.input_labels), model.command_columns)
    with pytest.warns(DeprecationWarning, match="VppLinearization is deprecated"):
        assert vpp.controllability(old).rank == vpp.controllability(model).rank == 12


def test_lanzons_plant_with_named_signals() -> None:
    from rotorfault.control import lanzon_plant
    from rotorfault.control.lanzon import LanzonVehicle

    vehicle = LanzonVehicle()
    plant = lanzon_plant(vehicle)
    assert plant.state_labels == ["phi", "theta", "p", "q", "dr"]
    assert plant.input_labels == ["du_f", "tau_q", "dtau_r"] and plant.output_labels == ["phi", "theta", "dr"]
    a, b = vehicle.linearisation()
    assert np.array_equal(plant.A, a) and np.array_equal(plant.B, b)
    assert np.array_equal(plant.C, vehicle.plant().C)


def test_lanzons_loop_shaping_design_names_every_signal() -> None:
    """The weight, the shaped plant, the synthesis plant and both controllers of Lanzon's design
    carry named signals, chained consistently: the controller reads the plant's outputs and drives
    its inputs; W1 reads the shaped inputs and drives the plant's inputs."""
    from rotorfault.control.lanzon import LanzonVehicle, design
    from rotorfault.control.systems import LANZON_INPUTS, LANZON_OUTPUTS, LANZON_STATES

    d = design(LanzonVehicle())
    plant = d.vehicle.plant()
    assert (plant.state_labels, plant.input_labels, plant.output_labels) == (
        list(LANZON_STATES), list(LANZON_INPUTS), list(LANZON_OUTPUTS))
    shaped_inputs = [f"shaped_{u}" for u in LANZON_INPUTS]
    assert d.w1.input_labels == shaped_inputs and d.w1.output_labels == list(LANZON_INPUTS)
    assert d.w1.state_labels == [f"w1_{i + 1}" for i in range(d.w1.nstates)]
    s = d.synthesis
    assert s.controller.input_labels == list(LANZON_OUTPUTS) and s.controller.output_labels == list(LANZON_INPUTS)
    assert s.controller.state_labels == s.shaped_controller.state_labels + d.w1.state_labels
    assert s.shaped_controller.input_labels == list(LANZON_OUTPUTS) and s.shaped_controller.output_labels == shaped_inputs
    assert s.shaped_plant.state_labels == d.w1.state_labels + list(LANZON_STATES)
    assert s.shaped_plant.input_labels == shaped_inputs and s.shaped_plant.output_labels == list(LANZON_OUTPUTS)
    assert s.synthesis_plant.state_labels == [f"gs_{i + 1}" for i in range(s.synthesis_plant.nstates)]
    assert s.synthesis_plant.input_labels == shaped_inputs
    # Names only: the matrices are those of the unnamed series connection.
    from rotorfault.control.realisation import series

    k = series(s.shaped_controller, d.w1)
    assert np.array_equal(np.asarray(k.A), np.asarray(s.controller.A))


def test_ncfsyn_names_unnamed_systems_by_role() -> None:
    """A plant and weight with python-control's default labels: the shaped plant's colliding state
    names are prefixed by their role, the controller keeps the plant's signal names."""
    import control as ct

    from rotorfault.control import ncfsyn

    plant = ct.ss([[-1.0]], [[1.0]], [[1.0]], [[0.0]])
    weight = ct.ss([[-0.1]], [[1.0]], [[1.0]], [[0.0]])
    result = ncfsyn(plant, weight)
    assert result.shaped_plant.state_labels == ["w1.x[0]", "plant.x[0]"]
    assert result.controller.input_labels == plant.output_labels
    assert result.controller.output_labels == plant.input_labels
    with pytest.raises(ValueError, match="states: expected 1 names, got 2"):
        from rotorfault.control.realisation import with_signals

        with_signals(plant, states=["a", "b"])
