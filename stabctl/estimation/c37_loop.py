"""The storage control loop closed over TCP: the simulator's PMUs publish C37.118.2 data
frames, a controller subscribes, runs its estimator and the Table 3 law, and sends the ESD
modes back, which the simulator applies (docs/estimation.md 6).

Both ends are halves of one `closed_loop.LoopController`: the plant (`PlantLink`, a
C37.118.2 server inside the simulator's `CommandFrames` callback) calls its `measure`,
the controller (`serve_controller`, a C37.118.2 client) its `act`, so the loop over TCP
runs the in-process loop's code with the wire in between.

Protocol, one TCP connection per loop (C37.118.2-2011 frames throughout, CRC checked,
each due whole within the time-out; the controller's commands and answers addressed to
the stream's IDCODE, others dropped):
1. the controller sends the command 'cfg2'; the plant answers with the stream's CFG-2
   (one PMU per generator, `c37.config_frame`); the controller checks its station names;
2. the controller sends 'start';
3. at each reporting instant the plant sends one data frame and waits for the answer: an
   extended command frame (CMD 0x0008, Table 15) time-stamped as the data frame it
   answers, its extended data one signed byte per ESD: the mode (-1 inject, 0 idle,
   +1 absorb);
4. at the end of its run the plant sends a header frame (frame type 1) reading
   ``stabctl: end of run at t = <s>`` and closes the connection; a connection closed
   without it is a plant that stopped early (killed, crashed), and so is a header whose
   end is not that of the last frame answered (the last reporting instant at or before
   it: frames of the run never came), which the controller says (`PlantStopped`)
   instead of presenting the frames it answered as the whole run.

The simulation waits for each answer (lock step), so the run is that of the in-process
loop with the frames as on the wire (`c37.on_wire`) whatever the network does; the modes
take effect at the time stamp plus the loop's modelled latency, and the wall-clock round
trip of each frame is measured beside it (`LinkStats`): a frame whose round trip exceeds
the modelled latency is counted late.
"""

from __future__ import annotations

import collections
import contextlib
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from stabctl.errors import InputError
from stabctl.estimation import c37
from stabctl.estimation.c37_tcp import (
    ACCEPT_RETRY_S,
    COMMANDS,
    MAX_STREAM_BYTES,
    NAMED_PEERS,
    NOT_SENT,
    SHORT_OF,
    End,
    FrameTimeout,
    Guard,
    _accept_conn,
    _accept_failed,
    _read_frame,
    command_word,
    hostport,
    listen,
    most_frames,
)

EXTENDED = 8  # C37.118.2-2011 Table 15: extended frame
#: C37.118.2-2011 frame type (SYNC bits 6-4) of a header frame
HEADER = 1
#: the text of the plant's last frame (a header frame) before it closes the loop
END_OF_RUN = "stabctl: end of run at t = "
#: what follows it: the latency after each frame's time stamp at which the plant applied the
#: modes (round 58 AZ09: a plant at 200 ms and a controller forecasting over 50 ms ran
#: the loop without a word)
APPLIED = "ESD modes applied after each frame's time stamp plus "


class PlantStopped(InputError):
    """The frames the controller answered are not the plant's whole run: the plant closed
    the loop without its end-of-run header (killed, crashed), or the end that header
    announces is not that of the last frame answered."""


def end_of_run_frame(idcode: int, t: float, latency_s: float | None = None) -> bytes:
    """The plant's last frame: a header frame reading `END_OF_RUN` and the run's end time t
    (s), and the latency after which the plant applied the modes, if given (`APPLIED`).

    Parameters
    ----------
    idcode : int
        The stream's ID code.
    t : float
        The last simulated instant, s.
    latency_s : float, optional
        The plant's latency (its ``--latency-ms``), s.

    Returns
    -------
    bytes
        The frame, CRC included.
    """
    from pyc37.frame import HeaderFrame

    applied = "" if latency_s is None else f"; {APPLIED}{1e3 * latency_s:g} ms"
    return HeaderFrame(idcode, f"{END_OF_RUN}{t:.6f} s{applied}").convert2bytes()


def _end_text(data: bytes, idcode: int) -> str | None:
    """The text of the plant's end-of-run header frame of the stream `idcode`, its CRC
    valid, from its end time on; None for any other frame."""
    from pyc37.frame import CommonFrame

    if len(data) < 16 or (data[1] >> 4) & 0x7 != HEADER:
        return None
    if not CommonFrame._check_crc(data) or int.from_bytes(data[4:6], "big") != idcode:
        return None
    text = data[14:-2].decode("ascii", "replace")
    return text[len(END_OF_RUN) :] if text.startswith(END_OF_RUN) else None


def _end_time(data: bytes, idcode: int) -> float | None:
    """The end time (s) a header frame of the stream `idcode` from the plant gives, its
    CRC valid; None for any other frame."""
    text = _end_text(data, idcode)
    try:
        return None if text is None else float(text.split()[0])
    except (ValueError, IndexError):
        return None


def _applied_latency(data: bytes, idcode: int) -> float | None:
    """The latency (s) after which the plant says it applied the modes (`APPLIED`), from
    its end-of-run header; None if it says none."""
    text = _end_text(data, idcode) or ""
    if APPLIED not in text:
        return None
    try:
        return 1e-3 * float(text.split(APPLIED)[1].split()[0])
    except (ValueError, IndexError):
        return None


@dataclass(frozen=True)
class LinkStats:
    """What the loop's link did.

    Attributes
    ----------
    frames : int
        Data frames sent (each answered).
    round_trip_s : ndarray
        Wall-clock time from handing each data frame to the socket to its answer (s).
    latency_s : float
        The loop's modelled latency (s), the budget of a round trip.
    """

    frames: int
    round_trip_s: np.ndarray
    latency_s: float

    def summary(self) -> dict:
        """Frames, late frames and the round trip's median, 99th percentile and largest
        (ms), for a report."""
        ms = 1e3 * self.round_trip_s
        some = ms.size > 0
        return {
            "frames": self.frames,
            "late": int(np.sum(self.round_trip_s > self.latency_s)),
            "round_trip_ms": {
                "median": float(np.median(ms)) if some else None,
                "p99": float(np.percentile(ms, 99)) if some else None,
                "max": float(ms.max()) if some else None,
            },
        }


def modes_frame(idcode: int, soc: int, fracsec: int, modes) -> bytes:
    """The controller's answer to the data frame stamped (soc, fracsec): an extended
    command frame carrying one signed byte per ESD mode."""
    from pyc37.frame import CommandFrame

    payload = np.asarray(modes, np.int8).tobytes()
    return CommandFrame(idcode, "extended", payload, soc, (fracsec, "+")).convert2bytes()


def read_modes(data: bytes, n_dev: int, idcode: int | None = None) -> tuple[int, np.ndarray]:
    """(the answered time stamp's SOC and FRACSEC count as one integer of TIME_BASE
    counts, the modes (n_dev,)) of an answer (`modes_frame`).

    Raises
    ------
    InputError
        Not an extended command frame, a CRC that fails, one addressed to another IDCODE
        than `idcode` (the plant's stream; None: not checked), not n_dev modes, or a mode
        other than -1, 0, +1.
    """
    from pyc37.frame import CommandFrame, FrameError

    try:
        cmd = CommandFrame.convert2frame(data)
    except FrameError as exc:
        raise InputError(f"controller's answer not readable: {exc}") from None
    if idcode is not None and cmd.get_id_code() != idcode:
        raise InputError(
            f"controller's answer is addressed to IDCODE {cmd.get_id_code()}, not this "
            f"stream's {idcode}"
        )
    if cmd._command != EXTENDED or len(cmd._extended_frame) != n_dev:
        raise InputError(f"controller's answer is not the modes of {n_dev} ESDs")
    stamp = cmd.get_soc() * c37.TIME_BASE + cmd.get_frasec()[0]
    modes = np.frombuffer(cmd._extended_frame, np.int8).astype(np.int64)
    if bad := sorted({int(m) for m in modes} - {-1, 0, 1}):
        raise InputError(f"controller's answer holds mode(s) {bad}: an ESD's mode is -1, 0 or +1")
    return stamp, modes


@dataclass(frozen=True)
class Listen:
    """Where a plant waits for a controller of its own (`stabctl pmu control`).

    Attributes
    ----------
    host : str
        Address to listen on.
    port : int
        TCP port (0: a free one).
    on_listen : callable or None
        Called with (host, port) once listening (e.g. to print it).
    timeout : float
        Longest wait for the controller to connect, and for each answer (s).
    speed : float
        Time-stamp seconds per wall-clock second: each frame is sent no earlier than its
        time stamp divided by speed after the first (1: real time, as a real-time
        simulator; inf: as soon as the previous answer is in).
    allow : tuple of str
        Controller addresses allowed to connect (empty: any).
    """

    host: str = "127.0.0.1"
    port: int = 0
    on_listen: Callable | None = None
    timeout: float = 30.0
    speed: float = float("inf")
    allow: tuple = ()


@dataclass(eq=False)
class _Shake:
    """A peer in a plant's handshake (`PlantLink._connected`): its connection, address,
    when it connected (`time.monotonic()`), whether it sent a valid command, whether its
    place was given to a new peer."""

    conn: socket.socket
    peer: tuple
    since: float
    commanded: bool = False
    evicted: bool = False


class PlantLink:
    """The plant's end: a C37.118.2 server on ``host``:``port`` (0: a free one, see
    `address`) for one controller, and the `CommandFrames` callback that sends each frame
    and returns the controller's modes.

    Parameters
    ----------
    controller : stabctl.estimation.closed_loop.LoopController
        The loop whose `measure` makes the frames (PMUs, noise seed).
    cfg : stabctl.estimation.c37.StreamConfig
        The stream of its PMUs.
    host : str, optional
    port : int, optional
    timeout : float, optional
        Longest wait for the controller to connect, and for each answer (s).
    speed : float, optional
        Pacing of the frames (`Listen.speed`; default inf, unpaced).
    allow : tuple of str, optional
        Controller addresses allowed (default: any).  A peer not allowed, or one that does
        not ask for CFG-2 and say 'start' in valid command frames within the time-out, is
        dropped (named in `refused`) and the plant waits for the next, until `timeout`.
    max_peers : int, optional
        Handshakes at once (`Guard.max_peers`, 8): with every place taken, a new peer
        takes that of the peer connected longest without a valid command, else of the one
        connected longest.

    Raises
    ------
    InputError
        A speed that is not > 0, or an address that cannot be listened on
        (`c37_tcp.listen`).
    """

    def __init__(
        self,
        controller,
        cfg,
        host="127.0.0.1",
        port=0,
        timeout=30.0,
        speed=float("inf"),
        allow=(),
        max_peers=Guard.max_peers,
    ):
        if not speed > 0:
            raise InputError(f"speed must be > 0, got {speed}")
        self.ctrl, self.cfg, self.timeout = controller, cfg, float(timeout)
        self.guard = Guard(tuple(allow), float(timeout), max_peers=max_peers)
        #: peers dropped, each with the reason: before a controller took the loop, and
        #: those whose handshake ended after it did (the first `NAMED_PEERS`; all of them
        #: counted in `n_refused`)
        self.refused: list[str] = []
        self.n_refused, self._last_refused, self._short = 0, "", ""
        self.speed, self._start = float(speed), None
        self.cfg2 = c37.config_frame(cfg)
        self._sock = listen(host, port)
        self._conn: socket.socket | None = None
        self._peer = "?"  # the controller's address, once connected
        self._trips: list[float] = []
        #: (time stamp s, modes) of every answer
        self.answers: list[tuple[float, np.ndarray]] = []

    @property
    def address(self) -> tuple[str, int]:
        """(host, port) the plant listens on."""
        host, port = self._sock.getsockname()[:2]
        return host, port

    def stats(self) -> LinkStats:
        """The link's figures so far."""
        trips = np.array(self._trips)
        return LinkStats(trips.size, trips, self.ctrl.settings.latency_s)

    def finish(self, t_end: float) -> None:
        """Tell the controller the run ended at t_end (s): the end-of-run header frame
        (`end_of_run_frame`), sent before `close` only when the run ended normally."""
        if self._conn is not None:
            try:
                latency = self.ctrl.settings.latency_s
                self._conn.sendall(end_of_run_frame(self.cfg.idcode, t_end, latency))
            except OSError:  # the controller has gone: nothing to tell
                pass

    def close(self) -> None:
        """End the loop: close the controller's connection and the listening socket."""
        for s in (self._conn, self._sock):
            if s is not None:
                s.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __call__(self, t_f: float, partial) -> np.ndarray:
        """`CommandFrames.decide`: the frame at t_f sent, the controller's modes returned
        (no frame before the run has two recorded points: the controller's in-process
        rule for that instant)."""
        if partial.t.size < 2:
            return self.ctrl(t_f, partial)
        conn = self._connected()
        data = c37.data_frame(self.cfg, self.cfg2, self.ctrl.measure(t_f, partial))
        if self._start is None:
            self._start = (time.perf_counter(), t_f)
        time.sleep(
            max(0.0, self._start[0] + (t_f - self._start[1]) / self.speed - time.perf_counter())
        )
        sent = time.perf_counter()
        try:
            conn.sendall(data)
        except OSError as exc:  # a reset or broken pipe: the controller has gone
            raise InputError(self._lost(t_f, f"{exc.strerror or exc} as it was sent")) from None
        answer = self._next(conn, t_f)
        self._trips.append(time.perf_counter() - sent)
        try:
            stamp, modes = read_modes(answer, self.ctrl.mode.size, self.cfg.idcode)
        except InputError as exc:
            raise InputError(self._lost(t_f, str(exc))) from None
        soc, counts = c37.time_stamp(self.cfg, t_f)
        if stamp != soc * c37.TIME_BASE + counts:
            raise InputError(self._lost(t_f, "answered another frame than this"))
        self.ctrl.mode = modes
        self.answers.append((t_f, modes))
        return modes

    def _connected(self) -> socket.socket:
        """The controller's connection: the first allowed peer that asks for CFG-2 and
        says 'start' (valid command frames) within the time-out, each peer's handshake
        on a thread of its own (a silent stranger holds no one up); others are dropped.
        At most `Guard.max_peers` handshakes at once: a new peer takes the place of the
        one connected longest without a valid command, else of the one connected
        longest (a flood of silent connections held a thread and a descriptor each until
        the time-out: 1 100 of them ended the plant with "Too many open files" before its
        controller came); an accept() short of descriptors or buffers is tried again."""
        if self._conn is not None:
            return self._conn
        deadline = time.monotonic() + self.timeout
        won: list[_Shake | None] = []
        live: list[_Shake] = []
        lock = threading.Lock()

        def shake(me: _Shake) -> None:
            try:
                self._handshake(me, deadline)
            except (InputError, OSError) as exc:
                with lock:
                    live.remove(me)
                self._drop(me.peer, self._evicted(me) if me.evicted else str(exc))
                me.conn.close()
                return
            with lock:
                live.remove(me)
                if me.evicted:  # its place given as it said 'start': its socket is shut
                    me.conn.close()
                    self._drop(me.peer, self._evicted(me))
                elif won:  # another peer took the loop first: dropped, and named
                    me.conn.close()
                    if won[0] is not None:
                        self._drop(me.peer, "another peer took the loop first")
                else:
                    won.append(me)

        self._sock.settimeout(0.05)
        while not won and time.monotonic() < deadline:
            me = self._accepted()
            if me is None:
                continue
            with lock:
                kept = [p for p in live if not p.evicted]  # the others are ending
                if len(kept) >= self.guard.max_peers:
                    victim = min(kept, key=lambda p: (p.commanded, p.since))
                    victim.evicted = True
                    with contextlib.suppress(OSError):  # wakes its thread: it ends, named
                        victim.conn.shutdown(socket.SHUT_RDWR)
                live.append(me)
            threading.Thread(target=shake, args=(me,), daemon=True).start()
        with lock:
            if won:
                self._conn = won[0].conn  # type: ignore[union-attr]
                with contextlib.suppress(OSError):  # gone already: the next send says so
                    self._peer = hostport(*self._conn.getpeername()[:2])
                return self._conn
            won.append(None)  # a late handshake closes its peer
        dropped = (
            f" ({self.n_refused} peer(s) dropped, the last {self._last_refused})"
            if self.n_refused
            else ""
        )
        short = f"; {self._short}" if self._short else ""
        raise InputError(f"no controller connected within {self.timeout:g} s{dropped}{short}")

    def _accepted(self) -> _Shake | None:
        """The next allowed peer (None: none came within the listening socket's time-out,
        one not allowed was dropped, or accept() failed for want of descriptors,
        buffers or memory, said once in the plant's final error and tried again after
        `ACCEPT_RETRY_S`)."""
        try:
            conn, peer = _accept_conn(self._sock)
        except TimeoutError:
            return None
        except OSError as exc:
            if exc.errno not in SHORT_OF:
                raise
            self._short = self._short or _accept_failed(exc)
            time.sleep(ACCEPT_RETRY_S)
            return None
        if not self.guard.admits(peer):
            self._drop(peer, "not in the allowed peers")
            conn.close()
            return None
        return _Shake(conn, peer, time.monotonic())

    def _evicted(self, me: _Shake) -> str:
        """Why a peer's handshake was ended for a new peer (`_connected`)."""
        what = "said no 'start'" if me.commanded else "sent no command"
        return (
            f"{what} in {time.monotonic() - me.since:.1f} s, with {self.guard.max_peers} peers "
            "connected: its place given to a new peer"
        )

    def _drop(self, peer, why: str) -> None:
        """Count a dropped peer and, among the first `NAMED_PEERS`, name it in `refused`
        (6 000 silent peers made a list of 6 000 lines in the plant's summary)."""
        line = f"{hostport(*peer[:2])}: {why}"
        self.n_refused += 1
        self._last_refused = line
        if len(self.refused) < NAMED_PEERS:
            self.refused.append(line)

    def _handshake(self, me: _Shake, deadline: float) -> None:
        """Answer 'cfg2' until 'start' (InputError past the deadline, each frame due
        whole by it, or on a peer that closes, speaks another protocol or addresses
        another IDCODE than the stream's: `c37_tcp.command_word`); `me.commanded` once
        a valid command came."""
        conn = me.conn
        conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        while True:
            conn.settimeout(max(deadline - time.monotonic(), 1e-3))
            try:
                frame = _read_frame(conn)
            except TimeoutError:
                raise InputError("sent no 'start' in time") from None
            if frame is None:
                raise InputError("closed before 'start'")
            word = command_word(frame, self.cfg.idcode)
            # a frame whose CRC fails, or no command this plant knows, is no valid command
            # (round 58 AZ01: seven strangers' bad frames kept their places and a peer that
            # had its CFG-2 was evicted for a ninth)
            me.commanded = me.commanded or word in COMMANDS or word in NOT_SENT
            if word == 2:  # 'start'
                return
            if word == 5:  # 'cfg2'
                conn.sendall(self.cfg2.convert2bytes())

    def _lost(self, t_f: float, what: str) -> str:
        """A message naming the controller's address, what it did (`what`) to the frame
        at t_f (s) and the frames it answered before."""
        return (
            f"the controller at {self._peer}: {what} (the frame at t = {t_f:.4f} s, after "
            f"{len(self.answers)} frame(s) answered)"
        )

    def _next(self, conn: socket.socket, t_f: float) -> bytes:
        """The controller's whole answer to the frame at t_f (s) within the time-out;
        InputError naming the controller, the frame and the frames answered if it sends
        none in time (or drips it), closes or resets the connection, or speaks another
        protocol."""
        conn.settimeout(self.timeout)
        try:
            frame = _read_frame(conn)
        except FrameTimeout as exc:
            raise InputError(self._lost(t_f, f"sent {exc}")) from None
        except TimeoutError:
            what = f"sent no answer within {self.timeout:g} s"
            raise InputError(self._lost(t_f, what)) from None
        except InputError as exc:  # cut in the middle, another protocol
            raise InputError(self._lost(t_f, str(exc))) from None
        except OSError as exc:  # a reset: the controller has gone
            raise InputError(self._lost(t_f, exc.strerror or str(exc))) from None
        if frame is None:
            raise InputError(self._lost(t_f, "closed the loop before its answer"))
        return frame


class Answered(NamedTuple):
    """What the controller answered (`serve_controller`).

    Attributes
    ----------
    frames : int
        Data frames answered.
    flagged : dict
        PMU values not used by their STAT (`c37.unusable`), by reason (the reasons that
        occurred only).
    gaps : tuple of Gap
        Each run of reporting instants the plant sent no frame for, between two it did
        (`sources.Gap`): one of at most `sources.FILL_S` s fed to the estimator as frames
        of missing values (it predicts across), after a longer one the estimator starts
        again (`closed_loop.LoopController.restart`), as `closed_loop.track` takes them.
    applied_latency_s : float or None
        The latency after each frame's time stamp at which the plant applied the modes,
        as its end-of-run header says (None: it says none).
    """

    frames: int
    flagged: dict
    gaps: tuple = ()
    applied_latency_s: float | None = None


def serve_controller(controller, cfg, host: str, port: int, timeout: float = 30.0) -> Answered:
    """The controller's end: subscribe to the plant at host:port, then answer every data
    frame with the modes `controller.act` gives (each answer stamped with the SOC and
    FRACSEC of the frame it answers), until the plant's end-of-run header.

    Parameters
    ----------
    controller : stabctl.estimation.closed_loop.LoopController
        The estimator and law (its `act`).
    cfg : stabctl.estimation.c37.StreamConfig
        The stream the controller expects (its PMUs' station names are checked against
        the plant's CFG-2).
    host, port : str, int
        The plant.
    timeout : float, optional
        Longest wait for a whole frame from the plant (s).

    Returns
    -------
    Answered
        Frames answered, PMU values not used by their STAT, and the gaps in the plant's
        time stamps.

    Raises
    ------
    InputError
        No plant there, no whole frame within `timeout` s, an answer to 'cfg2' that is
        not a readable CFG-2 (`c37.read_config`: a CFG-1 or CFG-3 among them), a CFG-2
        that does not describe the controller's stream (`c37.check_config`: its FNOM the
        case's nominal frequency among its fields), or a frame after 'start' that is
        neither a data frame of the stream (`c37.parse_frame`) nor the end-of-run header
        (its CRC valid), or more data frames than `c37_tcp.MAX_STREAM_BYTES` holds (a
        run that does not end).
    PlantStopped
        The plant closed the loop without its end-of-run header, or announced an end
        that is not its last frame's (`_check_run_end`) (an InputError).
    """
    from pyc37.frame import CommandFrame

    try:
        conn = socket.create_connection((host, port), timeout=timeout)
    except OSError as exc:
        raise InputError(f"no plant at {host}:{port}: {exc.strerror or exc}") from None
    from stabctl.estimation.sources import FILL_S, Gap, missing_frame

    n, last = 0, None
    ends: list[bytes] = []  # the first and the last data frame (`c37.ends_fault`)
    flagged: collections.Counter = collections.Counter()
    gaps: list[Gap] = []
    fill = int(round(FILL_S * cfg.rate))
    try:
        with conn:
            conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            conn.sendall(CommandFrame(cfg.idcode, "cfg2").convert2bytes())
            cfg2 = c37.read_config(_read_frame(conn) or b"", f"{host}:{port}'s CFG-2")
            try:
                c37.check_config(cfg2, cfg)
            except InputError as exc:
                raise InputError(f"the plant at {host}:{port}: {exc}") from None
            most = most_frames(cfg2, MAX_STREAM_BYTES, End())  # the rows the loop keeps
            conn.sendall(CommandFrame(cfg.idcode, "start").convert2bytes())
            while (data := _read_frame(conn)) is not None:
                if (t_end := _end_time(data, cfg.idcode)) is not None:
                    _check_run_end(t_end, last, n, cfg.rate, f"{host}:{port}")
                    applied = _applied_latency(data, cfg.idcode)
                    return Answered(n, dict(flagged), tuple(gaps), applied)
                if n >= most:
                    raise InputError(
                        f"the plant at {host}:{port} sent more than {most} data frames (what "
                        f"a stream received may hold, {MAX_STREAM_BYTES / 2**20:g} MiB) "
                        "without ending its run: a plant's run is one disturbance, whose "
                        "frames the controller keeps"
                    )
                try:  # a data frame, checked (`c37.check_data_frame`), on the rate's grid
                    frame, odd = c37.plausible(c37.parse_frame(cfg, cfg2, data), cfg.f0)
                    if odd:
                        flagged[c37.IMPLAUSIBLE] += odd
                    first, prev = (ends[0], ends[-1]) if ends else (None, None)
                    if why := c37.ends_fault(first, prev, n, data, cfg2):
                        raise InputError(why)
                except InputError as exc:
                    raise InputError(
                        f"the plant at {host}:{port}: its frame {n + 1} after 'start': {exc}"
                        f", after {n} frame(s) answered"
                    ) from None
                flagged.update(why for why in c37.flags(cfg2, data) if why)
                k = round(frame.t * cfg.rate)
                if last is not None and (lost := k - round(last * cfg.rate) - 1) > 0:
                    # as `sources.read_frames` and `closed_loop.track` take a gap: the
                    # estimator predicts across a short one frame by frame (no answer is
                    # due: no frame came), starts again after a longer one
                    gaps.append(Gap(last, frame.t, lost, lost <= fill))
                    if lost > fill:
                        controller.restart()
                    for j in range(lost if lost <= fill else 0):
                        controller.act(missing_frame((k - lost + j) / cfg.rate, frame.valid.size))
                soc, counts = int.from_bytes(data[6:10], "big"), int.from_bytes(data[11:14], "big")
                conn.sendall(modes_frame(cfg.idcode, soc, counts, controller.act(frame)))
                n, last = n + 1, frame.t
                ends = [ends[0] if ends else data, data]
    except KeyboardInterrupt as exc:  # said with what was answered (a loop is not resumed)
        at = "" if last is None else f", the last at t = {last:.4f} s"
        exc.kept = (  # type: ignore[attr-defined]
            f"the controller stopped after answering {n} frame(s) from the plant at "
            f"{host}:{port}{at}; a closed loop is not resumed: the plant's run is to be "
            "started again with its controller"
        )
        raise
    except OSError as exc:  # a reset or broken pipe (not a plant, or a second controller)
        if isinstance(exc, FrameTimeout):  # a frame dripped, not finished in time
            what = f"sent {exc}"
        elif isinstance(exc, TimeoutError):
            what = f"sent nothing for {timeout:g} s"
        else:
            what = exc.strerror or str(exc)
        raise InputError(
            f"the plant at {host}:{port}: {what}, after {n} frame(s) answered (a plant is "
            "`stabctl pmu plant`, one controller at a time)"
        ) from None
    at = "" if last is None else f", the last at t = {last:.4f} s"
    raise PlantStopped(
        f"the plant at {host}:{port} closed the loop without ending its run, after {n} "
        f"frame(s) answered{at}: it stopped early (killed or crashed), so they are not "
        "the whole run"
    )


def _check_run_end(t_end: float, last: float | None, n: int, rate: int, where: str) -> None:
    """PlantStopped unless the last frame answered (t = `last` s, None: none) is the
    plant's last reporting instant at or before the end of run it announced (`t_end` s):
    within one frame interval (1 / `rate` s) before it, to the time stamps' microsecond.
    The frame at t = 0 is decided in the plant (no run has two points yet) and never
    sent; a run that answers none is no run (a plant's run ends after its fault, `pmu
    plant` refuses an end at or before it), and refused as such."""
    if last is None:
        raise PlantStopped(
            f"the plant at {where} announced the end of its run at t = {t_end:.4f} s "
            "before any frame was answered: no run was controlled"
        )
    t_last = last
    count = 1.0 / c37.TIME_BASE
    if t_end - 1.0 / rate + count < t_last <= t_end + count:
        return
    at = "none" if last is None else f"the last at t = {last:.4f} s"
    raise PlantStopped(
        f"the plant at {where} announced the end of its run at t = {t_end:.4f} s, after "
        f"{n} frame(s) answered ({at}, {rate} frames/s): its frames "
        + ("stopped before that end" if t_last <= t_end else "went past that end")
        + ", so they are not the whole run"
    )


def controller_thread(controller, cfg, address, timeout: float = 30.0):
    """`serve_controller` in a daemon thread; returns (thread, errors): the thread's
    exception, if any, is appended to errors."""
    errors: list[Exception] = []

    def run():
        try:
            serve_controller(controller, cfg, address[0], address[1], timeout=timeout)
        except (InputError, OSError) as exc:  # handed to the caller
            errors.append(exc)

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    return thread, errors
