"""`stabctl pmu serve|replay|record`: the simulated PMUs as an IEEE C37.118.2 stream over
TCP, a recording served again, and a received stream recorded."""

from __future__ import annotations

import click

from stabctl.cli.checks import check_writable
from stabctl.cli.estimate import PMU_AT, RATE, _fault_event, _pmu_noise, _settings
from stabctl.cli.options import clear_cycles_option, fault_options, reports_errors, tf_option
from stabctl.errors import InputError

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
    """


def _serving(func):
    for option in reversed(
        (
            click.option(
                "--host", default="127.0.0.1", show_default=True, help="Address to listen on."
            ),
            click.option(
                "--port",
                type=click.IntRange(0, 65535),
                default=C37_PORT,
                show_default=True,
                help="TCP port (0: any free one, printed).",
            ),
            click.option(
                "--speed",
                type=float,
                default=1.0,
                show_default=True,
                help="Time-stamp seconds per second: 1 real time, 0 as fast as the client reads.",
            ),
        )
    ):
        func = option(func)
    return func


@pmu.command()
@click.argument("case_name", metavar="CASE")
@fault_options(required=True)
@clear_cycles_option("Clearing after N cycles, both ends")
@tf_option()
@RATE
@_pmu_noise
@click.option("--seed", type=int, default=0, show_default=True, help="PMU noise seed.")
@PMU_AT
@_serving
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
    speed,
):
    """Simulate CASE through a line fault and serve one PMU per generator as one IEEE
    C37.118.2 stream on HOST:PORT, to one PDC: CFG-2 and header on request, then the data
    frames from 'start', paced by their time stamps (docs/estimation.md 6).

    The frames are those `stabctl estimate rmse` evaluates for the same seed (C37.118.1
    noise, lost frames as absent data).  Exits when the PDC has been sent every frame or
    has closed the connection.
    \b
    Example:
      stabctl pmu serve miniwecc --fault 83 --far-bus 33 --tf 60 --port 4712
    """
    from stabctl.dynamics.driver import Simulator
    from stabctl.estimation import c37
    from stabctl.estimation import pmu as pm
    from stabctl.estimation.c37_tcp import StreamServer

    case, ev, tf = _fault_event(case_name, fault, far_bus, t_fault, clear_cycles, tf)
    settings = _settings(rate, 0.0, drop, tve_pct, fe_hz, rfe_hz_s, k_sigma, window_cycles)
    pmus = pm.machine_pmus(case, pmu_at)
    cfg = c37.stream_config(case, pmus, rate)
    res = Simulator(case).run([ev], t_end=tf)
    stream = pm.measure(pm.phasor_truth(case, res, pmus, window_cycles), settings, seed)
    _serve(StreamServer.of_frames(cfg, stream, host=host, port=port, speed=speed or _INF))


@pmu.command()
@click.argument("recording", type=click.Path(dir_okay=False))
@_serving
@reports_errors
def replay(recording, host, port, speed):
    """Serve RECORDING (a file `pmu record` wrote, or any capture of C37.118.2 frames,
    CFG-2 first) to one PDC, its frames as recorded, paced by their time stamps.
    \b
    Example:
      stabctl pmu replay wecc.c37 --speed 0
    """
    from stabctl.estimation.c37_tcp import StreamServer
    from stabctl.io.inputs import input_file

    path = input_file(recording, "RECORDING")
    _serve(StreamServer.of_recording(path, host=host, port=port, speed=speed or _INF))


def _serve(server) -> None:
    with server:
        host, port = server.address
        click.echo(
            f"serving {server.n_frames} frames on {host}:{port} (C37.118.2); waiting for a PDC",
            err=True,
        )
        server.finished.wait()
    click.echo(f"sent {server.n_sent} of {server.n_frames} frames")


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
    type=click.IntRange(1, 10_000_000),
    required=True,
    help="Data frames to record.",
)
@reports_errors
def record(address, out, frames):
    """Receive a C37.118.2 stream from the PMU or PDC at HOST:PORT (pyc37's client: CFG-2,
    then 'start') and write its CFG-2 and FRAMES data frames to OUT, as received; written
    whole or not at all.
    \b
    Example:
      stabctl pmu record 127.0.0.1:4712 --frames 3600 -o wecc.c37
    """
    from stabctl.estimation.c37_tcp import receive
    from stabctl.parallel import atomic_write

    host, _, port = address.rpartition(":")
    if not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise InputError(f"address {address!r}: expected HOST:PORT")
    check_writable(out, "--out")
    cfg2, data = receive(host, int(port), frames)
    atomic_write(out, lambda f: f.write(cfg2 + b"".join(data)), mode="wb")
    click.echo(f"recorded {len(data)} frames from {address} to {out}")
