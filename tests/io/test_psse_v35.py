"""PSS/E RAW versions 34, 35 and 36: the same cases written in the v33 layout and in the
v34, v35 or v36 layout import as the same case (buses, branches, generators, power flow),
and malformed v35/v36 files are refused naming file:line.

Layouts: the column headings (``@!`` lines) PSS/E 34, 35 and 36 write above each section
(the five-bus files here are ``five_bus_v33.raw`` converted by hand to them: v34 has
NREG at the end of generators and switched shunts and NOD at the end of transformer
windings, v35 moves them after IREG, SWREG and CONT). The IEEE
14-bus and 24-bus pairs are public (tests/data/psse/NOTICE): v33 files and their v35
forms; the 14-bus bus records carry the IEEE solution."""

import re
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from stabctl.cli import main
from stabctl.errors import CaseError
from stabctl.io.psse import load_psse
from stabctl.io.psse_raw import read_raw, split_fields
from stabctl.network.powerflow import solve_powerflow

DATA = Path(__file__).parents[1] / "data" / "psse"
V33, V34, V35, V36 = (DATA / f"five_bus_v{v}.raw" for v in (33, 34, 35, 36))
DYR = DATA / "five_bus.dyr"
IEEE14_V33, IEEE14_V35 = DATA / "ieee14_v33.raw", DATA / "ieee14_v35.raw"


def _same_raw(a, b):
    """The two RawData hold the same case (the file's own name and version aside)."""
    for k in ("bus", "line", "load_con", "solution"):
        np.testing.assert_array_equal(getattr(a, k), getattr(b, k), err_msg=k)
    assert (a.base_mva, a.freq_hz) == (b.base_mva, b.freq_hz)
    assert [g.as_dyr() for g in a.generators] == [g.as_dyr() for g in b.generators]
    assert a.out_of_service == b.out_of_service
    assert a.unsupported == b.unsupported == ()


def _write(tmp_path, text, name="v35.raw"):
    path = tmp_path / name
    path.write_text(text)
    return path


# ------------------------------------------------------------ the same case, new layout


@pytest.mark.parametrize("path", [V34, V35, V36], ids=["v34", "v35", "v36"])
def test_five_bus_reads_as_its_v33_original(path):
    for loads in ("raw", "impedance"):
        new, old = read_raw(path, loads=loads), read_raw(V33, loads=loads)
        _same_raw(new, old)
    assert new.version == int(path.stem[-2:])
    # the title is the two lines after the case identification (not the '@!' heading)
    assert new.title.startswith("FIVE-BUS TEST CASE FOR THE PSS/E IMPORT / FIELDS AS IN")
    # switched shunts at bus 4: BINIT = 30 Mvar (v35, v36: '1' in service, '2' (ST 0) out)
    assert new.bus[new.bus[:, 0] == 4][0, 8] == pytest.approx(0.30, abs=1e-15)


@pytest.mark.parametrize("path", [V35, V36], ids=["v35", "v36"])
def test_five_bus_case_with_machines_equals_the_v33_one(path):
    new, old = load_psse(path, DYR, loads="raw"), load_psse(V33, DYR, loads="raw")
    assert new.replace(name=old.name).equals(old)
    pf_new, pf_old = solve_powerflow(new), solve_powerflow(old)
    np.testing.assert_array_equal(pf_new.vmag, pf_old.vmag)
    np.testing.assert_array_equal(pf_new.vang, pf_old.vang)


def test_generator_lines_are_named_by_their_own_file_line():
    # v36 adds the voltage droop control section before the generators
    assert [g.source.line for g in read_raw(V35).generators] == [32, 33, 34]
    assert [g.source.line for g in read_raw(V36).generators] == [36, 37, 38]


def test_ieee24_v35_with_switched_shunts_reads_as_its_v33():
    # v35 switched shunts carry an ID after the bus number (1 '1' and 6 '1': BINIT 120,
    # 100 Mvar)
    new, old = read_raw(DATA / "ieee24_v35.raw"), read_raw(DATA / "ieee24_v33.raw")
    _same_raw(new, old)
    bus = {int(r[0]): r for r in new.bus}
    np.testing.assert_allclose([bus[1][8], bus[6][8]], [1.2, 1.0], rtol=0, atol=1e-15)


def test_ieee14_v35_reads_as_its_v33_and_solves_to_the_raws_own_solution():
    new, old = read_raw(IEEE14_V35), read_raw(IEEE14_V33)
    _same_raw(new, old)
    case = load_psse(IEEE14_V35)
    assert case.replace(name="x").equals(load_psse(IEEE14_V33).replace(name="x"))
    pf = solve_powerflow(case, tol=1e-12)
    idx = case.bus_indices(new.solution[:, 0].astype(int))
    # the RAW's VM to 5 decimals and VA to 4 (degrees): the IEEE 14-bus solution
    assert np.max(np.abs(pf.vmag[idx] - new.solution[:, 1])) < 1e-5
    assert np.max(np.abs(np.degrees(pf.vang[idx]) - new.solution[:, 2])) < 2e-4


def test_double_quoted_strings_are_whole_from_v35_on():
    line = '    4,"SUB / 115KV  ", 115.0000,1'
    assert split_fields(line, double_quotes=True) == ["4", "SUB / 115KV  ", "115.0000", "1"]
    # v32-v34: single quotes only, as before
    assert split_fields(line) == ["4", '"SUB']
    assert split_fields("1,'A \"B\"',2", double_quotes=True) == ["1", 'A "B"', "2"]


def test_import_psse_reads_a_v35_file(tmp_path):
    out = tmp_path / "five.json"
    res = CliRunner().invoke(main, ["import-psse", str(V35), str(DYR), "-o", str(out)])
    assert res.exit_code == 0, res.output


# ------------------------------------------------------------------ malformed v35/v36


@pytest.mark.parametrize("src", [V35, V36], ids=["v35", "v36"])
def test_every_cut_before_the_last_section_is_refused_with_file_line(tmp_path, src):
    text = src.read_text()
    end = text.rindex("0 / END OF")
    for n in range(1, end, 53):
        with pytest.raises(CaseError, match=r"v35\.raw:\d+"):
            read_raw(_write(tmp_path, text[:n]))


def test_headings_alone_are_not_a_case_identification(tmp_path):
    text = "@!IC,SBASE,REV,XFRRAT,NXFRAT,BASFRQ\n0, 100.0, 35, 0, 1, 60.0\nTITLE\n"
    with pytest.raises(CaseError, match=r"v35\.raw:2 case identification: a RAW file starts"):
        read_raw(_write(tmp_path, text))


def test_a_version_after_36_is_refused(tmp_path):
    text = V35.read_text().replace("100.00, 35, 0, 1", "100.00, 37, 0, 1")
    with pytest.raises(CaseError, match=r"v35\.raw:2 case identification .* RAW version 37"):
        read_raw(_write(tmp_path, text))


def test_missing_system_wide_terminator_is_refused_at_the_first_bus(tmp_path):
    text = V35.read_text().replace("0 / END OF SYSTEM-WIDE DATA, BEGIN BUS DATA\n", "")
    with pytest.raises(
        CaseError,
        match=r"v35\.raw:15 system-wide data record: '1' where a record starts with its "
        r"keyword .*'0 / END OF SYSTEM-WIDE DATA' record is missing",
    ):
        read_raw(_write(tmp_path, text))


def test_switched_shunt_without_its_v35_id_is_refused(tmp_path):
    # a v34 record (no ID) in a v35 file: ST would be read from VSWHI
    text = V35.read_text().replace(
        "    4,'1 ',   1,  0,  1,1.05000,0.95000,     0,   0, 100.0,",
        "    4,   1,  0,  1,1.05000,0.95000,     0,   0, 100.0,",
    )
    with pytest.raises(
        CaseError, match=r"v35\.raw:89 switched shunt record: ST = '1.05000': not an integer"
    ):
        read_raw(_write(tmp_path, text))


def test_switched_shunt_id_used_twice_is_refused(tmp_path):
    text = V35.read_text().replace("    4,'2 ',   1,  0,  0,", "    4,'1 ',   1,  0,  0,")
    with pytest.raises(
        CaseError,
        match=r"v35\.raw:90 .*switched shunt at bus 4 '1' appears twice \(first at line 89\)",
    ):
        read_raw(_write(tmp_path, text))


def test_v36_generator_with_a_field_too_many_is_refused(tmp_path):
    text = V36.read_text().replace("'GEN_3_1", "0,'GEN_3_1")
    with pytest.raises(
        CaseError, match=r"v35\.raw:37 generator record: 33 field\(s\), the v36 layout has 16 to 32"
    ):
        read_raw(_write(tmp_path, text))


def test_distributed_generation_in_service_is_unsupported(tmp_path):
    # load 4 '1' carries DGENP 5 MW, DGENQ 1 Mvar: with DGENM 1 they are in service
    text = V35.read_text().replace(
        "5.000,     1.000,    0,'INDUSTRY", "5.000,     1.000,    1,'INDUSTRY"
    )
    raw = read_raw(_write(tmp_path, text))
    assert [str(u) for u in raw.unsupported] == [
        "v35.raw:25 load at bus 4 '1': distributed generation in service (DGENM 1, DGENP, DGENQ)"
    ]


def test_v36_voltage_droop_control_is_unsupported(tmp_path):
    text = V36.read_text().replace(
        "VLOW,   VHIGH\n",
        "VLOW,   VHIGH\n'VLTDRP_A', 1, 3, 10.0, -50.0, 100.0, 0.97, 1.03, 0.95, 1.05\n",
    )
    raw = read_raw(_write(tmp_path, text))
    assert [str(u) for u in raw.unsupported] == [
        "v35.raw:34 voltage droop control record: not modelled"
    ]


_SUBSTATIONS = """0 / END OF INDUCTION MACHINE DATA, BEGIN SUBSTATION DATA
    1,'STATION 1   ', 0.0, 0.0, 0.1
  / BEGIN SUBSTATION NODE DATA
    1,'NB1', 1, 1, 1.0, 0.0
    2,'NL1', 1, 1, 1.0, 0.0
0 / END OF SUBSTATION NODE DATA, BEGIN SUBSTATION SWITCHING DEVICE DATA
    1, 2,'1 ','SW-1', 2, 1, 1, 0.0001, 0.0, 0.0, 0.0
0 / END OF SUBSTATION SWITCHING DEVICE DATA, BEGIN SUBSTATION TERMINAL DATA
    1, 2,'B', 2,'1 '
0 / END OF SUBSTATION TERMINAL DATA
    3,'STATION 3   ', 0.0, 0.0, 0.1
0 / END OF SUBSTATION NODE DATA, BEGIN SUBSTATION SWITCHING DEVICE DATA
0 / END OF SUBSTATION SWITCHING DEVICE DATA, BEGIN SUBSTATION TERMINAL DATA
0 / END OF SUBSTATION TERMINAL DATA
"""


def test_node_breaker_substations_are_unsupported_and_the_rest_is_read(tmp_path):
    # a substation record is followed by its node, switching device and terminal data,
    # each ending with '0 /' (the case's last section: read whole, not as data after it)
    text = V35.read_text().replace(
        "0 / END OF INDUCTION MACHINE DATA, BEGIN SUBSTATION DATA\n", _SUBSTATIONS
    )
    raw = read_raw(_write(tmp_path, text))
    assert [str(u) for u in raw.unsupported] == [
        "v35.raw:100 substation 1 'STATION 1': node-breaker data (4 node, switching "
        "device and terminal records)"
    ]
    np.testing.assert_array_equal(raw.bus, read_raw(V33).bus)
    cut = text[: text.index("0 / END OF SUBSTATION TERMINAL DATA\n    3,")]
    with pytest.raises(CaseError, match=r"v35\.raw:100 substation record: file ends inside"):
        read_raw(_write(tmp_path, cut))


#: a three-winding transformer 1-3-4 in the v33 layout and in the v35 one (12 ratings per
#: winding, NOD, CNXA; VECGRP and ZCOD on line 1), the same data
_THREE_WINDING_V33 = (
    "    1,     3,     4,'T ',1,2,1, 0.0, 0.0,2,'T3          ',1,   1,1.0000\n"
    " 0.002, 0.10, 200.0, 0.004, 0.05, 50.0, 0.003, 0.08, 80.0, 0.99, -3.0\n"
    "1.02, 0.0, 5.0, 0.0, 0.0, 0.0, 0, 0, 1.1, 0.9, 1.1, 0.9, 33, 0, 0.0, 0.0, 0.0\n"
    "0.98, 0.0, 0.0, 0.0, 0.0, 0.0, 0, 0, 1.1, 0.9, 1.1, 0.9, 33, 0, 0.0, 0.0, 0.0\n"
    "1.00, 0.0, -2.0, 0.0, 0.0, 0.0, 0, 0, 1.1, 0.9, 1.1, 0.9, 33, 0, 0.0, 0.0, 0.0\n"
)
_RATINGS = ", 0.0" * 12
_THREE_WINDING_V35 = (
    "    1,     3,     4,'T ',1,2,1, 0.0, 0.0,2,'T3          ',1,   1,1.0000,   0,1.0000,"
    "   0,1.0000,   0,1.0000,'YN0yn0d1    ', 0\n"
    " 0.002, 0.10, 200.0, 0.004, 0.05, 50.0, 0.003, 0.08, 80.0, 0.99, -3.0\n"
    f"1.02, 0.0, 5.0{_RATINGS}, 0, 0, 0, 1.1, 0.9, 1.1, 0.9, 33, 0, 0.0, 0.0, 0.0\n"
    f"0.98, 0.0, 0.0{_RATINGS}, 0, 0, 0, 1.1, 0.9, 1.1, 0.9, 33, 0, 0.0, 0.0, 0.0\n"
    f"1.00, 0.0, -2.0{_RATINGS}, 0, 0, 0, 1.1, 0.9, 1.1, 0.9, 33, 0, 0.0, 0.0, 0.0\n"
)


def test_three_winding_transformer_reads_as_in_v33(tmp_path):
    end = "0 / END OF TRANSFORMER DATA"
    old = read_raw(
        _write(tmp_path, V33.read_text().replace(end, _THREE_WINDING_V33 + end), "a.raw")
    )
    new = read_raw(_write(tmp_path, V35.read_text().replace(end, _THREE_WINDING_V35 + end)))
    _same_raw(new, old)
    assert new.line.shape[0] == old.line.shape[0] == 7  # 2 lines, 2 transformers, 3 windings


def test_v36_branch_with_the_field_after_stat_and_four_owners(tmp_path):
    # PSS/E Xplore 36.1 writes one field more after STAT than its heading (35 with four
    # owners); the fields read (R, X, B, GI..BJ, STAT) come before it
    text = V36.read_text().replace(
        " 0.00000,1,1, 10.00,   1,1.0000\n",
        " 0.00000,1,0,1, 10.00,   1,0.5000,   2,0.2000,   3,0.2000,   4,0.1000\n",
        1,
    )
    assert text != V36.read_text()
    _same_raw(read_raw(_write(tmp_path, text)), read_raw(V33))


def test_v36_branch_fields_are_read_from_their_v36_columns(tmp_path):
    """A v36 branch record with every field it reads distinct (12 ratings 101 to 112
    between NAME and GI; GI, BI, GJ, BJ 0.01 to 0.04; MET 2 after STAT): R, X, B and the
    line-end shunts come from the columns of PSS/E 36's heading, as in v35, none from a
    rating's or from the fields after STAT."""
    old = (
        "0.10000,'LINE 1-2 C                              ', 100.00, 100.00, 100.00,"
        + "   0.00," * 9
        + " 0.00000, 0.05000, 0.00000, 0.05000,1,1, 10.00,   1,1.0000"
    )
    new = (
        "0.10000,'LINE 1-2 C                              ',"
        + ",".join(f" {r}.00" for r in range(101, 113))
        + ", 0.01000, 0.02000, 0.03000, 0.04000,1,2, 10.00,   1,1.0000"
    )
    text = V36.read_text()
    assert text.count(old) == 1
    line = read_raw(_write(tmp_path, text.replace(old, new))).line
    np.testing.assert_allclose(line[1, :5], [1, 2, 0.02, 0.2, 0.1])
    np.testing.assert_allclose(line[1, 10:14], [0.01, 0.02, 0.03, 0.04])


@pytest.mark.parametrize(
    "tail, field",
    [
        (" 0.00000,1,1, 1O.00,   1,1.0000\n", "field 26 (after STAT) = '1O.00'"),
        (
            " 0.00000,1,0,1, 10.00,   1,0.5000,   2,0.2000,   3,0.2000,   4,0.1x00\n",
            "field 35 (after STAT) = '0.1x00'",
        ),
    ],
    ids=["heading layout", "field more after STAT"],
)
def test_v36_branch_fields_after_stat_must_be_numbers(tmp_path, tail, field):
    """Every field after a v36 branch's STAT (MET, LEN, the owners, or Xplore 36.1's field
    more first) is a number in PSS/E's layouts: text there is refused, named by position."""
    text = V36.read_text().replace(" 0.00000,1,1, 10.00,   1,1.0000\n", tail, 1)
    assert text != V36.read_text()
    with pytest.raises(CaseError, match=rf"v35\.raw:44 branch record: {re.escape(field)}"):
        read_raw(_write(tmp_path, text))
