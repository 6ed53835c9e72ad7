"""Governor models, one by one (stabctl.models.governors): the initial point is an
equilibrium at the initial mechanical power, the non-windup gate and valve limits (IEEE
Std 421.5-2016 annex E.5 rule), step responses against their closed forms, the named
packed layout."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from stabctl.case import GovernorTable
from stabctl.errors import CaseError
from stabctl.io import load_case
from stabctl.models import governors as gov

from model_rows import IEEEG1

#: tg_con rows (PST manual tg; stabctl types 2-5, docs/pst_models.md 4.1-4.3)
TG = [1, 1, 1, 20, 1.2, 0.4, 0.5, 2.0, 1.0, 3.0, 0.0]
TGOV1 = [2, 1, 1, 20, 1.2, 0.49, 7.0, 2.1, 0, 0, 0.1, 2.0]
#: HYGOV: GMAX 1, T_g 0.5, T_f 0.05, T_w 1.2, A_t 1.1, GMIN 0, D_turb 0.5, VELM 0.2,
#: R 0.04, r 0.5, q_NL 0.08, K_g = 1/(r T_r) = 0.4, velm_rel 0
HYGOV = [
    4,
    1,
    1,
    0,
    1.0,
    0.5,
    0.05,
    0,
    1.2,
    1.1,
    0.0,
    0.5,
    0,
    0,
    0.2,
    -0.2,
    0.04,
    0.5,
    0.08,
    0.4,
    0.0,
]
#: IEESGO: K_1 = 20, T_1 0.1, T_2/T_3 = 0.5/2, T_4 0.3, T_5 4, T_6 0.6, fractions (0.3, 0.3, 0.4)
IEESGO = [
    5,
    1,
    1,
    20,
    1.2,
    2.0,
    0.1,
    0.5,
    0.3,
    4.0,
    0.0,
    0,
    0.6,
    0,
    0,
    0,
    0.3,
    0,
    0.3,
    0,
    0.4,
    0,
    0,
    0,
]
#: GAST: 1/R = 20, T1 (Ts) 0.4, T2 (Tc) 0.1, T3 3, VMAX 1.0, VMIN -0.05, D_turb 0, AT 0.8,
#: KT 2 (tg_con columns 4-8, 11, 12, 25, 26): the load limit 0.8 + 2 (0.8 - 0.7) = 1.0
GAST = [6, 1, 1, 20, 1.0, 0.4, 0.1, 3.0, 0, 0, -0.05, 0.0] + [0] * 12 + [0.8, 2.0]
#: TG2 (ANDES): 1/R = 20, pmax 1.0 (Tmax), pmin 0 (Tmin), T1 0.2 (T3, lead), T2 10 (Tc,
#: lag), speed set point 1
TG2 = [7, 1, 1, 20, 1.0, 0, 10.0, 0.2, 0, 0, 0.0, 0.0]
#: GGOV1 (tg_con columns 28-59; Vmax 1, Vmin 0.15 in columns 5, 11, Tc 0 in 7): the
#: PSS/E Model Library's example values (OpenIPSL PSSE.TG.GGOV1 defaults) with Rselect 1,
#: Flag 1, Tact 0.5, Kturb 1.5, Wfnl 0.2, Tb 0.1, Ldref 1, Aset 0.1, Trate 0 (machine base)
GGOV1_FIELDS = dict(
    Rselect=1, Flag=1, Rdroop=0.04, Tpelec=1.0, maxerr=0.05, minerr=-0.05, Kpgov=10.0,
    Kigov=2.0, Kdgov=0.0, Tdgov=1.0, Tact=0.5, Kturb=1.5, Wfnl=0.2, Tb=0.1, Teng=0.0,
    Tfload=3.0, Kpload=2.0, Kiload=0.67, Ldref=1.0, Dm=0.0, Ropen=0.1, Rclose=-0.1, Kimw=0.0,
    Aset=0.1, Kacc=10.0, Tacc=0.1, Trate=0.0, db=0.0, Tsa=4.0, Tsb=5.0, Rup=99.0, Rdown=-99.0,
)  # fmt: skip


def ggov1_row(**changed):
    """A GGOV1 tg_con row (type 9) of `GGOV1_FIELDS` with `changed`."""
    row = [9, 1, 1, 0, 1.0, 0, 0.0, 0, 0, 0, 0.15] + [0] * 16
    return row + list({**GGOV1_FIELDS, **changed}.values())


#: DEGOV (type 10) with PSS/E's published run's values (PowerSimulationsDynamics.jl test
#: 57): T1 = T2 = T3 = 0 (no control box), K 18 (invR), T4 12, T5 5, T6 0.2, TD 0 (Teng),
#: TMAX 1.1, TMIN 0 (tg_con columns 4-13; Teng in column 42)
DEGOV = [10, 1, 1, 18.0, 1.1, 0.0, 0.0, 0.0, 12.0, 5.0, 0.0, 0.0, 0.2]


def degov_row(**changed):
    """A DEGOV tg_con row (`DEGOV`, zeros to GGOV1's columns) with fields `changed`."""
    row = DEGOV + [0.0] * (59 - len(DEGOV))
    for name, v in changed.items():
        row[gov.GOVERNOR.col(name) - 1] = v
    return row


ROWS = {
    "DEGOV": DEGOV,
    "GGOV1": ggov1_row(),
    "tg": TG,
    "TG2": TG2,
    "TGOV1": TGOV1,
    "IEEEG1": IEEEG1,
    "HYGOV": HYGOV,
    "IEESGO": IEESGO,
    "GAST": GAST,
}
PM0 = 0.7  # initial mechanical power (machine base)


def params(row):
    case = load_case("kundur")
    return gov.governor_params(case.replace(governors=GovernorTable.from_matrix([row])))


def started(row, pm0=PM0):
    x, Pref = gov.initialise(params(row), np.array([pm0]))
    return params(row).packed(Pref), x


def derivatives(P, x, omega=1.0):
    """The derivatives with the machine's electrical power at the governor's mechanical
    power (the machine in steady state; read by GGOV1 only)."""
    dx = np.full_like(x, np.nan)
    gov.derivatives(P, x, 0, omega, gov.pmech(P, x, 0, omega), dx)
    return dx


def pmech_after(P, x0, t, omega=1.0):
    """Mechanical power after t s at constant speed omega."""

    def f(_, y):
        return derivatives(P, y.reshape(x0.shape).copy(), omega).ravel()

    sol = solve_ivp(f, (0, t), x0.ravel(), rtol=1e-12, atol=1e-14)
    return gov.pmech(P, sol.y[:, -1].reshape(x0.shape), 0, omega)


@pytest.mark.parametrize("name", sorted(ROWS))
def test_initial_point_is_an_equilibrium(name):
    """At rated speed the initial states give the initial mechanical power and every
    derivative is 0 (PST tg flag 0; PSS/E's initialisation of the others)."""
    P, x = started(ROWS[name])
    assert gov.pmech(P, x, 0, 1.0) == pytest.approx(PM0, rel=1e-14)
    assert np.abs(derivatives(P, x)).max() < 1e-13


def test_tg_step_response_is_its_servo_lag():
    """tg with T_3 = T_c and T_4 = T_5 (both lead-lags cancel): P_ref step dP gives
    pmech = pm0 + dP (1 - e^(-t/T_s)); at t = T_s the fraction 1 - e^-1."""
    row = TG[:7] + [0.5, 3.0, 3.0, 0.0]
    P, x = started(row)
    dP = 1e-4
    P[0, gov.G.PREF] += dP
    assert (pmech_after(P, x, 0.4) - PM0) / dP == pytest.approx(1 - np.exp(-1), rel=1e-6)


def test_tg_lead_lags_jump_by_their_ratios():
    """tg: the servo state stepped by d moves pmech by d T_3/T_c T_4/T_5 at once."""
    P, x = started(TG)
    x[0, 0] += 1e-3
    assert gov.pmech(P, x, 0, 1.0) - PM0 == pytest.approx(1e-3 * 2.0 / 0.5 * 1.0 / 3.0, rel=1e-9)


def test_tgov1_valve_stays_at_its_limit_while_driven_outward():
    """TGOV1's valve (non-windup, [VMIN, VMAX]): beyond VMAX and driven outward it is put
    back on VMAX with a zero derivative; driven inward it leaves."""
    P, x = started(TGOV1)
    up = P.copy()
    up[0, gov.G.PREF] += 1.0
    x[0, 0] = 1.3
    assert derivatives(up, x)[0, 0] == 0.0 and x[0, 0] == 1.2
    assert derivatives(P, x)[0, 0] == pytest.approx((PM0 - 1.2) / 0.49, rel=1e-14)


def test_ieeeg1_gate_is_non_windup_at_pmax():
    """IEEEG1's gate at PMAX driven open stays there (derivative 0); closing leaves."""
    P, x = started(IEEEG1)
    up = P.copy()
    up[0, gov.G.PREF] += 1.0
    x[1, 0] = 0.95
    assert derivatives(up, x)[1, 0] == 0.0 and x[1, 0] == 0.95
    assert derivatives(P, x)[1, 0] == -1.0  # (0.7 - 0.95)/T3 limited to Uc


def test_hygov_gate_integrator_is_non_windup_and_rate_limited():
    """HYGOV: the gate integrator's rate K_g e is limited to [-VELM, VELM]; the
    integrator (position limits [GMIN, GMAX]) beyond GMAX and driven open is put back
    on GMAX with a zero derivative."""
    P, x = started(HYGOV)
    up = P.copy()
    up[0, gov.G.PREF] += 1.0
    x[0, 0] = 1.0  # a large filtered error e
    assert derivatives(up, x)[1, 0] == 0.2  # 0.4 e limited to VELM
    x[1, 0] = 1.3  # beyond GMAX, opening
    dx = derivatives(up, x)
    assert dx[1, 0] == 0.0 and x[1, 0] == 1.0


def test_hygov_psse_gate_is_the_whole_pi_rate_and_position_limited():
    """HYGOV as PSS/E (psse_gate, tg_con column 22; OpenIPSL's PSSE.TG.HYGOV: the lead
    (1 + s T_r)/(r T_r) of e into the VELM rate limiter and the [GMIN, GMAX] integrator):
    the state is the desired gate c itself, d c/dt = K_g e + (de/dt)/r.  At rest and 1 %
    over speed de/dt = -0.01/T_f = -0.2, so c moves at -0.2/r = -0.4, limited to -VELM;
    at 0.1 % it moves freely at -0.04 where stabctl's own reading (the integral part
    alone) moves at K_g e = 0; the gate servo follows c, not c + e/r."""
    P, x = started(HYGOV + [1.0])
    assert derivatives(P, x, 1.01)[1, 0] == pytest.approx(-0.2, rel=1e-14)  # -VELM
    assert derivatives(P, x, 1.001)[1, 0] == pytest.approx(-0.001 / 0.05 / 0.5, rel=1e-12)
    assert derivatives(*started(HYGOV), 1.001)[1, 0] == 0.0
    x[0, 0], x[1, 0] = 0.1, x[2, 0] + 0.05  # e 0.1: c + e/r would be 0.2 above c
    assert derivatives(P, x)[2, 0] == pytest.approx(0.05 / 0.5, rel=1e-12)
    P[0, gov.G.PREF] += 1.0
    x[1, 0] = 1.3  # beyond GMAX, opening: put back with a zero derivative
    dx = derivatives(P, x)
    assert dx[1, 0] == 0.0 and x[1, 0] == 1.0


def test_hygov_water_column_starts_at_rated_head():
    """HYGOV: at the initial point the flow is q0 = pm0/A_t + q_NL at head (q/g)^2 = 1;
    pm drops by D_turb g dw at a speed step."""
    P, x = started(HYGOV)
    q0 = PM0 / 1.1 + 0.08
    assert x[3, 0] == pytest.approx(q0, rel=1e-15) and x[2, 0] == pytest.approx(q0, rel=1e-15)
    assert gov.pmech(P, x, 0, 1.01) == pytest.approx(PM0 - 0.5 * 0.01 * q0, rel=1e-12)


def test_ieesgo_step_response_is_its_t4_lag():
    """IEESGO with T_1, T_3, T_5, T_6 absent: P_ref step dP through the T_4 lag, pmech =
    pm0 + (sum of fractions) dP (1 - e^(-t/T_4)); at t = T_4 the fraction 1 - e^-1."""
    row = list(IEESGO)
    row[5] = row[6] = row[9] = row[12] = 0.0  # T3 (Ts), T1 (Tc), T5, T6
    row[7] = 0.0  # T2 (no lead either)
    P, x = started(row)
    dP = 1e-4
    P[0, gov.G.PREF] += dP
    assert (pmech_after(P, x, 0.3) - PM0) / dP == pytest.approx(1 - np.exp(-1), rel=1e-6)


def test_lag_time_constants_below_the_threshold_are_refused():
    """tg's lags always exist in PST: a T_s below 1e-3 s (which would make the lag
    absent) is refused, naming the field."""
    with pytest.raises(
        CaseError, match=r"tg_con row 1 \(machine 1\), field 'Ts': must be >= 0\.001 s"
    ):
        params(TG[:5] + [5e-4] + TG[6:])


def test_layout_names_every_packed_column_once():
    """The shared columns named by `G`, then the most own columns of a type."""
    assert gov.G._fields == tuple(name for name, _ in gov.PACKED)
    assert params(HYGOV).packed(np.zeros(1)).shape == (1, len(gov.G) + gov.N_OWN)


def test_tg2_is_the_droop_through_its_lead_lag_then_a_hard_limit():
    """TG2 (ANDES 2.0 tg2.py): a speed step d moves pmech at once by -d/R T1/T2 (the
    lead-lag's ratio), then toward -d/R along T2 (closed form of (1 + s T1)/(1 + s T2):
    after T2, the jump plus (1 - T1/T2)(1 - e^-1) of the rest); the output is cut at pmax
    while the lead-lag runs on (no windup)."""
    P, x = started(TG2)
    d = 1e-3
    assert gov.pmech(P, x, 0, 1.0 - d) - PM0 == pytest.approx(20 * d * 0.2 / 10.0, rel=1e-9)
    after = pmech_after(P, x, 10.0, 1.0 - d) - PM0
    assert after == pytest.approx(20 * d * (0.02 + 0.98 * (1 - np.exp(-1))), rel=1e-6)
    assert gov.pmech(P, x, 0, 0.9) == pytest.approx(0.74, rel=1e-12)  # 0.7 + 20 x 0.1 x 0.02
    assert gov.pmech(P, x, 0, 0.0) == 1.0  # 0.7 + 20 x 1 x 0.02 = 1.1, cut at pmax
    dx = derivatives(P, x, 0.0)
    assert dx[0, 0] != 0.0  # the lead-lag runs on at the limit


def test_gast_load_limit_takes_over_the_droop_order():
    """GAST: the valve follows min(droop order, AT + KT (AT - y_3)) (PSS/E GAST's low-value
    gate; ANDES gast.py): at 5 % under-speed the droop asks 0.7 + 20 0.05 = 1.7, the load
    limit 1.0 wins, and the valve moves at (1.0 - 0.7)/T1; with y_3 lowered to 0.5 the
    limit rises to 1.4; at rest the power lag T2 and limit lag T3 hold."""
    P, x = started(GAST)
    dx = derivatives(P, x, omega=0.95)
    assert dx[0, 0] == pytest.approx((1.0 - 0.7) / 0.4, rel=1e-14)
    assert dx[1, 0] == dx[2, 0] == 0.0
    x[2, 0] = 0.5
    assert derivatives(P, x, omega=0.95)[0, 0] == pytest.approx((1.4 - 0.7) / 0.4, rel=1e-14)


def test_gast_valve_is_non_windup_and_power_is_its_lag():
    """GAST's valve at VMAX driven outward stays there with a zero derivative (IEEE 421.5
    E.5 rule); after a P_ref step dP the power is the two lags 1/((1 + s T1)(1 + s T2))
    (the load limit far away): pm0 + dP [1 - (T1 e^(-t/T1) - T2 e^(-t/T2))/(T1 - T2)]."""
    P, x = started(GAST)
    x[0, 0] = 1.0
    dx = derivatives(P, x, omega=0.9)
    assert x[0, 0] == 1.0 and dx[0, 0] == 0.0
    P, x = started(GAST)
    P[0, gov.G.AT] = 5.0  # the load limit out of the way
    dP, T1, T2, t = 1e-4, 0.4, 0.1, 0.3
    P[0, gov.G.PREF] += dP
    exact = PM0 + dP * (1 - (T1 * np.exp(-t / T1) - T2 * np.exp(-t / T2)) / (T1 - T2))
    assert pmech_after(P, x, t) == pytest.approx(exact, rel=1e-9)


def test_gast_starting_on_its_load_limit_is_at_rest():
    """PSS/E's own GAST run (PowerSimulationsDynamics.jl test 21, ThreeBus_GAST.dyr:
    AT = 1, KT = 2.5, the machine at Pm0 = 1) starts exactly on the load limit AT + KT
    (AT - Pm0) = Pm0: accepted within START_LIMIT_TOL (a power flow's 1e-9 above it) and
    at rest; 1e-5 above it refused."""
    row = GAST[:4] + [1.2] + GAST[5:24] + [1.0, 2.5]  # VMAX 1.2: the valve limit aside
    P, x = started(row, pm0=1.0 + 1e-9)
    assert np.abs(derivatives(P, x)).max() < 1e-7
    with pytest.raises(CaseError, match="GAST's load limit"):
        started(row, pm0=1.0 + 1e-5)


def test_gast_initial_power_above_its_load_limit_is_refused():
    """GAST starting where AT + KT (AT - Pm0) < Pm0 would not be at rest: refused."""
    with pytest.raises(CaseError, match="GAST's load limit"):
        started(GAST[:24] + [0.6, 2.0])
    with pytest.raises(CaseError, match="GAST's load limit"):  # 1e-5 pu beyond: refused
        started(GAST[:24] + [PM0 - 1e-5, 2.0])


def test_gast_starting_at_its_load_limit_within_the_tolerance_starts():
    """PSS/E's GAST run dispatches the turbine exactly at AT = Pm0 = 1 (issue 50): the
    limit AT + KT (AT - Pm0) equals Pm0, to the power flow's round-off; within
    START_LIMIT_TOL (1e-6 pu) of it the governor starts, at rest on its droop branch."""
    for at in (PM0, PM0 - 2e-7, PM0 + 1e-3):
        _, x = started(GAST[:24] + [at, 2.0])
        assert x[0, 0] == pytest.approx(PM0, abs=1e-15)


def test_cross_compound_ieeeg1_shares_its_power_between_two_machines():
    """An IEEEG1 on Kundur's machine 1 with its LP shaft on machine 2 (tg_con column 27):
    the HP machine gets K1, K3, K5, K7 of the lags' outputs, the LP machine K2, K4, K6, K8
    of them in its own base (times MVA_1/MVA_2); at rest both get their initial power,
    gate = (P_HP + P_LP MVA_2/MVA_1)/sum K; a split unlike the fractions' is refused."""
    case = load_case("kundur")
    row = [*IEEEG1, *[0] * (27 - len(IEEEG1))]
    row[16:24] = [0.2, 0.3, 0.2, 0.1, 0.1, 0.05, 0.0, 0.05]  # HP 0.5, LP 0.5
    row[4], row[26] = 2.0, 2  # PMAX on the turbine's base; the LP shaft on machine 2
    p = gov.governor_params(case.replace(governors=GovernorTable.from_matrix([row])))
    assert p.mac2[0] == case.machine_index(2) and p.lp_base[0] == pytest.approx(1.0)
    x, Pref = gov.initialise(p, np.array([0.6]), np.array([0.6]))
    P = p.packed(Pref)
    assert Pref[0] == pytest.approx(1.2)  # (0.6 + 0.6)/sum K = 1.2/1.0
    assert gov.pmech(P, x, 0, 1.0) == pytest.approx(0.6)
    assert gov.pmech_lp(P, x, 0) == pytest.approx(0.6)
    assert np.abs(derivatives(P, x)).max() < 1e-12
    with pytest.raises(CaseError, match=r"cross-compound unit's HP machine starts at 0\.7000"):
        gov.initialise(p, np.array([0.7]), np.array([0.6]))
    row[26] = 1
    with pytest.raises(CaseError, match="'machine2': machine 1 is the unit's own"):
        gov.governor_params(case.replace(governors=GovernorTable.from_matrix([row])))


def test_ggov1_flag_and_layout():
    """GGOV1's record fields land in tg_con columns 28-59 and its packed columns."""
    p = params(ggov1_row())
    assert gov.GOVERNOR.col("Rselect") == 28 and gov.GOVERNOR.col("Rdown") == 59
    assert p.Kturb[0] == 1.5 and p.Tmax[0] == 1.0 and p.Tmin[0] == 0.15
    assert p.turbine_scale[0] == 1.0


def test_ggov1_settles_on_its_droop():
    """Speed held 0.1 % low, the machine's power following the turbine's: the PID's
    integral drives the error to 0, P_ref - (omega - 1) - R P_e = 0, so P_m rises by
    0.001/R = 0.025 pu (droop on the electrical power, Rselect 1); Flag 1: the valve
    settles where Kturb (valve omega - Wfnl) = that power."""
    P, x = started(ggov1_row())
    pm = pmech_after(P, x, 200.0, omega=0.999)
    assert pm == pytest.approx(PM0 + 0.001 / 0.04, abs=1e-7)


def test_ggov1_load_limiter_holds_the_power_at_ldref():
    """Speed held 2 % low asks for 0.7 + 0.02/0.04 = 1.2 pu; the load limiter takes over
    where the measured exhaust temperature (the fuel flow, lagged) reaches Ldref/Kturb +
    Wfnl, so the turbine's power settles at Kturb (w_f - Wfnl) = Ldref = 1 pu."""
    P, x = started(ggov1_row())
    assert pmech_after(P, x, 400.0, omega=0.98) == pytest.approx(1.0, abs=1e-6)


def test_ggov1_valve_stays_within_its_limits_and_rates():
    """With Ldref out of the way, 2 % speed drop: the order fsr0 + min(Kpgov 0.02, Ta Ka
    Aset) (the acceleration limiter's headroom, 0.1) asks (0.1 pu)/Tact = 0.2 pu/s of the
    actuator, which opens at Ropen = 0.1 pu/s; it stops at Vmax (non-windup) and the
    power settles at Kturb (Vmax omega - Wfnl)."""
    P, x = started(ggov1_row(Ldref=5.0))
    dx = derivatives(P, x, omega=0.98)
    assert dx[gov.ggov1.S.valve, 0] == pytest.approx(0.1, abs=1e-15)
    pm = pmech_after(P, x, 400.0, omega=0.98)
    assert pm == pytest.approx(1.5 * (1.0 * 0.98 - 0.2), abs=1e-6)


def test_ggov1_rselect_minus_1_is_the_droop_on_the_fuel_valve_stroke():
    """PSS/E's (and PSLF's, the CIM's DroopSignalFeedbackKind, OpenIPSL's R_select)
    Rselect codes: 1 electrical power, 0 none, -1 fuel valve stroke, -2 governor output.
    stabctl had -1 and -2 swapped (round 50: -2 fed back the valve stroke, 4.2 % of a Pref
    step's response off; -1, PSS/E's valve stroke, refused): with -1 the set point is R
    times the stroke at rest, and a stroke 0.01 above rest moves the governor's integrator
    by -Kigov R 0.01 (-2: next test)."""
    P, x = started(ggov1_row(Rselect=-1))
    valve = x[gov.ggov1.S.valve, 0]
    assert P[0, gov.G.PREF] == pytest.approx(0.04 * valve, rel=1e-14)
    x[gov.ggov1.S.valve, 0] += 0.01
    dx = derivatives(P, x)
    assert dx[gov.ggov1.S.gov_i, 0] == pytest.approx(-2.0 * 0.04 * 0.01, rel=1e-9)


def test_ggov1_rselect_minus_2_feeds_back_the_governor_output_its_loop_solved():
    """Rselect -2 (PSS/E, PSLF, the CIM: the governor output fsr, the requested stroke, fed
    back; refused until 2026-12-02): e = P_ref - (omega - 1) - R fsr with fsr = Kpgov e +
    the integral, an algebraic loop solved exactly, as PSS/E's one-step delay tends to.
    Closed forms: the set point R fsr0 at rest; 0.1 % slow, fsr = fsr0 + Kpgov 0.001/(1 +
    Kpgov R) (the valve's rate (fsr - stroke)/Tact, 0.0143 pu/s within Ropen) and the
    integral's rate Kigov e; 10 % slow, e at maxerr asks fsr0 + 0.5, the acceleration
    limiter's fsr0 + Ta Ka Aset = fsr0 + 0.1 takes the gate (the error then 0.05, the
    integral tracking at Kigov (0.05 - 0.4/Kpgov)); held 0.1 % slow, the droop R on the
    stroke: the valve settles at fsr0 + 0.001/R, as with -1 (the valve stroke at rest is
    fsr).  An unknown code (2) is refused."""
    S, G = gov.ggov1.S, gov.G
    P, x = started(ggov1_row(Rselect=-2))
    fsr0 = x[S.valve, 0]
    assert P[0, G.PREF] == pytest.approx(0.04 * fsr0, rel=1e-14)
    dx = derivatives(P, x, omega=0.999)
    step = 10.0 * 0.001 / (1 + 10.0 * 0.04)
    assert dx[S.valve, 0] * 0.5 == pytest.approx(step, rel=1e-12)
    assert dx[S.gov_i, 0] == pytest.approx(2.0 * (0.001 - 0.04 * step), rel=1e-12)
    dx = derivatives(P, x, omega=0.9)
    assert dx[S.valve, 0] == 0.1  # Ropen
    assert dx[S.gov_i, 0] == pytest.approx(2.0 * (0.05 - 0.4 / 10.0), rel=1e-12)
    pm = pmech_after(P, x, 400.0, omega=0.999)  # the loop's time constant 17.5 s
    assert pm == pytest.approx(1.5 * ((fsr0 + 0.001 / 0.04) * 0.999 - 0.2), abs=1e-7)
    with pytest.raises(CaseError, match="'Rselect'"):
        params(ggov1_row(Rselect=2))


def _stroke_root(d, r, db, pid):
    """The root of f = clip(fsrn(error(d - r f)), 0.15, 1) by scipy's brentq: error the
    dead zone +-db and the limits +-0.05, fsrn(e) = kp e + xi + kd_t (e - xd)."""
    from scipy.optimize import brentq

    kp, xi, kd_t, xd = pid

    def g(f):
        u = d - r * f
        u = u - db if u > db else (u + db if u < -db else 0.0)
        e = min(max(u, -0.05), 0.05)
        return min(max(kp * e + xi + kd_t * (e - xd), 0.15), 1.0) - f

    return brentq(g, -1.0, 3.0, xtol=1e-15, rtol=1e-15)


def test_ggov1_rselect_minus_2_loop_against_a_root_finder():
    """The loop of Rselect -2 with the dead zone, the error limits and the PID's
    derivative path, on 200 random states: the requested stroke the kernel hands the
    actuator (stroke + Tact times its rate, the rates wide) is the root of f = clip(fsrn(
    error(P_ref - (omega - 1) - R f)), Vmin, Vmax), found by scipy's brentq (fsrn = Kpgov e
    + the integral + Kdgov (e - its state)/Tdgov; the limiters' orders above Vmax)."""
    S, G = gov.ggov1.S, gov.G
    rng = np.random.default_rng(54)
    for _ in range(200):
        kp, kd, r = rng.uniform(1, 20), rng.choice([0.0, 1.5]), rng.uniform(0, 0.1)
        db = rng.choice([0.0, rng.uniform(0, 0.01)])
        row = ggov1_row(Rselect=-2, Kpgov=kp, Kdgov=kd, Tdgov=0.2, Rdroop=r, db=db)
        P, x = started(row)
        P[0, G.TACT], P[0, G.ROPEN], P[0, G.RCLOSE] = 1.0, 99.0, -99.0
        x[S.gov_i, 0], x[S.gov_d, 0] = rng.uniform(0.2, 1.0), rng.uniform(-0.05, 0.05)
        x[S.valve, 0], x[S.load_i, 0], x[S.accel_i, 0] = 0.5, 5.0, 5.0
        omega = rng.uniform(0.95, 1.05)
        pid = (kp, x[S.gov_i, 0], kd / 0.2, x[S.gov_d, 0])
        want = _stroke_root(P[0, G.PREF] - (omega - 1), r, db, pid)
        dx = derivatives(P, x.copy(), omega=omega)
        assert 0.5 + dx[S.valve, 0] == pytest.approx(want, abs=1e-12), row


def test_ggov1_options_it_does_not_model_are_refused():
    for changed, field in (({"Teng": 0.1}, "Teng"), ({"Rselect": -3}, "Rselect"),
                           ({"Kimw": 0.01}, "Kimw"), ({"Dm": -0.1}, "Dm")):  # fmt: skip
        with pytest.raises(CaseError, match=f"'{field}'"):
            params(ggov1_row(**changed))


def test_ggov1_start_above_its_load_limit_is_refused():
    """Starting at 1.1 pu with Ldref 1 the load limiter, not the governor, would hold it."""
    with pytest.raises(CaseError, match="load limiter"):
        gov.initialise(params(ggov1_row()), np.array([1.1]))


def test_degov_actuator_ramps_the_torque_as_its_closed_form():
    """DEGOV without its control box, the speed held d below 1: the torque is Pm0 + K d
    times the inverse transform of (1 + s T4)/(s^2 (1 + s T5)(1 + s T6)) = t + (T4 - T5 -
    T6) + T5 (T5 - T4)/(T5 - T6) e^(-t/T5) + T6 (T6 - T4)/(T6 - T5) e^(-t/T6) (partial
    fractions), handed to the machine as its power (not times the speed)."""
    P, x = started(degov_row())
    K, T4, T5, T6, d, t = 18.0, 12.0, 5.0, 0.2, 1e-5, 1.5
    f = t + (T4 - T5 - T6) + T5 * (T5 - T4) / (T5 - T6) * np.exp(-t / T5)
    f += T6 * (T6 - T4) / (T6 - T5) * np.exp(-t / T6)
    assert pmech_after(P, x, t, omega=1 - d) == pytest.approx(PM0 + K * d * f, rel=1e-10)


def test_degov_control_box_is_its_second_order_lead_lag():
    """DEGOV with the actuator absent (T4 = T5 = T6 = 0) and the control box T1 0.5, T2
    0.1, T3 0.2: the torque rises at K times the box's step response, so after t it is
    Pm0 + K d (t - sum over its poles a, b of (a - T3) a/(a - b) (1 - e^(-t/a)))."""
    P, x = started(degov_row(Tc=0.5, Ts=0.1, T3=0.2, T4=0.0, T5=0.0, T6=0.0))
    K, T1, T2, T3, d, t = 18.0, 0.5, 0.1, 0.2, 1e-5, 0.4
    r = np.sqrt(T1 * T1 - 4 * T1 * T2)
    a, b = (T1 + r) / 2, (T1 - r) / 2
    f = t - (a - T3) * a / (a - b) * (1 - np.exp(-t / a))
    f -= (b - T3) * b / (b - a) * (1 - np.exp(-t / b))
    assert pmech_after(P, x, t, omega=1 - d) == pytest.approx(PM0 + K * d * f, rel=1e-9)


def test_degov_torque_is_non_windup_at_tmax():
    """Driven outward at TMAX the torque stays there with a zero derivative (IEEE 421.5
    E.5 rule)."""
    P, x = started(degov_row())
    x[gov.degov.S.torque, 0] = 1.1
    dx = derivatives(P, x, omega=0.9)
    assert x[gov.degov.S.torque, 0] == 1.1 and dx[gov.degov.S.torque, 0] == 0.0


def test_degov_transport_delay_is_its_pade_approximant():
    """DEGOV's engine delay TD = 1 s (tg_con 'Teng'): the torque reaches the machine
    through the Pade approximant of e^(-s TD) of order 8 (`degov.pade_order`).  At rest
    every state is still and P_m is the torque; a torque step of 0.1 pu held (speed 1,
    the chain at rest) comes out as python-control's step response of ``pade(1, 8)``
    (within 1e-9 pu at 0.25-3 s: the realisation is the approximant), 0.1 pu after the
    delay; TD 0.25 s gets order 3, below 1e-3 s none, and a multiple of 0.1 s its own
    step (0.3 s order 4: binary division gave 3, round 55 AQ26), the kernel and the
    array reading alike."""
    import control

    tds = (0.0, 5e-4, 0.05, 0.25, 0.3, 0.6, 0.7, 0.75, 3.0)
    orders = [0, 0, 1, 3, 4, 7, 8, 8, 8]
    assert [gov.degov.pade_order(td) for td in tds] == orders
    assert gov.degov.pade_orders(tds).tolist() == orders
    P, x0 = started(degov_row(Teng=1.0))
    state = [k for k, on in enumerate(params(degov_row(Teng=1.0)).has_state()[:, 0]) if on]
    assert np.max(np.abs(derivatives(P, x0)[state])) < 1e-12
    assert gov.pmech(P, x0, 0, 1.0) == pytest.approx(PM0, rel=1e-12)
    x = x0.copy()
    x[gov.degov.S.torque, 0] += 0.1
    times = np.array([0.25, 0.5, 0.9, 1.1, 1.5, 2.0, 3.0])
    grid = np.linspace(0.0, 3.0, 12001)
    resp = control.step_response(control.tf(*control.pade(1.0, 8)), T=grid)
    step = np.interp(times, resp.time, np.squeeze(resp.outputs))
    got = [pmech_after(P, x, t) - PM0 for t in times]
    assert np.allclose(got, 0.1 * step, atol=1e-9)
    assert got[-1] == pytest.approx(0.1, abs=1e-4)


def test_degov_options_it_does_not_model_are_refused():
    """A lead without its lag, TMAX below TMIN (the engine delay TD is modelled,
    `test_degov_transport_delay_is_its_pade_approximant`; DEGOV1's is refused)."""
    for changed, match in (
        ({"T3": 0.2}, "'T3'"),
        ({"T5": 0.0, "T6": 0.0}, "'T4'"),
        ({"Tmin": 1.2}, "field 'Tmax': must be >= Tmin = 1.2"),
    ):
        with pytest.raises(CaseError, match=match):
            params(degov_row(**changed))
