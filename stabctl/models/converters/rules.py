"""The converter and battery data that cannot be, one table for every route the data come
by (`RULES`): an ANDES case file's rows as written (`stabctl.io.andes_case`, before ANDES
fills its defaults: ``import-andes``) and the ibr_con table of any case
(`stabctl.case.ConverterTable`, each component's rows as `COMPONENTS` finds them), so
that the same data is refused whichever way it reaches a run.  ANDES 2.0 runs them.

Sources: WECC REGC_A, REEC_A/B/C model specifications (as ANDES 2.0 ``renewable/
regca1.py``, ``reeca1.py``, ``reecb1.py`` implement them); ANDES 2.0 ``distributed/
pvd1.py``, ``esd1.py``; the equations' divisions and rest points (docs/ibr.md).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

from stabctl.models.converters.table import (
    ESD1,
    PVD1,
    REECA1,
    REECB1,
    REECD1,
    REGCA1,
)

__all__ = ["Rule", "RULES", "COMPONENTS"]


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


def _positive(name: str) -> Rule:
    return Rule((name,), lambda v: v > 0, f"{name} > 0")


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
#: 2.0 reeca1.py, reecb1.py: it freezes below Vdip and above Vup)
_REEC = (_positive("Imax"), Rule(("Vdip", "Vup"), lambda lo, hi: lo < hi, "Vdip < Vup"))
#: REGCA1's piecewise gains divide by Lvpnt1 - Lvpnt0 and Brkpt - Zerox (with its LVPL on);
#: its Iq lag's rate limits hold the rest point's rate 0 between them (WECC REGC_A; ANDES
#: 2.0 regca1.py)
_REGC = (
    Rule(("Lvpnt1", "Lvpnt0"), lambda hi, lo: hi > lo, "Lvpnt1 > Lvpnt0"),
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
)

#: physically impossible converter and battery data, refused whichever route the data
#: come by: an ANDES case file's rows as written (`stabctl.io.andes_case`, before ANDES
#: fills its defaults) and the ibr_con table of any case (`stabctl.case.ConverterTable`,
#: the components' rows by `COMPONENTS`): ANDES 2.0 model -> its rules.  ANDES runs them
RULES: Mapping[str, tuple[Rule, ...]] = MappingProxyType(
    {
        "PVD1": (_positive("ialim"),),
        "ESD1": (
            _positive("ialim"),
            _positive("En"),
            *_SOC,
            _positive("Tf"),
            _positive("EtaC"),
            _positive("EtaD"),
        ),
        "REGCA1": _REGC,
        "REGCP1": _REGC,
        "REECA1": _REEC,
        "REECA1E": _REEC,
        "REECB1": _REEC,
        # the case route's drive train check is `wind.check`'s
        "WTDTA1": (_positive("H"), Rule(("Htfrac",), lambda f: f < 1, "Htfrac < 1")),
    }
)

#: where the ibr_con table holds each model of `RULES`: (the model as messages name it, the
#: rows of the table that have it, its rules); a REGCA1 battery (``storage`` 1 with En > 0:
#: WECC REEC_C's state of charge) has an ESD1's state-of-charge limits and divides by its
#: Tf as an ESD1 does
COMPONENTS: tuple[tuple[str, Callable[[Any], Any], tuple[Rule, ...]], ...] = (
    ("PVD1", lambda t: t.type == PVD1, RULES["PVD1"]),
    ("ESD1", lambda t: t.type == ESD1, RULES["ESD1"]),
    ("REGCA1", lambda t: t.type == REGCA1, RULES["REGCA1"]),
    *(
        (name, lambda t, code=code: (t.type == REGCA1) & (t.reec == code), _REEC)
        for name, code in (("REECA1", REECA1), ("REECB1", REECB1), ("REECD1", REECD1))
    ),
    (
        "REGCA1 battery",
        lambda t: (t.type == REGCA1) & (t.storage == 1) & (t.En > 0),
        (*_SOC, _positive("Tf")),
    ),
)
