"""Ninth reliability round (round 34, part B): input bounds, xlsx and npz containers, every
reader's odd files, records files changed mid-sweep, --allow, servers, the .m reader's
memory.

ANDES's kundur_full.xlsx changed one part at a time (1.2 million rows written plainly, with
a namespace prefix or in a sheet part outside xl/worksheets/; one row numbered 30 000 000;
a 1.5 GB shared-strings part; an external entity, a billion laughs; a dangling external
link beside a machine with M = 0), npz files for SimulationResult.from_npz (a pickled
array, an array it does not write, a t.npy that unpacks to 2 GiB), a records file deleted
or replaced while sweep-cct writes it, every reader given a NUL byte, UTF-16, bad UTF-8,
an empty file, a directory, a FIFO and links to /proc/self/pagemap and /proc/self/mem, a
RAW file with CRLF line ends, --allow spellings that are no IP address, a PMU server
crowded by silent, greedy and lying peers, and a 60 MB .m file under a 2 GB address space.

Contract: each probe runs `stabctl` commands (or python -c with the API) in fresh processes
(the package of this repository first on PYTHONPATH), the heavy ones under a timeout and,
where memory is the point, an address-space limit (RLIMIT_AS, as ``ulimit -v``), and states
what a careful tool does: a refused input ends with exit status 2 and an ``error:`` line,
no traceback, within seconds and within the limit (the API: an InputError naming what);
a sweep whose records file is deleted or replaced says so and keeps its records; a server
gives a real client its whole recording whoever else is connected, and exits 0.  The round
found X1-X4, X7, N1-N3, J1, J2 and M1 short; they are fixed and the probes are now their
regression checks.

    python benchmarks/reliability_probes_9.py [-k SUBSTRING] [ID ...]

ID: a probe's name or its prefix before the first ``_`` (``X4``, ``R1``); S1 reports S2
too (the server's exit after its clients left).  One line per probe (name, ok or SHORT,
why), then the counts.  Needs Linux (/proc, FIFOs, RLIMIT_AS) and the ``andes`` package
(its case files).  NUMBA_CACHE_DIR is the caller's (numba's default when unset); `stabctl
compile` is run first (seconds with a warm cache, about a minute cold).  The work directory
is a new temporary directory, removed at the end unless KEEP is set.  About 6 minutes on
two cores with a warm kernel cache.  Exit status 1 if any probe is short.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import time
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]  # the package under test
STABCTL = [sys.executable, "-m", "stabctl"]
ENV = dict(
    os.environ,
    PYTHONPATH=os.pathsep.join([str(ROOT), *filter(None, [os.environ.get("PYTHONPATH")])]),
)
ENV.pop("PYTHONWARNINGS", None)
WORK = Path(tempfile.mkdtemp(prefix="stabctl-probes-9."))
RESULTS: list[tuple[str, bool, str]] = []
PROBES: list = []


def probe(fn):
    PROBES.append(fn)
    return fn


def _limits(vmem_kb):
    """preexec_fn: default signal dispositions, the address space at vmem_kb KiB (or not)."""

    def pre():
        for s in (signal.SIGINT, signal.SIGHUP, signal.SIGTERM, signal.SIGQUIT):
            signal.signal(s, signal.SIG_DFL)
        if vmem_kb:
            resource.setrlimit(resource.RLIMIT_AS, (vmem_kb * 1024, vmem_kb * 1024))

    return pre


def run(args, cwd, timeout=120, vmem_kb=None):
    """(rc, stdout, stderr, seconds) of `stabctl args` in cwd; rc 124 on timeout."""
    t0 = time.monotonic()
    p = subprocess.Popen(
        [*STABCTL, *map(str, args)],
        cwd=cwd,
        env=ENV,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        preexec_fn=_limits(vmem_kb),
        start_new_session=True,
    )
    try:
        out, err = p.communicate(timeout=timeout)
        rc = p.returncode
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        out, err = p.communicate()
        rc = 124
    return rc, out.decode(errors="replace"), err.decode(errors="replace"), time.monotonic() - t0


def pyrun(code, cwd, timeout=120, vmem_kb=None):
    """(rc, stdout + stderr) of python -c code; rc 124 on timeout."""
    p = subprocess.Popen(
        [sys.executable, "-c", code],
        cwd=cwd,
        env=ENV,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        preexec_fn=_limits(vmem_kb),
        start_new_session=True,
    )
    try:
        out, _ = p.communicate(timeout=timeout)
        rc = p.returncode
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        out, _ = p.communicate()
        rc = 124
    return rc, out.decode(errors="replace")


def report(pid, ok, why):
    RESULTS.append((pid, ok, why))
    print(f"{pid:<30} {'ok   ' if ok else 'SHORT'} {why}", flush=True)


def clean_error(rc, out, err):
    """The contract's shape of a refusal: exit 2, an `error:` line, no traceback."""
    text = out + err
    return rc == 2 and "error:" in text and "Traceback" not in text


def last(text, n=220):
    lines = [ln for ln in text.strip().splitlines() if ln.strip()]
    return (lines[-1] if lines else "")[:n]


def workdir(name) -> Path:
    d = WORK / name
    d.mkdir()
    return d


def andes_cases() -> Path:
    import andes  # only to find ANDES's case files

    return Path(andes.__file__).parent / "cases"


# ---------------------------------------------------------------- xlsx helpers


def xlsx_copy(src, out, changes=None, stream=None, rename=None):
    """Copy xlsx `src` to `out`: changes {part: fn(bytes) -> bytes}; stream {part: fn(bytes)
    -> iterator of chunks} (zip64 streamed); rename {old part: new part} (rels and content
    types follow)."""
    changes, stream, rename = changes or {}, stream or {}, rename or {}
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as zo:
        for i in zin.infolist():
            data = zin.read(i.filename)
            name = rename.get(i.filename, i.filename)
            if i.filename in stream:
                with zo.open(name, "w", force_zip64=True) as f:
                    for chunk in stream[i.filename](data):
                        f.write(chunk)
                continue
            if i.filename in changes:
                data = changes[i.filename](data)
            for old, new in rename.items():
                o, n = old.removeprefix("xl/").encode(), new.removeprefix("xl/").encode()
                if i.filename in ("xl/_rels/workbook.xml.rels", "[Content_Types].xml"):
                    data = data.replace(o, n)
            zo.writestr(name, data)


MAIN = "http://schemas.openxmlformats.org/spreadsheetml/2006/main"
KUNDUR_XLSX = ("kundur", "kundur_full.xlsx")
AREA = "xl/worksheets/sheet6.xml"  # the Area sheet (rId6) of kundur_full.xlsx


def kundur_xlsx() -> Path:
    return andes_cases().joinpath(*KUNDUR_XLSX)


def area_rows(n, p=""):
    """An Area sheet of n rows (uid, idx, u), its tags with prefix p ('' or 'x:')."""
    ns = f'xmlns:x="{MAIN}"' if p else f'xmlns="{MAIN}"'
    yield (
        f'<?xml version="1.0" encoding="UTF-8" standalone="yes"?>\n<{p}worksheet {ns}>'
        f'<{p}sheetData><{p}row r="1"><{p}c r="A1" t="s"><{p}v>13</{p}v></{p}c>'
        f'<{p}c r="B1" t="s"><{p}v>0</{p}v></{p}c><{p}c r="C1" t="s"><{p}v>1</{p}v></{p}c>'
        f"</{p}row>"
    ).encode()
    buf = []
    for k in range(1, n + 1):
        r = k + 1
        buf.append(
            f'<{p}row r="{r}"><{p}c r="A{r}"><{p}v>{k}</{p}v></{p}c><{p}c r="B{r}">'
            f'<{p}v>{k}</{p}v></{p}c><{p}c r="C{r}"><{p}v>1</{p}v></{p}c></{p}row>'
        )
        if len(buf) == 10000:
            yield "".join(buf).encode()
            buf = []
    yield ("".join(buf) + f"</{p}sheetData></{p}worksheet>").encode()


def dtd(decl, ref):
    """A change of sharedStrings.xml: a DOCTYPE declaring `decl`, string 59 made `ref`."""

    def f(b):
        s = b.decode().replace("?>", f"?>\n<!DOCTYPE sst [{decl}]>", 1)
        parts = s.split("<si>")
        parts[59] = re.sub(r"<t([^>]*)>[^<]*</t>", "<t>" + ref + "</t>", parts[59], count=1)
        return "<si>".join(parts).encode()

    return f


# ---------------------------------------------------------------- X. xlsx


@probe
def X0_xlsx_rows_control():
    """1.2 million plain rows in a sheet: refused at once (the documented bound)."""
    d = workdir("x0")
    xlsx_copy(kundur_xlsx(), d / "plain.xlsx", stream={AREA: lambda _: area_rows(1_200_000)})
    rc, out, err, t = run(["import-andes", "plain.xlsx", "-o", "plain.json"], d, 120, 4_000_000)
    report(
        "X0_xlsx_rows_control",
        clean_error(rc, out, err) and "rows" in err and t < 30,
        f"rc {rc} in {t:.0f} s: {last(err)}",
    )


@probe
def X1_xlsx_row_number_gap():
    """Two rows, the second numbered 30 000 000 (openpyxl fills the gap with 30 million
    empty rows): refused at once by the bound, not by ANDES after minutes (round 34)."""

    def gap(b):
        return b.replace(
            b"</sheetData>", b'<row r="30000000"><c r="A30000000"><v>7</v></c></row></sheetData>'
        )

    d = workdir("x1")
    xlsx_copy(kundur_xlsx(), d / "gap.xlsx", changes={AREA: gap})
    rc, out, err, t = run(["import-andes", "gap.xlsx", "-o", "gap.json"], d, 180, 4_000_000)
    ok = clean_error(rc, out, err) and t < 15 and "row" in err and "ANDES cannot read" not in err
    report(
        "X1_xlsx_row_number_gap",
        ok,
        f"17 kB file, 1 data row numbered 30e6 (RLIMIT_AS 4 GB): rc {rc} after {t:.0f} s: "
        f"{last(err)}",
    )


@probe
def X2_xlsx_prefixed_rows():
    """X0's 1.2 million rows with a namespace prefix (<x:row>): refused as well (round 34:
    not counted, a timeout)."""
    d = workdir("x2")
    xlsx_copy(kundur_xlsx(), d / "ns.xlsx", stream={AREA: lambda _: area_rows(1_200_000, "x:")})
    rc, out, err, t = run(["import-andes", "ns.xlsx", "-o", "ns.json"], d, 45, 4_000_000)
    report(
        "X2_xlsx_prefixed_rows",
        clean_error(rc, out, err) and "rows" in err,
        f"1.2M <x:row> rows (plain ones refused in X0): rc {rc} after {t:.0f} s: "
        f"{last(out + err)[:160]}",
    )


@probe
def X3_xlsx_sheet_outside_dir():
    """X0's 1.2 million rows in a sheet part outside xl/worksheets/ (the rels point there):
    refused as well (round 34: a timeout)."""
    d = workdir("x3")
    xlsx_copy(
        kundur_xlsx(),
        d / "moved.xlsx",
        stream={AREA: lambda _: area_rows(1_200_000)},
        rename={AREA: "xl/data/sheet6.xml"},
    )
    rc, out, err, t = run(["import-andes", "moved.xlsx", "-o", "moved.json"], d, 45, 4_000_000)
    report(
        "X3_xlsx_sheet_outside_dir",
        clean_error(rc, out, err) and "rows" in err,
        f"1.2M rows in xl/data/sheet6.xml: rc {rc} after {t:.0f} s: {last(out + err)[:160]}",
    )


@probe
def X4_xlsx_sharedstrings_bomb():
    """A sharedStrings.xml of 1.5 GB (3 MB compressed), not a sheet: refused within 30 s
    under RLIMIT_AS 3 GB (round 34: a timeout)."""

    def ss(old):
        s = old.decode()
        i = s.index("<si>")
        yield s[:i].encode()
        yield s[i : s.rindex("</sst>")].encode()
        blk = b"<si><t>a</t></si>" * (1 << 16)
        for _ in range(1400):
            yield blk
        yield b"</sst>"

    d = workdir("x4")
    xlsx_copy(kundur_xlsx(), d / "ssbomb.xlsx", stream={"xl/sharedStrings.xml": ss})
    rc, out, err, t = run(["import-andes", "ssbomb.xlsx", "-o", "ss.json"], d, 60, 3_000_000)
    tb = "Traceback" in out + err
    report(
        "X4_xlsx_sharedstrings_bomb",
        clean_error(rc, out, err) and t < 30,
        f"{(d / 'ssbomb.xlsx').stat().st_size >> 20} MB file, 1.5 GB sharedStrings "
        f"(RLIMIT_AS 3 GB, timeout 60 s): rc {rc} after {t:.0f} s"
        f"{', traceback (MemoryError)' if tb else ''}: {last(err)[:120]}",
    )


@probe
def X5_xlsx_xxe():
    """An external entity naming /etc/passwd in a shared string: refused, not read."""
    d = workdir("x5")
    xxe = dtd('<!ENTITY x SYSTEM "file:///etc/passwd">', "&x;")
    xlsx_copy(kundur_xlsx(), d / "xxe.xlsx", changes={"xl/sharedStrings.xml": xxe})
    rc, out, err, _ = run(["import-andes", "xxe.xlsx", "-o", "xxe.json"], d, 120)
    leaked = "root:" in out + err or (
        (d / "xxe.json").exists() and "root:" in (d / "xxe.json").read_text()
    )
    report(
        "X5_xlsx_xxe",
        clean_error(rc, out, err) and not leaked,
        f"rc {rc}, /etc/passwd {'LEAKED' if leaked else 'not read'}: {last(err)[:140]}",
    )


@probe
def X6_xlsx_billion_laughs():
    d = workdir("x6")
    lol = (
        '<!ENTITY l "lol"><!ENTITY l1 "'
        + "&l;" * 10
        + '">'
        + "".join(f'<!ENTITY l{k} "' + f"&l{k - 1};" * 10 + '">' for k in range(2, 10))
    )
    xlsx_copy(kundur_xlsx(), d / "laughs.xlsx", changes={"xl/sharedStrings.xml": dtd(lol, "&l9;")})
    rc, out, err, t = run(["import-andes", "laughs.xlsx", "-o", "l.json"], d, 120, 4_000_000)
    report(
        "X6_xlsx_billion_laughs",
        clean_error(rc, out, err) and t < 30,
        f"rc {rc} after {t:.0f} s: {last(err)[:140]}",
    )


@probe
def X7_xlsx_checks_skipped():
    """A workbook.xml naming an external link its rels do not hold (openpyxl, as stabctl
    read the cells with keep_links=True, failed; pandas and ANDES read it) beside GENROU_1
    M = 0, which alone is refused: refused as well (round 34: every row check skipped,
    exit 0 and the machine written with ANDES's H)."""

    def ext(b):
        return b.replace(
            b"</sheets>",
            b'</sheets><externalReferences><externalReference r:id="rId99"/></externalReferences>',
        )

    def m0(b):
        return re.sub(r'(<c r="L2"[^>]*><v>)13(</v>)', r"\g<1>0\2", b.decode()).encode()

    d = workdir("x7")
    src = kundur_xlsx()
    xlsx_copy(src, d / "m0.xlsx", changes={"xl/worksheets/sheet7.xml": m0})
    xlsx_copy(
        src, d / "m0ext.xlsx", changes={"xl/worksheets/sheet7.xml": m0, "xl/workbook.xml": ext}
    )
    rc0, _, err0, _ = run(["import-andes", "m0.xlsx", "-o", "m0.json"], d, 120)
    rc, out, err, _ = run(["import-andes", "m0ext.xlsx", "-o", "m0ext.json"], d, 120)
    hs = ""
    if (d / "m0ext.json").exists():
        machines = json.loads((d / "m0ext.json").read_text())["tables"]["machines"]
        h = machines["columns"].index("H")
        hs = (
            f" with machine H {[r[h] for r in machines['rows']]} s "
            "(kundur_full: 6.5, 6.175, 6.175, 6.5)"
        )
    report(
        "X7_xlsx_checks_skipped",
        clean_error(rc, out, err),
        f"M = 0 alone: rc {rc0} ({last(err0)[:60]}); + dangling externalReference: rc {rc}, "
        f"{'written' if (d / 'm0ext.json').exists() else 'not written'}{hs}",
    )


# ---------------------------------------------------------------- N. npz (the API)

NPZ_HEAD = (
    "import numpy as np, io, zipfile\n"
    "from stabctl.dynamics.results import SimulationResult\n"
    "from stabctl.errors import InputError\n"
)
NPZ_READ = (
    "try:\n    SimulationResult.from_npz(F); print('READ')\n"
    "except InputError as e: print('InputError', e)\n"
    "except Exception as e: print('OTHER', type(e).__name__, str(e)[:150])\n"
)


@probe
def N1_npz_object_array():
    """An npz holding an object (pickled) array: an InputError, not numpy's allow_pickle
    ValueError (round 34)."""
    d = workdir("n1")
    code = (
        NPZ_HEAD + "np.savez('obj.npz', t=np.arange(3.), verdict=np.array([1., np.nan]), "
        "separated=np.array([], int), extra=np.array([{'a': 1}], dtype=object))\n"
        "F='obj.npz'\n" + NPZ_READ
    )
    _, out = pyrun(code, d)
    report(
        "N1_npz_object_array",
        "InputError" in out and "allow_pickle" not in out,
        f"from_npz of an npz holding an object array: {last(out)[:170]}",
    )


@probe
def N2_npz_unknown_array():
    """An npz with an array from_npz does not know: an InputError (round 34: TypeError)."""
    d = workdir("n2")
    code = (
        NPZ_HEAD + "np.savez('extra.npz', t=np.arange(3.), verdict=np.array([1., np.nan]), "
        "separated=np.array([], int), zzz=np.arange(2))\nF='extra.npz'\n" + NPZ_READ
    )
    _, out = pyrun(code, d)
    report(
        "N2_npz_unknown_array",
        "InputError" in out,
        f"from_npz of an npz with arrays t, verdict, separated, zzz: {last(out)[:170]}",
    )


@probe
def N3_npz_zip_bomb():
    """A t.npy declaring 2 GiB of zeros, 2 MB compressed, read under RLIMIT_AS 1.5 GB: an
    InputError (round 34: MemoryError)."""
    d = workdir("n3")
    make = NPZ_HEAD + (
        "n = 2**28\nhdr = io.BytesIO()\n"
        "np.lib.format.write_array_header_1_0("
        "hdr, {'descr': '<f8', 'fortran_order': False, 'shape': (n,)})\n"
        "def npy(a):\n    b = io.BytesIO(); np.save(b, a); return b.getvalue()\n"
        "with zipfile.ZipFile('bomb.npz', 'w', zipfile.ZIP_DEFLATED) as z:\n"
        "    z.writestr('verdict.npy', npy(np.array([1., np.nan])))\n"
        "    z.writestr('separated.npy', npy(np.array([], int)))\n"
        "    with z.open('t.npy', 'w', force_zip64=True) as f:\n"
        "        f.write(hdr.getvalue()); blk = bytes(1 << 24)\n"
        "        for _ in range(n * 8 // len(blk)): f.write(blk)\n"
    )
    pyrun(make, d, timeout=120)
    _, out = pyrun(NPZ_HEAD + "F='bomb.npz'\n" + NPZ_READ, d, timeout=120, vmem_kb=1_500_000)
    size = (d / "bomb.npz").stat().st_size >> 20 if (d / "bomb.npz").exists() else -1
    report(
        "N3_npz_zip_bomb",
        "InputError" in out,
        f"from_npz of a {size} MB npz whose t.npy unpacks to 2 GiB (RLIMIT_AS 1.5 GB): "
        f"{last(out)[:140]}",
    )


# ---------------------------------------------------------------- J. records mid-sweep


def sweep_mid(d: Path, name: str, act):
    """Start a sweep (32 Kundur CCT jobs, 2 workers), run act(path) once a record is in
    the file, wait for the end: (rc, stdout, stderr, lines in the file at the end, acted)."""
    cmd = [
        *STABCTL, "sweep-cct", "kundur", "--faults", "DEFAULT",
        "--esd-pct", "none," + ",".join(str(k) for k in range(1, 16)),
        "--workers", "2", "--out", name,
    ]  # fmt: skip
    p = subprocess.Popen(
        cmd,
        cwd=d,
        env=ENV,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        preexec_fn=_limits(None),
        start_new_session=True,
    )
    path, acted = d / name, False
    t0 = time.monotonic()
    while p.poll() is None and time.monotonic() - t0 < 300:
        if not acted and path.exists() and path.stat().st_size > 0:
            act(path)
            acted = True
        time.sleep(0.05)
    try:
        out, err = p.communicate(timeout=max(1, 300 - (time.monotonic() - t0)))
    except subprocess.TimeoutExpired:
        os.killpg(p.pid, signal.SIGKILL)
        out, err = p.communicate()
    n = len(path.read_text().splitlines()) if path.exists() else None
    return p.returncode, out.decode(errors="replace"), err.decode(errors="replace"), n, acted


@probe
def J1_records_deleted_midsweep():
    """The records file deleted after its first record: all 32 records in it at the end, or
    a failure that says so (round 34: exit 0, the file gone with every record)."""
    rc, out, err, n, acted = sweep_mid(workdir("j1"), "r.jsonl", lambda p: p.unlink())
    said = re.search(r"(removed|deleted|lost|gone|no longer)", out + err, re.I)
    ok = not acted or (n is not None and n >= 32) or (rc != 0 and said)
    report(
        "J1_records_deleted_midsweep",
        bool(ok),
        f"rm r.jsonl after its first record: rc {rc}, file at the end: "
        f"{'missing' if n is None else f'{n} lines'}; said: "
        f"{said.group(0) if said else 'nothing'}; summary: {last(out)[:110]}",
    )


@probe
def J2_records_replaced_midsweep():
    """An empty file moved over the records file after its first record: all 32 records
    in it at the end, or a failure that says so (round 34: exit 0, 0 lines)."""

    def over(p):
        other = p.with_name("other.jsonl")
        other.write_text("")
        os.replace(other, p)

    rc, out, err, n, acted = sweep_mid(workdir("j2"), "r.jsonl", over)
    said = re.search(r"(replaced|moved|lost|no longer)", out + err, re.I)
    ok = not acted or (n is not None and n >= 32) or (rc != 0 and said)
    report(
        "J2_records_replaced_midsweep",
        bool(ok),
        f"mv empty file over r.jsonl after its first record: rc {rc}, r.jsonl at the end: "
        f"{'missing' if n is None else f'{n} lines'} (32 jobs); said: "
        f"{said.group(0) if said else 'nothing'}",
    )


# ---------------------------------------------------------------- R. every reader, odd files


@probe
def R1_readers_odd_files():
    """Every reader given a NUL byte, UTF-16, bad UTF-8, an empty file, a directory and a
    FIFO (an --out records file: UTF-16, a directory and a FIFO; damaged lines are set aside
    by design and an empty file is fine): each refused cleanly."""
    cases = andes_cases()
    raw = (cases / "kundur" / "kundur.raw").read_bytes()
    variants = {
        "nul": lambda good: good[: len(good) // 2] + b"\x00" + good[len(good) // 2 :],
        "utf16": lambda good: b"\xff\xfe" + good.decode("latin-1").encode("utf-16-le"),
        "badutf8": lambda good: good.replace(b"\n", b"\xff\xfe\xfd\n", 1),
        "empty": lambda good: b"",
    }
    c37 = b"\xaa\x31\x00\x10" + b"\x00" * 12
    place = ["place", "kundur", "--faults", "DEFAULT"]
    # (id, file name, good content, command using it)
    readers = [
        ("raw", "c.raw", raw, ["import-psse", "c.raw", "-o", "o.json"]),
        (
            "dyr", "c.dyr", b"1 'GENCLS' 1 3.0 0.0 /\n",
            ["import-psse", "k.raw", "c.dyr", "-o", "o.json"],
        ),
        (
            "casejson", "c.json", b'{"format": "stabctl-case"}',
            ["simulate", "c.json", "--tf", "0.1"],
        ),
        ("m", "c.m", b"bus = [1 1.0 0 0 0 0 0 0 0 1];\n", ["simulate", "c.m", "--tf", "0.1"]),
        (
            "faults", "f.csv", b"bus,far_bus\n3,101\n",
            ["sweep-cct", "kundur", "--faults", "f.csv", "--out", "o.jsonl", "--workers", "1"],
        ),
        (
            "sitecosts", "s.csv", b"machine,cost_mw\n1,5\n",
            [*place, "--site-costs", "s.csv", "--workers", "1"],
        ),
        (
            "screening", "s.jsonl", b'{"key": "x"}\n',
            [*place, "--screening", "s.jsonl", "--workers", "1"],
        ),
        (
            "records", "o.jsonl", b'{"key": "x"}\n',
            ["sweep-cct", "kundur", "--faults", "DEFAULT", "--out", "o.jsonl", "--workers", "1"],
        ),
        ("recording", "r.bin", c37, ["pmu", "replay", "r.bin"]),
        (
            "track", "r.bin", c37,
            ["estimate", "track", "kundur", "--source", "r.bin", "--out", "t.csv"],
        ),
        (
            "andesjson", "a.json", (cases / "kundur" / "kundur_full.json").read_bytes(),
            ["import-andes", "a.json", "-o", "o.json"],
        ),
    ]  # fmt: skip
    d = workdir("r1")
    bad = []
    n = 0
    for rid, fname, good, cmd in readers:
        kinds: dict = dict(variants)
        if rid == "records":  # an --out: damaged lines are set aside by design, empty is fine
            kinds = {"utf16": variants["utf16"]}
        kinds["dir"] = None
        kinds["fifo"] = None
        for kind, make in kinds.items():
            w = d / f"{rid}-{kind}"
            w.mkdir()
            (w / "k.raw").write_bytes(raw)
            if kind == "dir":
                (w / fname).mkdir()
            elif kind == "fifo":
                os.mkfifo(w / fname)
            else:
                (w / fname).write_bytes(make(good))
            rc, out, err, _ = run(cmd, w, 60)
            n += 1
            if not clean_error(rc, out, err):
                bad.append(f"{rid}/{kind}: rc {rc} {last(out + err)[:100]!r}")
    report(
        "R1_readers_odd_files",
        not bad,
        f"{n} reader x file kinds (NUL, UTF-16, bad UTF-8, empty, directory, FIFO): "
        + ("all refused cleanly" if not bad else f"{len(bad)} not: " + "; ".join(bad[:4])),
    )


@probe
def R2_raw_crlf():
    """A RAW file with CRLF line ends reads as with LF (same name in two directories)."""
    raw = (andes_cases() / "kundur" / "kundur.raw").read_bytes()
    lf, cr = workdir("r2-lf"), workdir("r2-crlf")
    (lf / "c.raw").write_bytes(raw.replace(b"\r\n", b"\n"))
    (cr / "c.raw").write_bytes(raw.replace(b"\r\n", b"\n").replace(b"\n", b"\r\n"))
    r1 = run(["import-psse", "c.raw", "-o", "c.json", "--static"], lf, 120)
    r2 = run(["import-psse", "c.raw", "-o", "c.json", "--static"], cr, 120)
    same = r1[0] == r2[0] and (lf / "c.json").exists() == (cr / "c.json").exists()
    if same and (lf / "c.json").exists():
        same = (lf / "c.json").read_text() == (cr / "c.json").read_text()
    report(
        "R2_raw_crlf",
        same,
        f"LF rc {r1[0]}, CRLF rc {r2[0]}, outputs {'identical' if same else 'DIFFER'}: "
        f"{last(r2[1] + r2[2])[:100]}",
    )


@probe
def R3_proc_files():
    """Links to /proc/self/pagemap and /proc/self/mem (regular files of size 0 whose reading
    has no bound or fails), under RLIMIT_AS 3 GB: refused cleanly."""
    w = workdir("r3")
    bad = []
    for tgt, nm, cmd in [
        ("/proc/self/pagemap", "p.raw", ["import-psse", "p.raw", "-o", "o.json"]),
        ("/proc/self/mem", "m.raw", ["import-psse", "m.raw", "-o", "o.json"]),
        ("/proc/self/pagemap", "p.m", ["simulate", "p.m"]),
        ("/proc/self/pagemap", "p.bin", ["pmu", "replay", "p.bin"]),
    ]:
        os.symlink(tgt, w / nm)
        rc, out, err, _ = run(cmd, w, 60, 3_000_000)
        if not clean_error(rc, out, err):
            bad.append(f"{nm}: rc {rc} {last(out + err)[:80]}")
    report("R3_proc_files", not bad, "all refused cleanly" if not bad else "; ".join(bad))


# ---------------------------------------------------------------- A. --allow


@probe
def A1_allow_not_ip():
    """--allow given a CIDR, a host name, host:port, short and hex IPv4, blanks: refused."""
    d = workdir("a1")
    bad = []
    for a in ["127.0.0.0/8", "localhost", "127.0.0.1:4712", "127.1", "0x7f000001", " ", ""]:
        rc, out, err, _ = run(
            ["pmu", "serve", "kundur", "--fault", "3", "--far-bus", "101", "--port", "0",
             "--allow", a, "--tf", "1.2"],
            d,
            20,
        )  # fmt: skip
        if not clean_error(rc, out, err):
            bad.append(f"{a!r}: rc {rc}")
    report(
        "A1_allow_not_ip",
        not bad,
        "CIDR, host name, host:port, short and hex IPv4, blank: all refused"
        if not bad
        else "; ".join(bad),
    )


# ---------------------------------------------------------------- S. a crowded server


def command_frame(cmd_word: int, idcode: int = 1, size: int | None = None) -> bytes:
    """A C37.118.2 command frame (FRAMESIZE `size` if given, CRC-CCITT)."""
    body = struct.pack(">HHHIIH", 0xAA41, size or 18, idcode, int(time.time()), 0, cmd_word)
    crc = 0xFFFF
    for byte in body:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) & 0xFFFF if crc & 0x8000 else (crc << 1) & 0xFFFF
    return body + struct.pack(">H", crc)


@probe
def S1_server_crowd():
    """A server with 20 silent connections, one peer that says 'start' and never reads, and
    command frames with FRAMESIZE 65535 / 0 / 17 (less than a command frame): a real `pmu
    record` gets its whole recording (S1), and the server exits 0 after its clients left
    (S2)."""
    d = workdir("s1")
    srv = subprocess.Popen(
        [*STABCTL, "pmu", "serve", "kundur", "--fault", "3", "--far-bus", "101",
         "--port", "0", "--tf", "30", "--speed", "1000", "--wait", "5"],
        cwd=d,
        env=ENV,
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        preexec_fn=_limits(None),
        start_new_session=True,
    )  # fmt: skip
    socks = []
    port = None
    try:
        n_frames, t0 = 0, time.monotonic()
        while port is None and time.monotonic() - t0 < 120:
            line = srv.stderr.readline()
            m = re.search(rb"serving (\d+) frames on 127\.0\.0\.1:(\d+)", line)
            if m:
                n_frames, port = int(m.group(1)), int(m.group(2))
            if not line and srv.poll() is not None:
                break
        if port is None:
            srv.wait(timeout=30)
            report(
                "S1_server_crowd",
                False,
                f"server did not start: {srv.stderr.read().decode(errors='replace')[:100]!r}",
            )
            return
        greedy = socket.create_connection(("127.0.0.1", port))
        greedy.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)
        greedy.sendall(command_frame(2))  # start, then never read
        socks.append(greedy)
        for size in (65535, 0, 17):
            s = socket.create_connection(("127.0.0.1", port))
            s.sendall(command_frame(5, size=size)[:18])
            socks.append(s)
        for _ in range(20):
            socks.append(socket.create_connection(("127.0.0.1", port)))
        time.sleep(1)
        rc, out, err, t = run(
            ["pmu", "record", f"127.0.0.1:{port}", "--frames", n_frames, "-o", "rec.c37"], d, 150
        )
        report(
            "S1_server_crowd",
            rc == 0 and (d / "rec.c37").exists(),
            f"{n_frames} frames, 20 silent peers + 1 'start'-and-never-read + 3 bad sizes: "
            f"record rc {rc} in {t:.0f} s: {last(out + err)[:120]}",
        )
    finally:
        for s in socks:
            s.close()
        try:
            srv.wait(timeout=60)
        except subprocess.TimeoutExpired:
            os.killpg(srv.pid, signal.SIGTERM)
            srv.wait(timeout=10)
        tail = srv.stderr.read().decode(errors="replace")
        srv.stderr.close()
        srv.stdout.close()
        if port is not None:
            report(
                "S2_server_ends",
                srv.returncode == 0,
                f"server exit {srv.returncode} after its clients left: {last(tail)[:140]}",
            )


# ---------------------------------------------------------------- M. the .m reader's memory


@probe
def M1_m_file_memory():
    """A 60 MB PST .m file (within the 256 MiB input bound) under RLIMIT_AS 2 GB: refused
    with an error line (round 34: 35 times its size in memory, a MemoryError traceback)."""
    d = workdir("m1")
    with open(d / "big.m", "w") as f:
        f.write("zz = [" + "1 " * 30_000_000 + "];\n")
    rc, out, err, t = run(["simulate", "big.m"], d, 200, 2_000_000)
    report(
        "M1_m_file_memory",
        clean_error(rc, out, err),
        f"60 MB .m, RLIMIT_AS 2 GB: rc {rc} after {t:.0f} s"
        f"{', traceback' if 'Traceback' in out + err else ''}: {last(err)[:100]}",
    )


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("ids", nargs="*", help="probe names or their prefixes (X4, R1)")
    ap.add_argument("-k", default="", help="run the probes whose name holds this")
    opts = ap.parse_args(argv)
    selected = [
        fn
        for fn in PROBES
        if (not opts.ids or fn.__name__ in opts.ids or fn.__name__.split("_")[0] in opts.ids)
        and opts.k in fn.__name__
    ]
    t_start = time.monotonic()
    print(f"stabctl of {ROOT}; work directory {WORK}", flush=True)
    rc, _, err, _ = run(["compile"], WORK, timeout=900)  # a warm cache loads in seconds
    if rc != 0:
        print("stabctl compile failed:", err[-300:])
        shutil.rmtree(WORK, ignore_errors=True)
        return 2
    try:
        for fn in selected:
            try:
                fn()
            except Exception as ex:  # noqa: BLE001 - a probe that crashes is reported short
                report(fn.__name__, False, f"probe crashed: {type(ex).__name__}: {str(ex)[:200]}")
    finally:
        keep = bool(os.environ.get("KEEP"))
        if not keep:
            shutil.rmtree(WORK, ignore_errors=True)
    n_short = sum(not ok for _, ok, _ in RESULTS)
    print(
        f"\n{len(RESULTS)} probes, {len(RESULTS) - n_short} ok, {n_short} SHORT; "
        f"{time.monotonic() - t_start:.0f} s; work directory {WORK} "
        f"({'kept' if keep else 'removed'})"
    )
    return 1 if n_short else 0


if __name__ == "__main__":
    sys.exit(main())
