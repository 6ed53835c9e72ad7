"""PSS/E's DERA1 (stabctl.models.converters.dera1): PSS/E's ThreeBus case with the DERA1 of
PowerSimulationsDynamics.jl's test 42 at bus 102, imported as a user imports it,
initialises to that program's states and its linearisation has that program's eigenvalues
(tests/data/psse_runs/DERA_FREQFLAG0/README.md); the flags it does not model are refused
naming the record and the flag; held at a voltage it settles where its block diagram
puts it (closed forms)."""

import json
from pathlib import Path

import numpy as np
import pytest
from psid import assert_start_is_psids

from stabctl.dynamics.driver import Simulator
from stabctl.errors import CaseError
from stabctl.io.psse import load_psse
from stabctl.models import converters as conv
from stabctl.models.converters.dera1 import DA
from stabctl.smallsignal.linearise import linearise

DATA = Path(__file__).parents[1] / "data" / "psse_runs" / "DERA_FREQFLAG0"
PSID = json.loads((DATA / "psid_test42.json").read_text())
RAW, DYR = DATA / "ThreeBusMulti.raw", DATA / "ThreeBus_DERA1.dyr"
#: PSID's states of generator-102-1 (FreqFlag 0), in its order
PSID_STATES = ("Vmeas", "Pmeas", "Q_V", "Iq", "Mult", "Fmeas", "Ip")


@pytest.fixture(scope="module")
def sim():
    return Simulator(load_psse(RAW, DYR), background_compile=False)


def test_record_fills_its_columns(sim):
    """The DYR record: type 4 on MBASE 100 MVA, PfFlag 1, PQFlag 0 (Q priority), GenFlag
    1, and the CONs stabctl models in their columns."""
    t = sim.case.converters
    assert (t.type[0], t.bus[0], t.mva[0]) == (conv.DERA1, 102, 100.0)
    assert (t.da_PfFlag[0], t.pqflag[0], t.da_GenFlag[0]) == (1.0, 0.0, 1.0)
    got = [float(getattr(t, f"da_{n}")[0]) for n in ("Trv", "dbd1", "dbd2", "Kqv", "Vref0")]
    assert got == [0.02, -99.0, 99.0, 5.0, 0.0]
    got = [float(getattr(t, f"da_{n}")[0]) for n in ("Tp", "Tiq", "Imax", "Tg", "rrpwr")]
    assert got == [0.02, 0.02, 1.2, 0.02, 99.0]
    assert (t.da_Iqh1[0], t.da_Iql1[0]) == (1.0, -1.0)


def test_initial_states_are_psid_s(sim):
    """PSID's initial point: its bus voltages within 1e-9, its DERA's Vmeas, Pmeas, Q_V,
    Iq and Ip within 1e-8 (measured 2.1e-9 on Ip and Pmeas: stabctl's power flow gives
    bus 102 a generation of 0.9999999983 pu where PSID takes the RAW's 1; its Mult and
    Fmeas, 1, are no states of a DERA1 without tripping and with FreqFlag 0)."""
    ref = PSID["x0_flag0"]
    psid = dict(zip(PSID_STATES, assert_start_is_psids(sim, ref)))
    m = sim.model
    xi = m.layout.view(m.x0, "ibr")[:, 0]
    for name in ("Vmeas", "Pmeas", "Q_V", "Iq", "Ip"):
        assert xi[getattr(DA, name)] == pytest.approx(psid[name], abs=1e-8), name
    assert (psid["Mult"], psid["Fmeas"]) == (1.0, 1.0)


def test_eigenvalues_are_psid_s():
    """PSID's linearisation has 7 eigenvalues: the DERA's coupled loop (Vmeas, Q_V, Iq, Ip
    through the network: -65.157, -42.421 +- 13.531j, -50) and four decoupled lags of 0.02
    s (-50: Pmeas, and Mult and Fmeas, which stabctl's DERA1 has not).  stabctl's 5 are
    PSID's within 1e-6 1/s with the infinite bus's reactance PSID's source's (X_th 5e-6
    pu; measured 8e-8); with PSS/E's RAW's ZX 1e-5 they move by 3e-4."""
    case = load_psse(RAW, DYR)
    xdp = case.machines.xdp.copy()
    xdp[case.machines.bus == 101] = 5e-6
    case = case.replace(machines=case.machines.replace(xdp=xdp))
    lam = np.linalg.eigvals(np.asarray(linearise(Simulator(case, background_compile=False)).A))
    psid = np.array([complex(*v) for v in PSID["eigvals_flag0"]])
    assert lam.size == 5
    for z in lam:
        assert np.min(np.abs(psid - z)) < 1e-6, (z, psid)
    assert np.count_nonzero(np.abs(psid + 50.0) < 1e-9) == 4
    assert np.count_nonzero(np.abs(lam + 50.0) < 1e-9) == 2


def _dyr(tmp_path, flags=(1, 0, 0, 1, 0, 0), **cons):
    """The run's DYR with the DERA1's ICONs `flags` and CONs changed by name (`cons`)."""
    from stabctl.models.converters.dera1 import CONS

    base = [float(v) for v in DYR.read_text().split("'DERA1'")[1].split("/")[0].split()[7:]]
    vals = dict(zip(CONS, base))
    vals.update(cons)
    body = " ".join(f"{v:g}" for v in (*flags, *(vals[n] for n in CONS)))
    out = tmp_path / "dera1.dyr"
    out.write_text(f"101 'GENCLS' 1 0 0 /\n102 'DERA1' 1 {body} /\n")
    return out


def test_control_flags_fill_their_columns(tmp_path):
    """FreqFlag, VtripFlag, FtripFlag 1 (refused by earlier versions) import into their
    columns with the CONs of the controls they switch on (the README's values)."""
    t = load_psse(RAW, _dyr(tmp_path, (1, 1, 0, 1, 1, 1))).converters
    assert (t.da_FreqFlag[0], t.da_VtripFlag[0], t.da_FtripFlag[0]) == (1.0, 1.0, 1.0)
    names = ("Trf", "Ddn", "Dup", "fdbd1", "fdbd2", "femax", "femin", "Pmax", "Pmin")
    got = [float(getattr(t, f"da_{n}")[0]) for n in names]
    assert got == [0.02, 20.0, 0.0, -0.0006, 0.0006, 99.0, -99.0, 1.1, 0.0]
    names = ("dPmax", "dPmin", "Tpord", "Kpg", "Kig", "vl0", "vl1", "vh0", "vh1", "tvl1")
    got = [float(getattr(t, f"da_{n}")[0]) for n in names]
    assert got == [0.5, -0.5, 0.02, 0.1, 10.0, 0.44, 0.49, 1.2, 1.15, 0.16]
    names = ("Vrfrac", "fl", "fh", "tfl", "tfh", "Tv", "Vpr")
    assert [float(getattr(t, f"da_{n}")[0]) for n in names] == [0.7, 0.0, 2.0, 99, 99, 0.02, 0.8]


def test_a_current_limit_active_at_the_start_is_refused(tmp_path):
    """Imax 1 below the initial |I| (Ip 1.0, Iq 0.37; Q priority: Ipmax = sqrt(1 - Iq^2)
    = 0.929 < Ip): the DERA1 cannot start at rest, named."""
    case = load_psse(RAW, _dyr(tmp_path, Imax=1.0))
    with pytest.raises(CaseError, match="the DERA1 cannot start at its power-flow point"):
        Simulator(case, background_compile=False)


def _settled(sim, V, t_end=2.0, h=1e-3):
    """The DERA1's states held at bus voltage V (complex pu) for t_end s (forward Euler,
    step h: its lags are 0.02 s)."""
    cp = sim.model.cp
    P, _, V_nc = conv.at_power_flow(cp, sim.op.V)
    x = sim.model.layout.view(sim.model.x0, "ibr").copy()
    dx = np.zeros_like(x)
    Vb = np.array([V])
    for _ in range(int(round(t_end / h))):
        conv.derivatives_at(P, x, Vb, V_nc, dx)
        x += h * dx
    return x[:, 0], conv.derivatives_at(P, x, Vb, V_nc, dx)[0]


@pytest.mark.parametrize("v", [0.9, 1.1])
def test_held_voltage_settles_at_constant_power(sim, v):
    """PfFlag 1, FreqFlag 0, the voltage control's deadband +-99 pu: held at |V| = v it
    settles at its initial P0 and Q0 = tan(pfaref) P0 (Ip = P0/v, Iq = Q0/v)."""
    P0, Q0 = sim.model.cp.P0[0], sim.model.cp.Q0[0]
    x, S = _settled(sim, v)
    assert x[DA.Ip] == pytest.approx(P0 / v, rel=1e-9)
    assert x[DA.Iq] == pytest.approx(Q0 / v, rel=1e-9)
    assert S == pytest.approx(P0 + 1j * Q0, rel=1e-9)


def test_q_priority_limits_ip(sim):
    """Q priority (PQFlag 0): held at |V| = 0.7, Ip's command P0/0.7 = 1.43 exceeds
    Ipmax = sqrt(Imax^2 - Iq^2) with Iq = Q0/0.7 (Imax 1.2): Ip settles there."""
    Q0 = sim.model.cp.Q0[0]
    x, _ = _settled(sim, 0.7)
    iq = Q0 / 0.7
    assert x[DA.Iq] == pytest.approx(iq, rel=1e-9)
    assert x[DA.Ip] == pytest.approx(np.sqrt(1.2**2 - iq**2), rel=1e-6)


def test_a_dera1_with_other_converter_records_is_left_out(tmp_path):
    """A DERA1 and a REGCA1 for one generator: both records left out, named with why, and
    the generator, left without a model, stops the import."""
    dyr = _dyr(tmp_path)
    regca1 = "102 'REGCA1' 1 1 0.02 10 0.9 0.4 1.22 1.2 0.8 0.4 -1.3 0.02 0.7 999 -999 0.7 /"
    dyr.write_text(dyr.read_text() + regca1 + "\n")
    with pytest.raises(CaseError, match=r"a DERA1 with other converter records \(REGCA1\)"):
        load_psse(RAW, dyr)


def test_power_factor_control_without_power_is_refused(tmp_path):
    """Bus 102's generator at PG 0 (its Q from the power flow): PfFlag 1 has no power
    factor to hold, refused naming the field; PfFlag 0 (constant Q) starts at rest and,
    held at 0.95 pu, settles at its Q0 (Iq = Q0/0.95)."""
    raw = tmp_path / "no_p.raw"
    text = RAW.read_text()
    assert text.count("   102,'1 ',   100.000,") == 1
    raw.write_text(text.replace("   102,'1 ',   100.000,", "   102,'1 ',     0.000,"))
    with pytest.raises(
        CaseError,
        match=r"field 'da_PfFlag': a DERA1 holding its power factor \(1\) needs \|P0\| >= 1e-06 pu",
    ):
        Simulator(load_psse(raw, _dyr(tmp_path)), background_compile=False)
    sim = Simulator(load_psse(raw, _dyr(tmp_path, (0, 0, 0, 1, 0, 0))), background_compile=False)
    Q0 = sim.model.cp.Q0[0]
    assert abs(sim.model.cp.P0[0]) < 1e-9 and Q0 > 0.1
    x, S = _settled(sim, 0.95)
    assert x[DA.Iq] == pytest.approx(Q0 / 0.95, rel=1e-9)
    assert S == pytest.approx(1j * Q0, abs=1e-9)


# ---------------------------------------------------------------------------------------
# FreqFlag 1, VtripFlag 1, FtripFlag 1: the README's CONs (Ddn 20, Dup 0, fdbd
# +-0.0006, Kpg 0.1, Kig 10, Pmax 1.1, Pmin 0, dPmax 0.5, dPmin -0.5, Tpord 0.02, vl0
# 0.44, vl1 0.49, vh1 1.15, vh0 1.2, tvl* 0.16, Vrfrac 0.7, Tv 0.02) on MBASE 100 MVA =
# the system base (device-base powers equal the system-base ones)
# ---------------------------------------------------------------------------------------


def _sim(tmp_path, flags, **cons):
    return Simulator(load_psse(RAW, _dyr(tmp_path, flags, **cons)), background_compile=False)


def _held(sim, volts, t_end, h=1e-3, x=None, record=()):
    """Forward Euler of the DERA1 alone from its initial states (or x) at bus voltage
    volts(t) (complex pu): (states, injected S, {t: states} at the times of `record`)."""
    cp = sim.model.cp
    P, _, V_nc = conv.at_power_flow(cp, sim.op.V)
    if x is None:
        x = sim.model.layout.view(sim.model.x0, "ibr").copy()
    dx = np.zeros_like(x)
    seen = {}
    n = int(round(t_end / h))
    for j in range(n):
        conv.derivatives_at(P, x, np.array([volts(j * h)]), V_nc, dx)
        x += h * dx
        for t in record:
            if j + 1 == int(round(t / h)):
                seen[t] = x[:, 0].copy()
    S = conv.derivatives_at(P, x, np.array([volts(n * h)]), V_nc, dx)[0]
    return x, S, seen


def _at_frequency(sim, f, v=None):
    """The bus voltage of the DERA1 turning at frequency f (pu) from its initial
    phasor, |V| = v (default the initial)."""
    V0 = sim.op.V[sim.model.cp.bus_idx[0]]
    w = 2.0 * np.pi * sim.model.cp.fn[0] * (f - 1.0)
    mag = abs(V0) if v is None else v
    return lambda t: mag * np.exp(1j * (np.angle(V0) + w * t))


@pytest.fixture(scope="module")
def freq_sim(tmp_path_factory):
    return _sim(tmp_path_factory.mktemp("f1"), (1, 1, 0, 1, 0, 0))


def test_freqflag1_initial_states_are_psid_s(freq_sim):
    """PSID's initial point with FreqFlag 1 (test 42, x0_flag1): PowerPI = Pord = P0 = 1
    (PSID's dPord, its rate limiter's copy, also 1), the other states as FreqFlag 0's,
    within 1e-8 (stabctl's P0 0.9999999983, as there); theta_f the bus angle."""
    ref = PSID["x0_flag1"]
    names = ("Vmeas", "Pmeas", "Q_V", "Iq", "Mult", "Fmeas", "PowerPI", "dPord", "Pord", "Ip")
    psid = dict(zip(names, assert_start_is_psids(freq_sim, ref)))
    xi = freq_sim.model.layout.view(freq_sim.model.x0, "ibr")[:, 0]
    for name in ("Vmeas", "Pmeas", "Q_V", "Iq", "PowerPI", "Pord", "Ip"):
        assert xi[getattr(DA, name)] == pytest.approx(psid[name], abs=1e-8), name
    assert xi[DA.theta_f] == np.angle(freq_sim.op.V[freq_sim.model.cp.bus_idx[0]])
    assert psid["dPord"] == psid["Pord"] == psid["PowerPI"]


@pytest.mark.parametrize(
    ("f", "Dup", "dP"),
    [
        (1.002, 0.0, 20.0 * (-0.002 + 0.0006)),  # over-frequency: Ddn (1 - f + fdbd2)
        (0.997, 10.0, 10.0 * (0.003 - 0.0006)),  # under-frequency: Dup (1 - f + fdbd1)
        (0.997, 0.0, 0.0),  # under-frequency without Dup: none
        (1.0005, 0.0, 0.0),  # inside the deadband: none
    ],
)
def test_freqflag1_frequency_step_settles_at_the_droop(tmp_path, f, Dup, dP):
    """FreqFlag 1, the bus frequency held at f (pu): the PI brings the terminal power to
    P0 + Ddn min(ferr, 0) + Dup max(ferr, 0), ferr = dbd(1 - f, fdbd1, fdbd2) (the
    droop's closed form; 0 inside the deadband, where no state moves at all); its Q
    follows at tan(pfaref) P (PfFlag 1)."""
    sim = _sim(tmp_path, (1, 1, 0, 1, 0, 0), Dup=Dup)
    P0, Q0 = sim.model.cp.P0[0], sim.model.cp.Q0[0]
    x, S, _ = _held(sim, _at_frequency(sim, f), 5.0)
    assert S.real == pytest.approx(P0 + dP, abs=1e-9)
    assert S.imag == pytest.approx(Q0 * (P0 + dP) / P0, abs=1e-9)
    assert x[DA.Pord, 0] == pytest.approx(P0 + dP, abs=1e-9)
    if dP == 0.0:
        x0 = sim.model.layout.view(sim.model.x0, "ibr")
        moved = np.delete(np.abs(x - x0)[:, 0], DA.theta_f)  # theta_f turns with the bus
        assert moved.max() < 1e-12


def test_freqflag1_pord_falls_at_dpmin(freq_sim):
    """A large over-frequency (f = 1.01: the droop asks -0.188 pu): Pord falls at dPmin =
    -0.5 pu/s, the rate limit, not at its lag's rate (u - Pord)/Tpord: over 0.05-0.10 s
    exactly -0.025 pu."""
    _, _, seen = _held(freq_sim, _at_frequency(freq_sim, 1.01), 0.1, h=1e-4, record=(0.05, 0.1))
    assert seen[0.1][DA.Pord] - seen[0.05][DA.Pord] == pytest.approx(-0.5 * 0.05, abs=1e-12)


def test_freqflag1_pord_lags_through_tpord(tmp_path):
    """The power order's lag: with the PI's gains 0 its output is its state, set 0.002 pu
    above P0: Pord rises as 0.002 (1 - exp(-t/Tpord)), Tpord 0.02 s (the rate 0.1 pu/s
    inside dPmax 0.5); its rate at the start is 0.002/Tpord."""
    sim = _sim(tmp_path, (1, 1, 0, 1, 0, 0), Kpg=0.0, Kig=0.0)
    P0 = sim.model.cp.P0[0]
    x = sim.model.layout.view(sim.model.x0, "ibr").copy()
    x[DA.PowerPI, 0] += 0.002
    V0 = sim.op.V[sim.model.cp.bus_idx[0]]
    P, _, V_nc = conv.at_power_flow(sim.model.cp, sim.op.V)
    dx = np.zeros_like(x)
    conv.derivatives_at(P, x.copy(), np.array([V0]), V_nc, dx)
    assert dx[DA.Pord, 0] == pytest.approx(0.002 / 0.02, rel=1e-9)
    _, _, seen = _held(sim, lambda t: V0, 0.04, h=1e-6, x=x, record=(0.02, 0.04))
    for t, rise in seen.items():
        assert rise[DA.Pord] - P0 == pytest.approx(0.002 * (1 - np.exp(-t / 0.02)), rel=1e-4)


def test_freqflag1_and_trips_start_flat(tmp_path):
    """FreqFlag, VtripFlag and FtripFlag 1 on PSS/E's ThreeBus case: its initial point is at
    rest (the largest derivative below 1e-12) and 5 s without disturbance move no state by
    1e-9."""
    from runs import flat_run

    case = load_psse(RAW, _dyr(tmp_path, (1, 1, 0, 1, 1, 1), fl=0.98, fh=1.02, tfl=0.16, tfh=0.16))
    drift, _ = flat_run(case, t_end=5.0)
    assert drift < 1e-9
    sim = Simulator(case, background_compile=False)
    assert sim.model.initial_residual[0] < 1e-12


def _dip(v_dip, t_dip):
    return lambda t: v_dip if t < t_dip else 1.0


@pytest.fixture(scope="module")
def vtrip_sim(tmp_path_factory):
    """VtripFlag 1, FreqFlag 0; the bus voltage at 1 pu (its initial |V| 1.0000000)."""
    return _sim(tmp_path_factory.mktemp("vt"), (1, 0, 0, 1, 1, 0))


def test_a_dip_below_vl1_trips_the_share_then_vrfrac_reconnects(vtrip_sim):
    """|V| held at 0.47 pu for 1 s (between vl0 0.44 and vl1 0.49, beyond tvl1 0.16 s):
    the output is lowered at once to (0.47 - vl0)/(vl1 - vl0) = 0.6 (before tvl1, through
    Tv 0.02 s: forward Euler's 0.6 + 0.4 0.95^150 at 0.15 s; PowerWorld's DER_A page,
    InterPSS, Dynawo), then the share 0.4 trips and the multiplier stays at 0.6; the
    currents there are 0.6 times their commands (Iq = 0.6 Q0/0.47, Ip = 0.6 sqrt(Imax^2 -
    Iq^2), Q priority).  Back at 1 pu for 1 s, Vrfrac 0.7 of the tripped reconnect: 0.6 +
    0.7 0.4 = 0.88 of P0 + j Q0."""
    P0, Q0 = vtrip_sim.model.cp.P0[0], vtrip_sim.model.cp.Q0[0]
    x, S, seen = _held(vtrip_sim, _dip(0.47, 1.0), 1.0, record=(0.15,))
    m = (0.47 - 0.44) / (0.49 - 0.44)
    assert seen[0.15][DA.Mult] == pytest.approx(m + (1 - m) * 0.95**150, abs=1e-12)
    assert seen[0.15][DA.mpre_l] == 1.0  # nothing tripped yet
    assert x[DA.Mult, 0] == pytest.approx(m, abs=1e-9)
    iq = m * Q0 / 0.47
    assert x[DA.Iq, 0] == pytest.approx(iq, abs=1e-9)
    assert x[DA.Ip, 0] == pytest.approx(m * np.sqrt(1.2**2 - iq**2), abs=1e-6)
    x, S, _ = _held(vtrip_sim, _dip(0.47, 1.0), 2.0)
    back = m + 0.7 * (1 - m)
    assert x[DA.Mult, 0] == pytest.approx(back, abs=1e-9)
    assert S == pytest.approx(back * (P0 + 1j * Q0), abs=1e-8)


def test_a_dip_shorter_than_tvl1_trips_nothing(vtrip_sim):
    """|V| at 0.47 pu for 0.1 s (< tvl1 0.16 s), then 1 pu: the output lowered with the
    voltage during the dip (the multiplier toward 0.6 through Tv: forward Euler's 0.6 +
    0.4 0.95^n after n steps of 1 ms), nothing tripped (m_pre stays 1), and it settles back
    at P0 + j Q0."""
    P0, Q0 = vtrip_sim.model.cp.P0[0], vtrip_sim.model.cp.Q0[0]
    x, S, seen = _held(vtrip_sim, _dip(0.47, 0.1), 2.0, record=(0.05, 0.1, 0.5))
    for t in (0.05, 0.1):
        assert seen[t][DA.Mult] == pytest.approx(0.6 + 0.4 * 0.95 ** round(t / 1e-3), abs=1e-12)
    assert all(s[DA.mpre_l] == 1.0 for s in seen.values()) and x[DA.mpre_l, 0] == 1.0
    assert x[DA.Mult, 0] == pytest.approx(1.0, abs=1e-12)
    assert S == pytest.approx(P0 + 1j * Q0, abs=1e-9)


def test_after_the_trip_the_multiplier_follows_the_depressed_curve(vtrip_sim):
    """|V| 0.47 pu for 0.3 s (the trip at tvl1 0.16 s with the minimum from then on,
    0.47), then 0.48 pu (still below vl1 0.49) for 0.7 s: the multiplier rises with the
    share Vrfrac 0.7 of the recovery, ((0.47 - 0.44) + 0.7 (0.48 - 0.47))/(0.49 - 0.44) =
    0.74 (PowerWorld's "depressed curve according to Vrfrac and ... the minimum voltage",
    InterPSS's DER_A_PosSeqImpl), and back above vl1 it is the reconnected share 0.6 + 0.7
    0.4 = 0.88, continuous with that curve at vl1."""
    x, _, _ = _held(vtrip_sim, lambda t: 0.47 if t < 0.3 else 0.48, 1.0)
    assert x[DA.Mult, 0] == pytest.approx(((0.47 - 0.44) + 0.7 * 0.01) / 0.05, abs=1e-9)
    x, _, _ = _held(vtrip_sim, lambda t: 0.47 if t < 0.3 else (0.48 if t < 1.0 else 1.0), 2.0)
    assert x[DA.Mult, 0] == pytest.approx(0.88, abs=1e-9)
    assert x[DA.mpre_l, 0] == pytest.approx(0.88, abs=1e-12)


def test_a_dip_below_vl0_beyond_tvl0_trips_all_for_good(vtrip_sim):
    """|V| at 0.40 pu (< vl0 0.44) for 0.2 s (> tvl0 0.16 s), then 1 pu: all trip and none
    reconnects (the multiplier's target 0)."""
    x, S, _ = _held(vtrip_sim, _dip(0.40, 0.2), 2.0)
    assert x[DA.mpre_l, 0] == 0.0
    assert abs(x[DA.Mult, 0]) < 1e-9 and abs(S) < 1e-8


def test_a_swell_above_vh1_trips_the_share(vtrip_sim):
    """|V| at 1.17 pu for 1 s (between vh1 1.15 and vh0 1.2, beyond tvh1 0.16 s): the share
    (1.17 - vh1)/(vh0 - vh1) = 0.4 trips: 0.6 (P0 + j Q0) (constant power within its
    limits, Q0 = tan(pfaref) P0)."""
    P0, Q0 = vtrip_sim.model.cp.P0[0], vtrip_sim.model.cp.Q0[0]
    x, S, _ = _held(vtrip_sim, lambda t: 1.17, 1.0)
    m = (1.2 - 1.17) / (1.2 - 1.15)
    assert x[DA.Mult, 0] == pytest.approx(m, abs=1e-9)
    assert S == pytest.approx(m * (P0 + 1j * Q0), abs=1e-8)


@pytest.mark.parametrize(("v", "trips"), [(None, True), (0.7, False)])
def test_frequency_below_fl_beyond_tfl_trips_all(tmp_path, v, trips):
    """FtripFlag 1 (fl 0.99, tfl 0.1 s), the bus frequency held at 0.98 pu: Fmeas (lag Trf
    0.02 s) crosses fl at 0.02 ln 2 = 0.0139 s and all trip 0.1 s later (not at 0.1 s,
    at 0.13 s), the multiplier then falling through Tv to 0; with |V| 0.7 below Vpr 0.8
    the frequency trip is blocked."""
    sim = _sim(tmp_path, (1, 0, 0, 1, 0, 1), fl=0.99, tfl=0.1)
    x, S, seen = _held(sim, _at_frequency(sim, 0.98, v), 1.0, h=1e-4, record=(0.1, 0.13))
    assert seen[0.1][DA.ftrip] == 0.0
    assert seen[0.13][DA.ftrip] == (1.0 if trips else 0.0)
    if trips:
        assert abs(x[DA.Mult, 0]) < 1e-9 and abs(S) < 1e-8
    else:
        assert x[DA.Mult, 0] == 1.0


def test_trip_bands_out_of_order_are_refused(tmp_path):
    """VtripFlag 1 with vl0 0.5 above vl1 0.49: refused naming the record and both
    parameters as written, as the DYR import writes the table."""
    with pytest.raises(
        CaseError,
        match=r"dera1\.dyr:\d+ DERA1 \(bus 102, id 1\): vl0 = 0\.5, vl1 = 0\.49: the DERA1's "
        r"trip bands must be vl0 < vl1 <= vh1 < vh0",
    ):
        _sim(tmp_path, (1, 0, 0, 1, 1, 0), vl0=0.5)


@pytest.mark.parametrize(
    ("flags", "cons", "said"),
    [
        (
            (1, 0, 0, 1, 0, 0),
            {"Iqh1": -1.0, "Iql1": 1.0},
            r"Iqh1 = -1(\.0)?, Iql1 = 1(\.0)?: .*Iqh1 >= ",
        ),
        (
            (1, 1, 0, 1, 0, 0),
            {"dPmax": -0.5, "dPmin": 0.5},
            r"dPmax = -0\.5, dPmin = 0\.5: .*<= 0 <=",
        ),
        (
            (1, 1, 0, 1, 0, 0),
            {"femax": -99.0, "femin": 99.0},
            r"femax = -99(\.0)?, femin = 99(\.0)?: .*femax >= ",
        ),
        (
            (1, 1, 0, 1, 0, 0),
            {"Pmax": 0.0, "Pmin": 1.1},
            r"Pmax = 0(\.0)?, Pmin = 1\.1: .*Pmax >= ",
        ),
    ],
)
def test_limit_pairs_out_of_order_are_refused_at_import(tmp_path, flags, cons, said):
    """Round 44: Iqh1 below Iql1 imported and ran (exit 0, another Q at the fault); with
    FreqFlag 1 dPmax < 0 < dPmin, femax < femin and Pmax < Pmin imported and only the
    first run refused them, without naming the field.  Each is refused at import naming
    the record and its fields, as REECA1's and REPCA1's pairs are."""
    with pytest.raises(CaseError, match=r"dera1\.dyr:\d+ DERA1 \(bus 102, id 1\): " + said):
        load_psse(RAW, _dyr(tmp_path, flags, **cons))


def test_freqflag1_line_trip_settles_where_freqflag0_does(tmp_path):
    """PSS/E's ThreeBus event (line 101-102 tripped, here at 1 s, 6 s at 5 ms) with
    FreqFlag, VtripFlag and FtripFlag 1: the infinite bus brings the frequency back to 1,
    the PI the power to Pref, and |V102| stays inside [vl1, vh1] (nothing trips): the
    run ends at P0 + j Q0 (within 1e-9) with the bus voltages of the FreqFlag 0 run
    (within 1e-9)."""
    from stabctl.dynamics.events import LineTrip

    ends = []
    for flags in ((1, 1, 0, 1, 1, 1), (1, 0, 0, 1, 0, 0)):
        sim = _sim(tmp_path, flags)
        res = sim.run([LineTrip(101, 102, 1.0)], t_end=6.0, h=0.005)
        S0 = sim.model.cp.P0[0] + 1j * sim.model.cp.Q0[0]
        assert res.ibr_p[-1, 0] + 1j * res.ibr_q[-1, 0] == pytest.approx(S0, abs=1e-9)
        assert res.vmag[:, 1].min() > 0.49 and res.vmag[:, 1].max() < 1.15
        ends.append(res.vmag[-1] * np.exp(1j * res.vang[-1]))
    np.testing.assert_allclose(ends[0], ends[1], rtol=0, atol=1e-9)
