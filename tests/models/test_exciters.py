"""Exciter models, one by one (stabctl.models.exciters): the initial point is an
equilibrium, the non-windup regulator limit (IEEE Std 421.5-2016 annex E.5), step
responses against their closed forms, the named packed layout."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from stabctl.case import ExciterTable
from stabctl.errors import CaseError
from stabctl.io import load_case
from stabctl.models import exciters as exc
from stabctl.models.declaration import check_packed, layout

from model_rows import EXST1 as ST1

#: exc_con rows (PST manual 3.11 Table 2, 3.13 Table 3; stabctl columns 21-25)
SMP = [0, 1, 0.0, 200, 0.05, 10.0, 1.0, 5.0, -5.0]
SCRX = SMP + [0] * 9 + [1, 0]  # bus fed: exc_con column 19
DC1 = [1, 1, 0.02, 20, 0.02, 1, 1, 5.2, -4.16, 1.0, 0.83, 0, 0, 0, 0, 0.0754, 1.246, 0, 0, 0]
DC2 = [2] + DC1[1:]
IEEET2 = [5, 1, 0.02, 20, 0.02, 0, 0, 5.2, -4.16, 1.0, 0.83, 0, 0, 0, 0, 0.0754, 1.246, 0.5, 0, 0]
ST3 = [
    3,
    1,
    0.0,
    7.04,
    1.0,
    6.67,
    1.0,
    1.0,
    0.0,
    0.2,
    -0.2,
    200,
    4.37,
    20,
    4.83,
    0.09,
    1.1,
    8.63,
    1.0,
    6.53,
]
#: ESST1A (type 6): TR KA TA TB TC Vrmax Vrmin VImax VImin (columns 3-11), KC (17), KF TF
#: (21-22), TC1 TB1 VAmax VAmin KLR ILR (26-31); with EFD0 = 1.9 the field current limiter
#: is on at the start (I_fd0 = Efd0 > ILR): V_A0 = 1.9 + 2 (1.9 - 1.5) = 2.7
ST1A = [6, 1, 0.02, 200, 0.04, 10.0, 1.0, 7.3, -7.3, 0.8, -0.1, 0, 0, 0, 0, 0, 0.1, 0, 0, 0]
ST1A += [0.05, 1.0, 0, 0, 0, 0.5, 2.0, 6.0, -5.0, 2.0, 1.5]
#: EXAC1 (type 7): TR KA TA TB TC Vrmax Vrmin (3-9), KE TE E1 SE1 E2 SE2 (10-15, the DC
#: names), KC (17), KF TF (21-22), KD (32); I_N0 = 0.2 1.9 / V_E0 < 0.433
AC1 = [7, 1, 0.0, 400, 0.02, 0.0, 0.0, 8.0, -8.0, 1.0, 0.8, 2.0, 0.05, 3.0, 0.2, 0, 0.2, 0, 0, 0]
AC1 += [0.03, 1.0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0.38]
#: ESAC1A (type 9): EXAC1's row with V_R limited to [-5.4, 6] and V_A to [-14.5, 14.5]
#: (VAmax, VAmin: columns 28-29)
AC1A = [9, *AC1[1:7], 6.0, -5.4, *AC1[9:27], 14.5, -14.5, *AC1[29:]]
#: AC8B (type 10): EXAC1's exciter (K_E T_E, saturation, K_C, K_D) with K_A 40, T_A 0.04,
#: V_R on [1, 7.3], no lead-lag or rate feedback, and the PID (columns 34-39): K_P 3,
#: K_I 1, K_D 1, T_D 0.2, output on [-0.5, 0.5]
AC8B = [10, 1, 0.0, 40, 0.04, 0, 0, 7.3, 1.0, *AC1[9:20], 0, 0, *AC1[22:31], 0.38, 0]
AC8B += [3.0, 1.0, 1.0, 0.2, 0.5, -0.5]
#: EXAC4 (type 8): TR KA TA TB TC Vrmax Vrmin VImax VImin (3-11), KC (17)
AC4 = [8, 1, 0.02, 200, 0.04, 10.0, 1.0, 5.0, -4.0, 0.1, -0.1, 0, 0, 0, 0, 0, 0.1]
#: IEEET3 (type 11): TR KA TA (3-5), Vrmax Vrmin (8-9), KE TE (10-11, the DC names), KP
#: KI (13, 15), KF TF (21-22), VBmax (33); ANDES 2.0's ieee14_ieeet3.xlsx values
T3 = [11, 1, 0.02, 5.0, 0.04, 0, 0, 7.3, -7.3, 1.0, 1.0, 0, 4.0, 0, 0.1, 0, 0, 0, 0, 0]
T3 += [0.1, 1.0, *[0] * 10, 18.0]
#: ESST4B (type 12): TR TA (3, 5), Vrmax Vrmin (8-9), KP thetaP KI XL KC (13-17), KG
#: VGmax (19-20), VBmax (33), K_PR K_IR (34-35), K_PM K_IM VMmax VMmin (40-43)
ST4B = [12, 1, 0.01, 0, 0.1, 0, 0, 8.0, 0.0, 0, 0, 0, 4.0, 0, 0.1, 0.01, 0.1, 0, 1.0, 20.0]
ST4B += [*[0] * 12, 18.0, 1.0, 0.5, 0, 0, 0, 0, 1.0, 0.5, 8.0, 0.0]
#: EXST1 read as PSS/E (psse_st1, exc_con column 48)
ST1_PSSE = ST1 + [0] * (47 - len(ST1)) + [1]


def row(kind, **cols):
    """An exc_con row of type ``kind`` for machine 1, its other fields by declared name
    (stabctl.models.exciters.EXCITER), the rest 0."""
    out = [0.0] * len(exc.EXCITER.params)
    out[0], out[1] = kind, 1
    for name, value in cols.items():
        out[exc.EXCITER.col(name) - 1] = value
    return out


#: the AC exciter of IEEE 421.5's AC2A sample data (K_E 1, T_E 0.6, K_C 0.28, K_D 0.35,
#: saturation 0.037 at 4.4, 0.012 at 3.3)
AC_EXCITER = dict(KE=1.0, TE=0.6, KC=0.28, KD=0.35, E1=4.4, SE1=0.037, E2=3.3, SE2=0.012)
#: EXAC2 (type 13): IEEE 1981 AC2's sample regulator (K_A 400, T_A 0.01, V_A on [-8, 8],
#: K_B 25, V_R on [-95, 105], K_H 1, K_F 0.03, T_F 1), K_L 1, V_LR 4.4; V_FE0 = 2.32 so
#: that the gate passes V_H (K_B K_L (V_LR - V_FE0) = 52 > V_FE0)
_AC2_COLS = dict(TR=0.01, KA=400, TA=0.01, VAmax=8, VAmin=-8, KB=25, Vrmax=105, Vrmin=-95,
                 KL=1.0, KH=1.0, VLR=4.4, KF=0.03, TF=1.0, TB=1.0, TC=0.5,
                 **AC_EXCITER)  # fmt: skip
AC2 = row(13, **_AC2_COLS)
#: ESAC6A (type 14): IEEE 421.5's AC6A sample data; V_FE0 = 7.0 < V_FELIM = 19 (V_H0 = 0)
AC6A_EXCITER = dict(KE=1.6, TE=1.0, KC=0.173, KD=1.91, E1=7.4, SE1=0.214, E2=5.55, SE2=0.044)
AC6A_COLS = dict(TR=0.01, KA=536, TA=0.086, TK=0.18, TB=9, TC=3, VAmax=75, VAmin=-75,
                 Vrmax=44, Vrmin=-36, VFELIM=19, KH=92, VHMAX=75, TH=0.08, TJ=0.02,
                 **AC6A_EXCITER)  # fmt: skip
AC6A = row(14, **AC6A_COLS)
#: ESAC6A with the field current limiter on from the start: V_FELIM 5, K_H 1 (V_H0 = 2.0)
AC6A_VH = row(14, **{**AC6A_COLS, "VFELIM": 5.0, "KH": 1.0})
#: EXPIC1 (type 15): K_A 3, T_A1 1, the PI on [-0.87, 1], T_A2 0.05, T_A3 0.1, T_A4 0.2,
#: V_R on [-0.87, 1], K_F 0.05, T_F1 1, T_F2 0.1, E_0 on [0, 7.4], K_E 0.4, T_E 0.5,
#: saturation 0.05 at 2, 0.2 at 3, K_P 6.4 (V_B: the test's VB0), K_C 0.08
PIC1 = row(15, TR=0.01, KA=3, TA1=1, VAmax=1, VAmin=-0.87, TA=0.05, TC=0.1, TB=0.2, Vrmax=1,
           Vrmin=-0.87, KF=0.05, TF=1, TF_2=0.1, Efdmax=7.4, Efdmin=0, KE=0.4, TE=0.5, E1=2,
           SE1=0.05, E2=3, SE2=0.2, KP_pic=6.4, KC=0.08)  # fmt: skip
#: EXPIC1 as ACTIVSg2000's (bus 1051): no T_R, T_A2, T_A4, T_E or rate feedback, so the
#: field voltage V_B clip(3 (V_ref - V_t) + PIi) is algebraic in the terminal voltage
PIC1_ALG = row(15, KA=3, TA1=1, VAmax=1, VAmin=-0.87, Vrmax=1, Vrmin=-0.87, TF=1,
               Efdmax=7.4304, E1=1, E2=1.2, KP_pic=6.4388, KC=0.08)  # fmt: skip
#: ST6B (type 16): PSS/E's ST6B run's record (PowerSimulationsDynamics.jl's ST6B test: K_PA
#: 50.038, K_IA 45.094, V_A on [-3.85, 4.81], K_FF 1, K_M 1, K_CI 1.0577, K_LR 17.33, I_LR
#: 2.15, V_R on [-3.85, 4.81], K_G 1, T_G 0.02), with a derivative K_DA 0.5, T_DA 0.1
ST6B_ROW = row(16, TR=0.012, Kpid_P=50.038, Kpid_I=45.094, Kpid_D=0.5, Td=0.1, VAmax=4.81,
               VAmin=-3.85, KFF=1, KM=1, KCI=1.0577, KLR=17.33, ILR=2.15, Vrmax=4.81,
               Vrmin=-3.85, KG=1, TG=0.02)  # fmt: skip
#: ST8C (type 17): PSS/E's ST8C run's record (PowerSimulationsDynamics.jl's test 61)
ST8C_ROW = row(17, TR=0.01, Kpid_P=5, Kpid_I=5, VPmax=99.99, VPmin=0, KPA=4, KIA=0.1,
               VAmax=99.9962, VAmin=-99.866, KA=1.35, TA=0.003, Vrmax=99.3449,
               Vrmin=-99.1691, KF_ifd=0.5, TF_ifd=0.005, KC=0.1, KP=4, VB1max=99)  # fmt: skip
ROWS = {
    "ST6B": ST6B_ROW,
    "ST8C": ST8C_ROW,
    "EXAC2": AC2,
    "ESAC6A": AC6A,
    "ESAC6A limiter on": AC6A_VH,
    "EXPIC1": PIC1,
    "EXPIC1 algebraic": PIC1_ALG,
    "smpexc": SMP,
    "SCRX": SCRX,
    "DC1": DC1,
    "DC2": DC2,
    "IEEET2": IEEET2,
    "ST3": ST3,
    "EXST1": ST1,
    "EXST1_psse": ST1_PSSE,
    "ESST1A": ST1A,
    "ESST1A_vos2": ST1A[:19] + [1] + ST1A[20:],
    "EXAC1": AC1,
    "EXAC4": AC4,
    "ESAC1A": AC1A,
    "AC8B": AC8B,
    "IEEET3": T3,
    "ESST4B": ST4B,
}
EFD0, VT0, VB0 = 1.9, 1.02, 4.0  # initial field and terminal voltage, ST3 V_B


def params(row):
    case = load_case("kundur")
    return exc.exciter_params(case.replace(exciters=ExciterTable.from_matrix([row])))


def started(row):
    """(P, x) of an exciter started at EFD0, VT0 (ST3: source voltage VB0)."""
    x, Vref, p = exc.initialise(params(row), np.array([EFD0]), np.array([VT0]), np.array([VB0]))
    return p.packed(Vref), x


def derivatives(P, x, eterm=VT0, efd=EFD0, ieee=True):
    dx = np.full_like(x, np.nan)
    exc.derivatives(P, x, 0, eterm, eterm, 0.0, efd, efd, VB0, dx, ieee, 0.0)
    return dx


@pytest.mark.parametrize("ieee", [True, False])
@pytest.mark.parametrize("name", sorted(ROWS))
def test_initial_point_is_an_equilibrium(name, ieee):
    """At the initial point the exciter hands its machine the initial field voltage
    (ST3: V_R V_B; EXST1: I_fd0 = Efd0) and every derivative is 0 (PST flag 0)."""
    P, x = started(ROWS[name])
    assert exc.field_voltage_at(P, x, 0, VT0, 0.0, VB0, EFD0, ieee) == pytest.approx(
        EFD0, rel=1e-15
    )
    assert np.abs(derivatives(P, x, ieee=ieee)).max() < 1e-12


def simulate(P, x0, t, eterm=VT0):
    """States after t s with the terminal voltage held at eterm, the field voltage fed
    back as the exciter hands it over (V_B = 1)."""

    def f(_, y):
        x = y.reshape(x0.shape).copy()
        efd = exc.field_voltage_at(P, x, 0, eterm, 0.0, 1.0, 0.0, True)
        return derivatives(P, x, eterm, efd).ravel()

    return solve_ivp(f, (0, t), x0.ravel(), rtol=1e-12, atol=1e-14).y[:, -1].reshape(x0.shape)


def test_smpexc_step_response_is_a_lag():
    """smpexc without T_R and lead-lag: Efd = Efd0 + K_A dV (1 - e^(-t/T_A)); at t = T_A
    the fraction 1 - e^-1 (PST smpexc, IEEE 421.5 E.2)."""
    row = SMP[:5] + [0.0, 0.0] + SMP[7:]
    P, x = started(row)
    dV = 1e-4
    P[0, exc.E.VREF] += dV
    x = simulate(P, x, 0.05)
    assert (x[2, 0] - EFD0) / (200 * dV) == pytest.approx(1 - np.exp(-1), rel=1e-6)


def test_smpexc_without_ta_jumps_by_the_lead_lag_ratio():
    """smpexc without T_A: Efd = K_A (1 + s T_C)/(1 + s T_B) of the error, which jumps by
    K_A dV T_C/T_B at a V_ref step."""
    row = SMP[:4] + [0.0] + SMP[5:]
    P, x = started(row)
    dV = 1e-3
    P[0, exc.E.VREF] += dV
    jump = exc.field_voltage_at(P, x, 0, VT0, 0.0, 1.0, 0.0, True) - EFD0
    assert jump == pytest.approx(200 * dV * 1.0 / 10.0, rel=1e-9)


def test_scrx_bus_fed_output_scales_with_the_terminal_voltage():
    """SCRX with CSWITCH = 0: the output is the regulator state times V_t."""
    P, x = started(SCRX)
    assert exc.field_voltage_at(P, x, 0, 0.5, 0.0, 1.0, 0.0, True) == pytest.approx(
        EFD0 / VT0 * 0.5, rel=1e-15
    )


def test_dc1_step_response_is_two_lags():
    """DC1 without saturation, lead-lag or rate feedback (K_E = 1): Efd/dV = K_A/((1 +
    s T_A)(K_E + s T_E)), step response K_A dV [1 - (T_A e^(-t/T_A) - T_E e^(-t/T_E))/(T_A
    - T_E)] (PST exc_dc12)."""
    row = DC1[:2] + [0.0, 20, 0.02, 0.0, 0.0] + DC1[7:15] + [0.0] + DC1[16:]
    P, x = started(row)
    dV, TA, TE, t = 1e-4, 0.02, 0.83, 0.5
    P[0, exc.E.VREF] += dV
    x = simulate(P, x, t)
    exact = 20 * dV * (1 - (TA * np.exp(-t / TA) - TE * np.exp(-t / TE)) / (TA - TE))
    assert x[3, 0] - EFD0 == pytest.approx(exact, rel=1e-6)


def test_dc1_without_ta_has_an_algebraic_regulator():
    """DC1 with T_A = 0 (PSTess exc_dc12 "no TA"; EI_33's IEEET1 at row 36): V_R = K_A V_A
    within [Vrmin, Vrmax] with no state, so the step response is the exciter's lag alone,
    K_A dV (1 - e^(-t/T_E)) (K_E = 1); a step beyond the limit puts V_R on Vrmax at once."""
    row = DC1[:2] + [0.0, 20, 0.0, 0.0, 0.0] + DC1[7:15] + [0.0] + DC1[16:]
    P, x = started(row)
    dV, TE, t = 1e-4, 0.83, 0.5
    P[0, exc.E.VREF] += dV
    x = simulate(P, x, t)
    assert x[3, 0] - EFD0 == pytest.approx(20 * dV * (1 - np.exp(-t / TE)), rel=1e-6)
    P[0, exc.E.VREF] += 10.0  # K_A V_A far above Vrmax
    dx = derivatives(P, x)
    assert x[2, 0] == P[0, exc.E.VRMAX] and dx[2, 0] == 0.0


def test_ieeet2_rate_feedback_is_of_v_r_through_its_second_lag():
    """IEEET2 (IEEE Committee Report 1968, Type 2; OpenIPSL's PSS/E-verified IEEET2): the
    rate feedback s K_F/((1 + s T_F1)(1 + s T_F2)) of the regulator output V_R, not of Efd
    (round 49: fed Efd, like DC1, Nordic 44's twelve IEEET2 (K_A 729) gave twelve unstable
    2.5 Hz exciter modes and a flat run that drifted).  V_F lags K_F/T_F1 (V_R - R_f) by
    T_F2 (exc_con column 18, the layout's TF2; 0 for the other types); R_f follows V_R and
    an Efd step moves neither; with T_F2 below 1e-3 s, K_F/T_F1 (V_R - R_f) is subtracted
    from the error itself; T_A and T_F2 both below 1e-3 s (an algebraic loop) are refused."""
    P, x = started(IEEET2)
    assert P[0, exc.E.TF2] == 0.5 and started(DC1)[0][0, exc.E.TF2] == 0.0
    assert x[4, 0] == x[2, 0] and x[5, 0] == 0.0  # R_f at V_R0, V_F at rest
    x[2, 0] += 0.1  # V_R above R_f by 0.1
    dx = derivatives(P, x)
    assert dx[5, 0] == pytest.approx(0.0754 / 1.246 * 0.1 / 0.5, rel=1e-14)
    assert dx[4, 0] == pytest.approx(0.1 / 1.246, rel=1e-14)
    x = started(IEEET2)[1]
    x[3, 0] += 0.1  # Efd: no feedback of it
    dx = derivatives(P, x)
    assert dx[4, 0] == 0.0 and dx[5, 0] == 0.0
    P1, x1 = started(IEEET2[:17] + [0.0] + IEEET2[18:])
    x1[2, 0] += 0.1
    vf = 0.0754 / 1.246 * 0.1
    assert derivatives(P1, x1)[2, 0] == pytest.approx((-20 * vf - 0.1) / 0.02, rel=1e-12)
    with pytest.raises(CaseError, match=r"'TF2' \(column 18\): IEEET2 needs TA or TF2 >= 0.001 s"):
        started(IEEET2[:4] + [0.0] + IEEET2[5:17] + [0.0] + IEEET2[18:])


@pytest.mark.parametrize("name, slot", [("DC1", 2), ("ST3", 2), ("smpexc", 2)])
def test_regulator_is_non_windup(name, slot):
    """IEEE 421.5 E.5: V_R beyond Vrmax and driven outward is put back on the limit with
    a zero derivative; driven inward it leaves at once; PSTess (exc_dc12, exc_st3) acts
    only beyond the limit, so at the limit the outward derivative stays."""
    P, x0 = started(ROWS[name])
    hi = P[0, exc.E.VRMAX]
    up = P.copy()
    up[0, exc.E.VREF] += 1.0
    x = x0.copy()
    x[slot, 0] = hi + 0.5
    dx = derivatives(up, x)
    assert x[slot, 0] == hi and dx[slot, 0] == 0.0
    down = P.copy()
    down[0, exc.E.VREF] -= 1.0
    x[slot, 0] = hi
    assert derivatives(down, x)[slot, 0] < 0 and x[slot, 0] == hi
    if name != "smpexc":
        assert derivatives(up, x, ieee=False)[slot, 0] > 0


def test_st3_regulator_input_is_limited():
    """exc_st3: the error is limited to [VImin, VImax] before K_J: the lead-lag state
    moves at (K_J VImax - x)/T_B for a large error."""
    P, x = started(ST3)
    P[0, exc.E.VREF] += 1.0
    assert derivatives(P, x)[1, 0] == pytest.approx((200 * 0.2 - x[1, 0]) / 6.67, rel=1e-14)


def test_exst1_rate_feedback_is_a_washout_on_efd():
    """EXST1: the feedback s K_F/(1 + s T_F) Efd = K_F/T_F (Efd - R_f) subtracted from the
    error before the V_I limits; its state lags Efd by T_F."""
    P, x = started(ST1)
    dx = derivatives(P, x, efd=EFD0 + 0.5)
    assert dx[3, 0] == pytest.approx(0.5 / 1.0, rel=1e-14)
    err = P[0, exc.E.VREF] - x[0, 0] - 0.01 / 1.0 * 0.5
    assert dx[1, 0] == pytest.approx((err - x[1, 0]) / 0.02, rel=1e-12)


def test_exst1_psse_output_limits_both_lose_the_rectifier_drop():
    """EXST1 as PSS/E (OpenIPSL's PSSE.ES.EXST1, PowerSimulationsDynamics.jl): the field
    voltage V_R clipped to [V_t VRMIN - K_C I_fd, V_t VRMAX - K_C I_fd]; stabctl's own
    reading keeps V_t VRMIN: V_R = -5 at V_t 1.02, I_fd 2 (K_C 0.1, VRMIN -3) gives -3.26
    against -3.06."""
    for row, lo in ((ST1_PSSE, 1.02 * -3.0 - 0.1 * 2.0), (ST1, 1.02 * -3.0)):
        P, x = started(row)
        x[2, 0] = -5.0
        assert exc.field_voltage_at(P, x, 0, VT0, 0.0, VB0, 2.0, True) == pytest.approx(lo)
        x[2, 0] = 9.0
        hi = exc.field_voltage_at(P, x, 0, VT0, 0.0, VB0, 2.0, True)
        assert hi == pytest.approx(1.02 * 4.0 - 0.1 * 2.0)


def test_exst1_psse_rate_feedback_is_a_washout_on_vr():
    """EXST1 as PSS/E: the feedback s K_F/(1 + s T_F) takes V_R before the output limits
    (OpenIPSL's imDerivativeLag.u = EFD1), not the field voltage handed over: V_R 0.5
    above rest moves R_f at 0.5/T_F whatever the field voltage."""
    P, x = started(ST1_PSSE)
    x[2, 0] += 0.5
    dx = derivatives(P, x, efd=EFD0)
    assert dx[3, 0] == pytest.approx(0.5 / 1.0, rel=1e-14)
    err = P[0, exc.E.VREF] - x[0, 0] - 0.01 / 1.0 * 0.5
    assert dx[1, 0] == pytest.approx((err - x[1, 0]) / 0.02, rel=1e-12)


def test_esst1a_starts_with_its_field_current_limiter_on():
    """ESST1A at rest: V_A0 = Efd0 + K_LR (I_fd0 - I_LR) (ANDES esst1a.py VA0), both
    lead-lag states and V_ref - V_t at V_A0/K_A, the rate-feedback state at Efd0."""
    P, x = started(ST1A)
    assert x[2, 0] == pytest.approx(2.7, rel=1e-15)
    assert x[1, 0] == x[4, 0] == pytest.approx(2.7 / 200, rel=1e-15)
    assert x[3, 0] == EFD0 and P[0, exc.E.VREF] == pytest.approx(VT0 + 2.7 / 200, rel=1e-15)


def test_esst1a_field_current_limiter_and_output_limit():
    """ESST1A's output V_A - K_LR max(0, I_fd - I_LR), clipped to [V_t Vrmin, V_t Vrmax -
    K_C I_fd]: a field current 0.1 higher lowers Efd at once by K_LR 0.1; below I_LR the
    limiter is off; at V_t = 0.2 the upper limit 0.2 7.3 - 0.1 I_fd binds."""
    P, x = started(ST1A)

    def efd(vt, ifd):
        return exc.field_voltage_at(P, x, 0, vt, 0.0, 1.0, ifd, True)

    assert efd(VT0, EFD0 + 0.1) == pytest.approx(EFD0 - 2 * 0.1, rel=1e-14)
    assert efd(VT0, 1.0) == pytest.approx(2.7, rel=1e-15)
    assert efd(0.2, EFD0) == pytest.approx(0.2 * 7.3 - 0.1 * EFD0, rel=1e-14)


def test_esst1a_error_step_passes_both_lead_lags():
    """A stabiliser step dV at rest: the regulator's input jumps by dV (T_C/T_B)
    (T_C1/T_B1), so dV_A/dt = K_A dV (T_C/T_B)(T_C1/T_B1)/T_A (the lead-lags' IEEE 421.5
    E.3 realisation, the lag E.2)."""
    P, x = started(ST1A)
    dV, dx = 1e-3, np.zeros_like(x)
    exc.derivatives(P, x, 0, VT0, VT0, dV, EFD0, EFD0, 1.0, dx, True, 0.0)
    assert dx[2, 0] == pytest.approx(200 * dV * (1 / 10) * (0.5 / 2) / 0.04, rel=1e-12)
    assert dx[4, 0] == pytest.approx(dV * (1 / 10) / 2.0, rel=1e-12)


@pytest.mark.parametrize("ieee", [True, False])
def test_esst1a_va_is_non_windup(ieee):
    """ESST1A's V_A at VAmax driven outward (a stabiliser step of 50 pu: the error at
    VImax, K_A times the lead-lags' output 6.6 > VAmax) stays there with a zero derivative
    (IEEE 421.5 E.5), both conventions; driven inward it leaves at once."""
    P, x = started(ST1A)
    x[2, 0] = 6.0
    dx = np.zeros_like(x)
    exc.derivatives(P, x, 0, VT0, VT0, 50.0, EFD0, EFD0, 1.0, dx, ieee, 0.0)
    assert x[2, 0] == 6.0 and dx[2, 0] == 0.0
    exc.derivatives(P, x, 0, VT0, VT0, 0.0, EFD0, EFD0, 1.0, dx, ieee, 0.0)
    assert dx[2, 0] < 0


def test_esst1a_vos_2_adds_the_stabiliser_after_va():
    """ESST1A with VOS = 2 (exc_con column 20 vos_after_va = 1; PSS/E, PSID's Va_sum =
    Va - I_result + Vs): a stabiliser output 0.1 moves the field voltage at once by 0.1
    and the rate feedback's input with it, and leaves the voltage error (lead-lag input)
    alone; with VOS = 1 it enters the error and the field voltage waits for V_A."""
    row = ST1A[:19] + [1] + ST1A[20:]
    P, x = started(row)
    P1, _ = started(ST1A)
    vs = 0.1
    assert exc.field_voltage_at(P, x, 0, VT0, vs, VB0, EFD0, True) == pytest.approx(EFD0 + vs)
    assert exc.field_voltage_at(P1, x, 0, VT0, vs, VB0, EFD0, True) == pytest.approx(EFD0)
    dx = np.full_like(x, np.nan)
    exc.derivatives(P, x, 0, VT0, VT0, vs, EFD0, EFD0, VB0, dx, True, 0.0)
    assert dx[3, 0] == pytest.approx(vs / 1.0, rel=1e-12)  # R_f follows the output
    err = P[0, exc.E.VREF] - x[0, 0] - 0.05 / 1.0 * vs  # only the feedback moves it
    assert dx[1, 0] == pytest.approx((err - x[1, 0]) / 10.0, rel=1e-12)


def test_esst1a_rate_feedback_is_a_washout_of_the_regulator_output():
    """ESST1A's feedback s K_F/(1 + s T_F) acts on V_A - K_LR max(0, I_fd - I_LR) before
    the output limit (ANDES esst1a.py WF of LVG_y): V_A 0.5 above rest moves R_f at
    0.5/T_F and lowers the lead-lag's input by K_F/T_F 0.5."""
    P, x = started(ST1A)
    x[2, 0] += 0.5
    dx = derivatives(P, x)
    assert dx[3, 0] == pytest.approx(0.5 / 1.0, rel=1e-14)
    err = P[0, exc.E.VREF] - x[0, 0] - 0.05 / 1.0 * 0.5
    assert dx[1, 0] == pytest.approx((err - x[1, 0]) / 10.0, rel=1e-12)


#: ESST1A of PowerSimulationsDynamics.jl's PSS/E run (test 55): K_A 200, T_A 0.1 s, lead-lags
#: 14.14/20 twice, K_F = T_F = 0.01 s (VAmin opened to start at EFD0)
ST1A_PSSE = [6, 1, 0.01, 200, 0.1, 20.0, 14.1421356237310, 6.0, 0.0, 5.0, -5.0]
ST1A_PSSE += [0, 0, 0, 0, 0, 0.5, 0, 0, 0, 0.01, 0.01, 0, 0, 0, 14.1421356237310, 20.0]
ST1A_PSSE += [6.3, -10.0, 0.01, 2.8]


@pytest.mark.parametrize(
    "row, fed_back",
    [(ST1A_PSSE, False), (ST1A, False), (ST1, True)],
    ids=["ESST1A_psse", "ESST1A", "EXST1"],
)
def test_rate_feedback_loop_time_constant_is_the_fastest_pole(row, fed_back):
    """`exst1.inner_loop_time_constants` (the regulator loop built from the data) gives the
    fastest eigenvalue of the exciter's own Jacobian without its transducer state
    (central differences of `derivatives`, the terminal voltage and the machine's field
    current held; EXST1's field voltage, its rate feedback's input, fed back):
    PSS/E's ESST1A run at -1109 1/s, where T_F = 0.01 s suggests -100."""
    P, x0 = started(row)
    tau = params(row).inner_loop_time_constants(np.ones(1), np.array([EFD0]))[0]

    def f(x):
        x = x.reshape(x0.shape).copy()
        efd = exc.field_voltage_at(P, x, 0, VT0, 0.0, 1.0, EFD0, True) if fed_back else EFD0
        return derivatives(P, x, efd=efd).ravel()

    n, eps = x0.size, 1e-7
    J = np.column_stack(
        [(f(x0.ravel() + eps * e) - f(x0.ravel() - eps * e)) / (2 * eps) for e in np.eye(n)]
    )
    keep = np.any(J, 1) & (np.arange(n) > 0)  # the states, without V_TR
    fastest = np.linalg.eigvals(J[np.ix_(keep, keep)]).real.min()
    assert -1 / tau == pytest.approx(fastest, rel=1e-6)
    if row is ST1A_PSSE:
        assert tau == pytest.approx(1 / 1109.1, rel=1e-3)


def test_exac1_initial_point_in_closed_form():
    """EXAC1 at rest with I_N0 <= 0.433: V_E0 = Efd0 + 0.577 K_C I_fd0 (I_fd0 = Efd0), V_R0
    = V_FE0 = K_E V_E0 + B (V_E0 - A)^2 + K_D I_fd0 with the quadratic through (2, 0.05),
    (3, 0.2): S_E(E) E = B (E - A)^2 (PSS/E), the rate-feedback state at V_FE0."""
    P, x = started(AC1)
    VE0 = EFD0 + 0.577 * 0.2 * EFD0
    A = (3 - 2 * np.sqrt(6)) / (1 - np.sqrt(6))  # (3 - A) = sqrt(0.6/0.1) (2 - A)
    B = 0.1 / (2 - A) ** 2
    VFE0 = VE0 + B * (VE0 - A) ** 2 + 0.38 * EFD0
    assert x[3, 0] == pytest.approx(VE0, rel=1e-14)
    assert x[2, 0] == x[4, 0] == pytest.approx(VFE0, rel=1e-14)
    assert P[0, exc.E.VREF] == pytest.approx(VT0 + VFE0 / 400, rel=1e-15)


def test_exac1_output_follows_the_rectifier_regulation():
    """EXAC1's Efd = V_E F_EX(K_C I_fd/V_E) (IEEE 421.5 annex D): a field current of 5 pu
    gives I_N = 1/V_E0 in the sqrt(0.75 - I_N^2) segment; 20 pu, beyond 1: no output."""
    P, x = started(AC1)
    VE0 = x[3, 0]
    IN = 0.2 * 5 / VE0
    assert 0.433 < IN < 0.75
    got = exc.field_voltage_at(P, x, 0, VT0, 0.0, 1.0, 5.0, True)
    assert got == pytest.approx(VE0 * np.sqrt(0.75 - IN**2), rel=1e-14)
    assert exc.field_voltage_at(P, x, 0, VT0, 0.0, 1.0, 20.0, True) == 0.0


def test_exac1_exciter_integrates_vr_minus_vfe_and_vr_is_non_windup():
    """EXAC1: T_E dV_E/dt = V_R - V_FE (a field current 0.1 higher raises V_FE by K_D
    0.1); V_R at Vrmax driven outward stays there with a zero derivative (IEEE 421.5
    E.5)."""
    P, x = started(AC1)
    dx = np.zeros_like(x)
    exc.derivatives(P, x, 0, VT0, VT0, 0.0, EFD0, EFD0 + 0.1, 1.0, dx, True, 0.0)
    assert dx[3, 0] == pytest.approx(-0.38 * 0.1 / 0.8, rel=1e-12)
    x[2, 0] = 8.0
    exc.derivatives(P, x, 0, VT0, VT0, 1.0, EFD0, EFD0, 1.0, dx, True, 0.0)
    assert x[2, 0] == 8.0 and dx[2, 0] == 0.0


def test_esac1a_with_the_same_limits_is_exac1():
    """ESAC1A whose V_A limits are EXAC1's V_R limits (so the V_R clip never acts) has
    EXAC1's initial point and derivatives (IEEE 421.5-2005 AC1A without UEL/OEL)."""
    same = [9, *AC1[1:27], AC1[7], AC1[8], *AC1[29:]]
    (P7, x7), (P9, x9) = started(AC1), started(same)
    np.testing.assert_array_equal(x7, x9)
    x7[2, 0] = x9[2, 0] = 7.0  # V_R away from rest
    np.testing.assert_array_equal(derivatives(P7, x7), derivatives(P9, x9))


def test_esac1a_va_is_non_windup_and_vr_clips_it():
    """ESAC1A: V_A inside [VAmin, VAmax] but above Vrmax drives the exciter with V_R =
    Vrmax (T_E dV_E/dt = 6 - V_FE0); V_A beyond VAmax driven outward is put back on
    it with a zero derivative (IEEE 421.5 E.5)."""
    P, x = started(AC1A)
    VFE0 = x[4, 0]  # the rate-feedback state rests at V_FE0
    x[2, 0] = 10.0
    dx = derivatives(P, x)
    assert x[2, 0] == 10.0 and dx[3, 0] == pytest.approx((6.0 - VFE0) / 0.8, rel=1e-12)
    up = P.copy()
    up[0, exc.E.VREF] += 1.0
    x[2, 0] = 15.0
    dx = derivatives(up, x)
    assert x[2, 0] == 14.5 and dx[2, 0] == 0.0


def test_ac8b_starts_with_the_reference_at_the_terminal_voltage():
    """AC8B at rest (ANDES 2.0 ac8b.py): the PID's integral holds V_R0/K_A = V_FE0/K_A,
    its derivative washout 0, and V_ref = V_t (the PID integrates any error)."""
    P, x = started(AC8B)
    assert P[0, exc.E.VREF] == VT0
    assert x[1, 0] == pytest.approx(x[2, 0] / 40, rel=1e-15) and x[4, 0] == 0.0


def test_ac8b_pid_tracks_its_output_limit():
    """AC8B's PID (ANDES PIDTrackAW): ys = K_P u + x_i + K_D (u - x_d)/T_D, y = ys clipped
    to [VPmin, VPmax], dx_i/dt = K_I (u - 2 (ys - y)), T_D dx_d/dt = u - x_d; the
    regulator lag follows K_A y."""
    P, x = started(AC8B)
    u = 0.1  # a voltage error: ys = 3 0.1 + x_i + 1 0.1/0.2 = 0.8 + x_i > 0.5
    up = P.copy()
    up[0, exc.E.VREF] += u
    dx = derivatives(up, x)
    ys = 3 * u + x[1, 0] + 1 * u / 0.2
    assert dx[1, 0] == pytest.approx(1 * (u - 2 * (ys - 0.5)), rel=1e-12)
    assert dx[4, 0] == pytest.approx(u / 0.2, rel=1e-12)
    assert dx[2, 0] == pytest.approx((40 * 0.5 - x[2, 0]) / 0.04, rel=1e-12)


def test_exac4_output_limits_fall_with_the_field_current():
    """EXAC4's output is its regulator state clipped to [Vrmin - K_C I_fd, Vrmax - K_C
    I_fd] (PSS/E EXAC4), not scaled by V_t: the state at 6 with I_fd = 2 gives 5 - 0.2;
    a large error moves the windup lag at (K_A T_C/T_B VImax - V_R)/T_A."""
    P, x = started(AC4)
    x[2, 0] = 6.0
    assert exc.field_voltage_at(P, x, 0, 0.3, 0.0, 1.0, 2.0, True) == pytest.approx(4.8)
    dx = np.zeros_like(x)
    exc.derivatives(P, x, 0, VT0, VT0, 1.0, EFD0, EFD0, 1.0, dx, True, 0.0)
    u = x[1, 0] + 0.1 * (0.1 - x[1, 0])  # lead-lag output, ratio T_C/T_B
    assert dx[2, 0] == pytest.approx((200 * u - 6.0) / 0.04, rel=1e-12)


def test_ieeet3_source_and_regulator_sum_is_limited_to_0_and_vbmax():
    """IEEET3 (docs/pst_models.md 2.9): T_E dEfd/dt = clip(V_B + V_R, 0, VBmax) - K_E Efd;
    at rest V_R0 = K_E Efd0 - V_B0 (ANDES ``ieeet3.py``)."""
    P, x = started([*T3[:32], 10.0])  # VBmax 10
    assert x[2, 0] == pytest.approx(1.0 * EFD0 - VB0)
    for VR, fed in ((7.0, 10.0), (-7.0, 0.0), (-1.0, VB0 - 1.0)):
        x[2, 0] = VR
        assert derivatives(P, x)[3, 0] == pytest.approx((fed - EFD0) / 1.0, rel=1e-12)


def test_ieeet3_rate_feedback_and_source_term():
    """The rate feedback K_F/T_F (Efd - R_f) is taken from the regulator's input, and the
    source term is sqrt(V_E^2 - (0.78 I_fd)^2), 0 where negative (ANDES ``ieeet3.py``)."""
    P, x = started(T3)
    x[4, 0] = EFD0 - 0.5  # R_f behind Efd: feedback 0.1/1.0 * 0.5
    dx = derivatives(P, x)
    assert dx[2, 0] == pytest.approx((5.0 * (x[2, 0] / 5.0 - 0.05) - x[2, 0]) / 0.04, rel=1e-9)
    machine = exc.ST3Machine(1.0, 1.0 + 0j, 0.8, 0.1, 1.0, 2.0)
    VE = exc.potential_source(4.0 + 0j, 0.1, 0.0, machine)
    assert VE == pytest.approx(abs(4.0 + 1j * 0.1 * (0.8 - 0.1j)))
    assert exc.source_voltage_of(exc.T3, 4.0 + 0j, 0.1, 0.0, 0.0, np.inf, machine, False) == (
        pytest.approx(np.sqrt(VE**2 - 1.56**2))
    )
    dead = exc.ST3Machine(1.0, 1.0 + 0j, 0.8, 0.1, 1.0, VE / 0.78 + 0.1)
    assert exc.source_voltage_of(exc.T3, 4.0 + 0j, 0.1, 0.0, 0.0, np.inf, dead, False) == 0.0


@pytest.mark.parametrize("VGmax", [20.0, 1.0])
@pytest.mark.parametrize("VM", [0.3, 2.0, 8.5, -0.2])
def test_esst4b_field_voltage_solves_its_inner_loop(VM, VGmax):
    """ESST4B's Efd = V_B clip(K_PM (V_M - min(K_G Efd, VGmax)) + PIMi, VMmin, VMmax)
    holds exactly for the returned Efd, with the feedback free or on VGmax and the inner
    PI free or on either limit (the algebraic loop ANDES solves with its equations)."""
    row = ST4B.copy()
    row[19] = VGmax
    P, x = started(row)
    x[2, 0], x[3, 0] = VM, 0.3
    efd = exc.field_voltage_at(P, x, 0, VT0, 0.0, VB0, EFD0, True)
    inner = np.clip(1.0 * (VM - min(1.0 * efd, VGmax)) + 0.3, 0.0, 8.0)
    assert efd == pytest.approx(VB0 * inner, rel=1e-13, abs=1e-13)


def test_esst4b_regulators_track_their_limits():
    """Both PI regulators integrate K_I (u - 2 (ys - y)) (ANDES ``PITrackAW``, k_s = 2): a
    large error drives the regulator's ys above Vrmax = 8."""
    P, x = started(ST4B)
    dx = np.zeros_like(x)
    x[0, 0] = VT0 - 10.0  # the transducer's output 10 pu below V_ref
    exc.derivatives(P, x, 0, VT0 - 10.0, VT0 - 10.0, 0.0, EFD0, EFD0, VB0, dx, True, 0.0)
    ys = 1.0 * 10.0 + x[1, 0]
    assert dx[1, 0] == pytest.approx(0.5 * (10.0 - 2 * (ys - 8.0)), rel=1e-12)
    assert dx[2, 0] == pytest.approx((8.0 - x[2, 0]) / 0.1, rel=1e-12)
    assert dx[3, 0] == 0.0  # the inner loop still balanced: V_M = K_G Efd


def test_esst4b_regulators_hold_their_integrals_at_a_limit_as_pss_e_reads_them():
    """PSS/E's reading (exc_con psse_st1 1, import-psse's): both PIs with non-windup limits
    (IEEE 421.5-2016 ST4B and E.6; OpenIPSL's PSS/E-verified ESST4B.mo, OPAL-RT's): with
    the regulator's ys above Vrmax = 8 and its error driving it further, its integral
    stands still (ANDES's tracking moves it at K_I (u - 2 (ys - y)), above); driven back
    inside, it integrates K_I u.  Round 53 (AO11): the tracking took the integral to -1.3
    pu through a fault, Efd -0.68 pu after clearing where both PSS/E libraries give 2.8."""
    row = ST4B + [0.0] * (48 - len(ST4B))
    row[47] = 1.0  # psse_st1: PSS/E's reading
    P, x = started(row)
    dx = np.zeros_like(x)
    x[0, 0] = VT0 - 10.0  # the transducer's output 10 pu below V_ref: u = 10
    exc.derivatives(P, x, 0, VT0 - 10.0, VT0 - 10.0, 0.0, EFD0, EFD0, VB0, dx, True, 0.0)
    assert dx[1, 0] == 0.0
    x[0, 0] = VT0 + 0.5  # the error negative: back inside, K_I u
    exc.derivatives(P, x, 0, VT0 + 0.5, VT0 + 0.5, 0.0, EFD0, EFD0, VB0, dx, True, 0.0)
    u = P[0, exc.E.VREF] - (VT0 + 0.5)
    assert dx[1, 0] == pytest.approx(0.5 * u, rel=1e-12)


def test_esst4b_without_its_lag_feeds_the_regulator_output_to_the_inner_loop():
    """ESST4B with T_A = 0 (PSS/E: no lag; ACTIVSg2000's records): the inner loop takes
    the regulator PI's clipped output y = clip(K_PR (V_ref - V_TR) + PIi, Vrmin, Vrmax)
    in place of the lag's V_M, starts at rest, and its V_M slot is no state."""
    row = ST4B.copy()
    row[4] = 0.0  # T_A
    P, x = started(row)
    assert exc.field_voltage_at(P, x, 0, VT0, 0.0, VB0, EFD0, True) == pytest.approx(
        EFD0, rel=1e-14
    )
    assert np.abs(derivatives(P, x)).max() < 1e-12
    assert not params(row).has_state()[2, 0]
    x[1, 0] += 0.05  # the regulator's integral moves: so does Efd, at once
    y = min(1.0 * (P[0, exc.E.VREF] - x[0, 0]) + x[1, 0], 8.0)
    efd = exc.field_voltage_at(P, x, 0, VT0, 0.0, VB0, EFD0, True)
    inner = np.clip(1.0 * (y - min(1.0 * efd, 20.0)) + x[3, 0], 0.0, 8.0)
    assert efd == pytest.approx(VB0 * inner, rel=1e-13)
    assert efd > EFD0


def test_layout_names_every_packed_column_once():
    assert exc.E._fields == tuple(name for name, _ in exc.PACKED)
    assert list(exc.E) == list(range(len(exc.PACKED)))
    with pytest.raises(ValueError):
        layout("Twice", (("KA", "KA"), ("KA", "TA")))
    with pytest.raises(AttributeError, match="KX reads 'KX'"):
        check_packed(exc.ExciterParams, (*exc.PACKED, ("KX", "KX")), ("Vref",))


def _leadlag_lag_step(t, K, T_lead, T_lag1, T_lag2):
    """Step response of K (1 + s T_lead)/((1 + s T_lag1)(1 + s T_lag2)) (unit step, T_lag1
    != T_lag2): K (1 - sum over the two lags T of (T - T_lead)/(T - T_other) e^(-t/T))."""
    a = (T_lag1 - T_lead) / (T_lag1 - T_lag2)
    b = (T_lag2 - T_lead) / (T_lag2 - T_lag1)
    return K * (1 - a * np.exp(-t / T_lag1) - b * np.exp(-t / T_lag2))


def test_exac2_regulator_step_is_its_lead_lag_and_lag():
    """EXAC2 (K_F = 0, V_t held): a step dV of V_ref moves V_A as K_A dV (1 + s T_C)/((1 +
    s T_B)(1 + s T_A)) whatever the exciter does (the block diagram: V_A has no feedback
    but the rate feedback's)."""
    P, x = started(row(13, **{**_AC2_COLS, "KF": 0}))
    va0, dV, t = x[2, 0], 2e-3, 0.03
    P[0, exc.E.VREF] += dV
    x = simulate(P, x, t)
    exact = _leadlag_lag_step(t, 400 * dV, 0.5, 1.0, 0.01)
    assert x[2, 0] - va0 == pytest.approx(exact, rel=1e-7)


def test_exac2_field_current_limiter_holds_the_exciter():
    """EXAC2 after a large V_ref step (K_A dV = 200 pu against VAMAX = 8): V_A rests on
    VAMAX (non-windup), V_H = 8 - K_H V_FE falls below V_L = K_L (V_LR - V_FE) no longer
    and the low-value gate hands V_L on: the exciter settles where K_B K_L (V_LR - V_FE) =
    V_FE, V_FE = K_B K_L V_LR/(1 + K_B K_L) = 25 4.4/26 = 4.2308 pu (the rate feedback's
    washout R_f at rest is V_FE)."""
    P, x = started(AC2)
    P[0, exc.E.VREF] += 0.5
    x = simulate(P, x, 30.0)
    dx = derivatives(P, x, efd=exc.field_voltage_at(P, x, 0, VT0, 0, 1, 0, True))  # clamps x
    assert x[2, 0] == 8.0 and np.abs(dx).max() < 1e-8
    assert x[4, 0] == pytest.approx(25 * 4.4 / 26, rel=1e-8)


def test_esac6a_regulator_step_is_its_two_lead_lags():
    """ESAC6A (V_t held, the limiter off): V_A = K_A dV (1 + s T_K)(1 + s T_C)/((1 + s
    T_A)(1 + s T_B)) after a step dV of V_ref: at once K_A dV T_K T_C/(T_A T_B), then
    K_A dV (1 - (T_A - T_K)(T_A - T_C)/(T_A (T_A - T_B)) e^(-t/T_A) - (T_B - T_K)(T_B -
    T_C)/(T_B (T_B - T_A)) e^(-t/T_B)) (IEEE 421.5 AC6A sample data)."""
    P, x = started(AC6A)
    KA, TA, TK, TB, TC = 536, 0.086, 0.18, 9.0, 3.0
    va0, dV = x[2, 0], 1e-3
    P[0, exc.E.VREF] += dV

    def va(x):
        y = TK / TA * KA * (P[0, exc.E.VREF] - VT0) + x[1, 0]
        return TC / TB * y + (1 - TC / TB) * x[2, 0]

    assert va(x) - va0 == pytest.approx(KA * dV * TK * TC / (TA * TB), rel=1e-12)
    for t in (0.05, 0.5):
        xt = simulate(P, x, t)
        exact = (
            KA
            * dV
            * (
                1
                - (TA - TK) * (TA - TC) / (TA * (TA - TB)) * np.exp(-t / TA)
                - (TB - TK) * (TB - TC) / (TB * (TB - TA)) * np.exp(-t / TB)
            )
        )
        assert va(xt) - va0 == pytest.approx(exact, rel=1e-7)


def test_esac6a_field_current_limiter_holds_the_exciter():
    """ESAC6A after a large V_ref step (K_A dV = 268 pu): V_A on VAMAX = 75, the limiter
    V_H = K_H (V_FE - V_FELIM) (below V_HMAX) subtracted, V_R below V_t VRMAX: the exciter
    settles at V_FE = (VAMAX + K_H V_FELIM)/(1 + K_H) = (75 + 92 19)/93 = 19.602 pu; V_FE =
    (K_E + K_D) V_E + S_E(V_E) V_E with I_fd = Efd = V_E (the harness's field current)."""
    P, x = started(AC6A)
    P[0, exc.E.VREF] += 0.5
    x = simulate(P, x, 20.0)
    VE, p = x[3, 0], params(AC6A)
    VFE = (1.6 + 1.91) * VE + p.Bsat[0] * (VE - p.Asat[0]) ** 2
    assert VFE == pytest.approx((75 + 92 * 19) / 93, rel=1e-8)


def test_expic1_pi_ramps_and_leaves_its_limit_at_once():
    """EXPIC1 as ACTIVSg2000's (no T_R, T_A2, T_A4, T_E, rate feedback): after a step dV
    of V_ref the field voltage is V_B (V_R0 + K_A T_A1 dV + K_A dV t) (the PI), until
    the PI reaches VR1 = 1: Efd = V_B; the integral stops there (non-windup), so a step
    back down leaves the limit at once: V_B (1 - K_A T_A1 dV - K_A T_A1 dV)."""
    P, x = started(PIC1_ALG)
    dV = 0.01
    P[0, exc.E.VREF] += dV

    def efd(x):
        return exc.field_voltage_at(P, x, 0, VT0, 0.0, VB0, EFD0, True)

    assert efd(x) == pytest.approx(EFD0 + VB0 * 3 * dV, rel=1e-14)
    xt = simulate(P, x, 10.0)
    assert efd(xt) == pytest.approx(VB0 * (0.475 + 3 * dV * (1 + 10.0)), rel=1e-9)
    xt = simulate(P, x, 20.0)  # 0.475 + 0.03 (1 + t) reaches 1 at t = 16.5 s
    assert efd(xt) == VB0 * 1.0 and xt[1, 0] == pytest.approx(1 - 3 * dV, rel=1e-9)
    P[0, exc.E.VREF] -= 2 * dV
    assert efd(xt) == pytest.approx(VB0 * (1 - 3 * dV - 3 * dV), rel=1e-9)


@pytest.mark.parametrize("lam", [-50.0, -12 + 184j, -0.5 + 3j])
def test_heun_step_limit_is_the_root_of_its_stability_polynomial(lam):
    """Heun's |R(lam h)|^2 = 1 with R(z) = 1 + z + z^2/2, divided by h: |lam|^4/4 h^3 + a
    |lam|^2 h^2 + 2 a^2 h + 2 a = 0 (a = Re lam); the step limit is its smallest positive
    root (2/|lam| for a real lam)."""
    from stabctl.models.exciters.exac2 import heun_step_limit

    a, m2 = np.real(lam), abs(lam) ** 2
    roots = np.roots([m2**2 / 4, a * m2, 2 * a**2, 2 * a])
    exact = min(r.real for r in roots if abs(r.imag) < 1e-12 and r.real > 0)
    assert heun_step_limit(np.array([lam, np.conj(lam)])) == pytest.approx(exact, rel=1e-8)
    # a mode that does not decay (Re lam >= 0) is the model's growth, not the step's: no limit
    assert heun_step_limit(np.array([1j, -1j, 0.5])) == np.inf


def test_st6b_gate_hands_the_field_current_limiter_on():
    """ST6B: V_R = min(K_LR (K_CI I_LR - I_fd), clip(K_M (V_A - V_G) + K_FF V_A)) and Efd =
    V_R V_t: at rest (I_fd0 = 1.9) the inner loop's V_R0 = Efd0/V_t0 = 1.8627 passes; with
    I_fd = 2.2 the limiter's 17.33 (1.0577 2.15 - 2.2) = 1.3844 pu takes over."""
    P, x = started(ST6B_ROW)
    efd = exc.field_voltage_at(P, x, 0, VT0, 0.0, 1.0, EFD0, True)
    assert efd == pytest.approx(EFD0, rel=1e-14)
    limited = exc.field_voltage_at(P, x, 0, VT0, 0.0, 1.0, 2.2, True)
    assert limited == pytest.approx(17.33 * (1.0577 * 2.15 - 2.2) * VT0, rel=1e-14)


@pytest.mark.parametrize("name", ["EXAC1", "EXAC2", "ESAC1A"])
def test_ac_exciter_voltage_is_held_at_zero(name):
    """V_E >= 0, non-windup, in every AC exciter (the rectifier's diodes; OpenIPSL's and
    OPAL-RT's PSS/E EXAC1 and EXAC2): round 50 found EXAC1's and EXAC2's V_E unlimited, to
    -17 pu after a 0.6 pu VREF pulse.  V_E below 0 driven down is put back on 0 with a zero
    derivative; driven up it leaves at once."""
    P, x = started(ROWS[name])
    ve = exc.exac1.S.VE  # (EXAC2's slot too)
    regulator = 2  # V_R (EXAC1) or V_A (EXAC2, ESAC1A): the slot before V_E
    x[ve, 0], x[regulator, 0] = -0.5, P[0, exc.E.VRMIN]
    down = P.copy()
    down[0, exc.E.VREF] -= 1.0
    dx = derivatives(down, x)
    assert x[ve, 0] == 0.0 and dx[ve, 0] == 0.0
    x[regulator, 0] = 5.0
    assert derivatives(P, x)[ve, 0] > 0


def test_dc_exciter_with_ke_zero_starts_at_a_tenth_of_its_ceiling_as_psse():
    """K_E = 0 in a DC exciter read as PSS/E reads it (quadratic saturation, exc_con column
    23 = 1): PSS/E's self-excited exciter, K_E = V_Rmax/(10 Efd0) - S_E(Efd0), V_R0 =
    V_Rmax/10 (PAG 15.2.4; OpenIPSL's calculate_dc_exciter_params; round 50: V_R started at
    0, K_E 0 against 0.191 for VRMAX 3, and Efd 4 s after a step 0.11-0.35 pu off).  With
    PST's exponential fit (column 23 = 0) V_R0 stays 0."""
    sat = [3.0, 0.1, 4.0, 0.3]  # E1 SE1 E2 SE2 (columns 12-15)
    base = DC1[:9] + [0.0, 0.83] + sat + DC1[15:] + [0, 0]  # K_E 0; columns 21-22 0
    P, x = started(base + [1, 0])  # quadratic, K_E computed
    assert x[2, 0] == pytest.approx(5.2 / 10, rel=1e-12)  # V_R0 = Vrmax/10
    assert all(abs(v) < 1e-12 for v in derivatives(P, x).ravel() if not np.isnan(v))
    P, x = started(base + [0, 0])  # PST's exponential fit
    assert abs(x[2, 0]) < 1e-12


def test_dc_exciter_field_voltage_floor_holds_at_zero():
    """efd_floor (exc_con column 75; PSS/E's ESDC1A and ESDC2A as OpenIPSL's
    RotatingExciterLimited reads them; round 50: Efd went to -3 pu after a 0.6 pu VREF
    drop): Efd at 0 driven down stays at 0 with a zero derivative; without it (DC1 as PST's
    exc_dc12, IEEEX1) Efd falls through 0."""
    for floor in (1, 0):
        P, x = started(DC1 + [0] * (74 - len(DC1)) + [floor])
        x[3, 0], x[2, 0] = 0.0, P[0, exc.E.VRMIN]  # Efd at 0, V_R at its floor
        dx = derivatives(P, x)
        assert x[3, 0] == 0.0 and (dx[3, 0] == 0.0) == bool(floor)
        assert floor or dx[3, 0] < 0
