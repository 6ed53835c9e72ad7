"""`stabctl pmu serve|replay|record` over loopback: a served stream recorded by the
command line is the in-process PMU stream of the same seed, a recording served again and
recorded again is the same file byte for byte, and bad addresses and files are one error
line each."""

import json
import re
import subprocess
import sys
import time

import numpy as np
import pytest
from click.testing import CliRunner

pytest.importorskip("pyc37")

import stabctl
from stabctl.cli import main
from stabctl.dynamics.events import fault_with_clearing
from stabctl.estimation import c37
from stabctl.estimation import pmu as pm
from stabctl.estimation.settings import PMUSettings


def serving(*args, servers=1):
    """A `stabctl pmu ...` server in its own process, and the HOST:PORT it prints (with
    servers > 1, the list of the first `servers` it prints)."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "stabctl.cli", "pmu", *args, "--port", "0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    found = []
    for line in proc.stderr:
        found += re.findall(r"on (127\.0\.0\.1:\d+|\[::1\]:\d+)", line)
        if len(found) == servers:
            return proc, found[0] if servers == 1 else found
    proc.wait(timeout=60)
    raise AssertionError(f"{len(found)} server addresses printed (exit {proc.returncode})")


def finished(proc):
    """(exit status, stdout) of a `serving` process once it ends, its pipes closed."""
    out, _ = proc.communicate(timeout=60)
    return proc.returncode, out


def record(address, frames, out):
    res = CliRunner().invoke(
        main, ["pmu", "record", address, "--frames", str(frames), "-o", str(out)]
    )
    assert res.exit_code == 0, res.output
    return res


def test_served_stream_is_the_in_process_stream_and_replays_byte_for_byte(tmp_path):
    args = ["kundur", "--fault", "3", "--far-bus", "101", "--tf", "2", "--seed", "4"]
    proc, address = serving("serve", *args)
    record(address, 121, tmp_path / "a.c37")
    status, out = finished(proc)
    assert status == 0 and "sent 121 of 121 frames" in out
    case = stabctl.load_case("kundur")
    ev = fault_with_clearing(case, 3, 101, 1.0, 6.0)
    res = stabctl.Simulator(case).run([ev], t_end=2.0)
    pmus = pm.machine_pmus(case)
    stream = pm.measure(pm.phasor_truth(case, res, pmus), PMUSettings(), seed=4)
    back = c37.replay(tmp_path / "a.c37", c37.stream_config(case, pmus, 60))
    assert len(back) == len(stream) == 121
    for b, f in zip(back, stream):
        np.testing.assert_allclose(b.v, f.v, rtol=1.2e-7)
        assert np.max(np.abs(b.freq - f.freq)) <= 0.5e-3 + 1e-12
    proc, address = serving("replay", str(tmp_path / "a.c37"), "--speed", "0")
    record(address, 121, tmp_path / "b.c37")
    assert finished(proc)[0] == 0
    assert (tmp_path / "b.c37").read_bytes() == (tmp_path / "a.c37").read_bytes()


def test_estimate_rmse_from_a_served_stream_equals_in_process(tmp_path, capsys):
    """`estimate rmse --source tcp://...` on `pmu serve`'s stream of the same fault and
    seed: every estimator's figures equal those of the same seed's frames through the
    frame codec in process; the text report prints the three side by side."""
    fault = ["kundur", "--fault", "3", "--far-bus", "101", "--tf", "4", "--seed", "2"]
    proc, address = serving("serve", *fault, "--drop", "0.05", "--speed", "0")
    res = CliRunner().invoke(
        main,
        ["estimate", "rmse", *fault, "--drop", "0.05", "--source", f"tcp://{address}", "--json"],
    )
    assert res.exit_code == 0, res.output
    assert finished(proc)[0] == 0
    d = json.loads(res.stdout)
    src = d["source"]
    assert (src["frames"], src["data_frames"], src["missing"], d["runs"]) == (241, 241, 0, 1)
    assert src["absent"] > 0 and d["false_actions"] is None
    assert set(d["estimators"]) == {"raw", "kf", "ekf"}
    for name, fig in d["estimators"].items():
        assert {m: v["mean"] for m, v in fig.items()} == src["on_wire"][name]
    gap = abs(
        d["estimators"]["raw"]["speed_rmse_mhz"]["mean"]
        - src["in_process"]["raw"]["speed_rmse_mhz"]
    )
    assert gap <= 1 / np.sqrt(12)  # FREQ in whole mHz: at most its rounding RMS
    # the text: the loss probability is the in-process comparison's, the stream's own
    # losses its missing instants (round 44: "lost 0" beside "8 missing")
    from stabctl.cli.format import print_estimate

    print_estimate(d)
    text = capsys.readouterr().out
    assert "frames lost with probability 0.05 in the in-process comparison; frames from" in text
    assert "0 missing (labelled seed 2)" in text


@pytest.mark.heavy
def test_one_server_per_pmu_gives_the_one_stream_s_figures():
    """`pmu serve --each-pmu`: Kundur's four PMUs on four ports, read by `estimate rmse
    --source tcp://A,B,C,D`, give the figures of the four PMUs as one stream."""
    fault = ["kundur", "--fault", "3", "--far-bus", "101", "--tf", "3", "--seed", "1"]
    rmse = ["estimate", "rmse", *fault, "--json", "--source"]
    proc, address = serving("serve", *fault, "--speed", "0")
    one = json.loads(CliRunner().invoke(main, [*rmse, f"tcp://{address}"]).stdout)
    assert finished(proc)[0] == 0
    proc, addresses = serving("serve", *fault, "--speed", "0", "--each-pmu", servers=4)
    res = CliRunner().invoke(main, [*rmse, "tcp://" + ",".join(addresses)])
    status, out = finished(proc)
    assert res.exit_code == 0 and status == 0, res.output
    assert "sent 724 of 724 frames on 4 ports" in out  # 181 time stamps x 4 PMUs
    four = json.loads(res.stdout)
    assert four["source"]["streams"] == 4 and four["source"]["data_frames"] == 4 * 181
    assert four["estimators"] == one["estimators"]


def test_estimate_closed_loop_over_tcp_prints_the_link():
    """`estimate closed-loop --transport tcp`: the PMU estimators' rows carry the link's
    frames (one per reporting instant after the start) and round trips; the ideal
    estimator, which reads the true speeds, has no link; the verdicts are those of the
    loop in process through the codec."""
    args = ["estimate", "closed-loop", "kundur", "--fault", "3", "--far-bus", "101"]
    args += ["--clear-cycles", "7", "--tf", "3", "--esd-pct", "10", "--json"]
    tcp = json.loads(CliRunner().invoke(main, [*args, "--transport", "tcp"]).stdout)
    codec = json.loads(CliRunner().invoke(main, [*args, "--transport", "codec"]).stdout)
    assert tcp["closed_loop"]["ideal"]["link"] is None
    for e in ("raw", "kf", "ekf"):
        row = tcp["closed_loop"][e]
        assert row["link"]["frames"] == 3 * 60 and row["link"]["round_trip_ms"]["median"] > 0
        assert {k: row[k] for k in ("stable", "mode_commands", "false_actions")} == {
            k: codec["closed_loop"][e][k] for k in ("stable", "mode_commands", "false_actions")
        }
    assert "over TCP: 180 frames, round trip median" in "\n".join(tcp["lines"])


def test_estimate_closed_loop_says_how_many_frames_the_controller_used():
    """Round 30: `estimate closed-loop --drop 0.999` printed "stable switchings 0 false
    actions 0" for each estimator, as if the loop had worked, with nearly every frame
    lost.  Each row now gives the frames used of those due; the ideal estimator reads
    the true speeds and acts on every frame."""
    args = ["estimate", "closed-loop", "kundur", "--fault", "3", "--far-bus", "101"]
    args += ["--clear-cycles", "7", "--tf", "3", "--esd-pct", "10", "--json"]
    res = CliRunner().invoke(main, [*args, "--drop", "0.999"])
    assert res.exit_code == 0, res.output
    d = json.loads(res.stdout)
    rows = d["closed_loop"]
    assert rows["ideal"]["frames_formed"] == rows["ideal"]["frames"] > 150
    # what ran, as estimate rmse's JSON gives it (round 36: closed-loop's had none of it)
    assert d["case"] == "kundur" and d["esd_pct"] == 10 and d["seed"] == 0
    assert d["fault"] == {"bus": 3, "far_bus": 101, "t_fault_s": 1.0, "clear_cycles": 7.0}
    assert d["pmu"]["drop_prob"] == 0.999 and d["pmu"]["rate"] == 60
    assert d["control"] == {
        "deadband_hz": 0.1,
        "v_gate_pu": 0.8,
        "coi": "system",
        "hysteresis_hz": 0.0,
    }
    for e in ("raw", "kf", "ekf"):
        assert rows[e]["frames"] == rows["ideal"]["frames"] and rows[e]["frames_formed"] < 10
    lines = json.loads(res.stdout)["lines"]
    used, due = rows["raw"]["frames_formed"], rows["raw"]["frames"]
    assert f"frames used {used} of {due} ({due - used} lost or incomplete" in lines[2]
    assert f"frames used {due} of {due}\n" in "\n".join(lines) + "\n"  # ideal
    # the count is of the commands sent (round 35: called switchings, 26 of them with
    # a voltage gate of 1.5 pu that let no device deliver any power)
    assert f"mode commands {rows['ideal']['mode_commands']:5d}  false actions" in lines[1]


def test_plant_and_controller_in_two_processes_close_the_loop():
    """`pmu plant` in its own process, `pmu control` here: the run's verdict, switchings
    and false actions are those of the EKF loop in process through the codec, every frame
    is answered."""
    fault = ["kundur", "--fault", "3", "--far-bus", "101", "--clear-cycles", "7"]
    proc, address = serving(
        "plant", *fault, "--tf", "3", "--esd-pct", "10", "--speed", "0", "--json"
    )
    res = CliRunner().invoke(main, ["pmu", "control", "kundur", address, "--esd-pct", "10"])
    assert res.exit_code == 0, res.output
    assert "controller (ekf): answered 180 frames" in res.output
    assert "warning" not in res.output  # the plant applied the modes at the 50 ms forecast
    status, out = finished(proc)
    assert status == 0, out
    remote = json.loads(out)["closed_loop"]
    args = ["estimate", "closed-loop", *fault, "--tf", "3", "--esd-pct", "10"]
    codec = json.loads(CliRunner().invoke(main, [*args, "--transport", "codec", "--json"]).stdout)
    ekf = codec["closed_loop"]["ekf"]
    assert {k: remote[k] for k in ("stable", "mode_commands", "false_actions")} == {
        k: ekf[k] for k in ("stable", "mode_commands", "false_actions")
    }
    assert remote["link"]["frames"] == 180


def test_estimate_track_writes_a_row_per_recorded_frame(tmp_path, monkeypatch):
    """`estimate track` on a recording, no simulation: a CSV row per frame with each
    machine's speed, the COI speed, the relative speeds and the ESD modes; the COI column
    is each speed less its relative speed."""
    monkeypatch.chdir(tmp_path)
    proc, address = serving("serve", "kundur", "--fault", "3", "--far-bus", "101", "--tf", "2")
    record(address, 121, tmp_path / "k.c37")
    assert finished(proc)[0] == 0
    res = CliRunner().invoke(
        main,
        ["estimate", "track", "kundur", "--source", "k.c37", "--esd-pct", "10", "--out", "t.csv"],
    )
    assert res.exit_code == 0, res.output
    assert "tracked 121 frames from k.c37 with ekf" in res.stdout
    head, *rows = (tmp_path / "t.csv").read_text().splitlines()
    names = head.split(",")
    assert len(rows) == 121 and len(names) == 1 + 4 + 1 + 4 + 4 + 4
    data = np.array([[float(v) for v in r.split(",")] for r in rows])
    coi = data[:, names.index("f_coi_hz")]
    for k in range(1, 5):
        rel = data[:, 5 + k] / 1e3
        np.testing.assert_allclose(data[:, k] - rel, coi, atol=1e-6)
    assert set(np.unique(data[:, -8:-4])) <= {-1.0, 0.0, 1.0}  # the modes
    assert names[-4:] == ["age_B1:G1_s", "age_B2:G2_s", "age_B11:G3_s", "age_B12:G4_s"]
    assert not data[:, -4:].any()  # every frame measured every machine


def test_estimate_source_refuses_monte_carlo_options(tmp_path):
    (tmp_path / "r.c37").write_bytes(b"")
    args = ["estimate", "rmse", "kundur", "--fault", "3", "--far-bus", "101"]
    args += ["--runs", "5", "--source"]
    res = CliRunner().invoke(main, [*args, str(tmp_path / "r.c37")])
    assert res.exit_code == 2 and "--runs cannot go with it" in res.output, res.output


@pytest.mark.parametrize(
    "args, needle",
    [
        (["record", "nonsense", "--frames", "5", "-o", "r.c37"], "expected HOST:PORT"),
        (
            ["record", "127.0.0.1:99999", "--frames", "5", "-o", "r.c37"],
            "address '127.0.0.1:99999': port 99999 is out of range (1-65535)",
        ),
        (
            ["control", "kundur", "[::1]:0", "--esd-pct", "5"],
            "address '[::1]:0': port 0 is out of range (1-65535)",
        ),
        (["record", "127.0.0.1:1", "--frames", "5", "-o", "r.c37"], "no C37.118.2 server"),
        (["replay", "missing.c37"], "RECORDING"),
        (["replay", "junk.c37"], "C37.118.2 recording junk.c37: no frame SYNC at byte 0"),
        (["serve", "kundur", "--fault", "3", "--far-bus", "101", "--speed", "-1"], "--speed"),
        (["control", "kundur", "127.0.0.1:1", "--esd-pct", "5"], "no plant at 127.0.0.1:1"),
        (["control", "kundur", "127.0.0.1", "--esd-pct", "5"], "expected HOST:PORT"),
        # a list, looked up as one host ("[127.0.0.1:1,127.0.0.1]:2")
        (["record", "127.0.0.1:1,127.0.0.1:2", "--frames", "5", "-o", "r.c37"], "one HOST:PORT"),
        (["control", "kundur", "127.0.0.1:1,127.0.0.1:2", "--esd-pct", "5"], "one HOST:PORT"),
        (["track", "kundur", "--source", "junk.c37", "--out", "t.csv"], "junk.c37: no frame SYNC"),
        (["track", "kundur", "--source", "missing.c37", "--out", "t.csv"], "no such recording"),
        (
            ["track", "kundur", "--source", "tcp://127.0.0.1:1", "--out", "t.csv"],
            "a TCP --source needs its end: --until S or --frames N",
        ),
        (["replay", "junk.c37", "--allow", "pdc.example"], "'pdc.example': not an IP address"),
        (["replay", "junk.c37", "--allow", "10.0.0.1,,10.0.0.2"], "an empty item"),
        (["replay", "junk.c37", "--allow", ""], "--allow '': names no peer"),
        (["replay", "junk.c37", "--allow", "  "], "': names no peer"),
        (["serve", "kundur", "--fault", "9999", "--far-bus", "1", "--allow", ""], "--allow ''"),
        (
            ["plant", "kundur", "--fault", "9999", "--far-bus", "1", "--esd-pct", "5"]
            + ["--allow", ""],
            "--allow '': names no peer",
        ),
        (
            ["record", "127.0.0.1:1", "--frames", "5", "-o", "r.c37", "--idcode", "0"],
            "--idcode '0': '0' is not an IDCODE",
        ),
        (
            ["record", "127.0.0.1:1", "--frames", "5", "-o", "r.c37", "--idcode", "1,2"],
            "--idcode 1,2: 2 IDCODEs for 1 server(s)",
        ),
        (
            ["track", "kundur", "--source", "junk.c37", "--out", "t.csv", "--idcode", "5"],
            "--idcode given with a recording as --source",
        ),
        (
            ["track", "kundur", "--source", "tcp://127.0.0.1:1-2", "--frames", "5"]
            + ["--out", "t.csv", "--idcode", "1,2,3"],
            "--idcode 1,2,3: 3 IDCODEs for 2 server(s)",
        ),
        (["plant", "kundur", "--fault", "3", "--far-bus", "101"], "needs --esd-pct"),
        (
            ["plant", "kundur", "--fault", "3", "--far-bus", "101", "--esd-pct", "5"]
            + ["--port", "0", "--timeout", "0.5"],
            "no controller connected within 0.5 s",
        ),
    ],
)
def test_bad_input_is_one_error_line(args, needle, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "junk.c37").write_bytes(b"\x00" * 40)
    res = CliRunner().invoke(main, ["estimate" if args[0] == "track" else "pmu", *args])
    assert res.exit_code == 2, res.output
    assert needle in res.output and "Traceback" not in res.output
    assert not (tmp_path / "r.c37").exists() and not (tmp_path / "t.csv").exists()


_HUGE_PORT = "1" + "0" * 5000  # beyond Python's 4300-digit limit of int(str)


@pytest.mark.parametrize(
    "args",
    [
        ["pmu", "record", f"127.0.0.1:{_HUGE_PORT}", "--frames", "5", "-o", "r.c37"],
        ["estimate", "track", "kundur", "--source", f"tcp://127.0.0.1:{_HUGE_PORT}"]
        + ["--frames", "5", "--out", "t.csv"],
        ["pmu", "control", "kundur", f"127.0.0.1:{_HUGE_PORT}", "--esd-pct", "5"],
    ],
)
def test_a_port_of_thousands_of_digits_is_refused_by_its_length(args, tmp_path, monkeypatch):
    """A port of 5001 digits was converted with int(), which Python refuses beyond 4300
    digits: a ValueError traceback (exit 1).  It is out of range by its length alone:
    refused naming the port's digits and the range, one error line, exit 2; a port
    written with leading zeros is still its number."""
    from stabctl.estimation.c37_tcp import port_number

    monkeypatch.chdir(tmp_path)
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 2, (res.output, res.exception)
    lines = res.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), res.stderr[-300:]
    assert "port of 5001 digits is out of range (1-65535)" in lines[0]
    assert port_number("0" * 5000 + "4712") == 4712


def test_each_pmu_ports_beyond_65535_are_refused_by_name():
    """`pmu serve --each-pmu --port 65534` on Kundur (4 PMUs) needs ports 65534-65537: refused
    before any work (exit 2, the range and the largest port that fits), not an
    OverflowError from bind()."""
    res = CliRunner().invoke(
        main,
        ["pmu", "serve", "kundur", "--fault", "3", "--far-bus", "101", "--each-pmu",
         "--port", "65534"],
    )  # fmt: skip
    assert res.exit_code == 2
    assert "4 PMUs need ports 65534-65537, beyond 65535 (give --port <= 65532" in res.output


def test_record_beyond_the_stream_keeps_what_came_and_says_so(tmp_path):
    """`pmu record --frames 500` of a 121-frame stream (the finding: every frame received
    was discarded, or a partial result presented as whole): the 121 frames are written,
    the shortfall is one error line (exit 2: the recording is partial); the server is
    told nothing else."""
    args = ["kundur", "--fault", "3", "--far-bus", "101", "--tf", "2", "--speed", "0"]
    proc, address = serving("serve", *args)
    out = tmp_path / "a.c37"
    res = CliRunner().invoke(main, ["pmu", "record", address, "--frames", "500", "-o", str(out)])
    assert finished(proc)[0] == 0
    assert res.exit_code == 2, res.output
    assert res.stderr == (
        f"error: {address}: the server closed the connection after 121 data frames, the "
        f"last stamped 2.0000 s, before 500 frames; the 121 received are in {out}\n"
    )
    assert res.stdout == ""
    case = stabctl.load_case("kundur")
    assert len(c37.replay(out, c37.stream_config(case, pm.machine_pmus(case), 60))) == 121


def test_listening_beyond_loopback_without_allow_list_warns(capsys):
    """`--host 0.0.0.0` with no --allow is named a warning (any host that reaches the
    port may connect) as the server starts, not when it ends; with --allow it is not, nor
    on any loopback address (all of 127.0.0.0/8, ::1, localhost, and 127.1, which was
    warned as public).  An empty --host, which
    listened on every interface, is refused."""
    from stabctl.cli.pmu import _allowed
    from stabctl.errors import InputError

    assert _allowed("0.0.0.0", None) == ()
    assert _allowed("0.0.0.0", "10.0.0.5, 10.0.0.6") == ("10.0.0.5", "10.0.0.6")
    # 127.1 and 0x7f.1 are 127.0.0.1 as the server's bind reads them (inet_aton)
    for host in ("127.0.0.1", "127.0.0.2", "127.255.0.9", "::1", "localhost", "127.1", "0x7f.1"):
        assert _allowed(host, None) == ()
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("warning: listening on 0.0.0.0: any host")
    _allowed("10.1", None)  # 10.0.0.1: beyond loopback
    assert "warning: listening on 10.1: any host" in capsys.readouterr().err
    with pytest.raises(InputError, match="--host '': an empty address"):
        _allowed("", None)


def test_a_host_given_as_the_servers_print_it_or_not_of_this_machine(kundur_recording):
    """`--host [::1]` (the form the servers print their address in) failed with "Name or
    service not known" after a warning that any host may connect; an address of no
    interface here (fe80::1%lo) or a name that does not resolve likewise.  The brackets
    are taken off; a host this machine cannot listen on is refused as a usage error,
    before any warning and before any server starts."""
    from stabctl.cli.pmu import _listen_host

    assert _listen_host(None, None, "[::1]") == "::1"
    assert _listen_host(None, None, "127.0.0.1") == "127.0.0.1"
    for host in ("no.such.host.invalid", "[192.0.2.1]"):  # a name; a documentation address
        res = CliRunner().invoke(
            main, ["pmu", "replay", str(kundur_recording), "--port", "0", "--host", host]
        )
        assert res.exit_code == 2, res.output
        [said] = res.stderr.splitlines()
        assert said.startswith("error: Invalid value for '--host': ") and "cannot listen" in said


def test_an_allow_list_no_peer_can_match_is_named(capsys):
    """`--allow 10.1.2.3` with `--host 127.0.0.1` (a loopback listener's peers are
    loopback) or `--allow ::1` on an IPv4 listener admitted no one without a word: each
    such address is a warning as the server starts; `--allow 0.0.0.0`, no peer's address,
    is refused."""
    from stabctl.cli.pmu import _allowed
    from stabctl.errors import InputError

    assert _allowed("127.0.0.1", "10.1.2.3,127.0.0.1, ::1") == ("10.1.2.3", "127.0.0.1", "::1")
    assert _allowed("::1", "::1") == ("::1",)
    assert capsys.readouterr().err.splitlines() == [
        "warning: --allow 10.1.2.3: not a loopback address, and a server on 127.0.0.1 has "
        "loopback peers only: it admits no one",
        "warning: --allow ::1: an IPv6 address, and a server on 127.0.0.1 has IPv4 peers "
        "only: it admits no one",
    ]
    for unspecified in ("0.0.0.0", "::"):
        with pytest.raises(InputError, match=f"--allow {unspecified}: the unspecified address"):
            _allowed("127.0.0.1", unspecified)
    # round 46: `--allow ::1%lo` (an IPv6 zone) was taken as it was, which no peer's
    # address equals: a peer is matched by its address, the zone left out and said
    assert _allowed("::1", "::1%lo") == ("::1",)
    assert capsys.readouterr().err.splitlines() == [
        "warning: --allow ::1%lo: read as ::1 (a peer is matched by its address, not by the "
        "zone after %)"
    ]
    from stabctl.estimation.c37_tcp import Guard

    assert Guard(allow=("fe80::1",)).admits(("fe80::1%eth0", 4712, 0, 2))


def test_a_peer_that_resets_the_controller_is_named_by_its_address():
    """`pmu control` against a server that is not a plant (a `pmu serve`) ended with
    exit 141 and no message: the connection's BrokenPipeError was taken for a closed
    stdout.  A reset or broken connection is now an InputError naming the address."""
    import socket
    import struct
    import threading

    from stabctl.errors import InputError
    from stabctl.estimation import c37
    from stabctl.estimation import pmu as pmus
    from stabctl.estimation.c37_loop import serve_controller

    srv = socket.create_server(("127.0.0.1", 0))
    port = srv.getsockname()[1]

    def reset_at_once():
        conn, _ = srv.accept()
        conn.recv(64)
        conn.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        conn.close()  # an RST, not a FIN

    threading.Thread(target=reset_at_once, daemon=True).start()
    case = stabctl.load_case("kundur")
    cfg = c37.stream_config(case, pmus.machine_pmus(case), 60)
    with pytest.raises(InputError, match=f"the plant at 127.0.0.1:{port}: "):
        serve_controller(None, cfg, "127.0.0.1", port, 5)  # reset before any frame
    srv.close()


@pytest.fixture(scope="module")
def kundur_recording(tmp_path_factory):
    """A recording of Kundur's 4-PMU stream for 1.2 s (73 frames)."""
    from pmu_streams import kundur_stream

    _, _, cfg, frames = kundur_stream(t_end=1.2)
    path = tmp_path_factory.mktemp("rec") / "k.c37"
    c37.record(path, cfg, frames)
    return path


@pytest.mark.parametrize("signal, status", [(None, 130), (15, 143)])
def test_an_interrupted_track_keeps_what_it_estimated(
    kundur_recording, tmp_path, monkeypatch, signal, status
):
    """`estimate track` interrupted while estimating (Ctrl-C; SIGTERM) kept nothing: the
    frames estimated before the interrupt are written as a partial estimate (a CSV row
    each, as a whole track writes them), atomically and never over an existing --out, and
    the interrupted: line says how many (exit status 130, 143)."""
    from stabctl.cli.options import Terminated
    from stabctl.estimation.closed_loop import LoopController

    act = LoopController.act
    calls = []

    def interrupted(self, frame):
        calls.append(frame.t)
        if len(calls) == 31:
            raise KeyboardInterrupt if signal is None else Terminated(signal)
        return act(self, frame)

    monkeypatch.setattr(LoopController, "act", interrupted)
    out = tmp_path / "t.csv"
    args = ["estimate", "track", "kundur", "--source", str(kundur_recording), "--out", str(out)]
    for existing in (False, True):
        calls.clear()
        if existing:
            out.write_text("kept")
        res = CliRunner().invoke(main, args)
        assert res.exit_code == status, res.output
        said = f"interrupted: 30 of the {len(c37.recorded_frames(kundur_recording)[1])} frames"
        assert res.stderr.startswith(said), res.stderr
        if existing:
            beside = tmp_path / "t.partial.csv"
            assert (
                f"; the 30 frames estimated are in {beside}, a partial estimate ({out} is left "
                "as it was); " in res.stderr
            )
            assert out.read_text() == "kept"
            assert len(beside.read_text().splitlines()) == 1 + 30
        else:
            assert f"; the 30 frames estimated are in {out}, a partial estimate; " in res.stderr
            head, *rows = out.read_text().splitlines()
            assert head.startswith("t_s,f_") and len(rows) == 30


@pytest.mark.parametrize(
    "at, said",
    [
        (2, "the 1 frame estimated is in {out}, a partial estimate; "),
        (1, "no frame was estimated yet, so nothing is kept: 0 of the {n} frames from "),
    ],
)
def test_an_interrupted_track_counts_one_frame_or_none(
    kundur_recording, tmp_path, monkeypatch, at, said
):
    """Interrupted after one frame estimated, `estimate track` said "the 1 frames
    estimated are in"; before any, "nothing is kept" without saying no frame was
    estimated."""
    from stabctl.estimation.closed_loop import LoopController

    act = LoopController.act
    calls = []

    def interrupted(self, frame):
        calls.append(frame.t)
        if len(calls) == at:
            raise KeyboardInterrupt
        return act(self, frame)

    monkeypatch.setattr(LoopController, "act", interrupted)
    out = tmp_path / "t.csv"
    args = ["estimate", "track", "kundur", "--source", str(kundur_recording), "--out", str(out)]
    res = CliRunner().invoke(main, args)
    assert res.exit_code == 130, res.output
    n = len(c37.recorded_frames(kundur_recording)[1])
    assert said.format(out=out, n=n) in res.stderr, res.stderr
    assert out.exists() == (at == 2)


def test_a_server_listens_on_ipv6(kundur_recording, tmp_path):
    """`--host ::1` could not be served (the listening socket was IPv4 only, while --allow
    took IPv6 addresses): a replay on ::1, allowed only to ::1, is recorded from
    [::1]:PORT byte for byte."""
    import socket

    try:
        socket.create_server(("::1", 0), family=socket.AF_INET6).close()
    except OSError:
        pytest.skip("this machine has no IPv6 loopback (::1)")
    rec = str(kundur_recording)
    proc, address = serving("replay", rec, "--host", "::1", "--allow", "::1", "--speed", "0")
    assert address.startswith("[::1]:")
    record(address, 73, tmp_path / "b.c37")
    assert finished(proc) == (0, "sent 73 of 73 frames\n")
    assert (tmp_path / "b.c37").read_bytes() == kundur_recording.read_bytes()


@pytest.mark.parametrize("how, said", [("stop", "said 'stop'"), ("close", "closed the connection")])
def test_a_pdc_that_ends_the_stream_early_is_named(kundur_recording, how, said):
    """A PDC's 'stop' after a few frames ended `pmu replay` with exit 0 and "sent 18 of 121
    frames", a partial stream presented as a normal end.  The session is cut, as it is
    when the PDC closes the connection mid-stream: named as the PDC's when it ends, and,
    no other PDC coming for the stream within --wait, the server ends with one error
    naming the PDC and the frames sent (exit status 2)."""
    import socket

    from pyc37.frame import CommandFrame

    proc, address = serving("replay", str(kundur_recording), "--speed", "1", "--wait", "1")
    host, port = address.rsplit(":", 1)
    with socket.create_connection((host, int(port)), timeout=10) as pdc:
        pdc.sendall(CommandFrame(1, "cfg2").convert2bytes())
        pdc.recv(10_000)
        pdc.sendall(CommandFrame(1, "start").convert2bytes())
        pdc.recv(100)  # the first frame(s), sent at once
        me = f"127.0.0.1:{pdc.getsockname()[1]}"
        if how == "stop":
            pdc.sendall(CommandFrame(1, "stop").convert2bytes())
            time.sleep(0.3)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 2 and out == "", (out, err)
    cut, line = err.splitlines()
    assert re.fullmatch(rf"the PDC {me} {re.escape(said)} after \d+ of 73 frames", cut), cut
    assert line == (
        f"error: {address}: no PDC was sent the stream whole ({cut}) and none came for it "
        "within --wait 1 s: the stream was not sent whole"
    )


def test_a_peer_that_leaves_does_not_decide_the_stream_of_another(kundur_recording, tmp_path):
    """A PDC recording the stream while a second peer says 'start' and closes at once:
    the second peer's session ended the server with exit 2 ("the PDC ... closed the
    connection after 8 of 73 frames: the stream was not sent whole") though the first got
    every frame.  Now each session has its own verdict: the cut one is named as its
    peer's, the whole one's count is the server's, exit status 0."""
    import socket
    import threading

    from pyc37.frame import CommandFrame

    proc, address = serving("replay", str(kundur_recording), "--speed", "0.5", "--timeout", "5")
    host, port = address.rsplit(":", 1)
    got = {}
    pdc = threading.Thread(target=lambda: got.update(res=record(address, 73, tmp_path / "a.c37")))
    pdc.start()
    time.sleep(1.0)  # the PDC is streaming (2.4 s of frames at half speed)
    with socket.create_connection((host, int(port)), timeout=5) as stranger:
        stranger.sendall(CommandFrame(1, "cfg2").convert2bytes())
        stranger.sendall(CommandFrame(1, "start").convert2bytes())
        time.sleep(0.3)
        me = f"127.0.0.1:{stranger.getsockname()[1]}"
    pdc.join(60)
    out, err = proc.communicate(timeout=60)
    assert "res" in got and (tmp_path / "a.c37").read_bytes() == kundur_recording.read_bytes()
    assert proc.returncode == 0 and out == "sent 73 of 73 frames\n", (out, err)
    assert any(
        re.fullmatch(rf"the PDC {me} closed the connection after \d+ of 73 frames", x)
        for x in err.splitlines()
    ), err
    assert re.search(r"the PDC 127\.0\.0\.1:\d+ was sent 73 of 73 frames, whole", err), err


def test_a_peer_that_says_start_and_reads_nothing_is_not_the_stream_s_pdc(
    kundur_recording, tmp_path
):
    """Unpaced (--speed 0), a first peer that says 'start' three times, reads nothing and
    closes had every frame "sent" into the socket buffers: the server said "sent 73 of 73
    frames", exit 0, and the PDC connecting next was reset.  The session is whole only once
    the PDC has taken the last frame: this one reset the connection with the frames
    unread, it is named so, and the next PDC gets the stream whole."""
    import socket

    from pyc37.frame import CommandFrame

    proc, address = serving("replay", str(kundur_recording), "--speed", "0", "--timeout", "2")
    host, port = address.rsplit(":", 1)
    with socket.create_connection((host, int(port)), timeout=5) as peer:
        peer.sendall(CommandFrame(1, "start").convert2bytes() * 3)
        time.sleep(0.5)
        me = f"127.0.0.1:{peer.getsockname()[1]}"
    record(address, 73, tmp_path / "a.c37")
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 0 and out == "sent 73 of 73 frames\n", (out, err)
    assert f"the PDC {me} reset the connection with frames unread" in err, err


def test_configurations_the_server_does_not_send_are_named(kundur_recording, tmp_path):
    """A CFG-1 (command 4) or CFG-3 (command 6) request got no answer and its peer was
    later dropped as "silent for 2 s", a wrong reason: the drop names the request and that
    the server sends CFG-2 only."""
    import socket

    from pyc37.frame import CommandFrame

    proc, address = serving("replay", str(kundur_recording), "--speed", "0", "--timeout", "1")
    host, port = address.rsplit(":", 1)
    mes = []
    for word in (4, 6):
        with socket.create_connection((host, int(port)), timeout=5) as peer:
            frame = bytearray(CommandFrame(1, "cfg2").convert2bytes())
            frame[15] = word
            frame[-2:] = c37_crc(bytes(frame[:-2]))
            peer.sendall(bytes(frame))
            mes.append(f"127.0.0.1:{peer.getsockname()[1]}")
            time.sleep(1.5)
    record(address, 73, tmp_path / "a.c37")
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err
    for me, what in zip(mes, ("CFG-1 (command 4)", "CFG-3 (command 6)")):
        assert (
            f"dropped {me}: asked for {what}, which this server does not send (it sends its "
            "stream's CFG-2 only, command 5), then no command for 1 s"
        ) in err.splitlines(), err


def c37_crc(data: bytes) -> bytes:
    """CRC-CCITT of a frame's bytes (C37.118.2-2011 Annex B), as its CHK."""
    crc = 0xFFFF
    for b in data:
        crc ^= b << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) & 0xFFFF if crc & 0x8000 else (crc << 1) & 0xFFFF
    return crc.to_bytes(2, "big")


@pytest.mark.parametrize("kind", ["replay", "serve"])
def test_a_server_drops_a_peer_addressing_another_idcode_and_names_it(
    kundur_recording, tmp_path, kind
):
    """A command frame for IDCODE 999 (CRC valid) was obeyed by `pmu replay` and `pmu
    serve` of stream 1: the peer gets nothing, a line on stderr names it and the IDCODE,
    and the PDC addressing the stream gets it whole."""
    import socket

    from pyc37.frame import CommandFrame

    if kind == "replay":
        args, n = ["replay", str(kundur_recording)], 73
    else:
        args, n = ["serve", "kundur", "--fault", "3", "--far-bus", "101", "--tf", "1.2"], 73
    proc, address = serving(*args, "--speed", "0", "--timeout", "2")
    host, port = address.rsplit(":", 1)
    with socket.create_connection((host, int(port)), timeout=5) as peer:
        peer.sendall(CommandFrame(999, "cfg2").convert2bytes())
        me = f"127.0.0.1:{peer.getsockname()[1]}"
        peer.settimeout(1.5)
        try:
            got = peer.recv(100)
        except (TimeoutError, ConnectionError):
            got = b""
    assert got == b"", "answered a command addressed to another IDCODE"
    record(address, n, tmp_path / "b.c37")
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 0 and out == f"sent {n} of {n} frames\n", (out, err)
    assert f"dropped {me}: a command for IDCODE 999, not this stream's 1" in err.splitlines()


def test_record_names_the_gaps_of_the_stream_it_records(kundur_recording, tmp_path):
    """`pmu record` of a stream with reporting instants missing said only "recorded N
    frames", exit 0: the gaps are counted and named on its line (the recording is what
    was sent: exit status 0)."""
    from stabctl.estimation.c37_tcp import StreamServer

    cfg2, data = c37.recorded_frames(kundur_recording)
    gappy = data[:20] + data[30:]
    out = tmp_path / "g.c37"
    with StreamServer(cfg2, gappy, speed=float("inf")) as server:
        address = f"127.0.0.1:{server.address[1]}"
        res = CliRunner().invoke(main, ["pmu", "record", address, "--frames", "63", "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert res.stdout == (
        f"recorded 63 frames from {address} to {out}; 10 reporting instants missing in 1 "
        "gap(s): 10 after t = 0.3167 s, to 0.5000 s\n"
    )


def _restamped(frame: bytes, *, fracsec: int | None = None, quality: int | None = None) -> bytes:
    """A data frame with another FRACSEC count or time quality byte, its CRC made again."""
    body = bytearray(frame[:-2])
    if fracsec is not None:
        body[11:14] = fracsec.to_bytes(3, "big")
    if quality is not None:
        body[10] = quality
    return bytes(body) + c37_crc(bytes(body))


@pytest.mark.parametrize(
    "how,said",
    [
        ("repeated", "data frame 21 repeats the time stamp of frame 20 ("),
        ("backward", "data frame 21 goes back from the time stamp of frame 20 ("),
        ("off grid", "data frame 21 is stamped 0.353333 s into its second, not a reporting"),
    ],
)
def test_record_refuses_time_stamps_replay_and_track_refuse(kundur_recording, tmp_path, how, said):
    """`pmu record` of a stream with a frame sent twice, a frame stamped before the one
    before it, or one stamped off the 60 frames/s grid wrote all of it, exit 0 (a
    repeated frame was even named a 9-instant gap), a recording `pmu replay` and
    `estimate track` then refuse: refused as they refuse it, naming the frame and its
    time stamp (exit 2), the frames before it written as a partial recording, as for a
    frame refused by its CRC; an existing OUT is left as it was, the frames written beside
    it.  The frame is refused
    as it comes: the stream, served in real time, is cut there, not received to its end
    (all 73 frames) before the time stamps were looked at."""
    from stabctl.estimation.c37_tcp import StreamServer

    cfg2, data = c37.recorded_frames(kundur_recording)
    bad = {
        "repeated": data[19],
        "backward": data[18],
        "off grid": _restamped(data[20], fracsec=int.from_bytes(data[20][11:14], "big") + 20_000),
    }[how]
    sent = data[:20] + [bad] + data[21:]
    out = tmp_path / "o.c37"
    for existing in (False, True):
        if existing:
            out.write_bytes(b"kept")
        with StreamServer(cfg2, sent, speed=1.0) as server:
            address = f"127.0.0.1:{server.address[1]}"
            res = CliRunner().invoke(
                main, ["pmu", "record", address, "--frames", "73", "-o", str(out)]
            )
        assert server.n_sent < 40, server.n_sent  # cut at frame 21, not read to frame 73
        assert res.exit_code == 2 and res.stdout == "", res.output
        assert res.stderr.startswith(
            f"error: {address}: the server sent a data frame that is refused ({said}"
        ), res.stderr
        assert (
            "; the stream is cut there: 20 data frames before it, the last stamped 0.3167 s, "
            "before 73 frames; " in res.stderr
        )
        if existing:
            beside = tmp_path / "o.partial.c37"
            assert res.stderr.endswith(
                f"; the 20 received are in {beside} ({out} is left as it was)\n"
            )
            assert out.read_bytes() == b"kept"
            assert c37.recorded_frames(beside)[1] == data[:20]
        else:
            assert res.stderr.endswith(f"; the 20 received are in {out}\n")
            assert c37.recorded_frames(out)[1] == data[:20]
            out.unlink()


@pytest.mark.parametrize(
    "how,said",
    [
        ("backward", "data frame 21 goes back from the time stamp of frame 20 ("),
        ("a second", "data frame 21: a data frame stamped with FRACSEC count 1000000, not "),
    ],
)
def test_track_refuses_a_source_whose_frame_is_refused(kundur_recording, tmp_path, how, said):
    """A stream over TCP with a frame refused (a time stamp going back, a FRACSEC count of a
    whole second) is cut there; `pmu record` keeps the frames before it (above), and
    `estimate track` refuses the source: exit status 2 naming the frame, nothing written
    and an existing --out left as it was (a stream whose bytes or clock went wrong is no
    ground for the speeds, the frames before included), not a partial track."""
    from stabctl.estimation.c37_tcp import StreamServer

    cfg2, data = c37.recorded_frames(kundur_recording)
    soc = int.from_bytes(data[19][6:10], "big")
    bad = {
        "backward": data[18],
        "a second": _restamped(
            data[20][:6] + soc.to_bytes(4, "big") + data[20][10:], fracsec=10**6
        ),
    }[how]
    out = tmp_path / "t.csv"
    for existing in (False, True):
        if existing:
            out.write_text("kept")
        with StreamServer(cfg2, data[:20] + [bad] + data[21:], speed=float("inf")) as server:
            src = f"tcp://127.0.0.1:{server.address[1]}"
            res = CliRunner().invoke(
                main,
                [
                    "estimate",
                    "track",
                    "kundur",
                    "--source",
                    src,
                    "--frames",
                    "73",
                    "--out",
                    str(out),
                ],
            )
        assert res.exit_code == 2 and res.stdout == "", res.output
        assert res.stderr.startswith(f"error: --source {src}: data frame"), res.stderr
        assert said in res.stderr and "Traceback" not in res.output
        assert out.read_text() == "kept" if existing else not out.exists()


def test_record_names_frames_of_a_failed_clock(kundur_recording, tmp_path):
    """Data frames whose FRACSEC time quality is 0xF (clock failure) were recorded without
    a word: named on the line as `estimate track` names them (the recording is what was
    sent: exit status 0)."""
    from stabctl.estimation.c37_tcp import StreamServer

    cfg2, data = c37.recorded_frames(kundur_recording)
    sent = [_restamped(d, quality=0x0F) if 10 <= k < 20 else d for k, d in enumerate(data)]
    out = tmp_path / "q.c37"
    with StreamServer(cfg2, sent, speed=float("inf")) as server:
        address = f"127.0.0.1:{server.address[1]}"
        res = CliRunner().invoke(main, ["pmu", "record", address, "--frames", "73", "-o", str(out)])
    assert res.exit_code == 0, res.output
    assert res.stdout == (
        f"recorded 73 frames from {address} to {out}; 40 PMU values not used by their STAT "
        "or time quality (40 clock failure (FRACSEC time quality 0xF))\n"
    )
    assert c37.recorded_frames(out)[1] == sent


def test_control_names_the_gaps_in_the_plant_s_stream(kundur_recording):
    """`pmu control` against a plant that sent no frame for 30 reporting instants (frames
    40-69) said only "answered N frames", and its estimator was fed the frame after the
    gap as the next one: the gap is counted and named on its line as `estimate track` and
    `pmu record` name gaps (exit status 0: every frame sent was answered), and taken as
    track takes one: at most 1 s, the estimator is fed frames of missing values for it;
    longer, it starts again."""
    from pmu_streams import fake_server

    from stabctl.estimation.c37_loop import end_of_run_frame
    from stabctl.estimation.c37_tcp import _read_frame

    head, data = c37.recorded_frames(kundur_recording)
    sent = data[:40] + data[70:]

    def plant(conn, sent=sent):
        _read_frame(conn)  # 'cfg2'
        conn.sendall(head.convert2bytes())
        _read_frame(conn)  # 'start'
        for frame in sent:
            conn.sendall(frame)
            _read_frame(conn)  # the modes
        conn.sendall(end_of_run_frame(1, 72 / 60))
        conn.recv(1)  # until the controller closes

    srv, port = fake_server(plant)
    with srv:
        res = CliRunner().invoke(
            main, ["pmu", "control", "kundur", f"127.0.0.1:{port}", "--esd-pct", "5"]
        )
    assert res.exit_code == 0, res.output
    assert res.stdout.startswith(f"controller (ekf): answered 43 frames from 127.0.0.1:{port}, ")
    assert res.stdout.endswith(
        "; 30 reporting instants missing (no frame sent) in 1 gap(s): 30 after t = 0.6500 "
        "s, to 1.1667 s (filled with missing values)\n"
    ), res.stdout

    class Fed:
        """A controller that notes what it is fed."""

        def __init__(self):
            self.fed: list = []

        def act(self, frame):
            self.fed.append((round(frame.t * 60), bool(frame.valid.any())))
            return np.zeros(4, np.int8)

        def restart(self):
            self.fed.append("restart")

    from stabctl.estimation.c37_loop import serve_controller

    case = stabctl.load_case("kundur")
    cfg = c37.stream_config(case, pm.machine_pmus(case), 60)
    after = [(k, True) for k in (70, 71, 72)]
    for sent, fed in (
        (data[:40] + data[70:], [(k, not 40 <= k < 70) for k in range(73)]),
        (data[:2] + data[70:], [(0, True), (1, True), "restart", *after]),
    ):
        srv, port = fake_server(lambda conn, sent=sent: plant(conn, sent))
        ctrl = Fed()
        with srv:
            got = serve_controller(ctrl, cfg, "127.0.0.1", port, 10)
        assert got.frames == len(sent) and ctrl.fed == fed
        assert [g.filled for g in got.gaps] == [len(sent) == 43]


def test_control_says_when_the_plant_applied_the_modes_at_another_latency():
    """`pmu plant --latency-ms 200` with `pmu control` forecasting over its default 50 ms
    ran the loop without a word (round 58 AZ09): the plant's end-of-run header now says
    the latency at which it applied the modes, and the controller warns of a mismatch."""
    fault = ["kundur", "--fault", "3", "--far-bus", "101", "--clear-cycles", "7"]
    proc, address = serving(
        "plant", *fault, "--tf", "1.5", "--esd-pct", "10", "--speed", "0", "--latency-ms", "200"
    )
    res = CliRunner().invoke(main, ["pmu", "control", "kundur", address, "--esd-pct", "10"])
    assert res.exit_code == 0, res.output
    assert finished(proc)[0] == 0
    assert (
        "warning: the plant applied the ESD modes 200 ms after each frame's time stamp (its "
        "--latency-ms), and this controller forecast the relative speeds over 50 ms"
    ) in res.output
