"""PSS/E's IEEEG2 (stabctl.models.governors.ieeeg2, type 14): the DYR record fills the
shared tg_con columns, PSS/E's ThreeBus case with an IEEEG2 starts at rest, and the
governor's response is the closed form of its block diagram (IEEE Committee Report 1973,
PSS/E Model Library IEEEG2): K (1 + s T2)/((1 + s T1)(1 + s T3)) on the speed error, the
gate clamped to [PMIN, PMAX], the water column (1 - s T4)/(1 + s T4/2).  No PSS/E or
ANDES run of IEEEG2 is stored (ANDES 2.0 has none)."""

import governor_alone as alone
import numpy as np
import pytest

from stabctl.errors import CaseError
from stabctl.models import governors as gov

#: IEEEG2: K T1 T2 T3 PMAX PMIN T4 (K = 1/R for a 5 % droop)
VALUES = dict(K=20.0, T1=0.25, T2=0.1, T3=0.1, PMAX=1.0, PMIN=0.0, T4=1.0)
PM0 = 0.7

#: PSS/E's ThreeBus WPIDHY run with an IEEEG2 instead of the WPIDHY
imported = alone.threebus_fixture("IEEEG2", VALUES)


def test_record_fills_the_shared_columns(imported):
    """K in invR, the lag T1 in Tc, the lead T2 in T3, the lag T3 in Ts, PMAX, PMIN in
    Tmax, Tmin, T4 in T4."""
    g = imported.governors
    names = ("type", "invR", "Tc", "T3", "Ts", "Tmax", "Tmin", "T4")
    assert [float(getattr(g, n)[0]) for n in names] == [14, 20.0, 0.25, 0.1, 0.1, 1.0, 0.0, 1.0]


def test_imported_case_starts_at_rest(imported):
    """The whole case (GENROU, SEXS, IEEEG2) at its initial point: every derivative 0."""
    residual, where = alone.initial_residual(imported)
    assert residual < 1e-10, where


def _closed_form(s, v=VALUES):
    """IEEEG2's mechanical power over the speed deviation at s (within the gate limits)."""
    governor = -v["K"] * (1 + s * v["T2"]) / ((1 + s * v["T1"]) * (1 + s * v["T3"]))
    return governor * (1 - s * v["T4"]) / (1 + s * v["T4"] / 2)


def test_frequency_response_is_the_closed_form(imported):
    """From 0.01 to 10 Hz the governor's response of P_m to the speed (its derivatives
    and output linearised by central differences, exact for its linear blocks) is the
    closed form within 1e-7 (relative); its steady-state gain is -K."""
    H, gain = alone.response_at_rest(imported, PM0)
    for freq, h in zip(alone.FREQS, H, strict=True):
        s = 2j * np.pi * freq
        assert abs(h - _closed_form(s)) < 1e-7 * abs(_closed_form(s)), freq
    assert gain == pytest.approx(-20.0, rel=1e-7)


def test_steps_settle_as_the_closed_form_says(imported):
    """A step dP of P_ref: the water column first moves the power the other way, by -2
    dP (its high-frequency gain), then it settles at Pm0 + dP; the speed held d above
    rated: Pm0 - K d; a step beyond PMAX: the gate clamped, the power PMAX."""
    p, x, Pref = alone.started(alone.governor_row(imported), PM0)
    dP = 0.01
    P = p.packed(Pref + dP)
    assert gov.pmech(P, x, 0, 1.0) == pytest.approx(PM0 - 2 * dP, rel=1e-14)
    assert gov.pmech(P, alone.settled(P, x, 1.0, 60.0), 0, 1.0) == pytest.approx(PM0 + dP, rel=1e-8)
    d = 1e-3
    P = p.packed(Pref)
    assert gov.pmech(P, alone.settled(P, x, 1.0 + d, 60.0), 0, 1.0 + d) == pytest.approx(
        PM0 - 20.0 * d, rel=1e-8
    )
    P = p.packed(Pref + 0.5)
    assert gov.pmech(P, alone.settled(P, x, 1.0, 60.0), 0, 1.0) == pytest.approx(1.0, rel=1e-8)


def test_options_it_does_not_model_are_refused(imported):
    """PMAX below PMIN, a lead T2 without its lag T1, a start-up power outside [PMIN,
    PMAX]."""
    for changes, match in (
        ({"Tmin": 2.0}, r"field 'Tmax': must be >= Tmin = 2 \(governor type 14, IEEEG2"),
        ({"Tc": 0.0}, "IEEEG2's lead T2 needs its lag T1"),
        ({"Tmax": 0.6}, "initial power order 0.7000 pu outside"),
    ):
        with pytest.raises(CaseError, match=match):
            alone.started(alone.governor_row(imported, **changes), PM0)
