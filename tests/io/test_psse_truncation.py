"""Issue 15: PSS/E RAW and DYR files that end early or hold records that do not parse are
refused with file:line, never imported as a smaller case."""

from pathlib import Path

import numpy as np
import pytest

from stabctl.errors import CaseError
from stabctl.io.dyr import read_dyr
from stabctl.io.psse import load_psse
from stabctl.io.psse_raw import read_raw

DATA = Path(__file__).parents[1] / "data" / "psse"
V33, V34, DYR = DATA / "five_bus_v33.raw", DATA / "five_bus_v34.raw", DATA / "five_bus.dyr"


def _write(tmp_path, text, name="cut.raw"):
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.mark.parametrize("src", [V33, V34], ids=["v33", "v34"])
def test_every_cut_before_the_last_section_is_refused_with_file_line(tmp_path, src):
    text = src.read_text()
    full = read_raw(src)
    # the last section terminator: a cut after it (only 'Q' missing) is the whole case
    end = text.rindex("0 / END OF")
    for n in range(len(text.splitlines()[0]) + 1, end, 7):
        path = _write(tmp_path, text[:n])
        with pytest.raises(CaseError, match=r"cut\.raw:\d+"):
            read_raw(path)
    whole = read_raw(_write(tmp_path, text[: text.rindex("Q")]))
    assert whole.line.shape == full.line.shape


def test_cut_in_the_bus_data_names_file_line_not_a_missing_matrix(tmp_path):
    text = V33.read_text()
    cut = text[: text.index("    3,'GEN")]
    with pytest.raises(
        CaseError,
        match=r"cut\.raw:5: the file ends in the bus data, without "
        r"its '0 /' terminator and the 'Q' record",
    ):
        load_psse(_write(tmp_path, cut), DYR)


def test_cut_after_the_generators_is_a_raw_error_not_unsupported_dyr_records(tmp_path):
    text = V33.read_text()
    cut = text[: text.index("0 / END OF GENERATOR DATA")]
    with pytest.raises(CaseError) as err:
        load_psse(_write(tmp_path, cut), DYR)
    assert "cut.raw:20: the file ends in the generator data" in str(err.value)
    assert "unsupported" not in str(err.value)


def test_half_read_last_line_is_refused_not_read_with_a_wrong_value(tmp_path):
    # the case: a branch line cut inside X (0.22001 read as 2.2001 and B = 0)
    text = V33.read_text()
    line = "    1,      2,'2 ', 1.00000E-2, 1.0"
    cut = text[: text.index(line) + len(line)]
    with pytest.raises(CaseError, match=r"cut\.raw:23 branch record: 5 field\(s\)"):
        read_raw(_write(tmp_path, cut))


def test_a_missing_section_terminator_is_refused(tmp_path):
    text = V33.read_text().replace("0 / END OF LOAD DATA, BEGIN FIXED SHUNT DATA\n", "", 1)
    with pytest.raises(CaseError, match=r"cut\.raw:\d+"):
        read_raw(_write(tmp_path, text))


def test_q_ends_the_data_after_any_section(tmp_path):
    # PSS/E POM: 'Q' ends the data wherever a record may start; the sections after it are
    # empty (issue 50: CSVGN1's and PSS2A's RAW files end with Q after the transformers)
    text = V33.read_text()
    full = read_raw(V33)
    early_q = text.split("0 / END OF BRANCH DATA")[0] + "0 / END OF BRANCH DATA\nQ\n"
    early = read_raw(_write(tmp_path, early_q))
    assert early.line.shape[0] == len(full.line) - 2  # the two transformers of the file
    assert np.array_equal(early.bus[:, 0], full.bus[:, 0])
    cut = read_raw(_write(tmp_path, text[: text.index("0 / END OF TRANSFORMER DATA")] + "Q\n"))
    assert cut.line.shape == full.line.shape


@pytest.mark.parametrize(
    "marker,what",
    [
        ("    1,      2,'1 ', 1.00000E-2", r"branch 1-2 '1' appears twice \(first at line 22\)"),
        ("    3,'1 ',   150.000", r"generator at bus 3 '1' appears twice \(first at line 18\)"),
        ("    4,'1 ',1,   1,   1,    40.000", r"load at bus 4 '1' appears twice"),
    ],
)
def test_duplicated_record_is_refused(tmp_path, marker, what):
    text = V33.read_text()
    start = text.index(marker)
    line = text[start : text.index("\n", start) + 1]
    path = _write(tmp_path, text.replace(line, line + line, 1))
    with pytest.raises(CaseError, match=what):
        read_raw(path)


@pytest.mark.parametrize("token", ["nan", "inf", "-Infinity"])
def test_non_finite_raw_field_is_refused(tmp_path, token):
    text = V33.read_text().replace(
        "1.00000E-2, 1.00000E-1,   0.20000", f"1.00000E-2, {token},   0.20000", 1
    )
    with pytest.raises(CaseError, match=r"cut\.raw:22 branch record: X = .* not a finite"):
        read_raw(_write(tmp_path, text))


def test_record_of_another_section_read_as_this_one_is_refused(tmp_path):
    # without the load terminator the fixed shunt record would be read as a load
    text = V33.read_text().replace("0 / END OF LOAD DATA, BEGIN FIXED SHUNT DATA\n", "", 1)
    with pytest.raises(CaseError, match=r"cut\.raw:14 load record: 5 field\(s\)"):
        read_raw(_write(tmp_path, text))


@pytest.mark.parametrize("token", ["nan", "inf"])
def test_non_finite_dyr_parameter_is_refused(tmp_path, token):
    text = DYR.read_text().replace("8.0  0.03  0.4", f"8.0  {token}  0.4", 1)
    path = _write(tmp_path, text, "bad.dyr")
    with pytest.raises(
        CaseError,
        match=rf"bad\.dyr:1 GENROU \(bus 1, id 1\): T''do = {token}: not a finite number",
    ):
        read_dyr(path)


def test_dyr_cut_inside_a_record_is_refused(tmp_path):
    text = DYR.read_text()
    path = _write(
        tmp_path,
        text[: text.index("1.8  1.7  0.3  0.55  0.25  0.06  0.0  0.0 /  machine 3")],
        "cut.dyr",
    )
    with pytest.raises(CaseError, match=r"cut\.dyr:3: record not terminated by '/'"):
        load_psse(V33, path)


@pytest.mark.parametrize(
    "text, what",
    [
        ("", "is empty"),
        ("\n  \n", "is empty"),
        (" / a comment\n", "holds no record, only comments"),
    ],
    ids=["empty", "blank lines", "comments"],
)
def test_a_dyr_file_without_any_record_is_refused_by_name(tmp_path, text, what):
    """An empty DYR file read as no records: import-psse listed every generator as
    without a machine model, never naming the file that gave none."""
    path = _write(tmp_path, text, "empty.dyr")
    with pytest.raises(CaseError, match=rf"^empty\.dyr: the DYR file {what}: no machine"):
        read_dyr(path)
    with pytest.raises(CaseError, match=rf"^empty\.dyr: the DYR file {what}"):
        load_psse(V33, path, unmodelled="net")
