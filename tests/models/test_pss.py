"""PSS models, one by one (stabctl.models.pss): rest at the initial point, the output's
jump at an input step against the transfer function's high-frequency gain, the output
limits, the named packed layout."""

import numpy as np
import pytest

from stabctl.case import PssTable
from stabctl.errors import CaseError
from stabctl.io import load_case
from stabctl.models import pss as pss_

#: pss_con rows (PST manual 3.30 Table 13; stabctl types 3, 4)
PST_SPEED = [1, 1, 200.0, 10.0, 0.05, 0.02, 3.0, 5.4, 0.2, -0.05]
PST_POWER = [2] + PST_SPEED[1:]
#: PSS/E IEEEST on speed: K_w = 2, T_w = 5, lead-lags (0.2/0.05, 0.3/0.1, 0.4/0.2), K1 = 10,
#: input lag Tr1 = 0.02, filter 1/(1 + 0.1 s)
PSSE = [
    3,
    1,
    2.0,
    5.0,
    0.2,
    0.05,
    0.3,
    0.1,
    0.5,
    -0.5,
    0.4,
    0.2,
    1,
    10.0,
    0.02,
    0,
    0,
    0,
    0.1,
    0,
    0,
    0,
    0,
    0,
]
#: STAB2A: K2 T2 = 1.5 (K2 = 0.5, T2 = 3), K3 = 0.8, T3 = 0.5, K4 = 0.3, K5 = 1.2, T5 = 0.4
STAB2A = [4, 1, 1.5, 3.0, 0, 0, 0, 0, 0.5, -0.5, 1.2, 0.4, 0, 0.8, 0.5, 0, 0.3, 0]
OMEGA0, PE0 = 1.0, 0.7  # initial speed (pu), power (machine base)


def pss_row(**fields):
    """A pss_con row (every declared column, 0 where not given) from field names."""
    row = [0.0] * len(pss_.PSS.names)
    for name, v in fields.items():
        row[pss_.PSS.col(name) - 1] = float(v)
    return row


#: PSS2A of PSS/E's PSS2A run (tests/data/psse_runs/PSS2A: speed and power inputs, Tw4 =
#: T6 = 0 absent, ramp-tracking filter M = 5, N = 1, two lead-lags)
PSS2A = pss_row(
    type=5, machine=1, input1=1, input2=3, M=5, N=1, Tw=1.5, Tw2=1.5, Tr1=0.0, Tw3=1.5,
    Tw4=0.0, Tr2=1.5, K2=0.1875, Ks3=1.0, T8=0.5, T9=0.1, K1=2.0, T1=0.59451, T2=0.0447,
    T3=0.59451, T4=0.0447, ymax=0.1, ymin=-0.1,
)  # fmt: skip
#: PSS2B: PSS2A with input limits (the power's [0.6, 0.8] around PE0) and T10/T11
PSS2B = PSS2A.copy()
_B = dict(type=6, T5=0.2, T6=0.1, VS1MAX=0.1, VS1MIN=-0.1, VS2MAX=0.8, VS2MIN=0.6)
for _name, _v in _B.items():
    PSS2B[pss_.PSS.col(_name) - 1] = _v
#: PSS2C: PSS2B with T12/T13 and the output logic (on at 0.65 pu and above, off at 0.6)
PSS2C = PSS2B.copy()
for _name, _v in dict(type=7, T12=0.3, T13=0.15, PSSON=0.65, PSSOFF=0.6).items():
    PSS2C[pss_.PSS.col(_name) - 1] = _v
ROWS = {
    "PST speed": PST_SPEED,
    "PST power": PST_POWER,
    "PSS/E": PSSE,
    "STAB2A": STAB2A,
    "PSS2A": PSS2A,
    "PSS2B": PSS2B,
    "PSS2C": PSS2C,
}


def params(row):
    case = load_case("kundur")
    return pss_.pss_params(case.replace(pss=PssTable.from_matrix([row])))


def started(row, omega=OMEGA0, pe=PE0):
    """(P, x) of a PSS at rest at speed omega and power pe."""
    p = params(row)
    u1, u2 = pss_.pss_inputs(p, np.array([omega]), np.array([pe]))
    return p.packed(), pss_.initialise(p, u1, u2, np.array([pe]))


def output(P, x, omega=OMEGA0, pe=PE0):
    dx = np.full_like(x, np.nan)
    return pss_.output_and_derivatives(P, x, 0, omega, pe, 1.0, dx), dx


@pytest.mark.parametrize("name", sorted(ROWS))
def test_initial_point_is_at_rest(name):
    """At the initial point the output is 0 and every derivative 0 (washouts at their
    input; the PSS/E filter of DC gain 1 at its input)."""
    P, x = started(ROWS[name])
    y, dx = output(P, x)
    assert y == pytest.approx(0.0, abs=1e-15)
    assert np.abs(dx[: len(pss_.STATE_NAMES[ROWS[name][0]])]).max() < 1e-13


def test_pst_speed_pss_jumps_by_its_high_frequency_gain():
    """PST pss: K s T_w/(1 + s T_w) (1 + s T_1)/(1 + s T_2) (1 + s T_3)/(1 + s T_4) on the
    speed; a step dw gives y(0+) = K dw T_1 T_3/(T_2 T_4) (K = column 3 / T_w)."""
    P, x = started(PST_SPEED)
    dw = 1e-5
    y, _ = output(P, x, omega=OMEGA0 + dw)
    assert y == pytest.approx(200.0 / 10.0 * dw * 0.05 * 3.0 / (0.02 * 5.4), rel=1e-9)


def test_pst_power_pss_takes_the_power_and_is_limited():
    """PST pss type 2 on the electrical power; its output clipped to [ymin, ymax]."""
    P, x = started(PST_POWER)
    dp = 1e-6
    assert output(P, x, pe=PE0 + dp)[0] == pytest.approx(
        20.0 * dp * 0.05 * 3.0 / (0.02 * 5.4), rel=1e-7
    )
    assert output(P, x, pe=PE0 + 1.0)[0] == 0.2
    assert output(P, x, pe=PE0 - 1.0)[0] == -0.05


def test_psse_stabiliser_jump_and_filter():
    """IEEEST: K1/(1 + s Tr1), filter, K_w s/(1 + s T_w), three lead-lags: the lagged
    input and the filter make the output continuous at a speed step, and with both
    absent it jumps by K1 dw K_w/T_w T1 T3 T5/(T2 T4 T6)."""
    P, x = started(PSSE)
    dw = 1e-5
    assert output(P, x, omega=OMEGA0 + dw)[0] == pytest.approx(0.0, abs=1e-15)
    row = PSSE[:14] + [0.0] + PSSE[15:18] + [0.0] * 6
    P, x = started(row)
    assert output(P, x, omega=OMEGA0 + dw)[0] == pytest.approx(
        10.0 * dw * 2.0 / 5.0 * 0.2 * 0.3 * 0.4 / (0.05 * 0.1 * 0.2), rel=1e-9
    )


def test_psse_filter_is_its_transfer_function():
    """The filter 1/(1 + A1 s), A1 = 0.1 s, in controllable form (state z, output w = c_0
    z): w moves at (v - w)/A1 for its input v = K1 dw (the lag Tr1 at its new value)."""
    P, x = started(PSSE)
    dw = 1e-3
    v = 10.0 * dw
    x[0, 0], x[2, 0] = v, 0.3 * v / P[0, pss_.S.FC0]
    _, dx = output(P, x, omega=OMEGA0 + dw)
    w = P[0, pss_.S.FC0] * x[2, 0]
    assert P[0, pss_.S.FC0] * dx[2, 0] == pytest.approx((v - w) / 0.1, rel=1e-12)


def test_stab2a_jump_through_three_washouts():
    """STAB2A: -(K_2 T_2 s/(1 + s T_2))^3 on the power, K_3/(1 + s T_3) + K_4, then
    (K_5/(1 + s T_5))^2; with T_3 and T_5 absent a power step dp gives
    y(0+) = -K_5^2 (K_3 + K_4) (K_2)^3 dp."""
    row = list(STAB2A)
    row[11] = row[14] = 0.0  # T_5 (column 12), T_3 (column 15)
    P, x = started(row)
    dp = 1e-6
    assert output(P, x, pe=PE0 + dp)[0] == pytest.approx(
        -(1.2**2) * (0.8 + 0.3) * 0.5**3 * dp, rel=1e-8
    )


def test_pst_pss_first_lead_lag_needs_its_lag():
    """PST's pss always has its first lead-lag: T_2 below 1e-3 s (which would make the
    block absent) is refused."""
    with pytest.raises(
        CaseError, match=r"pss_con row 1 \(machine 1\), field 'T2': the first lead-lag"
    ):
        params(PST_SPEED[:5] + [5e-4] + PST_SPEED[6:])


def test_layout_names_every_packed_column_once():
    assert pss_.S._fields == tuple(name for name, _ in pss_.PACKED)
    assert params(PSSE).packed().shape == (1, len(pss_.S) + pss_.N_OWN)


@pytest.mark.parametrize("name", sorted(ROWS))
def test_output_is_cut_off_outside_vcl_vcu_while_the_states_move_on(name):
    """With VCU = 1.2, VCL = 0.8 (pss_con columns 25-26; PSS/E IEEEST, ANDES ``OLIM``) the
    output is 0 at a terminal voltage of 0.7 or 1.3 pu and unchanged at 1.0 pu; the
    derivatives are the same at all three (the blocks run on); VCU = VCL = 0: no cut-off."""
    row = list(ROWS[name]) + [0.0] * (26 - len(ROWS[name]))
    cut = list(row)
    cut[24], cut[25] = 1.2, 0.8
    P, x = started(cut)
    P0, _ = started(row)
    x = x + 0.01  # away from rest: every type's output moves
    ys, dxs = [], []
    for vt in (1.0, 0.7, 1.3):
        dx = np.zeros_like(x)
        ys.append(pss_.output_and_derivatives(P, x, 0, OMEGA0 + 0.01, PE0 + 0.1, vt, dx))
        dxs.append(dx)
    dx = np.zeros_like(x)
    free = pss_.output_and_derivatives(P0, x, 0, OMEGA0 + 0.01, PE0 + 0.1, 0.1, dx)
    assert ys[0] == free != 0 and ys[1] == ys[2] == 0.0
    assert np.array_equal(dxs[0], dxs[1]) and np.array_equal(dxs[0], dxs[2])


def test_pss2_jump_through_its_chain():
    """PSS2A with the input lags and the ramp-tracking filter absent (T6 = T7 = 0, N =
    0): a power step dp passes both washouts of input 2 (Tw4 absent: one), KS2, then
    KS3 KS2 dp - KS2 dp = 0 into KS1 (the filter's input minus input 2's branch); a speed
    step dw gives KS1 dw T1 T3/(T2 T4) (IEEE 421.5 PSS2A at high frequency)."""
    row = list(PSS2A)
    for name in ("Tr1", "Tr2", "N"):
        row[pss_.PSS.col(name) - 1] = 0.0
    P, x = started(row)
    assert output(P, x, pe=PE0 + 1e-4)[0] == pytest.approx(0.0, abs=1e-15)
    dw = 1e-5
    assert output(P, x, omega=OMEGA0 + dw)[0] == pytest.approx(
        2.0 * dw * (0.59451 / 0.0447) ** 2, rel=1e-12
    )


def test_pss2_ramp_tracking_filter_is_its_transfer_function():
    """The filter (1 + s T8)/(1 + s T9)^M (N = 1, M = 5) realised as M - 1 lags and a
    lead-lag: its states move at (u - x)/T9 (lags) and ((1 - T8/T9) u - x)/T9 (the
    lead-lag) for a held input u, and its output jumps by T8/T9 times the last lag's."""
    P, x = started(PSS2A)
    S = pss_.pss2a.S
    x[S.rtf1 : S.rtf5, 0] = [0.4, 0.3, 0.2, 0.1]
    x[S.rtf5, 0] = 0.05
    x[S.washout1, 0] = -0.5  # input 1's first washout: output dw - x = 0.5 at dw = 0
    x[S.washout2, 0] = 0.0  # second washout's output 0.5 - 0 = 0.5
    _, dx = output(P, x)
    u = [0.5, 0.4, 0.3, 0.2]
    for i in range(4):
        assert dx[S.rtf1 + i, 0] == pytest.approx((u[i] - x[S.rtf1 + i, 0]) / 0.1, rel=1e-12)
    r = 0.5 / 0.1
    assert dx[S.rtf5, 0] == pytest.approx(((1 - r) * 0.1 - 0.05) / 0.1, rel=1e-12)


def test_pss2b_limits_its_inputs():
    """PSS2B's power input is limited to [VS2MIN, VS2MAX] = [0.6, 0.8] before its
    washouts: 0.9 and 1.5 pu give the same output and derivatives, the KS2/(1 + s T7)
    lag moving at KS2 (0.8 - 0.7)/T7 (its washout Tw3 at 0.7, Tw4 absent); 0.75 pu,
    inside, at KS2 (0.75 - 0.7)/T7."""
    P, x = started(PSS2B)
    S = pss_.pss2b.S
    a, b = output(P, x, pe=0.9), output(P, x, pe=1.5)
    assert a[0] == b[0] and np.array_equal(a[1], b[1])
    assert a[1][S.lag2, 0] == pytest.approx(0.1875 * 0.1 / 1.5, rel=1e-12)
    inside = output(P, x, pe=0.75)[1]
    assert inside[S.lag2, 0] == pytest.approx(0.1875 * 0.05 / 1.5, rel=1e-12)


def test_pss2c_output_logic_switches_on_the_power_with_hysteresis():
    """PSS2C: off at pe <= PSSOFF = 0.6, held off up to PSSON = 0.65, on again there
    (the switch slot); the chain's derivatives run on while off."""
    P, x = started(PSS2C)
    S = pss_.pss2c.S
    x = x + 0.01
    x[S.switch, 0] = 1.0
    on = output(P, x, omega=OMEGA0 + 0.001, pe=0.62)[0]
    assert on != 0.0 and x[S.switch, 0] == 1.0  # in the band: held on
    off, dx_off = output(P, x, omega=OMEGA0 + 0.001, pe=0.6)
    assert off == 0.0 and x[S.switch, 0] == 0.0
    assert output(P, x, omega=OMEGA0 + 0.001, pe=0.62)[0] == 0.0  # held off
    assert output(P, x, omega=OMEGA0 + 0.001, pe=0.65)[0] != 0.0 and x[S.switch, 0] == 1.0
    assert dx_off[S.switch, 0] == 0.0


def test_pss2c_starts_off_at_or_below_pssoff():
    x = started(PSS2C, pe=0.6)[1]
    assert x[pss_.pss2c.S.switch, 0] == 0.0
    assert started(PSS2C, pe=0.62)[1][pss_.pss2c.S.switch, 0] == 1.0


def test_pss2_ramp_tracking_filter_needs_a_proper_form():
    row = list(PSS2A)
    row[pss_.PSS.col("M") - 1] = 0.0
    with pytest.raises(
        CaseError, match=r"pss_con row 1 \(machine 1\), field 'M': a ramp-tracking filter"
    ):
        params(row)
    row[pss_.PSS.col("M") - 1], row[pss_.PSS.col("N") - 1] = 3.0, 3.0  # M N = 9 > 8
    with pytest.raises(CaseError, match="M N <= 8"):
        params(row)
