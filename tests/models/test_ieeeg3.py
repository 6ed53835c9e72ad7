"""PSS/E's IEEEG3 (stabctl.models.governors.ieeeg3, type 15): the DYR record fills its
tg_con columns, PSS/E's ThreeBus case with an IEEEG3 starts at rest, and the governor's
response is the closed form of its block diagram (PSS/E Model Library IEEEG3, IEEE
Committee Report 1973): the speed error plus P_ref minus the droops SIGMA + DELTA TR s/(1
+ s TR) of the gate, over TG (1 + s TP), is the gate's velocity, limited to [Uc, Uo];
its integral the gate, limited to [PMIN, PMAX]; the water column (A23 + s TW (A11 A23 -
A13 A21))/(1 + s A11 TW).  No PSS/E or ANDES run of IEEEG3 is stored (ANDES 2.0 has
none)."""

import governor_alone as alone
import numpy as np
import pytest

from stabctl.errors import CaseError
from stabctl.models import governors as gov

#: IEEEG3: TG TP Uo Uc PMAX PMIN SIGMA DELTA TR TW A11 A13 A21 A23 (PSS/E's typical
#: hydro values: 5 % permanent, 30 % transient droop; A11 A23 - A13 A21 = -1, so the
#: water column's high-frequency gain is -2 as the ideal (1 - s TW)/(1 + s TW/2))
VALUES = dict(
    TG=0.05,
    TP=0.04,
    Uo=0.1,
    Uc=-0.2,
    PMAX=1.0,
    PMIN=0.0,
    SIGMA=0.05,
    DELTA=0.3,
    TR=5.0,
    TW=1.0,
    A11=0.5,
    A13=1.0,
    A21=1.5,
    A23=1.0,
)
PM0 = 0.7

#: PSS/E's ThreeBus WPIDHY run with an IEEEG3 instead of the WPIDHY
imported = alone.threebus_fixture("IEEEG3", VALUES)


def test_record_fills_its_columns(imported):
    """TG in Ts, TP in Tc, Uo, Uc, PMAX, PMIN in Tmax, Tmin, TW in T4; SIGMA, DELTA, TR,
    A11, A13, A21, A23 in IEEEG3's own columns."""
    g = imported.governors
    names = ("type", "Ts", "Tc", "Uo", "Uc", "Tmax", "Tmin", "T4")
    assert [float(getattr(g, n)[0]) for n in names] == [15, 0.05, 0.04, 0.1, -0.2, 1, 0, 1]
    names = ("sigma", "delta", "Tr", "a11", "a13", "a21", "a23")
    assert [float(getattr(g, n)[0]) for n in names] == [0.05, 0.3, 5, 0.5, 1, 1.5, 1]


def test_imported_case_starts_at_rest(imported):
    """The whole case (GENROU, SEXS, IEEEG3) at its initial point: every derivative 0."""
    residual, where = alone.initial_residual(imported)
    assert residual < 1e-10, where


def _closed_form(s, v=VALUES):
    """IEEEG3's mechanical power over the speed deviation at s (inside its limits)."""
    droop = v["SIGMA"] + v["DELTA"] * v["TR"] * s / (1 + s * v["TR"])
    gate = -1.0 / (v["TG"] * s * (1 + s * v["TP"]) + droop)
    b1 = v["TW"] * (v["A11"] * v["A23"] - v["A13"] * v["A21"])
    return gate * (v["A23"] + s * b1) / (1 + s * v["A11"] * v["TW"])


def test_frequency_response_is_the_closed_form(imported):
    """From 0.01 to 10 Hz the governor's response of P_m to the speed (its derivatives
    and output linearised by central differences, exact for its linear blocks) is the
    closed form within 1e-7 (relative); its steady-state gain is -A23/SIGMA."""
    H, gain = alone.response_at_rest(imported, PM0)
    for freq, h in zip(alone.FREQS, H, strict=True):
        s = 2j * np.pi * freq
        assert abs(h - _closed_form(s)) < 1e-7 * abs(_closed_form(s)), freq
    assert gain == pytest.approx(-1.0 / 0.05, rel=1e-7)


def test_start_steps_and_limits_are_the_closed_form(imported):
    """At rest every derivative is 0 and P_ref = SIGMA Pm0/A23; the speed held d above
    rated settles on the droop line, Pm0 - A23 d/SIGMA; a step dP of P_ref settles at Pm0
    + A23 dP/SIGMA (after 1000 s: the slowest pole, about TR (1 + DELTA/SIGMA) = 35 s,
    has decayed); after a large step the velocity is held at Uo and the gate opens at Uo,
    then stops at PMAX (both limits non-windup)."""
    p, x, Pref = alone.started(alone.governor_row(imported), PM0)
    assert Pref[0] == pytest.approx(0.05 * PM0, rel=1e-15)
    P = p.packed(Pref)
    dx = np.zeros_like(x)
    gov.derivatives(P, x.copy(), 0, 1.0, PM0, dx)
    assert gov.pmech(P, x, 0, 1.0) == pytest.approx(PM0, rel=1e-15)
    assert np.max(np.abs(dx)) < 1e-15
    d = 1e-3
    assert gov.pmech(P, alone.settled(P, x, 1.0 + d, 1000.0), 0, 1.0 + d) == pytest.approx(
        PM0 - d / 0.05, rel=1e-7
    )
    dP = 1e-3
    P = p.packed(Pref + dP)
    assert gov.pmech(P, alone.settled(P, x, 1.0, 1000.0), 0, 1.0) == pytest.approx(
        PM0 + dP / 0.05, rel=1e-7
    )
    P = p.packed(Pref + 0.5)  # a large step: the pilot valve's input far above Uo TG
    slot = {name: i for i, name in enumerate(gov.STATE_NAMES[15])}
    for gate, moving in ((PM0, 0.1), (1.0, 0.0)):  # inside the gate's limits, at PMAX
        held = x.copy()
        held[slot["velocity"], 0], held[slot["gate"], 0] = 0.1, gate
        dx = np.zeros_like(held)
        gov.derivatives(P, held, 0, 1.0, PM0, dx)
        assert dx[slot["velocity"], 0] == 0.0  # the velocity held at Uo
        assert dx[slot["gate"], 0] == moving  # the gate opens at Uo, or stops at PMAX


def test_options_it_does_not_model_are_refused(imported):
    """PMAX below PMIN, Uo below Uc, A23 not positive, TG below 1e-3 s, a start-up gate
    outside [PMIN, PMAX]."""
    for changes, match in (
        ({"Tmin": 2.0}, r"field 'Tmax': must be >= Tmin = 2 \(governor type 15, IEEEG3"),
        ({"Uo": -0.5}, r"field 'Uo': must be >= 0, got -0.5"),
        ({"a23": 0.0}, r"field 'a23': must be > 0 \(governor type 15, IEEEG3"),
        ({"Ts": 0.0}, "Ts"),
        ({"Tmax": 0.6}, "initial power order 0.7000 pu outside"),
    ):
        with pytest.raises(CaseError, match=match):
            alone.started(alone.governor_row(imported, **changes), PM0)
