"""The converter and battery data that cannot be, one table for every route the data come
by (`RULES`): an ANDES case file's rows as written (`stabctl.io.andes_case`, before ANDES
fills its defaults: ``import-andes``) and the ibr_con table of any case
(`stabctl.case.ConverterTable`, each component's rows as `COMPONENTS` finds them), so
that the same data is refused whichever way it reaches a run.  ANDES 2.0 runs them.

Sources: WECC REGC_A, REEC_A/B/C, REPC_A, WTGT_A, WTGAR_A, WTGPT_A, WTGTRQ_A model
specifications (as ANDES 2.0 ``renewable/regca1.py``, ``reeca1.py``, ``reecb1.py``,
``repca1.py``, ``wtdta1.py``, ``wtds.py``, ``wtara1.py``, ``wtpta1.py``, ``wttqa1.py``
implement them); ANDES 2.0 ``distributed/pvd1.py``, ``esd1.py``; the equations'
divisions, limit pairs and rest points (docs/ibr.md).

An ANDES file's REECA1 whose voltage-dependent current limit's points fall (Vq1..Vq4,
Iq1..Iq4 of VDL1; Vp1..Vp4, Ip1..Ip4 of VDL2) is refused: ANDES 2.0 ``reeca1.py`` takes
that curve out of service without a word (its ``zVDL1``/``zVDL2``); so is one whose
points are all 0 (ANDES limits the current to 0).  An ibr_con row's curve (PSS/E's
REEC_A data included) applies as PSS/E's REECA1 takes it: its voltages must not fall
(refused on any route), its currents may (round 43: a falling current point switched
the whole curve off without a word), and all its points 0 is no curve (Imax alone, as
a REECD1's table of no points).  Judged not impossible, so accepted without a word:
WTARA1's aerodynamic gain Ka = 0 (ANDES declares it non-negative: the turbine's power
then does not depend on its pitch, no division); a WTTQA1 speed curve sp1..sp4 that does
not rise (neither ANDES nor the WECC WTGTRQ_A specification orders it, nothing divides by its
steps: only its power points p1..p4 must rise).
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np

from stabctl.models.blocks import LBND
from stabctl.models.converters.table import (
    DERA1,
    ESD1,
    PVD1,
    REECA1,
    REECB1,
    REECD1,
    REGCA1,
    REPCA1,
    WTDS,
    WTDTA1,
)

__all__ = ["Rule", "RULES", "COMPONENTS", "SHARES", "share_sums"]


@dataclass(frozen=True)
class Rule:  # fields of a dataclass: numpydoc ignore=PR02
    """A relation a converter component's parameters must satisfy (`RULES`).

    Parameters
    ----------
    names : tuple of str
        The parameters it reads, ANDES 2.0's names (the ibr_con columns of the same names);
        the first is the field a message names.
    test : callable
        Of their values in ``names`` order (floats, or arrays of a table's rows): True (or
        a boolean array, True on every row) where the relation holds.
    what : str
        The relation, as messages state it ("Vdip < Vup").
    """

    names: tuple[str, ...]
    test: Callable[..., Any]
    what: str

    def holds(self, values: Mapping[str, Any]) -> Any:
        """Whether the relation holds for ``values`` (name -> value or array of values)."""
        return self.test(*(values[n] for n in self.names))

    def prefixed(self, prefix: str) -> Rule:
        """The same relation on the ibr_con columns named ``prefix`` + each name (REPCA1's
        ``pc_Qmax``, the wind turbine's ``wq_Temax``), its statement so named too."""
        pattern = r"\b(" + "|".join(map(re.escape, self.names)) + r")\b"
        what = re.sub(pattern, lambda m: prefix + m.group(1), self.what)
        return Rule(tuple(prefix + n for n in self.names), self.test, what)


def _positive(name: str, why: str = "") -> Rule:
    return Rule((name,), lambda v: v > 0, f"{name} > 0" + (f" ({why})" if why else ""))


def _nonnegative(name: str, why: str) -> Rule:
    return Rule((name,), lambda v: v >= 0, f"{name} >= 0 ({why})")


def _ordered(hi: str, lo: str, of: str) -> Rule:
    """``hi`` >= ``lo``: the upper and lower limits of ``of``."""
    return Rule((hi, lo), lambda h, l: h >= l, f"{hi} >= {lo} (the limits of {of})")


def _around_zero(hi: str, lo: str, of: str) -> Rule:
    """``lo`` <= 0 <= ``hi``: the rate limits of ``of``, whose rate at rest is 0."""
    return Rule(
        (hi, lo),
        lambda h, l: (l <= 0) & (h >= 0),
        f"{lo} <= 0 <= {hi} (the rate limits of {of}; at rest its rate is 0)",
    )


def _lag(name: str) -> Rule:
    """A lag time constant of at least `LBND` (the ibr_con table's, by
    `stabctl.models.converters.converter_params`: a faster one is no lag stabctl runs)."""
    return Rule((name,), lambda t: t >= LBND, f"{name} >= {LBND:g} s (a lag of the converter)")


def _rising(names: tuple[str, ...], of: str) -> Rule:
    """Each of ``names`` above the one before (the slopes of ``of`` divide by the steps)."""
    return Rule(
        names,
        lambda *v: np.logical_and.reduce([a < b for a, b in zip(v, v[1:])]),
        f"{' < '.join(names)} (the points of {of}: its slopes divide by their steps)",
    )


def _not_falling(names: tuple[str, ...], of: str) -> Rule:
    """Each of ``names`` at or above the one before: the points of ``of``, which ANDES 2.0
    takes out of service where they fall (REECA1's ``zVDL1``, ``zVDL2``)."""
    return Rule(
        names,
        lambda *v: np.logical_and.reduce([a <= b for a, b in zip(v, v[1:])]),
        f"{' <= '.join(names)} (the points of {of}: ANDES takes the curve out of service "
        "where they fall)",
    )


#: a device's share of its static generator's P or Q (ANDES's ``gammap``, ``gammaq``: a
#: machine's, a converter's), a fraction of that generator's power (an ANDES file's)
SHARES = tuple(
    Rule((g,), lambda v: (v >= 0) & (v <= 1), f"0 <= {g} <= 1 (a share of its static "
    "generator's power)")
    for g in ("gammap", "gammaq")
)  # fmt: skip

#: the tolerance of summed shares (`share_sums`)
_SHARE_TOL = 1e-9


def share_sums(sums: Mapping[str, float], machine: bool) -> tuple[str, str]:
    """Why the shares of one generation (a bus's, an ANDES static generator's) that its
    converters and machines take together cannot be, '' if they can.

    Parameters
    ----------
    sums : mapping of str to float
        The shares summed over the converters and machines, by name (``pfrac``, ``qfrac``
        of a case's tables; ``gammap``, ``gammaq`` of an ANDES file).
    machine : bool
        Whether a machine takes a share: then the shares must add up to 1 (the rest would
        be lost: a run nets the rest into the load of a bus without machine only).

    Returns
    -------
    name : str
        The first of ``sums`` that cannot be, '' if none: each at most 1 (more than all of
        the generation puts a converter's power-flow point above the bus's), with a
        machine 1.
    why : str
        ``"take pfrac 2.9 and qfrac 1 of its power: more than all of it ..."``, '' if
        none.
    """
    shown = " and ".join(f"{n} {v:.12g}" for n, v in sums.items())
    for name, v in sums.items():
        if v > 1 + _SHARE_TOL:
            return name, f"take {shown} of its power: more than all of it (at most 1)"
    for name, v in sums.items():
        if machine and abs(v - 1) > _SHARE_TOL:
            return name, (
                f"take {shown} of its power, not 1 (stabctl nets the rest into the load of "
                "a bus without machine only)"
            )
    return "", ""


#: the state of charge's limits: fractions of En, the lower below the upper, the initial
#: one between them (ANDES 2.0 ESD1; WECC REEC_C)
_SOC = (
    Rule(("SOCmin",), lambda lo: lo >= 0, "SOCmin >= 0 (a fraction of En)"),
    Rule(("SOCmax",), lambda hi: hi <= 1, "SOCmax <= 1 (a fraction of En)"),
    Rule(("SOCmin", "SOCmax"), lambda lo, hi: lo < hi, "SOCmin < SOCmax"),
    Rule(
        ("SOCinit", "SOCmin", "SOCmax"),
        lambda s, lo, hi: (lo <= s) & (s <= hi),
        "SOCmin <= SOCinit <= SOCmax",
    ),
)
#: the electrical controls' current limit and voltage dip band (WECC REEC_A, REEC_B; ANDES
#: 2.0 reeca1.py, reecb1.py: it freezes below Vdip and above Vup), their limit pairs
#: (Iqinj's [Iql1, Iqh1], the Q reference's [QMin, QMax], the voltage control's [VMIN,
#: VMAX], the P order's [PMIN, PMAX]: ANDES's HardLimiter, GainLimiter, LagAWFreeze) and
#: the P reference's rate limits, which hold its rest rate 0 between them (ANDES's
#: LagRate; its declaration: dPmax > 0, dPmin < 0)
_REEC = (
    _positive("Imax"),
    Rule(("Vdip", "Vup"), lambda lo, hi: lo < hi, "Vdip < Vup"),
    _ordered("Iqh1", "Iql1", "Iqinj"),
    _ordered("QMax", "QMin", "the Q reference"),
    _ordered("VMAX", "VMIN", "the voltage control"),
    _ordered("PMAX", "PMIN", "the P order"),
    _around_zero("dPmax", "dPmin", "the P reference"),
)
#: an ANDES file's REECA1's voltage-dependent current limits VDL1 (Iq) and VDL2 (Ip): their
#: voltage and current points do not fall (ANDES 2.0 reeca1.py's ``zVDL1``, ``zVDL2``),
#: and a curve is not all 0 (ANDES then limits the current to 0: nothing starts; an
#: ibr_con row's all-0 curve is no curve, PSS/E's table of no points)
_REEC_VDL = (
    *(
        _not_falling(tuple(f"{x}{j}" for j in range(1, 5)), f"the {curve} curve")
        for x, curve in (("Vq", "VDL1"), ("Iq", "VDL1"), ("Vp", "VDL2"), ("Ip", "VDL2"))
    ),
    *(
        Rule(
            tuple(f"{x}{j}" for x in (v, i) for j in range(1, 5)),
            lambda *pts: np.logical_or.reduce([np.asarray(p) != 0 for p in pts]),
            f"not all 0 (the points of the {curve} curve: ANDES then limits the current "
            "to 0, so the device cannot start)",
        )
        for v, i, curve in (("Vq", "Iq", "VDL1"), ("Vp", "Ip", "VDL2"))
    ),
)
#: an ibr_con row's REECA1 VDL curves (any route: PSS/E's REEC_A data, an ANDES file's):
#: voltages that do not fall (PSS/E interpolates in voltage; its currents may fall, as
#: PSS/E's and GridPACK's REECA1 take them)
_REEC_VDL_VOLTAGES = tuple(
    Rule(
        tuple(f"{x}{j}" for j in range(1, 5)),
        lambda *v: np.logical_and.reduce([a <= b for a, b in zip(v, v[1:])]),
        f"{' <= '.join(f'{x}{j}' for j in range(1, 5))} (the voltages of the {curve} curve, "
        "which is linear between them)",
    )
    for x, curve in (("Vq", "VDL1"), ("Vp", "VDL2"))
)
#: the lags an ANDES file's REECA1 (REECB1) must have, as the ibr_con table's
#: `stabctl.models.converters.converter_params` does (its Pe filter Tp may be 0: none)
_REEC_LAGS = (_lag("Trv"), _lag("Tiq"), _lag("Tpord"))
#: REPCA1's limit pairs (the error's [emin, emax], the Q command's [Qmin, Qmax], the P
#: error's [femin, femax], the P PI's [Pmin, Pmax]: ANDES 2.0 repca1.py's Limiters and
#: PITrackAW), its reactive droop Kc (VCFlag 0: V + Kc Qline; a negative droop is a
#: positive feedback, as a governor's droop below 0) and the voltage Vfrz below which it
#: holds its error (a voltage magnitude; ``freeze`` 0 turns the hold off) (WECC REPC_A)
_REPC = (
    _ordered("Qmax", "Qmin", "the Q command"),
    _ordered("emax", "emin", "the voltage error"),
    _ordered("femax", "femin", "the P error"),
    _ordered("Pmax", "Pmin", "the P PI's output"),
    _nonnegative("Kc", "a reactive droop gain"),
    _nonnegative("Vfrz", "a voltage magnitude"),
    _nonnegative("Ddn", "a droop gain: P down per pu frequency above the deadband"),
    _nonnegative("Dup", "a droop gain: P up per pu frequency below the deadband"),
)
#: the drive train's damping (a negative one feeds energy in), its shaft's torsional
#: frequency (Kshaft = 2 Ht Hg Freq1^2 / H: 0 is no shaft between the masses) and the
#: speed the turbine starts at without a torque control (Pm/wt divides by it; the
#: damping's reference) (WECC WTGT_A; ANDES 2.0 wtdta1.py, wtds.py)
_WT_SHAFT = (
    _nonnegative("Dshaft", "the shaft's damping"),
    _positive("Freq1", "the shaft's torsional frequency: at 0 no shaft joins the masses"),
)
_WT_SPEED = (_positive("w0", "a speed: Pm/wt divides by it at the start"),)
#: the pitch control's limit pairs, the pitch angle's [thmin, thmax] and its rates
#: [dthmin, dthmax] (at rest 0 between them) (WECC WTGPT_A; ANDES 2.0 wtpta1.py's
#: PIAWHardLimit, LagAntiWindupRate)
_WT_PITCH = (
    _ordered("thmax", "thmin", "the pitch angle"),
    _around_zero("dthmax", "dthmin", "the pitch angle"),
)
#: the torque control's limits [Temin, Temax] and its speed curve's power points, which
#: its slopes divide by (kp1 = (sp2 - sp1)/(p2 - p1), ...), at speeds above 0 (the start
#: divides by fPe(P0)) (WECC WTGTRQ_A; ANDES 2.0 wttqa1.py)
_WT_TORQUE = (
    _ordered("Temax", "Temin", "the electric torque"),
    _rising(("p1", "p2", "p3", "p4"), "the speed curve"),
    *(_positive(f"sp{j}", "a speed of the speed curve") for j in range(1, 5)),
)
#: PVD1's and ESD1's limit pairs: the Q command's [qmn, qmx], the Q-droop's deadband [v0,
#: v1] (ANDES 2.0 pvd1.py's Limiters VQ1 [Vql, v0], VQ2 [v1, Vqu]); the power limit pmx
#: >= 0 (PVD1's P order in [0, pmx], ESD1's in [-pmx, pmx])
_PVD = (
    _positive("ialim"),
    _ordered("qmx", "qmn", "the Q command"),
    Rule(("v0", "v1"), lambda lo, hi: lo <= hi, "v0 <= v1 (the Q-droop's deadband)"),
    _nonnegative("pmx", "the upper limit of the P order, [0, pmx] (ESD1 [-pmx, pmx])"),
)
#: an ANDES file's PVD1 or ESD1 only: the rated frequency fn (fHz = fn f; the trip
#: points ft0..ft3 are in Hz), the trip flags (ANDES 2.0 pvd1.py: "latching (0) or
#: self-resetting (0-1)"; ANDES reads but does not use them) and the current lags
_PVD_FILE = (
    _positive("fn", "the rated frequency"),
    *(
        Rule(
            (f,), lambda v: (v >= 0) & (v <= 1), f"0 <= {f} <= 1 ({what}: 0 latching, 1 resetting)"
        )
        for f, what in (("vrflag", "the voltage trip"), ("frflag", "the frequency trip"))
    ),
    _lag("tip"),
    _lag("tiq"),
)
#: REGCA1's piecewise gains divide by Lvpnt1 - Lvpnt0 and Brkpt - Zerox (with its LVPL on);
#: its Iq lag's rate limits hold the rest point's rate 0 between them (WECC REGC_A; ANDES
#: 2.0 regca1.py)
_REGC = (
    Rule(("Lvpnt1", "Lvpnt0"), lambda hi, lo: hi > lo, "Lvpnt1 > Lvpnt0"),
    _positive("Volim", "a voltage magnitude: the high-voltage management acts above it"),
    _positive("Rrpwr", "the LVPL's recovery rate of the active current: at 0 it never recovers"),
    _nonnegative("Lvpl1", "the LVPL's current limit at Brkpt"),
    Rule(
        ("Brkpt", "Zerox", "Lvplsw"),
        lambda b, z, on: (on == 0) | (b > z),
        "Brkpt > Zerox (Lvplsw 1)",
    ),
    Rule(
        ("Iqrmax", "Iqrmin"),
        lambda hi, lo: (lo <= 0) & (hi >= 0),
        "Iqrmin <= 0 <= Iqrmax (the rate limits of Iq; at rest its rate is 0)",
    ),
    # round 46: +1.3 imported without a word, then the run refused to start, naming six
    # causes but not this one; PSS/E's REGC_A states Iolim < 0 (ANDES's default -1.5)
    Rule(
        ("Iolim",),
        lambda v: v <= 0,
        "Iolim <= 0 (the lower limit of the reactive current out, the high-voltage "
        "management's clamp: above 0 the converter could absorb no reactive current)",
    ),
)

#: ESD1's energy, efficiencies (at most 1: ANDES 2.0 esd1.py declares (0, 1), its state of
#: charge gains EtaC of the energy charged, loses 1/EtaD of the energy discharged) and the
#: lag Tf of its state of charge
_ESD = (
    _positive("En"),
    *_SOC,
    _positive("Tf"),
    *(
        Rule((e,), lambda v: (v > 0) & (v <= 1), f"0 < {e} <= 1 (an efficiency)")
        for e in ("EtaC", "EtaD")
    ),
)

#: a PSS/E DERA1's limit pairs (its Iqinj's [Iql1, Iqh1]; with FreqFlag 1 the frequency
#: error's [femin, femax], the power PI's and Pord's [Pmin, Pmax], Pord's rate limits
#: around 0): the ibr_con table's ``da_`` columns (round 44: Iqh1 < Iql1 ran with exit 0
#: and another Q; the others were refused by `simulate` only, without the field)
_DERA_IQ = (_ordered("Iqh1", "Iql1", "Iqinj").prefixed("da_"),)
_DERA_FREQ = tuple(
    r.prefixed("da_")
    for r in (
        _ordered("femax", "femin", "the frequency error"),
        _ordered("Pmax", "Pmin", "the power order"),
        _around_zero("dPmax", "dPmin", "the power order"),
    )
)

#: physically impossible converter and battery data, refused whichever route the data
#: come by: an ANDES case file's rows as written (`stabctl.io.andes_case`, before ANDES
#: fills its defaults) and the ibr_con table of any case (`stabctl.case.ConverterTable`,
#: the components' rows by `COMPONENTS`): ANDES 2.0 model -> its rules.  ANDES runs them
RULES: Mapping[str, tuple[Rule, ...]] = MappingProxyType(
    {
        "PVD1": (*_PVD, *_PVD_FILE),
        "ESD1": (*_PVD, *_ESD, *_PVD_FILE),
        "REGCA1": (*_REGC, _lag("Tg"), _lag("Tfltr")),
        "REGCP1": (*_REGC, _lag("Tg"), _lag("Tfltr")),
        "REECA1": (*_REEC, *_REEC_LAGS, *_REEC_VDL),
        "REECA1E": (*_REEC, *_REEC_LAGS, *_REEC_VDL),
        "REECB1": (*_REEC, *_REEC_LAGS),
        "REPCA1": (*_REPC, *(_lag(t) for t in ("Tfltr", "Tfv", "Tp", "Tg"))),
        # the case route's H and Htfrac check is `wind.check`'s
        "WTDTA1": (
            _positive("H"),
            Rule(("Htfrac",), lambda f: f < 1, "Htfrac < 1"),
            _nonnegative("DAMP", "the generator's damping"),
            *_WT_SHAFT,
            *_WT_SPEED,
        ),
        "WTDS": (_nonnegative("D", "the damping"), *_WT_SPEED),
        "WTPTA1": (*_WT_PITCH, _lag("Tp")),
        "WTTQA1": (*_WT_TORQUE, _lag("Tp"), _lag("Twref")),
    }
)

#: where the ibr_con table holds each model of `RULES`: (the model as messages name it, the
#: rows of the table that have it, its rules); a REGCA1 battery (``storage`` 1 with En > 0:
#: WECC REEC_C's state of charge) has an ESD1's state-of-charge limits and divides by its
#: Tf as an ESD1 does
COMPONENTS: tuple[tuple[str, Callable[[Any], Any], tuple[Rule, ...]], ...] = (
    ("PVD1", lambda t: t.type == PVD1, _PVD),
    ("ESD1", lambda t: t.type == ESD1, (*_PVD, *_ESD)),
    ("REGCA1", lambda t: t.type == REGCA1, _REGC),
    *(
        (name, lambda t, code=code: (t.type == REGCA1) & (t.reec == code), _REEC)
        for name, code in (("REECA1", REECA1), ("REECB1", REECB1), ("REECD1", REECD1))
    ),
    ("REECA1", lambda t: (t.type == REGCA1) & (t.reec == REECA1), _REEC_VDL_VOLTAGES),
    ("DERA1", lambda t: t.type == DERA1, _DERA_IQ),
    ("DERA1", lambda t: (t.type == DERA1) & (t.da_FreqFlag == 1), _DERA_FREQ),
    (
        "REGCA1 battery",
        lambda t: (t.type == REGCA1) & (t.storage == 1) & (t.En > 0),
        (*_SOC, _positive("Tf")),
    ),
    (
        "REPCA1",
        lambda t: (t.type == REGCA1) & (t.reec != 0) & (t.repc == REPCA1),
        tuple(r.prefixed("pc_") for r in _REPC),
    ),
    (
        "WTDTA1",
        lambda t: (t.type == REGCA1) & (t.wind == WTDTA1),
        tuple(r.prefixed("wt_") for r in _WT_SHAFT),
    ),
    (
        "WTDTA1/WTDS",
        lambda t: (t.type == REGCA1) & ((t.wind == WTDTA1) | (t.wind == WTDS)),
        tuple(r.prefixed("wt_") for r in (_nonnegative("DAMP", "the damping"), *_WT_SPEED)),
    ),
    (
        "WTPTA1",
        lambda t: (t.type == REGCA1) & (t.wind != 0) & (t.pitch == 1),
        (
            *(r.prefixed("wp_") for r in _WT_PITCH),
            # the aerodynamics' initial pitch angle within the pitch control's limits
            Rule(
                ("wa_theta0", "wp_thmin", "wp_thmax"),
                lambda a, lo, hi: (lo <= a) & (a <= hi),
                "wp_thmin <= wa_theta0 <= wp_thmax (the initial pitch angle within the "
                "pitch control's limits)",
            ),
        ),
    ),
    (
        "WTTQA1",
        lambda t: (t.type == REGCA1) & (t.wind != 0) & (t.torque == 1),
        tuple(r.prefixed("wq_") for r in _WT_TORQUE),
    ),
)
