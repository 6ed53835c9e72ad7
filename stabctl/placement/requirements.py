"""What a planner asks of the storage (docs/placement.md, section 7): the requirement each
contingency must withstand, the cost of the devices, and what a screening already knows.

Requirements (`Requirement`, any mix, the strictest wins): a required clearing time in
cycles (every contingency stable when cleared after N cycles, in the spirit of NERC
TPL-001: normal clearing plus a margin), a CCT gain over the CCT without storage (%), or
an absolute CCT (s); per-contingency overrides (`read_requirements`).  A contingency is a
fault at one load level (`Contingency.load`, `stabctl.network.powerflow.scale_load`), with
its required clearing time (`contingencies_of`).

Costs (`CostModel`): cost = sum_j (c_mw,j MW_j + c_mwh,j MWh_j + c_site,j [MW_j > 0]),
per-site overrides (`read_site_costs`).

Screening (`screening_brackets`): the clearing times without storage a screening
bracketed, where the planner's CCT searches start.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from stabctl.errors import InputError
from stabctl.placement.evaluation import Contingency


@dataclass(frozen=True)
class Requirement:
    """What a contingency must withstand; any mix of the three, the strictest wins.

    Attributes
    ----------
    cycles : float or None
        Required clearing time, cycles of the case frequency: stable when cleared then.
    gain_pct : float or None
        CCT raised by this % over the CCT without storage.
    cct_s : float or None
        Required CCT, s.

    Raises
    ------
    InputError
        None given, or one not > 0.
    """

    cycles: float | None = None
    gain_pct: float | None = None
    cct_s: float | None = None

    def __post_init__(self):
        given = [v for v in (self.cycles, self.gain_pct, self.cct_s) if v is not None]
        if not given:
            raise InputError(
                "no requirement given: need a required clearing time "
                "(cycles), a CCT gain (%) or a target CCT (s)"
            )
        if not all(np.isfinite(v) and v > 0 for v in given):
            raise InputError(
                f"requirements must be > 0, got cycles={self.cycles}, "
                f"gain={self.gain_pct} %, cct={self.cct_s} s"
            )

    @property
    def needs_base(self) -> bool:
        """Whether the target depends on the CCT without storage (a gain)."""
        return self.gain_pct is not None

    def target_s(
        self,
        freq_hz: float,
        tol: float,
        base_cct_s: float | None = None,
        base_robust: bool = False,
    ) -> float:
        """The required clearing time (s), rounded up to the tolerance lattice.

        Parameters
        ----------
        freq_hz : float
            Case frequency, Hz.
        tol : float
            CCT tolerance, s.
        base_cct_s : float or None
            CCT without storage, s (needed with a gain).
        base_robust : bool, optional
            The fault is stable without storage when cleared at the search limit,
            `base_cct_s`: its CCT is only known to lie above it, so a gain holds it to stay
            stable cleared there (no search could show a clearing time beyond it met);
            default False.

        Raises
        ------
        InputError
            A gain without base_cct_s.
        """
        t = []
        if self.cycles is not None:
            t.append(self.cycles / freq_hz)
        if self.cct_s is not None:
            t.append(self.cct_s)
        if self.gain_pct is not None:
            if base_cct_s is None:
                raise InputError("a CCT gain needs the CCT without storage")
            t.append(base_cct_s * (1 if base_robust else 1 + self.gain_pct / 100))
        return round(float(np.ceil(max(t) / tol - 1e-6)) * tol, 12)

    def describe(self) -> str:
        """E.g. ``"5 cycles"``, ``"CCT +10 %"``."""
        parts = (
            ([f"{self.cycles:g} cycles"] if self.cycles is not None else [])
            + ([f"CCT +{self.gain_pct:g} %"] if self.gain_pct is not None else [])
            + ([f"CCT {1000 * self.cct_s:g} ms"] if self.cct_s is not None else [])
        )
        return ", ".join(parts)


def read_requirements(path) -> dict:
    """Per-fault requirement overrides from a fault list CSV (`stabctl.stability.cct.
    read_faults`: its columns ``required_clearing_cycles``, ``target_cct_gain``,
    ``target_cct_s``; a row with none keeps the global one).

    Returns
    -------
    dict
        Fault name (`Contingency.fault_name`, e.g. ``"83-33"``) -> `Requirement`.

    Raises
    ------
    InputError
        What `read_faults` refuses, a requirement that is not a number > 0, or a fault
        listed twice with requirements; naming file:line.
    """
    from stabctl.io.inputs import iter_csv, number
    from stabctl.stability.cct import FAULT_COLUMNS, read_faults

    faults = read_faults(path)
    rows = iter_csv(path, "fault list", *FAULT_COLUMNS)
    out: dict = {}
    for fault, row in zip(faults, rows, strict=True):
        vals = {
            k: number(row, c, 0.0) if row.values.get(c) else None
            for k, c in (
                ("cycles", "required_clearing_cycles"),
                ("gain_pct", "target_cct_gain"),
                ("cct_s", "target_cct_s"),
            )
        }
        if all(v is None for v in vals.values()):
            continue
        name = Contingency(fault, 1.0).fault_name
        if name in out:
            raise InputError(f"{row.where()}: fault {name} listed twice with requirements")
        try:
            out[name] = Requirement(**vals)
        except InputError as exc:
            raise InputError(f"{row.where()}: {exc}") from None
    return out


#: largest cost a `CostModel` takes (any currency per MW, MWh or site): the program's
#: scaling of 1e308 overflowed (numpy's warnings, the plan run on infinities)
LARGEST_COST = 1e15


@dataclass(frozen=True)
class CostModel:
    """Cost of an ESD: per MW, per MWh of usable energy and per site (any currency).

    Attributes
    ----------
    per_mw, per_mwh, per_site : float
        Defaults for every site (>= 0; per_mw + per_mwh > 0).
    overrides : dict
        Machine number -> {"per_mw", "per_mwh", "per_site"} (any subset) for its site.

    Raises
    ------
    InputError
        A cost that is not a number in [0, LARGEST_COST], or no cost per MW nor per MWh.
    """

    per_mw: float = 1.0
    per_mwh: float = 0.0
    per_site: float = 0.0
    overrides: dict = field(default_factory=dict)

    def __post_init__(self):
        for k, o in [
            (None, {"per_mw": self.per_mw, "per_mwh": self.per_mwh, "per_site": self.per_site}),
            *self.overrides.items(),
        ]:
            if any(not (0 <= v <= LARGEST_COST) for v in o.values()):
                where = "" if k is None else f" (site of G{k})"
                raise InputError(
                    f"costs must be numbers in [0, {LARGEST_COST:g}]{where} (a larger one "
                    f"overflows the program's scaling), got {o}"
                )
        if not self.per_mw + self.per_mwh > 0:
            raise InputError(  # the options named too (round 55 AS)
                "need a cost per MW or per MWh > 0 (CostModel per_mw, per_mwh; the CLI's "
                f"--cost-mw, --cost-mwh), got {self.per_mw:g} and {self.per_mwh:g}"
            )

    def of(self, machine: int) -> tuple[float, float, float]:
        """(per MW, per MWh, per site) at the site of `machine`."""
        o = self.overrides.get(int(machine), {})
        return (
            o.get("per_mw", self.per_mw),
            o.get("per_mwh", self.per_mwh),
            o.get("per_site", self.per_site),
        )

    def split(self, sites, mw, mwh) -> dict:
        """{"mw", "mwh", "site", "total"} cost of ratings mw and energies mwh per site."""
        c = np.array([self.of(s.machine) for s in sites]).reshape(len(sites), 3)
        mw, mwh = np.asarray(mw, float), np.asarray(mwh, float)
        out = {
            "mw": float(c[:, 0] @ mw),
            "mwh": float(c[:, 1] @ mwh),
            "site": float(c[:, 2] @ (mw > 0)),
        }
        out["total"] = out["mw"] + out["mwh"] + out["site"]
        return out


#: the columns of a site-cost table (`read_site_costs`): required, then optional
SITE_COST_COLUMNS = (("machine",), ("cost_mw", "cost_mwh", "cost_site"))


def read_site_costs(path, n_machines: int, no_site=()) -> dict:
    """Per-site cost overrides from a CSV (a strict table, `stabctl.io.inputs.read_csv`,
    of :data:`SITE_COST_COLUMNS`): machine -> {"per_mw", "per_mwh", "per_site"} (the
    costs given, each >= 0).  no_site: machines that are no candidate site (infinite
    buses, `stabctl.placement.program.candidate_sites`), whose row would be ignored.

    Raises
    ------
    InputError
        A row or header the table refuses, no cost column, a machine not in 1..n_machines,
        in no_site or listed twice, a cost that is not a finite number >= 0; naming
        file:line.
    """
    from stabctl.io.inputs import number, read_csv

    rows = read_csv(path, "site costs", *SITE_COST_COLUMNS)
    if not set(rows[0].values) & set(SITE_COST_COLUMNS[1]):
        raise InputError(
            f"site costs {path}: no cost column (any of {', '.join(SITE_COST_COLUMNS[1])})"
        )
    out: dict = {}
    for row in rows:
        m = int(number(row, "machine", 1, n_machines, integer=True))
        if m in out:
            raise InputError(f"{row.where()}: machine {m} listed twice")
        if m in no_site:
            raise InputError(
                f"{row.where()}: machine {m} is an infinite bus (H = 0), no ESD site, so it "
                "takes no site cost"
            )
        out[m] = {
            k: number(row, c, 0.0, LARGEST_COST)
            for k, c in (("per_mw", "cost_mw"), ("per_mwh", "cost_mwh"), ("per_site", "cost_site"))
            if row.values.get(c)
        }
    return out


def screening_brackets(path, case: str, digest: str, settings: dict | None = None) -> dict:
    """The [stable, unstable] clearing times without storage of a case's faults, as a
    screening bracketed them.

    Parameters
    ----------
    path : str or pathlib.Path
        Records of a screening (`stabctl screen --out`, or a placement study's).
    case : str
        The case they must be of: its input as the screening's jobs record it (a built-in
        name or a case file).
    digest : str
        The digest of that case's content (`stabctl.case.Case.digest`).
    settings : dict, optional
        The run settings the brackets must be of, as a job's inputs record them: the
        model's (`stabctl.dynamics.options.ModelOptions.to_inputs`: conventions, h,
        q_limits, subintervals) and the run end ``t_end`` (s, None: the default);
        default: the defaults.  A bracket found with other settings is another model's
        (a screening in PSTess's conventions made a fault stable that the placement's
        runs find unstable: "0.0 MW ... VERIFIED").

    Returns
    -------
    dict
        Fault name (`Contingency.fault_name`) -> (t_stable, t_unstable) in s, for
        `plan`'s `brackets`; a fault still stable at the screening's limit t_max:
        (t_max, None).  Records with storage or with another outcome are skipped.

    Raises
    ------
    InputError
        A file that is not a regular file, not sweep records, a line that is not a whole
        record (a damaged or cut line: the file must be whole) or one no CCT search can
        have written (`stabctl.stability.cct.cct_record_problem`), a record of another case or
        of other content of the case (its line named,
        `stabctl.parallel.check_records_case`), a record of other run settings than
        `settings` (the first such named, with both values), a malformed screening
        record, or records that bracket no fault.
    """
    from stabctl.io.inputs import input_file
    from stabctl.parallel import check_records_case, read_records
    from stabctl.stability.cct import LineFault, cct_record_problem
    from stabctl.stability.screening import ABOVE, verdict

    try:
        path = input_file(path, "screening records")
        check_records_case(
            path, {case: digest}, f"give the records of a screening of {case} as it is now"
        )
        records = read_records(path, whole="screening records", check=cct_record_problem)
    except InputError:  # it names the file
        raise
    except (OSError, ValueError) as exc:
        raise InputError(f"screening records {path}: {exc}") from None
    want = _run_settings(settings or {})
    out = {}
    for rec in records.values():
        r, inputs = rec.get("result") or {}, rec.get("inputs") or {}
        if differ := [k for k, v in _run_settings(inputs).items() if v != want[k]]:
            k = differ[0]
            raise InputError(
                f"screening records {path}: record {rec.get('key')!r} was run with {k} "
                f"{_run_settings(inputs)[k]!r}, the placement with {want[k]!r}: its brackets "
                "are of another model; give the records of `stabctl screen` run with the "
                "placement's --conventions, --step and --no-q-limits, and its default --tf"
            )
        still = verdict(rec) == ABOVE and "t_max" in inputs
        if inputs.get("esd_pct") is not None or not (
            (rec.get("status") == "ok" and "t_stable_s" in r) or still
        ):
            continue
        f = r.get("fault") or inputs
        try:
            fault = LineFault(
                _whole(f["bus"]),
                None if f["far_bus"] is None else _whole(f["far_bus"]),
                _seconds(f["t_fault_s"] if "t_fault_s" in f else f["t_fault"]),  # older records
                # a bus fault's circuit is null (round 48: every `screen` file refused)
                1 if f["far_bus"] is None and f["circuit"] is None else _whole(f["circuit"]),
                tuple((_whole(a), _whole(b)) for a, b in f["trips"]),
            )
            out[Contingency(fault, 1.0).fault_name] = (
                (_seconds(inputs["t_max"]), None)
                if still
                else (_seconds(r["t_stable_s"]), _seconds(r["t_unstable_s"]))
            )
        except (KeyError, TypeError, ValueError) as exc:
            raise InputError(
                f"screening records {path}: record {rec.get('key')!r} is not a screening "
                f"record ({type(exc).__name__}: {exc})"
            ) from None
    if not out:
        raise InputError(
            f"screening records {path}: no fault bracketed without storage (give the "
            "records of `stabctl screen --out`)"
        )
    return out


def _run_settings(inputs) -> dict:
    """The settings of a job's inputs that make its runs (`screening_brackets`), each
    at its default when not recorded: conventions, h (None: the case's step),
    q_limits, subintervals, t_end (None: the default run end)."""
    return {
        "conventions": inputs.get("conventions", "ieee"),
        "h": inputs.get("h"),
        "q_limits": inputs.get("q_limits", True),
        "subintervals": inputs.get("subintervals", True),
        "t_end": inputs.get("t_end"),
    }


def _whole(v) -> int:
    """A bus, circuit number of a record: a JSON integer >= 1 (ValueError else)."""
    if isinstance(v, bool) or not isinstance(v, int) or v < 1:
        raise ValueError(f"{v!r} is not a number >= 1")
    return v


def _seconds(v) -> float:
    """A time of a record: a finite JSON number >= 0 (ValueError else)."""
    if isinstance(v, bool) or not isinstance(v, (int, float)) or not 0 <= v < math.inf:
        raise ValueError(f"{v!r} is not a time >= 0 s")
    return float(v)


def contingencies_of(
    faults,
    requirement: Requirement,
    freq_hz: float,
    tol: float,
    load_levels=(1.0,),
    overrides: dict | None = None,
    base: dict | None = None,
    leave_out=(),
) -> tuple:
    """One `Contingency` per fault and load level with its required clearing time (s):
    the fault's override (by fault name) or `requirement`; base (name -> evaluation
    without storage) for gain requirements (a gain on a fault robust at the search limit
    holds it stable cleared there: `Requirement.target_s`); none for the names in
    leave_out (contingencies set aside before).  Raises InputError (a gain without
    base)."""
    overrides = overrides or {}
    out = []
    for f in faults:
        name = Contingency(f, 1.0).fault_name
        req = overrides.get(name, requirement)
        for load in load_levels:
            c = Contingency(f, 1.0, float(load))
            if c.name in leave_out:
                continue
            ev = None if base is None else base.get(c.name)
            b, robust = (None, False) if ev is None else (ev["cct_s"], ev.get("above_t_max"))
            out.append(replace(c, target_cct_s=req.target_s(freq_hz, tol, b, bool(robust))))
    return tuple(out)


def describe(requirement: Requirement, overrides) -> str:
    """The requirement in words (`Requirement.describe`), with the number of faults that
    have their own (overrides, fault name -> Requirement, `read_requirements`)."""
    extra = f" ({len(overrides)} fault(s) with their own)" if overrides else ""
    return requirement.describe() + extra
