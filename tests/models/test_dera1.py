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
    for name in DA._fields:
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


@pytest.mark.parametrize("flag", ["FreqFlag", "VtripFlag", "FtripFlag"])
def test_flags_it_does_not_model_are_refused(tmp_path, flag):
    flags = dict(zip(("PfFlag", "FreqFlag", "PQFlag", "GenFlag", "VtripFlag", "FtripFlag"),
                     (1, 0, 0, 1, 0, 0)))  # fmt: skip
    flags[flag] = 1
    with pytest.raises(CaseError, match=rf"DERA1 \(bus 102, id 1\): {flag} = 1 switches on"):
        load_psse(RAW, _dyr(tmp_path, tuple(flags.values())))


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
