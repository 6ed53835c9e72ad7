"""Where the estimators' PMU frames come from, whatever the transport: drawn in process
(`stabctl.estimation.pmu.measure`, the default of every study), read from a recording of
C37.118.2 frames (`stabctl.estimation.c37.record`, `stabctl pmu record`), or received over
TCP from one or more C37.118.2 servers (PMUs, a PDC, `stabctl pmu serve`), the streams
merged by time stamp into one `pmu.Frame` per reporting instant.

A source is written ``tcp://HOST:PORT[,HOST:PORT...]`` or as a file path.  Each stream's
CFG-2 names its PMUs by station name (a `pmu.PMU` label, ``B3:G1``); every PMU of the run
must be in exactly one stream.  Time: t = 0 of the run is the CFG-2 frame's own time
stamp (SOC), as `c37.config_frame` writes it; of several streams, the earliest CFG-2's:
their data frames are merged on the time stamps as sent (one clock), and streams that
share none are refused, their offset named (`merge`).
"""

from __future__ import annotations

import collections
import dataclasses
import threading
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from stabctl.errors import InputError
from stabctl.estimation import c37
from stabctl.estimation.c37_tcp import hostport, port_number, split_hostport
from stabctl.estimation.pmu import Frame, Frames

TCP = "tcp://"


@dataclass(frozen=True)
class Source:
    """A frame source: a recording's path, or the (host, port) of each TCP stream.

    Attributes
    ----------
    path : pathlib.Path or None
        The recording (None for TCP).
    servers : tuple of (str, int)
        The TCP servers (empty for a recording).
    """

    path: Path | None = None
    servers: tuple = ()

    def __str__(self) -> str:
        """As written to `parse_source`, consecutive ports of a host as a range."""
        if self.path is not None:
            return str(self.path)
        from itertools import groupby

        from stabctl.io.inputs import number_ranges

        items = [
            hostport(host, a) + (f"-{b}" if b > a else "")
            for host, ports in groupby(self.servers, key=lambda hp: hp[0])
            for a, b in number_ranges(p for _, p in ports)
        ]
        return TCP + ",".join(items)


def parse_source(text: str) -> Source:
    """The `Source` of ``tcp://HOST:PORT[,HOST:PORT...]`` (a port range ``P1-P2`` for
    one server per port, as `stabctl pmu serve --each-pmu` serves; an IPv6 address in
    brackets, ``[::1]:4712``) or of a recording's path.

    Raises
    ------
    InputError
        A TCP address without a port in 1..65535 (or an empty range), ``tcp://`` written
        again inside the list, a server given twice, or a recording that is not a regular
        file of at most `stabctl.io.inputs.MAX_INPUT_BYTES`.
    """
    if not text.startswith(TCP):
        from stabctl.io.inputs import input_file

        if not Path(text).exists():
            raise InputError(f"--source {text}: no such recording (or write tcp://HOST:PORT)")
        return Source(path=input_file(text, "--source"))
    servers: list[tuple[str, int]] = []
    for item in text[len(TCP) :].split(","):
        if item.startswith(TCP):
            raise InputError(
                f"--source {text}: {item!r}: write tcp:// once, before the list "
                "(tcp://HOST:PORT,HOST:PORT)"
            )
        try:
            host, ports = split_hostport(item)
        except InputError as exc:
            raise InputError(f"--source {text}: {exc}") from None
        first, _, last = ports.partition("-")
        try:
            if not host:
                raise InputError("expected HOST:PORT")
            span = range(port_number(first), port_number(last or first) + 1)
        except InputError as exc:
            why = " is not HOST:PORT" if str(exc) == "expected HOST:PORT" else f": {exc}"
            raise InputError(f"--source {text}: {item!r}{why}") from None
        if not span:
            raise InputError(f"--source {text}: {item!r}: the port range {ports} is empty")
        if twice := [p for p in span if (host, p) in servers]:
            raise InputError(f"--source {text}: {hostport(host, twice[0])} given twice")
        servers += [(host, p) for p in span]
    return Source(servers=tuple(servers))


@dataclass(frozen=True)
class Received:
    """The merged frames of a source and what came of them.

    Attributes
    ----------
    frames : Frames
        One per time stamp any stream sent, in order, one column per PMU of the run
        (held column by column).
    streams : int
        Streams merged.
    data_frames : int
        Data frames received over all streams.
    absent : int
        PMU values whose STAT makes them unusable (`c37.unusable`: absent data, PMU
        error, test mode, PMU sync lost, sorted by arrival): not used, as values lost.
    missing : int
        PMU values of a time stamp some streams sent and this PMU's did not, and of each
        reporting instant of a gap filled (`gaps`).
    short : tuple of str
        Each stream that stopped before its stated end (`c37_tcp.End`), with what cut it;
        empty: every stream whole.
    unsent : tuple of Unsent
        Each stream that sent no frame at time stamps other streams sent (its PMUs'
        values there among `missing`), in stream order; empty for one stream.
    flagged : dict
        `absent` by reason (`c37.STAT_UNUSABLE`'s, `c37.TIME_QUALITY_FAULT`'s), the
        reasons that occurred only.
    gaps : tuple of Gap
        Each run of reporting instants (k / DATA_RATE) between the first and the last
        time stamp that no stream sent, in order.  One of at most `FILL_S` s is in
        `frames` as frames whose every value is missing (the estimators predict across
        it frame by frame, as across lost frames); a longer one is not (`breaks`).
    breaks : tuple of int
        The index in `frames` of the first frame after each gap longer than `FILL_S` s:
        an estimator fed the frames starts again there (`closed_loop.track`), as a
        filter predicting across it would give figures of no meaning.
    """

    frames: Frames
    streams: int
    data_frames: int
    absent: int
    missing: int
    short: tuple = ()
    flagged: dict = dataclasses.field(default_factory=dict)
    gaps: tuple = ()
    breaks: tuple = ()
    unsent: tuple = ()

    @property
    def gap_frames(self) -> int:
        """Reporting instants no stream sent, over every gap."""
        return sum(g.frames for g in self.gaps)

    def summary(self) -> dict:
        """The counts, for a report (JSON)."""
        return {
            "streams": self.streams,
            "frames": len(self.frames),
            "data_frames": self.data_frames,
            "absent": self.absent,
            "flagged": dict(self.flagged),
            "missing": self.missing,
            "gaps": [dataclasses.asdict(g) for g in self.gaps],
            "unsent": [dataclasses.asdict(u) for u in self.unsent],
            "short": list(self.short),
        }


#: longest gap (s) of a source's reporting instants filled with frames whose every value is
#: missing; a longer one breaks the frames in two (`Received.breaks`)
FILL_S = 1.0


def longest_unusable(frames, labels) -> str:
    """The longest stretch over which one PMU's values were all unusable (invalid: absent,
    flagged, a clock failure, a gap filled with missing values), if longer than `FILL_S`
    s, in words naming the PMU and its time stamps; '' if none is.  An estimator predicts
    that PMU's machine across such a stretch no better than across a gap of frames that
    long (`closed_loop.LoopController.act`).

    Parameters
    ----------
    frames : pmu.Frames
        The frames, column by column (`Received.frames`).
    labels : sequence of str
        The PMUs' labels, in column order.

    Returns
    -------
    str
        E.g. ``"B1:G1's values unusable from t = 1.5000 s to 5.4833 s (4.02 s between
        usable values)"``, or ''.
    """
    t, best = np.asarray(frames.t), ("", 0.0)
    for k, label in enumerate(labels):
        bad = ~np.asarray(frames.valid[:, k], bool)
        edges = np.flatnonzero(np.diff(np.concatenate(([0], bad.astype(np.int8), [0]))))
        for a, b in zip(edges[::2], edges[1::2]):  # [a, b): a stretch of unusable values
            # from the last usable value before it to the first after (or the end)
            span = (t[b] if b < t.size else t[-1]) - (t[a - 1] if a else t[0])
            if span > FILL_S + 1e-9 and span > best[1]:
                when = f"from t = {t[a]:.4f} s to {t[b - 1]:.4f} s"
                best = (f"{label}'s values unusable {when}", span)
    return "" if not best[0] else f"{best[0]} ({best[1]:.3g} s between usable values)"


@dataclass(frozen=True)
class Gap:
    """Reporting instants (k / DATA_RATE) that no stream of a source sent, between two
    time stamps that one did.

    Attributes
    ----------
    after : float
        The time stamp before the gap (s; t = 0 is the CFG-2's).
    until : float
        The time stamp after it (s).
    frames : int
        Reporting instants missing.
    filled : bool
        In `Received.frames` as frames of missing values (at most `FILL_S` s), else a
        break (`Received.breaks`).
    """

    after: float
    until: float
    frames: int
    filled: bool

    def __str__(self) -> str:
        what = "filled with missing values" if self.filled else "the estimator restarts after it"
        return f"{self.frames} after t = {self.after:.4f} s, to {self.until:.4f} s ({what})"


@dataclass(frozen=True)
class Unsent:
    """The time stamps that other streams of a source sent and one stream did not: its
    PMUs' values there are missing (a stream that lost frames, or whose clock is off by
    part of the time the streams cover).

    Attributes
    ----------
    stream : str
        The stream (``stream 2 (127.0.0.1:4713)``).
    instants : int
        Time stamps it did not send.
    first, last : float
        The first and the last of them (s; t = 0 is the earliest CFG-2's).
    """

    stream: str
    instants: int
    first: float
    last: float

    def __str__(self) -> str:
        return (
            f"{self.stream} sent no frame at {self.instants} time stamp(s) the other "
            f"streams sent, t = {self.first:.4f} s to {self.last:.4f} s (its PMUs' values "
            "missing there)"
        )


def gap_line(received: Received) -> str:
    """The gaps of a source (`Received.gaps`) for a summary line: ``N reporting instants
    missing in G gap(s): n1 after t = ... s, to ... s (...); ...`` (the first five
    named); '' if none."""
    return gaps_line(received.gaps, " (sent by no stream)")


def gaps_line(gaps, by: str = "") -> str:
    """Gaps (`Gap`) for a summary line: ``N reporting instants missing<by> in G gap(s):
    n1 after t = ... s, to ... s (...); ...`` (the first five named); '' if none.

    Parameters
    ----------
    gaps : sequence of Gap
        The gaps, in order.
    by : str, optional
        Said after "missing" (who did not send them).

    Returns
    -------
    str
        The gaps, or ''.
    """
    if not gaps:
        return ""
    named = "; ".join(map(str, gaps[:5]))
    more = f"; {len(gaps) - 5} more" if len(gaps) > 5 else ""
    return (
        f"{sum(g.frames for g in gaps)} reporting instants missing{by} in {len(gaps)} "
        f"gap(s): {named}{more}"
    )


def stream_gaps(data, cfg2) -> str:
    """The reporting instants of its CFG-2's DATA_RATE that a stream's data frames skip,
    for a summary line (`pmu record`): ``N reporting instants missing in G gap(s): n1
    after t = ... s, to ... s; ...`` (the first five named; t = 0 is the CFG-2's time
    stamp); '' if none.

    Parameters
    ----------
    data : sequence of bytes
        The data frames, in order (`check_data_frame` passed).
    cfg2 : pyc37 ConfigFrame2
        Their stream's configuration frame (DATA_RATE frames per second, or, negative,
        seconds per frame; 0: no rate, nothing said).

    Returns
    -------
    str
        The gaps, or ''.
    """
    rate = cfg2.get_data_rate()
    if not rate or len(data) < 2:
        return ""
    per_s = 1.0 / c37.frame_interval(cfg2)
    soc, frac = c37.config_stamp(cfg2)
    t = list(c37.stamp_times(data, cfg2) - soc - frac)
    gaps = [
        (t[j - 1], t[j], lost)
        for j in range(1, len(t))
        if (lost := round((t[j] - t[j - 1]) * per_s) - 1) > 0
    ]
    if not gaps:
        return ""
    named = "; ".join(f"{n} after t = {a:.4f} s, to {b:.4f} s" for a, b, n in gaps[:5])
    more = f"; {len(gaps) - 5} more" if len(gaps) > 5 else ""
    return (
        f"{sum(n for _, _, n in gaps)} reporting instants missing in {len(gaps)} gap(s): "
        f"{named}{more}"
    )


def read_frames(
    source: Source,
    case,
    pmus,
    rate: float,
    end=None,
    timeout: float | None = None,
    idcode=1,
) -> Received:
    """Every frame of `source` for the PMUs `pmus` of `case` at `rate` frames/s up to
    `end` (`c37_tcp.End`; None: a recording whole, each TCP stream until its server
    closes): the recording read, or each TCP stream received (all at once, one thread
    each, as a PDC does; Ctrl-C ends the wait; `idcode` the IDCODE of the stream each
    server sends, which the commands address: one int for all, or one per server of the
    source; `timeout` the longest wait for a whole
    frame, None: `c37_tcp.RECEIVE_TIMEOUT_S`; the streams share `c37_tcp.MAX_STREAM_BYTES`,
    what one recording may hold), then merged.  A stream that stops before
    `end` is kept and named in `Received.short`; one cut at a data frame that is refused
    is not (the whole source is refused).

    Raises
    ------
    KeyboardInterrupt
        Ctrl-C or a termination while TCP streams are received, raised on with its
        ``received`` attribute saying how many data frames had come from which server,
        and ``recordings``: (server, its CFG-2 bytes, its data frames) of each stream
        that had sent data frames, a recording of what came (`estimate track` writes it).
    InputError
        As `c37.recorded_frames` and `c37_tcp.receive` (a TCP stream's named with its
        ``--source``, the error carrying ``recordings`` as a KeyboardInterrupt does: the
        other streams' frames received); more TCP servers than PMUs; a stream at another
        rate or nominal frequency (`c37.check_config`), a station that is not one of `pmus`
        or in two streams, a PMU in no stream, a data frame that is not readable or not the
        stream's (`c37.parse_frame`; over TCP as received: `c37_tcp.Stream.refused`), a
        stream whose time stamps repeat or go backwards, streams that share no time stamp
        (`merge`), or frames whose every value is absent.
    """
    from stabctl.estimation.c37_tcp import MAX_STREAM_BYTES, End, Stream, receive

    end = end or End()
    if source.path is not None:
        cfg2, data = c37.recorded_frames(source.path)
        streams = [_recorded_to(end, cfg2, data, str(source.path))]
        names = [str(source.path)]
    else:
        if len(source.servers) > len(pmus):
            raise InputError(
                f"--source {source}: {len(source.servers)} servers for {len(pmus)} PMUs "
                "(each stream carries at least one PMU)"
            )
        codes = [idcode] * len(source.servers) if isinstance(idcode, int) else list(idcode)
        if len(codes) != len(source.servers):
            raise InputError(
                f"--source {source}: {len(codes)} IDCODEs for {len(source.servers)} servers"
            )
        got: list[Stream | Exception | None] = [None] * len(source.servers)
        came: list[list] = [[] for _ in source.servers]  # each stream's data frames so far
        configs: list[list] = [[] for _ in source.servers]  # each stream's CFG-2, once read
        n_servers = len(source.servers)  # sharing what one stream may hold, as a recording

        def fetch(k, host, port):
            try:
                got[k] = receive(
                    host,
                    port,
                    end,
                    codes[k],
                    timeout,
                    came[k],
                    MAX_STREAM_BYTES // n_servers,
                    configs[k],
                )
            except (InputError, OSError) as exc:  # handed to the caller
                got[k] = exc

        threads = [
            threading.Thread(target=fetch, args=(k, h, p), daemon=True)
            for k, (h, p) in enumerate(source.servers)
        ]
        for t in threads:
            t.start()
        try:
            for t in threads:
                while t.is_alive():  # a join with a time-out lets Ctrl-C through
                    t.join(0.2)
        except KeyboardInterrupt as exc:  # said with what had come, kept by the caller
            exc.received = _came(source, came)  # type: ignore[attr-defined]
            exc.recordings = _recordings(source, configs, came)  # type: ignore[attr-defined]
            raise
        if errors := [g for g in got if isinstance(g, Exception)]:
            failed = InputError(_of_source(source, str(errors[0])))
            # the other streams' frames, kept by the caller as on Ctrl-C (round 58 AZ17: three
            # streams received whole were dropped for a fourth server that sent no CFG-2)
            failed.recordings = _recordings(source, configs, came)  # type: ignore[attr-defined]
            raise failed from None
        for (h, p), g in zip(source.servers, got):
            if isinstance(g, Stream) and g.refused:  # its frames are not taken in part
                raise InputError(_of_source(source, f"{hostport(h, p)}: {g.refused}"))
        streams = [
            (
                c37.read_config(g.cfg2, f"--source {source}: {hostport(h, p)}'s CFG-2"),
                g.data,
                f"{hostport(h, p)}: {g.short}" if g.short else "",
            )
            for (h, p), g in zip(source.servers, got)
            if isinstance(g, Stream)
        ]
        names = [
            f"stream {k + 1} ({hostport(h, p)})"
            for k, ((h, p), g) in enumerate(zip(source.servers, got))
            if isinstance(g, Stream)
        ]
    try:
        received = merge(case, pmus, rate, [(cfg2, data) for cfg2, data, _ in streams], names)
    except InputError as exc:
        raise InputError(f"--source {source}: {exc}") from None
    if not received.frames:
        raise InputError(f"--source {source}: no data frame (a configuration frame only)")
    if received.frames and not received.frames.valid.any():
        raise InputError(
            f"--source {source}: every PMU value of its {len(received.frames)} frames is "
            f"missing or not used: {unused_values(received.flagged) or 'none flagged'}, "
            f"{received.missing} missing: nothing was measured"
        )
    return dataclasses.replace(received, short=tuple(s for _, _, s in streams if s))


def _of_source(source: Source, said: str) -> str:
    """An error of one of a TCP `source`'s servers (``HOST:PORT: ...``), named with the
    source: its server's address said once where the source is that one server (round
    58: ``--source tcp://127.0.0.1:4712: 127.0.0.1:4712: ...``)."""
    (h, p), *more = source.servers
    if not more and said.startswith(f"{hostport(h, p)}: "):
        said = said[len(hostport(h, p)) + 2 :]
    return f"--source {source}: {said}"


def _recordings(source: Source, configs: list, came: list) -> list:
    """(server, its CFG-2 bytes, its data frames) of each stream of a TCP `source` whose
    CFG-2 and at least one data frame came (`read_frames`' threads' lists as they stand)."""
    return [
        (hostport(h, p), cfg[0], list(frames))
        for (h, p), cfg, frames in zip(source.servers, configs, came)
        if cfg and frames
    ]


def _came(source: Source, came: list) -> str:
    """What a TCP source's streams had sent when their receive was interrupted: ``N data
    frames from tcp://... (n1 from HOST:PORT, ...)``."""
    each = ", ".join(f"{len(d)} from {hostport(h, p)}" for (h, p), d in zip(source.servers, came))
    total = sum(len(d) for d in came)
    frames = "data frame" if total == 1 else "data frames"
    return f"{total} {frames} from {source}" + (f" ({each})" if len(came) > 1 else "")


def unused_values(flagged: dict) -> str:
    """The PMU values a stream's STAT words (or a frame's FRACSEC time quality) kept out
    (`Received.flagged`, `c37_loop.Answered.flagged`), by reason, for a summary line.

    Parameters
    ----------
    flagged : dict
        Count of values per reason (`c37.unusable`).

    Returns
    -------
    str
        ``N PMU values not used by their STAT (n1 reason1, ...)`` (``STAT or time
        quality`` when a clock failure is among the reasons; ``as marked absent in their
        fields`` for `c37.marked`; ``beyond any measurement`` for values no measurement
        gives, `c37.plausible`); '' if none.
    """
    if not flagged:
        return ""
    why = ", ".join(f"{n} {reason}" for reason, n in flagged.items())
    fracsec = {why for _, _, why in c37.TIME_QUALITY_UNUSABLE}
    by = "STAT or time quality" if fracsec.intersection(flagged) else "STAT"
    how = [f"by their {by}"] if set(flagged) - {c37.IMPLAUSIBLE, c37.MARKED} else []
    how += ["as marked absent in their fields"] if c37.MARKED in flagged else []
    how += ["beyond any measurement"] if c37.IMPLAUSIBLE in flagged else []
    return f"{sum(flagged.values())} PMU values not used {', or '.join(how)} ({why})"


def _recorded_to(end, cfg2, data, name: str) -> tuple:
    """(cfg2, the recording's data frames up to `end`, what is short of it or ''); the
    frames past the end checked in order too (`c37.order_faults`; those read are checked
    as merged): a recording of a run given twice, its second half's stamps going back, was
    read to the run's end by `estimate rmse` without a word, where `estimate track`
    refused it."""
    every = data
    soc, frac = c37.config_stamp(cfg2)  # t = 0
    if end.frames is not None:
        data = data[: end.frames]
    reached_tf = False
    if end.tf is not None:
        stamps = c37.stamp_times(data, cfg2) - soc - frac
        reached = [k for k, t in enumerate(stamps) if t >= end.tf - 0.5e-6]
        if reached:  # the frames to the end, not one stamped past it after a gap
            reached_tf = True
            k = reached[0]
            past = stamps[k] > end.tf + c37.frame_interval(cfg2) + 0.5e-6
            data = data[:k] if past else data[: k + 1]
            if not data:
                raise InputError(
                    f"{name}: its first data frame is stamped {stamps[0]:.4f} s (t = 0 its "
                    f"CFG-2's time stamp), after the end asked for ({end}): no frame to track"
                )
    if len(data) < len(every):  # the frames past the end: in order with those read
        kept = len(data)
        tail = [(k, why) for k, why in c37.order_faults(every, cfg2, name) if k >= kept]
        if tail:
            raise InputError(f"{tail[0][1]} (after the end asked for, {end})")
    # whichever end comes first, as a TCP stream's (`c37_tcp._data_frames`)
    at = c37.stamp_times(data, cfg2)[-1] - soc - frac if data else None
    whole = not end.given or (end.frames is not None and len(data) == end.frames) or reached_tf
    last = f", the last stamped {at:.4f} s" if at is not None else ""
    return cfg2, data, "" if whole else f"{name}: {len(data)} data frames{last}, before {end}"


#: how long before its stream's CFG-2 a data frame may be stamped, s: a frame measured
#: before the CFG-2 was sent and sent after it (a PMU's reporting latency); a frame stamped
#: earlier is refused (`merge`)
BEFORE_CFG2_S = 1.0


def merge(case, pmus, rate: float, streams, stream_names=None) -> Received:
    """One `Frame` per time stamp from streams of (CFG-2 as pyc37 reads it, data frames'
    bytes); each stream's values go to its PMUs' columns (by station name), those of a
    time stamp a stream did not send are NaN and invalid, and said (`Received.unsent`).
    The time stamps are read on one clock, t = 0 the earliest CFG-2's: a stream whose
    clock is off by more than the time the streams cover shares no time stamp with the
    first, and is refused naming the offset (merged, its frames would be of other
    instants than the first's, or, read each from its own CFG-2's time stamp, taken as
    simultaneous).

    Parameters
    ----------
    case : stabctl.case.Case
        The case (its nominal frequency, the PMU buses' rated kV).
    pmus : sequence of PMU
        The run's PMUs, one column each.
    rate : float
        Frames per second.
    streams : sequence of (pyc37 ConfigFrame2, sequence of bytes)
        Each stream's CFG-2 and data frames.
    stream_names : sequence of str, optional
        Each stream's name in messages (default ``stream 1``, ``stream 2``, ...).

    Returns
    -------
    Received

    Raises
    ------
    InputError
        As `read_frames`; a stream that shares no time stamp with the first (both
        sending frames); a data frame stamped more than BEFORE_CFG2_S before the earliest
        CFG-2.
    """
    called = list(stream_names or (f"stream {s + 1}" for s in range(len(streams))))
    labels = [p.label for p in pmus]
    owner: dict[str, int] = {}
    parsed = []
    flagged: collections.Counter = collections.Counter()
    # t = 0: the earliest CFG-2's time stamp; the frames read from its SOC, then its fraction
    epoch, frac = min((c37.config_stamp(cfg2) for cfg2, _ in streams), default=(0, 0.0))
    for s, (cfg2, data) in enumerate(streams):
        names = cfg2.get_station_name()
        names = [str(x).strip() for x in (names if isinstance(names, list) else [names])]
        for name in names:
            if name not in labels:
                raise InputError(
                    f"stream {s + 1}: station {name!r} is not a PMU of this run (its PMUs "
                    f"are {', '.join(labels[:4])}{', ...' if len(labels) > 4 else ''}: "
                    "at the machines' terminal buses by default, at their HV buses with "
                    "--pmu-at hv; the stream must be of the same case and placement)"
                )
            if name in owner:
                raise InputError(f"station {name!r} is in streams {owner[name] + 1} and {s + 1}")
            owner[name] = s
        cols = [labels.index(n) for n in names]
        cfg = c37.stream_config(case, [pmus[c] for c in cols], rate, cfg2.get_id_code(), epoch)
        try:
            c37.check_config(cfg2, cfg)
        except InputError as exc:
            raise InputError(f"stream {s + 1}: {exc}") from None
        frames = Frames.missing(len(data), len(cols))
        base = cfg2.get_time_base()
        for k, (d, leap) in enumerate(zip(data, c37.leap_offsets(data, cfg2))):
            try:
                frame = c37.parse_frame(cfg, cfg2, d)
            except InputError as exc:
                raise InputError(f"stream {s + 1}, data frame {k + 1}: {exc}") from None
            # a frame after a leap second is 1 s later than stamped (`c37.leap_offsets`)
            t = c37.reporting_instant(frame.t + int(leap) - frac, cfg.rate, base)
            if t < -BEFORE_CFG2_S:
                raise InputError(
                    f"stream {s + 1}, data frame {k + 1}: stamped {-t:.6g} s before the "
                    f"CFG-2{'s' * (len(streams) > 1)} (t = 0 the earliest CFG-2's time "
                    "stamp): a configuration frame comes before the data it describes; a "
                    "clock or a time stamp is wrong"
                )
            frames.t[k] = t
            for column, value in zip(frames.columns()[1:], frame[1:]):
                column[k] = value
            flagged.update(why for why in c37.flags(cfg2, d) if why)
        # after the frames' own checks (`c37.check_data_frame`), as a receiver makes them
        check_order(data, cfg2, f"stream {s + 1}")
        frames, odd = c37.plausible(frames, cfg.f0)
        if odd:
            flagged[c37.IMPLAUSIBLE] += odd
        parsed.append((cols, frames))
    if lost := [x for x in labels if x not in owner]:
        raise InputError(f"PMU {', '.join(lost)} in no stream")
    return dataclasses.replace(
        _by_time_stamp(len(labels), parsed, rate),
        flagged=dict(flagged),
        unsent=_unsent([frames for _, frames in parsed], called),
    )


def _stamps(frames: Frames) -> np.ndarray:
    """The frames' time stamps in us (int64), the keys they are merged on."""
    return np.round(frames.t * c37.TIME_BASE).astype(np.int64)


def _unsent(streams, names) -> tuple:
    """The `Unsent` time stamps of each of `streams` (each `Frames`): those another
    stream sent; refused if a stream shares none with the first (both sending)."""
    stamps = [_stamps(frames) for frames in streams]
    for s in range(1, len(stamps)):
        if stamps[0].size and stamps[s].size and not np.intersect1d(stamps[0], stamps[s]).size:
            t0, ts = streams[0].t.min(), streams[s].t.min()
            raise InputError(
                f"{names[s]} shares no time stamp with {names[0]}: its first is "
                f"{ts - t0:+.6f} s from {names[0]}'s (t = {ts:.6f} s and {t0:.6f} s, t = 0 "
                "the earliest CFG-2's): their clocks disagree, or they are of other times"
            )
    every, at = _every_stamp(streams)
    out = []
    for name, own in zip(names, stamps):
        lack = np.setdiff1d(every, own)
        if lack.size:
            first, last = at[np.searchsorted(every, lack[[0, -1]])]
            out.append(Unsent(name, int(lack.size), float(first), float(last)))
    return tuple(out)


def _every_stamp(streams) -> tuple[np.ndarray, np.ndarray]:
    """(every time stamp any of `streams` (`Frames`) sent, us, sorted; its time, s: the
    last stream's that sent it)."""
    keys = np.concatenate([_stamps(f) for f in streams] or [np.zeros(0, np.int64)])
    times = np.concatenate([f.t for f in streams] or [np.zeros(0)])
    every, last = np.unique(keys[::-1], return_index=True)
    return every, times[::-1][last]


def check_order(data, cfg2, what: str) -> None:
    """Refuse data frames whose time stamps repeat or go backwards (a frame would replace
    or be sorted before another without a word, or a replay paced by them would wait a
    negative time), or are not reporting instants of the stream's DATA_RATE: a PMU
    reports at k / DATA_RATE s into each second, frame 0 at the second's rollover
    (C37.118.1-2011 clause 5.3), each stamp within one FRACSEC count of its instant (a
    stream sent at another rate than its CFG-2 says would be read with a wrong time
    step).

    Parameters
    ----------
    data : sequence of bytes
        The data frames, in order.
    cfg2 : pyc37 ConfigFrame2
        Their stream's configuration frame (its TIME_BASE and DATA_RATE: frames per
        second, or, negative, seconds per frame; 0 is refused).
    what : str
        Their source, for messages (``stream 2``, a recording's path).

    Raises
    ------
    InputError
        The first frame whose time stamp repeats or goes back, or is off the DATA_RATE
        grid, and how many are.
    """
    if faults := c37.order_faults(data, cfg2, what):
        raise InputError(faults[0][1])


def _by_time_stamp(n: int, parsed, rate: float) -> Received:
    """Frames of every (columns, `Frames`) stream filled in at their time stamps (us), the
    reporting instants no stream sent between them counted as gaps (`Received.gaps`):
    those of a gap of at most `FILL_S` s added as frames of missing values, a longer one
    a break (`Received.breaks`)."""
    stamps, at = _every_stamp([frames for _, frames in parsed])
    lost = np.round(np.diff(at) * rate).astype(np.int64) - 1 if at.size else np.zeros(0, int)
    if len(parsed) == 1 and not (lost > 0).any() and list(parsed[0][0]) == list(range(n)):
        frames = parsed[0][1]  # one stream of every PMU, in order (`check_order`), whole
        absent = int(np.sum(~frames.valid))
        return Received(frames, 1, len(frames), absent, 0)
    fill = int(round(FILL_S * rate))
    filled = np.where((lost > 0) & (lost <= fill), lost, 0)
    row = np.arange(at.size) + np.concatenate([[0], np.cumsum(filled)])  # each stamp's
    out = Frames.missing(at.size + int(filled.sum()), n)
    came = np.zeros(out.valid.shape, bool)
    out.t[row] = at
    for cols, frames in parsed:
        rows = row[np.searchsorted(stamps, _stamps(frames))][:, None]
        came[rows, cols] = True
        for column, values in zip(out.columns()[1:], frames.columns()[1:]):
            column[rows, cols] = values
    gaps, breaks = [], []
    for k in np.nonzero(lost > 0)[0]:
        # counted by the time between (t = 0, the CFG-2's stamp, need not be an instant)
        before, many = float(at[k]), int(lost[k])
        gaps.append(Gap(before, float(at[k + 1]), many, many <= fill))
        if many <= fill:
            first = round(before * rate) + 1
            off = before - (first - 1) / rate  # the instants' offset from k / rate
            out.t[row[k] + 1 : row[k + 1]] = (first + np.arange(many)) / rate + off
        else:
            breaks.append(int(row[k + 1]))
    return Received(
        out,
        len(parsed),
        sum(len(f) for _, f in parsed),
        int(np.sum(came & ~out.valid)),
        int(np.sum(~came)),
        gaps=tuple(gaps),
        breaks=tuple(breaks),
    )


def missing_frame(t: float, n: int) -> Frame:
    """A frame at t (s) of n PMUs whose every value is missing: what a reporting instant
    of a gap of at most `FILL_S` s is filled with.

    Parameters
    ----------
    t : float
        Its time stamp (s).
    n : int
        PMUs.

    Returns
    -------
    Frame
        Every value NaN and invalid.
    """
    nan = np.full(n, np.nan)
    return Frame(t, np.zeros(n, bool), nan + 0j, nan + 0j, nan.copy(), nan.copy())
