"""Where the estimators' PMU frames come from, whatever the transport: drawn in process
(`stabctl.estimation.pmu.measure`, the default of every study), read from a recording of
C37.118.2 frames (`stabctl.estimation.c37.record`, `stabctl pmu record`), or received over
TCP from one or more C37.118.2 servers (PMUs, a PDC, `stabctl pmu serve`), the streams
merged by time stamp into one `pmu.Frame` per reporting instant.

A source is written ``tcp://HOST:PORT[,HOST:PORT...]`` or as a file path.  Each stream's
CFG-2 names its PMUs by station name (a `pmu.PMU` label, ``B3:G1``); every PMU of the run
must be in exactly one stream.  Time: t = 0 of the run is the CFG-2 frame's own time
stamp (SOC), as `c37.config_frame` writes it.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from stabctl.errors import InputError
from stabctl.estimation import c37
from stabctl.estimation.pmu import Frame

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
        runs: list[list] = []  # [host, first port, last port]
        for host, port in self.servers:
            if runs and runs[-1][0] == host and runs[-1][2] + 1 == port:
                runs[-1][2] = port
            else:
                runs.append([host, port, port])
        return TCP + ",".join(f"{h}:{a}" + (f"-{b}" if b > a else "") for h, a, b in runs)


def parse_source(text: str) -> Source:
    """The `Source` of ``tcp://HOST:PORT[,HOST:PORT...]`` (a port range ``P1-P2`` for
    one server per port, as `stabctl pmu serve --each-pmu` serves) or of a recording's
    path.

    Raises
    ------
    InputError
        A TCP address without a port in 1..65535 (or an empty range), or a recording that
        is not a file.
    """
    if not text.startswith(TCP):
        path = Path(text)
        if not path.is_file():
            raise InputError(f"--source {text}: no such recording (or write tcp://HOST:PORT)")
        return Source(path=path)
    servers = []
    for item in text[len(TCP) :].split(","):
        host, _, ports = item.rpartition(":")
        first, _, last = ports.partition("-")
        last = last or first
        if not (host and first.isdigit() and last.isdigit()):
            raise InputError(f"--source {text}: {item!r} is not HOST:PORT")
        span = range(int(first), int(last) + 1)
        if not span or span[0] < 1 or span[-1] > 65535:
            raise InputError(f"--source {text}: {item!r} is not HOST:PORT")
        servers += [(host, p) for p in span]
    return Source(servers=tuple(servers))


@dataclass(frozen=True)
class Received:
    """The merged frames of a source and what came of them.

    Attributes
    ----------
    frames : list of Frame
        One per time stamp any stream sent, in order, one column per PMU of the run.
    streams : int
        Streams merged.
    data_frames : int
        Data frames received over all streams.
    absent : int
        PMU values the streams flagged absent (STAT bits 15-14 = 10: lost at the source).
    missing : int
        PMU values of a time stamp some streams sent and this PMU's did not.
    """

    frames: list
    streams: int
    data_frames: int
    absent: int
    missing: int

    def summary(self) -> dict:
        """The counts, for a report (JSON)."""
        return {
            "streams": self.streams,
            "frames": len(self.frames),
            "data_frames": self.data_frames,
            "absent": self.absent,
            "missing": self.missing,
        }


def read_frames(source: Source, case, pmus, rate: float, timeout: float = 30.0) -> Received:
    """Every frame of `source` for the PMUs `pmus` of `case` at `rate` frames/s: the
    recording read whole, or each TCP stream received to its end (all at once, one thread
    each, as a PDC does), then merged.

    Raises
    ------
    InputError
        As `c37.recorded_frames` and `c37_tcp.receive`; a stream at another rate, a station
        that is not one of `pmus` or in two streams, a PMU in no stream, or a data frame
        that is not readable.
    """
    if source.path is not None:
        return merge(case, pmus, rate, [c37.recorded_frames(source.path)])
    from stabctl.estimation.c37_tcp import receive

    with ThreadPoolExecutor(max_workers=len(source.servers)) as pool:
        streams = list(pool.map(lambda hp: receive(hp[0], hp[1], timeout=timeout), source.servers))
    return merge(
        case,
        pmus,
        rate,
        [
            (c37.read_config(cfg2, f"{h}:{p}'s CFG-2"), data)
            for (h, p), (cfg2, data) in zip(source.servers, streams)
        ],
    )


def merge(case, pmus, rate: float, streams) -> Received:
    """One `Frame` per time stamp from streams of (CFG-2 as pyc37 reads it, data frames'
    bytes); each stream's values go to its PMUs' columns (by station name), those of a
    time stamp a stream did not send are NaN and invalid.

    Raises
    ------
    InputError
        As `read_frames`.
    """
    labels = [p.label for p in pmus]
    owner: dict[str, int] = {}
    parsed = []
    for s, (cfg2, data) in enumerate(streams):
        names = cfg2.get_station_name()
        names = [str(x).strip() for x in (names if isinstance(names, list) else [names])]
        for name in names:
            if name not in labels:
                raise InputError(f"stream {s + 1}: station {name!r} is not a PMU of this run")
            if name in owner:
                raise InputError(f"station {name!r} is in streams {owner[name] + 1} and {s + 1}")
            owner[name] = s
        if cfg2.get_data_rate() != rate:
            raise InputError(
                f"stream {s + 1} sends {cfg2.get_data_rate()} frames/s, the run's PMUs {rate:g}"
            )
        cols = [labels.index(n) for n in names]
        cfg = c37.stream_config(
            case, [pmus[c] for c in cols], rate, cfg2.get_id_code(), cfg2.get_soc()
        )
        parsed.append((cols, [c37.parse_frame(cfg, cfg2, d) for d in data]))
    if lost := [x for x in labels if x not in owner]:
        raise InputError(f"PMU {', '.join(lost)} in no stream")
    return _by_time_stamp(len(labels), parsed)


def _by_time_stamp(n: int, parsed) -> Received:
    """Frames of every (columns, frames) stream filled in at their time stamps (us)."""
    at = {round(f.t * c37.TIME_BASE): f.t for _, frames in parsed for f in frames}
    stamps = sorted(at)
    row = {stamp: k for k, stamp in enumerate(stamps)}
    valid = np.zeros((len(stamps), n), bool)
    came = np.zeros((len(stamps), n), bool)
    v, i = (np.full((len(stamps), n), np.nan + 0j) for _ in range(2))
    freq, rocof = (np.full((len(stamps), n), np.nan) for _ in range(2))
    for cols, frames in parsed:
        for f in frames:
            k = row[round(f.t * c37.TIME_BASE)]
            came[k, cols], valid[k, cols] = True, f.valid
            v[k, cols], i[k, cols], freq[k, cols], rocof[k, cols] = f.v, f.i, f.freq, f.rocof
    frames = [Frame(at[s], valid[k], v[k], i[k], freq[k], rocof[k]) for k, s in enumerate(stamps)]
    return Received(
        frames,
        len(parsed),
        sum(len(f) for _, f in parsed),
        int(np.sum(came & ~valid)),
        int(np.sum(~came)),
    )
