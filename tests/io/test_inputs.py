"""Input files as a user gives them (stabctl.io.inputs): regular files of bounded size and
strict CSV tables, on the fault list (`read_faults`, `read_requirements`) and the site
costs (`read_site_costs`); each refusal names file:line and the field."""

import json
import os

import pytest
from click.testing import CliRunner

from stabctl.cli import main
from stabctl.errors import InputError
from stabctl.io.inputs import input_file, plain_float, read_csv
from stabctl.placement.requirements import read_requirements, read_site_costs
from stabctl.stability.cct import LineFault, read_faults


def _csv(tmp_path, text, name="f.csv", encoding="utf-8"):
    path = tmp_path / name
    path.write_bytes(text.encode(encoding))
    return path


@pytest.mark.parametrize(
    "text,needle",
    [
        # a row cut before far_bus ran as a bus fault (CCT 0.238 s instead of 0.157 s)
        ("bus,far_bus,t_fault\n3,101,1.0\n3\n", r"f\.csv:3: 1 field\(s\), the header has 3"),
        ("bus,far_bus\n3,101,1.0\n", r"f\.csv:2: 3 field\(s\), the header has 2"),
        ("bus,far_bus,bus\n3,101,4\n", r"f\.csv:1: column\(s\) 'bus' twice"),
        ("bus,far_bus,t_falt\n3,101,1\n", r"f\.csv:1: column\(s\) 't_falt' unknown"),
        ("bus,t_fault\n3,1\n", r"f\.csv:1: column\(s\) 'far_bus' missing"),
        ("bus,far_bus,t_fault\n3,101,nan\n", r"f\.csv:2: t_fault nan is outside \[0, 1000\]"),
        ("bus,far_bus,t_fault\n3,101,inf\n", r"f\.csv:2: t_fault inf is outside"),
        ("bus,far_bus,t_fault\n3,101,1e300\n", r"f\.csv:2: t_fault 1e300 is outside"),
        ("bus,far_bus,t_fault\n3,101,1001\n", r"f\.csv:2: t_fault 1001 is outside"),
        ("bus,far_bus,circuit\n3,101,1.5\n", r"f\.csv:2: circuit 1.5 is not an integer"),
        # a bus number written as a measured value (accepted before as bus 3)
        ("bus,far_bus\n3.0,101\n", r"f\.csv:2: bus 3.0 is not an integer \(write it as digits\)"),
        ("bus,far_bus\n3,1.01e2\n", r"f\.csv:2: far_bus 1.01e2 is not an integer"),
        ("bus,far_bus\n0,101\n", r"f\.csv:2: bus 0 is outside"),
        # a bus fault's row with a circuit ran, recorded as that circuit (cct refuses it)
        ("bus,far_bus,circuit\n3,,2\n", r"f\.csv:2: circuit 2 given for a bus fault"),
        ("bus,far_bus\n", r"needs a header \(bus,far_bus\[,t_fault\]"),
        # a line from a bus to itself: "line: no branch between bus 3 and bus 3", no row
        ("bus,far_bus\n3,101\n3,3\n", r"f\.csv:3: far_bus 3 is the fault's bus: a line joins"),
        ("bus,far_bus\n3,003\n", r"f\.csv:2: far_bus 003 is the fault's bus"),
    ],
)
def test_fault_list_refusals_name_file_line_and_field(tmp_path, text, needle):
    with pytest.raises(InputError, match=needle):
        read_faults(_csv(tmp_path, text))


def test_a_fault_list_with_blank_lines_a_byte_order_mark_and_spaces_reads(tmp_path):
    path = _csv(tmp_path, "\ufeffbus, far_bus ,t_fault\n\n 3 ,101, 0.5\n13,,\n\n")
    assert read_faults(path) == [LineFault(3, 101, 0.5), LineFault(13, None, 1.0)]


def test_latin1_and_over_long_fields_are_refused_without_a_traceback(tmp_path):
    with pytest.raises(InputError, match=r"not UTF-8 text .*save it as UTF-8"):
        read_faults(_csv(tmp_path, "bus,far_bus\n3,101 \u00e9\n", encoding="latin-1"))
    long = _csv(tmp_path, 'bus,far_bus\n3,"' + "1" * 200_000 + '"\n', name="long.csv")
    with pytest.raises(InputError, match=r"long\.csv:2: field larger than field limit"):
        read_faults(long)


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="/dev/zero")
def test_devices_pipes_and_directories_are_refused_before_reading(tmp_path):
    link = tmp_path / "zero.csv"
    link.symlink_to("/dev/zero")
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)
    for path in ("/dev/zero", link, fifo, tmp_path):
        with pytest.raises(InputError, match="not a regular file"):
            input_file(path, "fault list")
    res = CliRunner().invoke(
        main, ["sweep-cct", "kundur", "--faults", str(link), "--out", str(tmp_path / "o.jsonl")]
    )
    assert res.exit_code == 2 and "not a regular file" in res.stderr
    assert not (tmp_path / "o.jsonl").exists()


@pytest.mark.skipif(not os.path.exists("/dev/zero"), reason="/dev/zero")
def test_import_andes_names_a_pipe_or_device_as_such(tmp_path):
    """`import-andes` of an existing FIFO or /dev/urandom said "case file not found", where
    every other reader says what the path is: named as not a regular file; a DYR beside
    a RAW file likewise; a missing file by the system's words."""
    pytest.importorskip("andes")
    fifo = tmp_path / "fifo.xlsx"
    os.mkfifo(fifo)
    raw = tmp_path / "c.raw"
    raw.write_text("0, 100.0\n")
    out = ["-o", str(tmp_path / "o.json")]
    for args, needle in (
        ([str(fifo)], f"case file {fifo}: not a regular file"),
        (["/dev/urandom"], "case file /dev/urandom: not a regular file"),
        ([str(raw), "/dev/zero"], "DYR file /dev/zero: not a regular file"),
        ([str(tmp_path / "none.xlsx")], "none.xlsx: No such file or directory"),
    ):
        res = CliRunner().invoke(main, ["import-andes", *args, *out])
        assert res.exit_code == 2 and needle in res.stderr, res.output
    assert not (tmp_path / "o.json").exists()


def test_requirement_columns_misspelt_are_refused_not_ignored(tmp_path):
    """A misspelt override column was ignored and the plan reported verified against the
    global requirement."""
    path = _csv(tmp_path, "bus,far_bus,required_clearing_cycle\n3,101,6\n")
    with pytest.raises(InputError, match=r"'required_clearing_cycle' unknown"):
        read_requirements(path)
    path = _csv(tmp_path, "bus,far_bus,target_cct_s\n3,101,0.3\n3,101,0.2\n")
    with pytest.raises(InputError, match=r"f\.csv:3: fault 3-101 listed twice"):
        read_requirements(path)


@pytest.mark.parametrize(
    "text,needle",
    [
        ("machine,cost_mv\n1,5\n", r"'cost_mv' unknown"),
        ("machine\n1\n", "no cost column"),
        ("machine,cost_mw\n0,5\n", r"c\.csv:2: machine 0 is outside \[1, 4\]"),
        ("machine,cost_mw\n99,5\n", r"machine 99 is outside \[1, 4\]"),
        ("machine,cost_mw\n2,5\n2,6\n", r"c\.csv:3: machine 2 listed twice"),
        ("machine,cost_mw\n2,-5\n", r"cost_mw -5 is outside"),
        # 1e308 overflowed the program's scaling (numpy's warnings, exit 0)
        ("machine,cost_site\n2,1e308\n", r"c\.csv:2: cost_site 1e308 is outside \[0, 1e\+15\]"),
    ],
)
def test_site_costs_refusals(tmp_path, text, needle):
    with pytest.raises(InputError, match=needle):
        read_site_costs(_csv(tmp_path, text, name="c.csv"), 4)


def test_site_costs_keep_the_costs_given_per_machine(tmp_path):
    path = _csv(tmp_path, "machine,cost_mw,cost_site\n1,5,\n3,,7\n", name="c.csv")
    assert read_site_costs(path, 4) == {1: {"per_mw": 5.0}, 3: {"per_site": 7.0}}


def test_read_csv_rows_carry_their_file_lines(tmp_path):
    rows = read_csv(_csv(tmp_path, "a,b\n\n1,2\n3,4\n"), "table", ("a",), ("b",))
    assert [(r.line, r.values) for r in rows] == [
        (3, {"a": "1", "b": "2"}),
        (4, {"a": "3", "b": "4"}),
    ]


def test_screening_records_must_bracket_a_fault(tmp_path):
    from stabctl.placement.requirements import screening_brackets

    other = tmp_path / "other.jsonl"  # a record of another kind of job: no CCT search's
    other.write_text('{"key": "k", "status": "ok", "inputs": {}, "result": {"y": 1}}\n')
    with pytest.raises(InputError, match=r"line 1: not a whole sweep record \(result\.cct_s"):
        screening_brackets(other, "kundur", "any")
    cct = {"cct_s": 0.1, "t_stable_s": 0.1, "t_unstable_s": 0.101, "cct_cycles": 6.0}
    cct.update(n_simulations=9, separated_machines=[1])
    stored = {"key": "k", "status": "ok", "inputs": {"esd_pct": 5.0}, "result": cct}
    other.write_text(json.dumps(stored) + "\n")  # a search's, with storage
    with pytest.raises(InputError, match="no fault bracketed without storage"):
        screening_brackets(other, "kundur", "any")
    bad = tmp_path / "bad.jsonl"  # a search's record without its fault
    bad.write_text(json.dumps({"key": "k", "status": "ok", "inputs": {}, "result": cct}) + "\n")
    with pytest.raises(InputError, match=r"record 'k' is not a screening record \(KeyError"):
        screening_brackets(bad, "kundur", "any")
    with pytest.raises(InputError, match="not a regular file"):
        screening_brackets(tmp_path, "kundur", "any")


def test_outputs_that_are_devices_and_write_failures_end_in_one_error_line(tmp_path, monkeypatch):
    """--out pointing at a device (or a link to /dev/full) is refused before any work; a
    write the system refuses mid-run (a disk full) is one error line, exit 2."""
    import errno

    link = tmp_path / "full.jsonl"
    link.symlink_to("/dev/full")
    res = CliRunner().invoke(
        main, ["sweep-cct", "kundur", "--faults", "DEFAULT", "--out", str(link)]
    )
    assert res.exit_code == 2 and "not a regular file" in res.stderr, res.stderr

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(tmp_path / "o.jsonl"))

    monkeypatch.setattr("stabctl.parallel.run_sweep", full)
    res = CliRunner().invoke(
        main, ["sweep-cct", "kundur", "--faults", "DEFAULT", "--out", str(tmp_path / "o.jsonl")]
    )
    assert res.exit_code == 2, res.output
    assert res.stderr.strip().splitlines() == [
        f"error: {tmp_path / 'o.jsonl'}: No space left on device"
    ]


def _disk_full(*args, **kwargs):
    import errno

    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))  # as write(2): no file named


def test_a_full_disk_as_a_sweep_takes_its_lock_names_the_output(tmp_path, monkeypatch):
    """screen --out on a full disk said only "error: No space left on device": the pid
    written in the output's lock file failed first, naming no file."""
    monkeypatch.setattr("stabctl.locking.os.pwrite", _disk_full)
    out = tmp_path / "sc.jsonl"
    res = CliRunner().invoke(main, ["screen", "kundur", "--workers", "1", "--out", str(out)])
    assert res.exit_code == 2, res.output
    said = [x for x in res.stderr.splitlines() if not x.startswith(("stabctl: ", "  ("))]
    assert said == [f"error: {out}: No space left on device"]  # (a compile notice aside)
    assert not out.exists() and os.listdir(tmp_path) == []


@pytest.mark.parametrize("where", ["lock", "figure"])
def test_a_full_disk_in_paper_names_its_directory_and_leaves_none(tmp_path, monkeypatch, where):
    """paper --out-dir NEW on a full disk said only "error: No space left on device" and
    left NEW (with an empty work directory) behind; the directory is named, and those the
    run created are removed again when they hold nothing."""
    target = (
        "stabctl.locking.os.pwrite" if where == "lock" else "stabctl.plotting.figures.save_figure"
    )
    monkeypatch.setattr(target, _disk_full)
    out = tmp_path / "pap"
    res = CliRunner().invoke(main, ["paper", "--only", "analytic", "--out-dir", str(out)])
    assert res.exit_code == 2, res.output
    assert res.stderr.strip().splitlines()[-1:] == [f"error: {out}: No space left on device"]
    assert os.listdir(tmp_path) == []


def test_a_plan_whose_file_cannot_be_written_is_still_shown(tmp_path, monkeypatch):
    """place --out on a full disk lost the whole run: the plan is printed first."""
    import errno

    def full(path, write, **kw):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))

    monkeypatch.setattr("stabctl.parallel.atomic_write", full)
    out = tmp_path / "plan.json"
    res = CliRunner().invoke(
        main,
        ["place", "kundur", "--faults", "DEFAULT", "--target-cct-gain", "5", "--workers", "1"]
        + ["--json", "--out", str(out)],
    )
    assert res.exit_code == 2 and "No space left on device" in res.stderr
    assert '"verified": true' in res.stdout and not out.exists()


def test_plain_float_reads_ascii_numbers_only_and_minus_zero_as_zero():
    """float() reads 1_0 as 10 and a fullwidth 5 as 5; every hand-parsed number of the
    readers and options goes through plain_float, which refuses both, reads Fortran's D
    exponent when asked, and gives -0 as 0 (a fault 'at -0 s' was printed)."""
    for text in ("1_0", "\uff15", "\u0665", "1.5D0"):
        with pytest.raises(ValueError):
            plain_float(text)
    assert plain_float("1.5D0", fortran=True) == 1.5
    assert str(plain_float("-0")) == "0.0" and str(plain_float("-0.0e0")) == "0.0"
    assert plain_float("-2.5e-1") == -0.25


def test_a_table_number_below_the_smallest_float_is_refused_as_written(tmp_path):
    """A fault list's 1e-400 was read as 0 and refused as 'gain=0.0 %' (a t_fault of
    1e-400 ran at 0 s): it is refused as written, naming file:line and column."""
    path = _csv(tmp_path, "bus,far_bus,target_cct_gain\n3,101,1e-400\n", name="g.csv")
    with pytest.raises(InputError, match=r"g\.csv:2: target_cct_gain 1e-400 is too small"):
        read_requirements(path)
    path = _csv(tmp_path, "bus,far_bus,t_fault\n3,101,-2E-999\n", name="t.csv")
    with pytest.raises(InputError, match=r"t\.csv:2: t_fault -2E-999 is too small"):
        read_faults(path)


def test_a_header_of_more_columns_than_the_table_has_is_refused_with_its_count(tmp_path):
    """Finding twice-named columns was quadratic in the header's columns (200 000 took
    most of a minute): a header of more columns than the table knows is refused first."""
    path = _csv(tmp_path, "bus,far_bus" + ",x" * 5000 + "\n3,101\n", name="wide.csv")
    with pytest.raises(
        InputError, match=r"fault list wide\.csv:1: a header of 5002 columns, more than the 7"
    ):
        read_faults(path)
    quoted = _csv(tmp_path, "bus,far_bus" + ',"x"' * 5000 + "\n3,101\n", name="q.csv")
    with pytest.raises(InputError, match=r"q\.csv:1: a header of 5002 columns, more than the 7"):
        read_faults(quoted)


def test_a_line_longer_than_a_row_can_be_is_refused_by_its_length(tmp_path):
    """The csv module split a whole line into fields, gigabytes for a line of millions of
    quoted fields; a line longer than the table's columns at the csv field limit each is
    refused before it is split."""
    import csv

    cap = 7 * (2 * csv.field_size_limit() + 3)
    path = _csv(tmp_path, "bus,far_bus" + ',"xy"' * (cap // 5 + 1) + "\n3,101\n", name="l.csv")
    with pytest.raises(InputError, match=rf"l\.csv:1: a line of \d+ characters.*at most {cap}"):
        read_faults(path)
    rows = _csv(tmp_path, 'bus,far_bus\n3,"' + "1" * (cap + 5) + '"\n', name="r.csv")
    with pytest.raises(InputError, match=rf"r\.csv:2: a line of {cap + 10} characters"):
        read_faults(rows)


def test_a_fault_list_stops_at_its_first_error(tmp_path):
    """The whole file was read into rows before the first was checked: a fault listed twice
    on line 3 was reported only after the rest of the file (here, after 100 000 more
    rows, a line that is not UTF-8)."""
    path = tmp_path / "f.csv"
    path.write_bytes(b"bus,far_bus\n3,101\n3,101\n" + b"13,\n" * 100_000 + b"13,\xe9\n")
    with pytest.raises(InputError, match=r"f\.csv:3: fault 3-101 listed twice"):
        read_faults(path)


def test_a_fault_list_keeps_a_few_hundred_bytes_a_fault(tmp_path):
    """Reading a fault list took about 70 times the file's size in memory (every row's
    fields kept); now only the faults and their lines are kept."""
    import tracemalloc

    n = 20_000
    path = _csv(tmp_path, "bus,far_bus\n" + "".join(f"{i + 1},{i + 2}\n" for i in range(n)))
    tracemalloc.start()
    try:
        faults = read_faults(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert len(faults) == n
    assert peak / n < 400, f"{peak / n:.0f} bytes a fault"
