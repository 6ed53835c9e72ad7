"""Stored ANDES reference traces for tests/io/test_andes.py (issue 51): the default test run
compares stabctl's live runs with ANDES's runs stored in ``tests/data/andes_refs/``, so that
it needs no ANDES time simulation (ANDES's parser still reads the case files).

A test takes the ``ref`` fixture and wraps each ANDES run in ``ref.run(tag, make)``:
``make()`` runs ANDES and returns a dict of arrays, the values the test compares.  The mode
(environment variable ``STABCTL_ANDES_REFS``):

* unset or ``stored`` (the default): ``make`` is not called, the values come from the test's
  file ``tests/data/andes_refs/<test>.npz``; a missing file or run fails the test naming the
  command that writes it;
* ``live`` (CI, ``.ci/run``): as ``stored``, and the few live smoke tests (the tests'
  ``[live-andes]`` variants, `live_too`) run ANDES and check that its fresh values are the
  stored ones (a new ANDES, or changed settings, is caught), then assert on the fresh ones;
* ``check``: every test runs ANDES and checks its values against the stored ones (all of
  the file against a new ANDES version: ``STABCTL_ANDES_REFS=check python -m pytest
  tests/io/test_andes.py``);
* ``record``: every test runs ANDES and writes its file (``tests/data/andes_refs/
  make_refs.py``, which also writes the README there).

Each file holds the arrays as ``<tag>/<name>`` (float64 as ANDES gives them) and ``_meta``,
a JSON text: the test, the ANDES version, the date, and per run the ANDES calls made (the
case file, the disturbance, the step and end time: `logged`).
"""

from __future__ import annotations

import datetime
import functools
import json
import os
import re
from pathlib import Path

import numpy as np
import pytest

REFS = Path(__file__).parent / "data" / "andes_refs"
MODES = ("stored", "live", "check", "record")
#: a fresh ANDES value against its stored one (the same ANDES on the same data repeats its
#: run to round-off; a changed model moves a trace by far more)
RTOL, ATOL = 1e-8, 1e-10


def _canonical(fresh: np.ndarray, stored: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The two arrays to compare: eigenvalues (1-D complex) each paired with its nearest
    in the other (`scipy.optimize.linear_sum_assignment` on their distances), since
    LAPACK's order of one spectrum depends on its build (scipy 1.17's OpenBLAS lists ANDES's
    IEEE 39 modes in another order than the stored run, the same values within 5e-13; a
    sort cannot pair near-equal eigenvalues reliably); anything else as it is."""
    if fresh.ndim == 1 and np.iscomplexobj(fresh) and fresh.shape == stored.shape:
        from scipy.optimize import linear_sum_assignment

        rows, cols = linear_sum_assignment(np.abs(fresh[:, None] - stored[None, :]))
        return fresh[rows], stored[cols]
    return fresh, stored


#: the parametrize ids of `live_too`'s two variants, left out of the file name
STORED_ID, LIVE_ID = "refs", "live-andes"

#: the ANDES calls of the run being recorded (`logged`), taken into its metadata
CALLS: list[str] = []


def env_mode() -> str:
    """The mode set by ``STABCTL_ANDES_REFS`` (``stored`` when unset)."""
    mode = os.environ.get("STABCTL_ANDES_REFS", "stored") or "stored"
    if mode not in MODES:
        raise ValueError(f"STABCTL_ANDES_REFS={mode!r}: one of {', '.join(MODES)}")
    return mode


def _arg(v) -> str:
    """A call argument as the README shows it: a path by its last two parts (ANDES's
    ``cases/<folder>/<file>``), a test's temporary file as ``tmp/<file>``, an ANDES
    system as ``ss``, a function by its name."""
    if isinstance(v, Path) or (isinstance(v, str) and ("/" in v or "\\" in v)):
        p = Path(v)
        return f"tmp/{p.name}" if "pytest-of-" in str(p) else f"{p.parent.name}/{p.name}"
    if type(v).__name__ == "System":
        return "ss"
    if callable(v) and hasattr(v, "__qualname__"):
        return v.__qualname__.replace(".<locals>", "")
    return repr(v)


def logged(f):
    """``f`` (an ANDES call of stabctl.io.andes, or ``andes.load``) that also appends its
    call, arguments shown by `_arg`, to `CALLS`."""

    @functools.wraps(f)
    def call(*args, **kw):
        shown = [_arg(a) for a in args] + [f"{k}={_arg(v)}" for k, v in kw.items()]
        name = getattr(f, "__name__", "call")
        CALLS.append(f"{name}({', '.join(shown)})")
        return f(*args, **kw)

    return call


def file_key(name: str) -> str:
    """The file name (without ``.npz``) of the test node ``name``: its parametrize ids kept,
    `live_too`'s left out, characters other than letters, digits, ``._-`` as ``_``."""
    base, _, ids = name.partition("[")
    text = ids[:-1]
    for token in map(re.escape, (LIVE_ID, STORED_ID)):
        text = re.sub(rf"^{token}$|^{token}-|-{token}(?=-|$)", "", text)
    key = f"{base}[{text}]" if text else base
    return re.sub(r"[^A-Za-z0-9._\[\]-]", "_", key).replace("[", "__").replace("]", "")


def regenerate_hint(key: str) -> str:
    """The command that writes the file ``key``."""
    test = key.split("__")[0]
    return f"python tests/data/andes_refs/make_refs.py -k {test} (ANDES installed)"


class AndesRef:
    """The stored ANDES runs of one test (module docstring).

    Parameters
    ----------
    key : str
        The file's name without ``.npz`` (`file_key`).
    mode : str
        One of `MODES`.
    test : str
        The test node's id, kept in the file's metadata.
    """

    def __init__(self, key: str, mode: str, test: str = ""):
        self.key, self.mode, self.test = key, mode, test
        self.path = REFS / f"{key}.npz"
        self._stored: dict | None = None
        self._made: dict[str, dict] = {}
        self._runs: dict[str, dict] = {}

    @property
    def live(self) -> bool:
        """Whether ANDES runs (modes live, check, record)."""
        return self.mode != "stored"

    def stored(self) -> dict:
        """The file's arrays (``<tag>/<name>``) and its metadata; fails the test, naming the
        command that writes it, when there is no file."""
        if self._stored is None:
            if not self.path.exists():
                pytest.fail(
                    f"stored ANDES reference {self.path.relative_to(REFS.parents[2])} is "
                    f"missing: write it with {regenerate_hint(self.key)}",
                    pytrace=False,
                )
            with np.load(self.path, allow_pickle=False) as z:
                self._stored = {k: z[k] for k in z.files}
        return self._stored

    def meta(self) -> dict:
        """The stored file's metadata (test, ANDES version, runs)."""
        return json.loads(str(self.stored()["_meta"]))

    def _from_file(self, tag: str) -> dict:
        """The stored values of run ``tag``."""
        data = self.stored()
        out = {k.split("/", 1)[1]: v for k, v in data.items() if k.startswith(f"{tag}/")}
        if not out:
            pytest.fail(
                f"{self.path.name} has no run {tag!r}: write it with {regenerate_hint(self.key)}",
                pytrace=False,
            )
        return out

    def run(self, tag: str, make, note: str = "", inputs: dict | None = None) -> dict:
        """The values of ANDES run ``tag``: ``make()``'s (a dict of arrays or numbers) when
        ANDES runs, checked against the stored ones (mode live, check) or kept for the file
        (record); the stored ones otherwise.  0-d values come back as Python scalars; a
        second call with the same tag returns the first's values (one ANDES run shared).
        ``note``: what the logged calls do not say (a disturbance added by hand).
        ``inputs``: numbers of stabctl's the ANDES run depends on (a clearing time from
        stabctl's CCT): stored with it, and a stored run made for other inputs fails the
        test (write it again)."""
        inputs = {k: float(v) for k, v in (inputs or {}).items()}
        if tag in self._made:
            return _scalars(self._made[tag])
        if not self.live:
            out = self._from_file(tag)
            self._check_inputs(tag, out, inputs)
            return _scalars({k: v for k, v in out.items() if not k.startswith("input.")})
        CALLS.clear()
        fresh = {k: np.asarray(v) for k, v in make().items()}
        fresh.update({f"input.{k}": np.asarray(v) for k, v in inputs.items()})
        self._runs[tag] = {"calls": list(CALLS), "note": note}
        self._made[tag] = fresh
        if self.mode in ("live", "check"):
            stored = self._from_file(tag)
            assert stored.keys() == fresh.keys(), f"{tag}: {sorted(stored)} != {sorted(fresh)}"
            for k, v in fresh.items():
                np.testing.assert_allclose(
                    *_canonical(v, stored[k]),
                    rtol=RTOL,
                    atol=ATOL,
                    err_msg=f"ANDES's fresh {tag}/{k} is not the stored one "
                    f"({self.path.name}); a new ANDES? {regenerate_hint(self.key)}",
                )
        return _scalars({k: v for k, v in fresh.items() if not k.startswith("input.")})

    def _check_inputs(self, tag: str, stored: dict, inputs: dict) -> None:
        """Fail when the stored run ``tag`` was made for other ``inputs`` than these."""
        was = {k[6:]: float(v) for k, v in stored.items() if k.startswith("input.")}
        if was.keys() != inputs.keys() or any(
            abs(was[k] - v) > 1e-12 * max(1.0, abs(v)) for k, v in inputs.items()
        ):
            pytest.fail(
                f"{self.path.name} run {tag!r} was made for {was}, the test now asks "
                f"{inputs}: write it again with {regenerate_hint(self.key)}",
                pytrace=False,
            )

    def finish(self) -> None:
        """In mode record: write the file (every run of the test, compressed)."""
        if self.mode != "record" or not self._made:
            return
        import andes

        meta = {
            "test": self.test,
            "andes": andes.__version__,
            "made": datetime.date.today().isoformat(),
            "runs": self._runs,
        }
        arrays = {f"{t}/{k}": v for t, d in self._made.items() for k, v in d.items()}
        REFS.mkdir(parents=True, exist_ok=True)
        np.savez_compressed(self.path, _meta=np.array(json.dumps(meta)), **arrays)


def _scalars(d: dict) -> dict:
    """The dict with its 0-d arrays as Python scalars (``is True`` holds for a verdict)."""
    return {k: (v.item() if np.ndim(v) == 0 else v) for k, v in d.items()}


def ref_for(request) -> AndesRef:
    """The `AndesRef` of the requesting test: mode from `env_mode`, or ``live`` for a
    `live_too` ``[live-andes]`` variant (skipped unless ``STABCTL_ANDES_REFS`` is ``live``
    or ``check``; in ``record`` its ``[refs]`` variant writes the file)."""
    mode = env_mode()
    variant = getattr(request, "param", None)
    if variant == LIVE_ID:
        if mode == "stored":
            pytest.skip("live ANDES smoke test: STABCTL_ANDES_REFS=live (CI, .ci/run)")
        if mode == "record":
            pytest.skip("recorded by its [refs] variant")
        mode = "check"
    elif mode == "live":  # the smoke tests above run ANDES; every other test reads its file
        mode = "stored"
    return AndesRef(file_key(request.node.name), mode, request.node.nodeid)


#: a test run twice: against the stored traces, and (``[live-andes]``) with ANDES live,
#: checking the stored traces still equal ANDES's fresh run (the smoke tests)
#: the live variant runs ANDES's time simulation (tens of seconds each): ``heavy``, so that
#: it starts first under pytest-xdist (tests/conftest.py)
live_too = pytest.mark.parametrize(
    "ref", [STORED_ID, pytest.param(LIVE_ID, marks=pytest.mark.heavy)], indirect=True
)
