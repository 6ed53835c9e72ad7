"""`stabctl pmu serve|replay|record`: the simulated PMUs as an IEEE C37.118.2 stream over
TCP, a recording served again, and a received stream recorded."""

from __future__ import annotations

import collections
import contextlib
import ipaddress
import json
import socket
import warnings

import click

from stabctl.cli.checks import check_writable
from stabctl.cli.format import shown
from stabctl.cli.options import (
    FLOAT,
    INT,
    PlainIntRange,
    _apply,
    clear_cycles_option,
    comma_list,
    controller,
    esd_model_option,
    fault_options,
    json_option,
    model_options,
    q_limits_option,
    refuse_given,
    reports_errors,
    storage_options,
    tf_option,
)
from stabctl.cli.pmu_options import (
    ESTIMATOR,
    IDCODE,
    PMU_AT,
    RATE,
    check_latency,
    fail_short,
    fault_event,
    fault_run_options,
    keep_interrupted,
    kept_at,
    pmu_noise_options,
    pmu_settings,
    rate_for_case,
    rate_latency_options,
    stream_controller,
    stream_idcodes,
    write_kept,
    write_recording,
)
from stabctl.errors import InputError, counted

#: IEEE C37.118.2's well-known TCP port
C37_PORT = 4712
_INF = float("inf")  # --speed 0: no pacing


@click.group()
def pmu():
    """IEEE C37.118.2 PMU streams (the `pmu` extra, pyc37).

    \b
    serve    simulate CASE through a fault and serve its PMUs' frames over TCP
    replay   serve a recording's frames again
    record   receive a stream from a PMU or PDC and write it to a file
    plant    simulate CASE through a fault with ESDs a controller commands over TCP
    control  the ESD controller: subscribe to a plant's PMUs, send back the modes
    """


def _listen_host(ctx, param, host: str) -> str:
    """--host as the socket layer takes it: an IPv6 address in brackets, as the servers
    print their address ([::1]:4712), without them; a usage error (before any warning
    about who may connect) for a host this machine cannot listen on (a name that does not
    resolve, an address of no interface here, an IPv4-mapped IPv6 address: the servers'
    own `c37_tcp.listen` is tried on a free port)."""
    from stabctl.estimation.c37_tcp import listen

    if host.startswith("[") and host.endswith("]"):
        host = host[1:-1]
    if not host.strip():
        return host  # refused with its own words (`_allowed`)
    try:
        listen(host, 0).close()
    except (InputError, UnicodeError) as exc:
        why = str(exc).partition("cannot listen: ")[2] or exc
        raise click.BadParameter(
            f"{host}: this machine cannot listen there ({why}); give an IPv4 or IPv6 "
            "address of one of its interfaces (127.0.0.1, ::1; 0.0.0.0 or :: for all)",
            ctx,
            param,
        ) from None
    return host


_LISTEN = (
    click.option(
        "--host",
        default="127.0.0.1",
        show_default=True,
        callback=_listen_host,
        help="Address to listen on, IPv4 or IPv6 (::1 or [::1]; :: every interface) "
        "(another than loopback: any host that reaches it may connect unless --allow names "
        "them).",
    ),
    click.option(
        "--port",
        type=PlainIntRange(0, 65535),
        default=C37_PORT,
        show_default=True,
        help="TCP port (0: any free one, printed).",
    ),
    click.option(
        "--allow",
        default=None,
        metavar="IP[,IP...]",
        help="Peers allowed to connect (IP addresses); others are closed at once and named. "
        "Default (left out): any.",
    ),
)
_LOOPBACK = ("127.0.0.1", "::1", "localhost")


def _loopback(host: str) -> bool:
    """Whether a server on `host` listens on loopback only: localhost, or an address of
    127.0.0.0/8 or ::1, also as the socket layer reads it (inet_aton: 127.1, 0x7f.1)."""
    if host in _LOOPBACK:
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        pass
    try:  # the short and hexadecimal IPv4 forms the server's bind accepts
        return ipaddress.ip_address(socket.inet_aton(host)).is_loopback
    except OSError:  # a name other than localhost
        return False


def _allowed(host: str, allow: str | None) -> tuple:
    """The --allow list as a tuple of addresses (None, the option left out: empty, any
    peer); InputError for an empty or blank value (it names no peer: it must not mean
    any), an item that is not an address, an empty item or a repeat (`comma_list`), or an
    unspecified address (0.0.0.0, ::: no peer's); warns when listening beyond loopback
    to any peer, for each address no peer of `host` can have (`_unreachable`), and for
    each IPv6 zone left out (`plain_ip`)."""
    from stabctl.estimation.c37_tcp import plain_ip

    if not host.strip():
        raise InputError(
            "--host '': an empty address listens on every interface; give 0.0.0.0 (or :: "
            "for IPv6) to mean that, or a local address"
        )
    if allow is not None and not allow.strip():
        raise InputError(
            f"--allow {allow!r}: names no peer; give IP[,IP...], or leave --allow out to "
            "let any peer connect"
        )
    peers = tuple(() if allow is None else comma_list(allow, "--allow", plain_ip, "an IP address"))
    for item in (allow or "").split(","):
        if "%" in item:  # an IPv6 zone: not compared (`plain_ip`)
            click.echo(
                f"warning: --allow {item.strip()}: read as {plain_ip(item.strip())} (a peer is "
                "matched by its address, not by the zone after %)",
                err=True,
            )
    for peer in peers:  # said now, before the server waits for peers
        if ipaddress.ip_address(peer).is_unspecified:
            raise InputError(
                f"--allow {peer}: the unspecified address is no peer's (it means 'every "
                "interface' where a server listens); leave --allow out to let any peer "
                "connect, or name the peers' addresses"
            )
        if why := _unreachable(host, peer):
            click.echo(f"warning: --allow {peer}: {why}: it admits no one", err=True)
    if not _loopback(host) and not peers:
        click.echo(
            f"warning: listening on {host}: any host that reaches this port may connect "
            "(name the peers with --allow IP[,IP...])",
            err=True,
        )
    return peers


def _unreachable(host: str, peer: str) -> str:
    """Why no peer of a server listening on `host` can have the address `peer` ('' if
    one can, or if `host` is a name other than localhost, which is not resolved here):
    a multicast address, an address beyond loopback for a loopback listener, or an
    address of the other IP version than the listener's (an IPv4 peer reaches ``::``
    where the system listens on both)."""
    ip = ipaddress.ip_address(peer)
    if ip.is_multicast:
        return "a multicast address, no TCP peer's"
    if host == "localhost":
        return "" if ip.is_loopback else f"a server on {host} has loopback peers only"
    try:
        bound = ipaddress.ip_address(host)
    except ValueError:
        return ""
    if bound.is_loopback and not ip.is_loopback:
        return f"not a loopback address, and a server on {host} has loopback peers only"
    dual = bound.version == 6 and bound.is_unspecified and socket.has_dualstack_ipv6()
    if ip.version != bound.version and not (dual and ip.version == 4):
        has = f"IPv{bound.version} peers only"
        return f"an IPv{ip.version} address, and a server on {host} has {has}"
    return ""


def _serving(func):
    speed = click.option(
        "--speed",
        type=FLOAT,
        default=1.0,
        show_default=True,
        help="Time-stamp seconds per second: 1 real time, 0 as fast as the client reads.",
    )
    timeout = click.option(
        "--timeout",
        type=FLOAT,
        default=60.0,
        show_default=True,
        help="Longest wait for a whole command frame from a peer (silent or sending it "
        "byte by byte), and for it to take a frame (s); a peer past it is dropped.",
    )
    wait = click.option(
        "--wait",
        type=FLOAT,
        default=60.0,
        show_default=True,
        help="With every PDC session so far cut (the PDC said 'stop' or left before the "
        "last frame), the longest wait for another peer (s); then the server ends, exit "
        "status 2.",
    )
    return _apply(func, (*_LISTEN, speed, timeout, wait))


def _listening(func):
    return _apply(func, _LISTEN)


@pmu.command()
@click.argument("case_name", metavar="CASE")
@fault_options(required=True)
@clear_cycles_option("Clearing after N cycles, both ends")
@tf_option()
@RATE
@pmu_noise_options
@click.option(
    "--seed", type=INT, default=0, show_default=True, metavar="S", help="Seed of the PMU noise."
)
@PMU_AT
@_serving
@click.option(
    "--each-pmu",
    is_flag=True,
    help="One stream per PMU, on consecutive ports from --port (read them with "
    "--source tcp://HOST:P1-P2).",
)
@q_limits_option
@reports_errors
def serve(
    case_name,
    fault,
    far_bus,
    t_fault,
    clear_cycles,
    tf,
    rate,
    drop,
    tve_pct,
    fe_hz,
    rfe_hz_s,
    k_sigma,
    window_cycles,
    seed,
    pmu_at,
    host,
    port,
    allow,
    speed,
    timeout,
    wait,
    each_pmu,
    q_limits,
):
    """Simulate CASE through a line fault and serve one PMU per generator as one IEEE
    C37.118.2 stream on HOST:PORT, to one PDC: CFG-2 and header on request, then the data
    frames from 'start', paced by their time stamps (docs/estimation.md 6).  The stream's
    IDCODE is 1: commands addressed to another drop their peer.  With --each-pmu every
    PMU is a server of its own, on PORT, PORT+1, ... (any free ports with --port 0), each
    stream IDCODE 1, its PMU's block 2, 3, ... as in the one stream.

    The frames are those `stabctl estimate rmse` evaluates for the same seed (C37.118.1
    noise, lost frames as absent data).  Each PDC that says 'start' has a session of its
    own, named on stderr as it ends: whole (every frame sent, and the PDC closed the
    connection in order after the last, within --timeout s: the evidence it read them),
    or cut by what the PDC did (said 'stop' and left: 'stop' pauses, 'start' resumes;
    closed the connection, reset it with frames unread, took no frame for --timeout s,
    stayed connected after the last frame) and the frames sent; each peer refused or
    dropped is named as it is.  At most 8 peers are connected at once: a ninth takes the
    place of the one that has waited longest without a valid command, else of the one
    connected longest, beyond --timeout, without starting a stream, and is refused when
    all 8 are streaming or within their first --timeout s.  Exits once a PDC has been
    sent the stream whole and none is streaming (exit status 0, "sent N of N frames"); if
    every session was cut and no peer comes for --wait s after the last, exits with an
    error naming each cut session (exit status 2: the stream was not sent whole).

    \b
    Example:
      stabctl pmu serve miniwecc --fault 83 --far-bus 33 --tf 60 --port 4712
    """
    from stabctl.dynamics.options import ModelOptions
    from stabctl.estimation import c37
    from stabctl.estimation import pmu as pm
    from stabctl.estimation.c37_tcp import StreamServer

    guard = _guard(host, allow, timeout, wait)
    case, ev, tf = fault_event(case_name, fault, far_bus, t_fault, clear_cycles, tf)
    settings = pmu_settings(rate, 0.0, drop, tve_pct, fe_hz, rfe_hz_s, k_sigma, window_cycles)
    settings = rate_for_case(settings, rate, case)
    pmus = pm.machine_pmus(case, pmu_at)
    if each_pmu and port and port + len(pmus) - 1 > 65535:
        raise InputError(
            f"--each-pmu --port {port}: {len(pmus)} PMUs need ports {port}-"
            f"{port + len(pmus) - 1}, beyond 65535 (give --port <= {65536 - len(pmus)}, "
            "or 0 for any free ones)"
        )
    res = ModelOptions(q_limits=q_limits).simulator(case).run([ev], t_end=tf)
    frames = list(pm.measure(pm.phasor_truth(case, res, pmus, window_cycles), settings, seed))
    # one stream of every PMU, or one per PMU: every stream IDCODE 1, the one a client's
    # commands address (`--idcode`), PMU k's block 2 + k either way
    streams = [range(len(pmus))] if not each_pmu else [[k] for k in range(len(pmus))]
    with contextlib.ExitStack() as stack:
        servers = [
            stack.enter_context(
                StreamServer.of_frames(
                    c37.stream_config(
                        case, [pmus[k] for k in cols], settings.rate, 1, pmu_idcode=2 + cols[0]
                    ),
                    [f.of(cols) for f in frames],
                    host=host,
                    port=port + j if port else 0,
                    speed=speed or _INF,
                    guard=guard,
                )
            )
            for j, cols in enumerate(streams)
        ]
        _serve(servers)


@pmu.command()
@click.argument("recording", type=click.Path(dir_okay=False))
@_serving
@reports_errors
def replay(recording, host, port, allow, speed, timeout, wait):
    """Serve RECORDING (a file `pmu record` wrote, or any capture of C37.118.2 frames,
    CFG-2 first) to one PDC, its frames as recorded, paced by their time stamps.  Every
    frame is checked before the server listens (CRC; each data frame's IDCODE, type and
    size against the CFG-2): a frame refused is an error naming RECORDING and the data
    frame's number.  The stream's IDCODE is the recording's (printed): commands
    addressed to another drop their peer.  Ends as `pmu serve` does: exit status 0 once
    a PDC has been sent the stream whole (every PDC session named as it ends, whole or
    cut, each peer dropped named as it is), 2 with an error naming each cut session if
    every session was cut and no peer came for --wait s after.

    \b
    Example:
      stabctl pmu replay wecc.c37 --speed 0
    """
    from stabctl.estimation import c37
    from stabctl.estimation.c37_tcp import StreamServer
    from stabctl.estimation.sources import check_order
    from stabctl.io.inputs import input_file

    guard = _guard(host, allow, timeout, wait)
    path = input_file(recording, "RECORDING")
    cfg2, data = c37.recorded_frames(path)
    if not data:
        raise InputError(f"RECORDING {path}: no data frame (a configuration frame only)")
    c37.check_data_frames(cfg2, data, f"RECORDING {path}")
    check_order(data, cfg2, f"RECORDING {path}")
    with StreamServer(cfg2, data, host=host, port=port, speed=speed or _INF, guard=guard) as server:
        _serve([server])


def _guard(host: str, allow, timeout: float, wait: float):
    """The servers' `c37_tcp.Guard` of the options; InputError for a --timeout or --wait
    that is not > 0."""
    from stabctl.estimation.c37_tcp import Guard

    for name, value in (("--timeout", timeout), ("--wait", wait)):
        if not value > 0:
            raise InputError(f"{name} must be > 0 s, got {value:g}")
    return Guard(_allowed(host, allow), timeout, wait=wait)


def _serve(servers) -> None:
    """Announce each listening server and wait until each is done (`StreamServer.done`),
    printing on stderr what each reports as it happens (`StreamServer.news`: each peer
    refused, each PDC session's end, whole or cut); InputError if a server's every
    session was cut (no PDC was sent its stream whole), naming each."""
    import time

    from stabctl.estimation.c37_tcp import hostport

    for server in servers:
        click.echo(
            f"serving {counted(server.n_frames, 'frame')} on {hostport(*server.address)} "
            "(C37.118.2, "
            f"IDCODE {server.idcode}); waiting for a PDC",
            err=True,
        )
    said = [0] * len(servers)

    def tell() -> None:
        for k, server in enumerate(servers):
            news = server.news[said[k] :]
            said[k] += len(news)
            where = f"{hostport(*server.address)}: " if len(servers) > 1 else ""
            for line in news:
                click.echo(where + line, err=True)

    try:
        while not all(server.done() for server in servers):
            tell()
            time.sleep(0.2)  # a wait with a time-out lets Ctrl-C through
    finally:
        for server in servers:
            server.close()
        tell()
    if short := [
        f"{hostport(*s.address)}: no PDC was sent the stream whole "
        f"({'; '.join(map(str, s.cut))}) and none came for it within --wait "
        f"{s.guard.wait:g} s"
        for s in servers
        if not s.finished.is_set()
    ]:
        raise InputError(f"{'; '.join(short)}: the stream was not sent whole")
    sent, total = (sum(getattr(s, a) for s in servers) for a in ("n_sent", "n_frames"))
    click.echo(
        f"sent {sent} of {counted(total, 'frame')}"
        + (f" on {len(servers)} ports" if len(servers) > 1 else "")
    )


@pmu.command()
@click.argument("address", metavar="HOST:PORT")
@click.option(
    "--out",
    "-o",
    required=True,
    type=click.Path(dir_okay=False),
    help="Output file: the recording (CFG-2, then the data frames).",
)
@click.option(
    "--frames",
    type=PlainIntRange(1, 10_000_000),
    required=True,
    help="Data frames to record.",
)
@IDCODE
@reports_errors
def record(address, out, frames, idcode):
    """Receive a C37.118.2 stream from the PMU or PDC at HOST:PORT (pyc37's client: CFG-2,
    then 'start', addressed to stream --idcode) and write its CFG-2 and FRAMES data frames
    to OUT, as received (an IPv6 HOST in brackets: [::1]:4712).  Each frame is checked as
    it comes (CRC; each data frame's IDCODE, type, size and FRACSEC count against the
    CFG-2; a CFG-2 resent must be the one in use) and must come whole within 30 s, each data
    frame within 30 s of the one before, whatever other frames come between.  A stream that
    stops before FRAMES (the server closes, resets or sends no whole data frame for 30 s, or
    a frame is refused) is written as far as it came, up to the frame refused, and named an
    error (exit status 2: the recording is partial), beside OUT when a file is there
    (STEM.partial.SUFFIX: a file at OUT is replaced only by a whole recording).  Time stamps
    are checked as `pmu replay` and `estimate track` check them, each data frame as it
    comes: one whose time stamp repeats or goes back, or is off the reporting instants of
    the CFG-2's DATA_RATE, is refused so, named with its time stamp, and the stream is cut
    there.
    Interrupted (Ctrl-C, SIGTERM), the frames received are written likewise, as a partial
    recording (exit status 130, 143), and said.  Reporting instants the stream skipped
    (gaps), and PMU values of a failed clock or flagged by their STAT, are counted and
    named with the frames recorded.

    \b
    Example:
      stabctl pmu record 127.0.0.1:4712 --frames 3601 -o wecc.c37
    """
    from stabctl.estimation import c37
    from stabctl.estimation.c37_tcp import End, receive
    from stabctl.estimation.sources import stream_gaps, unused_values

    host, port = _host_port(address)
    [code] = stream_idcodes(idcode, 1)
    check_writable(out, "--out")
    try:
        got = receive(host, port, End(frames=frames), idcode=code)
    except KeyboardInterrupt as exc:  # what came is kept, as of a stream cut short
        exc.kept = _keep_interrupted(  # type: ignore[attr-defined]
            out, address, getattr(exc, "stream", None)
        )
        raise
    cfg2 = c37.read_config(got.cfg2, "the CFG-2")
    data, why, kept = got.data, f"{address}: {got.short}", f"{len(got.data)} received"
    at = kept_at(out) if got.short else out
    write_kept(at, lambda to: write_recording(to, got.cfg2, data), why if got.short else None, kept)
    if got.short:
        fail_short(out, at, why, kept)
    gaps = stream_gaps(data, cfg2)
    flagged = unused_values(
        collections.Counter(why for d in data for why in c37.flags(cfg2, d) if why)
    )
    click.echo(
        f"recorded {counted(len(data), 'frame')} from {address} to {shown(out)}"
        + (f"; {gaps}" if gaps else "")
        + (f"; {flagged}" if flagged else "")
    )


def _keep_interrupted(out, address: str, stream) -> str:
    """What an interrupted `record` keeps, for its ``interrupted:`` line: the data frames
    received (`c37_tcp.receive`'s partial `stream`, None if the CFG-2 had not come) written
    to OUT as a partial recording, atomically (beside OUT when a file is there, as for
    any stream cut short), unless no data frame came.  A second interrupt while writing
    leaves the files as they were."""
    if stream is None:
        return f"nothing is kept: {address} had not sent its CFG-2"
    n = len(stream.data)
    what = f"{address} {stream.short.removeprefix('interrupted ')}"
    if not n:
        return f"nothing is kept: {what}"
    return keep_interrupted(
        out,
        what,
        n,
        "received",
        "a partial recording",
        lambda at: write_recording(at, stream.cfg2, stream.data),
    )


def _host_port(address: str) -> tuple[str, int]:
    """(host, port) of a HOST:PORT argument; InputError naming the address: no host or
    port, a port outside 1-65535 (`c37_tcp.port_number`), or a list (one server here:
    "127.0.0.1:1,127.0.0.1:2" was looked up as the host "[127.0.0.1:1,127.0.0.1]")."""
    from stabctl.estimation.c37_tcp import port_number, split_hostport

    if "," in address:
        raise InputError(
            f"address {address!r}: one HOST:PORT (this command talks to one server; "
            "`estimate track --source tcp://A,B` reads several)"
        )
    try:
        host, port = split_hostport(address)
        if not host:
            raise InputError("expected HOST:PORT")
        return host, port_number(port)
    except InputError as exc:
        raise InputError(f"address {address!r}: {exc}") from None


@pmu.command()
@fault_run_options
@click.option(
    "--seed", type=INT, default=0, show_default=True, metavar="S", help="Seed of the PMU noise."
)
@storage_options(" Required: the ESDs the controller commands.")
@esd_model_option
@_listening
@click.option(
    "--speed",
    type=FLOAT,
    default=1.0,
    show_default=True,
    help="Time-stamp seconds per second: 1 real time (a real-time simulator), "
    "0 as fast as the controller answers.",
)
@click.option(
    "--timeout",
    type=FLOAT,
    default=60.0,
    show_default=True,
    help="Longest wait for the controller to connect, and for each whole answer (s).",
)
@model_options
@q_limits_option
@json_option("the verdict and the link's figures")
@reports_errors
def plant(
    case_name,
    fault,
    far_bus,
    t_fault,
    clear_cycles,
    tf,
    rate,
    latency_ms,
    drop,
    tve_pct,
    fe_hz,
    rfe_hz_s,
    k_sigma,
    window_cycles,
    seed,
    esd_pct,
    deadband_hz,
    v_gate,
    coi,
    hysteresis_hz,
    esd_model,
    host,
    port,
    allow,
    speed,
    timeout,
    conventions,
    step,
    q_limits,
    as_json,
):
    """Simulate CASE through a line fault with one ESD per generator commanded over the
    network: the generators' PMUs are served as one C37.118.2 stream on HOST:PORT, the
    controller that connects (`stabctl pmu control`) answers each data frame with the ESD
    modes, which take effect --latency-ms after the frame's time stamp (docs/estimation.md
    6).  The run waits for each answer, and at --speed 1 (real time) sends each frame no
    earlier than its time stamp, so a round trip above the latency is a real miss.
    Prints the verdict, the ESD switchings, the false actions and the measured round trips.

    \b
    Example:
      stabctl pmu plant miniwecc --fault 83 --far-bus 33 --tf 10 --esd-pct 5 --port 4713
      stabctl pmu control miniwecc 127.0.0.1:4713 --esd-pct 5 --estimator ekf
    """
    from stabctl.cli.checks import model_settings
    from stabctl.cli.format import closed_loop_lines, control_record
    from stabctl.estimation import closed_loop as cl
    from stabctl.estimation.c37_loop import Listen
    from stabctl.estimation.c37_tcp import hostport
    from stabctl.studies.estimate import loop_row

    if esd_pct is None:
        raise InputError("pmu plant needs --esd-pct")
    refuse_given(
        ("hysteresis_hz",),
        "to pmu plant: the controller decides the ESD modes and applies its hysteresis "
        "(pmu control --hysteresis-hz); the plant's --deadband-hz and --coi set the rule "
        "of the false actions it counts, its --v-gate its devices' voltage gate",
    )
    peers = _allowed(host, allow)
    settings = pmu_settings(
        rate, latency_ms, drop, tve_pct, fe_hz, rfe_hz_s, k_sigma, window_cycles
    )
    case, ev, tf = fault_event(case_name, fault, far_bus, t_fault, clear_cycles, tf)
    settings = rate_for_case(settings, rate, case)
    check_latency(settings, t_fault, tf, f"--tf {tf:g} s")
    law = controller(deadband_hz, v_gate, coi, hysteresis_hz)
    # the plant only measures: the estimator named here is never run (the controller's is)
    loop = cl.LoopOptions(esd_pct, "raw", settings, seed, law, esd_model=esd_model, transport="tcp")
    listening = lambda a: click.echo(  # noqa: E731
        f"plant: PMUs of {case.name} on {hostport(*a)} (C37.118.2); waiting for a controller",
        err=True,
    )
    sim = model_settings(conventions, step, q_limits).simulator(case)
    run = cl.run_closed_loop(
        sim, [ev], tf, loop, serve=Listen(host, port, listening, timeout, speed or _INF, peers)
    )
    row = loop_row(run, deadband_hz, controller_here=False)
    rule = control_record(deadband_hz, v_gate, coi, hysteresis_hz)
    del rule["hysteresis_hz"]  # the controller's (refused above)
    lines = closed_loop_lines({"remote": row}, fault, far_bus, esd_pct, seed, esd_model, rule)
    out = {"closed_loop": row, "control": rule, "esd_model": esd_model, "lines": lines}
    click.echo(json.dumps(out, indent=1) if as_json else "\n".join(lines))


@pmu.command()
@click.argument("case_name", metavar="CASE")
@click.argument("address", metavar="HOST:PORT")
@ESTIMATOR
@rate_latency_options
@pmu_noise_options
@storage_options(
    " Required: the plant's ESDs, one at each generator's HV bus; the controller sends "
    "their modes, so P sets no mode here (the plant's --esd-pct sets their power)."
)
@PMU_AT
@click.option(
    "--timeout",
    type=FLOAT,
    default=60.0,
    show_default=True,
    help="Longest wait for a whole frame from the plant (s).",
)
@reports_errors
def control(
    case_name,
    address,
    estimator,
    rate,
    latency_ms,
    drop,
    tve_pct,
    fe_hz,
    rfe_hz_s,
    k_sigma,
    window_cycles,
    esd_pct,
    deadband_hz,
    v_gate,
    coi,
    hysteresis_hz,
    pmu_at,
    timeout,
):
    """The ESD controller of CASE over the network: subscribe to the C37.118.2 stream of
    the plant at HOST:PORT (`stabctl pmu plant`), feed every data frame to the estimator,
    apply the paper's Table 3 law to its relative speeds (forecast over --latency-ms) and
    answer each frame with the ESD modes, until the plant ends the run.  The noise options
    tune the estimator (they are the PMUs' stated accuracy).  Reporting instants the
    plant sent no frame for (gaps) are counted and named on the summary line and taken
    as `estimate track` takes them: the estimator predicts across a gap of at most 1 s,
    starts again after a longer one.

    \b
    Example:
      stabctl pmu control miniwecc 127.0.0.1:4713 --esd-pct 5 --estimator ekf
    """
    from stabctl.estimation import c37
    from stabctl.estimation.c37_loop import serve_controller
    from stabctl.estimation.sources import gaps_line, unused_values
    from stabctl.io import load_case

    if esd_pct is None:
        raise InputError("pmu control needs --esd-pct")
    refuse_given(
        ("drop", "window_cycles"),
        "to pmu control: its frames are the plant's, as received (no PMU is simulated)",
    )
    refuse_given(
        ("v_gate",),
        "to pmu control: the devices are the plant's, and they gate their commands by "
        "their bus voltage as the plant is told (pmu plant --v-gate)",
    )
    host, port = _host_port(address)
    settings = pmu_settings(
        rate, latency_ms, drop, tve_pct, fe_hz, rfe_hz_s, k_sigma, window_cycles
    )
    case = load_case(case_name)
    settings = rate_for_case(settings, rate, case)
    law = controller(deadband_hz, v_gate, coi, hysteresis_hz)
    ctrl = stream_controller(case, estimator, settings, esd_pct, law, pmu_at)
    got = serve_controller(
        ctrl, c37.stream_config(case, ctrl.pmus, settings.rate), host, port, timeout
    )
    d = ctrl.diagnostics()
    flagged, gaps = unused_values(got.flagged), gaps_line(got.gaps, " (no frame sent)")
    unformed = d.unformed([p.label for p in ctrl.pmus])
    click.echo(
        f"controller ({estimator}): answered {counted(got.frames, 'frame')} from {address}, "
        f"{counted(d.starts, 'ESD start')}"
        + (f"; {unformed}" if unformed else "")
        + (f"; {flagged}" if flagged else "")
        + (f"; {gaps}" if gaps else "")
    )
    applied = got.applied_latency_s
    if applied is not None and abs(applied - settings.latency_s) > 1e-9:
        warnings.warn(
            f"the plant applied the ESD modes {1e3 * applied:g} ms after each frame's time "
            f"stamp (its --latency-ms), and this controller forecast the relative speeds "
            f"over {1e3 * settings.latency_s:g} ms (--latency-ms): give both the same",
            stacklevel=2,
        )
