"""Physically impossible control-system, machine and bus data in a case is refused when
the case is made, naming the table, the row, its machine or bus, the field, the value and
the allowed range: a gain whose sign the model cannot have, a regulator gain of 0 the
start divides by, a lead without its lag, an upper limit below its lower, a speed set
point the start cannot honour, a saturation falling with the flux, a leakage reactance
the machine's equations divide by, a negative rated voltage.  Every type's declared
limits (`stabctl.models.declaration.Limits`) are checked here one by one."""

import re

import numpy as np
import pytest

from stabctl.case import ExciterTable, GovernorTable, PssTable
from stabctl.errors import CaseError
from stabctl.models.exciters import EXCITER
from stabctl.models.governors import GOVERNOR
from stabctl.models.pss import PSS
from tests.case.test_case import BUS, EXC, MAC, TG, make_case, modified
from tests.case.test_case import PSS as PSS_ROWS


def _col(fam, name):
    return fam.col(name) - 1


@pytest.mark.parametrize(
    "kwargs, pattern",
    [
        # a regulator gain of -200 ran and, in cct, gave "CCT 0 s, N-1 insecure"
        (
            dict(exc=modified(EXC, 0, _col(EXCITER, "KA"), -200.0)),
            r"exc_con row 1 \(machine 1\), field 'KA': must be >= 0, got -200",
        ),
        (  # Vrmax below Vrmin: the start was refused as "not an equilibrium" naming neither
            dict(exc=modified(modified(EXC, 0, 7, -5.0), 0, 8, 5.0)),
            r"exc_con row 1 \(machine 1\), field 'Vrmax': must be >= Vrmin = 5 \(exciter "
            r"type 0, .*IEEE Std 421.5.*\), got -5",
        ),
        (  # V_ref = V_t + V_R0/K_A: a gain of 0 ran (IEEET1 KA 0, exit 0)
            dict(exc=modified(EXC, 0, _col(EXCITER, "KA"), 0.0)),
            r"exc_con row 1 \(machine 1\), field 'KA': must be > 0 \(exciter type 0, .*"
            r"V_R0/K_A\), got 0",
        ),
        (  # smpexc bypasses its lead-lag without T_B: T_C = 0, 1, 5 ran alike
            dict(exc=modified(EXC, 0, _col(EXCITER, "TC"), 5.0)),
            r"exc_con row 1 \(machine 1\), field 'TC': must be 0 where TB = 0 \(below "
            r"0.001 s: no lag, the lead-lag bypassed\) \(exciter type 0, .*SEXS.*\), got 5",
        ),
        (
            dict(tg=modified(TG, 0, _col(GOVERNOR, "invR"), -25.0)),
            r"tg_con row 1 \(machine 1\), field 'invR': must be >= 0, got -25",
        ),
        (  # the start was refused as "not an equilibrium" naming the servo, not wf
            dict(tg=modified(TG, 0, _col(GOVERNOR, "wf"), 0.0)),
            r"tg_con row 1 \(machine 1\), field 'wf': must be 1 \(governor type 1, PST tg; "
            r"every governor starts at rated speed.*\), got 0",
        ),
        (
            dict(tg=modified(TG, 0, _col(GOVERNOR, "Tmax"), -1.0)),
            r"tg_con row 1 \(machine 1\), field 'Tmax': must be >= Tmin = 0 .*got -1",
        ),
        (  # the start was refused blaming ESST3A's K_C
            dict(pss=modified(modified(PSS_ROWS, 0, 8, -0.05), 0, 9, 0.2)),
            r"pss_con row 1 \(machine 1\), field 'ymax': must be >= ymin = 0.2 \(pss type 1, "
            r".*\), got -0.05",
        ),
        (
            dict(mac=modified(modified(MAC, 0, 19, 0.5), 0, 20, 0.1)),
            r"mac_con row 1 \(machine 1\), field 'S12': saturation S\(1.2\) must be >= "
            r"S\(1.0\) = 0.5 .*got 0.1",
        ),
        (
            dict(mac=modified(MAC, 0, 19, -0.1)),
            r"mac_con row 1 \(machine 1\), field 'S10': saturation S\(1.0\) must be >= 0",
        ),
        (  # x_l 0.9 above x'd 0.3 and x"d 0.25: mac_sub divides by x'd - x_l
            dict(mac=modified(MAC, 0, 3, 0.9)),
            r"mac_con row 1 \(machine 1\), field 'xl': leakage x_l must be < x'd = 0.3 .*"
            r"got 0.9",
        ),
        (
            dict(mac=modified(MAC, 0, 11, 0.2)),  # x'q 0.2 below x_l 0.2: x'q - x_l = 0
            r"mac_con row 1 \(machine 1\), field 'xl': leakage x_l must be < x'q = 0.2",
        ),
        (
            dict(mac=modified(MAC, 0, 11, 1.8)),  # x'q 1.8 above x_q 1.7
            r"mac_con row 1 \(machine 1\), field 'xqp': x'q must be <= x_q = 1.7 .*got 1.8",
        ),
        (
            dict(bus=modified(BUS, 2, 12, -230.0)),
            r"bus row 3 \(bus 3\), field 'kv': rated voltage must be >= 0 kV \(0: not given\), "
            r"got -230",
        ),
    ],
)
def test_impossible_control_machine_and_bus_data_is_refused_naming_the_field(kwargs, pattern):
    with pytest.raises(CaseError, match=pattern):
        make_case(**kwargs)


def test_a_rated_voltage_of_0_is_taken_as_not_given():
    make_case(bus=modified(BUS, 2, 12, 0.0))


def _base_row(fam, kind):
    """A row of type `kind` holding zeros but where its limits need more: a speed set point
    of 1, a positive value where one must be > 0, a PSS's washout and first lag of 1 s,
    and 1 in each field the table names as it refuses the row for its model (a time
    constant the model needs >= 1e-3 s, a PSS/E stabiliser's input code)."""
    row = np.zeros(len(fam.params))
    row[0], row[1] = kind, 1
    for lim in fam.limits[kind]:
        for name in lim.positive + lim.one:
            row[fam.col(name) - 1] = 1.0
    if fam is PSS:
        row[fam.col("Tw") - 1] = row[fam.col("T2") - 1] = 1.0
    table = {"exc_con": ExciterTable, "tg_con": GovernorTable, "pss_con": PssTable}[fam.table]
    ordered = {"G0": 0.2, "G1": 0.5, "G2": 0.8, "P1": 0.2, "P2": 0.5, "P3": 0.8, "Uc": -1.0}
    for _ in range(20):
        try:
            table.from_matrix([row])
            return row
        except CaseError as exc:
            assert exc.fields, exc
            for name in exc.fields:  # PIDGOV's gate table, its gate velocity limits
                row[fam.col(name) - 1] = ordered.get(name, 1.0)
    raise AssertionError(f"no base row of {fam.table} type {kind}")


def _breaking(fam):
    """(type, the values that break it, the field named, what the message says, the
    limits' source) for every limit every type of the family declares."""
    for kind, limits in fam.limits.items():
        for lim in limits:
            for name in lim.nonnegative:
                yield kind, {name: -1.0}, name, r"must be >= 0 \(", lim.source
            for name in lim.positive:
                yield kind, {name: 0.0}, name, r"must be > 0 \(", lim.source
            for hi, lo in lim.ordered:
                yield kind, {hi: -1.0, lo: 1.0}, hi, rf"must be >= {lo} = 1 \(", lim.source
            for name in lim.one:
                yield kind, {name: 0.0}, name, r"must be 1 \(", lim.source
            for lead, lag in lim.leads:
                yield kind, {lead: 1.0, lag: 0.0}, lead, rf"must be 0 where {lag} = 0 ", lim.source


@pytest.mark.parametrize(
    "fam, table, kind, values, field, what, source",
    [
        (fam, table, *case)
        for fam, table in ((EXCITER, ExciterTable), (GOVERNOR, GovernorTable), (PSS, PssTable))
        for case in _breaking(fam)
    ],
)
def test_every_declared_limit_of_every_type_is_refused_naming_field_type_and_source(
    fam, table, kind, values, field, what, source
):
    row = _base_row(fam, kind)
    table.from_matrix([row])  # the base row is taken
    for name, v in values.items():
        row[fam.col(name) - 1] = v
    with pytest.raises(CaseError) as err:
        table.from_matrix([row])
    msg = str(err.value)
    assert msg.startswith(f"{fam.table} row 1 (machine 1), field '{field}'"), msg
    assert fam.type_names[kind] in msg and source in msg, msg
    assert re.search(what, msg), msg


def test_a_dc_exciter_s_saturation_must_grow_with_the_voltage():
    """DC1 (IEEE Std 421.5 DC1A) with SE(3) = 0.5 above SE(4) = 0.1."""
    row = [1, 1, 0.0, 50.0, 0.05, 0, 0, 5.0, -5.0, 0.0, 0.5, 3.0, 0.5, 4.0, 0.1, 0.05, 1.0]
    with pytest.raises(
        CaseError,
        match=r"exc_con row 1 \(machine 1\), field 'SE2' \(column 15\): saturation must grow "
        r"with the voltage: SE\(E1 = 3\) = 0.5, SE\(E2 = 4\) = 0.1",
    ):
        ExciterTable.from_matrix([row])
    row[14] = 0.9
    ExciterTable.from_matrix([row])


def test_a_stabiliser_cut_off_above_and_below_the_same_voltage_is_refused():
    """IEEEST (pss type 3) with VCU 0.9 below VCL 1.1: off at every voltage; 0 is none."""
    row = np.zeros(len(PSS.params))
    row[:4] = 3, 1, 1.0, 1.0
    row[PSS.col("input1") - 1] = 1
    row[PSS.col("VCU") - 1], row[PSS.col("VCL") - 1] = 0.9, 1.1
    with pytest.raises(CaseError, match=r"pss_con row 1 \(machine 1\), field 'VCU': must be > "):
        PssTable.from_matrix([row])
    row[PSS.col("VCU") - 1] = 0.0
    PssTable.from_matrix([row])


@pytest.mark.parametrize("kind", [1, 2])
def test_the_pst_stabiliser_s_second_lead_needs_its_lag(kind):
    """Round 41: PST's stabiliser (types 1, 2) with T3 = 0.05 s and T4 = 0 ran as without
    T3 (the second lead-lag bypassed), no word said.  Refused naming both fields."""
    row = _base_row(PSS, kind)
    row[PSS.col("T3") - 1], row[PSS.col("T4") - 1] = 0.05, 0.0
    with pytest.raises(CaseError, match=r"field 'T4'.*a lead without its lag") as err:
        PssTable.from_matrix([row])
    assert set(err.value.fields) == {"T4", "T3"}
    row[PSS.col("T3") - 1] = 0.0
    PssTable.from_matrix([row])  # no lead: the block bypassed, as PST's
