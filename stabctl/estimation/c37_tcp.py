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

import contextlib
import errno
import ipaddress
import math
import os
import socket
import struct
import threading
import time
from dataclasses import dataclass

from stabctl.errors import InputError
from stabctl.estimation import c37
from stabctl.jsontext import MAX_INPUT_BYTES

#: least size of a command frame, bytes: SYNC, FRAMESIZE, IDCODE, SOC, FRACSEC, CMD and
#: CHK (C37.118.2-2011 Table 15; an extended frame adds to it)
COMMAND_BYTES = 18
#: C37.118.2-2011 Table 15 command words this server acts on
COMMANDS = {1: "stop", 2: "start", 3: "header", 5: "cfg2"}
#: Table 15 command words for a configuration this server does not send (it sends its
#: stream's CFG-2 only): not answered, and named as the peer's if it is dropped
NOT_SENT = {4: "CFG-1 (command 4)", 6: "CFG-3 (command 6)"}
#: distinct peer addresses a server names as it refuses them (`StreamServer.news`); the
#: refusals beyond are counted, so a scan from many addresses cannot flood the terminal
NAMED_PEERS = 64
#: refusals of one address named in `RENAME_S` s, the others counted (a scan from one
#: address)
NAMED_PER_WINDOW, RENAME_S = 5, 10.0
#: accept() errors of a process or system short of resources (open files, buffers,
#: memory): the server says so once and tries again every `ACCEPT_RETRY_S` s, serving on
#: once the resource is free
SHORT_OF = {errno.EMFILE, errno.ENFILE, errno.ENOBUFS, errno.ENOMEM}
ACCEPT_RETRY_S = 0.1
#: how often the accept thread looks whether the server was closed (s)
ACCEPT_POLL_S = 0.2


@dataclass(frozen=True)
class Guard:
    """Who may talk to a server and how long it waits for them.

    Attributes
    ----------
    allow : tuple of str
        Peer addresses (IP, as the socket reports them) allowed to connect; empty: any.
        A connection from another address is closed at once and counted in
        `StreamServer.refused`.
    timeout : float
        Longest wait for a whole frame from a peer expected to send (a command, an
        answer: silence and a frame sent byte by byte alike), and for a peer to take a
        frame (s); a peer past it is dropped.
    max_peers : int
        Peers served at once.  With every place taken, a new peer takes the place of the
        peer that has waited longest without sending a valid command (silent since it
        connected), else of the one connected longest, beyond `timeout`, without starting
        a stream (asking for the header or CFG-2 over and over); it is dropped and named.
        A peer streaming keeps its place; with none to drop, the new peer is closed at
        once.
    wait : float
        Once every streaming session so far was cut (`StreamServer.done`), the longest
        wait for another peer (s) before the server is done.
    """

    allow: tuple = ()
    timeout: float = 30.0
    max_peers: int = 8
    wait: float = 60.0

    def admits(self, peer) -> bool:
        """True if the peer's address (a socket's ``getpeername``) may connect."""
        return not self.allow or plain_ip(peer[0]) in self.allow


def plain_ip(address: str) -> str:
    """An IP address as `Guard.allow` holds it: an IPv4-mapped IPv6 address (a dual-stack
    socket's IPv4 peer, ``::ffff:10.0.0.5``) as its IPv4 address, any other in its
    compressed form, without an IPv6 zone (``fe80::1%eth0`` as ``fe80::1``: a peer is
    matched by its address; round 46: ``--allow ::1%lo`` admitted no one).

    Parameters
    ----------
    address : str
        An IPv4 or IPv6 address.

    Returns
    -------
    str
        The address.

    Raises
    ------
    ValueError
        Not an IP address.
    """
    ip = ipaddress.ip_address(address)
    if getattr(ip, "scope_id", None):
        ip = ipaddress.ip_address(address.split("%", 1)[0])
    return str(getattr(ip, "ipv4_mapped", None) or ip)


def listen(host: str, port: int) -> socket.socket:
    """A TCP socket listening on host:port, IPv4 or IPv6 as host resolves (``::``, every
    IPv6 interface, takes IPv4 peers too where the system can).

    Parameters
    ----------
    host : str
        Address or host name to listen on.
    port : int
        TCP port (0: any free one).

    Returns
    -------
    socket.socket
        The listening socket.

    Raises
    ------
    InputError
        A host that does not resolve, an address that is not this machine's, a port in
        use: naming ``--host`` and ``--port`` and the system's reason.
    """
    try:
        family, _, _, _, addr = socket.getaddrinfo(
            host, port, type=socket.SOCK_STREAM, flags=socket.AI_PASSIVE
        )[0]
        dual = addr[0] == "::" and socket.has_dualstack_ipv6()
        return socket.create_server(addr, family=family, dualstack_ipv6=dual)
    except OSError as exc:  # create_server's message adds the address as a tuple
        why = os.strerror(exc.errno) if exc.errno and exc.errno > 0 else exc.strerror or exc
        raise InputError(f"--host {host} --port {port}: cannot listen: {why}") from None


def hostport(host: str, port: int) -> str:
    """An address as written in a URL and read by `split_hostport`.

    Parameters
    ----------
    host : str
        Host name or IP address.
    port : int
        TCP port.

    Returns
    -------
    str
        ``host:port``, an IPv6 address in brackets (``[::1]:4712``).
    """
    return f"[{host}]:{port}" if ":" in host else f"{host}:{port}"


def split_hostport(text: str) -> tuple[str, str]:
    """The host and port of an address (``HOST:PORT``, ``[IPv6]:PORT``: RFC 3986's
    form).

    Parameters
    ----------
    text : str
        The address.

    Returns
    -------
    (str, str)
        The host (without brackets; empty if none) and the port's text (not checked).

    Raises
    ------
    InputError
        A bracket other than those around a whole IPv6 host (``[::1:4712``), or an IPv6
        host without them (``::1:4712`` is itself an IPv6 address: which colon ends the
        host cannot be told).
    """
    host, _, port = text.rpartition(":")
    bracketed = host.startswith("[") and host.endswith("]")
    if bracketed:
        host = host[1:-1]
    if "[" in host or "]" in host or "[" in port or "]" in port or (":" in host and not bracketed):
        raise InputError(
            f"{text!r} is not HOST:PORT (an IPv6 address in brackets, then its port: [::1]:4712)"
        )
    return host, port


#: the TCP ports an address may name (0, "any free one", only where a server listens)
PORTS = range(1, 65536)


def port_number(text: str) -> int:
    """The TCP port of an address's port text (`split_hostport`).

    Parameters
    ----------
    text : str
        The port as written: ASCII digits.

    Returns
    -------
    int
        In :data:`PORTS`, 1-65535.

    Raises
    ------
    InputError
        Not ASCII digits (``expected HOST:PORT``), or a number outside 1-65535 (``port
        99999 is out of range (1-65535)``; a port of more than 5 digits, leading zeros
        aside, is named by its length and never converted: Python refuses to convert a
        string of more than 4300 digits); the caller adds the address.
    """
    if not (text.isascii() and text.isdigit()):
        raise InputError("expected HOST:PORT")
    digits = text.lstrip("0") or "0"
    if len(digits) > len(str(PORTS[-1])):
        raise InputError(f"port of {len(digits)} digits is out of range ({PORTS[0]}-{PORTS[-1]})")
    if int(digits) not in PORTS:
        raise InputError(f"port {int(digits)} is out of range ({PORTS[0]}-{PORTS[-1]})")
    return int(digits)


class StreamServer:
    """Serve one stream's frames on ``host``:``port`` (0: a free port, `address` tells
    which), each peer on a thread of its own: CFG-2 and header on request, the data frames
    from 'start'.  Build it with `of_frames` (simulated PMUs) or `of_recording` (a
    recording, its frames re-sent as they are).  Command frames are obeyed only with a
    valid CRC and addressed to the stream's IDCODE (C37.118.2-2011 Table 2: a command's
    IDCODE is its destination stream's); a peer that is not allowed (`Guard.allow`),
    addresses another IDCODE, sends no whole frame within the time-out (silent, or
    dripping bytes), speaks another protocol or connects and closes is dropped without
    ending the server's session.

    Each PDC that says 'start' has a session of its own, and its own verdict (`Session`).
    'stop' pauses the session's data frames (C37.118.2-2011 Table 15, 'turn off
    transmission'): the connection stays open and 'start' resumes them where they
    stopped; requests for the CFG-2 or the header are answered at any time, mid-stream
    too.  After the last data frame the server closes its side of the connection, and the
    session is whole only once the PDC closes its side in turn, in order (FIN), within
    `Guard.timeout` s: a TCP whose application closes with bytes unread resets the
    connection instead (RFC 1122 4.2.2.13, as Linux, the BSDs and Windows do), so an orderly
    close after the last frame is the evidence that the PDC read the stream to its end.  A
    'stop' after the last frame, or TCP acknowledgements, are not: a peer that reads nothing
    has the whole stream acknowledged by its kernel once it fits the receive buffer.  A peer
    that half-closes (shuts only its sending side) with the frames unread cannot be told
    apart from a reader either: its in-order close is a reader's (docs/estimation.md section
    6; `Guard.allow` keeps such peers out).  A PDC still connected `Guard.timeout` s after
    the last frame is cut (delivery not confirmed), as is one that resets the connection,
    says 'stop' and leaves, or takes no frame for the time-out.  One PDC's session never
    decides another's: the server is done (`done`) once one session was whole and none
    streams, or, with every session cut, once no peer has been connected for `Guard.wait` s.

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
    guard : Guard, optional
        Allowed peers and time-outs (default: any peer, 30 s).

    Attributes
    ----------
    sessions : list of Session
        Every session that streamed, as each ended: whole, or cut by what its PDC did.
    finished : threading.Event
        Set once a session has delivered the stream whole (`Session.whole`).
    refused : list of str
        Peers refused or dropped, each with the reason (at most `NAMED_PEERS` x 16 kept;
        `unlisted` counts the others).
    news : list of str
        What happened, in order, for a caller to print as it happens: each session's end
        (`Session`), and each refused peer as it is refused: at most `NAMED_PER_WINDOW`
        of one address in `RENAME_S` s (the next named says how many were not), and of
        at most `NAMED_PEERS` addresses (then one line saying the rest are counted
        only); `close` adds the counts never named.

    Raises
    ------
    InputError
        A speed that is not > 0, no frame to serve, or an address that cannot be listened
        on (`listen`).
    """

    def __init__(
        self, cfg2, data, host: str = "127.0.0.1", port: int = 0, speed=1.0, guard=Guard()
    ):
        if not speed > 0:
            raise InputError(f"speed must be > 0, got {speed}")
        if not data:
            raise InputError("a stream server needs at least one data frame")
        self.speed, self._cfg2, self._data, self.guard = float(speed), cfg2, list(data), guard
        self._t = list(c37.stamp_times(self._data, cfg2))  # across a leap second too
        self.sessions: list[Session] = []
        self.refused: list[str] = []
        self.unlisted = 0
        self.news: list[str] = []
        self._lock = threading.Lock()
        self._named: dict[str, list] = {}  # address -> [last named at, refusals since]
        self._open = self._streaming = 0
        self._idle_since = time.monotonic()
        self._shown: _Shown | None = None  # the session `sent_at`, `due_at` show
        self._sock = listen(host, port)
        self._address = self._sock.getsockname()[:2]
        self._stop, self.finished = threading.Event(), threading.Event()
        self._live: dict[int, _Peer] = {}  # the peers connected, by id
        self._closed = False
        self._sock.settimeout(ACCEPT_POLL_S)  # accept() looks at `_stop` this often
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
        frames re-sent as recorded, each checked first.  Raises InputError as
        `c37.recorded_frames`, or at a data frame `c37.check_data_frame` refuses (named
        by its number), before listening."""
        cfg2, data = c37.recorded_frames(path)
        c37.check_data_frames(cfg2, data, f"C37.118.2 recording {path}")
        return cls(cfg2, data, **kw)

    @property
    def idcode(self) -> int:
        """The stream's IDCODE, which a peer's commands must address."""
        return int(self._cfg2.get_id_code())

    @property
    def n_frames(self) -> int:
        """Data frames served per session."""
        return len(self._data)

    @property
    def n_sent(self) -> int:
        """Data frames sent in the first session that was whole, else the most any session
        sent (0 before any)."""
        whole = [s.sent for s in self.sessions if s.whole]
        return whole[0] if whole else max((s.sent for s in self.sessions), default=0)

    @property
    def sent_at(self) -> list:
        """``time.perf_counter()`` when each data frame was handed to the socket, in the
        first session that was whole, else the last that began streaming (NaN until)."""
        return list(self._shown.sent_at) if self._shown else [math.nan] * len(self._data)

    @property
    def due_at(self) -> list:
        """``time.perf_counter()`` at which each frame was due by its time stamp, in the
        session `sent_at` shows."""
        return list(self._shown.due_at) if self._shown else [math.nan] * len(self._data)

    @property
    def cut(self) -> list:
        """The sessions that were not whole, each as `Session` says it."""
        return [s for s in self.sessions if not s.whole]

    def done(self) -> bool:
        """True when the server has nothing more to do: a session was whole and no PDC is
        at work (streaming, or connected and past its first command within `Guard.timeout`
        s of connecting: a PDC that has its CFG-2 and has not said 'start' yet is served,
        not left with a closed server; round 58 AZ08: a peer asking for the header every
        2 s, never starting, held the server open for as long as it went on), or every
        session that streamed was cut and no peer has been connected for `Guard.wait` s
        (no PDC came for the stream again)."""
        with self._lock:
            if self.finished.is_set():
                late = time.monotonic() - self.guard.timeout
                at_work = any(
                    p.commanded and not p.evicted and p.since > late for p in self._live.values()
                )
                return self._streaming == 0 and not at_work
            idle = self._open == 0 and time.monotonic() - self._idle_since >= self.guard.wait
            return bool(self.sessions) and idle

    @property
    def address(self) -> tuple[str, int]:
        """(host, port) the server listens on (or listened on, once closed)."""
        host, port = self._address
        return host, port

    def close(self) -> None:
        """Stop serving and close the listening socket (at once: the accept thread wakes
        within `ACCEPT_POLL_S` s); a second call does nothing."""
        with self._lock:
            if self._closed:
                return
            self._closed = True
        self._stop.set()
        with contextlib.suppress(OSError):  # wakes an accept() where the system does
            self._sock.shutdown(socket.SHUT_RDWR)
        self._sock.close()
        self._thread.join(timeout=2 * ACCEPT_POLL_S)
        with self._lock:
            for addr, (_, _, since) in self._named.items():
                if since:
                    who = addr or f"the other addresses (beyond {NAMED_PEERS})"
                    self.news.append(f"dropped {who} {since} more time(s) (not named above)")
            self._named.clear()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _refuse(self, peer, why: str) -> None:
        """A peer refused or dropped: kept in `refused`, named in `news` as the class says."""
        addr, now = plain_ip(peer[0]), time.monotonic()
        line = f"{hostport(*peer[:2])}: {why}"
        with self._lock:
            if len(self.refused) < 16 * NAMED_PEERS:
                self.refused.append(line)
            else:
                self.unlisted += 1
            seen = self._named.get(addr)
            if seen is None and len(self._named) >= NAMED_PEERS:
                if len(self._named) == NAMED_PEERS:
                    self._named[""] = [math.inf, math.inf, 0]  # said once
                    self.news.append(
                        f"dropped peers of more than {NAMED_PEERS} addresses: the others are "
                        "counted, not named"
                    )
                self._named[""][2] += 1
                return
            if seen is None:
                seen = self._named[addr] = [now, 0, 0]
            if now - seen[0] >= RENAME_S:
                seen[0], seen[1] = now, 0
            if seen[1] < NAMED_PER_WINDOW:
                again = f" ({seen[2]} more of {addr} not named before it)" if seen[2] else ""
                seen[1], seen[2] = seen[1] + 1, 0
                self.news.append(f"dropped {line}{again}")
            else:
                seen[2] += 1

    def _accept(self) -> None:
        """Accept peers until `close`; an accept() that fails (the process out of file
        descriptors, the system out of buffers) is said once per reason in `news` and
        tried again every `ACCEPT_RETRY_S` s."""
        failed: set = set()
        while not self._stop.is_set():
            try:
                conn, peer = _accept_conn(self._sock)
            except TimeoutError:  # no peer within ACCEPT_POLL_S: look at _stop
                continue
            except OSError as exc:
                if self._stop.is_set():  # closed
                    return
                if exc.errno not in failed:
                    failed.add(exc.errno)
                    with self._lock:
                        self.news.append(_accept_failed(exc))
                self._stop.wait(ACCEPT_RETRY_S)
                continue
            if not self.guard.admits(peer):
                self._refuse(peer, "not in the allowed peers")
                conn.close()
                continue
            me, victim = self._admit(conn)
            if victim is not None:
                with contextlib.suppress(OSError):  # wakes its thread: it ends, named
                    victim.conn.shutdown(socket.SHUT_RDWR)
            if me is None:
                self._refuse(
                    peer,
                    f"{self.guard.max_peers} peers served, each streaming or within its first "
                    f"{self.guard.timeout:g} s",
                )
                conn.close()
            else:
                threading.Thread(target=self._session, args=(me, peer), daemon=True).start()

    def _admit(self, conn: socket.socket):
        """(the new peer's `_Peer`, or None if refused; the peer dropped for it, or None):
        with `Guard.max_peers` connected, the one that has waited longest without a valid
        command gives its place, else the one connected longest beyond `Guard.timeout`
        without starting a stream (`Guard.max_peers`: eight peers asking for the header
        every 2 s held every place, and a PDC was refused for as long as they kept on)."""
        me, victim = _Peer(conn, time.monotonic()), None
        with self._lock:
            live = [p for p in self._live.values() if not p.evicted]
            if len(live) >= self.guard.max_peers:
                late = me.since - self.guard.timeout
                idle = [p for p in live if not p.commanded] or [
                    p for p in live if not p.streamed and p.since < late
                ]
                if not idle:
                    return None, None
                victim = min(idle, key=lambda p: p.since)
                victim.evicted = True
            self._live[id(me)] = me
            self._open += 1
        return me, victim

    def _session(self, me: _Peer, peer) -> None:
        """One peer's session: its `Session` added to `sessions` (and `finished` set if it
        was whole) if it streamed, else the peer named in `refused` if it was dropped."""
        asked: list[str] = []  # configurations asked for that this server does not send
        ended, dropped = None, True
        conn = me.conn
        try:
            with conn:
                conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                ended = self._serve(conn, asked, me)
                dropped = False
        except InputError as exc:  # another protocol, a cut frame: dropped, serve on
            self._refuse(peer, str(exc))
        except FrameTimeout as exc:  # a frame begun, dripped and not finished
            self._refuse(peer, f"sent {exc}")
        except AnswerTimeout as exc:  # commands sent, the answers not read
            self._refuse(peer, f"sent {me.commands} command(s) and {exc}")
        except TimeoutError:
            self._refuse(
                peer,
                f"{_asked(asked)}, then no command for {self.guard.timeout:g} s"
                if asked
                else f"{_ignored(me.ignored, 'silent')} for {self.guard.timeout:g} s",
            )
        except OSError:  # the peer vanished mid-session
            dropped = False
        finally:
            with self._lock:
                del self._live[id(me)]
                self._open -= 1
                if self._open == 0:
                    self._idle_since = time.monotonic()
        if ended is None and me.evicted:
            what = "started no stream" if me.commanded else "sent no command"
            self._refuse(
                peer,
                f"{what} in {time.monotonic() - me.since:.1f} s, with "
                f"{self.guard.max_peers} peers connected: its place given to a new peer",
            )
        elif ended is None and asked and not dropped:
            self._refuse(peer, f"{_asked(asked)}, then closed the connection")
        elif ended is None and not dropped and not me.commanded:  # a port scan, a stranger
            self._refuse(peer, _ignored(me.ignored, "closed the connection"))
        if ended is not None:
            why, shown = ended
            session = Session(
                hostport(*peer[:2]),
                shown.sent,
                len(self._data),
                why,
                _asked(asked) if asked else "",
            )
            with self._lock:
                self.sessions.append(session)
                self._streaming -= 1
                if session.whole and not self.finished.is_set():
                    self._shown = shown
                    self.finished.set()
                self.news.append(str(session))

    def _serve(self, conn: socket.socket, asked: list, me: _Peer):
        """Commands until the peer closes: 'start' streams the data frames from where they
        stopped (commands received meanwhile are read between frames), 'stop' pauses them
        (the connection stays open).  None if it did not stream, else (the session's
        verdict, its `_Shown`).  A request for a configuration this server does not send
        (`NOT_SENT`) is not answered and is added to `asked`."""
        shown = None
        while not self._stop.is_set():
            try:
                command = self._command(conn, block=True)
            except (TimeoutError, InputError, OSError) as exc:
                if shown is None:
                    raise
                return _paused_end(exc, self.guard.timeout), shown
            if command is None:
                return None if shown is None else (_PAUSED, shown)
            me.ignored += not command
            me.commands += bool(command)
            me.commanded = me.commanded or bool(command)
            if command == "start":
                with self._lock:  # (read by `_admit` under it)
                    me.streamed = True
                if shown is None:
                    shown = _Shown([math.nan] * len(self._data), [math.nan] * len(self._data))
                    with self._lock:
                        self._streaming += 1
                        if not self.finished.is_set():
                            self._shown = shown
                if (why := self._stream(conn, shown, asked)) != _PAUSED:
                    return why, shown
            else:
                self._answer(conn, command, asked)
        return None if shown is None else ("was stopped by the server's close", shown)

    def _answer(self, conn: socket.socket, command: str, asked: list) -> None:
        """Answer a command other than 'start' and 'stop': CFG-2 and header sent (at any
        time, mid-stream too: C37.118.2-2011 6.4), a configuration this server does not
        send added to `asked`."""
        try:
            if command == "cfg2":
                conn.sendall(self._cfg2.convert2bytes())
            elif command == "header":
                conn.sendall(self._header())
            elif command in NOT_SENT.values():
                asked.append(command)
        except TimeoutError:
            raise AnswerTimeout(
                f"took no answer to its commands for {self.guard.timeout:g} s"
            ) from None

    def _stream(self, conn: socket.socket, shown: _Shown, asked: list) -> str:
        """Send the data frames from `shown.sent` on, paced by their time stamps (each
        recorded in `shown`), then wait for the PDC to take the last (`_taken`): '' once
        it did, `_PAUSED` if it said 'stop' before, else what the peer did (closed the
        connection, ...)."""
        k0 = shown.sent
        start = time.perf_counter() - (self._t[k0] - self._t[0]) / self.speed
        try:
            for k in range(k0, len(self._data)):
                due = start + (self._t[k] - self._t[0]) / self.speed
                shown.due_at[k] = due
                while (wait := due - time.perf_counter()) > 0:
                    command = self._command(conn, block=False, timeout=min(wait, 0.05))
                    if command is None:
                        return "closed the connection"
                    if command == "stop":
                        return _PAUSED
                    self._answer(conn, command, asked)
                conn.settimeout(self.guard.timeout)
                conn.sendall(self._data[k])
                shown.sent_at[k] = time.perf_counter()
                shown.sent = k + 1
            return self._taken(conn)
        except FrameTimeout as exc:  # a command begun and not finished
            return f"sent {exc}"
        except TimeoutError:  # not reading
            return f"took no frame for {self.guard.timeout:g} s"
        except CutFrame:
            return "closed the connection in the middle of a frame"
        except ForeignCommand as exc:
            return f"sent {exc}"
        except InputError as exc:  # bytes that start no frame
            return f"sent what is not C37.118.2 ({exc})"
        except ConnectionError:  # a reset, a broken pipe
            return "closed the connection"
        except OSError as exc:
            return f"failed ({exc.strerror or exc})"

    def _taken(self, conn: socket.socket) -> str:
        """After the last frame: the server's side of the connection closed (the end of
        the stream, for a PDC that reads to it), then '' once the PDC closes in turn, in
        order, within `Guard.timeout` s (the evidence it read every frame: a TCP closed
        with bytes unread resets the connection); else what it did: reset the connection
        (it closed with frames unread), or stayed connected (delivery not confirmed,
        whatever its TCP acknowledged: a peer's kernel acknowledges what its application
        never reads)."""
        with contextlib.suppress(OSError):
            conn.shutdown(socket.SHUT_WR)
        deadline = time.monotonic() + self.guard.timeout
        while (left := deadline - time.monotonic()) > 0 and not self._stop.is_set():
            try:
                command = self._command(conn, block=False, timeout=min(left, 0.2))
            except ConnectionError:
                return "reset the connection with frames unread (it closed without reading them)"
            if command is None:
                return ""
        if (unacked := _unacknowledged(conn)) > 0:
            return (
                f"left {unacked} bytes unacknowledged {self.guard.timeout:g} s after the last "
                "frame was sent"
            )
        return (
            f"did not close the connection within {self.guard.timeout:g} s of the last frame "
            "(delivery not confirmed: a PDC that read the stream to its end closes in turn)"
        )

    def _command(self, conn: socket.socket, block: bool, timeout: float = 0.0):
        """The next command frame's word as a name (None: the peer closed; '' none, one
        this server ignores, or one whose CRC fails).  A frame must come whole within
        `Guard.timeout` s (block True: of the call; else of its first byte, which is
        waited for `timeout` s).

        Raises
        ------
        TimeoutError
            No whole frame within `Guard.timeout` s when block is True; `FrameTimeout`
            (a TimeoutError) a frame begun and not finished within it either way.
        ForeignCommand
            A command addressed to another IDCODE than the stream's.
        """
        conn.settimeout(self.guard.timeout)
        try:
            frame = _read_frame(conn, first_byte=None if block else timeout)
        except FrameTimeout:
            raise
        except TimeoutError:
            if block:
                raise
            return ""
        if frame is None:
            return None
        word = command_word(frame, self.idcode)
        return COMMANDS.get(word) or NOT_SENT.get(word, "")

    def _header(self) -> bytes:
        from pyc37.frame import HeaderFrame

        c = self._cfg2
        text = f"stabctl simulated PMUs: {c.get_num_pmu()}, {c.get_data_rate()} frames/s"
        return HeaderFrame(c.get_id_code(), text, c.get_soc(), (0, "+")).convert2bytes()


#: a session's verdict while 'stop' has paused it, and if its PDC then leaves
_PAUSED = "said 'stop'"


def _paused_end(exc: BaseException, timeout: float) -> str:
    """The verdict of a session paused by 'stop' that ends in `exc` (read by `_command`)."""
    if isinstance(exc, FrameTimeout | ForeignCommand):
        return f"{_PAUSED}, then sent {exc}"
    if isinstance(exc, TimeoutError):
        return f"{_PAUSED}, then no command for {timeout:g} s"
    if isinstance(exc, CutFrame):
        return f"{_PAUSED}, then closed the connection in the middle of a frame"
    if isinstance(exc, InputError):
        return f"{_PAUSED}, then sent what is not C37.118.2 ({exc})"
    if isinstance(exc, ConnectionError):
        return _PAUSED
    return f"{_PAUSED}, then failed ({getattr(exc, 'strerror', None) or exc})"


def _accept_conn(sock: socket.socket):
    """``sock.accept()`` (a function of its own, for the tests to make it fail)."""
    return sock.accept()


def _accept_failed(exc: OSError) -> str:
    """What a server says once as accept() fails for a reason: the system's message and,
    for a process out of file descriptors, its open-file limit."""
    why = os.strerror(exc.errno) if exc.errno else str(exc)
    limit = ""
    if exc.errno == errno.EMFILE:
        with contextlib.suppress(ImportError, OSError, ValueError):
            import resource

            soft = resource.getrlimit(resource.RLIMIT_NOFILE)[0]
            limit = f" (this process's open-file limit, ulimit -n, is {soft})"
    return (
        f"cannot accept a peer: {why}{limit}; trying again every {ACCEPT_RETRY_S:g} s, "
        "peers wait meanwhile"
    )


@dataclass(eq=False)
class _Peer:
    """A connected peer: its connection, when it connected (`time.monotonic()`), whether
    it has sent a valid command and whether 'start', whether its place was given to a new
    peer, how many frames it sent that the server ignores (not a command, a CRC that
    fails, a command word this server does not know) and how many valid commands."""

    conn: socket.socket
    since: float
    commanded: bool = False
    streamed: bool = False
    evicted: bool = False
    ignored: int = 0
    commands: int = 0


@dataclass
class _Shown:
    """One streaming session's times (`StreamServer.sent_at`, `StreamServer.due_at`) and
    the data frames it has sent."""

    sent_at: list
    due_at: list
    sent: int = 0


@dataclass(frozen=True)
class Session:
    """One PDC's streaming session of a `StreamServer` and its verdict.

    Attributes
    ----------
    peer : str
        The PDC's address, ``host:port``.
    sent : int
        Data frames handed to its connection.
    frames : int
        Data frames of the stream.
    ended : str
        Empty if the session was whole (every frame sent and the PDC closed in order
        after the last); else what the PDC did that cut it (said 'stop' and left,
        closed the connection, took no frame for the time-out, reset the connection with
        frames unread, stayed connected after the last frame, ...).
    asked : str
        Empty, or the configurations it asked for that the server does not send (CFG-1,
        CFG-3), said with the verdict.
    """

    peer: str
    sent: int
    frames: int
    ended: str
    asked: str = ""

    @property
    def whole(self) -> bool:
        """Every frame sent and taken."""
        return not self.ended

    def __str__(self) -> str:
        if self.whole:
            said = f"the PDC {self.peer} was sent {self.sent} of {self.frames} frames, whole"
        else:
            said = f"the PDC {self.peer} {self.ended} after {self.sent} of {self.frames} frames"
        return f"{said}; it {self.asked}" if self.asked else said


def _asked(asked: list) -> str:
    """What a peer asked for that a `StreamServer` does not send (C37.118.2-2011
    Table 15), for its drop's reason."""
    return (
        f"asked for {' and '.join(dict.fromkeys(asked))}, which this server does not send "
        "(it sends its stream's CFG-2 only, command 5)"
    )


def _unacknowledged(conn: socket.socket) -> int:
    """Bytes sent on conn that its peer's TCP has not acknowledged (Linux SIOCOUTQ); 0
    where the system cannot tell."""
    try:
        import fcntl
        import termios

        return struct.unpack("i", fcntl.ioctl(conn.fileno(), termios.TIOCOUTQ, bytes(4)))[0]
    except (ImportError, OSError, AttributeError):
        return 0


class ForeignCommand(InputError):
    """A command frame (its CRC valid) addressed to another stream's IDCODE."""


def command_word(frame: bytes, idcode: int | None = None) -> int:
    """The command word of a command frame whose CRC is valid (C37.118.2-2011 Table 15).

    Parameters
    ----------
    frame : bytes
        One whole frame.
    idcode : int, optional
        The IDCODE of the stream the server sends: a command's IDCODE is its destination
        stream's (C37.118.2-2011 Table 2).  None: not checked.

    Returns
    -------
    int
        The command word; 0 for any other frame, a command frame whose CRC fails, or
        one shorter than a command frame's 18 bytes (SYNC to CMD, then CHK; Table 15):
        a 16-byte one, its CRC valid, had its CRC read as its command word, and was
        obeyed.

    Raises
    ------
    ForeignCommand
        A command frame, its CRC valid, addressed to another IDCODE than `idcode`.
    """
    from pyc37.frame import CommonFrame

    if len(frame) < COMMAND_BYTES or frame[1] & 0x70 != 0x40:
        return 0
    if not CommonFrame._check_crc(frame):
        return 0
    if idcode is not None and (to := int.from_bytes(frame[4:6], "big")) != idcode:
        raise ForeignCommand(f"a command for IDCODE {to}, not this stream's {idcode}")
    return int.from_bytes(frame[14:16], "big")


def _ignored(n: int, then: str) -> str:
    """How a peer without a valid command is named as it is dropped: what it did
    (``then``: 'closed the connection', 'silent'), after the frames it sent that the
    server ignores, if any."""
    if not n:
        return then if then == "silent" else f"connected and {then}"
    frames = "1 frame" if n == 1 else f"{n} frames"
    return f"sent {frames} this server ignores (no command, or its CRC fails), then {then}"


class FrameTimeout(TimeoutError):
    """A frame begun and not finished within the time-out for a whole frame (a peer that
    sends it a byte at a time)."""


class AnswerTimeout(TimeoutError):
    """An answer (a CFG-2, a header frame) the peer did not take within the time-out: it
    sends commands and reads nothing (round 58 AZ07: such a peer was named 'silent')."""


@dataclass(frozen=True)
class _Deadline:
    """When a whole frame is due: ``at`` (`time.monotonic()`), ``budget`` s after its
    wait began."""

    at: float
    budget: float


def _recv_exactly(
    conn: socket.socket, n: int, deadline: _Deadline | None = None, begun: bool = False
):
    """n bytes from conn by `deadline` (None: each read within the socket's time-out),
    the socket's time-out set to what is left before each read.  None if the peer closed
    first; CutFrame if it closed after some of them (or `begun`: bytes of the frame came
    before); TimeoutError past the deadline, `FrameTimeout` once some bytes of the frame
    came."""
    out = b""
    while len(out) < n:
        try:
            if deadline is not None:
                if (left := deadline.at - time.monotonic()) <= 0:
                    raise TimeoutError("timed out")
                conn.settimeout(left)
            chunk = conn.recv(n - len(out))
        except TimeoutError:
            if not (out or begun):
                raise
            budget = conn.gettimeout() if deadline is None else deadline.budget
            raise FrameTimeout(f"part of a frame and not the rest within {budget:g} s") from None
        if not chunk:
            if out or begun:
                raise CutFrame("the peer closed the connection in the middle of a frame")
            return None
        out += chunk
    return out


#: Most bytes of data frames a receive keeps (`receive`'s ``max_bytes``): what a
#: recording may hold (`stabctl.jsontext.MAX_INPUT_BYTES`, 256 MiB), so a stream received
#: is never more than a recording that can be read back; an end (`End`) that asks for
#: more is refused before 'start', a stream without one is refused past it, instead of
#: filling the memory.
MAX_STREAM_BYTES = MAX_INPUT_BYTES


def most_frames(config, max_bytes: int, end: End) -> int:
    """The most data frames of a stream of CFG-2 `config` that fit in `max_bytes`
    (`c37.data_frame_size` each).

    Parameters
    ----------
    config : pyc37 ConfigFrame2
        The stream's CFG-2.
    max_bytes : int
        The bytes the data frames may take.
    end : End
        The end asked for: refused if it needs more frames (``frames``, or the
        reporting instants up to ``tf`` at the DATA_RATE).

    Returns
    -------
    int
        The frames.

    Raises
    ------
    InputError
        `end` needs more frames than fit: the message names the frame size, the most
        frames and seconds that fit, and the options that set the end.
    """
    size = c37.data_frame_size(config)
    most = max(1, max_bytes // size)
    step = c37.frame_interval(config)  # (a DATA_RATE of 0 is refused with the frames)
    wanted = end.frames
    if end.tf is not None and step > 0:
        by_time = math.floor(end.tf / step + 1e-6) + 1
        wanted = by_time if wanted is None else min(wanted, by_time)
    if wanted is not None and wanted > most:
        raise InputError(
            f"a stream to {end} is {wanted} data frames of {size} bytes, more than the "
            f"{max_bytes / 2**20:.0f} MiB a stream received may hold (at most {most} frames, "
            f"{(most - 1) * step:.0f} s of this stream; a recording holds as much): "
            "receive it in parts (--frames or --until)"
        )
    return most


@dataclass(frozen=True)
class End:
    """Where a received stream ends: after ``frames`` data frames, or at the first frame
    stamped ``tf`` s or later after the CFG-2's time stamp (SOC + FRACSEC / TIME_BASE,
    t = 0 of the run: `c37.config_stamp`), read as the time elapsed across a leap second
    (`c37.stamp_times`); both None: when the server closes the connection.

    Attributes
    ----------
    frames : int or None
        Data frames to receive.
    tf : float or None
        Last time stamp to receive (s after the CFG-2's time stamp).

    Raises
    ------
    InputError
        ``frames`` below 1, or ``tf`` not a finite time >= 0 s.
    """

    frames: int | None = None
    tf: float | None = None

    def __post_init__(self):
        if self.frames is not None and self.frames < 1:
            raise InputError(f"a stream's end needs at least 1 frame, got {self.frames}")
        if self.tf is not None and not (math.isfinite(self.tf) and self.tf >= 0):
            raise InputError(
                f"a stream's last time stamp --until must be a finite time >= 0 s (t = 0 is "
                f"the CFG-2's time stamp), got {self.tf:g}"
            )

    def __str__(self) -> str:
        parts = [] if self.frames is None else [f"{self.frames} frames"]
        parts += [] if self.tf is None else [f"t = {self.tf:g} s"]
        return " or ".join(parts) or "the server's close"

    @property
    def given(self) -> bool:
        """An end the client states (not the server's close)."""
        return self.frames is not None or self.tf is not None


@dataclass(frozen=True)
class Stream:
    """A received stream: its CFG-2 frame and data frames (bytes, as received, each
    checked: `c37.check_data_frame`) and, if it stopped before its `End`, why.

    Attributes
    ----------
    cfg2 : bytes
        The CFG-2 frame.
    data : list of bytes
        The data frames received, in arrival order, up to the first refused.
    short : str
        Empty if the stream reached its end; else what cut it (the server closed, the
        connection was reset or sent no whole data frame within the time-out, a frame cut
        in the middle, a frame refused), with the frames and the last time stamp
        received.
    refused : str
        Empty, or why the frame after `data` was refused (`c37.check_stream_frame`: its
        CRC; a data frame's IDCODE, type or size; a CFG-2 that changes the stream's
        configuration); the stream was cut there (`short` says so).
    """

    cfg2: bytes
    data: list
    short: str = ""
    refused: str = ""


#: a receiver's longest wait for a whole frame (s), unless the caller gives its own
RECEIVE_TIMEOUT_S = 30.0


def receive(
    host: str,
    port: int,
    end: End = End(),
    idcode: int = 1,
    timeout: float | None = None,
    data: list | None = None,
    max_bytes: int = MAX_STREAM_BYTES,
    config: list | None = None,
) -> Stream:
    """The CFG-2 frame and the data frames of the C37.118.2 stream at host:port: command
    frames (pyc37's) 'cfg2', then 'start', then 'stop' once `end` is reached, each
    addressed to the stream `idcode` (C37.118.2-2011 Table 2: a command's IDCODE is its
    destination stream's; a server of another drops the peer).  The CFG-2 and every frame
    after 'start' are checked (`c37.check_stream_frame`: CRC; a data frame's IDCODE, type
    and size; a CFG-2 resent must be the one in use; a data frame's time stamp, which must
    follow the one before on the DATA_RATE grid: `c37.next_frame_fault`) as each comes,
    and each must come whole within
    `timeout` s (None: `RECEIVE_TIMEOUT_S`), however its bytes are spread, and each data
    frame within `timeout` s of the one before, whatever other frames come between.  A
    stream that stops before its stated end (the server closes, resets or sends no whole
    data frame for `timeout` s, cuts a frame, or sends a frame that is refused) is
    returned with the good data frames that arrived before and `Stream.short` saying so
    (`Stream.refused` why a frame was refused); a stream with no stated end ends when the
    server closes.

    `data`, if given, is the list the data frames are appended to as they come: the
    caller's, which holds what came whatever ends the receive (a thread's receive that
    the caller stops waiting for); `config`, if given, the list the CFG-2 frame (bytes)
    is appended to once it is read (with `data`, a recording of what came).

    Raises
    ------
    KeyboardInterrupt
        Ctrl-C or a termination (`stabctl.cli.options.Terminated`) while receiving,
        raised on with the stream received so far as its ``stream`` attribute: a `Stream`
        whose `Stream.short` says it was interrupted, or None before the CFG-2 came.
    InputError
        No server there, no whole frame within `timeout` s before the first data frame, a
        reply to 'cfg2' that is not a readable CFG-2 (`c37.read_config`: its frame type, its
        CRC) or is another stream's than `idcode`'s, a peer of another protocol or bytes off
        a frame's start (a FRAMESIZE that is not the frame's), a connection reset or closed
        before the first data frame, a first data frame refused, an `end` whose data frames
        are more than `max_bytes` (`most_frames`, before 'start'), or more than those of a
        stream without a stated end: each named with host:port.
    """
    from pyc37.frame import CommandFrame

    where = hostport(host, port)
    timeout = RECEIVE_TIMEOUT_S if timeout is None else timeout
    try:
        conn = socket.create_connection((host, port), timeout=timeout)
    except OSError as exc:
        raise InputError(f"no C37.118.2 server at {where}: {exc.strerror or exc}") from None
    data = [] if data is None else data
    cfg2 = None
    with conn:
        try:
            try:
                conn.sendall(CommandFrame(idcode, "cfg2").convert2bytes())
                cfg2 = _read_frame(conn)
            except ConnectionError:  # closed with the command unread: a reset
                cfg2 = None
            if cfg2 is None:
                raise InputError(
                    f"the C37.118.2 server closed the connection before sending its CFG-2: "
                    f"it serves no more peers at once, does not allow this address, or "
                    f"serves another stream than IDCODE {idcode}, which these commands "
                    f"addressed (its messages say which)"
                )
            cfg = c37.read_config(cfg2, "its CFG-2")
            if (theirs := int(cfg.get_id_code())) != idcode:  # Table 2: the destination's
                raise InputError(
                    f"its CFG-2 is of stream IDCODE {theirs}, not the IDCODE {idcode} "
                    "these commands addressed (--idcode): another stream than the one asked for"
                )
            if config is not None:
                config.append(cfg2)
            most = most_frames(cfg, max_bytes, end)
            conn.sendall(CommandFrame(idcode, "start").convert2bytes())
            short, refused = _data_frames(conn, cfg, end, data, timeout, most)
        except FrameTimeout as exc:
            raise InputError(f"{where}: sent {exc}, before any data frame") from None
        except TimeoutError:
            raise InputError(f"{where}: nothing received for {timeout:g} s") from None
        except InputError as exc:
            raise InputError(f"{where}: {exc}") from None
        except OSError as exc:  # a reset or broken pipe before any data frame
            raise InputError(f"{where}: {exc.strerror or exc}") from None
        except KeyboardInterrupt as exc:  # handed on with what came
            exc.stream = _interrupted_stream(cfg2, data, end)  # type: ignore[attr-defined]
            raise
        if not data and short:
            raise InputError(f"{where}: {short}")
        if not short and end.given:
            with contextlib.suppress(OSError):
                conn.sendall(CommandFrame(idcode, "stop").convert2bytes())
    return Stream(cfg2, data, short, refused)


def _interrupted_stream(cfg2, data: list, end: End) -> Stream | None:
    """The `Stream` an interrupted `receive` hands on: its CFG-2 (None: it had not come,
    and None is returned) and the data frames received, `Stream.short` naming the
    interrupt, the frames and the last time stamp."""
    if not cfg2:
        return None
    try:
        config = c37.read_config(cfg2, "its CFG-2")
    except InputError:
        return None
    data = list(data)  # as it stands (the receive's thread may append still)
    soc, frac = c37.config_stamp(config)
    at = c37.stamp_times(data, config)[-1] - soc - frac if data else None
    last = f", the last stamped {at:.4f} s" if at is not None else ""
    said = f"interrupted after {len(data)} data frames{last}, before {end}"
    return Stream(cfg2, data, said)


def _data_frames(
    conn: socket.socket, cfg2, end: End, data: list, budget: float, most: int
) -> tuple[str, str]:
    """Append data frames from conn to data until `end`, every frame checked against cfg2
    (the CFG-2 as pyc37 reads it; `c37.check_stream_frame`: a data frame's CRC, IDCODE,
    type and size, any other frame's CRC, a CFG-2 resent unchanged; a data frame's time
    stamp against the frames before, `c37.next_frame_fault`): ('', '') if the end
    was reached (or, with no end stated, the server closed), else (what cut the stream,
    why a frame was refused or '').  `budget` (s) is the longest wait for the next data
    frame, whatever else comes meanwhile (a server sending header frames and no data
    frame is cut as a silent one is: a frame that begins within it has `budget` from its
    first byte to end, so a wait that runs out in the middle of a header frame is no
    frame cut short); the connection's time-out is left at it.  The frames' times, and
    the `End.tf` end, are the time elapsed since the CFG-2's time stamp
    (`c37.config_stamp`), across a leap second too (`c37.stamp_times`, as a recording's).
    More than `most` data frames (`most_frames`) is an InputError."""
    soc, frac = c37.config_stamp(cfg2)
    step = c37.frame_interval(cfg2)  # a frame within one interval past --until ends it
    leaps = 0  # positive leap seconds in the stream up to its last data frame
    last = ""  # ", the last stamped ... s" of the last data frame, for the messages
    since = time.monotonic()  # of 'start', then of the last data frame
    try:
        while end.frames is None or len(data) < end.frames:
            try:
                if (left := since + budget - time.monotonic()) <= 0:
                    raise TimeoutError("timed out")
                conn.settimeout(budget)  # a frame begun by then has `budget` to end
                frame = _read_frame(conn, first_byte=left)
            except FrameTimeout:
                cut = f"sent part of a frame and not the rest within {budget:g} s"
            except TimeoutError:
                cut = f"sent no data frame for {budget:g} s"
            except ConnectionError:
                cut = "reset the connection"
            except CutFrame:
                cut = "closed the connection in the middle of a frame"
            except NoFrameStart as exc:
                if not data:  # the peer speaks another protocol
                    raise InputError(f"after 0 data frames: {exc}") from None
                damaged = (
                    f"after data frame {len(data)}: {exc.head!r}, no frame start (SYNC 0xAA, "
                    f"FRAMESIZE of at least 16), or data frame {len(data)}'s FRAMESIZE is off"
                )
                return (  # a frame refused (round 46: the frames before it were lost)
                    f"the server sent bytes that start no frame ({damaged}); the stream is cut "
                    f"there: {len(data)} data frames before them{last}, before {end}",
                    damaged,
                )
            else:
                if frame is not None:
                    kind = c37.frame_kind(frame)
                    try:
                        if not c37.check_stream_frame(cfg2, frame):
                            continue  # a header, CFG-1, CFG-3, command or the same CFG-2
                        why = c37.next_frame_fault(data, frame, cfg2)  # its time stamp
                    except InputError as exc:
                        at = f"data frame {len(data) + 1}" if kind == "data frame" else kind
                        why = f"{at}: {exc}"
                    if why:
                        return (
                            f"the server sent a {kind} that is refused ({why}); the stream is "
                            f"cut there: {len(data)} data frames before it{last}, before {end}",
                            why,
                        )
                    if data:  # a leap second between the last frame and this one
                        leaps += int(c37.leap_offsets([data[-1], frame], cfg2)[-1])
                    elapsed = float(c37.stamp_times([frame], cfg2, leaps)[0] - soc) - frac
                    if end.tf is not None and elapsed > end.tf + step + 0.5e-6:
                        return "", ""  # past the end after a gap: not taken
                    data.append(frame)
                    since = time.monotonic()
                    last = f", the last stamped {elapsed:.4f} s"
                    if end.tf is not None and elapsed >= end.tf - 0.5e-6:
                        return "", ""
                    if len(data) > most:  # only without an end: `most_frames` checked it
                        raise InputError(
                            f"more than {most} data frames (what a stream received may "
                            "hold) without an end: give the frames or the last time stamp "
                            "to receive (--frames or --until)"
                        )
                    continue
                if not end.given:
                    return "", ""
                cut = "closed the connection"
            return f"the server {cut} after {len(data)} data frames{last}, before {end}", ""
        return "", ""
    finally:
        with contextlib.suppress(OSError):  # closed meanwhile
            conn.settimeout(budget)


class CutFrame(InputError):
    """The peer closed the connection in the middle of a frame."""


class NoFrameStart(InputError):
    """Bytes `head` (4) where a frame starts that start none (SYNC 0xAA, FRAMESIZE of at
    least 16): the peer speaks another protocol, or, after frames, one is damaged."""

    def __init__(self, head: bytes):
        super().__init__(f"the peer does not speak C37.118.2: it sent {head!r} for a frame start")
        self.head = head


def _read_frame(conn: socket.socket, first_byte: float | None = None):
    """One whole frame from conn, SYNC and FRAMESIZE first (None if the peer closed
    between frames), within the connection's time-out (``conn.gettimeout()``) for the
    whole frame, not for each read: a peer that sends a frame a byte at a time is timed
    out as a silent one is.  The connection's time-out is left as it was.

    Parameters
    ----------
    conn : socket.socket
        The connection.
    first_byte : float, optional
        Wait at most this long (s) for a frame to begin (TimeoutError, nothing taken);
        the connection's time-out then runs from its first byte.  None: the time-out
        runs from the call.

    Raises
    ------
    NoFrameStart
        Bytes that do not start a C37.118.2 frame (SYNC 0xAA, FRAMESIZE of at least 16):
        the peer speaks another protocol (or, after frames, one is damaged).
    CutFrame
        The peer closed in the middle of a frame.
    TimeoutError
        No frame within the time-out; `FrameTimeout` (a TimeoutError) if one began and
        did not end within it.
    """
    budget = conn.gettimeout()
    try:
        first = b""
        if first_byte is not None:
            conn.settimeout(first_byte)
            first = conn.recv(1)
            if not first:
                return None
        deadline = None if budget is None else _Deadline(time.monotonic() + budget, budget)
        rest = _recv_exactly(conn, 4 - len(first), deadline, begun=bool(first))
        if rest is None:
            return None
        head = first + rest
        if head[0] != 0xAA or int.from_bytes(head[2:4], "big") < 16:
            raise NoFrameStart(head)
        body = _recv_exactly(conn, int.from_bytes(head[2:4], "big") - 4, deadline, True)
        return head + body
    finally:
        with contextlib.suppress(OSError):  # closed meanwhile (by another thread)
            conn.settimeout(budget)


def pdc_client(host: str, port: int, idcode: int = 1):
    """pyc37's own PDC client connected to host:port, set up to read a stream whole: a
    receive buffer of one frame header (its ``get`` keeps no bytes beyond the frame it
    reads, so a larger buffer loses the next frame when two arrive together) and its
    loggers, which write every connection to stdout at INFO, at WARNING.  Its commands
    carry `idcode` (pyc37's ``pdc_id``), which must be the stream's: a command's IDCODE
    is its destination stream's (C37.118.2-2011 Table 2), and a `StreamServer` drops a
    peer addressing another.  Used by the tests and benchmarks/bench_c37.py as the
    independent client."""
    import logging

    from pyc37.pdc import Pdc

    pdc = Pdc(pdc_id=idcode, pmu_ip=host, pmu_port=port, buffer_size=4)
    pdc.run()
    for name in list(logging.root.manager.loggerDict):
        if name.startswith(("pyc37", "CLIENT")):
            logging.getLogger(name).setLevel(logging.WARNING)
    return pdc
