"""A C37.118.2 stream is read as its CFG-2 says, whoever wrote it: TIME_BASE, FORMAT
(polar or rectangular, floating-point or integer phasors scaled by PHUNIT, floating-point
or integer FREQ/DFREQ), FNOM and the phasor channels by their PHUNIT type, or refused
naming the field and the PMU; and a PMU whose STAT says its values are not a synchronised
measurement (sync lost, sorted by arrival) is not used, and counted by reason."""

import cmath
import struct

import numpy as np
import pytest
from click.testing import CliRunner

pytest.importorskip("pyc37")

from c37_check import crc_ccitt

from stabctl.cli import main
from stabctl.errors import InputError
from stabctl.estimation import c37, sources

SCALE = 1_000_000  # PHUNIT of the integer phasors: 10 V or A per bit


@pytest.fixture(scope="module")
def kundur():
    """Kundur's 4 machine PMUs for 1.5 s (91 frames), and the frames as stabctl's own
    stream carries them (the reference every layout must read back to)."""
    from pmu_streams import kundur_stream

    case, pmus, cfg, frames = kundur_stream(t_end=1.5)
    return case, pmus, cfg, frames, c37.on_wire(cfg, frames)


def build(
    kundur,
    polar=False,
    ph_float=True,
    fr_float=False,
    time_base=1_000_000,
    fnom=60,
    order="VI",
    phnmr=2,
    stat=0,
    pyc37_freq=False,
    every=False,
):
    """(CFG-2, data frames) of the Kundur stream written with pyc37 in the layout given,
    the values encoded as that CFG-2 says (a floating-point FREQ the actual frequency, or
    with pyc37_freq the deviation from FNOM, as pyc37 writes it); stat: OR-ed into the
    first PMU's STAT of every third frame (every: of every PMU and frame)."""
    from pyc37 import frame as f

    _case, pmus, cfg, frames, _ = kundur
    n = cfg.n
    fmt = (polar, ph_float, False, fr_float)
    cfg2 = f.ConfigFrame2(
        cfg.idcode, time_base, n, [p.label for p in pmus], [2 + k for k in range(n)], [fmt] * n,
        [phnmr] * n, [0] * n, [0] * n, [[f"{c} {p.label}" for c in order][:phnmr] for p in pmus],
        [[(SCALE, c.lower()) for c in order][:phnmr] for _ in pmus], [[]] * n, [[]] * n,
        [fnom] * n, [1] * n, cfg.rate, soc=cfg.epoch, frasec=(0, "+"),
    )  # fmt: skip
    body = []
    for j, fr in enumerate(frames):
        stats, phs, fq, dfq = [], [], [], []
        for k in range(n):
            ok = bool(fr.valid[k])
            hit = every or (k == 0 and j % 3 == 0)
            stats.append((0 if ok else 0x8000) | (stat if hit else 0))
            values = {"V": fr.v[k] * cfg.v_base[k], "I": fr.i[k] * cfg.i_base[k]}
            row = []
            for c in order[:phnmr]:
                z = complex(values[c]) if ok else 0j
                a, b = (abs(z), cmath.phase(z)) if polar else (z.real, z.imag)
                if not ph_float:
                    a = round(a * 1e5 / SCALE)
                    b = round(b * 1e4) if polar else round(b * 1e5 / SCALE)
                row.append((a, b))
            phs.append(row)
            dev = fr.freq[k] - fnom if ok else 0.0
            fq.append(float(dev) if fr_float else round(dev * 1000))
            roc = fr.rocof[k] if ok else 0.0
            dfq.append(float(roc) if fr_float else round(roc * 100))
        sec = int(np.floor(fr.t))
        counts = round((fr.t - sec) * time_base)
        df = f.DataFrame(
            cfg.idcode, stats, phs, fq, dfq, [[]] * n, [[]] * n, cfg2, soc=cfg.epoch + sec,
            frasec=(counts, "+"),
        )  # fmt: skip
        data = df.convert2bytes()
        if fr_float and not pyc37_freq:  # the actual frequency, which pyc37 cannot write
            data = _actual_freq(data, cfg2, [fr.freq[k] if fr.valid[k] else 0.0 for k in range(n)])
        body.append(data)
    return cfg2.convert2bytes(), body


def _actual_freq(data: bytes, cfg2, freq) -> bytes:
    """A data frame whose floating-point FREQ fields hold `freq` (Hz), its CRC valid."""
    out, at = bytearray(data), 14
    for block, hz in zip(c37.blocks(cfg2), freq):
        struct.pack_into(">f", out, at + 2 + 8 * len(block.units), hz)
        at += block.size
    return bytes(out[:-2]) + crc_ccitt(bytes(out[:-2])).to_bytes(2, "big")


def merged(kundur, head, body):
    case, pmus, cfg, _, _ = kundur
    return sources.merge(case, pmus, cfg.rate, [(c37.read_config(head, "CFG-2"), body)])


@pytest.mark.parametrize(
    "layout, f_tol",
    [
        ({"polar": True}, 0.0),
        ({"ph_float": False}, 0.0),
        ({"polar": True, "ph_float": False}, 0.0),
        ({"fr_float": True}, 6e-4),
        ({"time_base": 1000}, 0.0),
        ({"order": "IV"}, 0.0),
    ],
    ids=["polar", "integer", "polar-integer", "float-FREQ", "TIME_BASE-1000", "I-V"],
)
def test_a_stream_is_read_as_its_cfg2_says(kundur, layout, f_tol):
    """Streams whose CFG-2 says polar phasors, 16-bit integer phasors (PHUNIT 10 V or A
    per bit), floating-point FREQ/DFREQ (the actual frequency), TIME_BASE 1000 or the
    current phasor before the voltage were read
    with stabctl's own layout (exit 0, frequencies off by Hz, phasors swapped).  Each is
    read back to the frames of stabctl's own stream: the same time stamps and absent
    values, the phasors and frequencies within what the layout's resolution allows."""
    _, _, cfg, _, reference = kundur
    got = merged(kundur, *build(kundur, **layout))
    assert [f.t for f in got.frames] == [f.t for f in reference]
    for g, r in zip(got.frames, reference):
        assert np.array_equal(g.valid, r.valid)
        ok = r.valid
        for x, y, base in ((g.v, r.v, cfg.v_base), (g.i, r.i, cfg.i_base)):
            # float32 (and polar's float64 sine), or one count of an integer phasor: its
            # PHUNIT's 10 V or A, and 1e-4 rad of a polar one's angle
            integer = not layout.get("ph_float", True)
            count = SCALE * 1e-5 / base[ok] + 1e-4 * np.abs(y[ok]) if integer else 0.0
            tol = 3e-7 * np.abs(y[ok]) + count
            assert np.all(np.abs(x[ok] - y[ok]) <= tol), (x[ok], y[ok])
        np.testing.assert_allclose(g.freq[ok], r.freq[ok], rtol=0, atol=f_tol + 1e-9)
        np.testing.assert_allclose(g.rocof[ok], r.rocof[ok], rtol=0, atol=f_tol * 10 + 1e-9)


@pytest.mark.parametrize(
    "layout, needle",
    [
        ({"phnmr": 1}, "its CFG-2: PMU B1:G1: no current phasor(s) (PHUNIT type 1) among its "
         "PHNMR 1 ['V B1:G1' (v)], where the stream needs one"),
        ({"order": "VV"}, "PMU B1:G1: 2 voltage phasor(s) (PHUNIT type 0) among its PHNMR 2"),
        ({"fr_float": True, "pyc37_freq": True}, "data frame 1: PMU B1:G1: floating-point FREQ "
         "(FORMAT bit 3) 5.46559e-06 Hz is not within FNOM 60 +- 32.767 Hz"),
        ({"fnom": 50}, "its CFG-2 FNOM 50 Hz (PMU B1:G1, B2:G2, B11:G3, B12:G4), not the "
         "case's nominal frequency 60 Hz"),
    ],
    ids=["PHNMR-1", "two-voltages", "FREQ-deviation", "FNOM-50"],
)  # fmt: skip
def test_a_cfg2_not_read_is_refused_naming_field_and_pmu(kundur, layout, needle):
    """A CFG-2 with one phasor (the voltage) where the machine PMU's current is needed
    raised an IndexError (a traceback); one with two voltage phasors, or a floating-point
    FREQ holding the deviation (as pyc37 writes it, where the standard has the actual
    frequency), was read wrong; one whose FNOM is 50 Hz on a 60 Hz case was read as PMUs
    of that case, their FREQ taken from 50 Hz.  Each is refused naming the stream, the
    field and the PMU."""
    with pytest.raises(InputError) as err:
        merged(kundur, *build(kundur, **layout))
    assert str(err.value).startswith("stream 1") and needle in str(err.value), err.value


@pytest.mark.parametrize(
    "stat, reason",
    [(0x2000, "PMU sync lost (STAT bit 13)"), (0x1000, "sorted by arrival (STAT bit 12)")],
)
def test_values_not_synchronised_are_not_used_and_counted(kundur, tmp_path, stat, reason):
    """STAT bit 13 (PMU sync error) or bit 12 (data sorted by arrival) on the first PMU of
    every third frame was ignored: the values used as synchronised measurements, exit 0
    without a word.  They are not used (invalid, NaN, as absent data), counted by reason
    in the merged stream, and `estimate track` says how many and why; a stream whose
    every value is so flagged is refused naming the reason."""
    *_, reference = kundur
    head, body = build(kundur, stat=stat)
    got = merged(kundur, head, body)
    hit = [j for j, r in enumerate(reference) if j % 3 == 0 and r.valid[0]]
    assert all(not got.frames[j].valid[0] and np.isnan(got.frames[j].freq[0]) for j in hit)
    absent = int(sum((~r.valid).sum() for r in reference))
    counts = {"test mode or absent (STAT bits 15-14 = 10)": absent, reason: len(hit)}
    assert got.flagged == {why: n for why, n in counts.items() if n}
    assert got.absent == absent + len(hit)
    rec = tmp_path / "r.c37"
    rec.write_bytes(head + b"".join(body))
    res = CliRunner().invoke(
        main,
        ["estimate", "track", "kundur", "--source", str(rec), "--out", str(tmp_path / "t.csv")],
    )
    assert res.exit_code == 0, res.output
    assert f"{absent + len(hit)} PMU values not used by their STAT (" in res.stdout
    assert f"{len(hit)} {reason}" in res.stdout
    every = tmp_path / "every.c37"
    head, body = build(kundur, stat=stat, every=True)
    every.write_bytes(head + b"".join(body))
    with pytest.raises(InputError, match=f"is missing or not used: .*{reason[:12]}"):
        sources.read_frames(sources.parse_source(str(every)), *kundur[:2], 60)
