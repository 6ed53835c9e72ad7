"""Case model: tables, lookups, validation errors, built-in cases.

Expected values are PSTess's d2asbegp.m / d_minniWECC_base data (PST column order).
"""

import json
import re
from pathlib import Path

import numpy as np
import pytest

import stabctl
from stabctl.case import (
    BranchTable,
    BusTable,
    Case,
    ConverterTable,
    ExciterTable,
    GovernorTable,
    LoadTable,
    MachineTable,
    PssTable,
)
from stabctl.errors import CaseError, UnknownBusError
from stabctl.io import list_cases, load_case

# d2asbegp.m rows (bus 1, 2, 3; one line; machine 1; exciter; pss; tg)
BUS = [
    [1, 1.01, 18.5, 7.2615, 1.274, 0, 0, 0, 0, 1, 5.0, -2.0, 22.0, 1.1, 0.9],
    [2, 1.01, 7.725, 7.00, 1.948, 0, 0, 0, 0, 2, 5.0, -2.0, 22.0, 1.1, 0.9],
    [3, 0.9791, -7.441, 0, 0, 0, 0, 0, 3.00, 3, 0, 0, 230.0, 1.5, 0.5],
]
LINE = [
    [1, 3, 0.0, 0.0167, 0.0, 1.0, 0, 0, 0, 0],
    [2, 3, 0.001, 0.0100, 0.0175, 1.0, 0, 0, 0, 0],
]
MAC = [
    [
        1,
        1,
        900,
        0.2,
        0.0,
        1.8,
        0.3,
        0.25,
        8.0,
        0.03,
        1.7,
        0.55,
        0.24,
        0.4,
        0.05,
        6.5,
        0,
        0,
        1,
        0.0654,
        0.5743,
    ],
    [
        2,
        2,
        900,
        0.2,
        0.0,
        1.8,
        0.3,
        0.25,
        8.0,
        0.03,
        1.7,
        0.55,
        0.25,
        0.4,
        0.05,
        6.5,
        0,
        0,
        2,
        0.0654,
        0.5743,
    ],
]
EXC = [[0, 1, 0.01, 200.0, 0.05, 0, 0, 5.0, -5.0] + [0] * 11]
PSS = [[1, 1, 100, 10, 0.05, 0.01, 0.05, 0.01, 0.2, -0.05]]
TG = [[1, 1, 1, 25.0, 1.0, 0.1, 0.5, 0.0, 1.25, 5.0]]
LOAD = [[3, 0, 0, 0.5, 0]]


def make_case(bus=BUS, line=LINE, mac=MAC, exc=EXC, pss=PSS, tg=TG, load=LOAD):
    return Case(
        name="t",
        base_mva=100,
        freq_hz=60,
        buses=BusTable.from_matrix(bus),
        branches=BranchTable.from_matrix(line),
        machines=MachineTable.from_matrix(mac),
        exciters=ExciterTable.from_matrix(exc),
        pss=PssTable.from_matrix(pss),
        governors=GovernorTable.from_matrix(tg),
        loads=LoadTable.from_matrix(load),
    )


def modified(rows, i, j, value):
    rows = [list(r) for r in rows]
    rows[i][j] = value
    return rows


# ---------------------------------------------------------------------------- tables


def test_named_columns_follow_pst_column_order():
    c = make_case()
    assert c.buses.bshunt[2] == 3.0  # bus col 9
    assert c.buses.kind.tolist() == [1, 2, 3]
    assert c.branches.b[1] == 0.0175  # line col 5
    m = c.machines
    assert (m.xdp[0], m.xdpp[1], m.Tdop[0], m.H[0], m.S12[0]) == (0.3, 0.25, 8.0, 6.5, 0.5743)
    assert m.col19.tolist() == [1, 2]  # kept as given
    assert m.pfrac.tolist() == [1, 1]  # PSTess mac_indx default for omitted cols 22-23
    assert c.exciters.KA[0] == 200.0 and c.exciters.Vrmin[0] == -5.0
    assert c.pss.KTw[0] == 100 and c.pss.ymin[0] == -0.05
    assert c.governors.invR[0] == 25.0 and c.governors.T5[0] == 5.0
    assert c.loads.p_current[0] == 0.5 and c.loads.p_impedance[0] == 0.5
    assert c.loads.q_impedance[0] == 1.0


def test_matrix_gives_pst_matrix_back_and_col_is_1_based():
    c = make_case()
    np.testing.assert_array_equal(c.buses.matrix(), np.array(BUS, float))
    np.testing.assert_array_equal(c.machines.matrix()[:, :21], np.array(MAC, float))
    assert c.machines.col(16) is c.machines.H
    assert c.machines.speed_effects.tolist() == [1, 1]  # stabctl's column 24, PST default
    assert c.machines.psse_sat.tolist() == [0, 0]  # column 25: PST's mac_sub, unsaturated
    assert c.machines.psse_swing.tolist() == [0, 0]  # column 29: PST's swing equation
    with pytest.raises(CaseError, match="no column 30"):
        c.machines.col(30)


def test_tables_are_read_only():
    c = make_case()
    with pytest.raises(ValueError):
        c.buses.vmag[0] = 2.0
    with pytest.raises(AttributeError):  # dataclasses.FrozenInstanceError
        c.buses.vmag = np.ones(3)


def test_raw_values_are_kept_not_model_defaults():
    mac = modified(MAC, 0, 13, 0.0)  # T'qo = 0 stays 0 (PST's 999 is a model choice)
    c = make_case(mac=mac)
    assert c.machines.Tqop[0] == 0.0


def test_omitted_bus_columns_take_pst_loadflow_defaults():
    b = BusTable.from_matrix([r[:10] for r in BUS])
    assert b.qmax.tolist() == [9999] * 3 and b.qmin.tolist() == [-9999] * 3
    assert b.kv.tolist() == [1] * 3 and b.vmax.tolist() == [1.5] * 3
    assert b.vmin.tolist() == [0.5] * 3


def test_five_column_lines_get_tap_one():
    br = BranchTable.from_matrix([r[:5] for r in LINE])
    assert br.tap.tolist() == [1.0, 1.0] and br.phase_deg.tolist() == [0.0, 0.0]


# ---------------------------------------------------------------------------- lookups


def test_bus_index_and_unknown_bus():
    c = make_case()
    assert c.bus_index(3) == 2
    np.testing.assert_array_equal(c.bus_indices([3, 1, 2]), [2, 0, 1])
    with pytest.raises(UnknownBusError, match=r"bus 77 is not in case 't'") as e:
        c.bus_index(77)
    assert isinstance(e.value, CaseError) and isinstance(e.value, KeyError)
    with pytest.raises(UnknownBusError, match="bus 5 "):
        c.bus_indices([1, 5])
    with pytest.raises(UnknownBusError, match=r"\(its buses: 1, 2, 3\)$"):
        c.bus_index(77)


def test_an_unknown_bus_of_kundur_names_the_book_numbering():
    """Kundur's book numbers its buses 1-11; PSTess's data (and stabctl's case) do not:
    a book number that is not a bus gets the map in the message."""
    from stabctl.io import load_case

    with pytest.raises(UnknownBusError, match=r"Kundur's book \(Example 12.6\) buses 1-11 are"):
        load_case("kundur").bus_index(7)


def test_machine_index():
    c = make_case()
    assert c.machine_index(2) == 1
    with pytest.raises(CaseError, match="machine 9"):
        c.machine_index(9)


# ---------------------------------------------------------------------------- validation


@pytest.mark.parametrize(
    "kwargs, pattern",
    [
        (
            dict(bus=modified(BUS, 2, 0, 2)),
            r"bus row 3 \(bus 2\), field 'number': duplicate bus number 2 \(first at row 2\)",
        ),
        (
            dict(line=modified(LINE, 1, 1, 99)),
            r"line row 2 \(2-99\), field 'to_bus': bus 99 does not exist",
        ),
        (
            dict(mac=modified(MAC, 1, 1, 42)),
            r"mac_con row 2 \(machine 2\), field 'bus': bus 42 does not exist",
        ),
        (
            dict(load=[[8, 0, 0, 0.5, 0]]),
            r"load_con row 1 \(bus 8\), field 'bus': bus 8 does not exist",
        ),
        (
            dict(exc=modified(EXC, 0, 1, 7)),
            r"exc_con row 1 \(machine 7\), field 'machine': machine 7 does not exist",
        ),
        (
            dict(pss=modified(PSS, 0, 1, 5)),
            r"pss_con row 1 \(machine 5\), field 'machine': machine 5 does not exist",
        ),
        (
            dict(tg=modified(TG, 0, 1, 3)),
            r"tg_con row 1 \(machine 3\), field 'machine': machine 3 does not exist",
        ),
        (
            dict(mac=modified(MAC, 1, 15, -6.5)),
            r"mac_con row 2 \(machine 2\), field 'H': inertia constant must be >= 0.001 s "
            r"\(H = 0, an infinite bus, only for a classical machine, x_d = 0, with x'd > 0\), "
            r"got -6.5",
        ),
        (  # H = 0 on a subtransient machine: an infinite bus is a classical one
            dict(mac=modified(MAC, 1, 15, 0.0)),
            r"mac_con row 2 \(machine 2\), field 'H': .*only for a classical machine.*got 0",
        ),
        (
            dict(mac=modified(MAC, 0, 6, -0.3)),
            r"mac_con row 1 \(machine 1\), field 'xdp': must be >= 0, got -0.3",
        ),
        (
            dict(mac=modified(MAC, 1, 0, 1)),
            r"mac_con row 2 \(machine 1\), field 'number': duplicate machine number 1",
        ),
        (
            dict(line=modified(modified(LINE, 0, 2, 0.0), 0, 3, 0.0)),
            r"line row 1 \(1-3\), field 'x': series impedance",
        ),
        # a negative tap ran into a power flow that did not converge
        (
            dict(line=modified(LINE, 1, 5, -1.0)),
            r"line row 2 \(2-3\), field 'tap': off-nominal tap ratio must be > 0 \(0 stands "
            r"for 1\), got -1",
        ),
        (  # a tap changer (tapmax != 0) steps between its limits by its step
            dict(line=[LINE[0], LINE[1][:7] + [1.2, -0.8, 0.01]]),
            r"line row 2 \(2-3\), field 'tapmin': tap changer's lowest ratio must be > 0, got -0.8",
        ),
        (
            dict(line=[LINE[0], LINE[1][:7] + [0.9, 1.1, 0.01]]),
            r"line row 2 \(2-3\), field 'tapmax': tap changer's tapmax must be >= tapmin, got 0.9",
        ),
        (
            dict(line=[LINE[0], LINE[1][:7] + [1.2, 0.8, 0.0]]),
            r"line row 2 \(2-3\), field 'tapstep': tap changer's step must be > 0",
        ),
        (
            dict(bus=modified(BUS, 1, 1, float("nan"))),
            r"bus row 2 \(bus 2\), field 'vmag': non-finite value",
        ),
        (
            dict(bus=modified(BUS, 1, 9, 4)),
            r"bus row 2 \(bus 2\), field 'kind': bus type must be 1, 2 or 3",
        ),
        (dict(bus=modified(BUS, 0, 9, 2)), r"no swing bus"),
        (
            dict(bus=modified(BUS, 2, 0, 3.5)),
            r"bus row 3 \(bus 3.5\), field 'number': must be an integer",
        ),
        (
            dict(load=[[3, 0, 0, 1.2, 0]]),
            r"load_con row 1 \(bus 3\), field 'p_current': fraction must be in \[0, 1\]",
        ),
        (
            dict(load=[[3, 0.6, 0, 0.5, 0]]),
            r"load_con row 1 \(bus 3\), field 'p_current': p_power \+ p_current must be <= 1",
        ),
        (dict(exc=EXC + EXC), r"exc_con row 2 \(machine 1\), field 'machine': duplicate"),
    ],
)
def test_validation_names_table_row_and_field(kwargs, pattern):
    with pytest.raises(CaseError, match=pattern):
        make_case(**kwargs)


def test_series_capacitors_phase_shifts_and_a_tap_of_0_are_taken():
    """The branch checks refuse what cannot be (a negative tap), nothing a network holds:
    a series capacitor's x < 0, a phase shift of any sign, PST's tap 0 for 1."""
    rows = [LINE[0], modified([LINE[1]], 0, 3, -0.004)[0][:5] + [0.0, -30.0, 0, 0, 0]]
    br = BranchTable.from_matrix(rows)
    assert (br.x[1], br.tap[1], br.phase_deg[1]) == (-0.004, 0.0, -30.0)


def test_wrong_column_count():
    with pytest.raises(CaseError, match=r"pss_con: wrong column count 9, expected 10"):
        PssTable.from_matrix([r[:9] for r in PSS])
    with pytest.raises(CaseError, match=r"bus: wrong column count 16, expected 10 to 15"):
        BusTable.from_matrix([r + [0] for r in BUS])
    with pytest.raises(
        CaseError, match=r"line row 2: 9 columns, 1 other row\(s\) have 10 \(row 1\)"
    ):
        BranchTable.from_matrix([LINE[0], LINE[1][:9]])
    # the row that differs from the others is named, not the row after a broken first row
    with pytest.raises(CaseError, match=r"^line row 1: 11 columns, 2 other row\(s\) have 10$"):
        BranchTable.from_matrix([LINE[0] + [1.0], LINE[1], LINE[1]])
    with pytest.raises(CaseError, match=r"^line row 1: 9 columns, 2 other row\(s\) have 10$"):
        BranchTable.from_matrix([LINE[0][:9], LINE[1], LINE[1]])


def test_bad_bases_and_sw_con():
    c = make_case()
    with pytest.raises(CaseError, match="base_mva must be > 0"):
        c.replace(base_mva=0)
    with pytest.raises(CaseError, match="sw_con: wrong column count 6"):
        c.replace(sw_con=[[0, 0, 0, 0, 0, 0]])
    sw = [[0, 0, 0, 0, 0, 0, 0.01], [0.1, 3, 4, 0, 0, 0, 0.01], [0.15] + [0] * 6]
    sw += [[0.2] + [0] * 6, [5.0] + [0] * 6]  # PST's layout: start, fault, near, far, end
    backwards = np.array(sw)
    backwards[3, 0] = 0.12  # the far end cleared before the near end, 0.15 s
    with pytest.raises(
        CaseError, match=r"sw_con row 4, column 1 \(time\): 0.12 s comes before row 3's 0.15 s"
    ):
        c.replace(sw_con=backwards)
    same = np.array(sw)
    same[3, 0] = same[2, 0]  # both ends cleared at once: PSTess's own Kundur-type data
    assert c.replace(sw_con=same).sw_con[3, 0] == same[2, 0]


# ---------------------------------------------------------------------------- built-ins


def test_list_cases_has_both_builtins_with_descriptions():
    cases = list_cases()
    assert set(cases) >= {"kundur", "miniwecc"}
    assert "two-area" in cases["kundur"] and "miniWECC" in cases["miniwecc"]


def test_builtin_kundur_matches_d2asbegp():
    k = load_case("kundur")
    assert (k.name, k.base_mva, k.freq_hz) == ("kundur", 100.0, 60.0)
    assert k.buses.number.tolist() == [1, 2, 3, 4, 10, 11, 12, 13, 14, 20, 101, 110, 120]
    assert len(k.branches) == 14 and len(k.machines) == 4
    assert k.machines.bus.tolist() == [1, 2, 11, 12]
    assert k.buses.bshunt[k.bus_index(101)] == 1.27
    assert k.branches.tap[2] == 0.975 and k.branches.tapstep[2] == 0.00625
    assert k.loads.bus.tolist() == [4, 14] and k.loads.p_current.tolist() == [0.5, 0.5]
    np.testing.assert_array_equal(k.sw_con[1], [0.1, 3, 101, 0, 0, 0, 0.01])
    assert k.extra["lmod_con"].shape == (2, 7)
    assert "MIT" in (Path(stabctl.__file__).parent / "case" / "data" / "LICENSE").read_text()


def test_builtin_miniwecc_matches_d_minniwecc_base():
    w = load_case("miniwecc")
    assert (w.n_bus, len(w.branches), len(w.machines), len(w.governors)) == (122, 171, 34, 21)
    assert np.all(w.branches.tap == 1.0)  # 5-column line matrix
    assert np.all(w.exciters.type == 3) and len(w.pss) == 34
    assert w.buses.number[w.swing_index].tolist() == [17]
    assert w.buses.pload[w.bus_index(24)] == 28.5  # PDC(1) already in the bus loads
    assert w.extra["PDC"].ravel().tolist() == [28.5, 19]
    assert w.governors.T4[0] == -1.0  # hydro: negative lead constant kept


def test_load_case_errors():
    with pytest.raises(CaseError, match=r"unknown case 'nosuch'.*kundur"):
        load_case("nosuch")
    with pytest.raises(CaseError, match="case file not found"):
        load_case("/nonexistent/case.json")


def test_case_layer_never_reads_shared():
    src = Path(stabctl.__file__).parent
    for name in ("case/system.py", "io/pst.py", "network/ybus.py", "network/powerflow.py"):
        py = src / name
        text = py.read_text()
        assert not re.search(r"(\.\./|/work/)shared", text), py


# -- one declaration per parameter (stabctl.models.declaration) -----------------------------

from stabctl.case import params as decl  # noqa: E402
from stabctl.io import dyr as dyr_io  # noqa: E402
from stabctl.io import dyr_converters  # noqa: E402
from stabctl.models import exciters as exc_m  # noqa: E402
from stabctl.models import governors as gov_m  # noqa: E402
from stabctl.models import machines as mac_m  # noqa: E402
from stabctl.models import pss as pss_m  # noqa: E402

DECLARED_TABLES = {
    "machines": MachineTable,
    "exciters": ExciterTable,
    "pss": PssTable,
    "governors": GovernorTable,
    "converters": ConverterTable,
}


@pytest.mark.parametrize("kind", sorted(DECLARED_TABLES))
def test_tables_are_their_declaration(kind):
    fam, cls = decl.FAMILIES[kind], DECLARED_TABLES[kind]
    assert cls.columns() == fam.names == tuple(p.name for p in fam.params)
    assert [p.col for p in fam.params] == list(range(1, len(fam.params) + 1))
    assert (cls.TABLE, cls.MIN_COLUMNS, cls.FAMILY) == (fam.table, fam.min_columns, fam)
    assert cls.INTEGER == tuple(p.name for p in fam.params if p.integer)
    given = np.ones((1, fam.min_columns))
    if kind == "machines":  # a subtransient machine's leakage lies below its x'd (x_l = 0.5)
        given[0, fam.col("xl") - 1] = 0.5
    if kind == "exciters":  # a DC1 (type 1) needs its T_E and T_F (columns 11, 17) and
        # saturation points with a fit (E2 = SE2 = 2, columns 14-15)
        given = np.hstack([given, np.ones((1, 17 - fam.min_columns))])
        given[0, 13:15] = 2.0
    tab = cls.from_matrix(given)  # omitted columns: the defaults
    for p in fam.params[given.shape[1] :]:
        assert getattr(tab, p.name)[0] == p.default
    for p in fam.params:
        assert p.name in cls.__doc__  # the docstring table comes from it


@pytest.mark.parametrize(
    "fam, table, row",
    [
        (exc_m.EXCITER, ExciterTable, EXC[0]),
        (pss_m.PSS, PssTable, None),
        (gov_m.GOVERNOR, GovernorTable, TG[0]),
        (mac_m.MACHINE, MachineTable, MAC[0]),
    ],
)
def test_declared_bound_violated_names_the_field(fam, table, row):
    row = list(row if row is not None else [1, 1, 100, 10, 0.05, 0.01, 0.05, 0.01, 0.2, -0.05])
    for p in [p for p in fam.params if p.lo is not None]:
        bad = row + [0.0] * (len(fam.params) - len(row))
        bad[p.col - 1] = p.lo - 1.0
        with pytest.raises(
            CaseError,
            match=rf"{fam.table} row 1 \(machine 1\), field "
            rf"'{p.name}': must be >= 0, got -1",
        ):
            table.from_matrix([bad])
    for p in [p for p in fam.params if p.choices]:
        bad = row + [0.0] * (len(fam.params) - len(row))
        bad[p.col - 1] = 99
        with pytest.raises(
            CaseError,
            match=rf"field '{p.name}': {p.label or p.name} must be "
            r".* or .*, got 99",
        ):
            table.from_matrix([bad])


def test_packed_kernel_columns_come_from_the_declaration():
    case = load_case("kundur").replace(
        # columns 3-20 all different, each limit above its lower one (Vrmax 15 > Vrmin 14)
        exciters=ExciterTable.from_matrix([[3, 1] + list(np.arange(20.0, 2.0, -1)) + [0, 0, 0, 0]])
    )
    ep = exc_m.exciter_params(case)
    P = ep.packed(np.zeros(1))
    # the shared layout, then the widest type's own columns (`exciters.N_OWN`)
    assert P.shape == (1, len(exc_m.E) + exc_m.N_OWN) == (1, len(exc_m.PACKED) + exc_m.N_OWN)
    for name in exc_m.TABLE_FIELDS:  # given columns as the table holds them
        if name not in ("KP", "KA"):
            assert P[0, getattr(exc_m.E, name.upper())] == getattr(case.exciters, name)[0]
            if exc_m.EXCITER.param(name).col <= 20:  # PST's columns keep their place
                assert exc_m.EXCITER.param(name).col - 1 == getattr(exc_m.E, name.upper())
    gp = gov_m.governor_params(load_case("kundur"))
    G = gp.packed(np.zeros(gp.n))
    for name in gov_m.TABLE_FIELDS:
        np.testing.assert_array_equal(
            G[:, getattr(gov_m.G, name.upper())], getattr(load_case("kundur").governors, name)
        )
        if gov_m.GOVERNOR.col(name) <= 16:  # PST's and the PSS/E columns keep their place
            assert gov_m.GOVERNOR.col(name) - 1 == getattr(gov_m.G, name.upper())
    assert set(pss_m.TABLE_FIELDS) <= set(pss_m.PSS.names)
    assert set(mac_m.TABLE_FIELDS) <= set(mac_m.MACHINE.names)


def test_dyr_field_maps_come_from_the_declaration():
    for fam in decl.FAMILIES.values():
        for model in fam.dyr:
            if model.name in dyr_converters.CONVERTER_DYR:  # read by stabctl.io.dyr_converters
                assert dyr_converters.CONVERTER_DYR[model.name] is model
                continue
            assert dyr_io.N_PARAMS[model.name] == len(model.fields)
            assert dyr_io.DYR_MODELS[model.name] is model
            for target in model.copy:  # every copy lands in a declared column
                fam.col(target)
            row = fam.dyr_row(model, np.arange(1.0, len(model.fields) + 1))
            assert len(row) == len(fam.params)
            for target, src in model.copy.items():
                assert row[fam.col(target) - 1] == model.fields.index(src) + 1


def test_kundur_bus_numbers_map_onto_kundurs_book():
    """The description's PSTess-to-book bus map turns the case's branches into Kundur's
    Example 12.6 network (Fig. 12.93): step-up transformers 1-5, 2-6, 3-11, 4-10, lines
    5-6, 6-7, 7-8 (two circuits), 8-9 (two), 9-10, 10-11; PSTess's load buses 4 and 14
    hang off 7 and 9 by transformers."""
    case = load_case("kundur")
    pst = [
        int(b) for b in re.search(r"buses 1-11 are ([\d, ]+), and", case.description)[1].split(",")
    ]
    book = {p: k + 1 for k, p in enumerate(pst)}
    branches = sorted(
        tuple(sorted((book[int(a)], book[int(b)])))
        for a, b in zip(case.branches.from_bus, case.branches.to_bus)
        if int(a) in book and int(b) in book
    )
    assert branches == sorted(
        [
            (1, 5),
            (2, 6),
            (3, 11),
            (4, 10),
            (5, 6),
            (6, 7),
            (7, 8),
            (7, 8),
            (8, 9),
            (8, 9),
            (9, 10),
            (10, 11),
        ]
    )
    loads = {
        int(a) if int(b) in book else int(b)
        for a, b in zip(case.branches.from_bus, case.branches.to_bus)
        if not (int(a) in book and int(b) in book)
    }
    assert loads == {4, 14}
    assert {book[int(b)] for b in case.machines.bus} == {1, 2, 3, 4}


def test_converter_shares_of_a_bus_s_generation_must_not_exceed_it(tmp_path):
    """A case file whose converters at one bus take more than all of its generation (ibr_con
    ``pfrac`` edited to 2: the run refused it only as it started, for a current limit the
    converter then met): refused as the file is read, naming the file, the table, the row,
    the field and the sums; at a bus with a machine, machines and converters take all of
    it, as import-andes requires of an ANDES file's shares (an idle converter, 0, is
    fine)."""
    from stabctl.io.pst import case_to_dict

    kundur = load_case("kundur")
    mac_bus = int(kundur.machines.bus[0])
    free = int(next(b for b in kundur.buses.number if b not in set(kundur.machines.bus)))

    def with_converters(*rows):
        table = ConverterTable.from_matrix([[n, b, 1, 100.0, p, q, 0.0, 1] for n, b, p, q in rows])
        return kundur.replace(converters=table)

    with_converters((1, mac_bus, 0.0, 0.0), (2, free, 0.6, 1.0), (3, free, 0.4, 0.0))
    for rows, fld, sums in (
        (((1, free, 0.6, 0.5), (2, free, 0.6, 0.5)), "pfrac", "pfrac 1.2 and qfrac 1"),
        (((1, mac_bus, 0.0, 0.5),), "qfrac", "pfrac 1 and qfrac 1.5"),
    ):
        with pytest.raises(CaseError, match=rf"field '{fld}': bus \d+'s converters .*take {sums} "):
            with_converters(*rows)
    with pytest.raises(
        CaseError,
        match=rf"field 'pfrac': bus {mac_bus}'s converters 1 and machines 1 take pfrac "
        r"0.5 and qfrac 1 of its power, not 1",
    ):
        with_converters((1, mac_bus, -0.5, 0.0))
    data = case_to_dict(with_converters((1, free, 0.5, 0.5), (2, free, 0.5, 0.5)))
    conv = data["tables"]["converters"]
    conv["rows"][0][conv["columns"].index("pfrac")] = 2.0
    (tmp_path / "edited.json").write_text(json.dumps(data))
    expected = (
        f"{tmp_path / 'edited.json'}: table 'converters' row 1 (converter 1), field 'pfrac': "
        f"bus {free}'s converters 1, 2 take pfrac 2.5 and qfrac 1 of its power: more than all "
        "of it (at most 1)"
    )
    with pytest.raises(CaseError, match=f"^{re.escape(expected)}$"):
        load_case(tmp_path / "edited.json")


def test_a_case_prints_as_one_line_of_its_sizes():
    """`print(load_case(...))` printed every table (about 2 900 lines for the 240-bus WECC
    case): a case prints as one line of its name, sizes, base and frequency."""
    from stabctl.io import load_case

    case = load_case("kundur")
    assert (
        repr(case)
        == str(case)
        == (
            "Case('kundur': 13 buses, 14 branches, 4 machines, 4 exciters, 4 governors, "
            "0 converters, 100 MVA, 60 Hz)"
        )
    )
