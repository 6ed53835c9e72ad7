"""IEEE C37.118.2-2011 frames of the simulated PMUs: one multi-PMU stream (as a PDC sends
it), its configuration frame (CFG-2) and data frames, built with pyc37 (BSD-3, the
maintained fork of pypmu; the ``pmu`` extra), which reads the CFG-2 too, the data frames
read here as their CFG-2 lays them out, and recordings of a stream as the frames
themselves.

Stream layout (C37.118.2-2011 Tables 5, 6, 8, 9):
- one PMU block per `stabctl.estimation.pmu.PMU`, station name its label (``B3:G1``),
  IDCODE = the stream's IDCODE + 1 + its index (or from `StreamConfig.pmu_idcode`);
- FORMAT 0x0002: phasors rectangular floating point in engineering units (volts and
  amperes, phase-to-neutral: pu times `StreamConfig.v_base`, `StreamConfig.i_base`), FREQ
  and DFREQ 16-bit integers: FREQ the deviation from nominal in mHz, DFREQ the ROCOF in
  Hz/s times 100.  Integers, because pyc37 1.0.2 reads a floating-point FREQ as a
  deviation limited to +-32.767 Hz where the standard (Table 6) makes it the actual
  frequency (a defect reported upstream in pypmu), so it could neither send nor read a
  standard floating-point FREQ of a 60 Hz PMU.  Resolution: 1 mHz, 0.01 Hz/s;
- two phasors per PMU (V, I), one (V) for a PMU without current channel;
- a PMU's frame lost in the stream: STAT 0x8000 (bits 15-14 = 10, "absent data
  inserted"), values 0 on the wire, NaN once parsed;
- SOC/FRACSEC: the time stamp plus `StreamConfig.epoch` (UNIX seconds), TIME_BASE
  1 000 000 (1 us).
A recording is the CFG-2 frame followed by the data frames, each as sent (they carry their
own FRAMESIZE): any C37.118.2 reader can replay it.

A stream someone else wrote is read as its CFG-2 says (`check_config`, `parse_frame`):
TIME_BASE, FORMAT, PHUNIT, FNOM, the phasors by their PHUNIT type; STAT words that make
a PMU's values unusable (`STAT_UNUSABLE`) leave them out, counted by reason.
"""

from __future__ import annotations

import cmath
import collections.abc  # noqa: F401  pyc37 1.0.2 uses collections.abc without importing it
import math
import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from stabctl.errors import InputError
from stabctl.estimation.pmu import Frame
from stabctl.estimation.settings import check_rate
from stabctl.parallel import atomic_write

TIME_BASE = 1_000_000  # FRACSEC counts per second (1 us)
#: FORMAT (Table 9): phasor polar, phasor float, analog float, FREQ/DFREQ float
FORMAT = (False, True, False, False)
STAT_GOOD, STAT_ABSENT = 0x0000, 0x8000  # STAT bits 15-14: 00 good, 10 absent data inserted
MHZ_PER_HZ, DFREQ_PER_HZ_S = 1000.0, 100.0  # integer FREQ (mHz) and DFREQ (Hz/s x 100)
INT16 = 32767


@dataclass(frozen=True)
class StreamConfig:
    """What a C37.118.2 stream of simulated PMUs carries and how its values map to pu.

    Attributes
    ----------
    idcode : int
        The stream's IDCODE (1..65535 - number of PMUs), which a server's commands
        address; PMU k's block has idcode + 1 + k unless `pmu_idcode` is given.
    pmus : tuple of PMU
        The PMUs, in block order.
    f0 : float
        Nominal frequency (Hz): 50 or 60 (FNOM).
    rate : int
        Frames per second (DATA_RATE).
    v_base, i_base : ndarray
        Volts and amperes per pu of each PMU's voltage and current (n_pmu,).
    epoch : int
        UNIX second of the run's t = 0 (SOC of a time stamp t: epoch + floor(t)).
    pmu_idcode : int
        IDCODE of the first PMU's block, PMU k's pmu_idcode + k (0: idcode + 1).
    """

    idcode: int
    pmus: tuple
    f0: float
    rate: int
    v_base: np.ndarray
    i_base: np.ndarray
    epoch: int = 1_700_000_000
    pmu_idcode: int = 0

    @property
    def n(self) -> int:
        return len(self.pmus)

    def phasors(self, k: int) -> int:
        """Phasor channels of PMU k: V and I, or V alone."""
        p = self.pmus[k]
        return 1 if p.machine is None and p.device is None else 2


def stream_config(
    case,
    pmus,
    rate: float,
    idcode: int = 1,
    epoch: int = 1_700_000_000,
    pmu_idcode: int | None = None,
) -> StreamConfig:
    """The stream of `pmus` in `case`: engineering units from each PMU bus's rated kV
    (V per pu = kV 1000 / sqrt(3), A per pu = base MVA 1e6 / (sqrt(3) kV 1000)).
    `pmu_idcode`: the first PMU block's IDCODE (None: idcode + 1).

    Raises
    ------
    InputError
        No PMU, a rate that is not a whole number of frames per second in [1, 240] or not
        a reporting rate of the case's frequency (`check_rate`: a 50 Hz case's stream
        described as 60 frames/s), an IDCODE that leaves no room for the PMUs' own, a bus
        with no rated kV, or a nominal frequency other than 50 or 60 Hz (FNOM has no other).
    """
    pmus = tuple(pmus)
    if not pmus:
        raise InputError("a C37.118.2 stream needs at least one PMU")
    if rate != int(rate) or not 1 <= rate <= 240:
        raise InputError(f"C37.118.2 data rate must be 1..240 frames/s, got {rate:g}")
    if not 1 <= idcode <= 65535 - len(pmus):
        raise InputError(f"IDCODE must be in [1, {65535 - len(pmus)}], got {idcode}")
    if pmu_idcode is not None and not 1 <= pmu_idcode <= 65535 - len(pmus):
        raise InputError(
            f"the first PMU's IDCODE must be in [1, {65535 - len(pmus)}], got {pmu_idcode}"
        )
    if case.freq_hz not in (50.0, 60.0):
        raise InputError(f"C37.118.2 FNOM is 50 or 60 Hz, the case has {case.freq_hz:g} Hz")
    check_rate(rate, case.freq_hz, "stream_config(rate={})", "give {}")
    kv = np.array([case.buses.kv[case.bus_index(p.bus)] for p in pmus], float)
    if np.any(kv <= 0):
        bus = pmus[int(np.argmax(kv <= 0))].bus
        raise InputError(f"PMU bus {bus} has no rated kV: its volts per pu are unknown")
    v_base = kv * 1e3 / np.sqrt(3.0)
    return StreamConfig(
        idcode,
        pmus,
        float(case.freq_hz),
        int(rate),
        v_base,
        case.base_mva * 1e6 / (3.0 * v_base),
        int(epoch),
        0 if pmu_idcode is None else int(pmu_idcode),
    )


def _pyc37():
    try:
        from pyc37 import frame
    except ImportError as exc:  # the optional extra
        raise InputError("C37.118.2 streams need pyc37: pip install 'stabctl[pmu]'") from exc
    return frame


def config_frame(cfg: StreamConfig):
    """The stream's CFG-2 frame (a pyc37 ``ConfigFrame2``; ``convert2bytes()`` its
    bytes), time-stamped at the run's start."""
    f = _pyc37()
    n = cfg.n
    names = [[f"V {p.label}", f"I {p.label}"][: cfg.phasors(k)] for k, p in enumerate(cfg.pmus)]
    one = _one_or_list(n)
    return f.ConfigFrame2(
        cfg.idcode,
        TIME_BASE,
        n,
        one([p.label for p in cfg.pmus]),
        one([(cfg.pmu_idcode or cfg.idcode + 1) + k for k in range(n)]),
        one([FORMAT] * n),
        one([cfg.phasors(k) for k in range(n)]),
        one([0] * n),
        one([0] * n),
        one(names),
        one([[(0, "v"), (0, "i")][: cfg.phasors(k)] for k in range(n)]),
        one([[] for _ in range(n)]),
        one([[] for _ in range(n)]),
        one([int(cfg.f0)] * n),
        one([1] * n),
        cfg.rate,
        soc=cfg.epoch,
        frasec=(0, "+"),
    )


def _one_or_list(n: int):
    """pyc37 takes a single PMU's fields bare and several PMUs' as lists: the converter
    for a stream of n PMUs."""
    return (lambda values: values[0]) if n == 1 else (lambda values: values)


def time_stamp(cfg: StreamConfig, t: float) -> tuple[int, int]:
    """(SOC, FRACSEC count) of run time t (s): the second and its fraction in TIME_BASE
    counts, rounded to the count (a count of TIME_BASE carries into the next second)."""
    counts = int(round((t - np.floor(t)) * TIME_BASE))
    second = int(np.floor(t)) + counts // TIME_BASE
    return cfg.epoch + second, counts % TIME_BASE


def data_frame(cfg: StreamConfig, cfg2, frame: Frame) -> bytes:
    """One data frame of the stream (bytes, CRC included) from a `pmu.Frame` of its PMUs
    (pu, Hz, Hz/s); cfg2: `config_frame`'s result.

    Raises
    ------
    InputError
        A frequency deviation beyond +-32.767 Hz or a ROCOF beyond +-327.67 Hz/s (the
        16-bit FREQ and DFREQ), or a frame of another number of PMUs.
    """
    f = _pyc37()
    if frame.valid.size != cfg.n:
        raise InputError(f"a frame of {frame.valid.size} PMUs for a stream of {cfg.n}")
    stat, phasors, freq, dfreq = [], [], [], []
    for k in range(cfg.n):
        ok = bool(frame.valid[k])
        stat.append(STAT_GOOD if ok else STAT_ABSENT)
        ph = [frame.v[k] * cfg.v_base[k], frame.i[k] * cfg.i_base[k]][: cfg.phasors(k)]
        phasors.append([(float(z.real), float(z.imag)) if ok else (0.0, 0.0) for z in ph])
        freq.append(_int16(ok and (frame.freq[k] - cfg.f0) * MHZ_PER_HZ, "FREQ", k))
        dfreq.append(_int16(ok and frame.rocof[k] * DFREQ_PER_HZ_S, "DFREQ", k))
    soc, counts = time_stamp(cfg, frame.t)
    one = _one_or_list(cfg.n)
    df = f.DataFrame(
        cfg.idcode,
        one(stat),
        one(phasors),
        one(freq),
        one(dfreq),
        one([[] for _ in range(cfg.n)]),
        one([[] for _ in range(cfg.n)]),
        cfg2,
        soc=soc,
        frasec=(counts, "+"),
    )
    return df.convert2bytes()


def _int16(value, what: str, k: int) -> int:
    v = float(value)  # a non-finite value named as out of range, not int()'s OverflowError
    if not (math.isfinite(v) and -INT16 <= round(v) <= INT16):
        raise InputError(
            f"PMU {k}: {what} {v:g} does not fit C37.118.2's 16-bit field (FREQ at most "
            f"{INT16 / MHZ_PER_HZ:g} Hz off nominal, DFREQ {INT16 / DFREQ_PER_HZ_S:g} Hz/s; "
            "a simulated PMU's errors are --fe-hz and --rfe-hz-s over --k-sigma)"
        )
    return int(round(v))


#: STAT (C37.118.2-2011 Table 7) words whose PMU values are not a synchronised
#: measurement at the frame's time stamp, each (mask, value, reason): not used (as a frame
#: lost), counted by reason.  Bit 13 (PMU sync error): the PMU's clock has lost its time
#: source, so its time stamp, and the phase angles referred to it, cannot be trusted; bit
#: 12 (data sorting by arrival): the PDC put the values in the frame as they came, not by
#: their own time stamps, so they may belong to another instant.
STAT_UNUSABLE: tuple[tuple[int, int, str], ...] = (
    (0xC000, 0x4000, "PMU error, no information about data (STAT bits 15-14 = 01)"),
    (0xC000, 0x8000, "test mode or absent (STAT bits 15-14 = 10)"),
    (0xC000, 0xC000, "PMU error (STAT bits 15-14 = 11)"),
    (0x2000, 0x2000, "PMU sync lost (STAT bit 13)"),
    (0x1000, 0x1000, "sorted by arrival (STAT bit 12)"),
)


#: The time-quality rule: a PMU value is used only if its time stamp is known to within
#: 10 us.  At 60 Hz, 26.5 us of time error is 1 % TVE (C37.118.1-2011 5.3: 0.573 deg), so
#: a clock whose stated error bound is 100 us or more (or unknown) makes the phase angles,
#: and the relative speeds drawn from them, untrustworthy.  The indicators (C37.118.2-2011):
#: STAT bits 8-6 (PMU time quality, Table 7: 100 up to 100 us, 101 1 ms, 110 10 ms, 111 more
#: or unknown) and bits 5-4 (unlocked time: 11, unlocked for more than 1000 s), in
#: `STAT_UNUSABLE`; FRACSEC's message time quality (clause 6.2.2, Table 3: the byte before
#: the fraction-of-second count, bits 3-0) in `TIME_QUALITY_UNUSABLE`.  Each such value is
#: not used (as a frame lost) and counted by its reason.
STAT_UNUSABLE += (
    (0x01C0, 0x0100, "PMU time error up to 100 us (STAT bits 8-6 = 100)"),
    (0x01C0, 0x0140, "PMU time error up to 1 ms (STAT bits 8-6 = 101)"),
    (0x01C0, 0x0180, "PMU time error up to 10 ms (STAT bits 8-6 = 110)"),
    (0x01C0, 0x01C0, "PMU time error over 10 ms or unknown (STAT bits 8-6 = 111)"),
    (0x0030, 0x0030, "clock unlocked for over 1000 s (STAT bits 5-4 = 11)"),
)

#: FRACSEC's message time quality code 0xF: "fault, clock failure, time not reliable"
TIME_QUALITY_FAULT = (0x0F, 0x0F, "clock failure (FRACSEC time quality 0xF)")
#: FRACSEC message time quality codes (bits 3-0) that make a frame's every PMU value
#: unusable (the rule above: a clock error bound of 100 us or more; 0xC-0xE are reserved,
#: their meaning unknown), each (mask, value, reason); codes 0x0-0x5 (locked, or within
#: 10 us) and the leap-second bits (6-4) leave the values used.
TIME_QUALITY_UNUSABLE = (
    *(
        (0x0F, code, f"clock error up to {bound} (FRACSEC time quality 0x{code:X})")
        for code, bound in zip(range(6, 12), ("100 us", "1 ms", "10 ms", "100 ms", "1 s", "10 s"))
    ),
    *((0x0F, code, f"reserved FRACSEC time quality 0x{code:X}") for code in range(12, 15)),
    TIME_QUALITY_FAULT,
)


def time_unusable(data: bytes) -> str:
    """Why a data frame's time stamp makes its every PMU value unusable, by its FRACSEC
    message time quality (`TIME_QUALITY_UNUSABLE`), or ''.

    Parameters
    ----------
    data : bytes
        A data frame (FRACSEC's time quality byte at offset 10, C37.118.2-2011 Table 2).

    Returns
    -------
    str
        The reason, or ''.
    """
    q = data[10]
    return next((why for mask, value, why in TIME_QUALITY_UNUSABLE if q & mask == value), "")


#: the reason `marked` gives: a field holding C37.118.2's absent-data value (0x8000 in a
#: 16-bit integer, NaN in a floating-point field), an infinite floating-point value, or an
#: integer FREQ or DFREQ at the end of its span (0x7FFF or -0x7FFF: saturated)
MARKED = "absent-data value (0x8000 or NaN), infinite or saturated FREQ/DFREQ"
#: 16-bit integers that are no measurement: C37.118.2's absent-data value, and in FREQ
#: and DFREQ the ends of the span (saturated)
_ABSENT_INT, _SATURATED_INT = -0x8000, 0x7FFF


def marked(b: Block, data: bytes, at: int) -> str:
    """Why a PMU block's fields hold no measurement, STAT aside: `MARKED` if a phasor,
    FREQ or DFREQ field holds the absent-data value (0x8000 in a signed 16-bit integer
    field, NaN in a floating-point one; an unsigned integer magnitude has no such value),
    a floating-point field is infinite, or an integer FREQ or DFREQ is saturated
    (+-0x7FFF); else ''.  Such a value read as a
    measurement (0x8000 in FREQ is FNOM - 32.768 Hz) drove the raw estimator 25 Hz off.

    Parameters
    ----------
    b : Block
        The PMU's block.
    data : bytes
        A data frame.
    at : int
        Byte offset of the block's first phasor (after its STAT).

    Returns
    -------
    str
        `MARKED` or ''.
    """
    n = len(b.units)
    if b.ph_float:
        ph = struct.unpack_from(f">{2 * n}f", data, at)
        if not all(math.isfinite(x) for x in ph):
            return MARKED
    else:
        ph = struct.unpack_from(">" + ("Hh" if b.polar else "hh") * n, data, at)
        signed = ph[1::2] if b.polar else ph
        if _ABSENT_INT in signed:
            return MARKED
    at += n * (8 if b.ph_float else 4)
    if b.fr_float:
        fr = struct.unpack_from(">ff", data, at)
        return "" if all(math.isfinite(x) for x in fr) else MARKED
    fr = struct.unpack_from(">hh", data, at)
    return MARKED if any(x in (_ABSENT_INT, _SATURATED_INT, -_SATURATED_INT) for x in fr) else ""


def unusable(stat: int) -> str:
    """Why a PMU's values with STAT word `stat` are not used ('' if they are).

    Parameters
    ----------
    stat : int
        The PMU's 16-bit STAT word in a data frame.

    Returns
    -------
    str
        The first reason of `STAT_UNUSABLE` that applies, or ''.
    """
    return next((why for mask, value, why in STAT_UNUSABLE if stat & mask == value), "")


@dataclass(frozen=True)
class Block:
    """One PMU's block in a stream's data frames, as its CFG-2 gives it (C37.118.2-2011
    Tables 5, 8, 9).

    Attributes
    ----------
    station : str
        STN.
    polar, ph_float, an_float, fr_float : bool
        FORMAT bits 0-3: phasors polar, phasors, analogs, FREQ/DFREQ floating point.
    units : tuple of (int, str)
        PHUNIT of each phasor: (scale in 1e-5 V or A per bit of an integer phasor,
        ``v`` voltage or ``i`` current).
    channels : tuple of str
        CHNAM of each phasor.
    analogs, digitals : int
        ANNMR and DGNMR.
    fnom : float
        FNOM, Hz.
    """

    station: str
    polar: bool
    ph_float: bool
    an_float: bool
    fr_float: bool
    units: tuple
    channels: tuple
    analogs: int
    digitals: int
    fnom: float

    @property
    def size(self) -> int:
        """Bytes of the block: STAT, phasors, FREQ, DFREQ, analogs, digital words."""
        return (
            2
            + len(self.units) * (8 if self.ph_float else 4)
            + 2 * (4 if self.fr_float else 2)
            + self.analogs * (4 if self.an_float else 2)
            + 2 * self.digitals
        )

    def phasor(self, kind: str, need: bool, what: str) -> int | None:
        """The index of the block's one phasor of `kind` (``v``, ``i``) by its PHUNIT
        type; None if it has none and `need` is False.

        Raises
        ------
        InputError
            None of that kind where `need`, or more than one (which is the PMU's is not
            known), or an integer phasor whose PHUNIT scale is 0, named with `what`.
        """
        name = {"v": "voltage", "i": "current"}[kind]
        at = [j for j, (_, t) in enumerate(self.units) if t == kind]
        listed = ", ".join(f"{c.strip()!r} ({t})" for c, (_, t) in zip(self.channels, self.units))
        if len(at) > 1 or (need and not at):
            how = "no" if not at else f"{len(at)}"
            raise InputError(
                f"{what}: PMU {self.station}: {how} {name} phasor(s) (PHUNIT type "
                f"{'0' if kind == 'v' else '1'}) among its PHNMR {len(self.units)} "
                f"[{listed}], where the stream needs one"
            )
        if at and not self.ph_float and self.units[at[0]][0] == 0:
            raise InputError(
                f"{what}: PMU {self.station}: integer phasor {self.channels[at[0]].strip()!r} "
                "has PHUNIT scale 0"
            )
        return at[0] if at else None


def blocks(cfg2) -> list[Block]:
    """The PMU blocks of a stream's data frames, in order, as its CFG-2 gives them.

    Parameters
    ----------
    cfg2 : pyc37 ConfigFrame2
        The stream's configuration frame.

    Returns
    -------
    list of Block
    """
    c = cfg2
    one = (lambda x: x) if c.get_num_pmu() > 1 else (lambda x: [x])  # pyc37: one PMU's bare
    fields = (
        c.get_station_name,
        c.get_data_format,
        c.get_phasor_num,
        c.get_ph_units,
        c.get_channel_names,
        c.get_analog_num,
        c.get_digital_num,
        c.get_fnom,
    )
    return [
        Block(
            str(name).strip(),
            bool(fmt[0]),
            bool(fmt[1]),
            bool(fmt[2]),
            bool(fmt[3]),
            tuple(units),
            tuple(str(x) for x in chnam[:phnmr]),
            annmr,
            dgnmr,
            float(fnom),
        )
        for name, fmt, phnmr, units, chnam, annmr, dgnmr, fnom in zip(
            *(one(get()) for get in fields)
        )
    ]


@dataclass(frozen=True)
class Layout:
    """How a stream's data frames are read into the PMUs of a `StreamConfig`
    (`check_config`).

    Attributes
    ----------
    time_base : int
        TIME_BASE: FRACSEC counts per second.
    blocks : tuple of Block
        The PMUs' blocks, in the stream config's PMU order.
    voltage : tuple of int
        Each PMU's voltage phasor (its index among the block's phasors).
    current : tuple of int or None
        Each PMU's current phasor; None for a PMU the stream carries no current of.
    """

    time_base: int
    blocks: tuple
    voltage: tuple
    current: tuple


def check_config(cfg2, cfg: StreamConfig) -> Layout:
    """The one check of a stream's CFG-2 against the stream a reader expects, and how its
    data frames are read: every reader (a recording replayed, streams merged, the ESD
    controller's plant) calls it, and `parse_frame` reads by its result.  Read as the
    CFG-2 gives it: TIME_BASE, FORMAT (polar or rectangular, floating point or integer
    phasors scaled by their PHUNIT, floating-point or integer FREQ/DFREQ), FNOM, and each
    PMU's voltage and current phasors found by their PHUNIT type whatever their order.

    Parameters
    ----------
    cfg2 : pyc37 ConfigFrame2
        The stream's configuration frame.
    cfg : StreamConfig
        The stream expected: its IDCODE, PMUs (station names, in order), rate, and which
        PMUs carry a current phasor (`StreamConfig.phasors`).

    Returns
    -------
    Layout

    Raises
    ------
    InputError
        An IDCODE, station names or DATA_RATE other than cfg's, a PMU whose FNOM is not
        the case's nominal frequency (cfg's `StreamConfig.f0`: its FREQ, a deviation
        from its FNOM, would be read as one from the case's), a PMU without exactly
        one voltage phasor, or without exactly one current phasor where cfg needs one,
        or an integer phasor used whose PHUNIT scale is 0: each named (``its CFG-2``,
        the field, the PMU); the caller adds the source.
    """
    bl = blocks(cfg2)
    for field, theirs, ours in (
        ("IDCODE", cfg2.get_id_code(), cfg.idcode),
        ("station names", [b.station for b in bl], [p.label for p in cfg.pmus]),
        ("DATA_RATE", cfg2.get_data_rate(), cfg.rate),
    ):
        if theirs != ours:
            raise InputError(f"its CFG-2 {field} {theirs}, not the {ours} expected")
    if off := [b for b in bl if b.fnom != cfg.f0]:
        raise InputError(
            f"its CFG-2 FNOM {off[0].fnom:g} Hz (PMU {', '.join(b.station for b in off)}), "
            f"not the case's nominal frequency {cfg.f0:g} Hz: PMUs of another system"
        )
    return Layout(
        int(cfg2.get_time_base()),
        tuple(bl),
        tuple(b.phasor("v", True, "its CFG-2") for b in bl),
        tuple(
            b.phasor("i", True, "its CFG-2") if cfg.phasors(k) == 2 else None
            for k, b in enumerate(bl)
        ),
    )


#: a floating-point FREQ's range: FNOM +- this (Hz), the standard's range of FREQ
FREQ_SPAN_HZ = 32.767


def parse_frame(cfg: StreamConfig, cfg2, data: bytes) -> Frame:
    """A data frame of the stream back to a `pmu.Frame` (pu, Hz, Hz/s), read as cfg2
    says (`check_config`; its checks first, and `check_data_frame`'s).  A PMU whose STAT
    makes its values unusable (`unusable`: absent, PMU error, test mode, sync lost,
    sorted by arrival), or whose fields hold an absent-data value (`marked`), is invalid,
    its values NaN, as is every PMU of a frame whose FRACSEC time quality says clock
    failure (`time_unusable`).

    Raises
    ------
    InputError
        As `check_data_frame` and `check_config`; a floating-point FREQ (FORMAT bit 3)
        that is not within FNOM +- 32.767 Hz (C37.118.2-2011 Table 6: it is the actual
        frequency; pyc37 writes the deviation there) or a DFREQ that is not finite, named
        with its PMU.
    """
    check_data_frame(cfg2, data)
    lay = check_config(cfg2, cfg)
    n = cfg.n
    valid = np.zeros(n, bool)
    v, i = np.full(n, np.nan + 0j), np.full(n, np.nan + 0j)
    freq, rocof = np.full(n, np.nan), np.full(n, np.nan)
    at = 14
    clock = time_unusable(data)
    for k, b in enumerate(lay.blocks):
        stat = int.from_bytes(data[at : at + 2], "big")
        if not clock and not unusable(stat) and not marked(b, data, at + 2):
            valid[k] = True
            ph = _phasors(b, data, at + 2)
            v[k] = ph[lay.voltage[k]] / cfg.v_base[k]
            if (j := lay.current[k]) is not None:
                i[k] = ph[j] / cfg.i_base[k]
            freq[k], rocof[k] = _frequency(b, data, at + 2 + len(ph) * (8 if b.ph_float else 4))
        at += b.size
    count = int.from_bytes(data[11:14], "big")
    t = int.from_bytes(data[6:10], "big") - cfg.epoch + count / lay.time_base
    return Frame(reporting_instant(t, cfg.rate, lay.time_base), valid, v, i, freq, rocof)


def _phasors(b: Block, data: bytes, at: int) -> list[complex]:
    """The phasors of block b at byte `at` of a data frame, in volts and amperes: floating
    point as they are (polar: magnitude, angle in rad), integers times their PHUNIT scale
    (1e-5 V or A per bit; polar: the angle in 1e-4 rad)."""
    n = len(b.units)
    if b.ph_float:
        vals = struct.unpack_from(f">{2 * n}f", data, at)
    else:
        vals = struct.unpack_from(">" + ("Hh" if b.polar else "hh") * n, data, at)
    out = []
    for j, (scale, _) in enumerate(b.units):
        x, y = vals[2 * j], vals[2 * j + 1]
        unit = 1.0 if b.ph_float else scale * 1e-5
        if b.polar:
            out.append(x * unit * cmath.exp(1j * (y if b.ph_float else y * 1e-4)))
        else:
            out.append(complex(x, y) * unit)
    return out


def _frequency(b: Block, data: bytes, at: int) -> tuple[float, float]:
    """(FREQ Hz, DFREQ Hz/s) of block b at byte `at`: integers the deviation from FNOM in
    mHz and the ROCOF in Hz/s x 100, floating point the actual frequency and the ROCOF
    (C37.118.2-2011 Table 6)."""
    if not b.fr_float:
        mhz, dfreq = struct.unpack_from(">hh", data, at)
        return b.fnom + mhz / MHZ_PER_HZ, dfreq / DFREQ_PER_HZ_S
    f, dfreq = struct.unpack_from(">ff", data, at)
    if not abs(f - b.fnom) <= FREQ_SPAN_HZ:
        raise InputError(
            f"PMU {b.station}: floating-point FREQ (FORMAT bit 3) {f:g} Hz is not within FNOM "
            f"{b.fnom:g} +- {FREQ_SPAN_HZ} Hz: C37.118.2-2011 Table 6 makes it the actual "
            "frequency (pyc37 writes the deviation from FNOM there)"
        )
    if not math.isfinite(dfreq):
        raise InputError(f"PMU {b.station}: floating-point DFREQ {dfreq} is not a number")
    return f, dfreq


#: bounds beyond which a received value is no measurement (a byte error the CRC did not
#: catch, a PMU's fault): a voltage magnitude (pu of the bus's rated kV: insulation fails
#: far below), a current magnitude (pu on the system base: 100 GW on 100 MVA), a ROCOF
#: (Hz/s: the span of the integer DFREQ, C37.118.2-2011 Table 6)
V_PLAUSIBLE_PU = 3.0
I_PLAUSIBLE_PU = 1000.0
ROCOF_PLAUSIBLE_HZ_S = 327.67
#: a frequency this far from nominal (Hz) is no measurement either: twice the widest
#: range C37.118.1 has PMUs measure in (M class, FNOM +- 5 Hz), 0.17 pu of speed at 60 Hz,
#: beyond any machine still in step; one sample of 75 Hz on a 60 Hz case (a byte error)
#: had the raw estimator command every device for its frame
FREQ_PLAUSIBLE_HZ = 10.0
#: the reason `plausible` gives
IMPLAUSIBLE = (
    f"|V| > {V_PLAUSIBLE_PU:g} pu, |I| > {I_PLAUSIBLE_PU:g} pu, |ROCOF| > "
    f"{ROCOF_PLAUSIBLE_HZ_S:g} Hz/s or a frequency more than {FREQ_PLAUSIBLE_HZ:g} Hz from "
    "nominal"
)


def plausible(frames, f0_hz: float):
    """Frames (a `Frame`, or `pmu.Frames` held column by column) with each PMU value that
    no measurement gives (beyond `V_PLAUSIBLE_PU`, `I_PLAUSIBLE_PU`,
    `ROCOF_PLAUSIBLE_HZ_S`, or a frequency more than `FREQ_PLAUSIBLE_HZ` from nominal)
    made invalid, its values NaN, as a STAT saying absent data makes them: one such
    sample (1e30 pu, or a voltage a million times its value) drove an estimator to
    1e28 Hz.

    Parameters
    ----------
    frames : Frame or pmu.Frames
        Parsed (`parse_frame`).
    f0_hz : float
        The stream's nominal frequency (Hz; `StreamConfig.f0`).

    Returns
    -------
    (Frame or pmu.Frames, int)
        The frames, of the same type, and how many PMU values were made invalid (counted
        as `IMPLAUSIBLE` in `Received.flagged`).
    """
    with np.errstate(invalid="ignore"):
        bad = frames.valid & (
            (np.abs(frames.v) > V_PLAUSIBLE_PU)
            | (np.abs(frames.i) > I_PLAUSIBLE_PU)
            | (np.abs(frames.rocof) > ROCOF_PLAUSIBLE_HZ_S)
            | (np.abs(frames.freq - f0_hz) > FREQ_PLAUSIBLE_HZ)
        )
    n = int(np.count_nonzero(bad))
    if not n:
        return frames, 0
    nan = np.where(bad, np.nan, 1.0)
    kept = (frames.v * nan, frames.i * nan, frames.freq * nan, frames.rocof * nan)
    return type(frames)(frames.t, frames.valid & ~bad, *kept), n


def flags(cfg2, data: bytes) -> list[str]:
    """Why each PMU's values in a data frame are not used, by its STAT (`unusable`) or,
    STAT aside, the frame's FRACSEC time quality (`time_unusable`) or an absent-data value
    in its fields (`marked`); '' for those used.

    Parameters
    ----------
    cfg2 : pyc37 ConfigFrame2
        The stream's configuration frame.
    data : bytes
        A data frame of the stream (`check_data_frame` passed).

    Returns
    -------
    list of str
        One per PMU, in block order.
    """
    out, at, clock = [], 14, time_unusable(data)
    for b in blocks(cfg2):
        stat = unusable(int.from_bytes(data[at : at + 2], "big"))
        out.append(stat or clock or marked(b, data, at + 2))
        at += b.size
    return out


#: C37.118.2-2011 frame types (SYNC bits 6-4)
FRAME_TYPES = {
    0: "data frame",
    1: "header frame",
    2: "CFG-1",
    3: "CFG-2",
    4: "command frame",
    5: "CFG-3",
}


def frame_kind(data: bytes) -> str:
    """A frame's type as named in messages (SYNC bits 6-4, C37.118.2-2011 Table 2).

    Parameters
    ----------
    data : bytes
        One frame (at least its SYNC word).

    Returns
    -------
    str
        ``data frame``, ``header frame``, ``CFG-1``, ``CFG-2``, ``command frame``,
        ``CFG-3``, or ``frame of type N`` for the types the standard reserves.
    """
    kind = data[1] >> 4 & 0x7
    return FRAME_TYPES.get(kind, f"frame of type {kind}")


#: The CFG-2 fields (C37.118.2-2011 Table 8) as pyc37's getters read them, in frame order
CONFIG_FIELDS = (
    ("IDCODE", "get_id_code"),
    ("TIME_BASE", "get_time_base"),
    ("NUM_PMU", "get_num_pmu"),
    ("STN", "get_station_name"),
    ("the PMUs' IDCODE", "get_stream_id_code"),
    ("FORMAT", "get_data_format"),
    ("PHNMR", "get_phasor_num"),
    ("ANNMR", "get_analog_num"),
    ("DGNMR", "get_digital_num"),
    ("CHNAM", "get_channel_names"),
    ("PHUNIT", "get_ph_units"),
    ("ANUNIT", "get_analog_units"),
    ("DIGUNIT", "get_digital_units"),
    ("FNOM", "get_fnom"),
    ("CFGCNT", "get_cfg_count"),
    ("DATA_RATE", "get_data_rate"),
)


def config_change(old, new) -> str:
    """The first CFG-2 field in which `new` differs from `old` (both as pyc37 reads them),
    or '' if none does: a CFG-2 resent with only its time stamp new is the same.

    Parameters
    ----------
    old, new : pyc37 ConfigFrame2
        The CFG-2 in use and one received later.

    Returns
    -------
    str
        The field's name (``FORMAT``, ``DATA_RATE``) with both values, or ''.
    """
    for name, get in CONFIG_FIELDS:
        if (was := getattr(old, get)()) != (now := getattr(new, get)()):
            return f"{name} {now} where the CFG-2 in use has {was}"
    return ""


def check_stream_frame(cfg2, data: bytes) -> bool:
    """Check a frame received after 'start' on the stream `cfg2` describes: a data frame
    as `check_data_frame` does; any other frame's CRC; a CFG-2 must be `cfg2` resent (its
    time stamp aside): the data frames after one that differs would be read by a layout
    that is not theirs.

    Parameters
    ----------
    cfg2 : pyc37 ConfigFrame2
        The stream's configuration frame, by which its data frames are read.
    data : bytes
        One whole frame (SYNC and FRAMESIZE read, at least 16 bytes).

    Returns
    -------
    bool
        True for a data frame, False for another frame (a header, CFG-1, CFG-3 or
        command frame, or the same CFG-2), which carries no measurement.

    Raises
    ------
    InputError
        As `check_data_frame`; another frame whose CRC fails; a CFG-2 that is not
        readable or differs from `cfg2` (naming the field, `config_change`).
    """
    kind = frame_kind(data)
    if kind == "data frame":
        check_data_frame(cfg2, data)
        return True
    if not _pyc37().CommonFrame._check_crc(data):
        raise InputError(
            f"C37.118.2 {kind} not readable: CRC failed (its bytes or its FRAMESIZE damaged)"
        )
    if kind == "CFG-2" and (change := config_change(cfg2, read_config(data, "the CFG-2"))):
        raise InputError(
            f"a CFG-2 that changes the stream's configuration ({change}): a change "
            "mid-stream is not followed (receive the stream again)"
        )
    return False


def check_data_frame(cfg2, data: bytes) -> None:
    """Refuse bytes that are not a data frame of the stream `cfg2` describes: the checks
    every reader of data frames makes (`parse_frame`, a stream received over TCP, a
    recording served again), in one place.

    Parameters
    ----------
    cfg2 : pyc37 ConfigFrame2
        The stream's configuration frame.
    data : bytes
        One whole frame (SYNC and FRAMESIZE read, at least 16 bytes).

    Raises
    ------
    InputError
        A CRC that fails, another frame type, a data frame of another IDCODE than cfg2's,
        or whose FRAMESIZE is not the size cfg2 gives a data frame (a frame padded or cut,
        which pyc37 reads without a word), or whose FRACSEC count is not below cfg2's
        TIME_BASE (`check_fracsec`).
    """
    if not _pyc37().CommonFrame._check_crc(data):
        raise InputError(
            "C37.118.2 data frame not readable: CRC failed (its bytes or its FRAMESIZE damaged)"
        )
    if (kind := frame_kind(data)) != "data frame":
        raise InputError(f"C37.118.2: a {kind}, not a data frame")
    if (idcode := int.from_bytes(data[4:6], "big")) != cfg2.get_id_code():
        raise InputError(
            f"a data frame of IDCODE {idcode}, not the stream's {cfg2.get_id_code()} (its CFG-2's)"
        )
    if (size := int.from_bytes(data[2:4], "big")) != (want := data_frame_size(cfg2)):
        raise InputError(
            f"a data frame of FRAMESIZE {size} bytes, where its CFG-2 makes one {want} bytes"
        )
    check_fracsec(data, cfg2.get_time_base(), "a data frame")


def check_fracsec(data: bytes, time_base: int, what: str, base: str = "its CFG-2's") -> None:
    """Refuse a frame whose FRACSEC count (bytes 11-13) is not below TIME_BASE: the count
    is the fraction of one second of its time stamp (C37.118.2-2011 6.2.2), so a count of
    TIME_BASE or more stamps no instant of its SOC (a second's rollover written as
    (SOC, TIME_BASE) instead of (SOC + 1, 0), or a count beyond it).

    Parameters
    ----------
    data : bytes
        The frame (at least 14 bytes).
    time_base : int
        Its stream's TIME_BASE (FRACSEC counts per second, the CFG-2's).
    what : str
        The frame, the message's start (``a data frame``, ``its CFG-2``).
    base : str, optional
        Whose TIME_BASE it is, for the message (``its``: a CFG-2's own).

    Raises
    ------
    InputError
        The count not below `time_base`, naming both.
    """
    if (count := int.from_bytes(data[11:14], "big")) >= time_base:
        raise InputError(
            f"{what} stamped with FRACSEC count {count}, not below {base} TIME_BASE "
            f"{time_base}: the count is a fraction of one second (C37.118.2-2011 6.2.2)"
        )


def check_data_frames(cfg2, data, what: str) -> None:
    """`check_data_frame` on every frame of a stream or recording, before any is used.

    Parameters
    ----------
    cfg2 : pyc37 ConfigFrame2
        The stream's configuration frame.
    data : sequence of bytes
        The data frames, in order.
    what : str
        Their source, for the message (``RECORDING r.c37``).

    Raises
    ------
    InputError
        At the first frame refused: what, the frame's number (1: the first data frame)
        and why.
    """
    for k, frame in enumerate(data):
        try:
            check_data_frame(cfg2, frame)
        except InputError as exc:
            raise InputError(f"{what}: data frame {k + 1}: {exc}") from None


def data_frame_size(cfg2) -> int:
    """The size of a data frame of a stream (C37.118.2-2011 Table 5): 16 bytes of SYNC,
    FRAMESIZE, IDCODE, SOC, FRACSEC and CHK, and per PMU its STAT, phasors, FREQ, DFREQ,
    analog values and digital words in the sizes its FORMAT gives.

    Parameters
    ----------
    cfg2 : pyc37 ConfigFrame2
        The stream's configuration frame.

    Returns
    -------
    int
        Bytes.
    """
    return 16 + sum(b.size for b in blocks(cfg2))


def reporting_instant(t: float, rate: int, time_base: int) -> float:
    """A received time stamp t (s) snapped to the reporting instant k / rate it stands for
    when it is within one FRACSEC count (1 / time_base s) of it (as a PDC rounds time
    stamps to its frame rate): a TIME_BASE of 1 us cannot write k / 60 s exactly, and the
    estimators and their error windows should see the instants the PMU reported at.
    Other time stamps are kept."""
    k = round(t * rate)
    return k / rate if abs(t - k / rate) <= 1.0 / time_base else float(t)


def codec(cfg: StreamConfig):
    """frame -> the frame as a receiver gets it: encoded as a data frame of the stream and
    parsed back (float32 phasors, FREQ to 1 mHz, DFREQ to 0.01 Hz/s), with no transport
    in between: the in-process twin of a stream sent over TCP or recorded."""
    cfg2 = config_frame(cfg)
    return lambda frame: parse_frame(cfg, cfg2, data_frame(cfg, cfg2, frame))


def on_wire(cfg: StreamConfig, frames) -> list[Frame]:
    """`frames` each through `codec`."""
    return list(map(codec(cfg), frames))


def record(path, cfg: StreamConfig, frames) -> int:
    """Write a recording: the CFG-2 frame then one data frame per `pmu.Frame` of
    `frames`; returns the number of data frames.  Written whole or not at all
    (`stabctl.parallel.atomic_write`).

    Raises
    ------
    InputError
        A frame whose time stamp is not a reporting instant of cfg's rate (k / rate s: a
        50 frames/s stream recorded under a CFG-2 of 60 was written, and read back by
        `replay`, without a word), naming it.
    """
    cfg2 = config_frame(cfg)
    n = 0

    def write(fh) -> None:
        nonlocal n
        fh.write(cfg2.convert2bytes())
        for frame in frames:
            k = frame.t * cfg.rate
            if abs(k - round(k)) > 1e-6 * max(1.0, abs(k)):
                raise InputError(
                    f"record({path}): frame {n + 1} at t = {frame.t:.6g} s is no reporting "
                    f"instant of the stream's {cfg.rate} frames/s (k / {cfg.rate} s): frames "
                    "of another rate than its configuration's"
                )
            fh.write(data_frame(cfg, cfg2, frame))
            n += 1

    atomic_write(path, write, mode="wb")
    return n


def split_frames(data: bytes, what: str = "C37.118.2 recording") -> list[bytes]:
    """The frames of a byte string of consecutive C37.118.2 frames (each starts with
    SYNC 0xAA and gives its FRAMESIZE in bytes 2-3); what: the bytes' source, for
    messages (a recording's path).

    Raises
    ------
    InputError
        A frame not starting with 0xAA, or cut short, naming what and its byte offset.
    """
    out, at = [], 0
    while at < len(data):
        if data[at] != 0xAA or at + 4 > len(data):
            raise _no_sync(what, at)
        size = int.from_bytes(data[at + 2 : at + 4], "big")
        if size < 16 or at + size > len(data):
            raise InputError(f"{what}: frame at byte {at} cut short")
        out.append(data[at : at + size])
        at += size
    return out


def _no_sync(what: str, at: int) -> InputError:
    """The error of bytes `what` holding no frame SYNC (0xAA) at byte `at`."""
    return InputError(f"{what}: no frame SYNC at byte {at} (not a C37.118.2 recording)")


def frame_time(data: bytes, cfg2) -> float:
    """A frame's time stamp, SOC + FRACSEC / TIME_BASE (s, UNIX), read from its bytes
    (C37.118.2-2011 Table 2: SOC bytes 6-9, FRACSEC's count bytes 11-13), TIME_BASE its
    stream's (the CFG-2 `cfg2`, as pyc37 reads it)."""
    count = int.from_bytes(data[11:14], "big")
    return int.from_bytes(data[6:10], "big") + count / cfg2.get_time_base()


#: FRACSEC's time quality bits (C37.118.2-2011 Table 3): leap second pending (bit 4),
#: occurred (bit 5), direction (bit 6: 1 a second deleted)
LEAP_PENDING, LEAP_OCCURRED, LEAP_DELETED = 0x10, 0x20, 0x40


def leap_offsets(data, cfg2) -> np.ndarray:
    """The seconds a positive leap second puts between each data frame's time stamp and
    the time elapsed: SOC counts UTC seconds without leap seconds (C37.118.2-2011 6.2.2),
    so across an inserted leap second one second's SOC comes twice.  A frame stamped in
    the same second (SOC) as the one before it, earlier by more than half a second (the
    second's SOC again from its rollover: a frame repeated, swapped or replayed steps back
    less), where the frame before flags a leap second pending or the frame a leap second
    occurred (FRACSEC's time quality, Table 3; neither flagging a deleted one), in the
    last second of a UTC day or the first of the next (the only places a leap second is
    inserted), is 1 s later than stamped, as is every frame after it.

    Parameters
    ----------
    data : sequence of bytes
        The data frames of one stream, in order.
    cfg2 : pyc37 ConfigFrame2
        Their stream's configuration frame (its TIME_BASE).

    Returns
    -------
    numpy.ndarray of int
        Per frame, 0 before the leap second and 1 from the repeated second on.
    """
    base = cfg2.get_time_base()
    if len(data) < 2:
        return np.zeros(len(data), np.int64)
    stamps = np.array(
        [int.from_bytes(d[6:10], "big") * base + int.from_bytes(d[11:14], "big") for d in data],
        np.int64,
    )
    quality = np.array([d[10] for d in data], np.int64)
    back = np.diff(stamps)
    flagged = (quality[:-1] & LEAP_PENDING != 0) | (quality[1:] & LEAP_OCCURRED != 0)
    inserted = (quality[:-1] | quality[1:]) & LEAP_DELETED == 0
    # the second's SOC again, from its rollover: within half a second of the frame before
    # once the second is added (a repeated or swapped frame steps back less)
    repeat = (stamps[1:] // base == stamps[:-1] // base) & (back + base <= base // 2)
    # only at the end of a UTC day (ITU-R TF.460): the second repeated is the day's last
    # (23:59:59) or the next day's first (00:00:00, POSIX's reading of 23:59:60); a
    # "leap second" flagged at 22:13:23 was taken for one (round 40: a replayed second
    # re-timed 1 s later without a word), now its stamps go back (`order_faults`)
    day_end = np.isin(stamps[1:] // base % 86400, (0, 86399))
    leap = (back <= 0) & (back > -base) & repeat & flagged & inserted & day_end
    return np.concatenate([[0], np.cumsum(leap)])


def stamp_times(data, cfg2, leaps: int = 0) -> np.ndarray:
    """Each data frame's time stamp (`frame_time`, s, UNIX) and the positive leap seconds
    before it in its stream (`leap_offsets`): the time the frames were measured at, in
    order across a leap second.  The one reading of elapsed time, of a recording whole or
    of a stream as each frame comes (`c37_tcp.receive`: the frame with the one before it,
    and the leap seconds before that).

    Parameters
    ----------
    data : sequence of bytes
        The data frames of one stream, in order.
    cfg2 : pyc37 ConfigFrame2
        Their stream's configuration frame.
    leaps : int, optional
        Positive leap seconds in the stream before the first of `data` (0: `data` starts
        the stream).

    Returns
    -------
    numpy.ndarray
        The times (s).
    """
    times = np.array([frame_time(d, cfg2) for d in data], float)
    return times + leaps + leap_offsets(data, cfg2)


def order_faults(data, cfg2, what: str, numbers=None) -> list[tuple[int, str]]:
    """The time stamps `stabctl.estimation.sources.check_order` refuses: repeated, going
    back, or off the reporting instants of the CFG-2's DATA_RATE.

    Parameters
    ----------
    data : sequence of bytes
        The data frames, in order.
    cfg2 : pyc37 ConfigFrame2
        Their stream's configuration frame.
    what : str
        Their source, the messages' start (none if empty).
    numbers : sequence of int, optional
        The frames' numbers in their stream (default 1, 2, ...): `next_frame_fault`
        checks a frame with the first and the last before it; then the messages do not
        count the frames with each fault.

    Returns
    -------
    list of (int, str)
        Each fault as (the index in `data` of the first frame with it, the message naming
        that frame and its time stamp): off the DATA_RATE grid, then repeated or backward
        time stamps.
    """
    number = list(range(1, len(data) + 1)) if numbers is None else list(numbers)
    lead = f"{what}: " if what else ""

    def many(n: int) -> str:
        return f"; {n} such frame(s)" if numbers is None else ""

    base, rate = cfg2.get_time_base(), cfg2.get_data_rate()
    counts = np.array([int.from_bytes(d[11:14], "big") for d in data], np.int64)
    stamps = np.array([int.from_bytes(d[6:10], "big") for d in data], np.int64) * base + counts
    stamps += leap_offsets(data, cfg2) * base  # a leap second's repeated SOC is no repeat
    if rate == 0:
        return [(0, f"{lead}its CFG-2's DATA_RATE is 0, no rate (C37.118.2-2011 Table 8)")]
    faults = []
    if rate < 0 and len(data):
        # a period: one frame every -rate s, each at a second's rollover (within a count)
        soc = stamps // base - stamps[0] // base
        off = np.minimum(counts, base - counts) > 1
        if (bad := np.flatnonzero(off | (soc % -rate != 0))).size:
            k = int(bad[0])
            faults.append(
                (
                    k,
                    f"{lead}data frame {number[k]} is stamped {counts[k] / base:.6f} s into "
                    f"its second, {int(soc[k])} s after the first, not a reporting instant of "
                    f"its CFG-2's DATA_RATE {rate} (negative: one frame every {-rate} s, at a "
                    f"second's rollover, C37.118.2-2011 Table 8){many(bad.size)}: a stream at "
                    "another rate than its CFG-2 says",
                )
            )
    if rate > 0 and len(data):
        # counts * rate / base is the instant's number in its second: an integer, within
        # one count (rate / base of a frame) of one
        off = np.abs(counts * rate - np.round(counts * rate / base).astype(np.int64) * base)
        if (bad := np.flatnonzero(off > rate)).size:
            k = int(bad[0])
            faults.append(
                (
                    k,
                    f"{lead}data frame {number[k]} is stamped {counts[k] / base:.6f} s into "
                    f"its second, not a reporting instant of its CFG-2's DATA_RATE {rate} (k / "
                    f"{rate} s into each second, within one FRACSEC count){many(bad.size)}: a "
                    "stream at another rate than its CFG-2 says",
                )
            )
    slot = _instants(stamps, base, rate)
    if (bad := np.flatnonzero(np.diff(slot) <= 0)).size:
        k = int(bad[0]) + 1
        how, note = _order_fault(stamps, slot, k, base, number if numbers is None else None)
        # flagged, yet not one inserted second (`leap_offsets` reads those across)
        leap = any(d[10] & (LEAP_PENDING | LEAP_OCCURRED) for d in data[max(k - 1, 0) : k + 1])
        why = (
            ": its FRACSEC flags a leap second (C37.118.2-2011 Table 3), but the stamps are "
            "not one second inserted (the second's SOC again from its rollover, more than "
            "half a second and less than 1 s back): a frame repeated or out of order, a "
            "deleted second, or more than the leap second, is not read across; split the "
            "stream there"
            if leap
            else ""
        )
        faults.append(
            (
                k,
                f"{lead}data frame {number[k]} {how} frame {number[k - 1]} "
                f"({frame_time(data[k - 1], cfg2):.6f} s, UNIX){note}{many(bad.size)}{why}",
            )
        )
    return faults


def _instants(stamps: np.ndarray, base: int, rate: int) -> np.ndarray:
    """The reporting instant each time stamp (FRACSEC counts since the epoch, a
    TIME_BASE `base` a second) stands for, numbered in frames of DATA_RATE `rate` since
    the epoch (negative rate: whole seconds): the stamp rounded as `reporting_instant`
    rounds it, in integers (no int64 overflow at a TIME_BASE of 2**24)."""
    soc, counts = stamps // base, stamps % base
    if rate < 0:
        return soc + (2 * counts >= base)
    return soc * rate + (2 * counts * rate + base) // (2 * base)


def _order_fault(stamps, slot, k: int, base: int, number) -> tuple[str, str]:
    """How frame k's time stamp fails to follow frame k - 1's (`order_faults`), and a
    note: the same stamp, another on the same reporting instant (within a FRACSEC count
    of it: its data would replace the other's), or one going back; with the frames'
    `number` (a whole stream), a frame k - 1 ahead of both its neighbours is named in the
    note as the one out of place."""
    if stamps[k] == stamps[k - 1]:
        return "repeats the time stamp of", ""
    if slot[k] == slot[k - 1]:
        return "is on the reporting instant of", (
            f", {(stamps[k] - stamps[k - 1]) / base:.6g} s after it, within one FRACSEC "
            "count: its data would replace that frame's"
        )
    if number is not None and k >= 2 and slot[k] > slot[k - 2]:
        return "goes back from the time stamp of", (
            f"; frame {number[k - 1]} is the one out of order, ahead of both its "
            f"neighbours by {(stamps[k - 1] - stamps[k]) / base:.6g} s or more"
        )
    return "goes back from the time stamp of", ""


def next_frame_fault(data, frame: bytes, cfg2) -> str | None:
    """The time-stamp fault (`order_faults`) of a data frame arriving after `data`, whose
    stamps are in order: a receiver's check of each frame as it comes (`pmu record`
    stops at the first frame refused).

    Parameters
    ----------
    data : sequence of bytes
        The data frames received before it, in order.
    frame : bytes
        The data frame that came.
    cfg2 : pyc37 ConfigFrame2
        Their stream's configuration frame.

    Returns
    -------
    str or None
        The message naming the frame (by its number in the stream) and its fault, or None
        if its time stamp follows the one before on the DATA_RATE grid.
    """
    # the first (the grid), the last, the new; no slice of `data` past its ends, which
    # would copy every frame received at each frame
    return ends_fault(data[0] if data else None, data[-1] if data else None, len(data), frame, cfg2)


def ends_fault(first: bytes | None, last: bytes | None, n: int, frame: bytes, cfg2) -> str | None:
    """`next_frame_fault` of a frame arriving after n data frames of which only the
    first and the last are kept (None for none): its time stamp on the DATA_RATE grid of
    the first, after the last.

    Parameters
    ----------
    first, last : bytes or None
        The first and the last data frame received before it.
    n : int
        Data frames received before it.
    frame : bytes
        The data frame that came.
    cfg2 : pyc37 ConfigFrame2

    Returns
    -------
    str or None
    """
    window = [*([first] if n else []), *([last] if n > 1 else []), frame]
    numbers = [1, n, n + 1][-len(window) :]
    faults = order_faults(window, cfg2, "", numbers)
    return next((why for k, why in faults if k == len(window) - 1), None)


def recorded_frames(path) -> tuple:
    """(CFG-2 as pyc37 reads it, the data frames' bytes) of a recording.  The frames
    after the first that are not data frames are checked as a receiver checks them on a
    stream (`check_stream_frame`: their CRC; a CFG-2 must be the first one resent, its
    time stamp aside) and left out: a header, CFG-1, CFG-3 or command frame carries no
    measurement, and the data frames after a changed CFG-2 would be read by a layout
    that is not theirs.

    Raises
    ------
    InputError
        An empty file, a first frame that is not a configuration frame, or a broken one
        (`split_frames`); a later frame other than a data frame whose CRC fails, or a
        CFG-2 that changes the configuration, named by its place (the data frames before
        it) and the field that changed (`config_change`).
    """
    what = f"C37.118.2 recording {path}"
    with open(path, "rb") as fh:  # round 42: 200 MB of NUL bytes read whole (400 MiB) first
        head = fh.read(4)
    if head and head[0] != 0xAA:
        raise _no_sync(what, 0)
    frames = split_frames(Path(path).read_bytes(), what)
    if not frames:
        raise InputError(f"{path}: empty C37.118.2 recording")
    cfg2, data = read_config(frames[0], f"{path}: first frame"), []
    for k, frame in enumerate(frames[1:]):
        if frame_kind(frame) == "data frame":
            data.append(frame)
            continue
        try:
            check_stream_frame(cfg2, frame)
        except InputError as exc:
            raise InputError(
                f"{path}: frame {k + 2}, after data frame {len(data)}: {exc}"
            ) from None
    return cfg2, data


def read_config(data: bytes, what: str):
    """A CFG-2 frame's bytes as pyc37 reads them (``ConfigFrame2``): the one reading of
    a CFG-2 wherever one is expected (a recording's first frame, a server's or a plant's
    answer to 'cfg2', one resent mid-stream).  Its frame type (SYNC bits 6-4) is checked
    first, and only a CFG-2 is handed to pyc37's CFG-2 parser: a CFG-1 has the CFG-2's
    layout but gives what a PMU can report, not what it sends (C37.118.2-2011), which
    pyc37 read as a CFG-2 without a word, and pyc37's parser of any frame recursed
    without end on a CFG-3.

    Parameters
    ----------
    data : bytes
        The frame.
    what : str
        Its source, for messages (``its CFG-2``, ``r.c37: first frame``).

    Returns
    -------
    pyc37 ConfigFrame2

    Raises
    ------
    InputError
        A frame of another type (``... is a CFG-3 (SYNC frame type 5), not the CFG-2
        expected``), a CFG-2 that is not readable (its CRC, its fields), or whose FRACSEC
        count is not below its TIME_BASE (`check_fracsec`), named by ``what``.
    """
    if len(data) >= 2 and (kind := frame_kind(data)) != "CFG-2":
        raise InputError(
            f"{what} is a {kind} (SYNC frame type {data[1] >> 4 & 0x7}), not the CFG-2 expected"
        )
    f = _pyc37()
    try:  # pyc37 turns any error of its parse (a frame cut, a field out of range) into this
        cfg2 = f.ConfigFrame2.convert2frame(data)
    except f.FrameError as exc:
        raise InputError(f"{what} is not a configuration frame: {exc}") from None
    check_fracsec(data, cfg2.get_time_base(), what, "its")
    # its time stamp as sent: pyc37 keeps 23 of FRACSEC's 24 bits of count
    cfg2.stabctl_stamp = (
        int.from_bytes(data[6:10], "big"),
        int.from_bytes(data[11:14], "big") / cfg2.get_time_base(),
    )
    return cfg2


def frame_interval(cfg2) -> float:
    """The time between two reporting instants of a CFG-2's stream, s (DATA_RATE frames
    a second, or a negative DATA_RATE's seconds a frame; C37.118.2-2011 Table 8)."""
    rate = cfg2.get_data_rate()
    return 1.0 / rate if rate > 0 else float(-rate)


def config_stamp(cfg2) -> tuple[int, float]:
    """A CFG-2's time stamp, SOC and FRACSEC / TIME_BASE: t = 0 of the stream it
    describes (the frames' times, the ``--until`` end and the gaps are read from it).

    Parameters
    ----------
    cfg2 : pyc37 ConfigFrame2
        The configuration frame, as `read_config` reads it (its bytes' time stamp) or as
        `config_frame` builds it.

    Returns
    -------
    (int, float)
        The SOC (s, UNIX) and the fraction of that second (s, below 1); apart, as a
        fraction added to a SOC of today would be rounded to 0.24 us.
    """
    if (stamp := getattr(cfg2, "stabctl_stamp", None)) is not None:
        return stamp
    return int(cfg2.get_soc()), cfg2.get_frasec()[0] / cfg2.get_time_base()


def replay(path, cfg: StreamConfig) -> list[Frame]:
    """The frames of a recording (`record`'s, or any capture of this stream), in file
    order; cfg: the stream the recording's CFG-2 must describe (same PMUs and rate).

    Raises
    ------
    InputError
        No configuration frame first, one that does not describe cfg (`check_config`,
        naming the field), a data frame that is not readable, or time stamps off the
        reporting instants of its DATA_RATE, repeated or going back (`order_faults`).
    """
    cfg2, data = recorded_frames(path)
    try:
        check_config(cfg2, cfg)
    except InputError as exc:
        raise InputError(f"{path}: {exc}") from None
    if faults := order_faults(data, cfg2, str(path)):
        raise InputError(faults[0][1])
    return [
        f._replace(t=f.t + int(leap))
        for f, leap in zip((parse_frame(cfg, cfg2, d) for d in data), leap_offsets(data, cfg2))
    ]
