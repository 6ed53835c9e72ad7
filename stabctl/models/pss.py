"""Power system stabilisers: PST `pss` (types 1 and 2: speed or power input, washout, two
lead-lags, output limits), stabctl's PSS/E stabiliser (type 3: IEEEST and ST2CUT) and
PSS/E's STAB2A (type 4).

Sources: PSTess 1.1 `pss_indx.m`, `pss.m` (docs/pst_models.md section 3); PSS/E Model
Library IEEEST (IEEE Std 421.5 PSS1A-type with its filter) and ST2CUT (as ANDES
`andes/models/pss/ieeest.py`, `st2cut.py`), docs/pst_models.md 3.1; STAB2A (ASEA power
sensitive stabilising unit, PSS/E Model Library; block diagram as OpenIPSL
``OpenIPSL.Electrical.Controls.PSSE.PSS.STAB2A``): electrical power (machine base) through
-(K_2 T_2 s/(1 + s T_2))^3, then K_3/(1 + s T_3) + K_4, then (K_5/(1 + s T_5))^2, limited
to +-HLIM.  Column 3 of
pss_con is the gain times the washout time constant (K*T_w) for PST's pss, the washout
gain for type 3.  PST pss states: washout, lead-lag 1, lead-lag 2 (only when
T_4 >= 1e-3).  Type 3 states: input lags 1, 2, filter 1-4, washout, lead-lags 1-3 (each
only where its block exists).  Type 4 states: washouts 1-3, the T_3 lag, the two T_5 lags
(a lag below 1e-3 s passes its input).  Output in pu, added to the exciter summing junction of
the same machine; 0 while the terminal voltage is outside [VCL, VCU] (pss_con columns 25-26,
PSS/E's output cut-off; 0 none).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from stabctl._jit.decorators import kernel
from stabctl.errors import CaseError
from stabctl.models.blocks import GAIN_AFTER, GAIN_BEFORE, LBND, clip, lag, leadlag, washout
from stabctl.models.declaration import (
    Declared,
    DyrModel,
    Family,
    Param,
    check_packed,
    layout,
    pack,
    params_class,
)

if TYPE_CHECKING:
    from stabctl.case import Case


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
        Param(
            "VCU",
            "pu",
            25,
            doc="output cut-off: the output is 0 while the terminal voltage is above VCU "
            "(PSS/E IEEEST, ST2CUT VCU; 0 none)",
        ),
        Param(
            "VCL",
            "pu",
            26,
            doc="output cut-off: the output is 0 while the terminal voltage is below VCL "
            "(PSS/E IEEEST, ST2CUT VCL; 0 none)",
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
            {"Tw": "T6", "ymax": "LSMAX", "ymin": "LSMIN", "VCU": "VCU", "VCL": "VCL"},
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
                "VCU": "VCU",
                "VCL": "VCL",
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

PST_SPEED, PST_POWER, PSSE, STAB2A = 1, 2, 3, 4
SPEED, POWER = 1, 3  # PSS/E input codes (ICS, MODE)
STATE_NAMES = {
    PST_SPEED: ("washout", "leadlag1", "leadlag2"),
    PST_POWER: ("washout", "leadlag1", "leadlag2"),
    PSSE: (
        "lag1",
        "lag2",
        "filter1",
        "filter2",
        "filter3",
        "filter4",
        "washout",
        "leadlag1",
        "leadlag2",
        "leadlag3",
    ),
    STAB2A: ("washout1", "washout2", "washout3", "lag3", "lag5a", "lag5b"),
}
#: pss_con fields (stabctl.models.pss.PSS) the kernels take: columns 3-18 (type 3's
#: filter A1..A6 enters as its canonical form nf, fe, fa, fc)
TABLE_FIELDS = PSS.names[2:18]
#: packed parameter matrix of the kernels, (column name, PssParams attribute) per
#: column: pss_con columns 1-18 in declared order, then the filter (a_0..a_3, c_0..c_3)
_SUFFIX = {"ymax": "MAX", "ymin": "MIN", "input1": "IN1", "input2": "IN2"}
PACKED = (
    ("KIND", "kind"),
    ("MAC", "mac"),
    *((_SUFFIX.get(n, n.upper()), n) for n in TABLE_FIELDS),
    ("NF", "nf"),
    ("FE", "fe"),
    *((f"FA{i}", f"fa_{i}") for i in range(4)),
    *((f"FC{i}", f"fc_{i}") for i in range(4)),
    ("VCUT_HI", "v_cut_high"),
    ("VCUT_LO", "v_cut_low"),
)
#: the kernels' column of each PACKED name: P[k, S.TW]
S = layout("PssColumns", PACKED)
W_PSSE, LL_PSSE = 6, 7  # type 3 washout and first lead-lag slots


@params_class(("kind", "mac"), TABLE_FIELDS)
class PssParams(Declared):
    """PSS data, arrays of shape (n_pss,): ``kind`` the pss_con type, ``mac`` the machine's
    row (index), the pss_con fields :data:`TABLE_FIELDS` under their declared names
    (stabctl.models.pss.PSS; input1, input2 0 for types 1, 2).  Type 3: the filter in
    controllable canonical form of order nf (<= 4): fa (n, 4) the monic denominator
    coefficients a_0..a_3, fc (n, 4) output coefficients, fe the feedthrough.  Every
    type: v_cut_high, v_cut_low the output cut-off's terminal voltages (pu; VCU, VCL with
    0 read as none: +inf, -inf)."""

    nf: np.ndarray
    fa: np.ndarray
    fc: np.ndarray
    fe: np.ndarray
    v_cut_high: np.ndarray
    v_cut_low: np.ndarray

    @property
    def n(self) -> int:
        return self.mac.size

    @property
    def power_input(self):
        return self.kind == PST_POWER

    def packed(self) -> np.ndarray:
        """Parameter matrix (n_pss, len(PACKED)) for the compiled kernels, columns as
        :data:`PACKED`."""
        return pack(
            self,
            PACKED,
            **{f"fa_{i}": self.fa[:, i] for i in range(4)},
            **{f"fc_{i}": self.fc[:, i] for i in range(4)},
        )

    @property
    def has_T4(self):
        return self.T4 >= LBND

    def n_slots(self) -> int:
        """State slots per PSS: 3, or 10 when a PSS/E stabiliser (type 3 or 4) is present."""
        return 10 if np.any(self.kind >= PSSE) else 3

    def has_state(self) -> np.ndarray:
        """Boolean (n_slots, n_pss): the slots that are states of each PSS."""
        act = np.zeros((10, self.n), bool)
        pst, e = self.kind <= PST_POWER, self.kind == PSSE
        act[0] = pst | (e & (self.Tr1 >= LBND))
        act[1] = pst | (e & (self.input2 != 0) & (self.Tr2 >= LBND))
        act[2] = (pst & self.has_T4) | (e & (self.nf >= 1))
        for r in range(3, 6):
            act[r] = e & (self.nf >= r - 1)
        act[W_PSSE] = e
        for r, T in zip(range(LL_PSSE, LL_PSSE + 3), (self.T2, self.T4, self.T6)):
            act[r] = e & (T >= LBND)
        s2 = self.kind == STAB2A
        act[:3] |= s2
        act[3] |= s2 & (self.Tr1 >= LBND)
        act[4:6] |= s2 & (self.T6 >= LBND)
        return act[: self.n_slots()]

    def time_constants(self):
        """(label, values, mask) of every time constant that sets a state's speed."""
        e = self.kind >= PSSE
        return (
            ("pss_con T_w", self.Tw, np.ones(self.n, bool)),
            ("pss_con T_2", self.T2, (self.kind <= PST_POWER) | (e & (self.T2 >= LBND))),
            ("pss_con T_4", self.T4, self.T4 >= LBND),
            ("pss_con T_6", self.T6, e & (self.T6 >= LBND)),
            ("pss_con Tr1", self.Tr1, e & (self.Tr1 >= LBND)),
            ("pss_con Tr2", self.Tr2, e & (self.input2 != 0) & (self.Tr2 >= LBND)),
        )


check_packed(PssParams, PACKED, (*(f"fa_{i}" for i in range(4)), *(f"fc_{i}" for i in range(4))))


def pss_params(case: Case) -> PssParams:
    """PSS parameters of a case.

    Raises CaseError (pss_con row) for a PST pss (types 1, 2) whose first lead-lag has
    no lag (T_2 below 1e-3 s; PST has no such case), a type-3 or 4 washout below 1e-3 s,
    a type-3 lead-lag with a lead but no lag, an input
    code other than 1 (speed) or 3 (power), or an improper filter (A6 without a
    second-order denominator)."""
    s = case.pss
    e = s.type == PSSE
    _check_psse(s)
    nf, fa, fc, fe = _filters(s)
    given = {n: getattr(s, n).copy() for n in TABLE_FIELDS}
    given.update(input1=np.where(e, s.input1, 0), input2=np.where(e, s.input2, 0))
    return PssParams(
        kind=s.type.astype(int),
        mac=np.array([case.machine_index(m) for m in s.machine], int),
        **given,
        nf=nf,
        fa=fa,
        fc=fc,
        fe=fe,
        v_cut_high=np.where(s.VCU == 0, np.inf, s.VCU),
        v_cut_low=np.where(s.VCL == 0, -np.inf, s.VCL),
    )


def _check_psse(s) -> None:
    for r in np.nonzero((s.type <= PST_POWER) & (s.T2 < LBND))[0]:
        raise CaseError(f"pss_con row {r + 1}, field 'T2': the first lead-lag needs T2 >= {LBND} s")
    for r in np.nonzero((s.type >= PSSE) & (s.Tw < LBND))[0]:
        raise CaseError(f"pss_con row {r + 1}, field 'Tw': washout needs Tw >= {LBND} s")
    for r in np.nonzero(s.type == PSSE)[0]:
        if s.input1[r] not in (SPEED, POWER) or s.input2[r] not in (0, SPEED, POWER):
            raise CaseError(
                f"pss_con row {r + 1}, fields 'input1', 'input2': PSS/E input codes "
                "1 (speed) or 3 (electrical power) only (input2 may be 0)"
            )
        if s.Tw[r] < LBND:
            raise CaseError(f"pss_con row {r + 1}, field 'Tw': washout needs Tw >= {LBND} s")
        for lead_name, lag_name in (("T1", "T2"), ("T3", "T4"), ("T5", "T6")):
            if getattr(s, lag_name)[r] < LBND and getattr(s, lead_name)[r] != 0:
                raise CaseError(
                    f"pss_con row {r + 1}, field '{lag_name}': lead {lead_name} without lag"
                )


def _filters(s):
    """IEEEST filter N(s)/D(s), N = 1 + A5 s + A6 s^2, D = (1 + A1 s + A2 s^2)(1 + A3 s +
    A4 s^2), in controllable canonical form (DC gain 1): order nf, monic denominator
    coefficients fa, output coefficients fc, feedthrough fe."""
    n = len(s)
    nf, fa, fc, fe = np.zeros(n, int), np.zeros((n, 4)), np.zeros((n, 4)), np.ones(n)
    for r in np.nonzero(s.type == PSSE)[0]:
        den = np.polymul([s.A4[r], s.A3[r], 1.0], [s.A2[r], s.A1[r], 1.0])[::-1]  # ascending
        num = np.array([1.0, s.A5[r], s.A6[r]])
        order = int(np.max(np.nonzero(den)[0]))
        if np.any(num[order + 1 :] != 0):
            raise CaseError(
                f"pss_con row {r + 1}, fields 'A5', 'A6': filter numerator of "
                f"higher order than its denominator ({order})"
            )
        if order == 0:
            continue
        a, b = den[:order] / den[order], np.append(num, np.zeros(3))[: order + 1] / den[order]
        nf[r], fe[r] = order, b[order]
        fa[r, :order] = a
        fc[r, :order] = b[:order] - b[order] * a
    return nf, fa, fc, fe


def pss_inputs(p: PssParams, omega, pe_machine):
    """Signals 1 and 2 of each PSS at the initial point, shape (n_pss,) each.

    Parameters
    ----------
    p : PssParams
        The stabilisers.
    omega : numpy.ndarray
        Machine speeds (pu), shape (n_mac,).
    pe_machine : numpy.ndarray
        Electrical power of each machine on its own base (pu), shape (n_mac,): the air-gap
        power ``Re(psi conj(I))`` of the internal voltage the network sees, the signal
        :func:`output_and_derivatives` is given in a run (at the initial point the
        mechanical power, terminal power plus ``r_a |I|^2``).  ANDES's IEEEST takes the
        same (``sig``: ``tm0`` at initialisation, ``te`` after, ``andes/models/pss/
        ieeest.py``); with the terminal power here a machine with ``r_a`` started off
        equilibrium (IEEE 39 G6: 0.015 on ``pss.leadlag1``).

    Returns
    -------
    u1 : numpy.ndarray
        PST types: speed (pu) or the power; type 3: its first PSS/E input (speed
        deviation or power); type 4: the power.
    u2 : numpy.ndarray
        Type 3: its second PSS/E input; the other types: 0.
    """
    w, pe = omega[p.mac], pe_machine[p.mac]
    u1 = np.where(p.kind == PST_SPEED, w, pe)
    u1 = np.where(p.kind == PSSE, np.where(p.input1 == SPEED, w - 1.0, pe), u1)
    u2 = np.where(p.input2 == SPEED, w - 1.0, np.where(p.input2 == POWER, pe, 0.0))
    return u1, u2


def initialise(p: PssParams, u1, u2):
    """States (n_slots, n_pss) from the initial inputs (pss_inputs): every washout input
    state at its input, input lags at K u, filter state 1 at its input times the
    denominator's leading coefficient (controllable form, zero derivative), others 0."""
    x = np.zeros((10, p.n))
    e = p.kind == PSSE
    y1 = np.where(p.Tr1 >= LBND, p.K1 * u1, 0.0)
    y2 = np.where(p.Tr2 >= LBND, p.K2 * u2, 0.0)
    v = p.K1 * u1 + p.K2 * u2
    x[0] = np.where(e, y1, u1)
    x[1] = np.where(e, y2, 0.0)
    x[2] = np.where(e & (p.nf >= 1), v / np.where(p.nf >= 1, p.fa[:, 0], 1.0), 0.0)
    x[W_PSSE] = np.where(e, v, 0.0)
    return x[: p.n_slots()]


# -- compiled runtime kernels: P is PssParams.packed(), x the PSS block of the state
# -- vector (n_slots, n_pss), k the PSS; one function per type, dispatched on kind


@kernel
def output_and_derivatives(P, x, k, omega, pe, vt, dx):
    """Output of PSS k (pu, to its exciter's summing junction) at machine speed omega (pu),
    electrical power pe (machine base) and terminal voltage magnitude vt (pu), PST flag
    1/2; its derivatives into dx[:, k].  The output is 0 while vt is outside [VCL, VCU]
    (PSS/E IEEEST, ST2CUT; ANDES 2.0 ``ieeest.py`` ``OLIM``); the states move on."""
    kind = P[k, S.KIND]
    if kind == PSSE:
        y = _psse(P, x, k, omega, pe, dx)
    elif kind == STAB2A:
        y = _stab2a(P, x, k, pe, dx)
    else:
        y = _pst(P, x, k, pe if kind == PST_POWER else omega, dx)
    return y if P[k, S.VCUT_LO] <= vt <= P[k, S.VCUT_HI] else 0.0


@kernel(inline="always")
def _pst(P, x, k, u, dx):
    """PST pss (pss.m): washout s T_w/(1 + s T_w) on u (speed or power), then
    K (1 + s T_1)/(1 + s T_2) (K T_w given, column 3), then (1 + s T_3)/(1 + s T_4)
    (absent for T_4 < 1e-3 s), output limits [ymin, ymax]."""
    y, dx[0, k] = washout(u, x[0, k], P[k, S.TW], 1.0, GAIN_AFTER)
    y, dx[1, k] = leadlag(y, x[1, k], P[k, S.T1], P[k, S.T2], P[k, S.KTW])
    y, dx[2, k] = leadlag(y, x[2, k], P[k, S.T3], P[k, S.T4])
    return clip(y, P[k, S.MIN], P[k, S.MAX])


@kernel
def _signal(code, omega, pe):
    """A PSS/E stabiliser input: speed deviation (pu) or electrical power (code 3), else 0."""
    if code == SPEED:
        return omega - 1.0
    if code == POWER:
        return pe
    return 0.0


@kernel(inline="always")
def _psse(P, x, k, omega, pe, dx):
    """PSS/E stabiliser: input lags K_i/(1 + s Tr_i) summed, filter N/D, washout
    K_w s/(1 + s T_w), three lead-lags, output limits (docs 3.1)."""
    dx[:, k] = 0.0
    v = 0.0
    for r, code, K, T in ((0, S.IN1, S.K1, S.TR1), (1, S.IN2, S.K2, S.TR2)):
        u, dx[r, k] = lag(P[k, K] * _signal(P[k, code], omega, pe), x[r, k], P[k, T])
        v += u
    nf = int(P[k, S.NF])
    w = P[k, S.FE] * v
    if nf > 0:
        acc = v
        for i in range(nf):
            w += P[k, S.FC0 + i] * x[2 + i, k]
            acc -= P[k, S.FA0 + i] * x[2 + i, k]
            if i < nf - 1:
                dx[2 + i, k] = x[3 + i, k]
        dx[1 + nf, k] = acc
    y, dx[W_PSSE, k] = washout(w, x[W_PSSE, k], P[k, S.TW], P[k, S.KTW], GAIN_BEFORE)
    for j, lead, lag_ in ((0, S.T1, S.T2), (1, S.T3, S.T4), (2, S.T5, S.T6)):
        y, dx[LL_PSSE + j, k] = leadlag(y, x[LL_PSSE + j, k], P[k, lead], P[k, lag_])
    return clip(y, P[k, S.MIN], P[k, S.MAX])


@kernel(inline="always")
def _stab2a(P, x, k, pe, dx):
    """STAB2A: -(K_Tw s/(1 + s T_w))^3 on pe (K_Tw = K_2 T_2, T_w = T_2), then
    K_3/(1 + s T_3) + K_4 (columns K1, Tr1, K2), then (K_5/(1 + s T_5))^2 (columns K5 = T5,
    T6), limited to [ymin, ymax]."""
    dx[:, k] = 0.0
    y = pe
    for r in range(3):
        y, dx[r, k] = washout(y, x[r, k], P[k, S.TW], P[k, S.KTW], GAIN_AFTER)
    y = -y
    y3, dx[3, k] = lag(P[k, S.K1] * y, x[3, k], P[k, S.TR1])
    y = y3 + P[k, S.K2] * y
    for r in (4, 5):
        y, dx[r, k] = lag(P[k, S.T5] * y, x[r, k], P[k, S.T6])
    return clip(y, P[k, S.MIN], P[k, S.MAX])
