"""Files that carry only data (issue 27): a name cannot add a line to an exported file (control
characters refused at construction, the exported PX4 file has exactly the expected parameter
lines), imports check parameter names, and a PX4 frame whose mass cannot be inferred (an
omnicopter) is a clear error naming the mass, given with ``mass_kg=`` or ``--mass``."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import rotorfault as rf
from rotorfault.cli import cli

INJECTED = "quad\n1\t1\tCBRK_IO_SAFETY\t22027\t6"


@pytest.mark.parametrize("name", [INJECTED, "a\rb", "tab\there", "bell\x07", "del\x7f", "nel\x85", "ls\u2028x", "bidi\u202eevil"])
def test_names_with_control_characters_are_refused_everywhere(name: str, tmp_path: Path) -> None:
    q = rf.Airframe.preset("quad-x")
    with pytest.raises(ValueError, match=r"name: must not contain control characters, got U\+"):
        rf.Airframe(q.arm_angle_rad, q.arm_length_m, q.spin, q.max_thrust_n, 1.0, [0.01, 0.01, 0.02], 0.05, name=name)
    with pytest.raises(ValueError, match="name: must not contain control characters"):
        rf.Airframe.from_rotors(position_m=q.position_m, spin=q.spin, max_thrust_n=q.max_thrust_n, mass_kg=1.0,
                                inertia_kg_m2=[0.01, 0.01, 0.02], drag_torque_ratio_m=0.05, name=name)
    with pytest.raises(ValueError, match="name: must not contain control characters"):
        q.with_parameters(name=name)
    text = q.to_toml().replace('name = "quad-x"', f"name = {rf.analysis.airframe.toml_string(name)}")
    with pytest.raises(ValueError, match="name: must not contain control characters"):
        rf.Airframe.from_toml_str(text)
    params = tmp_path / "frame.params"
    params.write_text(q.to_px4_params())
    with pytest.raises(ValueError, match="name: must not contain control characters"):
        rf.Airframe.from_px4_params(params, name=name)


def test_the_exported_px4_file_has_exactly_the_expected_lines() -> None:
    frame = rf.Airframe.from_toml_str(rf.Airframe.preset("hexa-pnpnpn").to_toml().replace('"hexa-pnpnpn"', '"a \\"quoted\\" name # ; = [x]"'))
    text = frame.to_px4_params(vehicle_id=3, component_id=7)
    parameter_lines = [line for line in text.split("\n") if line and not line.startswith("#")]
    m = frame.rotor_count
    expected = ["CA_ROTOR_COUNT"] + [f"CA_ROTOR{n}_{k}" for n in range(m) for k in ("PX", "PY", "PZ", "AX", "AY", "AZ", "CT", "KM")]
    expected += ["CA_R_REV", "MPC_THR_HOVER"]
    assert [line.split("\t")[2] for line in parameter_lines] == expected
    for line in parameter_lines:
        assert re.fullmatch(r"3\t7\t[A-Z0-9_]+\t-?[0-9.e+-]+\t(6|9)", line), line
    comments = [line for line in text.split("\n") if line.startswith("#")]
    assert len(comments) == 4 and len(text.splitlines()) == len(parameter_lines) + 4
    for bad in ("1\n1\t1\tCBRK_IO_SAFETY\t22027\t6", True, 256, -1):
        with pytest.raises((TypeError, ValueError), match="vehicle_id"):
            frame.to_px4_params(vehicle_id=bad)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("line", "message"),
    [
        ("1\t1\tCA_ROTOR0_PX;rm\t0.1\t9", "is not a PX4 parameter name"),
        ("1\t1\tCA_ROTOR0_PX_TOO_LONG_NAME\t0.1\t9", "is not a PX4 parameter name"),
        ("1\t1\tCA_ROTOR_COUNT\t4\t6", "CA_ROTOR_COUNT is given twice"),
        ("x\t1\tMPC_XY_P\t4\t9", "vehicle id must be a whole number"),
        ("1\t1\tMPC_XY_P\t4\tfloat", "type must be a whole number"),
        ("1\t1\tCA_ROTOR0\u2028CT\t4\t9", "expected 'vehicle component NAME value type'"),
    ],
)
def test_imports_check_parameter_names(tmp_path: Path, line: str, message: str) -> None:
    path = tmp_path / "bad.params"
    path.write_text(rf.Airframe.preset("quad-x").to_px4_params() + line + "\n")
    with pytest.raises(ValueError, match=message):
        rf.Airframe.from_px4_params(path)


def omnicopter_params() -> str:
    """PX4's omnicopter shape: 8 reversible rotors on the cube's corners, axes along the space
    diagonals, half pointing up and half down (sum of CT x -AZ = 0), with MPC_THR_HOVER."""
    lines = ["1\t1\tCA_ROTOR_COUNT\t8\t6", "1\t1\tCA_R_REV\t255\t6", "1\t1\tMPC_THR_HOVER\t0.5\t9"]
    corners = [(x, y, z) for x in (1, -1) for y in (1, -1) for z in (1, -1)]
    for n, (x, y, z) in enumerate(corners):
        axis = np.array([y * z, x * z, -(1.0 if n % 2 else -1.0)]) / math.sqrt(3)
        for key, value in zip(("PX", "PY", "PZ", "AX", "AY", "AZ"), (0.2 * x, 0.2 * y, 0.2 * z, *axis)):
            lines.append(f"1\t1\tCA_ROTOR{n}_{key}\t{float(value)!r}\t9")
        lines.append(f"1\t1\tCA_ROTOR{n}_KM\t{0.05 if n % 2 else -0.05}\t9")
    return "\n".join(lines) + "\n"


def test_an_omnicopter_names_the_missing_mass_and_takes_it(tmp_path: Path) -> None:
    path = tmp_path / "omni.params"
    path.write_text(omnicopter_params())
    with pytest.raises(ValueError, match=r"mass_kg: cannot be inferred: MPC_THR_HOVER = 0.5 .* pass mass_kg= \(CLI: --mass\)"):
        rf.Airframe.from_px4_params(path)
    omni = rf.Airframe.from_px4_params(path, mass_kg=1.3)
    assert omni.mass_kg == 1.3 and omni.is_fully_actuated
    text = omni.to_px4_params()  # no ZeroDivisionError: the mass travels in its comment
    assert "MPC_THR_HOVER" not in text
    back = tmp_path / "back.params"
    back.write_text(text)
    assert rf.Airframe.from_px4_params(back).mass_kg == 1.3
    runner = CliRunner()
    refused = runner.invoke(cli, ["certify", "-a", str(path)])
    assert refused.exit_code == 1 and "mass_kg: cannot be inferred" in refused.output and "--mass" in refused.output
    given = runner.invoke(cli, ["certify", "-a", str(path), "--mass", "1.3", "--json", "-"])
    assert given.exit_code == 0, given.output
    acai = runner.invoke(cli, ["acai", "-a", str(path), "--mass", "1.3"])
    assert acai.exit_code == 0, acai.output
    wrong = runner.invoke(cli, ["acai", "-a", "quad-x", "--mass", "1.3"])
    assert wrong.exit_code == 1 and "mass_kg: only a PX4 .params airframe" in wrong.output
