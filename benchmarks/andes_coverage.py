"""Which of ANDES 2.0's own case files with dynamics stabctl imports (the coverage table
of docs/andes_coverage.md): every ``.xlsx`` and ``.json`` under ``andes/cases`` holding a
dynamic device (a model of ANDES's machine, exciter, governor, stabiliser, renewable,
distributed or motor groups) is read with :func:`stabctl.io.andes_case.read_andes_case`
(``on_unsupported="skip"``).  A file imports when nothing but ANDES's own disturbance
records is left out: Toggle, Fault and Alter are read as the case's own events (an Alter
stabctl cannot map, ieee14_hygov4's of a PQ's Ppf, is refused by name), TimeSeries is
left out.

Run: ``python benchmarks/andes_coverage.py [--markdown docs/andes_coverage.md]``; prints
one line per file and the count, and with ``--markdown`` writes the table (with what
blocks each file that does not import, most frequent first).
"""

from __future__ import annotations

import argparse
import collections
import os
import warnings
from pathlib import Path

import andes
import numpy as np

from stabctl.dynamics.driver import Simulator
from stabctl.io.andes_case import read_andes_case
from stabctl.network.topology import without_dead_islands

FLAT_S = 10.0  # s, the flat run
#: why a file that imports fails its flat run, where known (printed only while it fails;
#: none now: EI_33, whose power flow ANDES cannot solve, runs flat in stabctl)
FLAT_WHY: dict[str, str] = {}

#: ANDES's disturbance models: events of a run, not devices (Toggle, Fault, Alter: the
#: case's own events, `stabctl.io.andes_case.EVENT_MODELS`).  TimeSeries is a schedule of
#: values like Alter's; ieee14_timeseries's writes PQ.Ppf and Qpf, which ANDES's own
#: time-domain run does not read (its loads become constant impedances at initialisation,
#: Req = Ppf / v0**2 with the default p2z = 1: its 10 s run stays flat, as without it)
DISTURBANCES = {"Toggle", "Fault", "Alter", "TimeSeries"}
#: ANDES model groups whose devices make a case dynamic
DYNAMIC_GROUPS = {
    "SynGen",
    "RenGen",
    "DG",
    "Exciter",
    "TurbineGov",
    "PSS",
    "RenExciter",
    "RenPlant",
    "RenGovernor",
    "RenAerodynamics",
    "RenPitch",
    "RenTorque",
    "Motor",
}


def dynamic_case_files(root: Path) -> list[Path]:
    """The ``.xlsx``/``.json`` case files under root holding a dynamic device."""
    found = []
    for path in sorted(root.rglob("*")):
        if path.suffix not in (".xlsx", ".json"):
            continue
        try:
            ss = andes.load(str(path), setup=False, no_output=True, default_config=True)
        except Exception:  # noqa: BLE001 - a file ANDES itself cannot read is not a case
            continue
        if any(m.n and getattr(m, "group", "") in DYNAMIC_GROUPS for m in ss.models.values()):
            found.append(path)
    return found


def check(path: Path) -> tuple[list[str], str]:
    """What keeps the file from importing (empty: it imports) and, if it imports, its flat
    run (`flat_run`)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            result = read_andes_case(str(path), on_unsupported="skip")
    except Exception as exc:  # noqa: BLE001 - every refusal is a row of the table
        return [f"{type(exc).__name__}: {str(exc).splitlines()[0][:160]}"], ""
    why = [x for x in result.left_out if x.split(" ")[0] not in DISTURBANCES]
    return why, ("" if why else flat_run(result.case))


def flat_run(case) -> str:
    """10 s without disturbance at the case's default step, PV Q limits off (ANDES's
    default), islands without a swing bus left out as ``--leave-out-islands`` does
    (`without_dead_islands`, said in the cell): the largest change of any recorded
    quantity (speeds, angles, P, Q, E_fd, P_m, bus voltages, converter P and Q; pu, rad)
    and the largest initial derivative, or why it fails."""
    case, islands = without_dead_islands(case)
    said = f"; {'; '.join(islands)} left out" if islands else ""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = Simulator(case, q_limits=False).run([], FLAT_S)
    except Exception as exc:  # noqa: BLE001 - a refusal is the row's verdict
        return f"{type(exc).__name__}: {str(exc).splitlines()[0][:120]}"
    series = [res.speed, res.angle, res.pelect, res.pmech, res.efd, res.vmag, res.vang]
    series += [x for x in (res.ibr_p, res.ibr_q) if x is not None and x.size]
    drift = max(float(np.ptp(x, axis=0).max(initial=0.0)) for x in series)
    return f"{drift:.1e} ({res.meta['max_initial_derivative']:.0e}){said}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--markdown", type=Path, help="write the coverage table here")
    args = ap.parse_args()
    andes.config_logger(50, file=False, log_path=os.devnull)  # no log directory left
    root = Path(andes.__file__).parent / "cases"
    rows, flat = {}, {}
    for path in dynamic_case_files(root):
        key = str(path.relative_to(root))
        rows[key], flat[key] = why, drift = check(path)
        print(f"{key}: {f'imports, flat {drift}' if not why else '; '.join(why[:3])}")
    ok = sorted(k for k, v in rows.items() if not v)
    worst = max((float(flat[k].split()[0]) for k in ok if flat[k][0].isdigit()), default=0.0)
    failed = [k for k in ok if not flat[k][0].isdigit()]
    print(f"\n{len(ok)} of {len(rows)} ANDES {andes.__version__} case files with dynamics import")
    print(f"flat {FLAT_S:g} s: largest drift {worst:.1e}; runs refused or failed: {failed}")
    if args.markdown:
        causes = collections.Counter(
            w.split(" (")[0] if not w.startswith(("CaseError", "InputError")) else w
            for v in rows.values()
            for w in v
        )
        lines = [
            f"# ANDES {andes.__version__} case files stabctl imports",
            "",
            f"Generated by `python benchmarks/andes_coverage.py --markdown {args.markdown}`.",
            f"**{len(ok)} of {len(rows)}** `.xlsx`/`.json` case files with dynamic devices "
            "import with `read_andes_case` (their own disturbance records: Toggle, Fault and "
            "Alter read as the case's own events, which `simulate --case-events` runs, those "
            "stabctl cannot map refused by name; TimeSeries left out; ieee14_timeseries's schedule "
            "writes PQ.Ppf and Qpf, which ANDES's own time-domain run does not read: its "
            "loads are constant impedances from initialisation).",
            "",
            f"Flat run of each file that imports ({FLAT_S:g} s without disturbance at its "
            "default step, PV Q limits off as ANDES): largest change of any recorded "
            "quantity (speeds, angles, P, Q, E_fd, P_m, bus voltages, converter P and Q), "
            "and in brackets the largest "
            f"initial derivative: **{worst:.1e} at most** over the files"
            + (f"; refused or failed: {', '.join(failed)}" if failed else "")
            + ".",
            "",
            *(f"- `{k}`: {FLAT_WHY[k]}." for k in failed if k in FLAT_WHY),
            "",
            "## What blocks the others (files per cause)",
            "",
            "A column ANDES ignores (no parameter of its model: an older ANDES's, such as "
            "WTDTA1's `Ht` and `Hg`, whose values ANDES replaces by its defaults without a "
            "word) refuses the file; `stabctl import-andes --skip-unsupported` imports it "
            "with each such column named in a warning.",
            "",
            "| files | model left out, or refusal |",
            "|---|---|",
            *(f"| {n} | {cause} |" for cause, n in causes.most_common()),
            "",
            "## Per file",
            "",
            "| case file | imports | flat 10 s: drift (initial derivative) | left out / refused |",
            "|---|---|---|---|",
            *(
                f"| `{k}` | {'yes' if not v else 'no'} | {flat[k]} | "
                f"{'; '.join(v).replace('|', '/')} |"
                for k, v in sorted(rows.items())
            ),
            "",
        ]
        tmp = args.markdown.with_suffix(".tmp")
        tmp.write_text("\n".join(lines))
        tmp.replace(args.markdown)


if __name__ == "__main__":
    main()
