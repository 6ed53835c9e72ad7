"""PSS/E RAW import: record layouts and unit conversions of the PSS/E POM (v33, v34) on a
hand-written five-bus case (closed-form values), the power flow of ANDES's Kundur and
WECC-179 RAW files against ANDES's own power flow, unsupported records and the
`import-psse` command."""

import json
import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from stabctl.case import PQ, PV, SWING
from stabctl.cli import main
from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.results import SimulationResult
from stabctl.errors import CaseError
from stabctl.io import load_case
from stabctl.io.andes import _andes
from stabctl.io.psse import import_psse, load_psse
from stabctl.io.psse_raw import ZERO_Q_LIMIT, read_raw, split_fields, unclosed_quote
from stabctl.network.powerflow import solve_powerflow
from stabctl.network.ybus import branch_admittances, branch_stamp

DATA = Path(__file__).parents[1] / "data" / "psse"
V33 = DATA / "five_bus_v33.raw"
V34 = DATA / "five_bus_v34.raw"


def run(*args):
    return CliRunner().invoke(main, [str(a) for a in args])


# ------------------------------------------------------------------- record layouts


def test_fields_split_on_commas_and_blanks_with_quoted_names_and_comments():
    # POM: items separated by commas or blanks, names in single quotes, '/' ends the data
    assert split_fields("  1,'AB, C/ ',  2.0 3,,4 / 5, 6") == ["1", "AB, C/ ", "2.0", "3", "", "4"]


@pytest.mark.parametrize("path", [V33, V34])
def test_five_bus_buses_loads_and_shunts(path):
    raw = read_raw(path, loads="raw")
    assert (raw.version, raw.base_mva, raw.freq_hz) == (int(path.stem[-2:]), 100.0, 50.0)
    bus = {int(r[0]): r for r in raw.bus}
    assert sorted(bus) == [1, 2, 3, 4]  # bus 5 is IDE 4 (isolated): left out with its load
    # bus 2: load 1 in service (load 2 is not), I part at VM = 0.98, Y part and the fixed
    # shunt GL + jBL = 5 + j20 MW/Mvar as bus shunt; YQ = -4 Mvar is inductive
    np.testing.assert_allclose(
        bus[2][[5, 6, 7, 8]],
        [(100 + 20 * 0.98) / 100, (30 + 5 * 0.98) / 100, (10 + 5) / 100, (-4 + 20) / 100],
        rtol=0,
        atol=1e-15,
    )
    assert bus[2][9] == PQ and bus[4][9] == PQ and bus[1][9] == SWING and bus[3][9] == PV
    # switched shunt at bus 4: fixed at BINIT = 30 Mvar
    assert bus[4][8] == pytest.approx(0.30, abs=1e-15)
    # load_con: constant-power and constant-current shares of the bus load
    np.testing.assert_allclose(
        raw.load_con,
        [[2, 100 / 119.6, 30 / 34.9, 19.6 / 119.6, 4.9 / 34.9], [4, 1, 1, 0, 0]],
        rtol=0,
        atol=1e-15,
    )


@pytest.mark.parametrize("path", [V33, V34])
def test_five_bus_generators(path):
    raw = read_raw(path)
    bus3 = raw.bus[raw.bus[:, 0] == 3][0]
    # generators '1' and '2' in service (PG 150 + 50 MW, QG 20 + 10 Mvar, QT 100 + 60,
    # QB -50 - 20 Mvar); '3' has STAT 0; the bus is PV at VS = 1.01
    np.testing.assert_allclose(
        bus3[[1, 3, 4, 10, 11]], [1.01, 2.0, 0.3, 1.6, -0.7], rtol=0, atol=1e-15
    )
    assert [g.as_dyr() for g in raw.generators] == [
        {
            "number": 1,
            "bus": 1,
            "id": "1",
            "mbase": 500.0,
            "ra": 0.0,
            "xsource": 0.25,
            "zsorce": True,
            "pg": 0.0,
            "qg": 0.0,
        },
        {
            "number": 2,
            "bus": 3,
            "id": "1",
            "mbase": 200.0,
            "ra": 0.0,
            "xsource": 0.2,
            "zsorce": True,
            "pg": 150.0,
            "qg": 20.0,
        },
        {
            "number": 3,
            "bus": 3,
            "id": "2",
            "mbase": 100.0,
            "ra": 0.0,
            "xsource": 0.3,
            "zsorce": True,
            "pg": 50.0,
            "qg": 10.0,
        },
    ]
    assert raw.generators[2].source.line == (19 if path == V33 else 22)


@pytest.mark.parametrize("path", [V33, V34])
def test_five_bus_branches_and_transformer_bases(path):
    line = read_raw(path).line
    # lines: circuit 2 is out of service; circuit 3 has BI = BJ = 0.05 added to B = 0.1
    np.testing.assert_allclose(
        line[:2, :7], [[1, 2, 0.01, 0.1, 0.2, 0, 0], [1, 2, 0.02, 0.2, 0.2, 0, 0]]
    )
    # T1: CW 2 (kV): t1 = 240/230, t2 = 21/20; CZ 2: Z = (0.005 + j0.08) * 100/500 on the
    # system base, referred through t2: Z * t2^2, tap t1/t2
    t1, t2 = 240 / 230, 21 / 20
    np.testing.assert_allclose(
        line[2, :7], [2, 3, 0.001 * t2**2, 0.016 * t2**2, 0, t1 / t2, 0], rtol=1e-14
    )
    # T2: CW 3 (pu of NOMV1 = 120 kV on a 115 kV bus): t1 = 1.02 * 120/115; ANG1 = 30 deg
    # is PST's phase -30 (stabctl.network.ybus)
    np.testing.assert_allclose(line[3, :7], [4, 2, 0, 0.05, 0, 1.02 * 120 / 115, -30], rtol=1e-14)


def test_two_winding_circuit_of_two_off_nominal_windings():
    # bus I - ideal t1:1 - Z - ideal 1:t2 - bus J gives Y_II = 1/(Z t1^2),
    # Y_IJ = Y_JI = -1/(Z t1 t2), Y_JJ = 1/(Z t2^2), Z on the system base
    case = load_psse(V33)
    ba = branch_admittances(case, rows=[2])
    z, t1, t2 = (0.005 + 0.08j) * 100 / 500, 240 / 230, 21 / 20
    np.testing.assert_allclose(
        [ba.yff[0], ba.yft[0], ba.ytf[0], ba.ytt[0]],
        [1 / (z * t1**2), -1 / (z * t1 * t2), -1 / (z * t1 * t2), 1 / (z * t2**2)],
        rtol=1e-13,
    )


def test_impedance_loads_leave_load_con_empty():
    raw = read_raw(V33)
    assert raw.load_con.shape == (0, 5)
    assert raw.bus[1, 5] == pytest.approx(1.196, abs=1e-15)  # I part still at VM


def test_dyr_machines_share_their_bus_generation():
    # machine k is the k-th in-service RAW generator; at bus 3 generators '1' and '2'
    # produce 150 + 50 MW and 20 + 10 Mvar
    case = load_psse(V33, DATA / "five_bus.dyr")
    mac = case.machines
    assert list(mac.number) == [1, 2, 3] and list(mac.bus) == [1, 3, 3]
    assert list(mac.mva) == [500.0, 200.0, 100.0]  # MBASE
    np.testing.assert_allclose(mac.pfrac, [1, 0.75, 0.25], rtol=0, atol=1e-15)
    np.testing.assert_allclose(mac.qfrac, [1, 2 / 3, 1 / 3], rtol=0, atol=1e-15)
    np.testing.assert_allclose(mac.H, [5.0, 4.0, 3.0])


def test_machines_are_named_by_bus_and_psse_id_and_keep_their_ids_in_the_case_file(tmp_path):
    """Outputs named a PSS/E case's machines "G2 (bus 3)" and "G3 (bus 3)": which of bus
    3's machines '1' and '2' was which had to be guessed from the RAW order.  The import
    keeps each machine's RAW ID (the out-of-service '3' has no machine) and names them as
    PSS/E does, by bus and ID; the case file keeps the IDs; a case whose two machines of
    one bus share an ID is refused."""
    from stabctl.io.pst import read_case_json, write_case_json

    case = load_psse(V33, DATA / "five_bus.dyr")
    assert dict(case.machine_ids) == {1: "1", 2: "1", 3: "2"}
    names = [case.machine_name(k) for k in case.machines.number]
    assert names == ["G1 (bus 1, id '1')", "G2 (bus 3, id '1')", "G3 (bus 3, id '2')"]
    back = read_case_json(write_case_json(case, tmp_path / "five.json"))
    assert back.equals(case) and dict(back.machine_ids) == dict(case.machine_ids)
    assert back.digest() == case.digest() == case.replace(machine_ids={}).digest()
    with pytest.raises(CaseError, match=r"machines 2 and 3 at bus 3 share the ID '1'"):
        case.replace(machine_ids={1: "1", 2: "1", 3: "1"})
    assert load_case("kundur").machine_name(1) == "G1 (bus 1)"  # PST data: no IDs


@pytest.mark.parametrize(
    "ic, needle",
    [
        (1, "IC 1: the file holds changes to add to a case in PSS/E's working memory"),
        (2, "IC 2: not a change code of the POM (0: a new case, 1: changes to a case)"),
    ],
)
def test_a_change_file_is_refused_not_read_as_a_whole_case(tmp_path, ic, needle):
    """A RAW file with IC 1 (POM: changes PSS/E adds to the case in its working memory)
    or IC 2 (no such code) was imported as a whole case without a word."""
    text = V33.read_text().splitlines()
    text[0] = str(ic) + text[0][1:]
    path = tmp_path / f"ic{ic}.raw"
    path.write_text("\n".join(text) + "\n")
    with pytest.raises(CaseError, match=re.escape(f"ic{ic}.raw:1 case identification")) as err:
        read_raw(path)
    assert needle in str(err.value)


def test_a_double_quoted_name_in_a_v33_file_is_said_to_be_the_cause(tmp_path):
    """A v33 bus record with its name in double quotes (read as quotes from v34 on) was
    refused as "IDE = '230.0000': not an integer", the quotes unmentioned."""
    text = V33.read_text().replace("'LOAD        '", '"LOAD BUS"', 1)
    path = tmp_path / "dq33.raw"
    path.write_text(text)
    with pytest.raises(CaseError, match=r"dq33.raw:5 bus record: ") as err:
        read_raw(path)
    assert str(err.value).endswith(
        "(the record holds double quotes: before v34 a RAW file quotes its names with ' "
        "only, so a double-quoted name is split at its blanks)"
    )


def test_a_name_whose_quote_is_not_closed_is_named(tmp_path):
    """A bus name without its closing quote took the rest of the line: refused as "2
    field(s), the v33 layout has 9 to 13", the quote unmentioned."""
    text = V33.read_text().replace("'LOAD        '", "'LOAD        ", 1)
    path = tmp_path / "q33.raw"
    path.write_text(text)
    with pytest.raises(CaseError, match=r"q33.raw:5: the quote ' at column \d+ is not closed"):
        read_raw(path)
    # a quote in the comment after '/' is no string
    assert unclosed_quote("1,'A', 2 / it's a comment") is None
    assert unclosed_quote('1,"A, 2', double_quotes=True) == 2
    assert unclosed_quote('1,"A, 2') is None  # before v34 '"' is no quote


def test_parallel_circuits_whose_ids_are_not_their_file_order_are_named(tmp_path):
    """The commands number parallel circuits by their order in the file (--trip A B:K,
    --circuit K), not by their CKT id: with circuits '2' then '1' between two buses,
    `--trip A B:1` opens PSS/E's '2', without a word.  The import names every such pair
    and which id each K is; circuits '1', '2', ... in file order say nothing."""
    raw = read_raw(V33)  # 1-2: '1' in service, '2' out, '3' in (metered at 2)
    assert raw.circuit_order == ("1-2 (in file order :1 is '1', :2 is '3')",)
    swapped = V33.read_text().replace("    1,      2,'1 ',", "    1,      2,'9 ',", 1)
    path = tmp_path / "swapped.raw"
    path.write_text(swapped)
    with pytest.warns(
        UserWarning, match=r"numbered in file order \(LineFault and LineTrip's circuit\)"
    ) as said:
        load_psse(path, DATA / "five_bus.dyr")
    text = " ".join(str(w.message) for w in said)
    assert "1-2 (in file order :1 is '9', :2 is '3')" in text
    ordered = V33.read_text().replace("    1,     -2,'3 ',", "    1,     -2,'2 ',", 1)
    ordered = ordered.replace("    1,      2,'2 ',", "    1,      2,'8 ',", 1)
    path.write_text(ordered)
    assert read_raw(path).circuit_order == ()  # '1' then '2' in service: K is the id


def _dyr(tmp_path, *lines):
    """A DYR file of the given record lines."""
    path = tmp_path / "edited.dyr"
    path.write_text("\n".join(lines) + "\n")
    return path


_GENROU = "8.0 0.03 0.4 0.05 {H} 0.0 1.8 1.7 0.3 0.55 0.25 0.06 0.0 0.0 /"


def test_a_record_after_a_slash_on_the_same_line_is_refused_not_dropped_silently(tmp_path):
    """PSS/E reads one record up to '/', the rest of the line being a comment: a second
    record there would not be read, so the reader refuses it (a comment is read as one)."""
    from stabctl.io.dyr import read_dyr

    path = tmp_path / "two.dyr"
    path.write_text(
        "1 'GENCLS' 1 6.0 0.0 / 3 'GENCLS' 1 5.0 0.0 /\n3 'GENCLS' 1 5.0 0.0 / a note\n"
    )
    with pytest.raises(CaseError, match=r"two\.dyr:1: '3 'GENCLS' 1 5.0 0.0 /' after '/'"):
        read_dyr(path)
    path.write_text("1 'GENCLS' 1 6.0 0.0 / machine 1\n3 'GENCLS' 1 5.0 0.0 / 2 units\n")
    assert [(r.bus, r.model) for r in read_dyr(path)] == [(1, "GENCLS"), (3, "GENCLS")]


def test_generators_without_a_machine_model_are_refused_or_netted(tmp_path):
    """PSS/E's netting: generator 3 '2' (50 + j10 MW/Mvar) has no DYR machine record; it
    is refused by name, or becomes a negative constant-power load at bus 3, where
    generator 3 '1' holds the voltage: the power flow is the un-netted one (the same
    injections), to round-off."""
    dyr = _dyr(
        tmp_path, f"1 'GENROU' 1 {_GENROU.format(H=5.0)}", f"3 'GENROU' 1 {_GENROU.format(H=4.0)}"
    )
    with pytest.raises(CaseError, match=r"machine 3 \(bus 3, id 2\).*unmodelled='net'"):
        load_psse(V33, dyr)
    with pytest.warns(UserWarning, match="netted 1 generator"):
        case, left_out, netted, *_ = import_psse(V33, dyr, unmodelled="net")
    assert left_out == () and netted == (
        "five_bus_v33.raw:19 generator at bus 3 '2': no machine model record in the DYR data",
    )
    assert list(case.machines.number) == [1, 2] and list(case.machines.pfrac) == [1, 1]
    bus3 = case.bus_index(3)
    assert case.buses.pgen[bus3] == pytest.approx(1.5, abs=1e-15)
    assert case.buses.pload[bus3] == pytest.approx(-0.5, abs=1e-15)
    assert case.buses.qload[bus3] == pytest.approx(-0.1, abs=1e-15)
    assert case.buses.qmax[bus3] == pytest.approx(1.0, abs=1e-15)  # its QT only
    full = solve_powerflow(load_psse(V33, DATA / "five_bus.dyr"), q_limits=False)
    nett = solve_powerflow(case, q_limits=False)
    np.testing.assert_allclose(nett.v, full.v, rtol=0, atol=1e-12)


def test_netting_the_swing_generator_is_refused(tmp_path):
    dyr = _dyr(
        tmp_path, f"3 'GENROU' 1 {_GENROU.format(H=4.0)}", f"3 'GENROU' 2 {_GENROU.format(H=3.0)}"
    )
    with pytest.raises(CaseError, match="swing bus 1 has no generator left once netted"):
        load_psse(V33, dyr, unmodelled="net")


def test_a_swing_bus_without_a_generator_in_service_is_refused(tmp_path):
    """The swing bus's only generator out of service (STAT 0) was imported without a
    word, its power flow injection then netted as a negative load: PSS/E's swing bus
    holds at least one generator in service (POM, bus data: IDE 3)."""
    lines = V33.read_text().splitlines()
    k = next(i for i, x in enumerate(lines) if x.lstrip().startswith("1,'1 '") and "999.000" in x)
    fields = lines[k].split(",")
    fields[14] = "0"  # STAT
    lines[k] = ",".join(fields)
    raw = tmp_path / "swing_off.raw"
    raw.write_text("\n".join(lines) + "\n")
    said = r"swing_off.raw:4 bus 1: swing bus 1 \(IDE 3\) has no generator in service"
    with pytest.raises(CaseError, match=said):  # named at its bus record
        read_raw(raw)


def test_records_of_generators_out_of_service_are_ignored(tmp_path):
    """Generator 3 '3' has STAT 0: its DYR records are ignored (PSS/E), not refused."""
    extra = f"3 'GENROU' 3 {_GENROU.format(H=2.0)}"
    dyr = _dyr(tmp_path, (DATA / "five_bus.dyr").read_text(), extra)
    case = load_psse(V33, dyr)
    assert len(case.machines) == 3


#: what PSS/E leaves out of the five-bus network, each record named with why
FIVE_BUS_OFF = (
    "five_bus_v33.raw:8 bus 5: isolated (IDE 4)",
    "five_bus_v33.raw:11 load at bus 2 '2': out of service (STATUS 0)",
    "five_bus_v33.raw:13 load at bus 5 '1': at isolated bus 5 (IDE 4)",
    "five_bus_v33.raw:20 generator at bus 3 '3': out of service (STAT 0)",
    "five_bus_v33.raw:23 branch 1-2 '2': out of service (ST 0)",
)


def test_records_out_of_the_network_are_named(tmp_path):
    """The import reported nothing left out while it dropped isolated bus 5 with its
    load, the load, branch and generator out of service and the DYR record of that
    generator: each is named with why, in a warning, `PsseImport.out_of_service` and
    the CLI's summary (JSON `out_of_service`), and still left out, as PSS/E does."""
    extra = f"3 'GENROU' 3 {_GENROU.format(H=2.0)}"
    dyr = _dyr(tmp_path, (DATA / "five_bus.dyr").read_text(), extra)
    named = (
        *FIVE_BUS_OFF,
        "edited.dyr:6 GENROU (bus 3, id 3): its generator is out of the network (out of "
        "service or at an isolated bus)",
    )
    with pytest.warns(UserWarning, match=r"left out 6 record\(s\) out of the network"):
        imported = import_psse(V33, dyr)
    assert imported.out_of_service == named and imported.left_out == ()
    assert read_raw(V33).switched_off[0].line == 8
    res = run("import-psse", V33, dyr, "-o", tmp_path / "x.json", "--json")
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["out_of_service"] == list(named)
    res = run("import-psse", V33, dyr, "-o", tmp_path / "x.json")
    assert f"  out of the network: {FIVE_BUS_OFF[3]}" in res.stdout
    assert "6 out of the network (as PSS/E)" in res.stdout


def test_magnetizing_admittance_is_a_shunt_at_the_winding_1_bus(tmp_path):
    """MAG1 + jMAG2 (CM 1, pu on SBASE) of transformer 2-3: the branch's from-end shunt
    (line columns 11-12), switched with it."""
    old = "    2,     3,     0,'1 ',2,2,1, 0.00000E+0, 0.00000E+0,"
    path = _edit(tmp_path, old, "    2,     3,     0,'1 ',2,2,1, 0.002, -0.01,")
    line = read_raw(path).line
    row = line[(line[:, 0] == 2) & (line[:, 1] == 3)][0]
    np.testing.assert_array_equal(row[10:14], [0.002, -0.01, 0.0, 0.0])


def test_magnetizing_admittance_given_as_loss_and_current(tmp_path):
    """CM 2 (refused as unsupported until round 49): MAG1 the no-load loss in W, MAG2 the
    exciting current in pu on SBASE1-2 (500 MVA) at NOMV1 (240 kV, bus 2's base 230 kV):
    G = MAG1/(1e6 SBASE) (230/240)^2, |Y| = MAG2 SBASE1-2/SBASE (230/240)^2 and
    B = -sqrt(|Y|^2 - G^2) (POM Transformer Data; OpenPA's XfrMagYcm2 alike).  A current
    below its loss, or a negative field, is refused naming the fields.  A three-winding
    transformer's is at its winding-1 bus."""
    old = "    2,     3,     0,'1 ',2,2,1, 0.00000E+0, 0.00000E+0,"
    path = _edit(tmp_path, old, "    2,     3,     0,'1 ',2,2,2, 2.0E5, 0.004,")
    text = path.read_text().replace("240.00,   0.000,   0.000,", "240.00,   240.0,   0.000,", 1)
    path.write_text(text)  # NOMV1 240 kV
    raw = read_raw(path)
    assert raw.unsupported == ()
    row = raw.line[(raw.line[:, 0] == 2) & (raw.line[:, 1] == 3)][0]
    scale = (230 / 240) ** 2
    g, y = 0.2 / 100 * scale, 0.004 * 500 / 100 * scale
    np.testing.assert_allclose(row[10:14], [g, -np.sqrt(y * y - g * g), 0, 0], rtol=1e-12)
    t3 = _three_winding(tmp_path)  # bus 1's 230 kV, NOMV1 0 (bus base), SBASE1-2 200 MVA
    t3.write_text(t3.read_text().replace("'T ',1,2,1, 0.0, 0.0,", "'T ',1,2,2, 1.0E5, 0.01,"))
    rows = read_raw(t3).line
    g, y = 0.1 / 100, 0.01 * 200 / 100
    np.testing.assert_allclose(rows[rows[:, 1] == 6][0, 10:12], [g, -np.sqrt(y * y - g * g)])
    path = _edit(tmp_path, old, "    2,     3,     0,'1 ',2,2,2, 2.0E5, 0.0001,")
    with pytest.raises(
        CaseError,
        match=r"MAG2 = 0.0001: exciting current 0.0005 pu below the no-load loss 0.002 pu",
    ):
        read_raw(path)
    path = _edit(tmp_path, old, "    2,     3,     0,'1 ',2,2,2, 2.0E5, -0.004,")
    with pytest.raises(CaseError, match=r"MAG1 = 2.0E5, MAG2 = -0.004: CM 2 gives a loss"):
        read_raw(path)


def test_a_zero_q_limit_stays_a_limit(tmp_path):
    """PSS/E QT = QB = 0 holds Q at 0; PST's bus table reads 0 as no limit, so the RAW
    reader writes +-ZERO_Q_LIMIT and the power flow holds the bus at Q = 0."""
    path = _edit(tmp_path, "100.000,   -50.000,1.01000", "0.000,     0.000,1.01000")
    path.write_text(
        path.read_text().replace("60.000,   -20.000,1.01000", "0.000,     0.000,1.01000")
    )
    raw = read_raw(path)
    bus3 = raw.bus[raw.bus[:, 0] == 3][0]
    assert (bus3[10], bus3[11]) == (ZERO_Q_LIMIT, -ZERO_Q_LIMIT)
    case = load_psse(path, DATA / "five_bus.dyr")
    pf = solve_powerflow(case, q_limits=True)
    k = case.bus_index(3)
    assert pf.q_limited[k] and abs(pf.qgen[k]) <= ZERO_Q_LIMIT


# --------------------------------------------------------- three-winding transformers

#: winding lines (v33): WINDV, NOMV, ANG, RATA, RATB, RATC, COD, CONT, RMA, RMI, VMA, VMI,
#: NTP, TAB, CR, CX, CNXA
_WINDING = "{windv}, {nomv}, {ang}, 0.0, 0.0, 0.0, 0, 0, 1.1, 0.9, 1.1, 0.9, 33, 0, 0.0, 0.0, 0.0\n"


def _three_winding(
    tmp_path, cw=1, cz=2, stat=1, windv=(1.0, 1.0, 1.0), ang=(0.0, 0.0, 0.0), name="t3.raw"
):
    """The v33 case with transformer 1-3-4 (230/20/115 kV) 'T' added: pair impedances
    on SBASE 200, 50, 80 MVA, VMSTAR 0.99, ANSTAR -3 deg."""
    record = (
        f"    1,     3,     4,'T ',{cw},{cz},1, 0.0, 0.0,2,'T3          ',{stat},   1,1.0000\n"
        " 0.002, 0.10, 200.0, 0.004, 0.05, 50.0, 0.003, 0.08, 80.0, 0.99, -3.0\n"
        + "".join(_WINDING.format(windv=w, nomv=0.0, ang=a) for w, a in zip(windv, ang))
    )
    path = _edit(tmp_path, "0 / END OF TRANSFORMER DATA", record + "0 / END OF TRANSFORMER DATA")
    return path.rename(tmp_path / name)


_Z_PAIRS = {
    (0, 1): (0.002 + 0.10j) / 2,
    (1, 2): (0.004 + 0.05j) * 2,
    (2, 0): (0.003 + 0.08j) * 1.25,
}


def test_three_winding_pair_impedances_are_the_measured_ones(tmp_path):
    """POM: R1-2 + jX1-2 is the impedance measured between the buses of windings 1 and 2
    (the third open), on SBASE1-2 (CZ 2). Kron-reducing the star point and driving 1 pu
    current from one winding's bus to another's gives the RAW's pair impedance on the
    system base (100/SBASE) for each of the three pairs."""
    case = load_psse(_three_winding(tmp_path))
    star = case.bus_index(6)  # above the file's buses 1-5
    buses = [case.bus_index(n) for n in (1, 3, 4)]
    rows = [k for k in range(len(case.branches)) if case.branches.to_bus[k] == 6]
    y = branch_stamp(case, rows).toarray()
    keep = buses
    y_red = y[np.ix_(keep, keep)] - np.outer(y[keep, star], y[star, keep]) / y[star, star]
    for (a, c), z_pair in _Z_PAIRS.items():
        ground = 3 - a - c  # the open winding: ground winding c instead, leave the third open
        idx = [a, ground]
        v = np.linalg.solve(y_red[np.ix_(idx, idx)], [1.0, 0.0])
        assert v[0] == pytest.approx(z_pair, rel=1e-12), (a, c)


def test_three_winding_star_rows_taps_phases_and_status(tmp_path):
    """CW 2 (kV): t_w = WINDV_w / bus kV; PST's phase is -ANG_w; the star point is bus 6
    at VMSTAR/ANSTAR; STAT 2 leaves winding 2 out, STAT 0 the whole transformer."""
    path = _three_winding(tmp_path, cw=2, windv=(235.0, 21.0, 110.0), ang=(0.0, 30.0, 0.0))
    raw = read_raw(path)
    star = raw.bus[raw.bus[:, 0] == 6][0]
    np.testing.assert_allclose(star[[1, 2, 9]], [0.99, -3.0, PQ])
    rows = raw.line[raw.line[:, 1] == 6]
    np.testing.assert_allclose(rows[:, 0], [1, 3, 4])
    np.testing.assert_allclose(rows[:, 5], [235 / 230, 21 / 20, 110 / 115], rtol=1e-14)
    np.testing.assert_allclose(rows[:, 6], [0, -30, 0])
    z1, z2, z3 = (
        (_Z_PAIRS[0, 1] + _Z_PAIRS[2, 0] - _Z_PAIRS[1, 2]) / 2,
        (_Z_PAIRS[0, 1] + _Z_PAIRS[1, 2] - _Z_PAIRS[2, 0]) / 2,
        (_Z_PAIRS[1, 2] + _Z_PAIRS[2, 0] - _Z_PAIRS[0, 1]) / 2,
    )
    np.testing.assert_allclose(rows[:, 2] + 1j * rows[:, 3], [z1, z2, z3], rtol=1e-13)
    s2 = read_raw(_three_winding(tmp_path, stat=2, name="s2.raw"))
    np.testing.assert_allclose(s2.line[s2.line[:, 1] == 6][:, 0], [1, 4])
    # round 43: the winding left out was not named
    named = [str(s) for s in s2.switched_off if "three-winding" in str(s)]
    assert named == [
        "s2.raw:34 three-winding transformer 1-3-4 'T': winding 2 (bus 3) out of service (STAT 2)"
    ]
    raw = read_raw(_three_winding(tmp_path, stat=0, name="s0.raw"))
    assert 6 not in raw.bus[:, 0] and not np.any(raw.line[:, 1] == 6)


def test_three_winding_solves_as_its_star_of_two_winding_transformers(tmp_path):
    """The power flow of the case with transformer 1-3-4 equals that of the same case with
    the star point written as bus 6 and three two-winding transformers (CZ 1) holding the
    star impedances and the windings' taps and phases: the two RAW paths agree to 1e-10."""
    windv, ang = (1.03, 0.98, 1.01), (5.0, 0.0, -10.0)
    case3 = load_psse(_three_winding(tmp_path, cz=2, windv=windv, ang=ang))
    zs = read_raw(tmp_path / "t3.raw").line
    zs = zs[zs[:, 1] == 6][:, 2:4]
    star_bus = "    6,'STAR        ',   1.0000,1,   1,   1,   1,0.99000,  -3.0000,1.1,0.9,1.1,0.9\n"
    two = "".join(
        f"    {n},     6,     0,'T{w}',1,1,1, 0.0, 0.0,2,'T{w}          ',1,   1,1.0000\n"
        f" {float(zs[w, 0])!r}, {float(zs[w, 1])!r}, 100.0\n"
        + _WINDING.format(windv=windv[w], nomv=0.0, ang=ang[w])
        + "1.0, 0.0\n"
        for w, n in enumerate((1, 3, 4))
    )
    path = _edit(tmp_path, "0 / END OF TRANSFORMER DATA", two + "0 / END OF TRANSFORMER DATA")
    path.write_text(
        path.read_text().replace("0 / END OF BUS DATA", star_bus + "0 / END OF BUS DATA")
    )
    case2 = load_psse(path)
    pf3, pf2 = solve_powerflow(case3), solve_powerflow(case2)
    for n in (1, 2, 3, 4, 6):
        k3, k2 = case3.bus_index(n), case2.bus_index(n)
        assert pf3.vmag[k3] == pytest.approx(pf2.vmag[k2], abs=1e-10)
        assert pf3.vang[k3] == pytest.approx(pf2.vang[k2], abs=1e-10)
    assert pf3.qgen[case3.bus_index(1)] == pytest.approx(pf2.qgen[case2.bus_index(1)], abs=1e-9)
    # the transformer carries power: the case without it solves differently
    base = solve_powerflow(load_psse(V33))
    assert abs(base.vmag[case3.bus_index(4)] - pf3.vmag[case3.bus_index(4)]) > 1e-3


# ---------------------------------------------------------------- errors, unsupported


def _edit(tmp_path, old, new, src=V33):
    text = src.read_text(encoding="utf-8")
    assert old in text
    path = tmp_path / "edited.raw"
    path.write_text(text.replace(old, new, 1), encoding="utf-8")
    return path


def test_malformed_number_names_file_line_and_record(tmp_path):
    path = _edit(
        tmp_path,
        "1.00000E-2, 1.00000E-1,   0.20000,  100.00,  100.00,  100.00,"
        "  0.00000,  0.00000,  0.00000,  0.00000,1,1",
        "1.00000E-2, 1.0O000E-1,   0.20000,  100.00,  100.00,  100.00,"
        "  0.00000,  0.00000,  0.00000,  0.00000,1,1",
    )
    with pytest.raises(
        CaseError, match=r"edited\.raw:22 branch record: X = '1\.0O000E-1': not a number"
    ):
        read_raw(path)


@pytest.mark.parametrize("value", ["4_0.000", "\uff14\uff10.000"])
def test_a_raw_number_is_written_in_ascii_digits(tmp_path, value):
    """float() read a load's PL 4_0.000 as 40 MW, and fullwidth digits as ASCII ones."""
    load = "    4,'1 ',1,   1,   1,    "
    path = _edit(tmp_path, f"{load}40.000", f"{load}{value}")
    with pytest.raises(CaseError, match=rf"edited\.raw:12 load record: PL = '{value}': not"):
        read_raw(path)


def test_unknown_bus_names_file_line_and_record(tmp_path):
    path = _edit(tmp_path, "    4,'1 ',1,   1,   1,    40.000", "    9,'1 ',1,   1,   1,    40.000")
    with pytest.raises(CaseError, match=r"edited\.raw:12 load record: load bus 9 is not in"):
        read_raw(path)


def _with_unsupported(tmp_path):
    """The v33 case with a multi-section line and a FACTS device added."""
    path = _edit(
        tmp_path,
        "0 / END OF MULTI-SECTION LINE DATA",
        "    1,     2,'&1',1,     4\n0 / END OF MULTI-SECTION LINE DATA",
    )
    text = path.read_text().replace(
        "0 / END OF FACTS DEVICE DATA", "'SVC1', 4, 0, 1\n0 / END OF FACTS DEVICE DATA", 1
    )
    path.write_text(text)
    return path


_FACTS = "edited.raw:47 FACTS device 'SVC1' at bus 4: FACTS devices are not modelled: its "


def test_unsupported_records_refused_together_by_default(tmp_path):
    """Each unsupported record is named with what it is (its name and buses) and what a
    run lacks without it (round 49: 'facts device record' alone); a multi-section line
    grouping is read without use: its sections are branch records, read as such."""
    path = _with_unsupported(tmp_path)
    with pytest.raises(CaseError) as err:
        load_psse(path)
    msg = str(err.value)
    assert "1 unsupported record(s)" in msg
    assert _FACTS + "compensation is lost" in msg
    path.write_text(path.read_text().replace("'SVC1', 4, 0, 1\n", ""))
    unused = read_raw(path).unused
    assert (
        "1 multi-section line record(s) (edited.raw:41): groupings of branch records, whose "
        "sections are read as the branches they are" in " ".join(unused)
    )


def test_unsupported_records_skipped_with_a_warning(tmp_path):
    path = _with_unsupported(tmp_path)
    with pytest.warns(UserWarning, match="left out 1 unsupported record"):
        case, left_out, *_ = import_psse(path, on_unsupported="skip")
    assert left_out == (_FACTS + "compensation is lost",)
    assert len(case.branches) == 4  # the case without them


def test_a_dc_line_is_named_with_its_buses_and_setting(tmp_path):
    """A two-terminal dc line left out is named with its name, rectifier and inverter
    buses and its scheduled power (round 49: 'two-terminal dc line record')."""
    dc = (
        "'DC1',1,5.0,10.0,500.0,0,0,0,'I',0,20,1.0\n"
        "    1,1,90,5,13.0,0.0,2.0,1.0,230,1,1,1.5,0.51,0.0,0,0,0,'1',0.0\n"
        "    4,1,90,5,13.0,0.0,2.0,1.0,115,1,1,1.5,0.51,0.0,0,0,0,'1',0.0\n"
    )
    path = _edit(
        tmp_path, "0 / END OF TWO-TERMINAL DC DATA", dc + "0 / END OF TWO-TERMINAL DC DATA"
    )
    left_out = [str(s) for s in read_raw(path).unsupported]
    assert left_out == [
        "edited.raw:37 two-terminal dc line 'DC1' from bus 1 to bus 4, SETVL 10 MW: dc lines "
        "are not modelled: the power it carries is lost"
    ]


@pytest.mark.andes
def test_unsupported_dyr_records_are_listed_with_the_raw_ones():
    _andes, raw = _andes_case("kundur/kundur.raw")
    dyr = raw.with_name("kundur_full.dyr")  # ends with ANDES's own Toggle record (line 37)
    with pytest.raises(
        CaseError,
        match=r"kundur\.raw \+ kundur_full\.dyr: 1 unsupported "
        r"record\(s\).*kundur_full\.dyr:37 TOGGLE 'LINE_8'",
    ):
        load_psse(raw, dyr)
    with pytest.warns(UserWarning, match="kundur_full.dyr:37 TOGGLE 'LINE_8': model TOGGLE is not"):
        case = load_psse(raw, dyr, on_unsupported="skip")
    assert (len(case.machines), len(case.exciters), len(case.governors)) == (4, 4, 4)


def test_load_of_mixed_sign_has_no_load_con_fractions(tmp_path):
    # PL = 100 MW with IP = -200 MW: no fractions in [0, 1] (PST load_con); fine when all
    # loads are constant impedance
    path = _edit(tmp_path, "100.000,    30.000,    20.000", "100.000,    30.000,  -200.000")
    with pytest.raises(CaseError, match=r"edited\.raw:10 loads at bus 2: constant-power"):
        load_psse(path, loads="raw")
    assert load_psse(path).buses.pload[1] == pytest.approx((100 - 200 * 0.98) / 100)


def test_two_iregs_at_one_bus_are_unsupported(tmp_path):
    """PSS/E's plant data is per bus: its machines regulate one bus (remote regulation
    itself: tests/network/test_remote_regulation.py)."""
    path = _edit(tmp_path, "1.01000,     3,   100.000", "1.01000,     4,   100.000")
    with pytest.raises(
        CaseError,
        match=r"edited\.raw:19 generator at bus 3 '2': IREG 4 differs from bus 3's first "
        r"generator's",
    ):
        load_psse(path)


# --------------------------------------------------------------------------- the CLI


def test_import_psse_writes_a_case_that_reads_back(tmp_path):
    out = tmp_path / "five.json"
    dyr = DATA / "five_bus.dyr"
    res = run("import-psse", V34, dyr, "-o", out, "--json", "--loads", "raw")
    assert res.exit_code == 0, res.output
    summary = json.loads(res.stdout)
    assert (summary["buses"], summary["branches"], summary["nonconforming_loads"]) == (4, 4, 2)
    assert load_case(out).equals(load_psse(V34, dyr, loads="raw"))


def test_import_psse_without_dyr_is_refused_unless_static(tmp_path):
    """A RAW file alone has no machine: the import is refused (nothing written) unless
    --static asks for a power-flow-only case."""
    out = tmp_path / "five.json"
    res = run("import-psse", V34, "-o", out)
    assert res.exit_code == 2 and not out.exists()
    assert "five_bus_v34.raw: no dynamic data: the case would have no machines" in res.stderr
    assert "--static" in res.stderr
    res = run("import-psse", V34, "-o", out, "--static", "--json")
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["machines"] == 0 and out.exists()


def test_a_case_whose_machines_are_all_infinite_buses_is_warned_of(tmp_path):
    """The SMIB with its machine's H = 0 as well: both machines are infinite buses, so none
    can swing and every CCT lies above its search limit.  The import warns naming them, and
    so does loading the written case; the SMIB as given (H = 3 s) is not warned of."""
    dyr = tmp_path / "smib_h0.dyr"
    dyr.write_text((DATA / "smib.dyr").read_text().replace("   3.0  0.0 /", "   0.0  0.0 /"))
    out = tmp_path / "smib_h0.json"
    said = "every machine is an infinite bus (H = 0: machine(s) 1, 2): none can swing"
    res = run("import-psse", DATA / "smib_v33.raw", dyr, "-o", out)
    assert res.exit_code == 0 and out.exists(), res.output
    assert f"warning: smib_v33.raw: {said}" in res.stderr
    with pytest.warns(UserWarning, match=re.escape(said)):
        load_case(out)
    res = run("import-psse", DATA / "smib_v33.raw", DATA / "smib.dyr", "-o", out)
    assert res.exit_code == 0 and "infinite bus" not in res.stderr, res.output
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        load_case(out)


def test_imported_case_runs_flat_from_its_power_flow(tmp_path):
    # the CLI's case file through `simulate`: no disturbance, so the machines initialised
    # from the imported power flow stay at synchronous speed (the five-bus generators have
    # ZSORCE R = 0: with armature resistance stabctl's flat runs drift, ~4e-4 pu in 1 s)
    out = tmp_path / "five.json"
    assert run("import-psse", V33, DATA / "five_bus.dyr", "-o", out).exit_code == 0
    res = run("simulate", out, "--tf", "1", "--out", tmp_path / "flat.npz", "--json")
    assert res.exit_code == 0, res.output
    flat = SimulationResult.from_npz(tmp_path / "flat.npz")
    assert np.max(np.abs(flat.speed - 1.0)) < 1e-9


def test_import_psse_bad_input_exits_2_and_writes_nothing(tmp_path):
    src = _with_unsupported(tmp_path)
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    res = run("import-psse", src, "-o", out_dir / "x.json")
    assert res.exit_code == 2, res.output
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: edited.raw: 1 unsupported")
    assert list(out_dir.iterdir()) == []
    res = run("import-psse", src, "-o", out_dir / "x.json", "--skip-unsupported", "--static")
    assert res.exit_code == 0, res.output
    assert "warning: edited.raw: left out 1 unsupported record(s)" in res.stderr
    assert [p.name for p in out_dir.iterdir()] == ["x.json"]


# ------------------------------------------------------------------ against ANDES


def _andes_case(name):
    pytest.importorskip("andes")
    andes = _andes()  # its logger set as stabctl sets it: no log directory left behind
    return andes, Path(andes.__file__).parent / "cases" / name


def _andes_pflow(andes, raw):
    ss = andes.load(str(raw), no_output=True, default_config=True)
    ss.PFlow.config.tol = 1e-12
    assert ss.PFlow.run()
    return ss


@pytest.mark.andes
@pytest.mark.parametrize("name", ["kundur/kundur.raw", "wecc/wecc.raw"])
def test_power_flow_matches_andes(name):
    andes, raw = _andes_case(name)
    ss = _andes_pflow(andes, raw)
    case = load_psse(raw)
    # ANDES's line model adds 1e-8 pu to every R and X (andes/models/line/line.py: yhk =
    # 1/((r+1e-8) + j(x+1e-8))); the same here makes the networks identical. ANDES leaves
    # PV Q limits alone (PV.config.pv2pq = 0): so do we.
    br = case.branches
    same = case.replace(branches=br.replace(r=br.r + 1e-8, x=br.x + 1e-8))
    idx = case.bus_indices(np.array(ss.Bus.idx.v))
    for c, vtol, atol in ((same, 1e-10, 1e-10), (case, 1e-5, 2e-5)):
        pf = solve_powerflow(c, q_limits=False, tol=1e-12)
        assert np.max(np.abs(pf.vmag[idx] - ss.Bus.v.v)) < vtol
        assert np.max(np.abs(pf.vang[idx] - ss.Bus.a.v)) < atol


@pytest.mark.andes
def test_phase_shifter_sign_matches_andes(tmp_path):
    andes, raw = _andes_case("kundur/kundur.raw")
    # transformer 1-5 with ANG1 = 10 deg (winding 1 leads, PSS/E POM)
    text = raw.read_text().replace(
        "1.00000,   0.000,   0.000,     0.00", "1.00000,   0.000,  10.000,     0.00", 1
    )
    path = tmp_path / "kundur_ps.raw"
    path.write_text(text)
    ss = _andes_pflow(andes, path)
    case = load_psse(path)
    br = case.branches
    case = case.replace(branches=br.replace(r=br.r + 1e-8, x=br.x + 1e-8))
    pf = solve_powerflow(case, q_limits=False, tol=1e-12)
    idx = case.bus_indices(np.array(ss.Bus.idx.v))
    assert np.max(np.abs(pf.vang[idx] - ss.Bus.a.v)) < 1e-10
    assert abs(pf.vang[case.bus_index(5)] - pf.vang[case.bus_index(1)]) > 0.1


@pytest.mark.andes
def test_q_limits_switch_matches_andes_ieee14(tmp_path):
    """IEEE 14 (ANDES's ieee14.raw + ieee14.dyr): without PV Q limits (ANDES's default,
    `Simulator(q_limits=False)`, `--no-q-limits`) the simulator starts from ANDES's power
    flow; with them (PST's chq_lim, the default) PV buses switch to PQ and the voltages
    move.  The case starts at all: its bus-6 unit has Pm0 = 0.3 = TGOV1's Tmin, reached
    up to round-off (the start-up check's tolerance)."""
    from stabctl.dynamics.driver import Simulator
    from stabctl.io.andes import strip_dyr

    andes, folder = _andes_case("ieee14")
    raw, dyr = folder / "ieee14.raw", tmp_path / "ieee14.dyr"
    strip_dyr(folder / "ieee14.dyr", dyr, {"TOGGLE"})
    ss = _andes_pflow(andes, raw)
    case = load_psse(raw, dyr, conventions="andes")
    idx = case.bus_indices(np.array(ss.Bus.idx.v))
    v_andes = np.array(ss.Bus.v.v) * np.exp(1j * np.array(ss.Bus.a.v))
    free, limited = Simulator(case, q_limits=False), Simulator(case)
    assert (free.q_limits, limited.q_limits) == (False, True)
    assert np.max(np.abs(free.op.V[idx] - v_andes)) < 2e-5  # ANDES's R, X + 1e-8
    assert np.max(np.abs(limited.op.V[idx] - v_andes)) > 0.01
    assert np.sum(solve_powerflow(case).q_limited) == 4
    assert not solve_powerflow(case, q_limits=False).q_limited.any()
    out = tmp_path / "ieee14.json"
    r = CliRunner().invoke(
        main, ["import-psse", str(raw), str(dyr), "-o", str(out), "--conventions", "andes"]
    )
    assert r.exit_code == 0, r.output
    for flag, expected in (("--no-q-limits", False), ("--q-limits", True)):
        r = CliRunner().invoke(main, ["simulate", str(out), "--tf", "0.1", "--json", flag])
        assert r.exit_code == 0, r.output
        assert json.loads(r.output)["q_limits"] is expected


# ------------------------------------------------------------- PSS/E's own runs (issue 50)

RUNS = Path(__file__).parents[1] / "data" / "psse_runs"


def test_raw_ending_with_q_after_the_transformer_data_is_read():
    """PSS/E's CSVGN1 run: its RAW ends with 'Q' right after the transformer section
    (valid PSS/E: 'Q' ends the data, the sections after it empty): read, the step-up
    transformer 1-2 (WINDV1 0.9524) among its branches."""
    raw = read_raw(RUNS / "CSVGN1" / "3_BUS_System.raw")
    assert sorted(raw.bus[:, 0].astype(int)) == [1, 2, 3]
    assert raw.line.shape[0] == 3
    assert raw.line[2, 5] == pytest.approx(0.9524, abs=1e-12)


def test_csvgn1_generator_imports_as_a_compensator_and_round_trips(tmp_path):
    """PSS/E's CSVGN1 run as written (tests/data/psse_runs/README.md): its generator at bus
    3 with the CSVGN1 record is a static var compensator, not a machine; the case file
    keeps the svc_con table; a CSVGN1 whose generator carries real power is refused by
    name."""
    out = tmp_path / "svc.json"
    svc = RUNS / "CSVGN1"
    res = run("import-psse", svc / "3_BUS_System_SVC.raw", svc / "3_BUS_System_SVC.dyr", "-o", out)
    assert res.exit_code == 0, res.output
    assert "1 machine," in res.output and "1 static var compensator" in res.output
    case = load_case(out)
    assert case.svcs.equals(
        load_psse(svc / "3_BUS_System_SVC.raw", svc / "3_BUS_System_SVC.dyr").svcs
    )
    raw = (svc / "3_BUS_System_SVC.raw").read_text().replace("3, '1', 0.000,", "3, '1', 5.000,")
    (tmp_path / "p.raw").write_text(raw)
    with pytest.raises(CaseError, match=r"CSVGN1 \(bus 3, id 1\): its generator has PG = 5 MW"):
        load_psse(tmp_path / "p.raw", svc / "3_BUS_System_SVC.dyr")


def test_gast_dispatched_at_its_load_limit_imports_and_runs_flat(tmp_path):
    """PSS/E's GAST run: AT = 1 and the machine dispatched at Pm0 = 1 pu (the limit
    AT + KT (AT - Pm0) = Pm0 to round-off) was refused by a strict start-up check
    (issue 50); with the checks' tolerance it starts, and at rest: flat for 0.2 s."""
    out = tmp_path / "gast.json"
    gast = RUNS / "GAST"
    res = run("import-psse", gast / "ThreeBusMulti.raw", gast / "ThreeBus_GAST.dyr", "-o", out)
    assert res.exit_code == 0, res.output
    res = run("simulate", out, "--tf", "0.2", "--out", tmp_path / "flat.npz", "--json")
    assert res.exit_code == 0, res.output
    flat = SimulationResult.from_npz(tmp_path / "flat.npz")
    assert np.max(np.abs(flat.speed - 1.0)) < 1e-8


def _with_unsupported_machine(tmp_path):
    """five_bus.dyr with generator 3 '2' given a generator model stabctl does not support
    (GENTPJ1: any such record, e.g. REGCC1, takes the same path)."""
    lines = (DATA / "five_bus.dyr").read_text().splitlines()
    return _dyr(tmp_path, *lines[:2], "3 'GENTPJ1' '2' 8.0 0.03 0.4 0.05 3.0 0.0 1.8 1.7 /")


def test_an_unsupported_machine_record_is_named_not_called_missing(tmp_path):
    """Issue 50: a generator whose machine record is of a model stabctl lacks was
    refused as 'without a machine model record', the record unnamed, with
    --net-unmodelled --skip-unsupported failing the same way.  Now the record is named
    with file:line and why; --net-unmodelled alone refuses it as unsupported; both flags
    leave it out and net its generator, each named with why."""
    dyr = _with_unsupported_machine(tmp_path)
    named = "edited.dyr:3 GENTPJ1: generator model not supported by stabctl (yet)"
    for mode in ("error", "skip"):
        with pytest.raises(CaseError) as err:
            import_psse(V33, dyr, on_unsupported=mode)
        assert f"machine model record stabctl cannot read: machine 3 (bus 3, id 2): {named}" in (
            str(err.value)
        )
        assert "unmodelled='net'" in str(err.value) and "on_unsupported='skip'" in str(err.value)
    with pytest.raises(CaseError, match=r"1 unsupported record\(s\).*edited\.dyr:3 GENTPJ1"):
        import_psse(V33, dyr, unmodelled="net")
    with pytest.warns(UserWarning):
        case, left_out, netted, *_ = import_psse(V33, dyr, on_unsupported="skip", unmodelled="net")
    assert left_out == (
        "edited.dyr:3 GENTPJ1 at bus 3 '2': generator model not supported by stabctl (yet)",
    )
    assert netted == (
        "five_bus_v33.raw:19 generator at bus 3 '2': its machine record edited.dyr:3 GENTPJ1 "
        "is not supported (left out)",
    )
    assert list(case.machines.number) == [1, 2]
    assert case.buses.pload[case.bus_index(3)] == pytest.approx(-0.5, abs=1e-15)


def test_cli_names_every_record_left_out_and_generator_netted(tmp_path):
    dyr = _with_unsupported_machine(tmp_path)
    out = tmp_path / "x.json"
    res = run("import-psse", V33, dyr, "-o", out)
    assert res.exit_code == 2 and not out.exists()
    assert "edited.dyr:3 GENTPJ1: generator model not supported" in res.stderr
    res = run("import-psse", V33, dyr, "-o", out, "--skip-unsupported", "--net-unmodelled")
    assert res.exit_code == 0, res.output
    assert "  left out: edited.dyr:3 GENTPJ1 at bus 3 '2': generator model not supported" in (
        res.stdout
    )
    assert "  netted: five_bus_v33.raw:19 generator at bus 3 '2': its machine record" in res.stdout
    res = run(
        "import-psse", V33, dyr, "-o", out, "--skip-unsupported", "--net-unmodelled", "--json"
    )
    summary = json.loads(res.stdout)
    assert summary["left_out"][0].startswith("edited.dyr:3 GENTPJ1 at bus 3 '2'")
    assert summary["netted"][0].endswith("edited.dyr:3 GENTPJ1 is not supported (left out)")


def test_power_flow_is_reported_against_the_raw_files_own_solution(tmp_path):
    """PSS/E's EXST1 run (TVC system: a step-down transformer 4-3 with WINDV2 1.04, which
    ANDES's reader drops): stabctl's power flow of the imported case (Q limits on, as
    simulate solves it) is compared with the RAW's VM, VA, bus by bus: within 1e-4 here
    (the RAW's voltages are written to 5 decimals), no warning but the one naming the
    transformer whose voltage control (COD1 1) is held at the RAW's ratio."""
    exst1 = RUNS / "EXST1"
    out = tmp_path / "exst1.json"
    res = run("import-psse", exst1 / "TVC_System_32.raw", exst1 / "TVC_System.dyr", "-o", out)
    assert res.exit_code == 0, res.output
    assert "power flow against the RAW's solution (Q limits on" in res.stdout
    warned = [line for line in res.stderr.splitlines() if line.startswith("warning")]
    assert warned == [
        "warning: TVC_System_32.raw + TVC_System.dyr: 1 control(s) held at their RAW setting: "
        "TVC_System_32.raw:23 transformer 4-3 '1': held at its RAW ratio and angle (COD1 1: "
        "voltage control of bus 3, not modelled in the power flow or the dynamics)"
    ], res.stderr
    res = run(
        "import-psse", exst1 / "TVC_System_32.raw", exst1 / "TVC_System.dyr", "-o", out, "--json"
    )
    gap = json.loads(res.stdout)["powerflow_against_raw"]
    assert gap["vmag_diff_pu"] < 1e-4 and gap["angle_diff_rad"] < 1e-4
    assert gap["vmag_bus"] in (1, 2, 3, 4) and gap["angle_bus"] in (1, 2, 3, 4)


def test_a_dyr_value_read_otherwise_is_named_changed(tmp_path):
    """Issue 50: nothing changed silently.  An ESDC2A's VRMAX = 0 is computed as PSS/E
    computes it (`test_dc_exciter_vrmax_zero_is_computed_as_psse`), read as no upper limit
    with conventions="pst": each named with file:line in `changed`, a warning and the CLI's
    summary; an SCRX read with conventions="andes" (ANDES's SEXS with SEXS's defaults)
    likewise."""
    esdc2a = "1 'ESDC2A' 1 0.0 400 0.04 0 0 0.0 -7.3 1.0 0.8 0.03 1.0 0 3.1 0.33 2.3 0.1 /"
    lines = (DATA / "five_bus.dyr").read_text().splitlines()
    dyr = _dyr(tmp_path, *lines, esdc2a)
    with pytest.warns(UserWarning, match=r"read 1 record\(s\) with a value other than"):
        imported = import_psse(V33, dyr)
    assert imported.changed == (
        "edited.dyr:5 ESDC2A (bus 1, id 1): VRMAX = 0 computed as PSS/E does, (KE + SE(E2)) "
        "E2 = (1 + 0.1) 2.3 = 2.53, VRMIN = -VRMAX (PAG 15.2.4)",
    )
    res = run("import-psse", V33, dyr, "-o", tmp_path / "x.json", "--json")
    assert json.loads(res.stdout)["changed"] == list(imported.changed)
    with pytest.warns(UserWarning, match=r"read 1 record\(s\) with a value other than"):
        imported = import_psse(V33, dyr, conventions="pst")
    assert imported.changed == (
        "edited.dyr:5 ESDC2A (bus 1, id 1): VRMAX = 0 read as no upper limit (999)",
    )
    assert imported.case.exciters.Vrmax[0] == 999.0
    scrx = _dyr(tmp_path, *lines, "1 'SCRX' 1 0.1 10 200 0.05 -5 5 0 0 /")
    with pytest.warns(UserWarning, match="SEXS's defaults"):
        imported = import_psse(V33, scrx, conventions="andes")
    (changed,) = imported.changed
    assert changed.startswith("edited.dyr:5 SCRX (bus 1, id 1): read as ANDES 2.0 reads it")
    assert import_psse(V33, scrx).changed == ()


def test_a_model_andes_lacks_read_with_its_conventions_is_said_read_as_psse(tmp_path):
    """Round 55 AQ25: with --dyr-conventions andes, a DEGOV (which ANDES 2.0 lacks, and
    import-andes refuses by name) was read as PSS/E's Model Library without a word, while
    an SCRX read as ANDES's SEXS was named.  Now it is named in `changed`; under the psse
    conventions nothing is."""
    runs = Path(__file__).parents[1] / "data" / "psse_runs" / "DEGOV"
    raw, dyr = runs / "ThreeBusMulti.raw", runs / "ThreeBus_DEGOV.dyr"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        imported = import_psse(raw, dyr, conventions="andes")
        plain = import_psse(raw, dyr)
    degov = [c for c in imported.changed if " DEGOV (bus 102, id 1): " in c]
    assert degov == [
        "ThreeBus_DEGOV.dyr:3 DEGOV (bus 102, id 1): ANDES 2.0 has no DEGOV: read as PSS/E's "
        "Model Library reads it (no ANDES reading to compare like for like)"
    ]
    assert not [c for c in plain.changed if "DEGOV" in c]


@pytest.mark.parametrize(
    ("model", "ke", "vrmax"),
    [("ESDC2A", 1.0, (1.0 + 0.1) * 2.3), ("ESDC1A", 0.0, 0.1 * 2.3), ("IEEEX1", -0.05, 0.1 * 2.3)],
)
def test_dc_exciter_vrmax_zero_is_computed_as_psse(tmp_path, model, ke, vrmax):
    """A DC exciter's VRMAX = 0 read as PSS/E reads it (PAG 15.2.4; OpenIPSL's
    ``calculate_dc_exciter_params``): VRMAX = SE(E2) E2 when KE <= 0 (OpenIPSL's value),
    (KE + SE(E2)) E2 when KE > 0 (the ceiling that holds Efd at E2 in steady state), VRMIN
    = -VRMAX (with KE = 0, K_E is then computed from it so that V_R starts at VRMAX/10),
    and a run without disturbance stays at rest (Efd, speeds and voltages).  It was read as
    no upper limit (999), and IEEEX1's refused.  No ceiling (SE(E2) = 0, KE = 0) is refused
    by name."""
    rec = f"1 '{model}' 1 0.0 400 0.04 0 0 0.0 -7.3 {ke} 0.8 0.03 1.0 0 3.1 0.33 2.3 0.1 /"
    lines = (DATA / "five_bus.dyr").read_text().splitlines()
    with pytest.warns(UserWarning, match="VRMAX = 0 computed as PSS/E does"):
        case = import_psse(V33, _dyr(tmp_path, *lines, rec)).case
    e = case.exciters
    assert e.Vrmax[0] == pytest.approx(vrmax, rel=1e-14) and e.Vrmin[0] == -e.Vrmax[0]
    assert Simulator(case).run(t_end=2.0).drift()["pu"] < 1e-9
    dead = rec.replace("2.3 0.1 /", "2.3 0.0 /").replace(f" {ke} 0.8", " 0 0.8")
    with pytest.raises(CaseError, match=r"VRMAX = 0 is computed as \(KE \+ SE\(E2\)\) E2 = 0"):
        import_psse(V33, _dyr(tmp_path, *lines, dead))


_T1_WINDING_1 = "240.00,   0.000,   0.000,"


def test_a_blank_winding_voltage_under_cw_2_is_the_nominal_one_as_pss_e_reads_it(tmp_path):
    """POM Transformer Data: WINDV1 left blank is NOMV1 under CW 2 (kV), 1.0 only under
    CW 1 and 3.  T1 (CW 2, NOMV1 0: bus 2's 230 kV) with WINDV1 blank has t1 = 1, not
    1 kV / 230 kV (which had made the power flow fail with no record named)."""
    path = _edit(tmp_path, _T1_WINDING_1, ",   0.000,   0.000,")
    line = read_raw(path).line
    np.testing.assert_allclose(line[2, 5], 1 / (21 / 20), rtol=1e-14)


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        (
            _T1_WINDING_1,
            "0.0,   0.000,   0.000,",
            r"edited\.raw:28 transformer record \(line 3 of the record\): "
            r"transformer 2-3 '1': WINDV1 0\.0 must be > 0",
        ),
        (_T1_WINDING_1, "-240.0,   0.000,   0.000,", r"WINDV1 -240\.0 must be > 0"),
        (_T1_WINDING_1, "240.00,   -5.000,   0.000,", r"NOMV1 -5\.000 kV must be >= 0"),
        (_T1_WINDING_1, "240.00,   0.000,   400.000,", r"ANG1 400\.000 degrees must be within"),
        (
            "    2,'LOAD        ', 230.0000",
            "    2,'LOAD        ',   0.0000",
            r"transformer 2-3 '1': CW 2 gives WINDV1 in kV, but bus 2 has no BASKV",
        ),
        (
            "    2,'LOAD        ', 230.0000",
            "    2,'LOAD        ', -230.000",
            r"edited\.raw:\d+ bus record: bus 2: BASKV -230\.000 kV must be >= 0",
        ),
        (
            "    2,     3,     0,'1 ',2,2,1,",
            "    2.0,     3,     0,'1 ',2,2,1,",
            r"edited\.raw:26 transformer record \(line 1 of the record\): I = '2\.0': not an "
            r"integer",
        ),
    ],
)
def test_transformer_and_bus_data_pss_e_refuses_are_refused_naming_the_field(
    tmp_path, old, new, message
):
    """A winding voltage that is not > 0, a negative NOMV or BASKV, a phase shift outside
    PSS/E's -180 to 180 degrees, kV under CW 2 at a bus without a base voltage and a bus
    number written as 2.0 are refused naming the RAW line and the PSS/E field (they had
    been replaced by 1.0 or 1 kV silently, or refused later naming a row of stabctl's
    own tables)."""
    with pytest.raises(CaseError, match=message):
        read_raw(_edit(tmp_path, old, new))


def test_the_import_help_example_runs_as_written(tmp_path, monkeypatch):
    """`import-psse --help`'s example, on ANDES's cases/kundur files it names, run line by
    line as printed: the import exits 0 (its TOGGLE record, a disturbance, left out by
    name) and the simulation of the imported case too."""
    import shutil

    andes = pytest.importorskip("andes")
    for name in ("kundur.raw", "kundur_full.dyr"):
        shutil.copy(andes.get_case(f"kundur/{name}"), tmp_path / name)
    monkeypatch.chdir(tmp_path)
    text = CliRunner().invoke(main, ["import-psse", "--help"]).output
    lines = [x.split() for x in text.splitlines() if x.strip().startswith("stabctl ")]
    assert [x[1] for x in lines] == ["import-psse", "simulate"]
    outputs = []
    for line in lines:
        res = CliRunner().invoke(main, line[1:])
        assert res.exit_code == 0, (line, res.output)
        outputs.append(res.output)
    assert "kundur_full.dyr:37 TOGGLE" in outputs[0] and "stable" in outputs[1]


#: the five-bus v35 case's generator at bus 3 '1' (PG 150 MW, QT 100, QB -50): WMOD, WPF
WIND_TAIL = "   0,1.0000, 0, 1.000\n    3,'2 '"


@pytest.mark.parametrize(
    "wmod, wpf, qt, qb",
    [
        # WMOD 2: +-|PG| tan(acos |WPF|) = +-150 * 0.75, with generator 3 '2's 60 and -20
        (2, "0.800", 112.5 + 60.0, -112.5 - 20.0),
        # WMOD 3: a fixed Q of PG tan(acos |WPF|), the sign of PG times that of WPF
        (3, "-0.800", -112.5 + 60.0, -112.5 - 20.0),
    ],
)
def test_a_wind_machine_s_q_limits_come_from_wpf_as_pss_e_derives_them(tmp_path, wmod, wpf, qt, qb):
    """POM Generator Data: WMOD 2 gives limits of equal magnitude and opposite sign from the
    machine's P and WPF, WMOD 3 a fixed Q (limits equal); QT and QB are not used.  The
    generator is named in ``changed`` with the limits and the fields they come from."""
    raw = tmp_path / "wind.raw"
    text = (DATA / "five_bus_v35.raw").read_text()
    assert text.count(WIND_TAIL) == 1
    raw.write_text(text.replace(WIND_TAIL, WIND_TAIL.replace(" 0, 1.000", f" {wmod}, {wpf}")))
    data = read_raw(raw)
    row = data.bus[data.bus[:, 0] == 3][0]
    assert (row[10], row[11]) == pytest.approx((qt / 100.0, qb / 100.0), abs=1e-12)
    (said,) = [str(c) for c in data.changed if "generator" in str(c)]
    q = 112.5 if wmod == 2 else -112.5
    assert said == (
        f"wind.raw:33 generator at bus 3 '1': Q limits QT {q:g}, QB {-q if wmod == 2 else q:g} "
        f"Mvar from PG 150.000 and WPF {wpf} (WMOD {wmod}, PSS/E's rule) instead of QT 100.000, "
        "QB -50.000"
    )


def test_an_ide_2_bus_without_a_generator_in_service_is_named_as_a_load_bus(tmp_path):
    """PSS/E takes an IDE 2 bus without an in-service generator as a load bus (type 1):
    so does stabctl, naming the bus's record in ``load_buses`` and the import's
    ``changed`` (it had been silent); many such buses make one summary line."""
    from stabctl.io.psse import held_lines

    raw = tmp_path / "pv.raw"
    old = "    4,'SUB         ', 115.0000,1,"
    raw.write_text(V33.read_text().replace(old, old.replace(",1,", ",2,")))
    data = read_raw(raw)
    assert data.bus[data.bus[:, 0] == 4][0][9] == PQ
    said = "pv.raw:7 bus 4: IDE 2, no generator in service: a load bus (PSS/E)"
    assert [str(h.source) for h in data.load_buses] == [said]
    with pytest.warns(UserWarning, match="IDE 2, no generator in service"):
        imported = import_psse(raw, DATA / "five_bus.dyr")
    assert said in imported.changed and said in imported.changed_summary
    assert held_lines(data.load_buses * 6) == [
        "6 IDE 2 buses without a generator in service (none, or netted) read as load buses "
        "(PSS/E), at buses 4, 4, 4, 4, 4, 4"
    ]


def test_controls_not_modelled_are_named_as_held_at_their_raw_setting(tmp_path):
    """A switched shunt that PSS/E switches (MODSW not 0) stays at BINIT, a transformer
    winding under control (COD > 0) at its ratio and angle: each is named in `held` (a
    locked shunt, MODSW 0, or a control switched off, COD < 0, is as PSS/E holds it: not
    named), in the import's warning and in the CLI's summary; many of a kind make one
    line with their buses."""
    from stabctl.io.psse import held_lines
    from stabctl.io.psse_raw import Held, RawSource

    winding = "240.00,   0.000,   0.000,   100.00,   100.00,   100.00, 0,      0,"
    raw = tmp_path / "held.raw"
    raw.write_text(V33.read_text().replace(winding, winding.replace(" 0,      0,", " 1,      3,")))
    with pytest.warns(UserWarning, match=r"2 control\(s\) held at their RAW setting"):
        imported = import_psse(raw, DATA / "five_bus.dyr")
    assert imported.held == (
        "held.raw:26 transformer 2-3 '1': held at its RAW ratio and angle (COD1 1: voltage "
        "control of bus 3, not modelled in the power flow or the dynamics)",
        "held.raw:47 switched shunt at bus 4: held at BINIT 30.00 Mvar (MODSW 1: not switched "
        "in the power flow or the dynamics)",
    )
    res = run("import-psse", raw, DATA / "five_bus.dyr", "-o", tmp_path / "h.json")
    assert res.exit_code == 0, res.output
    assert "2 control(s) held at their RAW setting" in res.stdout
    assert [line for line in res.stdout.splitlines() if line.startswith("  held: ")] == [
        f"  held: {h}" for h in imported.held
    ]
    res = run("import-psse", raw, DATA / "five_bus.dyr", "-o", tmp_path / "h.json", "--json")
    assert json.loads(res.stdout)["held"] == list(imported.held)
    locked = tmp_path / "locked.raw"
    locked.write_text(V33.read_text().replace("    4,1,0,1,1.05000", "    4,0,0,1,1.05000"))
    assert read_raw(locked).held == ()
    many = [Held("switched shunt", str(n), RawSource("a.raw", n, f"shunt {n}")) for n in range(6)]
    assert held_lines(many) == [
        "6 switched shunts held at BINIT (MODSW not 0: not switched in the power flow or the "
        "dynamics), at buses 0, 1, 2, 3, 4, 5"
    ]


def test_raw_generators_outside_their_power_limits_and_unused_records_are_named(tmp_path):
    """Round 42: generator 101 dispatched at PG 153.335 MW with PT 50 MW, and an area
    interchange record, were read without a word (the import's help says each record not
    read is named).  PSS/E solves the dispatch as written: kept, and named; the area
    record (a name and an interchange schedule, of no use to a run) is counted with its
    lines in the summary (`import-psse`'s text and --json)."""
    from stabctl.io.psse import import_psse

    raw = Path(__file__).parents[1] / "data" / "psse_runs" / "GENROU" / "ThreeBusMulti.raw"
    text = raw.read_text().replace(
        "   318.000,     0.000,   1,1.0000", "    50.000,     0.000,   1,1.0000", 1
    )
    text = text.replace(
        "Begin Area interchange data\n",
        "Begin Area interchange data\n   1,   101,    80.000,    10.000,'AREA1'\n",
    )
    path = tmp_path / "odd.raw"
    path.write_text(text)
    with pytest.warns(UserWarning, match=r"1 record\(s\) kept as written that look wrong") as got:
        imported = import_psse(path)
    said = " ".join(str(w.message) for w in got)
    assert "odd.raw:11 generator at bus 101 '1': PG 153.335 MW above PT 50.000 MW" in said
    assert imported.unused == ("1 area record(s) (odd.raw:19)",)
    res = run("import-psse", path, "--static", "-o", tmp_path / "o.json", "--json")
    assert json.loads(res.stdout)["unused"] == ["1 area record(s) (odd.raw:19)"]
    res = run("import-psse", path, "--static", "-o", tmp_path / "o.json")
    assert (
        "read, of no use to a run (names, schedules, ratings): 1 area record(s) (odd.raw:19)"
        in res.stdout
    )
    assert import_psse(raw).unused == ()


def test_a_machine_whose_leakage_lies_above_its_subtransient_reactance_is_named(tmp_path):
    """Round 42: a GENROU with X''d 0.25 < Xl 0.28 < X'd 0.3 was read without a word
    (PSS/E's Model Library wants Xl < X''d; stabctl's model needs Xl < X'd only, and
    ANDES's ieee39_full has two such units): kept, and named with both values; Xl 0.2
    says nothing."""
    import warnings

    from stabctl.io.psse import import_psse

    raw = Path(__file__).parents[1] / "data" / "psse_runs" / "GENROU" / "ThreeBusMulti.raw"
    genrou = "8.0 0.03 0.4 0.05 6.175 0.05 1.8 1.7 0.3 0.55 0.25 {xl} 0.1 0.8"
    for xl, said in (("0.28", True), ("0.2", False)):
        dyr = tmp_path / f"x{xl}.dyr"
        dyr.write_text(
            f"    101 'GENCLS' 1 0.0 0.0 /\n    102 'GENROU' 1 {genrou.format(xl=xl)} /\n"
        )
        with warnings.catch_warnings(record=True) as got:
            warnings.simplefilter("always")
            import_psse(raw, dyr)
        named = [str(w.message) for w in got if "Xl" in str(w.message)]
        assert named == (
            [
                f"x{xl}.dyr:2 GENROU (bus 102, id 1): Xl 0.28 above X''d 0.25 (PSS/E's Model "
                "Library wants Xl < X''d; the model runs with Xl < X'd): kept as written"
            ]
            if said
            else []
        )


def test_a_saturation_value_the_model_ignores_is_named(tmp_path):
    """Round 47: a GENROU with S(1.0) = 0, S(1.2) = 0.5 and an IEEET1 with SE(E1) = 0,
    SE(E2) = 0.5 imported without a word, and ran bit for bit as with S(1.2) = 0 and
    SE(E2) = 0: PSS/E's saturation curve goes through both points, so a point 0 means
    none (OpenIPSL's SE()).  Kept as PSS/E reads it, and named; PST's machine curve,
    through (0.8, 0.8) too, still fits one (conventions "pst": no word of the machine)."""
    import warnings

    from stabctl.io.psse import import_psse

    raw = Path(__file__).parents[1] / "data" / "psse_runs" / "GENROU" / "ThreeBusMulti.raw"
    dyr = tmp_path / "s.dyr"
    dyr.write_text(
        "    101 'GENCLS' 1 0.0 0.0 /\n"
        "    102 'GENROU' 1 8.0 0.03 0.4 0.05 6.175 0.05 1.8 1.7 0.3 0.55 0.25 0.2 0.0 0.5 /\n"
        "    102 'IEEET1' 1 0.0 400.0 0.04 7.3 -7.3 1.0 0.8 0.03 1.0 0.0 2.3 0.0 3.1 0.5 /\n"
    )
    machine = (
        "s.dyr:2 GENROU (bus 102, id 1): S(1.2) = 0.5 has no effect: with S(1.0) = 0 there "
        "is no saturation (PSS/E's curve goes through both points): the machine runs "
        "unsaturated"
    )
    exciter = (
        "s.dyr:3 IEEET1 (bus 102, id 1): saturation points (E1, SE(E1)) = (2.3, 0) and (E2, "
        "SE(E2)) = (3.1, 0.5) have a 0: no saturation (a curve needs both points, as "
        "PSS/E): the exciter runs unsaturated"
    )
    for conventions, said in (("psse", [machine, exciter]), ("pst", [exciter])):
        with warnings.catch_warnings(record=True) as got:
            warnings.simplefilter("always")
            import_psse(raw, dyr, conventions=conventions)
        assert [str(w.message) for w in got if "saturation" in str(w.message)] == said


def test_a_source_reactance_other_than_the_subtransient_one_is_named(tmp_path):
    """Round 47: generator 102's ZSORCE X 0.1 beside its GENROU's X''d 0.25 was left
    unused without a word (PSS/E's Model Library wants ZSORCE = R_a + j X''d); the model
    runs with X''d, and the import says so.  The file's own 0.25 says nothing, nor does
    0.25015, the two files' rounding (round 49: Nordic 44's RAW 0.19375 against its DYR's
    0.1937 was said ten times)."""
    from stabctl.io.psse import import_psse

    runs = Path(__file__).parents[1] / "data" / "psse_runs" / "GENROU"
    raw = tmp_path / "z.raw"
    raw.write_text((runs / "ThreeBusMulti.raw").read_text().replace("2.500E-1", "1.000E-1"))
    rounded = tmp_path / "r.raw"
    rounded.write_text((runs / "ThreeBusMulti.raw").read_text().replace("2.500E-1", "2.5015E-1"))
    assert rounded.read_text() != (runs / "ThreeBusMulti.raw").read_text()
    for path, said in ((raw, True), (runs / "ThreeBusMulti.raw", False), (rounded, False)):
        with warnings.catch_warnings(record=True) as got:
            warnings.simplefilter("always")
            import_psse(path, runs / "ThreeBus_GENROU.dyr")
        named = [str(w.message) for w in got if "ZSORCE" in str(w.message)]
        assert named == (
            [
                "ThreeBus_GENROU.dyr:2 GENROU (bus 102, id 1): the RAW's ZSORCE X 0.1 differs "
                "from X''d 0.25 (PSS/E's Model Library wants ZSORCE = R_a + j X''d): the model "
                "runs with X''d"
            ]
            if said
            else []
        )


def test_an_exciter_of_a_classical_machine_is_left_out_by_name(tmp_path):
    """Round 47: a SEXS on a GENCLS imported as "1 exciter", and its field voltage rose
    from 1.04 to 1.37 pu in a run whose every other trajectory was the run's without it
    (a classical machine has no field winding).  It is an unsupported record: refused,
    or left out with --skip-unsupported, saying why."""
    from stabctl.io.psse import import_psse

    raw = Path(__file__).parents[1] / "data" / "psse_runs" / "GENROU" / "ThreeBusMulti.raw"
    dyr = tmp_path / "c.dyr"
    dyr.write_text(
        "    101 'GENCLS' 1 0.0 0.0 /\n    102 'GENCLS' 1 6.0 0.0 /\n"
        "    102 'SEXS' 1 0.4 5.0 20.0 1.0 -50.0 50.0 /\n"
    )
    why = "its machine is a GENCLS: a classical machine (constant E' behind X'd) has no field"
    with pytest.raises(CaseError, match=r"c.dyr:3 SEXS at bus 102 '1': " + re.escape(why)):
        import_psse(raw, dyr)
    got = import_psse(raw, dyr, on_unsupported="skip")
    assert len(got.left_out) == 1 and got.left_out[0].startswith("c.dyr:3 SEXS")
    assert why in got.left_out[0] and len(got.case.exciters) == 0


def test_a_radial_phase_shifter_solves_from_a_flat_start_with_its_shift(tmp_path):
    """Round 47: a 30-degree phase shifter 103-104 feeding a 10 MW load at bus 104, whose
    RAW angle is 103's (not yet solved), was refused as not converging: Newton from the
    RAW's angles, then from a flat start at the swing bus's angle (30 degrees off, both),
    went to a spurious low-voltage solution.  PSS/E's flat start sets each angle to the
    phase shifts on its way from the swing bus; so does stabctl's, and the case solves,
    bus 104 about 30 degrees below bus 103, as from a RAW holding the solved angle."""
    from stabctl.io.psse import import_psse

    runs = Path(__file__).parents[1] / "data" / "psse_runs" / "GENROU"
    text = (runs / "ThreeBusMulti.raw").read_text()
    bus = "   104,'BUS 4', 13.8,1, 1, 1, 1,1.00000, {angle},1.1,0.9,1.1,0.9\n"
    load = "   104,'1 ',1, 1, 1, 10.000, 2.000, 0.000, 0.000, 0.000, 0.000, 1,1,0\n"
    xf = (
        "   103,   104,     0,'1 ',1,1,1, 0.0, 0.0,2,'            ',1,   1,1.0000\n"
        " 0.0, 0.08, 100.0\n"
        "1.0, 0.0,   30.000,   100.00,   100.00,   100.00, 0,      0, 1.10000, 0.90000, 1.10000, "
        "0.90000,  33, 0, 0.00000, 0.00000,  0.000\n"
        "1.0,   0.000\n"
    )
    solved = {}
    for angle in ("-8.7697", "-39.0000"):
        raw = tmp_path / f"ps{angle}.raw"
        raw.write_text(
            text.replace(" 0 /End of Bus data", bus.format(angle=angle) + " 0 /End of Bus data")
            .replace(" 0 /End of Load data", load + " 0 /End of Load data")
            .replace(" 0 /End of Transformer data", xf + " 0 /End of Transformer data")
        )
        with warnings.catch_warnings(record=True):
            warnings.simplefilter("always")
            case = import_psse(raw, runs / "ThreeBus_GENROU.dyr").case
        pf = solve_powerflow(case)
        solved[angle] = np.rad2deg(pf.vang[case.bus_indices([103, 104])])
    np.testing.assert_allclose(solved["-8.7697"], solved["-39.0000"], atol=1e-6)
    assert solved["-8.7697"][1] - solved["-8.7697"][0] == pytest.approx(-30, abs=1.0)


def test_raw_records_that_look_wrong_are_kept_and_named(tmp_path):
    """Round 41: a bus whose NVHI 0.9 is below its NVLO 1.1 and a branch of R = -0.01 pu
    were read without a word.  PSS/E reads both (the limits stabctl does not use; a
    negative R as a network equivalent's): kept, and named."""
    from stabctl.io.psse import import_psse

    raw = Path(__file__).parents[1] / "data" / "psse_runs" / "GENROU" / "ThreeBusMulti.raw"
    text = raw.read_text()
    text = text.replace(
        "-8.7697,1.10000,0.90000,1.10000,0.90000", "-8.7697,0.90000,1.10000,1.10000,0.90000"
    )
    text = text.replace("   101,   102,'1 ', 1.00000E-2,", "   101,   102,'1 ', -1.00000E-2,")
    path = tmp_path / "odd.raw"
    path.write_text(text)
    with pytest.warns(UserWarning, match=r"2 record\(s\) kept as written that look wrong") as got:
        import_psse(path)
    said = " ".join(str(w.message) for w in got)
    assert "bus 103: NVHI 0.90000 below NVLO 1.10000 (voltage limits stabctl does not use" in said
    assert "odd.raw:14 branch 101-102 '1': R -1.00000E-2 pu, negative (kept" in said


@pytest.mark.parametrize(
    "header, named",
    [
        ("0,   100.00, 33, 0, 1", ["BASFRQ not given: read as 60 Hz (the POM's default)"]),
        ("0,   100.00, , 0, 1, 50.00", ["REV not given: read as version 33"]),
        (
            "0,   100.00",
            ["REV not given: read as version 33", "BASFRQ not given: read as 60 Hz"],
        ),
    ],
)
def test_a_header_s_blank_version_or_frequency_is_named(tmp_path, header, named):
    """Round 43: a case identification without REV (read as version 33) or BASFRQ (60
    Hz) was read without a word; each default taken is named in ``changed`` (the
    import's "read ... with a value other than the file's" warning)."""
    path = _edit(tmp_path, "0,   100.00, 33, 0, 1, 50.00", header)
    said = [str(c) for c in read_raw(path).changed if "case identification" in str(c)]
    assert len(said) == len(named)
    for text, want in zip(said, named):
        assert text.startswith("edited.raw:1 ") and want in text
    with pytest.warns(UserWarning, match=r"case identification: (REV|BASFRQ) not given"):
        load_psse(path)


def test_the_loads_change_of_model_is_said(tmp_path):
    """Round 49 (AG06): WECC-240's 139 constant-current loads ran as constant impedance
    (--loads impedance, the default) with nothing in the summary (the docs alone said it).
    The summary's `load_model` names it, in the caller's words; with loads='raw' the
    RAW's composition is kept and nothing is said."""
    said = (
        "the loads at 2 bus(es) (from five_bus_v33.raw:10 on): their constant-power (PL, QL) "
        "and constant-current (IP, IQ) parts run as constant impedance at the power-flow "
        "voltage ({}, the default; {} keeps the RAW's composition)"
    )
    assert read_raw(V33).load_model == said.format("loads='impedance'", "loads='raw'")
    assert read_raw(V33, loads="raw").load_model == ""
    dyr = DATA / "five_bus.dyr"
    res = run("import-psse", V33, dyr, "-o", tmp_path / "x.json")
    assert res.exit_code == 0, res.output
    assert "  load model: " + said.format("--loads impedance", "--loads raw") in res.stdout
    res = run("import-psse", V33, dyr, "-o", tmp_path / "x.json", "--json")
    assert json.loads(res.stdout)["load_model"].startswith("the loads at 2 bus(es)")
    res = run("import-psse", V33, "-o", tmp_path / "x.json", "--static", "--json")
    assert json.loads(res.stdout)["load_model"] == ""  # no dynamic run
