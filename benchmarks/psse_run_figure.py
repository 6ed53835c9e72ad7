"""One PSS/E run (tests/psse_reference.py) drawn: each compared channel, PSS/E's and
stabctl's (repeated as a user runs it, at PSS/E's step), and their difference.

    python benchmarks/psse_run_figure.py DERA_FREQFLAG0 docs/dera1_psse_run.png
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import psse_reference as ref

from stabctl.plotting.figures import save_figure


def draw(run: ref.Run, out: Path) -> None:
    """Write the figure of `run` to `out`: one column per compared quantity, its two
    traces above, stabctl's minus PSS/E's below."""
    t_ref, chans = ref.psse_channels(run)
    with tempfile.TemporaryDirectory() as tmp:
        case, tr = ref.simulate(run, Path(tmp), run.step)
    n = len(run.quantities)
    fig, axes = plt.subplots(2, n, figsize=(5 * n, 5.5), sharex=True, squeeze=False)
    for k, q in enumerate(run.quantities):
        ours = np.interp(t_ref, tr["t"], ref._stabctl_series(q, run, case, tr))
        theirs = ref._psse_series(q, chans[:, q.col])
        top, bottom = axes[0, k], axes[1, k]
        top.plot(t_ref, theirs, "k-", lw=2.5, label="PSS/E")
        top.plot(t_ref, ours, "C1--", lw=1.5, label="stabctl")
        top.set_title(f"{run.name}: {q.label}")
        top.legend()
        bottom.plot(t_ref, ours - theirs, "C3-")
        tol = "" if q.tol is None else f" (tolerance {q.tol:g})"
        bottom.set_title(f"stabctl - PSS/E{tol}")
        bottom.set_xlabel("t (s)")
    save_figure(fig, out)  # stabctl's one figure writer: the same bytes every time


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", choices=sorted(ref.BY_NAME), metavar="RUN", help="run name")
    ap.add_argument("out", type=Path, help="PNG file to write")
    a = ap.parse_args(argv)
    draw(ref.BY_NAME[a.run], a.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
