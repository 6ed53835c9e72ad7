#!/usr/bin/env python
"""Thirtieth reliability round (round 45, part Z): the Python API (stabctl.__all__ and the objects they return) and CLI
options given hostile or unusual values: wrong types, numpy scalars, NaN/inf/huge, unknown
numbers, damaged result files, round trips of SimulationResult / CCTResult, repeated and
conflicting options, odd spellings of numbers, environment variables.

    python benchmarks/reliability_probes_30.py [ID_PREFIX ...]

CLONE (default: this repository) is the package under test; NUMBA_CACHE_DIR the caller's
(warm it first with `python -m stabctl compile`).  Prints per probe: id, ok/SHORT, reason;
exits 1 if any is SHORT.  Every command has a timeout; work in a temporary directory
(removed at the end unless KEEP=1).  About 3 minutes with a warm kernel cache.

The contract throughout (stabctl/errors.py's own docstring: "Every error names what is
wrong and where ... so that the CLI can print it and exit non-zero without a traceback";
issue 54: "a crash ... never a bare numpy/scipy/numba exception"): a hostile value is
refused with a stabctl.errors.* exception naming the argument, or accepted with a result
that is right; never a foreign exception from deep inside, a hang or a wrong result.

The round found 24 of 31 short, most of them messages of Python's or numpy's words or classes; fixed: linearise's rel_step below 1e-9, from_npz's damaged arrays, the stabctl error classes of run(storage), run(events), OMIB, coi_speed, a mode index, a long case name, a result written over a directory, `--tf` beyond a float, `--trip TO:`; still short: speed_at/end_state arguments, storage ratings far beyond the grid, Case.replace of an unknown field, circuit_row of a text bus.
"""

# ruff: noqa: E501, RUF001, RUF059 - a tester's script, kept as written

import json
import os
import subprocess
import sys
import textwrap

from _probe_kit import INHERIT, Kit

KIT = Kit("probes_z45_", path=False)
CLONE, ENV, WD, RESULTS, PROBES = KIT.clone, KIT.env, KIT.wd, KIT.results, KIT.probes
rec, probe = KIT.rec, KIT.probe

PRELUDE = textwrap.dedent(
    """
    import json, math, os, sys, traceback, warnings, fractions
    import numpy as np
    import stabctl
    from stabctl import *
    import stabctl.errors as E
    def outcome(f):
        try:
            r = f()
            return {"kind": "accepted", "value": repr(r)[:300]}
        except E.StabctlError as e:
            return {"kind": "stabctl", "type": type(e).__name__, "msg": str(e)[:400]}
        except Exception as e:
            tb = traceback.extract_tb(e.__traceback__)[-1]
            return {"kind": "foreign", "type": type(e).__name__, "msg": str(e)[:300],
                    "where": tb.filename.split("site-packages/")[-1] + ":" + str(tb.lineno)}
    def say(x):
        print("@@" + json.dumps(x, default=str))
    """
)


def py(code, timeout=240):
    """Run a snippet (after PRELUDE) in a fresh interpreter; the dict it says last."""
    try:
        p = subprocess.run(
            [sys.executable, "-c", PRELUDE + textwrap.dedent(code)],
            capture_output=True,
            text=True,
            timeout=timeout,
            cwd=WD,
            env=ENV,
        )
    except subprocess.TimeoutExpired:
        return {"kind": "timeout"}
    lines = [ln for ln in p.stdout.splitlines() if ln.startswith("@@")]
    if not lines:
        return {"kind": "crashed", "rc": p.returncode, "err": p.stderr.strip()[-300:]}
    return json.loads(lines[-1][2:])


def cli(args, timeout=120, env=None):
    """(rc, stdout, stderr); the caller's stdin, nothing kept of a run out of time."""
    return KIT.cli(args, timeout, env=env, stdin=INHERIT, partial=False)


def refused(o, types=None):
    """ok when a stabctl error (of one of `types`, if given) refused the value."""
    if o["kind"] != "stabctl":
        return (
            False,
            f"{o['kind']}: {o.get('type', '')} {o.get('msg', o.get('value', o.get('err', '')))} {o.get('where', '')}".strip(),
        )
    if types and o["type"] not in types:
        return False, f"stabctl {o['type']} (wanted {'/'.join(types)}): {o['msg'][:200]}"
    return True, f"{o['type']}: {o['msg'][:160]}"


# ------------------------------------------------------------------ linearise's step
@probe("Z01")
def _():
    """linearise(case, rel_step=1e-16): rel_step is documented "in (0, 0.1)" and 1e-16 is
    inside it; a step below the floats' resolution must be refused by name (or give a
    model), not end in numba's ZeroDivisionError ('complex division by zero') from
    stabctl/smallsignal/linearise.py jacobian_columns."""
    return refused(
        py("say(outcome(lambda: linearise(load_case('kundur'), rel_step=1e-16).A.shape))")
    )


@probe("Z02")
def _():
    """linearise(case, rel_step=1e-12): a step too small for the floats gives a refusal
    naming rel_step (the argument the user chose), not 'meets a kink at the operating
    point' / 'a limiter saturated' (there is none: the default step linearises fine)."""
    o = py("say(outcome(lambda: linearise(load_case('kundur'), rel_step=1e-12).A.shape))")
    if o["kind"] == "accepted":
        return True, "accepted (a model)"
    if o["kind"] == "stabctl" and "rel_step" in o["msg"]:
        return True, o["msg"][:150]
    return False, f"{o['kind']} {o.get('type')}: {o.get('msg', '')[:220]} (no word of rel_step)"


@probe("Z03")
def _():
    """linearise(case, rel_step='1e-4'): text where a number is needed -> WrongTypeError
    naming rel_step (as run(h='...') and Simulator(step='...') do), not Python's
    "'<' not supported between instances of 'int' and 'str'"."""
    return refused(py("say(outcome(lambda: linearise(load_case('kundur'), rel_step='1e-4')))"))


# ------------------------------------------------------------------ result files
DAMAGE = """
k = load_case('kundur'); sim = Simulator(k)
r = sim.run([Fault(3, 1.0, clear_near=1.1, far_bus=101)], t_end=2.0)
p = r.to_npz('ok.npz'); z = dict(np.load(p))
{change}
np.savez('bad.npz', **z)
say(outcome(lambda: SimulationResult.from_npz('bad.npz').summary()['verdict']))
"""


def damaged(change):
    return py(DAMAGE.format(change=change))


@probe("Z04")
def _():
    """from_npz of a result file whose `verdict` array holds one value (a damaged file):
    from_npz's docstring promises an InputError naming the file for a file not written
    by to_npz; got Python's 'not enough values to unpack' from results.py from_npz."""
    return refused(damaged("z['verdict'] = np.array([1.0])"), ["InputError"])


@probe("Z05")
def _():
    """from_npz of a file whose `t` is a 0-d text array: InputError naming the file and
    the array, not numpy's IndexError ('array is 0-dimensional') from de_energised_s."""
    return refused(damaged("z['t'] = np.array('abc')"), ["InputError"])


@probe("Z06")
def _():
    """from_npz of a file whose `speed` has 3 columns for 4 machines: not a result
    to_npz writes; read as a whole result with a verdict ('stable') it presents damaged
    data as a run's.  Expected: InputError naming the array and its shape."""
    return refused(damaged("z['speed'] = z['speed'][:, :3]"), ["InputError"])


@probe("Z07")
def _():
    """from_npz of a file whose verdict is NaN (stable unknown): bool(nan) is True, so the
    run reads back 'stable'.  Expected: refused (to_npz writes 0 or 1), never a verdict
    the file does not hold."""
    o = damaged("z['verdict'] = np.array([np.nan, np.nan])")
    if o["kind"] == "accepted" and "stable" in o["value"] and "loss" not in o["value"]:
        return False, f"verdict NaN read back as {o['value']}"
    return refused(o)


@probe("Z08")
def _():
    """from_npz of a file whose times run backwards: t_end_s 0 and n_steps 0 were
    reported as a whole run; a result's `t` is documented non-decreasing."""
    return refused(damaged("z['t'] = z['t'][::-1].copy()"), ["InputError"])


@probe("Z09")
def _():
    """to_npz/from_npz/to_csv round trips of runs with a fault, loss of synchronism
    (stopped and not), a generator trip, an island, every machine tripped, storage and a
    monitor: verdict, summary figures, arrays, partitions and the CSV's columns as written
    (to_npz's docstring: every array and the verdict)."""
    o = py("""
    import csv
    k = load_case('kundur'); sim = Simulator(k)
    ev = [Fault(3, 1.0, clear_near=1.1, far_bus=101)]
    runs = {
      'fault': sim.run(ev, t_end=2.5),
      'unstable': sim.run([Fault(3, 1.0, clear_near=1.4, far_bus=101)], t_end=3.0),
      'stop': sim.run([Fault(3, 1.0, clear_near=1.4, far_bus=101)], t_end=3.0, stop_at_separation=True),
      'gentrip': sim.run([GeneratorTrip(2, 1.0)], t_end=2.5),
      'island': sim.run([LineTrip(3,101,1.0,1), LineTrip(3,101,1.0,2), LineTrip(13,101,1.0,1), LineTrip(13,101,1.0,2)], t_end=2.5),
      'alltrip': sim.run([GeneratorTrip(m, 1.0) for m in (1, 2, 3, 4)], t_end=2.0),
      'storage': sim.run(ev, t_end=2.5, storage=uniform_fleet(k, 5)),
      'monitor': sim.run(ev, t_end=2.5, monitor=lambda r: 'enough' if r.t[-1] > 1.5 else None),
    }
    bad = []
    keys = ['stable','verdict','de_energised_s','t_separation_s','separated_machines','max_angle_from_coi_rad','t_end_s','n_steps']
    for n, r in runs.items():
        q = SimulationResult.from_npz(r.to_npz(n + '.npz'))
        a, b = r.summary(), q.summary()
        bad += [f'{n}.{x}: {a[x]} vs {b[x]}' for x in keys if a[x] != b[x]]
        for x in ['t','speed','angle','pelect','pmech','efd','vmag','vang','inertia','island','pesd','qelect']:
            u, v = getattr(r, x), getattr(q, x)
            if (u is None) != (v is None) or (u is not None and not np.array_equal(u, v)):
                bad.append(f'{n}.{x} differs')
        if len(r.partitions) != len(q.partitions): bad.append(f'{n}.partitions')
        names, data = r.columns()
        rows = list(csv.reader(open(r.to_csv(n + '.csv'))))
        back = np.array(rows[1:], float)
        if rows[0] != names or back.shape != data.shape or not np.allclose(back, data, rtol=1e-9, atol=1e-12):
            bad.append(f'{n}.csv')
    say({'kind': 'accepted', 'value': bad, 'verdicts': {n: r.verdict for n, r in runs.items()}})
    """)
    if o["kind"] != "accepted":
        return False, str(o)[:300]
    return (not o["value"]), (
        f"all preserved; verdicts {o['verdicts']}"
        if not o["value"]
        else "; ".join(o["value"])[:300]
    )


@probe("Z10")
def _():
    """summary() and CCTResult.to_dict() are JSON (strict: no NaN/inf) for runs with
    trips, islands, storage and for line, bus and storage CCT searches (the CLI's --json
    prints them)."""
    o = py("""
    k = load_case('kundur'); sim = Simulator(k)
    ev = [Fault(3, 1.0, clear_near=1.1, far_bus=101)]
    out = [sim.run(ev, t_end=2.0, storage=uniform_fleet(k, 5)).summary(),
           sim.run([GeneratorTrip(m, 1.0) for m in (1, 2, 3, 4)], t_end=2.0).summary(),
           sim.run([LineTrip(3,101,1.0,1), LineTrip(3,101,1.0,2), LineTrip(13,101,1.0,1), LineTrip(13,101,1.0,2)], t_end=2.0).summary(),
           critical_clearing_time(sim, LineFault(3, 101)).to_dict(),
           critical_clearing_time(sim, LineFault(3, None)).to_dict(),
           critical_clearing_time(sim, LineFault(3, 101), storage=uniform_fleet(k, 5)).to_dict()]
    json.dumps(out, allow_nan=False)
    say({'kind': 'accepted', 'value': [d.get('cct_s') for d in out[3:]]})
    """)
    return o["kind"] == "accepted", str(o)[:200]


# ------------------------------------------------------------------ error types
@probe("Z11")
def _():
    """run(storage='x') and critical_clearing_time(..., storage='x'): a WrongTypeError
    (stabctl.errors, as run(events='x') and run(monitor=5) give), not a bare TypeError
    that `except stabctl.errors.StabctlError` misses (driver.py:677)."""
    return refused(
        py(
            "k = load_case('kundur'); say(outcome(lambda: Simulator(k).run(t_end=0.5, storage='x')))"
        ),
        ["WrongTypeError"],
    )


@probe("Z12")
def _():
    """run(events=np.ones((2, 2))): each row is no event -> WrongTypeError (run(events='x')
    gives one), not a bare TypeError from dynamics/events.py."""
    return refused(
        py(
            "k = load_case('kundur'); say(outcome(lambda: Simulator(k).run(np.ones((2, 2)), t_end=0.5)))"
        ),
        ["WrongTypeError"],
    )


@probe("Z13")
def _():
    """OMIB(H=Fraction(1, 3), ...): a number Python's numbers.Real accepts; either used or
    refused naming H, not numpy's "ufunc 'isfinite' not supported" (smib/omib.py:77)."""
    o = py(
        "say(outcome(lambda: OMIB(fractions.Fraction(1, 3), 0.8, 2.0, 0.5, 1.5).critical_clearing_time()))"
    )
    return (True, f"accepted {o['value']}") if o["kind"] == "accepted" else refused(o)


@probe("Z14")
def _():
    """OMIB(H='5', ...): refused with stabctl's WrongTypeError (a plain TypeError now:
    the message is right, the class is not stabctl's)."""
    return refused(py("say(outcome(lambda: OMIB('5', 0.8, 2.0, 0.5, 1.5)))"), ["WrongTypeError"])


@probe("Z15")
def _():
    """coi_speed(speed, '5'): a text weight named as such (WrongTypeError), not a
    ValueError about 'inertia of shape ()'."""
    return refused(py("say(outcome(lambda: coi_speed(np.ones((3, 2)), '5')))"))


@probe("Z16")
def _():
    """ModalAnalysis.groups(999) / groups(-1) / area_sides(999): the object modal_analysis
    returns takes mode indices as its table prints them (0..m-1); another is refused
    naming the mode and the range, not numpy's IndexError, nor -1 silently the last."""
    o = py("""
    ma = modal_analysis(linearise(load_case('kundur')))
    res = [outcome(lambda: ma.groups(999)), outcome(lambda: ma.groups(-1)), outcome(lambda: ma.area_sides(999)), outcome(lambda: ma.groups('1'))]
    say({'kind': 'accepted', 'value': res})
    """)
    if o["kind"] != "accepted":
        return False, str(o)[:200]
    bad = [
        f"{x['kind']} {x.get('type', '')} {x.get('msg', x.get('value', ''))[:60]}"
        for x in o["value"]
        if x["kind"] != "stabctl"
    ]
    return (not bad), ("; ".join(bad) if bad else "refused by name")


@probe("Z17")
def _():
    """SimulationResult.speed_at('1') / speed_at(None) / speed_at(nan): a time in s is
    needed; got numpy's casting TypeError, and NaN speeds for a NaN time."""
    o = py("""
    r = Simulator(load_case('kundur')).run(t_end=0.5)
    say({'kind': 'accepted', 'value': [outcome(lambda: r.speed_at('1')), outcome(lambda: r.speed_at(None)), outcome(lambda: r.speed_at(float('nan')))]})
    """)
    bad = [
        f"{x['kind']} {x.get('type', '')} {x.get('msg', x.get('value', ''))[:70]}"
        for x in o.get("value", [])
        if x["kind"] != "stabctl"
    ]
    return (not bad and o["kind"] == "accepted"), ("; ".join(bad) if bad else "refused by name")


@probe("Z18")
def _():
    """SimulationResult.end_state(freq_hz) with nan, 0, -60 and '60': the nominal
    frequency (a case's: 1-1000 Hz, Case refuses others) -- got frequency_hz nan, 0.0,
    -60.25, and Python's "can't multiply sequence" for text."""
    o = py("""
    r = Simulator(load_case('kundur')).run(t_end=0.5)
    say({'kind': 'accepted', 'value': [outcome(lambda: r.end_state(v)) for v in (float('nan'), 0.0, -60.0, '60')]})
    """)
    bad = [
        f"{x['kind']} {x.get('type', '')} {x.get('msg', x.get('value', ''))[:60]}"
        for x in o.get("value", [])
        if x["kind"] != "stabctl"
    ]
    return (not bad), ("; ".join(bad)[:300] if bad else "refused by name")


@probe("Z19")
def _():
    """A StorageDevice of 1e308 MW (and 3000 MW at a 900 MVA machine's bus) runs 'stable'
    with 4 switchings and 0 MJ moved: the CLI bounds the rating (--esd-pct in (0, 100] %
    of machine MVA, numbers at most 1e9) and uniform_fleet(pct) too; the API's device
    takes any finite rating without a word."""
    o = py("""
    k = load_case('kundur')
    say(outcome(lambda: Simulator(k).run([Fault(3, 1.0, clear_near=1.1, far_bus=101)], t_end=2.0, storage=StorageFleet(devices=(StorageDevice(10, 1, 1e308),))).summary()['storage']))
    """)
    return refused(o)


@probe("Z20")
def _():
    """Case.replace(foo=1): an unknown field named by stabctl (CaseError/InputError),
    not dataclasses' "Case.__init__() got an unexpected keyword argument"."""
    return refused(py("say(outcome(lambda: load_case('kundur').replace(foo=1)))"))


@probe("Z21")
def _():
    """Case.circuit_row('3', 101): said 'no branch between bus 3 and bus 101' where two
    circuits exist -- a message naming the wrong thing; expected a WrongTypeError for
    the text bus (or the row: bus_index('3') and machine_name('1') accept text)."""
    o = py("say(outcome(lambda: load_case('kundur').circuit_row('3', 101)))")
    if o["kind"] == "accepted":
        return True, f"accepted {o['value']}"
    if o["kind"] == "stabctl" and "no branch" in o["msg"]:
        return False, o["msg"][:150]
    return refused(o)


@probe("Z22")
def _():
    """load_case('x' * 5000): an unknown case (CaseError), not OSError 'File name too
    long' naming the package's own data directory."""
    return refused(py("say(outcome(lambda: load_case('x' * 5000)))"), ["CaseError"])


@probe("Z23")
def _():
    """to_npz / to_csv to an existing directory: a refusal naming the path (stabctl's
    InputError, or an OSError without the '-> None' of parallel.py's atomic_write)."""
    o = py(
        "r = Simulator(load_case('kundur')).run(t_end=0.5); os.makedirs('d', exist_ok=True); say(outcome(lambda: r.to_npz('d')))"
    )
    if o["kind"] == "stabctl" or (o["kind"] == "foreign" and "None" not in o["msg"]):
        return True, o["msg"][:150]
    return False, f"{o['kind']} {o.get('type')}: {o.get('msg')}"


# ------------------------------------------------------------------ refusals that hold
@probe("Z24")
def _():
    """Events with NaN/inf/negative times and impedances, unknown buses and machines,
    NaN/inf load steps, hostile run() and Simulator() arguments: each refused with a
    stabctl error (the contract of errors.py)."""
    o = py("""
    k = load_case('kundur'); sim = Simulator(k); nan, inf = float('nan'), math.inf
    cases = [
      lambda: sim.run([Fault(3, nan, clear_near=1.1)], t_end=1.2), lambda: sim.run([Fault(3, 1.0, clear_near=1.1, r=nan)], t_end=1.2),
      lambda: sim.run([Fault(3, 1.0, clear_near=1.1, x=-0.1)], t_end=1.2), lambda: sim.run([LineTrip(3, 101, -1.0)], t_end=1.2),
      lambda: sim.run([GeneratorTrip(99, 0.5)], t_end=1.2), lambda: sim.run([LoadStep(4, 0.5, inf)], t_end=1.2),
      lambda: sim.run([LoadStep(999, 0.5, 0.1)], t_end=1.2), lambda: sim.run([Fault(10**40, 1.0, clear_near=1.1)], t_end=1.2),
      lambda: sim.run(t_end=nan), lambda: sim.run(t_end='1'), lambda: sim.run(t_end=True), lambda: sim.run(t_end=1e308),
      lambda: sim.run(t_end=0.5, h=1e-300), lambda: sim.run(t_end=0.5, h=True), lambda: sim.run(t_end=0.5, separation_limit=inf),
      lambda: sim.run(t_end=0.5, voltages=[999]), lambda: sim.run(t_end=0.5, voltages=[1.5]), lambda: sim.run(t_end=0.5, stop_at_separation='no'),
      lambda: Simulator(k, step='0.005'), lambda: Simulator(k, injection_buses=[999]), lambda: Simulator(k, op=5),
      lambda: uniform_fleet(k, nan), lambda: uniform_fleet(k, 5, controller=5),
      lambda: sim.run(t_end=0.5, storage=StorageFleet(devices=(StorageDevice(10, 1, 10.0, soc0=2.0, energy_mj=10.0),))),
      lambda: critical_clearing_time(sim, LineFault(3, 101, t_fault=nan)),
      lambda: modal_analysis(linearise(k), inertia=np.array([1, 1, nan, 1.0])),
      lambda: linearise(k, esd_buses=[3.5]),
    ]
    res = [outcome(f) for f in cases]
    say({'kind': 'accepted', 'value': [(i, r['kind'], r.get('type'), r.get('msg', r.get('value', ''))[:80]) for i, r in enumerate(res) if r['kind'] != 'stabctl']})
    """)
    return (o["kind"] == "accepted" and not o["value"]), (
        str(o.get("value", o))[:300]
        if o.get("value") or o["kind"] != "accepted"
        else "27 refused by stabctl errors"
    )


@probe("Z25")
def _():
    """A case's arrays made writeable again after a Simulator was built and H cut to 0.3x:
    the Simulator keeps its own copy (its runs unchanged), a new Simulator sees the
    change -- no run mixing the two."""
    o = py("""
    k = load_case('kundur'); sim = Simulator(k); ev = [Fault(3, 1.0, clear_near=1.1, far_bus=101)]
    a = sim.run(ev, t_end=2.0).max_angle_from_coi
    H = k.machines.H; H.flags.writeable = True; H[:] = H * 0.3
    b = sim.run(ev, t_end=2.0).max_angle_from_coi
    say({'kind': 'accepted', 'value': [a, b]})
    """)
    return (o["kind"] == "accepted" and o["value"][0] == o["value"][1]), str(o.get("value", o))[
        :200
    ]


# ------------------------------------------------------------------ CLI
@probe("Z26")
def _():
    """simulate --tf with 0, -1, nan, inf, 1e308, 1_000, 0x10, -0, 1e-400, a full-width
    digit, an Arabic-Indic digit: each refused (exit 2, one error line, no output)."""
    bad = []
    for v in ["0", "-1", "nan", "inf", "1e308", "1_000", "0x10", "-0", "1e-400", "５", "١", "0b1"]:
        rc, out, err = cli(["simulate", "kundur", "--tf", v, "--json"], 60)
        if rc != 2 or out.strip() or "Traceback" in err:
            bad.append(f"{v!r}: rc {rc}")
    return not bad, "; ".join(bad) or "12 spellings refused"


@probe("Z27")
def _():
    """simulate --tf 999...9 (5000 digits): the refusal names the value given (or says
    it is too large), not '--tf inf' which the user never typed."""
    rc, out, err = cli(["simulate", "kundur", "--tf", "9" * 5000], 60)
    if rc == 2 and "inf" not in err.split("must")[0]:
        return True, err.strip()[:120]
    return False, f"rc {rc}: {err.strip()[:120]}"


@probe("Z28")
def _():
    """simulate --trip 3 101: (nothing after the colon): help says FROM TO[:K]; a
    truncated K is refused (as 101:0 and 101:2:3 are), not read as circuit 1."""
    rc, out, err = cli(["simulate", "kundur", "--trip", "3", "101:", "--tf", "1.5"], 60)
    return (
        rc == 2,
        f"rc {rc}: {(err.strip() or out.strip().splitlines()[1] if out.strip() else '')[:120]}",
    )


@probe("Z29")
def _():
    """A case name of 5000 characters: 'unknown case' (a one-line error), not 'File name
    too long' with the package's data directory and 5 KB of x."""
    rc, out, err = cli(["simulate", "x" * 5000], 60)
    ok = rc == 2 and "File name too long" not in err and "case/data" not in err
    return ok, f"rc {rc}: {err.strip()[:60]}...{err.strip()[-40:]} ({len(err)} chars)"


@probe("Z30")
def _():
    """Repeated single-value options, options after `--`, conflicting options: each
    refused with exit 2 and no output."""
    cmds = [
        ["simulate", "kundur", "--tf", "1", "--tf", "2"],
        ["simulate", "kundur", "--esd-pct", "5", "--esd-pct", "0", "--tf", "1"],
        ["simulate", "kundur", "--tf", "1", "--", "--json"],
        ["simulate", "kundur", "--deadband-hz", "0.5", "--tf", "1"],
        ["simulate", "kundur", "--conventions", "pstess", "--single-rate", "--tf", "1"],
        ["simulate", "kundur", "--method", "trapezoid", "--esd-pct", "5", "--tf", "1"],
        [
            "simulate",
            "kundur",
            "--fault",
            "3",
            "--clear-cycles",
            "10",
            "--far-clear-cycles",
            "5",
            "--far-bus",
            "101",
        ],
        [
            "simulate",
            "kundur",
            "--trip",
            "3",
            "101",
            "--t-trip",
            "1",
            "--t-trip",
            "2",
            "--tf",
            "2.5",
        ],
        ["cct", "kundur", "--fault", "3", "--far-bus", "101", "--tol-ms", "1e308"],
        ["simulate", "kundur", "--fault", "99999999999999999999999999"],
    ]
    bad = []
    for c in cmds:
        rc, out, err = cli(c, 60)
        if rc != 2 or out.strip() or "Traceback" in err:
            bad.append(f"{' '.join(c[2:])[:40]}: rc {rc}")
    return not bad, "; ".join(bad) or f"{len(cmds)} refused"


@probe("Z31")
def _():
    """COLUMNS=5/0/-1/abc, LANG=C, LC_ALL=C, PYTHONIOENCODING=ascii, TZ=Nowhere/Bogus,
    TERM=dumb, XDG_CACHE_HOME=/dev/null, a file, '' or a missing path: the same verdict
    line as without, exit 0."""
    base = cli(["simulate", "kundur", "--fault", "3", "--far-bus", "101", "--tf", "1.5"], 60)
    want = base[1].splitlines()[2] if base[0] == 0 else None
    open(os.path.join(WD, "afile"), "w").close()
    bad = []
    for e in [
        "COLUMNS=5",
        "COLUMNS=0",
        "COLUMNS=-1",
        "COLUMNS=abc",
        "LANG=C",
        "LC_ALL=C",
        "PYTHONIOENCODING=ascii",
        "TZ=Nowhere/Bogus",
        "TERM=dumb",
        "XDG_CACHE_HOME=/dev/null",
        f"XDG_CACHE_HOME={WD}/afile",
        "XDG_CACHE_HOME=",
        "XDG_CACHE_HOME=/nonexistent/deep",
    ]:
        k, v = e.split("=", 1)
        rc, out, err = cli(
            ["simulate", "kundur", "--fault", "3", "--far-bus", "101", "--tf", "1.5"],
            60,
            dict(ENV, **{k: v}),
        )
        if rc != 0 or want not in out:
            bad.append(f"{e}: rc {rc} {err.strip()[-80:]}")
    return (want is not None and not bad), "; ".join(bad) or f"13 environments: {want}"


def main():
    KIT.main(kept=None)


if __name__ == "__main__":
    main()
