"""A certificate case holds the failure-table row it is derived from and reads the failed rotors,
the ACAIs and the hover points through it (issue 26: no copied fields); its repr, equality, hash,
pickle and ``to_dict`` are those of the dataclass it was (the CLI's output is unchanged)."""

from __future__ import annotations

import pickle

import pytest

import rotorfault as rf
from rotorfault.studies.certify import CertificateCase, certify


def test_a_case_reads_its_rows_fields_through_the_row() -> None:
    frame = rf.Airframe.preset("hexa-pnpnpn")
    certificate = certify(frame, max_failed=1)
    table = rf.failure_table(frame, max_failed=1, formula="facet-margin")
    assert len(certificate.cases) == len(table) == 7
    for case, row in zip(certificate.cases, table):
        assert case.failure_case == row
        assert (case.failed, case.acai, case.acai_give_up_yaw, case.hover_wrench, case.hover_wrench_give_up_yaw) == (
            row.failed, row.acai, row.acai_give_up_yaw, row.hover, row.hover_give_up_yaw)
    case = certificate.cases[1]
    # Rotor 1 of the PNPNPN hexa: hovers only by giving up yaw (the failure table says so above).
    assert (case.failed, case.hover, case.drop_axes) == ((1,), "give-up-yaw", ("yaw",))
    assert repr(case).startswith(f"CertificateCase(failed=(1,), hover='give-up-yaw', acai={case.acai!r}, acai_give_up_yaw=")
    assert "failure_case" not in repr(case) and repr(case).endswith("relaxed_hover=None)")
    assert list(certificate.to_dict()["cases"][1]) == list(CertificateCase.FIELDS)
    back = pickle.loads(pickle.dumps(case))
    assert back == case and hash(back) == hash(case) and back != certificate.cases[2]
    with pytest.raises(AttributeError):
        case.acai = 1.0  # type: ignore[misc]


def test_a_case_pickled_before_it_held_its_row_is_refused() -> None:
    # The old dataclass's pickle (class, then its fields as a dict, here only `failed`).
    old = (b"\x80\x04\x95\x00\x00\x00\x00\x00\x00\x00\x00\x8c\x1arotorfault.studies.certify\x94\x8c\x0fCertificateCase\x94\x93\x94"
           b")\x81\x94}\x94\x8c\x06failed\x94K\x01\x85\x94sb.")
    with pytest.raises(TypeError, match="pickled before .* make it again with certify"):
        pickle.loads(old)
