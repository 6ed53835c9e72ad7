"""A C37.118.2-2011 PMU server on TCP for one stream of simulated PMUs
(`stabctl.estimation.c37`): it answers the command frames (Table 15: send CFG-2 or the
header, turn transmission on or off) and, once turned on, sends the stream's data frames
paced at their time stamps (divided by `speed`: 1 real time, inf as fast as the socket
takes them).

Not pyc37's ``Pmu``: its client handler waits up to 100 ms for a command before sending
each queued frame, so it sends at most about 9 frames/s, and drops frames silently once
1000 are queued (pyc37 1.0.2 ``pmu.py``); a 60 frames/s stream needs a sender paced by
the frames' own time stamps.  Its ``Pdc`` client reads this server's frames (with a
receive buffer of at most one frame header, ``buffer_size=4``: its ``get`` keeps no bytes
beyond the frame it reads).
"""

from __future__ import annotations

import socket
import threading
import time

from stabctl.errors import InputError
from stabctl.estimation import c37

#: C37.118.2-2011 Table 15 command words this server acts on
COMMANDS = {1: "stop", 2: "start", 3: "header", 5: "cfg2"}


class StreamServer:
    """Serve one stream's frames to one client at a time on ``host``:``port`` (0: a free
    port, `address` tells which).  Build it with `of_frames` (simulated PMUs) or
    `of_recording` (a recording, its frames re-sent as they are).

    Parameters
    ----------
    cfg2 : pyc37 ConfigFrame2
        The stream's configuration frame.
    data : list of bytes
        The data frames, in time-stamp order.
    host : str, optional
        Address to listen on (default loopback).
    port : int, optional
        TCP port (default 0: any free one).
    speed : float, optional
        Time-stamp seconds per wall-clock second (default 1, real time; ``inf``: no
        pacing).

    Attributes
    ----------
    sent_at : list of float
        ``time.perf_counter()`` when each data frame was handed to the socket (NaN until).
    due_at : list of float
        ``time.perf_counter()`` at which each frame was due by its time stamp.
    finished : threading.Event
        Set when a session has ended (every frame sent, or the client gone).

    Raises
    ------
    InputError
        A speed that is not > 0, or no frame to serve.
    OSError
        The address cannot be listened on (a port in use).
    """

    def __init__(self, cfg2, data, host: str = "127.0.0.1", port: int = 0, speed=1.0):
        if not speed > 0:
            raise InputError(f"speed must be > 0, got {speed}")
        if not data:
            raise InputError("a stream server needs at least one data frame")
        self.speed, self._cfg2, self._data = float(speed), cfg2, list(data)
        self._t = [c37.frame_time(d) for d in self._data]
        self.sent_at = [float("nan")] * len(self._data)
        self.due_at = [float("nan")] * len(self._data)
        self._sock = socket.create_server((host, port))
        self._stop, self.finished = threading.Event(), threading.Event()
        self._thread = threading.Thread(target=self._accept, daemon=True)
        self._thread.start()

    @classmethod
    def of_frames(cls, cfg, frames, **kw) -> StreamServer:
        """The server of a stream's `pmu.Frame` objects (encoded once here; ``kw`` as the
        constructor's)."""
        cfg2 = c37.config_frame(cfg)
        return cls(cfg2, [c37.data_frame(cfg, cfg2, f) for f in frames], **kw)

    @classmethod
    def of_recording(cls, path, **kw) -> StreamServer:
        """The server of a recording (`c37.record`'s or any capture): its CFG-2 and data
        frames re-sent as recorded.  Raises InputError as `c37.recorded_frames`."""
        cfg2, data = c37.recorded_frames(path)
        return cls(cfg2, data, **kw)

    @property
    def n_frames(self) -> int:
        """Data frames served per session."""
        return len(self._data)

    @property
    def n_sent(self) -> int:
        """Data frames handed to the socket in the last session."""
        return sum(t == t for t in self.sent_at)  # NaN until sent

    @property
    def address(self) -> tuple[str, int]:
        """(host, port) the server listens on."""
        host, port = self._sock.getsockname()[:2]
        return host, port

    def close(self) -> None:
        """Stop serving and close the listening socket."""
        self._stop.set()
        self._sock.close()
        self._thread.join(timeout=5)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _accept(self) -> None:
        while not self._stop.is_set():
            try:
                conn, _ = self._sock.accept()
            except OSError:  # closed
                return
            with conn:
                conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                try:
                    self._serve(conn)
                except InputError:  # a client of another protocol: dropped, serve on
                    continue
                except OSError:  # the client vanished mid-session: the session ends
                    pass
            self.finished.set()

    def _serve(self, conn: socket.socket) -> None:
        """Commands until the client closes; a 'start' streams every frame (commands
        received meanwhile are read between frames)."""
        while not self._stop.is_set():
            command = self._command(conn, block=True)
            if command is None:
                return
            if command == "cfg2":
                conn.sendall(self._cfg2.convert2bytes())
            elif command == "header":
                conn.sendall(self._header())
            elif command == "start":
                self._stream(conn)
                return

    def _stream(self, conn: socket.socket) -> bool:
        """Send the data frames paced by their time stamps; False if the client left or
        said 'stop'."""
        start = time.perf_counter()
        for k, data in enumerate(self._data):
            due = start + (self._t[k] - self._t[0]) / self.speed
            self.due_at[k] = due
            while (wait := due - time.perf_counter()) > 0:
                if self._command(conn, block=False, timeout=min(wait, 0.05)) in ("stop", None):
                    return False
            try:
                conn.sendall(data)
            except OSError:
                return False
            self.sent_at[k] = time.perf_counter()
        return True

    def _command(self, conn: socket.socket, block: bool, timeout: float = 0.0):
        """The next command frame's word as a name (None: the client closed; '' none or
        one this server ignores)."""
        conn.settimeout(None if block else timeout)
        try:
            frame = _read_frame(conn)
        except TimeoutError:
            return ""
        finally:
            conn.settimeout(None)
        if frame is None:
            return None
        if frame[1] & 0x70 != 0x40:  # frame type 100: a command frame
            return ""
        return COMMANDS.get(int.from_bytes(frame[14:16], "big"), "")

    def _header(self) -> bytes:
        from pyc37.frame import HeaderFrame

        c = self._cfg2
        text = f"stabctl simulated PMUs: {c.get_num_pmu()}, {c.get_data_rate()} frames/s"
        return HeaderFrame(c.get_id_code(), text, c.get_soc(), (0, "+")).convert2bytes()


def _recv_exactly(conn: socket.socket, n: int):
    """n bytes from conn (None if the peer closed first)."""
    out = b""
    while len(out) < n:
        chunk = conn.recv(n - len(out))
        if not chunk:
            return None
        out += chunk
    return out


def receive(
    host: str, port: int, n: int | None = None, pdc_id: int = 1, timeout: float = 30.0
) -> tuple:
    """The CFG-2 frame and the data frames (bytes, as received) of the C37.118.2 stream at
    host:port: command frames (pyc37's) 'cfg2', then 'start', then 'stop' once n frames
    have arrived (n None: every frame until the server ends the stream by closing).

    Raises
    ------
    InputError
        No server there, silence for `timeout` s, the connection closed before n frames
        (or before any with n None), or a reply to 'cfg2' that is not a configuration
        frame.
    """
    from pyc37.frame import CommandFrame

    try:
        conn = socket.create_connection((host, port), timeout=timeout)
    except OSError as exc:
        raise InputError(f"no C37.118.2 server at {host}:{port}: {exc.strerror or exc}") from None
    with conn:
        try:
            conn.sendall(CommandFrame(pdc_id, "cfg2").convert2bytes())
            cfg2 = _frame(conn)
            if cfg2[1] & 0x70 != 0x30:  # frame type 011: CFG-2
                raise InputError(
                    f"{host}:{port} answered 'cfg2' with frame type {cfg2[1] >> 4 & 7}"
                )
            conn.sendall(CommandFrame(pdc_id, "start").convert2bytes())
            if n is None:
                data = list(iter(lambda: _read_frame(conn), None))
                if not data:
                    raise InputError(f"{host}:{port} closed the stream before a data frame")
            else:
                data = [_frame(conn) for _ in range(n)]
                conn.sendall(CommandFrame(pdc_id, "stop").convert2bytes())
        except TimeoutError:
            raise InputError(f"{host}:{port}: nothing received for {timeout:g} s") from None
    return cfg2, data


def _frame(conn: socket.socket) -> bytes:
    """One whole frame from conn; InputError if it closes first."""
    frame = _read_frame(conn)
    if frame is None:
        raise InputError("the C37.118.2 server closed the connection")
    return frame


def _read_frame(conn: socket.socket):
    """One whole frame from conn, SYNC and FRAMESIZE first (None if the peer closed).

    Raises
    ------
    InputError
        Bytes that do not start a C37.118.2 frame (SYNC 0xAA, FRAMESIZE of at least 16):
        the peer speaks another protocol.
    """
    head = _recv_exactly(conn, 4)
    if head is not None and (head[0] != 0xAA or int.from_bytes(head[2:4], "big") < 16):
        raise InputError(f"the peer does not speak C37.118.2: it sent {head!r} for a frame start")
    body = None if head is None else _recv_exactly(conn, int.from_bytes(head[2:4], "big") - 4)
    return None if body is None else head + body


def pdc_client(host: str, port: int, pdc_id: int = 1):
    """pyc37's own PDC client connected to host:port, set up to read a stream whole: a
    receive buffer of one frame header (its ``get`` keeps no bytes beyond the frame it
    reads, so a larger buffer loses the next frame when two arrive together) and its
    loggers, which write every connection to stdout at INFO, at WARNING.  Used by the
    tests and benchmarks/bench_c37.py as the independent client."""
    import logging

    from pyc37.pdc import Pdc

    pdc = Pdc(pdc_id=pdc_id, pmu_ip=host, pmu_port=port, buffer_size=4)
    pdc.run()
    for name in list(logging.root.manager.loggerDict):
        if name.startswith(("pyc37", "CLIENT")):
            logging.getLogger(name).setLevel(logging.WARNING)
    return pdc
