"""One declaration per dynamic-model parameter: :class:`Param`, :class:`DyrModel`,
:class:`Family`, and the four families ``MACHINE``, ``EXCITER``, ``PSS``, ``GOVERNOR``.

Each parameter of a PST dynamic-data matrix (``mac_con``, ``exc_con``, ``pss_con``,
``tg_con``) is declared here once: its table field name, unit, PST column, default for an
omitted trailing column, bounds and meaning.  Everything else is derived from it:

* the case tables of :mod:`stabctl.case.system` (fields in column order, ``DEFAULTS``,
  ``INTEGER``, the bound and choice checks, the column table of the docstring),
* the parameter classes and packed kernel columns of :mod:`stabctl.models` (field names
  are the table names; the ``E_*`` / ``S_*`` / ``G_*`` column constants are generated
  from the column order),
* the PSS/E DYR import of :mod:`stabctl.io.dyr` (each DYR model's parameter order and the
  table field each of its parameters is copied to).

Adding a model parameter is one :class:`Param` line; adding a DYR model one
:class:`DyrModel` (plus a mapper in :mod:`stabctl.io.dyr` for values it computes).

Sources: PST manual (Power System Toolbox 3.0, Rogers & Chow) section 3.22 Table 10
(``mac_con``), 3.11 Table 2 and 3.13 Table 3 (``exc_con``), 3.30 Table 13 (``pss_con``),
3.45 (``tg_con``); PSS/E Model Library (DYR parameter order, as ANDES
``andes/io/psse-dyr.yaml``); docs/pst_models.md for stabctl's extension columns.
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

__all__ = [
    "Param",
    "DyrModel",
    "Family",
    "MACHINE",
    "EXCITER",
    "PSS",
    "GOVERNOR",
    "CONVERTER",
    "FAMILIES",
]


@dataclass(frozen=True)
class Param:  # fields of a dataclass: numpydoc ignore=PR02
    """One column of a PST dynamic-data matrix, declared once.

    Parameters
    ----------
    name : str
        Table field name (``ExciterTable.KA``); also the name in the models' parameter
        classes and in messages (``field 'KA'``).
    unit : str
        Unit: ``"pu"`` (machine base unless said otherwise), ``"s"``, ``"deg"``,
        ``"MVA"``, ``""`` (dimensionless) or ``"code"`` (an integer selector).
    col : int
        1-based PST column (the PST manual's numbering).
    default : float, optional
        Value of the column when a PST matrix omits it (trailing columns), default 0.
    lo, hi : float or None, optional
        Inclusive bounds checked when a table is built; a value outside raises
        :class:`~stabctl.errors.CaseError` "``{table} row {r} ({key} {k}), field
        '{name}': must be >= {lo}, got {v}``".  None: unbounded.
    doc : str, optional
        Meaning, one line (goes into the table's docstring).
    integer : bool, optional
        The column must hold integers (numbers, codes).
    choices : tuple of float, optional
        Allowed values (checked at construction), e.g. the model types.
    label : str, optional
        What the choices message calls the field ("exciter type must be 0, 1 or 2");
        default the field name.
    alt : str, optional
        The column's name where another model reads it differently (``exc_con`` columns
        10-17 for the DC exciters, PST manual 3.11 Table 2: ``KE``, ``TE``, ...).
    """

    name: str
    unit: str
    col: int
    default: float = 0.0
    lo: float | None = None
    hi: float | None = None
    doc: str = ""
    integer: bool = False
    choices: tuple[float, ...] = ()
    label: str = ""
    alt: str = ""


@dataclass(frozen=True)
class DyrModel:  # fields of a dataclass: numpydoc ignore=PR02
    """How one PSS/E dynamic model's DYR record fills a table row.

    Parameters
    ----------
    name : str
        PSS/E model name (upper case), e.g. ``"SEXS"``.
    fields : tuple of str
        The numbers after the machine id, ICONs then CONs, in PSS/E Model Library order
        (their count is the record's required length).
    copy : Mapping[str, str]
        Table field <- DYR field for the parameters copied as given.  Table fields may be
        a column's ``alt`` name.  Values the importer computes (unit changes, products,
        saturation fits) are set by its mapper in :mod:`stabctl.io.dyr`.
    kind : int or None
        Value of the table's ``type`` column (None: the mapper chooses it, or the table
        has none).
    andes : tuple of str
        The ANDES 2.0 models whose parameters are this record's (ANDES's
        ``andes/io/psse-dyr.yaml`` maps each onto one ANDES parameter), read back as this
        record by :mod:`stabctl.io.andes_case`; empty when ANDES has no such model.

    Notes
    -----
    A record whose row is its copies and the machine number (no unit change, product or
    fit) needs no mapper of its own: :mod:`stabctl.io.dyr` maps it with its family's
    default, so adding such a model is this declaration and its model's kernel.
    """

    name: str
    fields: tuple[str, ...]
    copy: Mapping[str, str] = field(default_factory=dict)
    kind: int | None = None
    andes: tuple[str, ...] = ()

    def __post_init__(self):
        unknown = set(self.copy.values()) - set(self.fields)
        if unknown:
            raise ValueError(f"DYR model {self.name}: copies unknown fields {sorted(unknown)}")
        object.__setattr__(self, "copy", MappingProxyType(dict(self.copy)))

    def values(self, params) -> dict[str, float]:
        """DYR field name -> value of one record's numbers ``params`` (in ``fields`` order)."""
        return dict(zip(self.fields, params))


@dataclass(frozen=True)
class Family:  # fields of a dataclass: numpydoc ignore=PR02
    """The declaration of one PST dynamic-data matrix and the DYR models that fill it.

    Parameters
    ----------
    table : str
        PST matrix name (``"exc_con"``), used in messages.
    params : tuple of Param
        Every column, in PST column order (``params[k].col == k + 1``).
    min_columns : int
        Fewest columns a PST matrix may give (the rest take ``Param.default``).
    key, key_label : str
        Field identifying a row in messages, and what messages call it (``"machine"``).
    dyr : tuple of DyrModel, optional
        The PSS/E models imported into this table.

    Raises
    ------
    ValueError
        If columns are not 1, 2, ... in order, or a name or alternative name repeats.
    """

    table: str
    params: tuple[Param, ...]
    min_columns: int
    key: str
    key_label: str
    dyr: tuple[DyrModel, ...] = ()

    def __post_init__(self):
        for k, p in enumerate(self.params):
            if p.col != k + 1:
                raise ValueError(
                    f"{self.table}: parameter {p.name} declared as column {p.col}, "
                    f"is column {k + 1}"
                )
        names = [p.name for p in self.params] + [p.alt for p in self.params if p.alt]
        if len(set(names)) != len(names):
            raise ValueError(f"{self.table}: a parameter name or alternative name repeats")

    @property
    def names(self) -> tuple[str, ...]:
        """Field names in PST column order."""
        return tuple(p.name for p in self.params)

    @property
    def defaults(self) -> Mapping[str, float]:
        """Field -> value of an omitted trailing column, for the non-zero defaults."""
        return MappingProxyType({p.name: p.default for p in self.params if p.default != 0})

    @property
    def integer(self) -> tuple[str, ...]:
        """Fields that must hold integers."""
        return tuple(p.name for p in self.params if p.integer)

    def param(self, name: str) -> Param:
        """The declaration of field ``name`` or of the column whose ``alt`` name it is.

        Raises
        ------
        KeyError
            If no column has that name.
        """
        for p in self.params:
            if name in (p.name, p.alt):
                return p
        raise KeyError(f"{self.table} has no parameter {name!r}")

    def col(self, name: str) -> int:
        """1-based PST column of field (or alternative name) ``name``."""
        return self.param(name).col

    def dyr_model(self, name: str) -> DyrModel:
        """The DYR model ``name`` of this family (KeyError if not declared)."""
        for m in self.dyr:
            if m.name == name:
                return m
        raise KeyError(name)

    def dyr_row(self, model: DyrModel, params, **computed) -> list[float]:
        """One table row (all columns, zeros where nothing is given) from a DYR record.

        Parameters
        ----------
        model : DyrModel
            The record's model.
        params : sequence of float
            The record's numbers after the id, in ``model.fields`` order.
        **computed : float
            Table fields (or alternative names) set by the importer, applied after the
            copied fields (and after ``model.kind``).

        Returns
        -------
        list of float
            The row, one value per declared column, PST column order.
        """
        row = [0.0] * len(self.params)
        vals = model.values(params)
        if model.kind is not None:
            row[0] = float(model.kind)
        for name, src in model.copy.items():
            row[self.col(name) - 1] = float(vals[src])
        for name, v in computed.items():
            row[self.col(name) - 1] = float(v)
        return row

    def rst_table(self) -> str:
        """The column table of the table class's docstring (reStructuredText)."""
        width = max(len(p.name) for p in self.params)
        units = [p.unit if p.unit != "code" else "" for p in self.params]
        uw = max(4, *(len(u) for u in units))
        rule = f"    ==  {'=' * width}  {'=' * uw}  {'=' * 60}"
        lines = [rule, f"    {'':<2}  {'name':<{width}}  {'unit':<{uw}}  meaning", rule]
        for p, unit in zip(self.params, units):
            lines.append(f"    {p.col:<2}  {p.name:<{width}}  {unit:<{uw}}  {p.doc}")
        lines.append(rule)
        return "\n".join(lines)


def _choices_text(values) -> str:
    """'0, 1, 2 or 3' for the choices message."""
    txt = [str(int(v)) if float(v).is_integer() else repr(v) for v in values]
    return txt[0] if len(txt) == 1 else ", ".join(txt[:-1]) + " or " + txt[-1]


def choices_message(p: Param) -> str:
    """The message of a value not in ``p.choices``: '{label} must be 0, 1 or 2'."""
    return f"{p.label or p.name} must be {_choices_text(p.choices)}"


# --------------------------------------------------------------------------------------
# mac_con: synchronous machines (PST manual 3.22 Table 10)
# --------------------------------------------------------------------------------------

_REACT: dict[str, Any] = dict(unit="pu", lo=0.0)
_TC: dict[str, Any] = dict(unit="s", lo=0.0)

MACHINE = Family(
    table="mac_con",
    min_columns=16,
    key="number",
    key_label="machine",
    params=(
        Param("number", "code", 1, integer=True, doc="machine number"),
        Param("bus", "code", 2, integer=True, doc="bus number"),
        Param("mva", "MVA", 3, doc="machine base"),
        Param("xl", col=4, doc="leakage reactance", **_REACT),
        Param("ra", col=5, doc="armature resistance", **_REACT),
        Param("xd", col=6, doc="d-axis synchronous reactance (0: classical model)", **_REACT),
        Param("xdp", col=7, doc="d-axis transient reactance x'd", **_REACT),
        Param(
            "xdpp", col=8, doc='d-axis subtransient reactance x"d (0: transient model)', **_REACT
        ),
        Param("Tdop", col=9, doc="d-axis open-circuit transient time constant T'do", **_TC),
        Param("Tdopp", col=10, doc='d-axis open-circuit subtransient time constant T"do', **_TC),
        Param("xq", col=11, doc="q-axis synchronous reactance", **_REACT),
        Param("xqp", col=12, doc="q-axis transient reactance x'q", **_REACT),
        Param("xqpp", col=13, doc='q-axis subtransient reactance x"q', **_REACT),
        Param(
            "Tqop", col=14, doc="q-axis open-circuit transient time constant T'qo (0 kept)", **_TC
        ),
        Param("Tqopp", col=15, doc='q-axis open-circuit subtransient time constant T"qo', **_TC),
        Param("H", "s", 16, doc="inertia constant (MW s / MVA on machine base)"),
        Param("D0", "pu", 17, doc="local damping coefficient d_o"),
        Param("D1", "pu", 18, doc="system damping coefficient d_1"),
        Param("col19", "", 19, doc='"bus number" in the manual; unused by PSTess, kept as given'),
        Param("S10", "", 20, doc="saturation factor S(1.0)"),
        Param("S12", "", 21, doc="saturation factor S(1.2)"),
        Param("pfrac", "", 22, default=1.0, doc="fraction of the bus generation P"),
        Param("qfrac", "", 23, default=1.0, doc="fraction of the bus generation Q"),
        Param(
            "speed_effects",
            "code",
            24,
            default=1.0,
            choices=(0.0, 1.0),
            doc="subtransient: 1 stator voltage and torque with speed (PST mac_sub), "
            "0 without (ANDES GENROU/GENSAL)",
        ),
        Param(
            "psse_sat",
            "code",
            25,
            default=0.0,
            choices=(0.0, 1.0),
            doc="subtransient: 0 no saturation (PST mac_sub as modelled here), 1 PSS/E's "
            'GENROU saturation of the air-gap flux |psi"| through S(1.0), S(1.2) '
            "(ANDES GENROU/GENSAL)",
        ),
    ),
    dyr=(
        # GENROU -> mac_sub with x"q = x"d (set by the importer)
        DyrModel(
            "GENROU",
            (
                "T'do",
                "T''do",
                "T'qo",
                "T''qo",
                "H",
                "D",
                "Xd",
                "Xq",
                "X'd",
                "X'q",
                "X''d",
                "Xl",
                "S(1.0)",
                "S(1.2)",
            ),
            {
                "Tdop": "T'do",
                "Tdopp": "T''do",
                "Tqop": "T'qo",
                "Tqopp": "T''qo",
                "H": "H",
                "D0": "D",
                "xd": "Xd",
                "xq": "Xq",
                "xdp": "X'd",
                "xqp": "X'q",
                "xdpp": "X''d",
                "xl": "Xl",
                "S10": "S(1.0)",
                "S12": "S(1.2)",
            },
            andes=("GENROU",),
        ),
        # GENSAL -> mac_sub without the q-axis transient circuit (x'q = x_q, T'qo = 0)
        DyrModel(
            "GENSAL",
            (
                "T'do",
                "T''do",
                "T''qo",
                "H",
                "D",
                "Xd",
                "Xq",
                "X'd",
                "X''d",
                "Xl",
                "S(1.0)",
                "S(1.2)",
            ),
            {
                "Tdop": "T'do",
                "Tdopp": "T''do",
                "Tqopp": "T''qo",
                "H": "H",
                "D0": "D",
                "xd": "Xd",
                "xq": "Xq",
                "xdp": "X'd",
                "xdpp": "X''d",
                "xl": "Xl",
                "S10": "S(1.0)",
                "S12": "S(1.2)",
            },
        ),
        # GENCLS -> mac_em behind x'd = ZSORCE X (set by the importer)
        DyrModel(
            "GENCLS",
            ("H", "D"),
            {"H": "H", "D0": "D"},
            andes=("GENCLS",),
        ),
    ),
)


# --------------------------------------------------------------------------------------
# exc_con: exciters (PST manual 3.38 Table 15, 3.11 Table 2, 3.13 Table 3; docs 2.3-2.4)
# --------------------------------------------------------------------------------------


def _upper(*names: str, **renamed: str) -> dict[str, str]:
    """DYR copies of table fields whose PSS/E name is theirs in upper case (``"Vrmax"`` <-
    ``"VRMAX"``), and of ``renamed`` fields (table field=DYR name)."""
    return {**{n: n.upper() for n in names}, **renamed}


#: the copies the IEEE 1968 DC records IEEET1 and IEEET2 share (PSS/E Model Library)
_IEEET_COPY = {
    "TR": "TR",
    "KA": "KA",
    "TA": "TA",
    "Vrmax": "VRMAX",
    "Vrmin": "VRMIN",
    "KE": "KE",
    "TE": "TE",
    "KF_dc": "KF",
}

EXCITER = Family(
    table="exc_con",
    min_columns=9,
    key="machine",
    key_label="machine",
    params=(
        Param(
            "type",
            "code",
            1,
            integer=True,
            choices=(0, 1, 2, 3, 4, 5, 6, 7, 8),
            label="exciter type",
            doc="0 simple (smpexc), 1 DC1, 2 DC2 (exc_dc12), 3 ST3 (exc_st3), 4 EXST1, "
            "5 IEEET2 (DC1 with a two-lag rate feedback), 6 ESST1A (IEEE 421.5 ST1A), "
            "7 EXAC1 (IEEE AC1), 8 EXAC4 (IEEE AC4)",
        ),
        Param("machine", "code", 2, integer=True, doc="machine number"),
        Param("TR", "s", 3, lo=0.0, doc="input filter time constant"),
        Param("KA", "", 4, doc="voltage regulator gain"),
        Param("TA", "s", 5, lo=0.0, doc="voltage regulator time constant"),
        Param("TB", "s", 6, lo=0.0, doc="transient gain reduction time constant"),
        Param("TC", "s", 7, doc="transient gain reduction time constant"),
        Param("Vrmax", "pu", 8, doc="maximum regulator output"),
        Param("Vrmin", "pu", 9, doc="minimum regulator output"),
        Param(
            "VImax",
            "pu",
            10,
            alt="KE",
            doc="ST3, EXST1: max internal signal | DC1/2, EXAC1: KE exciter constant",
        ),
        Param(
            "VImin",
            "pu",
            11,
            alt="TE",
            doc="ST3, EXST1: min internal signal | DC1/2, EXAC1: TE exciter time constant, s",
        ),
        Param("KJ", "", 12, alt="E1", doc="ST3: first stage regulator gain | DC1/2, EXAC1: E1, pu"),
        Param("KP", "", 13, alt="SE1", doc="ST3: potential circuit gain | DC1/2, EXAC1: SE(E1)"),
        Param(
            "thetaP", "deg", 14, alt="E2", doc="ST3: potential circuit angle | DC1/2, EXAC1: E2, pu"
        ),
        Param("KI", "", 15, alt="SE2", doc="ST3: current circuit gain | DC1/2, EXAC1: SE(E2)"),
        Param(
            "XL",
            "pu",
            16,
            alt="KF_dc",
            doc="ST3: potential source reactance | DC1/2: KF stabilizer gain",
        ),
        Param(
            "KC",
            "",
            17,
            alt="TF_dc",
            doc="ST3, EXST1, ESST1A, EXAC1, EXAC4: rectifier loading factor | DC1/2: TF "
            "stabilizer time constant, s",
        ),
        Param(
            "Efdmax",
            "pu",
            18,
            alt="TF2",
            doc="ST3: maximum field voltage | IEEET2: second rate feedback time constant TF2, s",
        ),
        Param(
            "KG",
            "",
            19,
            alt="bus_fed",
            doc="ST3: inner loop feedback constant | smpexc: 1 the output times the "
            "terminal voltage (bus-fed SCRX), 0 not",
        ),
        Param("VGmax", "pu", 20, doc="ST3: maximum inner loop feedback"),
        Param("KF", "", 21, doc="EXST1, ESST1A, EXAC1: rate feedback gain"),
        Param("TF", "s", 22, doc="EXST1, ESST1A, EXAC1: rate feedback time constant"),
        Param(
            "dc_sat",
            "code",
            23,
            choices=(0, 1),
            doc="DC1/2 saturation through (E1, SE1), (E2, SE2): 0 PST's exponential, "
            "1 PSS/E's quadratic",
        ),
        Param(
            "ke_given",
            "code",
            24,
            choices=(0, 1),
            doc="DC1/2: 0 K_E = 0 computed so that V_R starts at 0 (PST), 1 as given (ANDES)",
        ),
        Param(
            "ifd_machine",
            "code",
            25,
            choices=(0, 1),
            doc="ST3: field current of I_N = K_C I_fd / V_E, 0 PST exc_st3's own estimate "
            "E_Isat(E'q) + p6 (E'q - psi_kd) + p7 i_d, 1 the machine's (IEEE 421.5 "
            "I_FD; ANDES esst3a.py XadIfd)",
        ),
        Param("TC1", "s", 26, doc="ESST1A: second lead time constant"),
        Param("TB1", "s", 27, lo=0.0, doc="ESST1A: second lag time constant"),
        Param("VAmax", "pu", 28, doc="ESST1A: maximum regulator output V_A"),
        Param("VAmin", "pu", 29, doc="ESST1A: minimum regulator output V_A"),
        Param("KLR", "", 30, doc="ESST1A: field current limiter gain"),
        Param("ILR", "pu", 31, doc="ESST1A: field current limiter pick-up (machine base)"),
        Param("KD", "", 32, doc="EXAC1: demagnetising factor of the field current"),
        Param(
            "VBmax",
            "pu",
            33,
            lo=0.0,
            doc="ST3: upper limit of the source voltage V_B = V_E F_EX (PSS/E ESST3A "
            "VBMAX); 0 none (PST exc_st3)",
        ),
    ),
    dyr=(
        # SEXS -> smpexc: T_C = (TA/TB) TB is computed
        DyrModel(
            "SEXS",
            ("TA/TB", "TB", "K", "TE", "EMIN", "EMAX"),
            {"KA": "K", "TA": "TE", "TB": "TB", "Vrmax": "EMAX", "Vrmin": "EMIN"},
            kind=0,
            andes=("SEXS",),
        ),
        *(
            DyrModel(
                name,
                (
                    "TR",
                    "KA",
                    "TA",
                    "TB",
                    "TC",
                    "VRMAX",
                    "VRMIN",
                    "KE",
                    "TE",
                    "KF",
                    "TF1",
                    "Switch",
                    "E1",
                    "SE(E1)",
                    "E2",
                    "SE(E2)",
                ),
                {
                    "TR": "TR",
                    "KA": "KA",
                    "TA": "TA",
                    "TB": "TB",
                    "TC": "TC",
                    "Vrmax": "VRMAX",
                    "Vrmin": "VRMIN",
                    "KE": "KE",
                    "TE": "TE",
                    "KF_dc": "KF",
                    "TF_dc": "TF1",
                },
                kind=kind,
                andes=(name,),
            )
            for name, kind in (("IEEEX1", 1), ("EXDC2", 2), ("ESDC2A", 2))
        ),
        # IEEET1 (IEEE 1968 type 1) -> DC1 (type 1) without the lead-lag (TB = TC = 0)
        DyrModel(
            "IEEET1",
            (
                "TR",
                "KA",
                "TA",
                "VRMAX",
                "VRMIN",
                "KE",
                "TE",
                "KF",
                "TF",
                "Switch",
                "E1",
                "SE(E1)",
                "E2",
                "SE(E2)",
            ),
            {**_IEEET_COPY, "TF_dc": "TF"},
            kind=1,
            andes=("IEEET1",),
        ),
        # IEEET2 -> DC1 (type 5) with the rate feedback s KF/((1 + s TF1)(1 + s TF2))
        DyrModel(
            "IEEET2",
            (
                "TR",
                "KA",
                "TA",
                "VRMAX",
                "VRMIN",
                "KE",
                "TE",
                "KF",
                "TF1",
                "TF2",
                "E1",
                "SE(E1)",
                "E2",
                "SE(E2)",
            ),
            {**_IEEET_COPY, "TF_dc": "TF1", "TF2": "TF2"},
            kind=5,
        ),
        # SCRX -> smpexc: T_C = (TA/TB) TB computed; CSWITCH 0 (bus fed): bus_fed = 1
        DyrModel(
            "SCRX",
            ("TA/TB", "TB", "K", "TE", "EMIN", "EMAX", "CSWITCH", "rc/rfd"),
            {"KA": "K", "TA": "TE", "TB": "TB", "Vrmax": "EMAX", "Vrmin": "EMIN"},
            kind=0,
        ),
        DyrModel(
            "EXST1",
            ("TR", "VIMAX", "VIMIN", "TC", "TB", "KA", "TA", "VRMAX", "VRMIN", "KC", "KF", "TF"),
            _upper(
                "TR", "KA", "TA", "TB", "TC", "Vrmax", "Vrmin", "VImax", "VImin", "KC", "KF", "TF"
            ),
            kind=4,
            andes=("EXST1",),
        ),
        # EXAC1 -> type 7 (IEEE 1981 AC1); saturation: PSS/E's quadratic through the points
        DyrModel(
            "EXAC1",
            (
                "TR",
                "TB",
                "TC",
                "KA",
                "TA",
                "VRMAX",
                "VRMIN",
                "TE",
                "KF",
                "TF",
                "KC",
                "KD",
                "KE",
                "E1",
                "SE(E1)",
                "E2",
                "SE(E2)",
            ),
            _upper(
                "TR",
                "TB",
                "TC",
                "KA",
                "TA",
                "Vrmax",
                "Vrmin",
                "TE",
                "KF",
                "TF",
                "KC",
                "KD",
                "KE",
                "E1",
                "E2",
                SE1="SE(E1)",
                SE2="SE(E2)",
            ),
            kind=7,
            andes=("EXAC1",),
        ),
        # EXAC4 -> type 8 (IEEE 1981 AC4)
        DyrModel(
            "EXAC4",
            ("TR", "VIMAX", "VIMIN", "TC", "TB", "KA", "TA", "VRMAX", "VRMIN", "KC"),
            _upper("TR", "VImax", "VImin", "TC", "TB", "KA", "TA", "Vrmax", "Vrmin", "KC"),
            kind=8,
            andes=("EXAC4",),
        ),
        # ESST1A -> type 6; UEL (no under-excitation limiter is modelled: no signal) and
        # VOS (1: the stabiliser at the voltage error) are checked by the mapper
        DyrModel(
            "ESST1A",
            (
                "UEL",
                "VOS",
                "TR",
                "VIMAX",
                "VIMIN",
                "TC",
                "TB",
                "TC1",
                "TB1",
                "KA",
                "TA",
                "VAMAX",
                "VAMIN",
                "VRMAX",
                "VRMIN",
                "KC",
                "KF",
                "TF",
                "KLR",
                "ILR",
            ),
            _upper(
                "TR",
                "VImax",
                "VImin",
                "TC",
                "TB",
                "TC1",
                "TB1",
                "KA",
                "TA",
                "VAmax",
                "VAmin",
                "Vrmax",
                "Vrmin",
                "KC",
                "KF",
                "TF",
                "KLR",
                "ILR",
            ),
            kind=6,
            andes=("ESST1A",),
        ),
        # ESST3A -> exc_st3 (TA = 0): its KA is PST's K_J, its inner loop KM/(1 + s TM)
        # limited [VMMIN, VMMAX] PST's K_A/(1 + s T_A); VBMAX limits V_B (column 33);
        # Efdmax = VBMAX VMMAX is computed
        DyrModel(
            "ESST3A",
            (
                "TR",
                "VIMAX",
                "VIMIN",
                "KM",
                "TC",
                "TB",
                "KA",
                "TA",
                "VRMAX",
                "VRMIN",
                "KG",
                "KP",
                "KI",
                "VBMAX",
                "KC",
                "XL",
                "VGMAX",
                "THETAP",
                "TM",
                "VMMAX",
                "VMMIN",
            ),
            {
                "TR": "TR",
                "KA": "KM",
                "TA": "TM",
                "TB": "TB",
                "TC": "TC",
                "Vrmax": "VMMAX",
                "Vrmin": "VMMIN",
                "VImax": "VIMAX",
                "VImin": "VIMIN",
                "KJ": "KA",
                "KP": "KP",
                "thetaP": "THETAP",
                "KI": "KI",
                "XL": "XL",
                "KC": "KC",
                "KG": "KG",
                "VGmax": "VGMAX",
                "VBmax": "VBMAX",
            },
            kind=3,
            andes=("ESST3A",),
        ),
    ),
)


# --------------------------------------------------------------------------------------
# pss_con: power system stabilisers (PST manual 3.30 Table 13; docs 3.1)
# --------------------------------------------------------------------------------------

PSS = Family(
    table="pss_con",
    min_columns=10,
    key="machine",
    key_label="machine",
    params=(
        Param(
            "type",
            "code",
            1,
            integer=True,
            choices=(1, 2, 3, 4),
            label="pss type",
            doc="1 PST pss, speed input; 2 PST pss, electrical power input; 3 PSS/E; "
            "4 PSS/E STAB2A",
        ),
        Param("machine", "code", 2, integer=True, doc="machine number"),
        Param(
            "KTw", "", 3, doc="gain times washout time constant (K*Tw); type 3: washout gain K_w"
        ),
        Param("Tw", "s", 4, lo=0.0, doc="washout time constant"),
        Param("T1", "s", 5, doc="first lead time constant"),
        Param("T2", "s", 6, lo=0.0, doc="first lag time constant"),
        Param("T3", "s", 7, doc="second lead time constant"),
        Param("T4", "s", 8, lo=0.0, doc="second lag time constant"),
        Param("ymax", "pu", 9, doc="maximum output"),
        Param("ymin", "pu", 10, doc="minimum output"),
        Param(
            "T5",
            "s",
            11,
            alt="K5",
            doc="type 3: third lead time constant | type 4: output lag gain K5",
        ),
        Param("T6", "s", 12, lo=0.0, doc="type 3: third lag time constant"),
        Param(
            "input1",
            "code",
            13,
            integer=True,
            doc="type 3: first input, PSS/E code (1 speed deviation, 3 electrical power)",
        ),
        Param("K1", "", 14, doc="type 3: first input gain"),
        Param("Tr1", "s", 15, lo=0.0, doc="type 3: first input transducer time constant"),
        Param("input2", "code", 16, integer=True, doc="type 3: second input, PSS/E code (0 none)"),
        Param("K2", "", 17, doc="type 3: second input gain"),
        Param("Tr2", "s", 18, lo=0.0, doc="type 3: second input transducer time constant"),
        *(
            Param(
                f"A{k}",
                "s" if k % 2 else "s^2",
                18 + k,
                doc=f"type 3: filter (1 + A5 s + A6 s^2)/((1 + A1 s + A2 s^2)(1 + A3 s + "
                f"A4 s^2)), A{k}",
            )
            for k in range(1, 7)
        ),
    ),
    dyr=(
        # IEEEST -> PST pss (types 1, 2) when exactly equivalent, else type 3; the mapper
        # chooses the type and computes K_Tw = KS T5
        DyrModel(
            "IEEEST",
            (
                "ICS",
                "IB",
                "A1",
                "A2",
                "A3",
                "A4",
                "A5",
                "A6",
                "T1",
                "T2",
                "T3",
                "T4",
                "T5",
                "T6",
                "KS",
                "LSMAX",
                "LSMIN",
                "VCU",
                "VCL",
            ),
            {"Tw": "T6", "ymax": "LSMAX", "ymin": "LSMIN"},
            andes=("IEEEST",),
        ),
        DyrModel(
            "ST2CUT",
            (
                "MODE",
                "BUSR",
                "MODE2",
                "BUSR2",
                "K1",
                "K2",
                "T1",
                "T2",
                "T3",
                "T4",
                "T5",
                "T6",
                "T7",
                "T8",
                "T9",
                "T10",
                "LSMAX",
                "LSMIN",
                "VCU",
                "VCL",
            ),
            {
                "input1": "MODE",
                "K1": "K1",
                "Tr1": "T1",
                "input2": "MODE2",
                "K2": "K2",
                "Tr2": "T2",
                "KTw": "T3",
                "Tw": "T4",
                "T1": "T5",
                "T2": "T6",
                "T3": "T7",
                "T4": "T8",
                "T5": "T9",
                "T6": "T10",
                "ymax": "LSMAX",
                "ymin": "LSMIN",
            },
            kind=3,
            andes=("ST2CUT",),
        ),
        # STAB2A -> type 4: three washouts K2 T2 s/(1 + s T2) (KTw = K2 T2 computed), K3/(1 +
        # s T3) + K4, two lags K5/(1 + s T5), output limits +-HLIM
        DyrModel(
            "STAB2A",
            ("K2", "T2", "K3", "T3", "K4", "K5", "T5", "HLIM"),
            {
                "Tw": "T2",
                "K1": "K3",
                "Tr1": "T3",
                "K2": "K4",
                "K5": "K5",
                "T6": "T5",
                "ymax": "HLIM",
            },
            kind=4,
        ),
    ),
)


# --------------------------------------------------------------------------------------
# tg_con: turbine-governors (PST manual 3.45; PSS/E TGOV1, IEEEG1; docs section 4)
# --------------------------------------------------------------------------------------

#: tg_con columns 17-21 (IEEEG1's K1..K5) as HYGOV reads them: (alternative name, doc)
_HYGOV_ALT = {
    1: ("Rp", " | HYGOV: permanent droop R, pu"),
    2: ("rt", " | HYGOV: temporary droop r, pu"),
    3: ("qNL", " | HYGOV: no-load flow qNL, pu"),
    4: ("Kg", " | HYGOV: gate integrator gain, 1/s (PSS/E: 1/(r Tr))"),
    5: ("velm_rel", " | HYGOV: 1 gate rate limits [-VELM, VELM] - e/r (ANDES), 0 [-VELM, VELM]"),
}

GOVERNOR = Family(
    table="tg_con",
    min_columns=10,
    key="machine",
    key_label="machine",
    params=(
        Param(
            "type",
            "code",
            1,
            integer=True,
            choices=(1, 2, 3, 4, 5, 6),
            label="governor type",
            doc="1 PST tg, 2 TGOV1, 3 IEEEG1, 4 HYGOV, 5 IEESGO, 6 GAST",
        ),
        Param("machine", "code", 2, integer=True, doc="machine number"),
        Param("wf", "pu", 3, doc="speed set point"),
        Param("invR", "pu", 4, doc="steady-state gain 1/R (IEEEG1: K), on machine base"),
        Param("Tmax", "pu", 5, doc="maximum power order (TGOV1: VMAX, IEEEG1: PMAX)"),
        Param("Ts", "s", 6, lo=0.0, doc="servo time constant (TGOV1: T1; IEEEG1: T3, gate servo)"),
        Param("Tc", "s", 7, lo=0.0, doc="governor lag time constant (TGOV1: T3; IEEEG1: T1)"),
        Param("T3", "s", 8, doc="transient gain (lead) time constant (TGOV1, IEEEG1: T2)"),
        Param(
            "T4",
            "s",
            9,
            alt="Tw",
            doc="HP section time constant (IEEEG1: T4, steam "
            "chest); < 0 hydro | HYGOV: water time constant Tw",
        ),
        Param(
            "T5",
            "s",
            10,
            lo=0.0,
            alt="At",
            doc="reheater time constant (IEEEG1: T5) | HYGOV: turbine gain At",
        ),
        Param(
            "Tmin", "pu", 11, doc="minimum power order (tg: 0 as PST; TGOV1: VMIN; IEEEG1: PMIN)"
        ),
        Param("Dt", "pu", 12, doc="turbine damping (TGOV1), pu power / pu speed"),
        Param("T6", "s", 13, lo=0.0, doc="IEEEG1 third turbine time constant"),
        Param("T7", "s", 14, lo=0.0, doc="IEEEG1 fourth turbine time constant"),
        Param("Uo", "pu/s", 15, doc="IEEEG1 maximum valve opening rate"),
        Param("Uc", "pu/s", 16, doc="IEEEG1 maximum valve closing rate (< 0)"),
        *(
            Param(
                f"K{k}",
                "",
                16 + k,
                alt=_HYGOV_ALT.get(k, ("", ""))[0],
                doc=f"IEEEG1 fraction of power after T{3 + (k + 1) // 2} "
                f"({'HP' if k % 2 else 'LP'} shaft)" + _HYGOV_ALT.get(k, ("", ""))[1],
            )
            for k in range(1, 9)
        ),
        Param("AT", "pu", 25, doc="GAST ambient temperature load limit"),
        Param("KT", "", 26, doc="GAST temperature limiter gain"),
    ),
    dyr=(
        # TGOV1: invR = 1/R is computed
        DyrModel(
            "TGOV1",
            ("R", "T1", "VMAX", "VMIN", "T2", "T3", "Dt"),
            {"Tmax": "VMAX", "Tmin": "VMIN", "Ts": "T1", "Tc": "T3", "T3": "T2", "Dt": "Dt"},
            kind=2,
            andes=("TGOV1", "TGOV1N"),
        ),
        DyrModel(
            "IEEEG1",
            (
                "JBUS",
                "M",
                "K",
                "T1",
                "T2",
                "T3",
                "Uo",
                "Uc",
                "PMAX",
                "PMIN",
                "T4",
                "K1",
                "K2",
                "T5",
                "K3",
                "K4",
                "T6",
                "K5",
                "K6",
                "T7",
                "K7",
                "K8",
            ),
            {
                "invR": "K",
                "Tc": "T1",
                "T3": "T2",
                "Ts": "T3",
                "Uo": "Uo",
                "Uc": "Uc",
                "Tmax": "PMAX",
                "Tmin": "PMIN",
                "T4": "T4",
                "T5": "T5",
                "T6": "T6",
                "T7": "T7",
                **{f"K{k}": f"K{k}" for k in range(1, 9)},
            },
            kind=3,
            andes=("IEEEG1",),
        ),
        # HYGOV -> type 4: Kg = 1/(r Tr) and Uc = -VELM computed
        DyrModel(
            "HYGOV",
            ("R", "r", "Tr", "Tf", "Tg", "VELM", "GMAX", "GMIN", "TW", "At", "Dturb", "qNL"),
            {
                "Rp": "R",
                "rt": "r",
                "T3": "Tr",
                "Tc": "Tf",
                "Ts": "Tg",
                "Uo": "VELM",
                "Tmax": "GMAX",
                "Tmin": "GMIN",
                "Tw": "TW",
                "At": "At",
                "Dt": "Dturb",
                "qNL": "qNL",
            },
            kind=4,
            andes=("HYGOV",),
        ),
        # IEESGO -> type 5: K1 (speed gain), lag T1, lead-lag T2/T3, limits, lags T4-T6;
        # the power fractions after T4, T5, T6 (1 - K2, (1 - K3) K2, K2 K3) computed
        DyrModel(
            "IEESGO",
            ("T1", "T2", "T3", "T4", "T5", "T6", "K1", "K2", "K3", "PMAX", "PMIN"),
            {
                "Tc": "T1",
                "T3": "T2",
                "Ts": "T3",
                "T4": "T4",
                "T5": "T5",
                "T6": "T6",
                "invR": "K1",
                "Tmax": "PMAX",
                "Tmin": "PMIN",
            },
            kind=5,
            andes=("IEESGO",),
        ),
        # GAST -> type 6: invR = 1/R is computed; T1 the valve (Ts), T2 the power lag (Tc), T3
        # the load-limit feedback lag
        DyrModel(
            "GAST",
            ("R", "T1", "T2", "T3", "AT", "KT", "VMAX", "VMIN", "Dturb"),
            {
                "Ts": "T1",
                "Tc": "T2",
                "T3": "T3",
                "AT": "AT",
                "KT": "KT",
                "Tmax": "VMAX",
                "Tmin": "VMIN",
                "Dt": "Dturb",
            },
            kind=6,
            andes=("GAST",),
        ),
    ),
)

# --------------------------------------------------------------------------------------
# ibr_con: converter-interfaced devices (stabctl's table; ANDES 2.0 PVD1, ESD1, REGCA1)
# --------------------------------------------------------------------------------------

#: ANDES's converter types: PVD1 (WECC distributed PV), ESD1 (PVD1 with a state of charge),
#: REGCA1 (WECC second-generation renewable generator/converter, REGC_A)
PVD1, ESD1, REGCA1 = 1, 2, 3

_DEV_PU: dict[str, Any] = dict(unit="pu")  # on the device base mva (ANDES ``power=True``)

CONVERTER = Family(
    table="ibr_con",
    min_columns=8,
    key="number",
    key_label="converter",
    params=(
        Param("number", "code", 1, integer=True, doc="converter number"),
        Param("bus", "code", 2, integer=True, doc="bus number"),
        Param(
            "type",
            "code",
            3,
            integer=True,
            choices=(PVD1, ESD1, REGCA1),
            label="converter type",
            doc="1 PVD1 (ANDES distributed PV), 2 ESD1 (PVD1 with a state of charge), "
            "3 REGCA1 (WECC renewable generator/converter, constant current commands)",
        ),
        Param("mva", "MVA", 4, default=100.0, lo=0.0, doc="device base Sn"),
        Param("pfrac", "", 5, default=1.0, doc="fraction of the bus generation P (ANDES gammap)"),
        Param("qfrac", "", 6, default=1.0, doc="fraction of the bus generation Q (ANDES gammaq)"),
        Param(
            "xc",
            col=7,
            lo=0.0,
            doc="coupling reactance of the Q-droop's compensated voltage (device base)",
            **_DEV_PU,
        ),
        Param(
            "pqflag",
            "code",
            8,
            choices=(0.0, 1.0),
            doc="current-limit priority: 0 reactive (Q), 1 active (P)",
        ),
        Param("qmx", col=9, default=0.33, doc="maximum reactive power command", **_DEV_PU),
        Param("qmn", col=10, default=-0.33, doc="minimum reactive power command", **_DEV_PU),
        Param(
            "pmx",
            col=11,
            default=9999.0,
            doc="maximum active power command (ESD1: -pmx the minimum)",
            **_DEV_PU,
        ),
        Param("v0", "pu", 12, default=0.8, doc="lower voltage of the Q-droop deadband"),
        Param("v1", "pu", 13, default=1.1, doc="upper voltage of the Q-droop deadband"),
        Param("dqdv", col=14, default=-1.0, doc="Q-V droop (< 0), pu Q per pu V", **_DEV_PU),
        Param("fdbd", "Hz", 15, default=-0.017, hi=0.0, doc="frequency deadband (<= 0)"),
        Param(
            "ddn",
            "pu/Hz",
            16,
            lo=0.0,
            doc="P droop gain beyond the deadband, pu (device base) per Hz",
        ),
        Param("ialim", col=17, default=1.3, lo=0.0, doc="apparent current limit", **_DEV_PU),
        *(
            Param(f"vt{k}", "pu", 18 + k, default=d, lo=0.0, doc=f"voltage trip curve point {k}")
            for k, d in enumerate((0.88, 0.90, 1.1, 1.2))
        ),
        *(
            Param(f"ft{k}", "Hz", 22 + k, default=d, lo=0.0, doc=f"frequency trip curve point {k}")
            for k, d in enumerate((59.5, 59.7, 60.3, 60.5))
        ),
        Param("tip", "s", 26, default=0.02, lo=0.0, doc="active current lag time constant"),
        Param("tiq", "s", 27, default=0.02, lo=0.0, doc="reactive current lag time constant"),
        Param(
            "recflag",
            "code",
            28,
            default=1.0,
            choices=(0.0, 1.0),
            doc="1 the currents times the voltage and frequency trip curves, 0 without",
        ),
        Param(
            "plim",
            "code",
            29,
            default=1.0,
            choices=(0.0, 1.0),
            doc="1 the power order limited to [0, pmx] (ESD1 [-pmx, pmx]), 0 not (ANDES plim)",
        ),
        Param(
            "Tfm",
            "s",
            30,
            default=0.02,
            lo=0.0,
            doc="frequency measurement: angle filter time constant (ANDES BusFreq Tf)",
        ),
        Param(
            "Twm",
            "s",
            31,
            default=0.1,
            lo=0.0,
            doc="frequency measurement: washout time constant (ANDES BusFreq Tw, > 0)",
        ),
        Param("Tf", "s", 32, default=1.0, doc="ESD1: state-of-charge integrator time constant"),
        Param("SOCmin", "", 33, doc="ESD1: minimum state of charge"),
        Param("SOCmax", "", 34, default=1.0, doc="ESD1: maximum state of charge"),
        Param("SOCinit", "", 35, default=0.5, doc="ESD1: initial state of charge"),
        Param("En", "MWh", 36, default=100.0, doc="ESD1: rated energy"),
        Param("EtaC", "", 37, default=1.0, doc="ESD1: charging efficiency"),
        Param("EtaD", "", 38, default=1.0, doc="ESD1: discharging efficiency"),
        Param("Tg", "s", 39, default=0.1, lo=0.0, doc="REGCA1: converter time constant"),
        Param(
            "Rrpwr",
            "pu",
            40,
            default=10.0,
            lo=0.0,
            doc="REGCA1: LVPL rate limit of Tg dIp/dt (system base, as ANDES: not converted)",
        ),
        Param("Brkpt", "pu", 41, default=1.0, doc="REGCA1: LVPL breakpoint voltage"),
        Param("Zerox", "pu", 42, default=0.5, doc="REGCA1: LVPL zero-crossing voltage"),
        Param(
            "Lvplsw",
            "code",
            43,
            default=1.0,
            choices=(0.0, 1.0),
            doc="REGCA1: low-voltage power logic 1 on, 0 off",
        ),
        Param("Lvpl1", "pu", 44, default=1.0, doc="REGCA1: LVPL current limit at Brkpt"),
        Param("Volim", "pu", 45, default=1.2, doc="REGCA1: voltage of high-voltage Iq management"),
        Param("Lvpnt1", "pu", 46, default=0.8, doc="REGCA1: upper voltage of the Ip gain LVG"),
        Param("Lvpnt0", "pu", 47, default=0.4, doc="REGCA1: lower voltage of the Ip gain LVG"),
        Param(
            "Iolim",
            col=48,
            default=-1.5,
            doc="REGCA1: lower limit of the output Iq (high-voltage management)",
            **_DEV_PU,
        ),
        Param("Tfltr", "s", 49, default=0.1, lo=0.0, doc="REGCA1: LVPL voltage filter"),
        Param("Khv", "", 50, default=0.7, lo=0.0, doc="REGCA1: over-voltage Iq gain"),
        Param("Iqrmax", col=51, default=1.0, doc="REGCA1: upper rate of Tg dIq/dt", **_DEV_PU),
        Param("Iqrmin", col=52, default=-1.0, doc="REGCA1: lower rate of Tg dIq/dt", **_DEV_PU),
    ),
)

#: table field of Case -> family, for the four dynamic-data tables
FAMILIES: Mapping[str, Family] = MappingProxyType(
    {
        "machines": MACHINE,
        "exciters": EXCITER,
        "pss": PSS,
        "governors": GOVERNOR,
        "converters": CONVERTER,
    }
)


def array_dataclass(cls, names):
    """``cls`` as a frozen dataclass whose fields are one ``np.ndarray`` per name in
    `names`, then the class's own annotated fields (the case tables and the models'
    parameter classes, whose fields come from the declarations).

    Parameters
    ----------
    cls : type
        The class to decorate.
    names : iterable of str
        Field names, in order.

    Returns
    -------
    type
        The dataclass.
    """
    own = dict(inspect.get_annotations(cls))
    cls.__annotations__ = {**{n: "np.ndarray" for n in names}, **own}
    return dataclass(frozen=True, eq=False)(cls)
