"""PMU data over IEEE C37.118.2: Kundur's bus-3 fault measured by one PMU per generator,
served as a C37.118.2 stream on loopback TCP, received and fed to the speed estimators;
then the storage loop closed over TCP, the EKF controller answering every frame with the
ESD modes.  Needs the `pmu` extra (pyc37).

    python examples/pmu_stream.py
"""

import stabctl
from stabctl.dynamics.events import fault_with_clearing
from stabctl.estimation import c37, sources
from stabctl.estimation import closed_loop as cl
from stabctl.estimation import pmu as pm
from stabctl.estimation.c37_tcp import StreamServer
from stabctl.estimation.settings import PMUSettings
from stabctl.studies import estimation as study


def main():
    case = stabctl.load_case("kundur")
    sim = stabctl.Simulator(case)
    events = [fault_with_clearing(case, 3, 101, 1.0, 7)]  # line 3-101, cleared after 7 cycles
    res = sim.run(events, t_end=6.0)
    pmus, settings = pm.machine_pmus(case), PMUSettings()
    drawn = pm.measure(pm.phasor_truth(case, res, pmus), settings, seed=0)
    cfg = c37.stream_config(case, pmus, settings.rate)

    # the stream served unpaced on a free port and received as `--source tcp://` reads it
    with StreamServer.of_frames(cfg, drawn, speed=float("inf")) as server:
        source = sources.Source(servers=(server.address,))
        got = sources.read_frames(source, case, pmus, settings.rate)
    print(f"received {len(got.frames)} frames from {source}")
    window = (1.0 + 7 / 60 + 0.1, 6.0)
    figures = study.received_errors(case, res, settings, got.frames, 0, window)
    for name, fig in figures.items():
        print(f"{name:4}: relative-speed RMSE {fig['rel_rmse_mhz']['mean']:.2f} mHz")

    # the loop closed over TCP: 10 % ESDs commanded by the EKF controller
    run = cl.run_closed_loop(sim, events, 6.0, cl.LoopOptions(10, "ekf", transport="tcp"))
    rt = run.link["round_trip_ms"]
    print(
        f"loop over TCP: stable={run.result.stable}, {run.link['frames']} frames answered, "
        f"round trip median {rt['median']:.2f} ms, largest {rt['max']:.2f} ms"
    )


if __name__ == "__main__":
    main()
