"""C37.118.2 over loopback TCP: miniWECC's 34 PMUs at 60 frames/s for 60 s of its Case 2
fault run, served by `stabctl.estimation.c37_tcp.StreamServer` in real time and read by
pyc37's own PDC client; frames lost, latency from each frame's due time (its time stamp
on the server's clock) to its arrival (median, 99th percentile, largest), and the cost
of encoding and parsing a frame; Case 2's fault cleared after 4 cycles (the estimation
study's: the run stays in step).  Then the estimators fed the same stream received by
stabctl's own reader (`--source tcp://`) against the same frames in process, and Case 2's
storage loop closed over TCP (EKF controller, 5 % ESDs): verdict against in process, and
the round trip of every frame.

    python benchmarks/bench_c37.py [--seconds 60] [--rate 60]
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import stabctl
from stabctl.estimation import c37
from stabctl.estimation import pmu as pm
from stabctl.estimation.c37_tcp import StreamServer, pdc_client
from stabctl.estimation.settings import PMUSettings
from stabctl.studies.cases import CASE2


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--rate", type=int, default=60)
    args = ap.parse_args()
    case = stabctl.load_case("miniwecc")
    cycles = CASE2.cycles["estimation"]  # cleared in time: the run stays in step
    res = stabctl.Simulator(case).run(CASE2.fault.events(cycles / case.freq_hz), t_end=args.seconds)
    pmus = pm.machine_pmus(case)
    stream = pm.measure(pm.phasor_truth(case, res, pmus), PMUSettings(rate=args.rate), seed=0)
    frames = list(stream)
    cfg = c37.stream_config(case, pmus, args.rate)
    t0 = time.perf_counter()
    server = StreamServer.of_frames(cfg, frames)
    encode = (time.perf_counter() - t0) / len(frames)
    with server:
        pdc = pdc_client(*server.address, idcode=server.idcode)
        cfg2 = pdc.get_config()
        pdc.start()
        got, arrived = [], []
        for _ in frames:
            got.append(pdc.get())
            arrived.append(time.perf_counter())
        pdc.quit()
    t0 = time.perf_counter()
    back = [c37.parse_frame(cfg, cfg2, g.convert2bytes()) for g in got]
    parse = (time.perf_counter() - t0) / len(got)
    same = sum(abs(b.t - f.t) < 1e-6 for b, f in zip(back, frames))
    late = 1e3 * (np.array(arrived) - np.array(server.due_at))
    print(
        f"{len(pmus)} PMUs, {args.rate} frames/s, {args.seconds:g} s: {len(frames)} frames "
        f"sent, {len(got)} received ({len(frames) - same} lost or out of place)\n"
        f"latency, due to arrival: median {np.median(late):.2f} ms, 99th percentile "
        f"{np.percentile(late, 99):.2f} ms, largest {np.max(late):.2f} ms\n"
        f"per frame: encode {1e3 * encode:.2f} ms, parse {1e3 * parse:.2f} ms "
        f"({len(got[0].convert2bytes())} bytes)"
    )

    estimators_over_tcp(case, res, frames, stream, cfg, cycles)
    loop_over_tcp(case)


def estimators_over_tcp(case, res, frames, stream, cfg, cycles) -> None:
    """Relative-speed RMSE of each estimator: the stream received over TCP (unpaced),
    through the codec in process, as drawn."""
    from stabctl.estimation import sources
    from stabctl.studies import estimation as study

    window = (CASE2.fault.t_fault + cycles / case.freq_hz + 0.1, res.t[-1])
    with StreamServer.of_frames(cfg, frames, speed=float("inf")) as server:
        t0 = time.perf_counter()
        got = sources.read_frames(
            sources.Source(servers=(server.address,)), case, cfg.pmus, cfg.rate
        )
        wall = time.perf_counter() - t0
    figs = [
        study.received_errors(case, res, stream.settings, f, 0, window)
        for f in (got.frames, c37.on_wire(cfg, frames))
    ]
    drawn = study.monte_carlo(case, res, stream.settings, 1, 0, window)
    print(f"estimators, {len(got.frames)} frames received unpaced in {wall:.1f} s:")
    for e in drawn:
        a, b, c = (f[e]["rel_rmse_mhz"]["mean"] for f in (*figs, drawn))
        print(
            f"  {e:4} relative-speed RMSE {a:.4f} mHz over TCP, {b:.4f} through the codec "
            f"in process ({'equal' if a == b else 'DIFFERENT'}), {c:.4f} as drawn"
        )


def loop_over_tcp(case) -> None:
    """Case 2's loop with the EKF and 5 % ESDs in process and over TCP."""
    from stabctl.estimation import closed_loop as cl

    sim, events = stabctl.Simulator(case), CASE2.fault.events(6 / case.freq_hz)
    runs = {}
    for transport in ("process", "tcp"):
        t0 = time.perf_counter()
        runs[transport] = cl.run_closed_loop(
            sim, events, CASE2.t_end, cl.LoopOptions(5, "ekf", transport=transport)
        )
        runs[transport].result.meta["wall_s"] = time.perf_counter() - t0
    for transport, run in runs.items():
        r = run.result
        print(
            f"Case 2 loop {transport:7}: {'stable' if r.stable else 'UNSTABLE'}, "
            f"{len(r.meta['switchings'])} switchings, {cl.false_actions(run)} false actions, "
            f"{r.meta['wall_s']:.1f} s"
        )
    link = runs["tcp"].link
    rt = link["round_trip_ms"]
    print(
        f"  over TCP: {link['frames']} frames answered, round trip median {rt['median']:.2f} "
        f"ms, 99th percentile {rt['p99']:.2f} ms, largest {rt['max']:.2f} ms; "
        f"{link['late']} later than the 50 ms latency modelled"
    )


if __name__ == "__main__":
    main()
