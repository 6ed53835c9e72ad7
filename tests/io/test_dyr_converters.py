"""Converter records read natively from a PSS/E DYR file (stabctl.io.dyr_converters): the
row import-andes builds from the same data, PSS/E's own-bus and no-filter readings, and
the records left out with why.  The RAW + DYR data are PSS/E's RENA run
(tests/data/psse_runs/RENA_DEFAULT, PowerSimulationsDynamics.jl, BSD-3; the agreement with
PSS/E's trajectories is tests/io/test_psse_runs.py)."""

import os
import warnings
from pathlib import Path

import numpy as np
import pytest

from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import Fault, LineTrip
from stabctl.errors import CaseError, SimulationError
from stabctl.io.dyr import CONVERTER_DYR, read_dyr
from stabctl.io.psse import import_psse, load_psse
from stabctl.models.converters import CONVERTER, REECB1, REECD1, REGC_B, REGCA1, REPCA1

RENA = Path(__file__).resolve().parents[1] / "data" / "psse_runs" / "RENA_DEFAULT"
RAW = RENA / "ThreeBusRenewable.raw"
DYR = RENA / "ThreeBus_REN_A_DEFAULT_FLAG.dyr"
#: the ibr_con fields set by where the plant is, not by its records
_PLACE = ("number", "bus", "mva", "pfrac", "qfrac")


def _text(rec, **change) -> str:
    """DYR text of record ``rec`` with the fields ``change`` (name -> value) replaced."""
    from stabctl.io.dyr import CONVERTER_DYR, DYR_MODELS

    fields = (DYR_MODELS | CONVERTER_DYR)[rec.model].fields
    text = iter(rec.text)
    vals = []
    for name, v in zip(fields, rec.params):
        v = change.get(name, v)
        vals.append(f"'{next(text)}'" if name == "CKTID" else repr(float(v)))
    return f"{rec.bus} '{rec.model}' '{rec.id}' {' '.join(vals)} /\n"


def _dyr(tmp_path, records, name="plant.dyr") -> Path:
    path = tmp_path / name
    path.write_text("".join(records))
    return path


def _row(table, k=0) -> dict:
    return {p.name: float(getattr(table, p.name)[k]) for p in CONVERTER.params}


def test_rena_reads_as_one_regca1_with_its_reecb1_and_repca1():
    """PSS/E's RENA record values (their file lines) land in their ibr_con columns: the
    ICONs (REGCA1 Lvplsw 0, REECB1 IREG PFFLAG VFLAG QFLAG PQFLAG 0 0 0 0 0) first, then
    REGCA1's Tg 0.02, REECB1's Tp 0 (no filter) and Imax 1.11, REPCA1's Kp 18, Tp 0.25."""
    res = import_psse(RAW, DYR)
    assert res.left_out == ()
    t = res.case.converters
    assert len(t) == 1 and len(res.case.machines) == 1  # the GENCLS infinite bus
    row = _row(t)
    assert (row["type"], row["reec"], row["repc"], row["bus"]) == (REGCA1, REECB1, REPCA1, 103)
    assert (row["Lvplsw"], row["Tg"], row["Rrpwr"], row["Iqrmin"]) == (0.0, 0.02, 10.0, -100.0)
    assert (row["VFLAG"], row["QFLAG"], row["pqflag"], row["Tp"], row["Imax"]) == (
        0.0,
        0.0,
        0.0,
        0.0,
        1.11,
    )
    assert (row["Vdip"], row["Kvi"], row["tiq"], row["Tpord"]) == (-99.0, 60.0, 0.02, 0.02)
    assert (row["pc_Kp"], row["pc_Ki"], row["pc_Tp"], row["pc_Dup"]) == (18.0, 5.0, 0.25, 0.0)
    assert (row["pc_bus1"], row["pc_bus2"]) == (0.0, 0.0)  # BUS1 BUS2 0 0: no branch
    assert res.case.machines.H[0] == 0.0  # the GENCLS H = 0 infinite bus


def test_repca1_p_bounds_are_the_p_reference_bounds_of_pss_e():
    """PSS/E's REPCA1 limits its P reference, which starts at the dispatch (the Model
    Library's block diagram; GridPACK's repca1.cpp initialises its PI at Pref = Pg): the
    table's bounds of the increment are Pmax - P0, Pmin - P0, P0 = PG / MBASE; ANDES's
    reading keeps the file's numbers."""
    from stabctl.io.psse_raw import read_raw

    gen = read_raw(RAW).generators[-1]
    p0 = gen.pg / gen.mbase
    rec = next(r for r in read_dyr(DYR) if r.model == "REPCA1")
    given = CONVERTER_DYR["REPCA1"].values(rec.params)
    psse, andes = (_row(load_psse(RAW, DYR, conventions=c).converters) for c in ("psse", "andes"))
    assert (andes["pc_Pmax"], andes["pc_Pmin"]) == (given["Pmax"], given["Pmin"])
    assert psse["pc_Pmax"] == pytest.approx(given["Pmax"] - p0, abs=1e-15)
    assert psse["pc_Pmin"] == pytest.approx(given["Pmin"] - p0, abs=1e-15)
    assert 0 < p0 < given["Pmax"]


@pytest.fixture
def own_bus_andes(monkeypatch):
    """ANDES's DYR reading with its REECx ``busr`` None: ANDES reads PSS/E's IREG = 0 (own
    bus) as bus 0, which import-andes refuses as a remote bus."""
    pytest.importorskip("andes")
    import stabctl.io.andes_case as ac

    load = ac._load

    def own_bus(path, dyr, said):
        ss = load(path, dyr, said)
        for name in ("REECA1", "REECB1"):
            ss.models[name].busr.v[:] = [None] * ss.models[name].n
        return ss

    monkeypatch.setattr(ac, "_load", own_bus)
    return ac.read_andes_case


def test_rena_row_and_trip_as_import_andes_reads_the_same_dyr(tmp_path, own_bus_andes):
    """The DYR-read plant is import-andes's row for the same RAW + DYR, column for column,
    and runs PSS/E's line trip the same (V103, P, Q within 1e-9).  Two readings ANDES
    does not share are set aside: its REECB1 refuses Tp = 0 (RENA's; 0.02 s here) and
    reads IREG = 0 as bus 0 (`own_bus_andes`); and read like for like, with ANDES's
    conventions (its REPCA1's Pmax, Pmin bound the increment Pext)."""
    recs = read_dyr(DYR)
    dyr = _dyr(tmp_path, [_text(r, **({"Tp": 0.02} if r.model == "REECB1" else {})) for r in recs])
    native = load_psse(RAW, dyr, conventions="andes")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        andes = own_bus_andes(RAW, dyr=dyr).case
    assert _row(native.converters) == _row(andes.converters)
    runs = [
        Simulator(c, q_limits=False).run([LineTrip(101, 103, 1.0)], 2.0, h=0.005)
        for c in (native, andes)
    ]
    k = [list(c.buses.number).index(103) for c in (native, andes)]
    n, a = runs
    assert np.max(np.abs(n.vmag[:, k[0]] - a.vmag[:, k[1]])) < 1e-9
    assert np.max(np.abs(n.ibr_p - a.ibr_p)) < 1e-9
    assert np.max(np.abs(n.ibr_q - a.ibr_q)) < 1e-9
    assert np.ptp(n.vmag[:, k[0]]) > 5e-3  # the trip moves V103 (1.015 -> 1.0245)


#: PSS/E Model Library orders (ICONs first) -> ANDES 2.0's parameter names, written
#: here from the Model Library, independently of the declarations under test
_PSSE_ORDER = {
    "REGCA1": "Lvplsw Tg Rrpwr Brkpt Zerox Lvpl1 Volim Lvpnt1 Lvpnt0 Iolim Tfltr Khv Iqrmax "
    "Iqrmin -",
    "REECA1": "busr PFFLAG VFLAG QFLAG PFLAG PQFLAG Vdip Vup Trv dbd1 dbd2 Kqv Iqh1 Iql1 "
    "Vref0 Iqfrz Thld Thld2 Tp QMax QMin VMAX VMIN Kqp Kqi Kvp Kvi Vref1 Tiq dPmax dPmin "
    "PMAX PMIN Imax Tpord Vq1 Iq1 Vq2 Iq2 Vq3 Iq3 Vq4 Iq4 Vp1 Ip1 Vp2 Ip2 Vp3 Ip3 Vp4 Ip4",
    "WTDTA1": "H DAMP Htfrac Freq1 Dshaft",
    "WTARA1": "Ka theta0",
    "WTPTA1": "Kiw Kpw Kic Kpc Kcc Tp thmax thmin dthmax dthmin",
    "WTTQA1": "Tflag Kpp Kip Tp Twref Temax Temin p1 sp1 p2 sp2 p3 sp3 p4 sp4 Tn",
}


def test_wind_turbine_records_read_as_andes_reads_its_wind_case(tmp_path):
    """ANDES's ieee14_wt3 plant (REGCA1 + REECA1 + WTDTA1 + WTARA1 + WTPTA1 + WTTQA1),
    written as PSS/E DYR records in the Model Library's orders and read natively on
    RENA's bus 103, gives import-andes's row of that plant, column for column but the
    place (number, bus, base, shares) and its REPCA1's (not written: its monitored line
    is ieee14's).  (ANDES's own DYR reader fails on WTARA1 and
    WTTQA1 records: its WTARA1 lookup and its WTTQA1 TRATE mapping.)"""
    andes = pytest.importorskip("andes")
    from stabctl.io.andes_case import read_andes_case

    case = os.path.join(os.path.dirname(andes.__file__), "cases", "ieee14", "ieee14_wt3.xlsx")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ss = andes.load(case, setup=True, no_output=True, default_config=True)
        want = _row(read_andes_case(case, on_unsupported="skip").case.converters)
    assert want["wind"] and want["aero"] and want["pitch"] and want["torque"]
    lines = ["102 'GENCLS' 1 0.0 0.0 /\n"]
    for model, order in _PSSE_ORDER.items():
        m = ss.models[model]
        vals = []
        for name in order.split():
            if name == "busr" or name == "-":  # IREG 0 (own bus); REGCA1's Accel
                vals.append("0")
                continue
            v = m.params[name].vin[0]
            vals.append(repr(float(0.0 if v is None or not np.isfinite(v) else v)))
        lines.append(f"103 '{model}' 1 {' '.join(vals)} /\n")
    # read like for like: ANDES's readings of the wind models (PSS/E's: ``psse`` 1)
    got = _row(load_psse(RAW, _dyr(tmp_path, lines), conventions="andes").converters)
    plant = ("repc", "Tfm", "Twm")  # ieee14_wt3's REPCA1, on its own network: not written
    same = [k for k in got if k not in _PLACE + plant and not k.startswith("pc_")]
    differ = {k: (got[k], want[k]) for k in same if got[k] != want[k]}
    assert differ == {}


#: a REGCA1 + REECA1 plant on RENA's bus 103 (ANDES's ieee14_wt3 values in the Model
#: Library's orders; its VDL1 Iq (2, 4, 8, 10) at Vq (0.2, 0.4, 0.8, 1.0)), the CONs from
#: Vq1 on written by `_reeca1_plant`
_REECA1_PLANT = (
    "102 'GENCLS' 1 0.0 0.0 /\n"
    "103 'REGCA1' 1 1 0.1 999.0 0.8 0.5 1.0 1.2 1.0 0.4 0.0 0.1 0.7 1.0 -1.0 0 /\n"
    "103 'REECA1' 1 0 0 0 0 0 0 0.8 1.1 0.02 -0.02 0.02 20.0 999.0 -999.0 1.03 0.0 -2.0 "
    "1.0 0.02 999.0 -999.0 999.0 -999.0 1.0 0.1 1.0 0.1 1.03 0.02 999.0 -999.0 999.0 "
    "-999.0 10.0 0.02 {vdl} /\n"
)


def _reeca1_plant(tmp_path, vq=(0.2, 0.4, 0.8, 1.0), iq=(2.0, 4.0, 8.0, 10.0)) -> Path:
    """`_REECA1_PLANT` with VDL1 (vq, iq) and VDL2 0.2 2 0.4 4 0.8 8 1.0 10."""
    vdl1 = " ".join(f"{v} {i}" for v, i in zip(vq, iq))
    text = _REECA1_PLANT.format(vdl=vdl1 + " 0.2 2.0 0.4 4.0 0.8 8.0 1.0 10.0")
    return _dyr(tmp_path, [text])


def test_reeca1_vdl_curve_reads_as_psse_takes_it(tmp_path):
    """Round 43: a VDL1 curve with one falling current switched the whole curve off
    without a word (ANDES's zVDL1); PSS/E interpolates its currents as given (it applies);
    voltages that fall are refused naming the record; all points 0 is no curve (Imax
    alone), named at import (every run was refused at a current limit 0)."""
    case = load_psse(RAW, _reeca1_plant(tmp_path, iq=(1.0, 0.5, 8.0, 10.0)))
    sim = Simulator(case)
    assert sim.model.cp.zVDL1[0] == 1.0 and case.converters.Iq2[0] == 0.5
    with pytest.raises(CaseError, match=r"plant\.dyr:3 REECA1 .*Vq3 = 0\.3.*Vq1 <= Vq2 <= Vq3"):
        load_psse(RAW, _reeca1_plant(tmp_path, vq=(0.2, 0.4, 0.3, 1.0)))
    with pytest.warns(UserWarning, match=r"plant\.dyr:3 REECA1 .*VDL1 .*all 0: read as no curve"):
        case = load_psse(RAW, _reeca1_plant(tmp_path, vq=(0.0,) * 4, iq=(0.0,) * 4))
    sim = Simulator(case)
    assert sim.model.cp.zVDL1[0] == 0.0 and sim.model.cp.zVDL2[0] == 1.0
    assert sim.run([], 0.5).verdict == "stable"


def _rena(tmp_path, **change) -> Path:
    """RENA's DYR with ``change``: model -> {field: value}."""
    recs = read_dyr(DYR)
    return _dyr(tmp_path, [_text(r, **change.get(r.model, {})) for r in recs])


def test_remote_regulation_is_left_out_naming_the_record(tmp_path):
    """IREG other than 0 or the plant's bus: the whole plant (its three records) left out
    with the REECB1's file:line and why; the generator then has no model (refused)."""
    dyr = _rena(tmp_path, REECB1={"IREG": 101})
    with pytest.raises(CaseError, match=r"plant\.dyr:3 REECB1 at bus 103 '1': REECB1 regulates"):
        import_psse(RAW, dyr)
    with (
        pytest.raises(CaseError, match=r"generator\(s\) left without a model, .*: bus 103 '1'"),
        pytest.warns(UserWarning, match="left out 3 unsupported record"),
    ):
        import_psse(RAW, dyr, on_unsupported="skip")
    from stabctl.io.dyr_converters import converter_rows
    from stabctl.io.psse_raw import read_raw

    raw = read_raw(RAW)
    res = converter_rows(read_dyr(dyr), [g.as_dyr() for g in raw.generators], raw.line)
    assert res.rows == [] and [r.model for r, _ in res.skipped] == ["REGCA1", "REECB1", "REPCA1"]
    assert all(
        why == "REECB1 regulates remote bus IREG = 101 (stabctl: its own)" for _, why in res.skipped
    )
    own = _rena(tmp_path, REECB1={"IREG": 103}, REPCA1={"IREG": 103})
    assert import_psse(RAW, own).left_out == ()  # its own bus, given by number


def test_monitored_branch_is_the_raw_branch(tmp_path):
    """REPCA1's BUS1 BUS2 name the RAW branch 103-101 (r 0.01, x 0.12 on 100 MVA)."""
    dyr = _rena(tmp_path, REPCA1={"BUS1": 103, "BUS2": 101})
    row = _row(load_psse(RAW, dyr).converters)
    assert (row["pc_bus1"], row["pc_bus2"], row["pc_r"], row["pc_x"]) == (103, 101, 0.01, 0.12)
    far = _rena(tmp_path, REPCA1={"BUS1": 101, "BUS2": 102})
    with pytest.raises(CaseError, match=r"REPCA1 monitors branch 101-102, which does not end"):
        import_psse(RAW, far)
    with pytest.raises(CaseError, match=r"103-104 circuit '0': 0 in-service RAW branches join"):
        import_psse(RAW, _rena(tmp_path, REPCA1={"BUS1": 103, "BUS2": 104}))


@pytest.mark.parametrize(
    "change, message",
    [
        (
            {"REECB1": {"PQFLAG": 2}},
            r"plant\.dyr:\d+ REECB1 \(bus 103, id 1\): PQFLAG = 2 must be one of 0, 1",
        ),
        (
            {"REGCA1": {"Lvplsw": 0.5}},
            r"REGCA1 \(bus 103, id 1\): Lvplsw = 0.5 must be one of 0, 1",
        ),
    ],
)
def test_a_flag_out_of_its_choices_is_refused_naming_the_record(tmp_path, change, message):
    with pytest.raises(CaseError, match=message):
        import_psse(RAW, _rena(tmp_path, **change))


@pytest.mark.parametrize(
    "model, field",
    [("REPCA1", "Kp"), ("REPCA1", "Ki"), ("REPCA1", "Kpg"), ("REPCA1", "Kig"), ("REECB1", "Kqp")]
    + [("REECB1", "Kvi")],
)
def test_a_negative_pi_gain_is_refused_naming_the_record(tmp_path, model, field):
    """Round 40: REPCA1's Kp of -18 (a positive feedback) was read without a word, where
    K_A, Kqv and Khv below 0 are refused (WECC REPC_A, REEC_B: the PI gains are >= 0)."""
    with pytest.raises(CaseError, match=rf"{model} \(bus 103, id 1\): {field} = -\d.*must be >= 0"):
        import_psse(RAW, _rena(tmp_path, **{model: {field: -1.5}}))


def test_repca1_circuit_id_must_be_quoted(tmp_path):
    text = DYR.read_text().replace("'0 '", "0")
    with pytest.raises(CaseError, match=r"REPCA1 \(bus 103, id 1\): CKTID = 0: not a quoted id"):
        read_dyr(_dyr(tmp_path, [text]))


def test_control_records_without_regca1_are_left_out(tmp_path):
    """A REECB1 and REPCA1 without their REGCA1: each left out, named; the generator,
    without a model, netted on request."""
    recs = [r for r in read_dyr(DYR) if r.model != "REGCA1"]
    with (
        pytest.warns(UserWarning, match="left out 2 unsupported record"),
        pytest.warns(UserWarning, match="netted 1 generator"),
    ):
        res = import_psse(
            RAW, _dyr(tmp_path, [_text(r) for r in recs]), on_unsupported="skip", unmodelled="net"
        )
    assert res.left_out == (
        "plant.dyr:2 REECB1 at bus 103 '1': no REGCA1 or REGCB1 record for its generator",
        "plant.dyr:3 REPCA1 at bus 103 '1': no REGCA1 or REGCB1 record for its generator",
    )
    assert res.netted == (
        "ThreeBusRenewable.raw:13 generator at bus 103 '1': no machine model record in the "
        "DYR data",
    )


def test_a_plant_sharing_its_bus_takes_its_own_generation(tmp_path):
    """RENA with a second generator at bus 103 (PG 10 MW, QG 2.488 Mvar, a GENCLS of
    H = 3 s): the plant takes 40/50 of the bus's P and 9.952/12.44 of its Q, the machine
    the rest, as their RAW lines give; the case starts at rest."""
    lines = RAW.read_text().splitlines(keepends=True)
    k = next(j for j, s in enumerate(lines) if s.lstrip().startswith("103,'1 ',    40.000"))
    second = lines[k].replace("'1 ',    40.000,     9.952", "'2 ',    10.000,     2.488")
    raw = tmp_path / "shared.raw"
    raw.write_text("".join(lines[: k + 1] + [second] + lines[k + 1 :]))
    dyr = _dyr(tmp_path, [DYR.read_text(), "103 'GENCLS' 2 3.0 0.0 /\n"])
    case = load_psse(raw, dyr)
    t, m = case.converters, case.machines
    assert (t.pfrac[0], t.qfrac[0]) == pytest.approx((0.8, 9.952 / 12.44))
    k = list(m.bus).index(103)
    assert (m.pfrac[k], m.qfrac[k]) == pytest.approx((0.2, 2.488 / 12.44))
    res = Simulator(case, q_limits=False).run([], 0.5, h=0.005)
    assert np.max(np.abs(res.speed - 1.0)) < 1e-9
    assert np.max(np.abs(res.ibr_p[:, 0] - 0.4)) < 1e-9


@pytest.mark.parametrize(
    "extra, why",
    [
        ("103 'WTDTA1' 1 3.0 0.0 0.5 1.0 1.0 /\n", "a wind turbine without a REECA1"),
        ("103 'WTARA1' 1 1.0 0.0 /\n", "a wind turbine without a REECA1"),
    ],
)
def test_wind_records_of_a_reecb1_plant_leave_it_out(tmp_path, extra, why):
    """stabctl's wind turbine is a REECA1's (as import-andes): RENA's REECB1 plant with a
    wind record is left out whole, each record named with why."""
    model = extra.split("'")[1]
    with pytest.raises(CaseError, match=rf"plant\.dyr:21 {model} at bus 103 '1': {why}"):
        import_psse(RAW, _dyr(tmp_path, [DYR.read_text(), extra]))


def _regcb1_plant(tmp_path, regcb1="0 0 0.02 0.02 100.0 -100.0 10.0 0.02 1.11") -> tuple:
    """RENA's RAW + DYR with a REGCB1 record (ICONs RateFlag PQFlag, CONs Tg Tfltr Iqrmax
    Iqrmin Rrpwr Te Imax) in place of its REGCA1 and the plant's ZSORCE 0.2 pu (RENA's
    j9999: a current source)."""
    raw = RAW.read_text().replace("0.00000E+0, 9.99900E+3,", "0.00000E+0, 2.00000E-1,")
    recs = [r for r in read_dyr(DYR) if r.model != "REGCA1"]
    text = [f"103 'REGCB1' 1 {regcb1} /\n", *(_text(r) for r in recs)]
    (tmp_path / "plant.raw").write_text(raw)
    return tmp_path / "plant.raw", _dyr(tmp_path, text)


def test_regcb1_record_reads_as_the_regc_b_interface_with_its_zsorce(tmp_path):
    """The REGCB1's values land in the REGC_B columns (its Tg, Tfltr the REGCA1's), its
    source impedance the generator's ZSORCE on MBASE; the plant keeps its REECB1, REPCA1."""
    t = load_psse(*_regcb1_plant(tmp_path)).converters
    row = _row(t)
    assert (row["type"], row["regc"], row["reec"], row["repc"]) == (REGCA1, REGC_B, REECB1, REPCA1)
    assert (row["Tg"], row["Tfltr"], row["gb_Iqrmax"], row["gb_Iqrmin"]) == (
        0.02,
        0.02,
        100.0,
        -100.0,
    )
    assert (row["gb_Rrpwr"], row["gb_Te"], row["gb_Imax"]) == (10.0, 0.02, 1.11)
    assert (row["gb_Rsource"], row["gb_Xsource"]) == (0.0, 0.2)


def test_regcb1_plant_runs_flat_and_rides_through_a_fault(tmp_path):
    """REGCB1 + REECB1 + REPCA1 from the DYR: 10 s without a disturbance move no state
    (1e-8).  A 0.1 s fault at bus 101 drops V103 to about 0.58 pu: the internal voltage
    held, its current (E - v)/Z is beyond Imax 1.11 at once, all of it reactive (Q
    priority, PQFlag 0): Q = v Imax, P = 0; P returns to the dispatch within 1 % 2.4 s
    after the clearing."""
    from runs import flat_run

    case = load_psse(*_regcb1_plant(tmp_path))
    drift, _ = flat_run(case, t_end=10.0)
    assert drift < 1e-8
    res = Simulator(case, q_limits=False).run([Fault(101, 1.0, 1.1, x=1e-3)], 3.5, h=0.002)
    k = list(case.buses.number).index(103)
    on = np.searchsorted(res.t, 1.0)
    assert res.vmag[on, k] < 0.6
    assert res.ibr_q[on, 0] == pytest.approx(res.vmag[on, k] * 1.11, rel=1e-9)
    assert res.ibr_p[on, 0] == pytest.approx(0.0, abs=1e-12)
    assert abs(res.ibr_p[-1, 0] / res.ibr_p[0, 0] - 1.0) < 0.01


def test_two_converter_interfaces_leave_the_plant_out(tmp_path):
    """A REGCA1 and a REGCB1 for one generator: the plant (its four records) left out,
    each named with why."""
    from stabctl.io.dyr_converters import converter_rows
    from stabctl.io.psse_raw import read_raw

    raw, dyr = _regcb1_plant(tmp_path)
    regca1 = next(r for r in read_dyr(DYR) if r.model == "REGCA1")
    dyr.write_text(dyr.read_text() + _text(regca1))
    r = read_raw(raw)
    res = converter_rows(read_dyr(dyr), [g.as_dyr() for g in r.generators], r.line)
    assert res.rows == [] and len(res.skipped) == 4
    assert all(
        why == "two converter interfaces (REGCA1 and REGCB1; stabctl: one)"
        for _, why in res.skipped
    )


def test_a_machine_model_beside_a_converter_of_one_generator_is_named(tmp_path):
    """Round 30: RENA's GENCLS at bus 102 with a REGCA1 for that generator too was said
    to match "no generator in service (none at bus 102)": the converter had taken it."""
    regca1 = next(r for r in read_dyr(DYR) if r.model == "REGCA1")
    dyr = _dyr(tmp_path, [DYR.read_text(), _text(regca1).replace("103 ", "102 ", 1)])
    for how in ("error", "skip"):
        with pytest.raises(CaseError, match=r"GENCLS .*102.*: second source model for this "):
            import_psse(RAW, dyr, on_unsupported=how)


#: REECD1's own CONs in the plant of `_reecd1_plant`: VDL1 (Iq) flat at Imax, VDL2 (Ip)
#: rising from 0 at 0.2 pu to Imax at 0.5 pu (the rest of each table 0: unused), no
#: compensation, Tr1 0.02 s, Ke 1 (storage), no blocking band
_REECD1_OWN = {"Vq1": 0.0, "Iq1": 1.11, "Vq2": 2.0, "Iq2": 1.11}
_REECD1_OWN |= {"Vp1": 0.2, "Ip1": 0.0, "Vp2": 0.5, "Ip2": 1.11, "Vp3": 2.0, "Ip3": 1.11}
_REECD1_OWN |= {"Tr1": 0.02, "Ke": 1.0, "Vblkl": -1.0, "Vblkh": 9.0, "Tblk": 0.0}


def _reecd1_plant(tmp_path) -> tuple:
    """`_regcb1_plant` with a REECD1 in place of its REECB1: the REECB1's values (PSS/E's
    RENA), PMIN -1.2 (a battery's range), VCMPFLAG 0, Iqfrz Thld Thld2 0, Vbias 1 and
    `_REECD1_OWN`."""
    raw, dyr = _regcb1_plant(tmp_path)
    b1 = next(r for r in read_dyr(DYR) if r.model == "REECB1")
    vals = CONVERTER_DYR["REECB1"].values(b1.params) | {"PMIN": -1.2, "Vbias": 1.0}
    fields = CONVERTER_DYR["REECD1"].fields
    nums = [vals.get(f, _REECD1_OWN.get(f, 0.0)) for f in fields]
    rec = f"103 'REECD1' 1 {' '.join(repr(float(v)) for v in nums)} /\n"
    dyr.write_text(
        "".join(ln for ln in dyr.read_text().splitlines(True) if "REECB1" not in ln) + rec
    )
    return raw, dyr


def test_reecd1_record_reads_into_reeca1_s_columns_and_its_own(tmp_path):
    """REECD1's 6 ICONs and 77 CONs: the shared ones in REECA1's columns (Vbias in Vref1's),
    the ten-point tables in Vq1 ... Ip10, its own in ``rd_``; no IREG (its own bus)."""
    t = load_psse(*_reecd1_plant(tmp_path)).converters
    row = _row(t)
    assert (row["reec"], row["regc"], row["repc"]) == (REECD1, REGC_B, REPCA1)
    assert (row["Kvi"], row["Imax"], row["PMIN"], row["Vref1"], row["tiq"]) == (
        60.0,
        1.11,
        -1.2,
        1.0,
        0.02,
    )
    assert (row["Vp2"], row["Ip2"], row["Vp3"], row["Vp4"], row["Ip10"]) == (0.5, 1.11, 2.0, 0, 0)
    assert (row["rd_Tr1"], row["rd_Ke"], row["rd_Vblkl"], row["rd_Vblkh"]) == (0.02, 1.0, -1.0, 9.0)


def test_reecd1_plant_runs_flat_and_through_a_fault(tmp_path):
    """REGCB1 + REECD1 + REPCA1 from the DYR: 10 s without a disturbance move no state
    (1e-8); through a 0.1 s fault at bus 101 it returns to its dispatch within 1 %."""
    from runs import flat_run

    case = load_psse(*_reecd1_plant(tmp_path))
    drift, _ = flat_run(case, t_end=10.0)
    assert drift < 1e-8
    res = Simulator(case, q_limits=False).run([Fault(101, 1.0, 1.1, x=1e-3)], 3.5, h=0.002)
    assert np.all(np.isfinite(res.ibr_p))
    assert abs(res.ibr_p[-1, 0] / res.ibr_p[0, 0] - 1.0) < 0.01


def test_a_converter_record_of_no_generator_is_named_with_the_generator_it_left_bare(tmp_path):
    """RENA's REGCA1 plant written at bus 999, where the RAW has no generator: the import
    said only that machine 2 (bus 103) has no model.  The REGCA1 that matches no generator
    is named first, as a machine record of no generator is: the likely cause."""
    from stabctl.io.dyr import UnmodelledError

    recs = read_dyr(DYR)
    moved = [_text(r).replace(f"{r.bus} '", "999 '", 1) if r.bus == 103 else _text(r) for r in recs]
    with pytest.raises(UnmodelledError) as err:
        load_psse(RAW, _dyr(tmp_path, moved))
    said = str(err.value)
    assert said.startswith(f"{Path(tmp_path / 'plant.dyr').name}:")
    assert (
        "REGCA1 (bus 999, id 1): matches no generator in service of the RAW data (none at " in said
    )
    assert (
        "; so generator(s) without a machine model record in the DYR data: machine 2 (bus 103"
        in said
    )


# ---------------------------------------------------------------- PSS/E's readings (round 50
# AJ08-AJ12): the models read as PSS/E reads them (``psse`` 1, import-psse's default), the
# sources OpenIPSL's PSS/E-verified OpenIPSL/Electrical/Renewables/PSSE/* and the PSS/E Model
# Library; ANDES 2.0's readings kept under conventions="andes"


def _rena_text(flags="0 0 0 0 0", vmin=None, drop=("REPCA1",), extra="") -> str:
    """RENA's DYR text without ``drop``, its REECB1 ICONs IREG PFFLAG VFLAG QFLAG PQFLAG
    ``flags`` (RENA's 0 0 0 0 0), VMIN ``vmin`` (RENA's 0.9), ``extra`` records appended."""
    out = []
    for r in read_dyr(DYR):
        if r.model in drop:
            continue
        change = {}
        if r.model == "REECB1":
            change = dict(zip(("IREG", "PFFLAG", "VFLAG", "QFLAG", "PQFLAG"), flags.split()))
            change = {k: float(v) for k, v in change.items()}
            if vmin is not None:
                change["VMIN"] = vmin
        out.append(_text(r, **change))
    return "".join(out) + extra


def _evaluate(case):
    """(f(x), model, state names, evaluate) of ``case``'s dynamic model at its initial
    states: evaluate(x) the derivatives at states x, the network at its initial
    voltages."""
    from stabctl.dynamics.model import StageConfig
    from stabctl.smallsignal.linearise import default_esd_buses

    model = Simulator(case, background_compile=False).model_for(default_esd_buses(case))
    net = model.network(StageConfig())
    names = [model.state_name(k) for k in range(len(model.x0))]

    def evaluate(x):
        return np.asarray(model.evaluate(np.array(x, float), net, model.V_nc0)[0])

    x0 = np.array(model.x0, float)
    return x0, names, evaluate


@pytest.mark.parametrize(("conventions", "rate"), [("psse", 0.5), ("andes", 0.1 / 0.02)])
def test_p_reference_rate_limit_is_in_pu_per_second_as_pss_e_reads_it(tmp_path, conventions, rate):
    """PSS/E's REEC_A/B/D limit the P reference's rate to [dPmin, dPmax] pu/s (Dynawo's
    BaseREEC: a SlewRateLimiter on Pref; round 51 AK11).  RENA's REECB1 with dPmax 0.5,
    dPmin -0.5 and its P reference filter's state 0.1 pu below Pref: read as PSS/E's, the
    filter moves at 0.5 pu/s; read as ANDES's (LagRate, the limit on Pref - state before
    1/Tpfilt), at min(0.1, 0.5)/Tpfilt = 5 pu/s.  It was 5 pu/s under both: dPmax/Tpfilt,
    50 times PSS/E's rate."""
    recs = [r for r in read_dyr(DYR) if r.model != "REPCA1"]
    texts = [
        _text(r, **({"dPmax": 0.5, "dPmin": -0.5} if r.model == "REECB1" else {})) for r in recs
    ]
    case = load_psse(RAW, _dyr(tmp_path, texts), conventions=conventions)
    assert _row(case.converters)["psse"] == (conventions == "psse")
    x0, names, evaluate = _evaluate(case)
    (k,) = [i for i, n in enumerate(names) if "Pref_filter" in n]
    assert abs(evaluate(x0)[k]) < 1e-12
    x = x0.copy()
    x[k] -= 0.1
    assert evaluate(x)[k] == pytest.approx(rate, rel=1e-12)


@pytest.mark.parametrize("flags", ["0 0 0 1 0", "0 0 1 1 0"])
def test_reecb1_qflag_1_starts_at_rest_as_pss_e_reads_it(tmp_path, flags):
    """REECB1 with QFLAG 1 (VFLAG 0: the V PI regulates Vt_filt to Vref0, RENA's 0 the
    initial 1.015 pu; VFLAG 1: the Q PI's output, started at V0, is its reference) and
    RENA's VMIN 0.9 runs 5 s flat (OpenIPSL REECB1.mo: V PI input clip(VFLAG ? Q PI :
    Vref0, Vmin, Vmax) - Vt_filt, 0 at the start).  ANDES 2.0's reading (V PI input
    clip(VFLAG Q PI, VMIN, VMAX), no voltage) cannot start there: its input is VMIN."""
    from runs import flat_run

    dyr = _dyr(tmp_path, [_rena_text(flags)])
    case = load_psse(RAW, dyr)
    assert _row(case.converters)["psse"] == 1.0
    drift, _ = flat_run(case, t_end=5.0)
    assert drift < 1e-8
    with pytest.raises(CaseError, match="PIV"):
        Simulator(load_psse(RAW, dyr, conventions="andes")).run([], 0.01, h=0.005)


def test_reecb1_voltage_control_returns_the_voltage_to_vref0_after_a_q_step(tmp_path):
    """REECB1 QFLAG 1 VFLAG 0 (VMIN 0, as round 50's probe): a 0.2 pu reactive load step
    at the plant's bus 103 pulls |V| down; PSS/E's integral voltage control (Kvi 60 on
    Vref0 - Vt_filt, Vref0 the initial 1.015 pu) brings it back to Vref0 (within 1e-5 pu
    after 5 s), with the plant's Q up.  ANDES 2.0's reading leaves it at 0.9999 pu."""
    from stabctl.case.events import LoadStep

    case = load_psse(RAW, _dyr(tmp_path, [_rena_text("0 0 0 1 0", vmin=0.0)]))
    res = Simulator(case, q_limits=False).run([LoadStep(103, 0.5, 0.0, 0.2)], 6.0, h=0.005)
    v = res.vmag[:, list(case.buses.number).index(103)]
    step = np.searchsorted(res.t, 0.6)
    assert v[0] == pytest.approx(1.015, abs=1e-4)
    assert v[step] < v[0] - 2e-3  # the step pulls the voltage down ...
    assert abs(v[-1] - v[0]) < 1e-5  # ... and the integral control restores Vref0
    assert res.ibr_q[-1, 0] > res.ibr_q[0, 0] + 0.1


@pytest.mark.parametrize("vflag", [0, 1])
def test_reeca1_qflag_1_starts_at_rest_as_pss_e_reads_it(tmp_path, vflag):
    """REECA1 with QFLAG 1 (RENA's REECB1 values in a REECA1 record, Vref1 0, no VDL
    curves): PSS/E's V PI compares with Vt_filt the Q PI's output, started at V0, Q0 its
    reference (VFLAG 1), or Vref1 + the Q reference, V0 at the start (VFLAG 0; OpenIPSL
    REECA1.mo ``Vmod = V0 - PFsel``): a flat start, where ANDES 2.0's reading (VFLAG 1: no
    voltage in the V PI; the Q reference Vref1 - V0) is refused."""
    from runs import flat_run

    reeca1 = (
        f"103 'REECA1' 1 0 0 {vflag} 1 0 0 -99.0 99.0 0.02 -0.01 0.01 1.0 1.1 -1.1 0.0 0.0 0.0 0.0 "
        "0.0 0.44 -0.44 1.05 0.9 0.0 0.01 10.0 60.0 0.0 0.02 99.0 -99.0 1.2 0.0 1.11 0.02 "
        + "0 " * 16
        + "/\n"
    )
    dyr = _dyr(tmp_path, [_rena_text(drop=("REPCA1", "REECB1"), extra=reeca1)])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # its all-0 VDL curves: no curve, told
        case = load_psse(RAW, dyr)
        andes = load_psse(RAW, dyr, conventions="andes")
    drift, _ = flat_run(case, t_end=5.0)
    assert drift < 1e-8
    with pytest.raises(CaseError):
        Simulator(andes).run([], 0.01, h=0.005)


#: a REECA1 of RENA's REECB1 values (flags 0, no VDL curves) for the wind turbine, and a
#: WTDTA1 of WECC-typical values: H 4.95 s, DAMP 0, Htfrac 0.875, Freq1 1.8 Hz, Dshaft 1.5
_WIND_REECA1 = (
    "103 'REECA1' 1 0 0 0 0 0 0 -99.0 99.0 0.02 -0.01 0.01 1.0 1.1 -1.1 0.0 0.0 0.0 0.0 "
    "0.0 0.44 -0.44 1.05 0.9 0.0 0.01 10.0 60.0 0.0 0.02 99.0 -99.0 1.2 0.0 1.11 0.02 "
    + "0 " * 16
    + "/\n"
)
_WTDTA1 = "103 'WTDTA1' 1 4.95 0.0 0.875 1.8 1.5 /\n"
_WTPTA1 = "103 'WTPTA1' 1 25.0 150.0 30.0 3.0 0.0 0.3 27.0 0.0 10.0 -10.0 /\n"
_WTTQA1 = "103 'WTTQA1' 1 0 3.0 0.6 0.05 60.0 1.2 0.0 0.2 0.58 0.4 0.72 0.6 0.86 0.8 1.0 0.0 /\n"


def _wind_case(tmp_path, *records, conventions="psse"):
    """RENA's plant with `_WIND_REECA1` in place of its REECB1 (no REPCA1) and the wind
    ``records``."""
    text = _rena_text(drop=("REPCA1", "REECB1"), extra=_WIND_REECA1 + "".join(records))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the REECA1's all-0 VDL curves: no curve, told
        return load_psse(RAW, _dyr(tmp_path, [text]), conventions=conventions)


def test_wtdta1_torsional_mode_is_at_freq1_hz(tmp_path):
    """WTDTA1's Freq1 is in Hz (PSS/E Model Library; OpenIPSL WTDTA1.mo: Kshaft = 2 Ht Hg
    (2 pi Freq1)^2/(H w0) on the shaft angle, whose rate is w0 (wt - wg)): the shaft
    torque's rate per pu speed difference is 2 Ht Hg (2 pi Freq1)^2/H, and the
    three-state drive train (wt, wg, Tshaft; Pm, Pe constant), its Jacobian taken from
    stabctl's own derivatives, has its torsional mode at the closed form's 1.798 Hz
    (H 4.95, Htfrac 0.875, Freq1 1.8, Dshaft 1.5, P0 0.4).  ANDES's reading (Freq1 in
    rad/s, Kshaft = 2 Ht Hg Freq1^2/H) keeps its 0.272 Hz under conventions="andes"."""
    H, frac, f1, D = 4.95, 0.875, 1.8, 1.5
    Ht, Hg = frac * H, (1 - frac) * H
    K = {"psse": 2 * Ht * Hg * (2 * np.pi * f1) ** 2 / H, "andes": 2 * Ht * Hg * f1**2 / H}

    def closed_form(K, P0):
        A = [
            [(-P0 - D) / (2 * Ht), D / (2 * Ht), -1 / (2 * Ht)],
            [D / (2 * Hg), (P0 - D) / (2 * Hg), 1 / (2 * Hg)],
            [K, -K, 0.0],
        ]
        return np.abs(np.linalg.eigvals(A).imag).max() / (2 * np.pi)

    modes = {}
    for conventions in ("psse", "andes"):
        case = _wind_case(tmp_path, _WTDTA1, conventions=conventions)
        x0, names, f = _evaluate(case)
        idx = [names.index(f"ibr.{s}.C1") for s in ("wt", "wg", "Tshaft")]
        f0 = f(x0)
        assert np.max(np.abs(f0[idx])) < 1e-12  # at rest
        J = np.empty((3, 3))
        for j, i in enumerate(idx):
            dx = np.zeros_like(x0)
            dx[i] = 1e-6
            J[:, j] = (f(x0 + dx)[idx] - f(x0 - dx)[idx]) / 2e-6
        modes[conventions] = np.abs(np.linalg.eigvals(J).imag).max() / (2 * np.pi)
        # H, Dshaft and so Kshaft on the system base: x Sn/Sb
        scale = case.converters.mva[0] / case.base_mva
        assert J[2, 0] == pytest.approx(K[conventions] * scale, rel=1e-6)
        bus = list(case.buses.number).index(103)
        P0 = case.converters.pfrac[0] * case.buses.pgen[bus] / scale  # device base
        want = closed_form(K[conventions], P0)
        assert modes[conventions] == pytest.approx(want, rel=1e-6)
    assert modes["psse"] == pytest.approx(1.798, abs=1e-3)
    assert modes["andes"] == pytest.approx(0.272, abs=1e-3)  # Freq1 1.8 rad/s


@pytest.mark.parametrize("pitch", [False, True])
def test_wtara1_theta0_starts_at_rest_as_pss_e_reads_it(tmp_path, pitch):
    """WTARA1 with Theta0 5 deg (Ka 0.007): PSS/E's Pm = Pm0 - Ka theta (theta - theta0),
    theta the pitch angle in degrees, is Pm0 at theta = theta0, where WTPTA1's pitch
    starts (its speed PI's integrator at theta0): 5 s flat.  ANDES 2.0's mix of
    rad(theta0) and degrees (theta = rad(theta0) - theta0 + pitch) is refused at the
    start under conventions="andes"."""
    from runs import flat_run

    records = [_WTDTA1, "103 'WTARA1' 1 0.007 5.0 /\n", *([_WTPTA1] if pitch else [])]
    case = _wind_case(tmp_path, *records)
    drift, _ = flat_run(case, t_end=5.0)
    assert drift < 1e-8
    if pitch:
        x0, names, _ = _evaluate(case)
        assert x0[names.index("ibr.theta_pitch.C1")] == 5.0
    with pytest.raises(CaseError, match="cannot start"):
        Simulator(_wind_case(tmp_path, *records, conventions="andes")).run([], 0.01, h=0.005)


def test_wtpta1_speed_pi_acts_on_wttqa1_speed_reference(tmp_path):
    """WTPTA1 with WTTQA1 (speed curve 0.2/0.58 ... 0.8/1.0: at P0 0.4 the turbine runs
    at wref 0.72 pu): PSS/E's speed PI acts on wt - wref, wref WTTQA1's speed reference
    (PSS/E Model Library WTPTA1, WECC WTGPT_A; GridPACK wtpta1.cpp).  At rest at 0.72 pu
    no pitch state moves; with the turbine 0.01 pu above wref the speed PI's integrator
    moves at Kiw 0.01 = 0.25 deg/s and the pitch at Kpw 0.01/Tp = 5 deg/s (no limit
    reached), where ANDES's reading (wt - 1) holds the pitch at its lower limit 0."""
    records = [_WTDTA1, "103 'WTARA1' 1 0.007 0.0 /\n", _WTPTA1, _WTTQA1]
    rates = {}
    for conventions in ("psse", "andes"):
        x0, names, f = _evaluate(_wind_case(tmp_path, *records, conventions=conventions))
        wt = names.index("ibr.wt.C1")
        pitch = [k for k, n in enumerate(names) if "pitch" in n]
        assert x0[wt] == pytest.approx(0.72, abs=1e-12)
        assert x0[names.index("ibr.wref_tq.C1")] == x0[wt]
        assert np.max(np.abs(f(x0)[pitch])) < 1e-12
        x = x0.copy()
        x[wt] += 0.01
        d = f(x)
        rates[conventions] = (
            d[names.index("ibr.PIw_pitch.C1")],
            d[names.index("ibr.theta_pitch.C1")],
        )
    assert rates["psse"][0] == pytest.approx(25.0 * 0.01, rel=1e-9)
    assert rates["psse"][1] == pytest.approx(150.0 * 0.01 / 0.3, rel=1e-9)
    assert rates["andes"] == (0.0, 0.0)


def test_wttqa1_power_control_holds_the_power_at_its_reference_as_pss_e_reads_it(tmp_path):
    """WTTQA1 with Tflag 1 (power control): PSS/E's torque PI acts on (Pref0 - the
    Tp-filtered Pe)/wg (GridPACK wttqa1.cpp: (Pref0 - Pelec_filter_blk_out)/(1 +
    domega_g); InterPSS's Wttqa1Model: (powerReference - filteredPower)/generatorSpeed), a
    negative feedback; ANDES 2.0's wttqa1.py takes (Pe - Pref0)/wg, its unfiltered Pe.
    Round 51 (AK09) found the ANDES form under both readings.  At rest nothing moves; the
    filtered power 0.05 pu above P0 moves the PI's integrator at Kip (-0.05)/wg (Kip 0.6)
    read as PSS/E's, not at all read as ANDES's (its Pe unchanged)."""
    tq = _WTTQA1.replace("'WTTQA1' 1 0 3.0", "'WTTQA1' 1 1 3.0")
    records = [_WTDTA1, "103 'WTARA1' 1 0.007 0.0 /\n", _WTPTA1, tq]
    rates = {}
    for conventions in ("psse", "andes"):
        x0, names, f = _evaluate(_wind_case(tmp_path, *records, conventions=conventions))
        pi, pef = names.index("ibr.PI_tq.C1"), names.index("ibr.Pe_filter_tq.C1")
        assert abs(f(x0)[pi]) < 1e-12
        x = x0.copy()
        x[pef] += 0.05
        rates[conventions] = (f(x)[pi], x0[names.index("ibr.wg.C1")])
    assert rates["psse"][0] == pytest.approx(0.6 * -0.05 / rates["psse"][1], rel=1e-12)
    assert abs(rates["andes"][0]) < 1e-12


def test_wtpta1_both_pitch_pis_at_the_minimum_pitch_linearise_as_with_the_limits_inactive(
    tmp_path,
):
    """WTPTA1 + WTTQA1 below rated power, the pitch at its minimum (WTARA1 Theta0 0,
    thmin 0): both pitch PIs rest on their lower limit, and a perturbation of the torque
    controller's speed reference drives one into its limit and frees the other, the other
    way on the other side (round 56 AU: `linearise` refused it, "no derivative left
    unchanged on one side", under every `limits`).  Each derivative is now taken on its
    own side: "auto" and "free" frees both limits (reached, not driven into: each free
    side linear in the step), as small-signal analysis takes limits inactive, so the
    modes are the limit of the same plant's just inside the limits (Theta0 0.2, 0.02,
    0.005 deg: the 0.024 Hz mode's damping 0.834, 0.807, 0.805 against 0.804 at the
    limit; at 0.005 deg every oscillatory mode within 0.5 % in frequency and damping,
    rel_step 1e-6 there, whose limit is 0.005 deg away); "hold" leaves the three pitch
    PIs out (held on their limits, frozen); "refuse" refuses by the column's name."""
    from stabctl.smallsignal.linearise import linearise
    from stabctl.smallsignal.modal import modal_analysis

    tq = _WTTQA1.replace("0.58 0.4 0.72", "0.58 0.45 0.72")  # P0 0.4 off the curve's point

    def modes(theta0, limits, rel_step=1e-4):
        records = [_WTDTA1, f"103 'WTARA1' 1 0.007 {theta0} /\n", _WTPTA1, tq]
        sim = Simulator(_wind_case(tmp_path, *records), background_compile=False)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            lin = linearise(sim, limits=limits, rel_step=rel_step)
        said = " ".join(str(w.message) for w in caught)
        lam = modal_analysis(lin).eigenvalues  # one of each pair, Im >= 0
        return lin, said, lam[lam.imag > 2 * np.pi * 0.01]  # the oscillatory modes

    lin, said, at_min = modes(0.0, "auto")
    assert "ibr.wref_tq.C1 of C1 (bus 103) (free)" in said
    assert "ibr.PIw_pitch.C1 of C1 (bus 103) (free)" in said
    _, _, inside = modes(0.005, "auto", rel_step=1e-6)
    assert at_min.imag == pytest.approx(inside.imag, rel=5e-3)
    assert -at_min.real / np.abs(at_min) == pytest.approx(-inside.real / np.abs(inside), rel=5e-3)
    free, _, _ = modes(0.0, "free")
    assert np.allclose(free.A, lin.A)
    held, said, _ = modes(0.0, "hold")
    assert "ibr.PIw_pitch.C1 of C1 (bus 103) (held, frozen: left out)" in said
    assert held.nstates == lin.nstates - 3
    with pytest.raises(SimulationError, match=r"ibr\.Pord\.C1 of C1 \(bus 103\) meets a limit"):
        modes(0.0, "refuse")


def test_wtpta1_rate_limits_bound_the_pitch_rate(tmp_path):
    """PSS/E's WTPTA1 rate limits RTetaMax, RTetaMin (10, -10) bound dtheta/dt in deg/s:
    the turbine 0.05 pu above WTTQA1's wref asks Kpw 0.05 = 7.5 deg through Tp 0.3 s (25
    deg/s) and pitches at 10 deg/s (ANDES's LagAntiWindupRate bounds Tp dtheta/dt, which
    would allow 10/Tp = 33 deg/s)."""
    records = [_WTDTA1, "103 'WTARA1' 1 0.007 0.0 /\n", _WTPTA1, _WTTQA1]
    x0, names, f = _evaluate(_wind_case(tmp_path, *records))
    x = x0.copy()
    x[names.index("ibr.wt.C1")] += 0.05
    assert f(x)[names.index("ibr.theta_pitch.C1")] == pytest.approx(10.0, rel=1e-12)


def test_wttqa1_speed_control_slows_a_fast_generator_as_pss_e_reads_it(tmp_path):
    """WTTQA1 with Tflag 0 (speed control) on a WTDTA1 drive train: PSS/E's torque PI acts
    on wg - wref (GridPACK wttqa1.cpp 1 + domega_g - omega_ref; Dynawo WTGQa.mo; the
    PowerWorld WTGTRQ_A diagram), so a generator 0.01 pu above its reference moves the PI's
    integrator at +Kip 0.01 (more torque, which slows it) and the plant's linearisation
    (central differences of stabctl's own derivatives) has no eigenvalue in the right half
    plane; ANDES 2.0's wref - wg (and InterPSS's) lowers the torque of a fast generator: a
    real eigenvalue near +0.6 1/s, the speed running away.  Round 52 (AN03-AN05) found
    ANDES's sign under both readings."""
    records = [_WTDTA1, "103 'WTARA1' 1 0.007 0.0 /\n", _WTPTA1, _WTTQA1]
    for conventions, sign in (("psse", 1.0), ("andes", -1.0)):
        x0, names, f = _evaluate(_wind_case(tmp_path, *records, conventions=conventions))
        x = x0.copy()
        x[names.index("ibr.wg.C1")] += 0.01
        assert f(x)[names.index("ibr.PI_tq.C1")] == pytest.approx(sign * 0.6 * 0.01, rel=1e-9)
        n = len(x0)
        J = np.empty((n, n))
        for j in range(n):
            dx = np.zeros(n)
            dx[j] = 1e-6
            J[:, j] = (f(x0 + dx) - f(x0 - dx)) / 2e-6
        worst = np.linalg.eigvals(J).real.max()
        if conventions == "psse":
            assert worst < 1e-6
        else:
            assert worst > 0.3


def _commands(case, change):
    """(REECx's active current command Ipcmd, reactive Iq target as dIq/dt, REGCA1's Ip
    output, the REPCA1's initial line P and Q) of ``case``'s plant after the states named
    in ``change`` (state name -> value) are set, from one evaluation of stabctl's model
    (its memory slot Ipcmd_last written in place)."""
    from stabctl.dynamics.model import StageConfig
    from stabctl.smallsignal.linearise import default_esd_buses

    model = Simulator(case, background_compile=False).model_for(default_esd_buses(case))
    names = [model.state_name(k) for k in range(len(model.x0))]
    x = np.array(model.x0, float)
    for name, value in change.items():
        x[names.index(f"ibr.{name}.C1")] = value
    dx, _ = model.evaluate(x, model.network(StageConfig()), model.V_nc0)
    cp = model.cp
    return x[names.index("ibr.Ipcmd_last.C1")], cp, x, names, np.asarray(dx)


@pytest.mark.parametrize("conventions", ["psse", "andes"])
def test_reec_divides_the_power_order_by_the_filtered_voltage_as_pss_e_reads_it(conventions):
    """REEC_B (RENA) divides its power order by the Trv-filtered voltage under PSS/E's
    reading (GridPACK reeca1.cpp Vt_filter_lowcap_out, Dynawo BaseREEC UFilteredPu, OpenIPSL
    REECA1.mo/REECB1.mo; round 52 AL02), by |V| under ANDES's: with the filter's state at
    0.9 |V0| the command is P0/(0.9 |V0|) read as PSS/E's, P0/|V0| read as ANDES's."""
    case = load_psse(RAW, DYR, conventions=conventions)
    at_rest, _, x, names, _ = _commands(case, {})
    v0 = x[names.index("ibr.Vt_filter.C1")]
    ipcmd, *_ = _commands(case, {"Vt_filter": 0.9 * v0})
    want = at_rest / 0.9 if conventions == "psse" else at_rest
    assert ipcmd == pytest.approx(want, rel=1e-12)


@pytest.mark.parametrize("conventions", ["psse", "andes"])
def test_reeca1_caps_the_lower_priority_current_by_its_vdl_curve_as_pss_e_reads_it(
    tmp_path, conventions
):
    """REECA1 with Q priority (PQFLAG 0) and a VDL2 (P) curve 0.2 0.1 / 0.4 0.2 / 0.8 0.3 /
    1.0 0.5: at a filtered voltage of 0.6 pu VDL2 gives 0.25 pu; PSS/E's reading caps Ip
    by min(VDL2, the room Imax leaves the Iq command) (GridPACK's CurrentLimitLogic,
    Dynawo's CurrentLimitsCalculationA, OpenIPSL's CurrentLimitLogicREECA; round 52 AL06),
    ANDES's by the room alone (here above 0.25)."""
    text = _REECA1_PLANT.format(
        vdl="0.2 2.0 0.4 4.0 0.8 8.0 1.0 10.0 0.2 0.1 0.4 0.2 0.8 0.3 1.0 0.5"
    )
    case = load_psse(RAW, _dyr(tmp_path, [text]), conventions=conventions)
    ipcmd, *_ = _commands(case, {"Vt_filter": 0.6})
    if conventions == "psse":
        assert ipcmd == pytest.approx(0.25, rel=1e-12)
    else:
        assert ipcmd > 0.3


@pytest.mark.parametrize("conventions", ["psse", "andes"])
def test_regca1_lvpl_limits_the_output_as_pss_e_reads_it(tmp_path, conventions):
    """REGCA1's low-voltage power logic (RENA's with Lvplsw 1: Zerox 0.4, Brkpt 0.9, Lvpl1
    1.22): with the filtered voltage at 0.6 pu the limit is (0.6 - 0.4) 1.22/0.5 = 0.488
    pu, below an Ip of 0.7 above its command 0.6.  PSS/E's reading limits the
    output to it (Dynawo REGCa.mo, OpenIPSL REGCA1.mo: a limiter after the lag; round 52
    AL08) and lets the state run on (never clamped); ANDES's AntiWindup neither clamps nor
    limits an Ip that is not driven into the limit: its output stays 0.7."""
    from stabctl.models.converters import N_STATES, regca1

    case = load_psse(RAW, _rena(tmp_path, REGCA1={"Lvplsw": 1}), conventions=conventions)
    _, cp, x, names, _ = _commands(case, {"V_filter": 0.6, "Ip": 0.7, "Ipcmd_last": 0.6})
    first = names.index("ibr.Ip.C1")  # slot 0: the device's states in slot order
    xi = x[first : first + N_STATES].reshape(N_STATES, 1).copy()
    assert xi[regca1.RG.Ip, 0] == 0.7  # not clamped
    Ipout, _ = regca1.currents(cp.packed(), xi, 0, 1.0)
    assert Ipout == pytest.approx(0.488 if conventions == "psse" else 0.7, rel=1e-12)


@pytest.mark.parametrize("conventions", ["psse", "andes"])
def test_regca1_rate_limits_bound_the_currents_rates_as_pss_e_reads_them(tmp_path, conventions):
    """REGCA1's Rrpwr 2 and Iqrmax 3 (RENA's plant, Tg 0.02 s, Q0 > 0), its Ip state 0.5 pu
    and its Iq state 0.3 pu below their commands, the lags asking 25 and 15 pu/s.  PSS/E's
    reading bounds the rates, pu/s (the Model Library's unit; GridPACK ``regca1.cpp``
    setdxlimits, InterPSS ``PsseRegca1ConverterTest``: Rrpwr 0.2, Ip up 0.002 pu in 0.01 s;
    Dynawo ``BaseREGC.mo``; round 54 AL09): 2 and 3 pu/s.  ANDES's bounds Tg times the
    rates by them (its RateLimiter on the right-hand side, OpenIPSL's ``REGCA1.mo`` alike),
    rates of 100 and 150 pu/s: neither binds (about 25, 15)."""
    case = load_psse(
        RAW, _rena(tmp_path, REGCA1={"Rrpwr": 2.0, "Iqrmax": 3.0}), conventions=conventions
    )
    _, cp, x, names, _ = _commands(case, {})
    assert cp.Q0[0] > 0.0
    ip, iq = x[names.index("ibr.Ip.C1")], x[names.index("ibr.Iq.C1")]
    ipcmd, *_, dx = _commands(case, {"Ip": ip - 0.5, "Iq": iq - 0.3})
    rates = dx[names.index("ibr.Ip.C1")], dx[names.index("ibr.Iq.C1")]
    # (the command moves with the network's voltage, P0/|V| under ANDES's reading)
    want = (2.0, 3.0) if conventions == "psse" else ((ipcmd - ip + 0.5) / 0.02, 0.3 / 0.02)
    assert rates == pytest.approx(want, rel=1e-9)


@pytest.mark.parametrize("conventions", ["psse", "andes"])
def test_repca1_without_a_monitored_branch_measures_the_plant_as_pss_e_reads_it(
    conventions,
):
    """RENA's REPCA1 monitors no branch (BUS1 = BUS2 = 0).  PSS/E's reading measures the
    plant's own output then (GridPACK's plant control fed the generator's P, Q, V; Dynawo's
    WECC plant its terminal; round 52 AL13): its line P and Q at rest are the plant's P0,
    Q0, and its Q filter follows the plant's Q; ANDES's no-line patch measures nothing (0),
    so that a frequency droop integrates to its deadband's edge and a Q control holds
    nothing."""
    case = load_psse(RAW, DYR, conventions=conventions)
    _, cp, _, names, dx = _commands(case, {})
    P = cp.packed()
    from stabctl.models.converters.table import C

    if conventions == "psse":
        assert cp.pc_Pline0[0] == pytest.approx(P[0, C.P0], rel=1e-12) and P[0, C.P0] > 0.3
        assert cp.pc_Qline0[0] == pytest.approx(P[0, C.Q0], rel=1e-12)
    else:
        assert cp.pc_Pline0[0] == 0.0 and cp.pc_Qline0[0] == 0.0
    # at rest nothing moves under either reading
    assert abs(dx[names.index("ibr.Qline_filter.C1")]) < 1e-12


@pytest.mark.parametrize("run", ["RENA_DEFAULT", "RENA_Q_FLAG", "RENA_REF_FLAG"])
def test_a_plant_runs_the_same_on_any_system_base(tmp_path, run):
    """PSS/E's REGC_A, REEC_B and REPC_A take their values on MBASE, so a plant's run does
    not depend on SBASE.  The ThreeBus plant at SBASE 200 (the RAW's branch R and X doubled,
    the fault's reactance too: the same ohms) ran with its Q 0.21 pu of 100 MVA off, the
    gains and currents the table holds on the system base (Kqv, Kvp, Kqp, Iqh1, REPC_A's
    Kp, Qmax, the PIs' tracking gains, ...) read unconverted (round 59 BB16-17); now the
    two runs are the same in MW, Mvar and pu voltage."""
    src = RENA.parent / run
    raw = (src / "ThreeBusRenewable.raw").read_text()
    (dyr,) = src.glob("*.dyr")
    at_200 = tmp_path / "ThreeBusRenewable.raw"
    at_200.write_text(
        raw.replace("0,   100.00,  32,", "0,   200.00,  32,", 1).replace(
            "1.00000E-2, 1.20000E-1,", "2.00000E-2, 2.40000E-1,"
        )
    )
    runs = []
    for path, base in ((src / "ThreeBusRenewable.raw", 100.0), (at_200, 200.0)):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            case = load_psse(path, dyr, on_unsupported="skip")
        assert case.base_mva == base
        res = Simulator(case).run([Fault(103, 1.0, 1.1, x=0.1 * base / 100.0)], 4.0)
        runs.append((res.ibr_p[:, 0] * base, res.ibr_q[:, 0] * base, res.vmag))
    for a, b in zip(*runs):
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-9)
