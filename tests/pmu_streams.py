"""The PMU stream and the fake servers that the stream tests (tests/cli) and the
reliability probes (benchmarks/reliability_probes*.py) share: each written once.

Importable from any test module (``tests/`` is on ``sys.path``, as ``model_rows``); the
benchmarks put ``tests/`` on ``sys.path`` first."""

from __future__ import annotations

import socket
import threading
from contextlib import contextmanager


def kundur_stream(t_end: float = 2.0, rate: int = 60):
    """Kundur's bus-3 fault on line 3-101 at 1 s, cleared after 6 cycles, simulated for
    `t_end` s, and its 4 machine PMUs' frames (default C37.118.1 noise, seed 1) at `rate`
    frames/s.

    Returns
    -------
    case, pmus, cfg, frames
        The case, its machine PMUs, their `c37.StreamConfig` and the `pmu.Frame` list
        (t = 0 .. t_end s).
    """
    import stabctl
    from stabctl.dynamics.events import fault_with_clearing
    from stabctl.estimation import c37
    from stabctl.estimation import pmu as pm
    from stabctl.estimation.settings import PMUSettings

    case = stabctl.load_case("kundur")
    res = stabctl.Simulator(case).run([fault_with_clearing(case, 3, 101, 1.0, 6)], t_end=t_end)
    pmus = pm.machine_pmus(case)
    frames = list(pm.measure(pm.phasor_truth(case, res, pmus), PMUSettings(), seed=1))
    return case, pmus, c37.stream_config(case, pmus, rate), frames


def on_the_wire(cfg, frames) -> tuple[bytes, list[bytes]]:
    """(CFG-2 frame, data frames) of a stream as bytes: what `c37.record` writes and a
    C37.118.2 server sends."""
    from stabctl.estimation import c37

    cfg2 = c37.config_frame(cfg)
    return cfg2.convert2bytes(), [c37.data_frame(cfg, cfg2, f) for f in frames]


def fake_server(talk, *, answer_all: bool = False) -> tuple[socket.socket, int]:
    """A fake server on 127.0.0.1 at a free port, for the tests and probes that point a
    command at one (a web server, a PMU server): a daemon thread accepts a connection and
    runs ``talk(conn)`` on it.

    Parameters
    ----------
    talk : callable
        What the server does on a connection: ``talk(conn)``, conn the accepted socket.
    answer_all : bool, optional
        True: every connection until the caller closes the listening socket, each left
        open once talked to (the client, not the server, hangs up; an OSError in `talk`
        ends the thread).  False: the first connection only, closed after `talk` (an
        OSError in `talk`, the client gone, ends it quietly), then the listening socket.

    Returns
    -------
    (socket.socket, int)
        The listening socket (the caller closes it when done: closing it again is
        harmless) and its port.
    """
    srv = socket.create_server(("127.0.0.1", 0))

    def serve():
        while True:
            try:
                conn, _ = srv.accept()
            except OSError:
                return  # the caller closed the listening socket
            if answer_all:
                talk(conn)
                continue
            with conn:
                try:
                    talk(conn)
                except OSError:
                    pass
            srv.close()
            return

    threading.Thread(target=serve, daemon=True).start()
    return srv, srv.getsockname()[1]


@contextmanager
def endless_server(head: bytes, body: list, gap: float = 0.1):
    """A PMU server that sends the CFG-2 `head` on request, then after 'start' a data
    frame of `body` every `gap` s, and then nothing, never closing the connection (an
    endless stream, as far as its client knows) until the block ends.

    Yields
    ------
    (int, threading.Event)
        The port, and an event set once the first data frame is sent (the client is
        receiving).
    """
    stop, streaming = threading.Event(), threading.Event()

    def talk(conn):
        conn.recv(1000)  # 'cfg2'
        conn.sendall(head)
        conn.recv(1000)  # 'start'
        for frame in body:
            conn.sendall(frame)
            streaming.set()
            if stop.wait(gap):
                return
        stop.wait()

    srv, port = fake_server(talk)
    try:
        yield port, streaming
    finally:
        stop.set()
        srv.close()
