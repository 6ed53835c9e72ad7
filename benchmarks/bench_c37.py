"""C37.118.2 over loopback TCP: miniWECC's 34 PMUs at 60 frames/s for 60 s of its Case 2
fault run, served by `stabctl.estimation.c37_tcp.StreamServer` in real time and read by
pyc37's own PDC client; frames lost, latency from each frame's due time (its time stamp
on the server's clock) to its arrival (median, 99th percentile, largest), and the cost
of encoding and parsing a frame.

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
    res = stabctl.Simulator(case).run(CASE2.fault.events(6 / case.freq_hz), t_end=args.seconds)
    pmus = pm.machine_pmus(case)
    stream = pm.measure(pm.phasor_truth(case, res, pmus), PMUSettings(rate=args.rate), seed=0)
    frames = list(stream)
    cfg = c37.stream_config(case, pmus, args.rate)
    t0 = time.perf_counter()
    server = StreamServer.of_frames(cfg, frames)
    encode = (time.perf_counter() - t0) / len(frames)
    with server:
        pdc = pdc_client(*server.address, pdc_id=9)
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


if __name__ == "__main__":
    main()
