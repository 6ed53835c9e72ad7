"""PSS/E DYR import (stabctl.io.dyr) and the models it maps to: exc_dc12 (DC1/DC2), TGOV1,
IEEEG1.  Reference values: the ANDES DYR files (parameter order of the PSS/E Model
Library), closed forms of the linear blocks, steady-state equalities of the models."""

from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from stabctl.case import ExciterTable, GovernorTable, MachineTable, PssTable
from stabctl.dynamics.driver import Simulator
from stabctl.errors import CaseError
from stabctl.io import load_case
from stabctl.io.dyr import VRMAX_UNLIMITED, dyr_tables, exp_saturation, read_dyr
from stabctl.io.psse import load_psse
from stabctl.models import exciters as exc
from stabctl.models import governors as gov
from stabctl.models import machines as mac
from stabctl.models import pss as pss_
from stabctl.models.exciters import EXCITER
from stabctl.models.governors import GOVERNOR
from stabctl.models.machines import MACHINE
from stabctl.models.pss import PSS
from stabctl.smallsignal.linearise import linearise

from model_rows import EXST1, IEEEG1

pytestmark = pytest.mark.andes  # every test reads ANDES's case files
andes = pytest.importorskip("andes")
CASES = Path(andes.__file__).parent / "cases"
KUNDUR_DYR = CASES / "kundur" / "kundur_full.dyr"
WECC_DYR = CASES / "wecc" / "wecc_full.dyr"


#: a GENROU record's data for the tests whose machine has an exciter (an exciter of a GENCLS
#: is left out, round 47)
ROUND = "'GENROU' 1 8.0 0.03 0.4 0.05 6.175 0 1.8 1.7 0.3 0.55 0.25 0.2 0 0 /\n"


def kundur_generators(mbase=900.0):
    """The four Kundur generators as the RAW reader gives them (ANDES buses 1-4, id 1)."""
    return [dict(number=k, bus=k, id="1", mbase=mbase, ra=0.0, xsource=0.25) for k in range(1, 5)]


def wecc_generators(records):
    keys = sorted({(r.bus, r.id) for r in records if r.model == "GENROU"})
    return [
        dict(number=i + 1, bus=b, id=d, mbase=100.0, ra=0.0, xsource=0.2)
        for i, (b, d) in enumerate(keys)
    ]


def andes_initialised(folder):
    """ANDES's own case <folder>.raw + <folder>_full.dyr, power flow solved, dynamics
    initialised."""
    cases = CASES / folder
    ss = andes.load(
        str(cases / f"{folder}.raw"),
        addfile=str(cases / f"{folder}_full.dyr"),
        setup=True,
        no_output=True,
        default_config=True,
    )
    ss.PFlow.run()
    ss.TDS.init()
    return ss


def write(tmp_path, text, name="t.dyr"):
    p = tmp_path / name
    p.write_text(text, encoding="utf-8")
    return p


@pytest.fixture(scope="module")
def kundur_tables():
    return dyr_tables(
        read_dyr(KUNDUR_DYR), kundur_generators(), on_unsupported="skip", conventions="pst"
    )


# -- parsing and mapping against the files ------------------------------------------------------


def test_kundur_records_as_in_the_file():
    recs = read_dyr(KUNDUR_DYR)
    assert [r.model for r in recs[:3]] == ["GENROU", "EXDC2", "TGOV1"]
    assert (recs[0].line, recs[1].line, recs[2].line) == (1, 4, 8)
    assert recs[0].params == (
        8.0,
        0.03,
        0.4,
        0.05,
        6.5,
        0.0,
        1.8,
        1.7,
        0.3,
        0.55,
        0.25,
        0.06,
        0.0,
        0.0,
    )
    assert recs[-1].model == "TOGGLE" and recs[-1].line == 37  # ANDES's own event record


def test_kundur_genrou_to_mac_sub(kundur_tables):
    m = kundur_tables.mac_con
    row = dict(
        zip(
            (
                "number",
                "bus",
                "mva",
                "xl",
                "ra",
                "xd",
                "xdp",
                "xdpp",
                "Tdop",
                "Tdopp",
                "xq",
                "xqp",
                "xqpp",
                "Tqop",
                "Tqopp",
                "H",
                "D0",
            ),
            m[2],
        )
    )
    assert row == dict(
        number=3,
        bus=3,
        mva=900,
        xl=0.06,
        ra=0,
        xd=1.8,
        xdp=0.3,
        xdpp=0.25,
        Tdop=8.0,
        Tdopp=0.03,
        xq=1.7,
        xqp=0.55,
        xqpp=0.25,
        Tqop=0.4,
        Tqopp=0.05,
        H=6.175,
        D0=0,
    )
    assert m.shape == (4, len(MACHINE.names)) and np.all(m[:, 21:24] == 1.0)  # pfrac, qfrac,
    # speed effects
    assert np.all(m[:, 24] == 0)  # PST's mac_sub: no saturation
    assert np.all(m[:, 25] == 0)  # not a playback source (column 26)


def test_kundur_exdc2_to_dc2_and_tgov1(kundur_tables):
    e = kundur_tables.exc_con[0]
    # type 2 (bus fed), TR KA TA TB TC VRMAX VRMIN KE TE; E1 = SE1 = 0: no saturation
    np.testing.assert_array_equal(e[:11], [2, 1, 0.02, 20, 0.02, 1, 1, 5.2, -4.16, 1, 0.83])
    assert (e[12], e[13], e[14], e[15], e[16]) == (0, 0, 0, 0.0754, 1.246)
    g = GovernorTable.from_matrix(kundur_tables.tg_con)
    assert (g.type[0], g.invR[0], g.Ts[0], g.Tmax[0], g.Tmin[0]) == (2, 1 / 0.05, 0.49, 33, 0.4)
    assert (g.T3[0], g.Tc[0], g.Dt[0]) == (2.1, 7.0, 0.0)
    assert kundur_tables.pss_con is None


def test_wecc_ieeeg1_sums_hp_and_lp():
    recs = read_dyr(WECC_DYR)
    t = dyr_tables(recs, wecc_generators(recs), on_unsupported="skip")
    g = GovernorTable.from_matrix(t.tg_con)
    # K = 20, T1 = 0.1, T2 = 0, T3 = 0.2, Uo = 1, Uc = -1, PMAX 0.95, T4 = 0.1, T7 = 8.72
    assert (g.type[0], g.invR[0], g.Tc[0], g.T3[0], g.Ts[0]) == (3, 20, 0.1, 0, 0.2)
    assert (g.Uo[0], g.Uc[0], g.Tmax[0], g.Tmin[0], g.T4[0], g.T7[0]) == (1, -1, 0.95, 0, 0.1, 8.72)
    assert (g.K5[0], g.K7[0]) == (0.3, 0.7)
    p = gov.governor_params(
        load_case("kundur").replace(
            governors=g.select(np.arange(4)).replace(machine=np.array([1, 2, 3, 4]))
        )
    )
    np.testing.assert_allclose(p.K[0], [0, 0, 0.3, 0.7])


def test_psse_conventions_read_exst1_as_pss_e_and_no_other_control_differently():
    """conventions="psse" (the default) marks WECC's EXST1 rows psse_st1 = 1 (PSS/E's
    output limits and rate feedback, docs/pst_models.md 12.6), gives its DC exciters
    (ESDC2A) PSS/E's quadratic saturation through their own points (next tests), its
    ESST3A the machine's field current (ifd_machine = 1, as PSS/E's I_N = K_C I_FD / V_E),
    its ESDC2A a field voltage held at >= 0 (efd_floor = 1, round 50) and leaves every
    other exciter, PSS and governor column as "pst" reads it."""
    recs = read_dyr(WECC_DYR)
    gens = wecc_generators(recs)
    pst = dyr_tables(recs, gens, on_unsupported="skip", conventions="pst")
    psse = dyr_tables(recs, gens, on_unsupported="skip")
    col = ExciterTable.columns().index("psse_st1")
    st1 = pst.exc_con[:, 0] == exc.ST1
    assert st1.sum() > 0
    assert np.all(psse.exc_con[st1, col] == 1) and np.all(psse.exc_con[~st1, col] == 0)
    assert np.all(pst.exc_con[:, col] == 0)
    dc = np.isin(pst.exc_con[:, 0], (exc.DC1, exc.DC2))
    assert dc.sum() == 8 and np.all(psse.exc_con[dc, 22] == 1)  # dc_sat: the quadratic
    sat = [11, 12, 13, 14, 22]  # E1 SE1 E2 SE2 dc_sat (columns 12-15, 23)
    ifd = ExciterTable.columns().index("ifd_machine")
    st3 = pst.exc_con[:, 0] == exc.ST3
    assert st3.sum() == 4 and np.all(psse.exc_con[st3, ifd] == 1)
    assert np.all(psse.exc_con[~st3, ifd] == 0) and np.all(pst.exc_con[:, ifd] == 0)
    floor = ExciterTable.columns().index("efd_floor")  # ESDC2A's Efd >= 0 (PSS/E's)
    assert np.all(psse.exc_con[dc, floor] == 1) and np.all(pst.exc_con[:, floor] == 0)
    zero = dc & (pst.exc_con[:, 7] == VRMAX_UNLIMITED)  # VRMAX = 0: computed from E2
    assert zero.sum() == 8
    ke, e2, se2 = (psse.exc_con[zero, c] for c in (9, 13, 14))  # E2 SE2: the points
    ceiling = (np.maximum(ke, 0) + se2) * e2  # PSS/E PAG 15.2.4 (docs 12.4)
    np.testing.assert_allclose(psse.exc_con[zero, 7], ceiling, rtol=1e-14)
    np.testing.assert_array_equal(psse.exc_con[zero, 8], -psse.exc_con[zero, 7])
    others = (np.arange(pst.exc_con.shape[1]) != col) & ~np.isin(
        np.arange(pst.exc_con.shape[1]), [*sat, ifd, floor]
    )
    np.testing.assert_array_equal(pst.exc_con[~zero][:, others], psse.exc_con[~zero][:, others])
    limits = others & ~np.isin(np.arange(pst.exc_con.shape[1]), [7, 8])
    np.testing.assert_array_equal(pst.exc_con[zero][:, limits], psse.exc_con[zero][:, limits])
    np.testing.assert_array_equal(pst.exc_con[~dc][:, sat], psse.exc_con[~dc][:, sat])
    np.testing.assert_array_equal(pst.tg_con, psse.tg_con)  # WECC has no HYGOV
    np.testing.assert_array_equal(pst.pss_con, psse.pss_con)


def test_psse_conventions_read_hygov_with_pss_e_gate():
    """conventions="psse" marks HYGOV psse_gate = 1 (tg_con column 22, the PI's whole
    output rate- and position-limited, docs/pst_models.md 12.6), every other column as
    "pst"; PSS/E's HYGOV run (tests/data/psse_runs/HYGOV)."""
    run = Path(__file__).resolve().parents[1] / "data" / "psse_runs" / "HYGOV"
    raw, dyr = run / "ThreeBusMulti.raw", run / "ThreeBus_HYGOV.dyr"
    psse = load_psse(raw, dyr).governors
    pst = load_psse(raw, dyr, conventions="pst").governors
    n = len(GovernorTable.columns())
    assert psse.col(22).tolist() == [1.0] and pst.col(22).tolist() == [0.0]
    for c in set(range(1, n + 1)) - {22}:
        np.testing.assert_array_equal(psse.col(c), pst.col(c))


def test_esst1a_vos_2_read_by_psse_refused_by_pst(tmp_path):
    """ESST1A with VOS = 2 (the stabiliser after V_A): conventions="psse" reads it
    (vos_after_va, exc_con column 20, = 1); "pst" leaves it out, naming VOS."""
    run = Path(__file__).resolve().parents[1] / "data" / "psse_runs" / "ESST1A"
    dyr = tmp_path / "vos2.dyr"
    dyr.write_text(
        (run / "TVC_System.dyr").read_text().replace("'ESST1A'  1   1  1", "'ESST1A'  1   1  2")
    )
    raw = run / "TVC_System_32.raw"
    assert load_psse(raw, dyr).exciters.VGmax.tolist() == [1.0]
    assert load_psse(raw, run / "TVC_System.dyr").exciters.VGmax.tolist() == [0.0]
    with pytest.raises(CaseError, match=r"ESST1A.*VOS = 2: not modelled"):
        load_psse(raw, dyr, conventions="pst")


@pytest.mark.parametrize("uel", [0, 5])
def test_esst1a_uel_outside_psse_s_codes_is_refused(tmp_path, uel):
    """ESST1A's UEL, the under-excitation limiter's input (PSS/E Model Library: 1, 2 or
    3), given 0 or 5 ran without a word: refused naming the record, UEL and its value."""
    run = Path(__file__).resolve().parents[1] / "data" / "psse_runs" / "ESST1A"
    dyr = tmp_path / "uel.dyr"
    dyr.write_text(
        (run / "TVC_System.dyr")
        .read_text()
        .replace("'ESST1A'  1   1  1", f"'ESST1A'  1   {uel}  1")
    )
    with pytest.raises(CaseError, match=rf"ESST1A.*UEL = {uel} must be 1, 2 or 3"):
        load_psse(run / "TVC_System_32.raw", dyr)


def test_andes_conventions_change_only_what_andes_reads_differently():
    pst = dyr_tables(
        read_dyr(KUNDUR_DYR), kundur_generators(), on_unsupported="skip", conventions="pst"
    )
    andes_ = dyr_tables(
        read_dyr(KUNDUR_DYR), kundur_generators(), on_unsupported="skip", conventions="andes"
    )
    speed = MachineTable.columns().index("speed_effects")
    sat = MachineTable.columns().index("psse_sat")  # GENROU's air-gap saturation
    assert np.all(pst.mac_con[:, speed] == 1) and np.all(andes_.mac_con[:, speed] == 0)
    assert np.all(pst.mac_con[:, sat] == 0) and np.all(andes_.mac_con[:, sat] == 1)
    assert np.all(pst.exc_con[:, 0] == 2) and np.all(andes_.exc_con[:, 0] == 1)  # EXDC2
    others = np.ones(pst.mac_con.shape[1], bool)
    others[[speed, sat]] = False
    np.testing.assert_array_equal(pst.mac_con[:, others], andes_.mac_con[:, others])
    # EXDC2's saturation: PST's exponential (A, B stored) or the quadratic through the
    # points (stored as given), K_E as given (columns 23, 24)
    np.testing.assert_array_equal(pst.exc_con[:, 1:11], andes_.exc_con[:, 1:11])
    np.testing.assert_array_equal(pst.exc_con[:, 15:20], andes_.exc_con[:, 15:20])
    assert np.all(pst.exc_con[:, 22:] == 0) and np.all(andes_.exc_con[:, 22:24] == 1)
    np.testing.assert_array_equal(andes_.exc_con[0, 11:15], [0, 0, 1, 1])  # E1 SE1 E2 SE2
    # IEEEG1's rate limits Uo, Uc: machine base (PSS/E) or system base (ANDES)
    recs = read_dyr(WECC_DYR)
    gens = [dict(g, mbase=400.0, sbase=100.0) for g in wecc_generators(recs)]
    g_pst = GovernorTable.from_matrix(dyr_tables(recs, gens).tg_con)
    t_andes = dyr_tables(recs, gens, conventions="andes")
    g_andes = GovernorTable.from_matrix(t_andes.tg_con)
    e = ExciterTable.from_matrix(t_andes.exc_con)
    dc2 = e.type == exc.DC2  # WECC's 8 ESDC2A
    assert dc2.sum() == 8 and np.all(e.TR[dc2] == 0) and np.all(e.dc_sat[dc2] == 1)
    st3 = e.type == exc.ST3  # WECC's 4 ESST3A: I_N from the machine's I_fd
    assert st3.sum() == 4 and np.all(e.ifd_machine[st3] == 1) and np.all(e.ifd_machine[~st3] == 0)
    pst_tables = dyr_tables(recs, gens, conventions="pst")  # PST's exc_st3 estimate
    assert np.all(ExciterTable.from_matrix(pst_tables.exc_con).ifd_machine == 0)
    assert (g_pst.Uo[0], g_pst.Uc[0]) == (1.0, -1.0)
    assert (g_andes.Uo[0], g_andes.Uc[0]) == (0.25, -0.25)
    with pytest.raises(CaseError, match="conventions"):
        dyr_tables(recs, gens, conventions="pss/e")


def test_unsupported_records_are_listed_with_file_and_line(tmp_path):
    with pytest.raises(CaseError) as e:
        dyr_tables(read_dyr(KUNDUR_DYR), kundur_generators())
    assert str(e.value).endswith(
        "kundur_full.dyr:37 TOGGLE (bus 0, id LINE_8): model TOGGLE is not mapped"
    )
    text = (
        "1 'GENCLS' 1 3.0 0.0 /\n1 'ESST5B' 1 0 0 /\n"
        "1 'IEEEST' 1 1 0 0 0 0 0 0 0 0.2 0.02 0 0.5 1.5 10 20 0.1 -0.1 0 0 /\n"
        "1 'HYGOV4' 1 0 0 0 0.05 0.1 0.2 0.3 -0.3 1 0 1 0.05 0.5 1 1 0 1 0.08 /\n"
    )
    with pytest.raises(CaseError) as e:
        dyr_tables(read_dyr(write(tmp_path, text)), kundur_generators()[:1])
    # PSS/E's HYGOV4 (deadbands, gate-power curve) is not ANDES's HYGOV4, which stabctl
    # reads from ANDES only
    assert str(e.value).splitlines()[1:] == [
        "  t.dyr:2 ESST5B (bus 1, id 1): model ESST5B is not mapped",
        "  t.dyr:3 IEEEST (bus 1, id 1): its machine has no (supported) exciter",
        "  t.dyr:4 HYGOV4 (bus 1, id 1): model HYGOV4 is not mapped",
    ]


def test_wecc_imports_completely():
    recs = read_dyr(WECC_DYR)
    t = dyr_tables(recs, wecc_generators(recs))
    assert (t.mac_con.shape, t.exc_con.shape, t.pss_con.shape, t.tg_con.shape) == (
        (29, len(MACHINE.names)),  # every declared column (28, stabctl.models.machines)
        (29, len(EXCITER.names)),  # every declared column (43, stabctl.models.exciters)
        (29, len(PSS.names)),  # every declared column (44, stabctl.models.pss)
        (29, len(GOVERNOR.names)),  # every declared column (59, stabctl.models.governors)
    ) and t.unsupported == ()
    kinds = dict(zip(*np.unique(t.exc_con[:, 0], return_counts=True)))
    assert kinds == {2: 8, 3: 4, 4: 17}  # ESDC2A, ESST3A, EXST1


def test_wecc_esdc2a_to_dc2():
    """Line 60 (bus 10): TR .02 KA 50 TA .05 TB .02 TC 0 VRMAX 0 (read as PSS/E: computed
    from E2, (KE + SE(E2)) E2 = 5.57019 with VRMIN = -VRMAX, PAG 15.2.4; as PST: no limit,
    as ANDES, and VRMIN as given) VRMIN -3
    KE 0 (computed at initialisation) TE .512 KF .07 TF1 1.3 Switch 0 E1 3.9825 SE1 .5
    E2 5.31 SE2 1.049.  Saturation: read as PSS/E (the default), the two points themselves
    for PSS/E's quadratic (dc_sat = 1, column 23) with K_E computed (ke_given = 0, column
    24); read as PST, its exponential A exp(B E) through them (E2 column 0)."""
    recs = read_dyr(WECC_DYR)
    gens = wecc_generators(recs)
    n10 = next(g["number"] for g in gens if g["bus"] == 10)
    for conventions in ("psse", "pst"):
        t = dyr_tables(recs, gens, conventions=conventions)
        e = t.exc_con[t.exc_con[:, 1] == n10][0]
        ceiling = (0 + 1.049) * 5.31 if conventions == "psse" else None  # (KE + SE(E2)) E2
        limits = [ceiling, -ceiling] if ceiling else [999, -3]
        head = [2, n10, 0.02, 50, 0.05, 0.02, 0, *limits, 0, 0.512]
        np.testing.assert_allclose(e[:11], head, rtol=1e-15)
        assert (e[15], e[16]) == (0.07, 1.3)
        if conventions == "psse":
            assert (e[11], e[12], e[13], e[14], e[22], e[23]) == (3.9825, 0.5, 5.31, 1.049, 1, 0)
            continue
        A, B = e[12], e[14]
        assert (e[13], e[22], e[23]) == (0, 0, 0)
        points = A * np.exp(B * np.array([3.9825, 5.31]))
        np.testing.assert_allclose(points, [0.5, 1.049], rtol=1e-14)


def test_psse_dc_exciter_saturation_is_pss_e_quadratic():
    """Read as PSS/E, WECC's ESDC2A at bus 10 saturates as the PSS/E Model Library's
    S_E(E) = B (E - A)^2 / E through its two points (OpenIPSL's "PTI PSS/E" ``SE``):
    S_E(3.9825) = 0.5 and S_E(5.31) = 1.049, where the exciter's feedback with K_E =
    -S_E(E) vanishes."""
    from stabctl.models.exciters import _dc_saturation, dc_feedback

    recs = read_dyr(WECC_DYR)
    gens = wecc_generators(recs)
    t = dyr_tables(recs, gens, on_unsupported="skip")
    n10 = next(g["number"] for g in gens if g["bus"] == 10)
    r = int(np.nonzero(t.exc_con[:, 1] == n10)[0][0])
    (A,), (B,) = _dc_saturation(ExciterTable.from_matrix(t.exc_con[r : r + 1]))
    for E, SE in ((3.9825, 0.5), (5.31, 1.049)):
        assert B * (E - A) ** 2 / E == pytest.approx(SE, rel=1e-12)
        assert dc_feedback(-SE, A, B, 1.0, E) == pytest.approx(0, abs=1e-12)


def test_wecc_esst3a_to_exc_st3():
    """Line 8 (bus 3): TR .02 VIMAX .3 VIMIN -.2 KM 8 TC 1 TB 5 KA 20 TA 0 VRMAX 99 VRMIN -99
    KG 1 KP 3.67 KI .435 VBMAX 6.48 KC .01 XL .0098 VGMAX 4.86 THETAP 3.33 TM .4 VMMAX 99
    VMMIN 0 -> exc_st3 with K_J = KA, K_A = KM, T_A = TM, V_R limits = VM limits, V_B
    limited to VBMAX (column 26)."""
    recs = read_dyr(WECC_DYR)
    gens = wecc_generators(recs)
    t = dyr_tables(recs, gens, on_unsupported="skip")
    r = [g["bus"] for g in gens].index(3)
    row = t.exc_con[list(t.exc_con[:, 1]).index(gens[r]["number"])]
    np.testing.assert_array_equal(
        row[:20],
        [
            3,
            gens[r]["number"],
            0.02,
            8,
            0.4,
            5,
            1,
            99,
            0,
            0.3,
            -0.2,
            20,
            3.67,
            3.33,
            0.435,
            0.0098,
            0.01,
            6.48 * 99,
            1,
            4.86,
        ],
    )
    assert row[EXCITER.col("VBmax") - 1] == 6.48
    np.testing.assert_array_equal(
        t.pss_con[0],
        [2, gens[r]["number"], -2 * 1.0, 4.2, 0, 0.75, 0, 0, 0.1, -0.1]
        + [0] * (len(PSS.names) - 10),
    )


def test_wecc_exst1_mapping():
    recs = read_dyr(WECC_DYR)
    gens = wecc_generators(recs)
    t = dyr_tables(recs, gens, on_unsupported="skip")
    e = ExciterTable.from_matrix(t.exc_con)
    r = list(e.machine).index(next(g["number"] for g in gens if g["bus"] == 8))
    # line 44: TR .02 VIMAX 99 VIMIN -99 TC 0 TB .02 KA 50 TA .02 VRMAX 9999 VRMIN -9999
    # KC 0 KF .01 TF 1
    assert (e.type[r], e.TR[r], e.VImax[r], e.VImin[r]) == (4, 0.02, 99, -99)
    assert (e.TC[r], e.TB[r]) == (0, 0.02)
    assert (e.KA[r], e.TA[r], e.Vrmax[r], e.Vrmin[r], e.KC[r]) == (50, 0.02, 9999, -9999, 0)
    assert (e.KF[r], e.TF[r]) == (0.01, 1.0)


def test_ieeest_maps_to_pst_pss_when_equivalent(tmp_path):
    text = (
        f"1 {ROUND}1 'SEXS' 1 0.1 10 100 0.05 -5 5 /\n"
        "1 'IEEEST' 1 1 0 0 0 0 0 0 0 0.2 0.02 0 0.5 1.5 10 20 0.1 -0.1 0 0 /\n"
    )
    t = dyr_tables(read_dyr(write(tmp_path, text)), kundur_generators()[:1])
    # speed input (PST type 1), K*Tw = KS T5 = 20 * 1.5, Tw = T6, lead-lags (0.2/0.02), (0/0.5)
    np.testing.assert_array_equal(
        t.pss_con[0], [1, 1, 30, 10, 0.2, 0.02, 0, 0.5, 0.1, -0.1] + [0] * (len(PSS.names) - 10)
    )
    np.testing.assert_array_equal(t.exc_con[0][:9], [0, 1, 0, 100, 0.05, 10, 1.0, 5, -5])
    assert t.mac_con[0][6] == 0.3 and t.mac_con[0][5] == 1.8  # the GENROU's x'd, x_d


def test_gensal_has_no_q_axis_transient_circuit(tmp_path):
    text = "1 'GENSAL' 1 5.0 0.05 0.1 3.0 0.0 1.2 0.7 0.3 0.2 0.1 0.1 0.3 /\n"
    m = dyr_tables(read_dyr(write(tmp_path, text)), kundur_generators()[:1]).mac_con[0]
    assert (m[10], m[11], m[12], m[13], m[14]) == (0.7, 0.7, 0.2, 0.0, 0.1)  # xq, x'q=xq, x''q=x''d


# -- errors --------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "text, message",
    [
        ("1 'GENCLS' 1 3.0 0.0\n", r"t.dyr:1: record not terminated by '/'"),
        ("\n1 'GENCLS' 1 3.0 x0 /\n", r"t.dyr:2 GENCLS \(bus 1, id 1\): D = 'x0': not a number"),
        ("1 GENCLS 1 3.0 0.0 /\n", r"t.dyr:1: malformed record"),
        # the tokens skipped a quote that opens no string: 'GENCLS was read as GENCLS
        ("1 'GENCLS 1 3.0 0.0 /\n", r"t.dyr:1: the quote ' at column 3 is not closed"),
        ("1 'GENCLS' 1 3.0 0.0 ' /\n", r"t.dyr:1: the quote ' at column 22 is not closed"),
        # a comment's apostrophe where the record lacks its '/' (round 29: the message
        # pointed at the apostrophe only, not at the '/' missing)
        (
            "1 'GENCLS' 1 3.0 0.0 the paper's machine\n",
            r"t.dyr:1: the quote ' at column 31 is not closed: .*; if it is in a comment, the "
            r"record before it is not terminated by '/'",
        ),
        (
            "B1 'GENCLS' 1 3.0 0.0 /\n",
            r"t.dyr:1 GENCLS \(bus B1, id 1\): IBUS = 'B1': not an integer",
        ),
        # float() and int() read 3_0 as 30, 0_2 as 2 and fullwidth digits as ASCII ones
        ("1 'GENCLS' 1 3_0 0.0 /\n", r"t.dyr:1 GENCLS \(bus 1, id 1\): H = '3_0': not a number"),
        ("1 'GENCLS' 1 \uff13.0 0.0 /\n", r"t.dyr:1 GENCLS \(bus 1, id 1\): H = '\uff13.0': not a"),
        (
            "0_2 'GENCLS' 1 3.0 0.0 /\n",
            r"t.dyr:1 GENCLS \(bus 0_2, id 1\): IBUS = '0_2': not an integer",
        ),
        (
            "\uff12 'GENCLS' 1 3.0 0.0 /\n",
            r"t.dyr:1 GENCLS \(bus \uff12, id 1\): IBUS = '\uff12': not an",
        ),
        # round 46: read as bus 2, where the RAW reader (and PSS/E) refuse a real number in
        # an integer field
        ("2.0 'GENCLS' 1 3.0 0.0 /\n", r"t.dyr:1 GENCLS \(bus 2.0, id 1\): IBUS = '2.0': not an"),
        ("2E0 'GENCLS' 1 3.0 0.0 /\n", r"t.dyr:1 GENCLS \(bus 2E0, id 1\): IBUS = '2E0': not an"),
    ],
)
def test_malformed_records_name_file_and_line(tmp_path, text, message):
    with pytest.raises(CaseError, match=message):
        read_dyr(write(tmp_path, text))


@pytest.mark.parametrize(
    "text, message",
    [
        (
            "1 'GENCLS' 1 3.0 /\n",
            r"t.dyr:1 GENCLS \(bus 1, id 1\): needs 2 parameters after the id, got 1",
        ),
        (
            "1 'GENCLS' 1 3.0 0 /\n7 'GENCLS' 1 3.0 0 /\n",
            r"unsupported DYR .*\n  t.dyr:2 GENCLS \(bus 7, id 1\): matches no generator in",
        ),
        (
            "1 'GENCLS' 1 3.0 0 /\n1 'GENCLS' 1 3.0 0 /\n",
            r"t.dyr:2 GENCLS .*second machine model .*t.dyr:1",
        ),
        ("1 'GENCLS' 1 -1.0 0 /\n", r"H = -1.0 s must be >= 0 \(0: an infinite bus\)"),
        (
            "1 'GENCLS' 1 3.0 0 /\n1 'TGOV1' 1 0 0.5 1 0 1 2 0 /\n",
            r"t.dyr:2 TGOV1 .*droop R = 0 must",
        ),
        ("1 'TGOV1' 1 0.05 0.5 1 0 1 2 0 /\n", r"machine 1 \(bus 1, id 1\)"),
    ],
)
def test_mapping_errors_name_the_record(tmp_path, text, message):
    with pytest.raises(CaseError, match=message):
        dyr_tables(read_dyr(write(tmp_path, text)), kundur_generators()[:1])


def test_ids_compare_without_quotes_and_other_models_parse_leniently(tmp_path):
    text = "1 'GENCLS' '1 ' 3.0 0 /\n1 'USRMDL' 1 'GENTPJU1' 1 0 2 /  comment\n"
    recs = read_dyr(write(tmp_path, text))
    assert recs[0].id == "1" and recs[1].model == "USRMDL" and np.isnan(recs[1].params[0])
    t = dyr_tables(recs, [dict(kundur_generators()[0], id="'1'")], on_unsupported="skip")
    assert t.mac_con.shape == (1, len(MACHINE.names)) and [r.line for r in t.unsupported] == [2]


def test_generator_without_machine_model_is_named(tmp_path):
    with pytest.raises(CaseError, match=r"machine 2 \(bus 2, id 1\)"):
        dyr_tables(read_dyr(write(tmp_path, "1 'GENCLS' 1 3.0 0 /\n")), kundur_generators()[:2])


# -- model equations ------------------------------------------------------------------------------


def test_exponential_saturation_passes_both_points():
    A, B = exp_saturation(3.1, 0.33, 2.3, 0.1)
    np.testing.assert_allclose([A * np.exp(B * 3.1), A * np.exp(B * 2.3)], [0.33, 0.1], rtol=1e-14)
    assert exp_saturation(0.0, 0.0, 1.0, 1.0) == (0.0, 0.0)


def dc_params(kind=exc.DC1, KE=1.0, A=0.0, B=0.0):
    e = ExciterTable.from_matrix(
        [[kind, 1, 0.02, 20, 0.02, 1, 1, 5.2, -4.16, KE, 0.83, 0, A, 0, B, 0.0754, 1.246, 0, 0, 0]]
    )
    return exc.exciter_params(load_case("kundur").replace(exciters=e))


@pytest.mark.parametrize("KE", [1.0, 0.0])
def test_dc_exciter_steady_state_vr_equals_ke_plus_se_times_efd(KE):
    """V_R0 = (K_E + S_E(Efd0)) Efd0 (PST exc_dc12 flag 0); K_E = 0 -> -S_E(Efd0): V_R0 = 0;
    all derivatives zero at the initial point."""
    A, B = exp_saturation(3.1, 0.33, 2.3, 0.1)
    p = dc_params(KE=KE, A=A, B=B)
    Efd, Vt = 1.9, 1.03
    x, Vref, p = exc.initialise(p, np.array([Efd]), np.array([Vt]))
    SE = A * np.exp(B * Efd)
    KE_eff = KE if KE else -SE
    assert x[2, 0] == pytest.approx((KE_eff + SE) * Efd, abs=1e-15)
    assert Vref[0] == pytest.approx(Vt + x[2, 0] / 20, rel=1e-15)
    dx = np.zeros_like(x)
    exc.derivatives(p.packed(Vref), x, 0, Vt, Vt, 0.0, Efd, Efd, 1.0, dx, True, 0.0)
    assert np.abs(dx).max() < 1e-12


def test_quadratic_saturation_passes_both_points_and_keeps_ke():
    """ANDES's (and PSS/E's) DC saturation SE(E) E = B (E - A)^2 through (E1, SE1),
    (E2, SE2) (WECC bus 111's ESDC2A data); with ke_given, K_E = 0 stays 0 and
    V_R0 = B (Efd0 - A)^2; all derivatives zero at the initial point."""
    E1, SE1, E2, SE2 = 2.625, 0.54, 20.0, 1.0
    row = [
        exc.DC2,
        1,
        0.02,
        40.5,
        0.06,
        0.02,
        0,
        999,
        -2,
        0,
        0.5,
        E1,
        SE1,
        E2,
        SE2,
        0.05,
        1.0,
        0,
        0,
        0,
        0,
        0,
        1,
        1,
    ]
    p = exc.exciter_params(load_case("kundur").replace(exciters=ExciterTable.from_matrix([row])))
    A, B = p.Asat[0], p.Bsat[0]
    np.testing.assert_allclose(
        [B * (E1 - A) ** 2, B * (E2 - A) ** 2], [SE1 * E1, SE2 * E2], rtol=1e-13
    )
    Efd, Vt = 1.9, 1.03
    x, Vref, p = exc.initialise(p, np.array([Efd]), np.array([Vt]))
    assert p.KE[0] == 0.0 and x[2, 0] == pytest.approx(B * (Efd - A) ** 2, rel=1e-14)
    dx = np.zeros_like(x)
    exc.derivatives(p.packed(Vref), x, 0, Vt, Vt, 0.0, Efd, Efd, 1.0, dx, True, 0.0)
    assert np.abs(dx).max() < 1e-12
    row[23] = 0  # K_E = 0 computed: V_R0 = 0
    p = exc.exciter_params(load_case("kundur").replace(exciters=ExciterTable.from_matrix([row])))
    x, Vref, p = exc.initialise(p, np.array([Efd]), np.array([Vt]))
    assert p.KE[0] == pytest.approx(-B * (Efd - A) ** 2 / Efd) and abs(x[2, 0]) < 1e-15


def test_dc2_limit_scales_with_terminal_voltage():
    """DC2 (bus fed): V_R is held at VRMAX * V_t; DC1 at VRMAX."""
    for kind, bound in ((exc.DC1, 5.2), (exc.DC2, 5.2 * 0.5)):
        p = dc_params(kind)
        x, Vref, p = exc.initialise(p, np.array([1.0]), np.array([1.0]))
        x[2, 0] = 10.0
        dx = np.zeros_like(x)
        exc.derivatives(p.packed(Vref + 1.0), x, 0, 0.5, 0.5, 0.0, 1.0, 1.0, 1.0, dx, True, 0.0)
        assert x[2, 0] == pytest.approx(bound, rel=1e-15) and dx[2, 0] == 0.0


def test_dc2_state_held_on_a_limit_that_rose_within_reach():
    """DC2 under ieee: V_R held at VRMAX V_t = 5.2 x 0.5 when V_t then rises to 0.51 is
    inside the new limit 2.652 by 0.052 pu while K_A V_A drives it out at (K_A V_A - V_R)/T_A
    pu/s; within one step's reach it is set on the limit with a zero derivative (no
    alternation between the full derivative and zero); with no reach (the linearisation,
    or a step too short to get there) it keeps its derivative.  DC1's fixed limit never
    moves: no reach is applied."""
    p = dc_params(exc.DC2)
    x0, Vref, p = exc.initialise(p, np.array([1.0]), np.array([1.0]))
    P = p.packed(Vref + 1.0)
    for reach, held in ((0.01, True), (0.0, False), (1e-6, False)):
        x = x0.copy()
        x[2, 0] = 5.2 * 0.5
        dx = np.zeros_like(x)
        exc.derivatives(P, x, 0, 0.51, 0.51, 0.0, 1.0, 1.0, 1.0, dx, True, reach)
        if held:
            assert x[2, 0] == pytest.approx(5.2 * 0.51, rel=1e-15) and dx[2, 0] == 0.0
        else:
            assert x[2, 0] == 5.2 * 0.5 and dx[2, 0] > 0.052 / 0.01


def st1_params(KC=0.1, KF=0.01):
    e = ExciterTable.from_matrix(
        [
            [
                4,
                1,
                0.02,
                50,
                0.02,
                0.02,
                0.1,
                4.0,
                -3.0,
                0.2,
                -0.2,
                0,
                0,
                0,
                0,
                0,
                KC,
                0,
                0,
                0,
                KF,
                1.0,
            ]
        ]
    )
    return exc.exciter_params(load_case("kundur").replace(exciters=e))


def test_exst1_steady_state_and_output_limit():
    """Efd0 = V_R0 = K_A V_I0, Vref = V_t + Efd0/K_A, zero derivatives; output clipped to
    V_t Vrmax - K_C I_fd and V_t Vrmin (PSS/E EXST1)."""
    p = st1_params()
    Efd, Vt = 1.9, 1.02
    x, Vref, p = exc.initialise(p, np.array([Efd]), np.array([Vt]))
    assert (x[2, 0], x[3, 0]) == (Efd, Efd) and Vref[0] == pytest.approx(Vt + Efd / 50, rel=1e-15)
    P = p.packed(Vref)
    assert exc.field_voltage_at(P, x, 0, Vt, 0.0, 1.0, Efd, True) == Efd
    dx = np.full_like(x, np.nan)
    exc.derivatives(P, x, 0, Vt, Vt, 0.0, Efd, Efd, 1.0, dx, True, 0.0)
    assert np.abs(dx).max() < 1e-12
    x[2, 0] = 10.0
    assert exc.field_voltage_at(P, x, 0, 0.9, 0.0, 1.0, 2.0, True) == pytest.approx(
        0.9 * 4.0 - 0.1 * 2.0
    )
    x[2, 0] = -10.0
    assert exc.field_voltage_at(P, x, 0, 0.9, 0.0, 1.0, 2.0, True) == pytest.approx(0.9 * -3.0)


def test_exst1_initial_point_outside_limits_is_refused():
    with pytest.raises(CaseError, match=r"exc_con row 1: EXST1 initial field voltage 3\.9"):
        exc.initialise(st1_params(), np.array([3.9]), np.array([1.0]))


def tgov1_params(Dt=0.0):
    g = GovernorTable.from_matrix([[2, 1, 1, 20, 1.2, 0.49, 7.0, 2.1, 0, 0, 0.1, Dt]])
    return gov.governor_params(load_case("kundur").replace(governors=g))


def test_tgov1_pm_equals_pref_at_rated_speed_and_damps_with_dt():
    p = tgov1_params(Dt=2.0)
    x, Pref = gov.initialise(p, np.array([0.78]))
    P = p.packed(Pref)
    assert Pref[0] == 0.78 and gov.pmech(P, x, 0, 1.0) == pytest.approx(0.78, rel=1e-15)
    assert gov.pmech(P, x, 0, 1.01) == pytest.approx(0.78 - 2.0 * 0.01, rel=1e-14)
    dx = np.zeros_like(x)
    gov.derivatives(P, x, 0, 1.0, 0.0, dx)
    assert np.abs(dx).max() < 1e-15


def test_start_up_limit_checks_allow_round_off_only():
    """A power order at TGOV1's limit up to the power flow's round-off (IEEE 14's bus-6
    unit: Pm0 = 0.3 = Tmin lands at 0.3 - 3e-17) starts; 1e-3 pu beyond it is refused,
    naming the row."""
    p = tgov1_params()
    for at in (p.Tmin[0], p.Tmax[0]):
        for pm in (at - 3e-17, at + 3e-17, np.nextafter(at, -1), np.nextafter(at, 9)):
            gov.initialise(p, np.array([pm]))
    for pm in (p.Tmin[0] - 1e-3, p.Tmax[0] + 1e-3):
        with pytest.raises(CaseError, match=r"tg_con row 1: .* outside \[Tmin, Tmax\]"):
            gov.initialise(p, np.array([pm]))
    e = dc_params(KE=1.0)  # DC1: V_R0 = K_E Efd0 against Vrmax = 5.2
    exc.initialise(e, np.array([5.2 * (1 + 1e-15)]), np.array([1.0]))
    with pytest.raises(CaseError, match="exc_con row 1: initial DC regulator output"):
        exc.initialise(e, np.array([5.21]), np.array([1.0]))


def test_tgov1_step_response_matches_closed_form():
    """Pref step dP: Pm(t) = dP [1 - (T1 - T2)/(T1 - T3) e^(-t/T1)
    - (T3 - T2)/(T3 - T1) e^(-t/T3)]."""
    p = tgov1_params()
    x0, Pref = gov.initialise(p, np.array([0.5]))
    dP, T1, T2, T3 = 0.1, 0.49, 2.1, 7.0
    P = p.packed(Pref + dP)

    def f(t, y):
        x, dx = y.reshape(x0.shape).copy(), np.zeros_like(x0)
        gov.derivatives(P, x, 0, 1.0, 0.0, dx)
        return dx.ravel()

    t = 3.0
    sol = solve_ivp(f, (0, t), x0.ravel(), rtol=1e-11, atol=1e-13)
    pm = gov.pmech(P, sol.y[:, -1].reshape(x0.shape), 0, 1.0) - 0.5
    exact = dP * (
        1 - (T1 - T2) / (T1 - T3) * np.exp(-t / T1) - (T3 - T2) / (T3 - T1) * np.exp(-t / T3)
    )
    assert pm == pytest.approx(exact, rel=1e-8)


def test_tgov1_valve_is_non_windup():
    p = tgov1_params()
    x, Pref = gov.initialise(p, np.array([1.1]))
    dx = np.zeros_like(x)
    x[0, 0] = 1.3
    gov.derivatives(p.packed(Pref + 1.0), x, 0, 1.0, 0.0, dx)
    assert x[0, 0] == 1.2 and dx[0, 0] == 0.0


def ieeeg1_params():
    g = GovernorTable.from_matrix([IEEEG1])
    return gov.governor_params(load_case("kundur").replace(governors=g))


def test_ieeeg1_steady_state_and_gate_rate_limit():
    """Pm = (K1+..+K8) gate in steady state; a large Pref step moves the gate at Uo."""
    p = ieeeg1_params()
    x, gate = gov.initialise(p, np.array([0.7]))
    assert gate[0] == pytest.approx(0.7, rel=1e-15)  # K sum = 0.3 + 0.6 + 0.1 = 1
    P = p.packed(gate)
    assert gov.pmech(P, x, 0, 1.0) == pytest.approx(0.7, rel=1e-15)
    dx = np.zeros_like(x)
    gov.derivatives(P, x, 0, 1.0, 0.0, dx)
    assert np.abs(dx).max() < 1e-15
    gov.derivatives(p.packed(gate + 0.2), x, 0, 1.0, 0.0, dx)
    assert dx[1, 0] == 0.5  # (0.2 / T3 = 1) limited to Uo
    gov.derivatives(P, x, 0, 1.01, 0.0, dx)  # speed up 1 %: the T1 lag starts at K dw/T1
    assert dx[1, 0] == 0.0 and dx[0, 0] == pytest.approx(20 * 0.01 / 0.1, rel=1e-12)
    x[0, 0] = 0.4  # lag output K dw = 0.4: (0 - 0.4)/T3 -> Uc
    gov.derivatives(P, x, 0, 1.02, 0.0, dx)
    assert dx[1, 0] == -1.0 and dx[0, 0] == pytest.approx(0.0, abs=1e-12)


# -- the models in the simulator and the linearisation -------------------------------------------


def replaced_kundur(exc_con, tg_con):
    case = load_case("kundur")
    return case.replace(
        exciters=ExciterTable.from_matrix(exc_con),
        governors=GovernorTable.from_matrix(tg_con),
        pss=case.pss.empty(),
    )


@pytest.fixture(scope="module")
def dyr_kundur(kundur_tables):
    """Built-in Kundur with ANDES's EXDC2 and TGOV1 data (the machines stay PSTess's)."""
    return replaced_kundur(kundur_tables.exc_con, kundur_tables.tg_con)


def test_flat_run_with_exdc2_and_tgov1_has_no_drift(dyr_kundur):
    sim = Simulator(dyr_kundur)
    residual, where = sim.model_for([]).initial_residual
    assert residual < 1e-9, where
    r = sim.run([], 10.0)
    assert np.abs(r.speed - 1).max() < 1e-9
    assert np.abs(r.efd - r.efd[0]).max() < 1e-9 and np.abs(r.pmech - r.pmech[0]).max() < 1e-9


def test_flat_run_with_ieeex1_and_ieeeg1_has_no_drift(kundur_tables):
    exc_con = kundur_tables.exc_con.copy()
    exc_con[:, 0] = 1  # IEEEX1: solid-fed DC1
    exc_con[:, 12], exc_con[:, 14] = exp_saturation(3.1, 0.33, 2.3, 0.1)
    rows = np.tile(
        GovernorTable.from_matrix([IEEEG1]).matrix(),
        (4, 1),
    )
    rows[:, 1] = [1, 2, 3, 4]
    sim = Simulator(replaced_kundur(exc_con, rows))
    residual, where = sim.model_for([]).initial_residual
    assert residual < 1e-9, where
    r = sim.run([], 10.0)
    assert np.abs(r.speed - 1).max() < 1e-9 and np.abs(r.pmech - r.pmech[0]).max() < 1e-9
    # per machine 6 + DC 5 + IEEEG1 4 (lead-lag, gate, T4, T7 lags; T5 = T6 = 0 pass through)
    sys = linearise(sim)
    assert sys.nstates == 4 * (6 + 5 + 4) and "tg_T7lag_G1" in sys.state_labels
    B, s, i = np.asarray(sys.B), sys.state_labels, sys.input_labels
    assert B[s.index("tg_gate_G2"), i.index("Pref_G2")] == pytest.approx(1 / 0.2, rel=1e-9)


def test_flat_run_with_exst1_has_no_drift(kundur_tables):
    """WECC's EXST1 data (T_C = 0: no transient gain; with T_C/T_B = 5 and no PSS, Kundur's
    inter-area mode is unstable and round-off grows), K_C = 0.1 so the I_fd limit acts."""
    e = np.tile(ExciterTable.from_matrix([[*EXST1[:6], 0.0, *EXST1[7:]]]).matrix(), (4, 1))
    e[:, 1] = [1, 2, 3, 4]
    sim = Simulator(replaced_kundur(e, kundur_tables.tg_con))
    residual, where = sim.model_for([]).initial_residual
    assert residual < 1e-9, where
    r = sim.run([], 10.0)
    assert np.abs(r.speed - 1).max() < 1e-9 and np.abs(r.efd - r.efd[0]).max() < 1e-9
    sys = linearise(sim)  # 6 + EXST1 4 (V_TR, V_As, V_R, R_f) + 2
    assert sys.nstates == 4 * (6 + 4 + 2) and "exc_Rf_G3" in sys.state_labels


def test_flat_run_with_esst3a_and_ieeest_has_no_drift():
    """WECC's ESST3A (as exc_st3) and power-input IEEEST (as PST pss) on Kundur's machines,
    with K_C = 0: PST's exc_st3 feeds K_C a field current formed differently from the one
    of its initialisation, so K_C != 0 starts off equilibrium (docs/pst_models.md 12.2)."""
    recs = read_dyr(WECC_DYR)
    gens = wecc_generators(recs)
    t = dyr_tables(recs, gens, on_unsupported="skip")
    n3 = next(g["number"] for g in gens if g["bus"] == 3)
    e = np.tile(t.exc_con[t.exc_con[:, 1] == n3], (4, 1))
    p = np.tile(t.pss_con[t.pss_con[:, 1] == n3], (4, 1))
    e[:, 1] = p[:, 1] = [1, 2, 3, 4]
    case = load_case("kundur")
    e[:, 16] = 0.0  # K_C
    case = case.replace(exciters=ExciterTable.from_matrix(e), pss=PssTable.from_matrix(p))
    sim = Simulator(case)
    residual, where = sim.model_for([]).initial_residual
    assert residual < 1e-9, where
    r = sim.run([], 10.0)
    assert np.abs(r.speed - 1).max() < 1e-9 and np.abs(r.efd - r.efd[0]).max() < 1e-9


def test_linearised_dyr_kundur_states_and_reference_inputs(dyr_kundur):
    """States: 6 machine + 5 DC exciter (V_TR, V_As, V_R, Efd, R_f) + 2 TGOV1 per machine;
    dV_R'/dVref = K_A/T_A (T_C = T_B), d valve'/dPref = 1/T1 (closed forms of the blocks)."""
    sys = linearise(dyr_kundur)
    assert sys.nstates == 4 * (6 + 5 + 2)
    B, s, i = np.asarray(sys.B), sys.state_labels, sys.input_labels
    assert B[s.index("exc_VR_G2"), i.index("Vref_G2")] == pytest.approx(20 / 0.02, rel=1e-9)
    assert B[s.index("tg_valve_G3"), i.index("Pref_G3")] == pytest.approx(1 / 0.49, rel=1e-9)
    assert np.all(np.linalg.eigvals(np.asarray(sys.A)).real < 1e-3)


KUNDUR_PST_DYR = """\
1 'GENSAL' 1  8.0 0.03 0.05  6.5 0.0  1.8 1.7 0.3 0.25 0.2  0.0 0.0 /
2 'GENCLS' 1  6.5 0.0 /
11 'GENROU' 1 8.0 0.03 0.4 0.05  6.175 0.0  1.8 1.7 0.3 0.55 0.25 0.2  0.0 0.0 /
12 'GENROU' 1 8.0 0.03 0.4 0.05  6.175 0.0  1.8 1.7 0.3 0.55 0.25 0.2  0.0 0.0 /
1 'SEXS' 1  1.0 1.0 200 0.05 -5 5 /
11 'SEXS' 1  0.2 10.0 200 0.05 -5 5 /
12 'EXDC2' 1  0.02 20 0.02 1 1 5.2 -4.16 1 0.83 0.0754 1.246 0 3.1 0.33 2.3 0.1 /
1 'TGOV1' 1  0.05 0.49 33 0.4 2.1 7.0 0.0 /
2 'TGOV1' 1  0.05 0.49 33 0.4 2.1 7.0 1.0 /
11 'TGOV1' 1  0.05 0.49 33 0.4 2.1 7.0 0.0 /
"""


def test_kundur_network_with_dyr_machines_runs_flat(tmp_path):
    """Built-in Kundur network with every machine, exciter and governor from DYR records
    (GENSAL, GENCLS, GENROU; SEXS, EXDC2 with saturation; TGOV1 with Dt; machine 4 without
    governor): equilibrium at t = 0, no drift, GENSAL's E'd identically 0 (docs 12.1)."""
    case = load_case("kundur")
    gens = [
        dict(number=int(k), bus=int(b), id="1", mbase=900.0, ra=0.0, xsource=0.3)
        for k, b in zip(case.machines.number, case.machines.bus)
    ]
    t = dyr_tables(read_dyr(write(tmp_path, KUNDUR_PST_DYR)), gens)
    case = case.replace(
        machines=MachineTable.from_matrix(t.mac_con),
        exciters=ExciterTable.from_matrix(t.exc_con),
        pss=PssTable.empty(),
        governors=GovernorTable.from_matrix(t.tg_con),
    )
    sim = Simulator(case)
    m = sim.model_for([])
    assert m.initial_residual[0] < 1e-9, m.initial_residual[1]
    assert list(m.mp.kind) == [2, 0, 2, 2]  # mac_sub, mac_em, mac_sub x2
    assert abs(m.layout.view(m.x0, "mac")[4, 0]) < 1e-12  # GENSAL: E'd = 0
    r = sim.run([], 10.0)
    assert np.abs(r.speed - 1).max() < 1e-9 and np.abs(r.efd - r.efd[0]).max() < 1e-9


# -- PSS/E stabilisers (pss type 3) ------------------------------------------------------------


def test_wecc_st2cut_mapping():
    """Line 21 (bus 5): MODE 1 BUSR 0 MODE2 0 BUSR2 0 K1 5.5 K2 0 T1 .03 T2 0 T3 10 T4 10
    T5 .4 T6 .04 T7..T10 0 LSMAX .05 LSMIN -.05 VCU 0 VCL 0."""
    recs = read_dyr(WECC_DYR)
    gens = wecc_generators(recs)
    t = dyr_tables(recs, gens, on_unsupported="skip")
    n5 = next(g["number"] for g in gens if g["bus"] == 5)
    s = PssTable.from_matrix(t.pss_con[t.pss_con[:, 1] == n5])
    assert (s.type[0], s.input1[0], s.K1[0], s.Tr1[0], s.input2[0]) == (3, 1, 5.5, 0.03, 0)
    assert (s.KTw[0], s.Tw[0], s.T1[0], s.T2[0], s.T3[0], s.T4[0]) == (10, 10, 0.4, 0.04, 0, 0)
    assert (s.ymax[0], s.ymin[0]) == (0.05, -0.05)


def test_st2cut_cut_off_is_relative_to_the_initial_terminal_voltage(tmp_path):
    """PSS/E's ST2CUT passes its output while VT0 + VCL < VT < VT0 + VCU, VT0 the initial
    terminal voltage (OPAL-RT's PSS/E ST2CUT, ``Output_Limiter_2``: VCL + VTO < VT < VCU +
    VTO; ANDES 2.0 ``st2cut.py``: VOU = VCUr + v0, VOL = VCLr + v0); IEEEST's and PSS1A's
    VCU, VCL are terminal voltages.  Round 51 found ST2CUT's read as terminal voltages: VCU
    0.1, VCL -0.1 cut the output off at all times (VT0 1.02).  PSS/E's GENROU run's case
    with an SEXS and an ST2CUT on the speed, its states moved from rest: with VCU 0.1, VCL
    -0.1 the output passes at VT0 and VT0 - 0.09, and is 0 at VT0 - 0.11 and VT0 + 0.11;
    with VCU = VCL = 0 it passes everywhere."""
    run = Path(__file__).resolve().parents[1] / "data" / "psse_runs" / "GENROU"
    dyr = (run / "ThreeBus_GENROU.dyr").read_text().rstrip() + "\n"
    st2cut = "102 'ST2CUT' 1 1 0 0 0 20 0 0.02 0 5 5 0.2 0.05 0.3 0.1 0 0 0.1 -0.1 {} {} /\n"
    sexs = "102 'SEXS' 1 0.1 10 100 0.1 0 5 /\n"
    for vcu, vcl in ((0.1, -0.1), (0.0, 0.0)):
        path = tmp_path / f"st2cut_{vcu}.dyr"
        path.write_text(dyr + sexs + st2cut.format(vcu, vcl))
        sim = Simulator(load_psse(run / "ThreeBusMulti.raw", path))
        model = sim.model_for([])
        pp = model.pp
        vt0 = abs(sim.op.V[model.mp.bus_idx[pp.mac[0]]])
        assert vt0 > 1.0 and pp.cut_relative[0] == 1
        P, x = pp.packed(), model.layout.view(model.x0, "pss") + 0.01  # away from rest
        out = []
        for vt in (vt0, vt0 - 0.09, vt0 - 0.11, vt0 + 0.11):
            dx = np.zeros_like(x)
            out.append(pss_.output_and_derivatives(P, x, 0, 1.001, 0.5, vt, dx))
        assert out[0] == out[1] != 0
        assert out[2:] == ([0.0, 0.0] if vcu else out[:2])


PSSE_ROW = [
    3,
    1,
    2.0,
    3.0,
    0.3,
    0.05,
    0.2,
    0.04,
    0.2,
    -0.2,
    0.1,
    0.02,
    1,
    20.0,
    0.03,
    3,
    0.5,
    0.1,
    0.05,
    0.002,
    0.02,
    0.0001,
    0.01,
    0.0005,
]


def psse_params(row=PSSE_ROW):
    return pss_.pss_params(load_case("kundur").replace(pss=PssTable.from_matrix([row])))


def test_psse_stabiliser_transfer_function_matches_closed_form():
    """Type 3, speed input: Vs/dw = K1/(1 + s Tr1) N(s)/D(s) K_w s/(1 + s T_w)
    prod (1 + s T_lead)/(1 + s T_lag), N = 1 + A5 s + A6 s^2, D = (1 + A1 s + A2 s^2)
    (1 + A3 s + A4 s^2), at 1 Hz, from the kernel's state equations (linear inside the
    output limits, here opened)."""
    p = psse_params(PSSE_ROW[:8] + [1e9, -1e9] + PSSE_ROW[10:])
    P = p.packed()
    x0 = pss_.initialise(p, *pss_.pss_inputs(p, np.array([1.0]), np.array([0.0])))
    act = np.nonzero(p.has_state()[:, 0])[0]

    def f(x, w):
        full, dx = x0.copy(), np.zeros_like(x0)
        full[act, 0] = x
        y = pss_.output_and_derivatives(P, full, 0, w, 0.0, 1.0, dx)
        return dx[act, 0], y

    n, h = act.size, 1e-4
    A, C = np.zeros((n, n)), np.zeros(n)
    for j in range(n):
        e = np.zeros(n)
        e[j] = h
        (fp, yp), (fm, ym) = f(x0[act, 0] + e, 1.0), f(x0[act, 0] - e, 1.0)
        A[:, j], C[j] = (fp - fm) / (2 * h), (yp - ym) / (2 * h)
    (fp, yp), (fm, ym) = f(x0[act, 0], 1.0 + h), f(x0[act, 0], 1.0 - h)
    B, D = (fp - fm) / (2 * h), (yp - ym) / (2 * h)
    s = 2j * np.pi
    H = C @ np.linalg.solve(s * np.eye(n) - A, B) + D
    Kw, Tw, T1, T2, T3, T4 = PSSE_ROW[2:8]
    T5, T6, K1, Tr1 = PSSE_ROW[10], PSSE_ROW[11], PSSE_ROW[13], PSSE_ROW[14]
    A1, A2, A3, A4, A5, A6 = PSSE_ROW[18:]
    exact = (
        K1
        / (1 + s * Tr1)
        * (1 + A5 * s + A6 * s**2)
        / ((1 + A1 * s + A2 * s**2) * (1 + A3 * s + A4 * s**2))
        * Kw
        * s
        / (1 + s * Tw)
        * (1 + s * T1)
        / (1 + s * T2)
        * (1 + s * T3)
        / (1 + s * T4)
        * (1 + s * T5)
        / (1 + s * T6)
    )
    assert H == pytest.approx(exact, rel=1e-7)
    assert n == 2 + 4 + 1 + 3  # lags, 4th-order filter, ...


def test_psse_stabiliser_output_is_zero_and_steady_at_the_initial_point():
    p = psse_params()
    u1, u2 = pss_.pss_inputs(p, np.array([1.0]), np.array([0.7]))
    assert (u1[0], u2[0]) == (0.0, 0.7)  # speed deviation, power
    x = pss_.initialise(p, u1, u2)
    dx = np.full_like(x, np.nan)
    y = pss_.output_and_derivatives(p.packed(), x, 0, 1.0, 0.7, 1.0, dx)
    assert y == pytest.approx(0, abs=1e-15)
    assert np.abs(dx).max() < 1e-14


def test_flat_run_and_linearisation_with_psse_stabilisers(dyr_kundur):
    """Kundur (EXDC2, TGOV1) with a type-3 stabiliser on every machine: equilibrium, no
    drift; the linearised model has its 10 states per PSS and no unstable mode."""
    rows = np.tile(PSSE_ROW, (4, 1))
    rows[:, 1] = [1, 2, 3, 4]
    rows[:, 13] = 2.0  # K1: a moderate speed gain
    case = dyr_kundur.replace(pss=PssTable.from_matrix(rows))
    sim = Simulator(case)
    residual, where = sim.model_for([]).initial_residual
    assert residual < 1e-9, where
    r = sim.run([], 10.0)
    assert np.abs(r.speed - 1).max() < 1e-9 and np.abs(r.efd - r.efd[0]).max() < 1e-9
    sys = linearise(sim)
    assert sys.nstates == 4 * (6 + 5 + 10 + 2)
    assert "pss_filter4_G2" in sys.state_labels


def test_ieeest_with_filter_maps_to_psse_type_and_other_inputs_are_unsupported(tmp_path):
    text = (
        f"1 {ROUND}1 'SEXS' 1 0.1 10 100 0.05 -5 5 /\n"
        "1 'IEEEST' 1 3 0 0.1 0.01 0 0 0.05 0 0.2 0.02 0 0.5 1.5 10 20 0.1 -0.1 0 0 /\n"
        f"2 {ROUND}2 'SEXS' 1 0.1 10 100 0.05 -5 5 /\n"
        "2 'IEEEST' 1 2 0 0 0 0 0 0 0 0.2 0.02 0 0.5 1.5 10 20 0.1 -0.1 0 0 /\n"
    )
    t = dyr_tables(read_dyr(write(tmp_path, text)), kundur_generators()[:2], on_unsupported="skip")
    s = PssTable.from_matrix(t.pss_con)
    assert (s.type[0], s.input1[0], s.K1[0], s.KTw[0], s.Tw[0]) == (3, 3, 1.0, 20 * 1.5, 10)
    assert (s.A1[0], s.A2[0], s.A5[0]) == (0.1, 0.01, 0.05)
    assert (s.T1[0], s.T2[0], s.T4[0]) == (0.2, 0.02, 0.5)
    assert [r.line for r in t.unsupported] == [6]  # ICS 2: bus frequency


def test_initial_point_matches_andes_kundur_full():
    """ANDES reference: kundur.raw + kundur_full.dyr solved and initialised by ANDES; from
    its bus voltages and generator powers, stabctl's mapping and initialisation give the
    same rotor angles, field voltages (GENROU vf0), mechanical powers (tm0, TGOV1 pref0)
    and EXDC2 voltage references (vref0)."""
    ss = andes_initialised("kundur")
    g = ss.GENROU
    rows = [ss.Bus.idx.v.index(b) for b in g.bus.v]
    t = dyr_tables(read_dyr(KUNDUR_DYR), kundur_generators(), on_unsupported="skip")
    case = load_case("kundur")  # its bus list holds ANDES's generator buses 1-4
    case = case.replace(
        machines=MachineTable.from_matrix(t.mac_con),
        exciters=ExciterTable.from_matrix(t.exc_con),
        governors=GovernorTable.from_matrix(t.tg_con),
    )
    mp = mac.machine_params(case)
    V, S = np.ones(case.n_bus, complex), np.zeros(case.n_bus, complex)
    V[mp.bus_idx] = ss.Bus.v.v[rows] * np.exp(1j * ss.Bus.a.v[rows])
    S[mp.bus_idx] = g.Pe.v + 1j * g.Qe.v
    x, vex, pm = mac.initialise(mp, V, S)
    np.testing.assert_allclose(x[0], g.delta.v, atol=1e-12)
    np.testing.assert_allclose(vex, g.vf0.v, atol=1e-12)
    _, Vref, _ = exc.initialise(exc.exciter_params(case), vex, np.abs(V[mp.bus_idx]))
    np.testing.assert_allclose(Vref, ss.EXDC2.vref0.v, atol=1e-12)
    _, Pref = gov.initialise(gov.governor_params(case), pm)
    np.testing.assert_allclose(Pref * 900 / 100, ss.TGOV1.pref0.v, rtol=1e-12)  # system base


def test_ieeex1_initialisation_matches_andes_npcc():
    """ANDES reference (npcc.raw + npcc_full.dyr, solved and initialised by ANDES): read as
    ANDES reads it (conventions="andes": quadratic saturation, K_E as given, V_R limits
    not times V_t), IEEEX1 gives ANDES's vref0 from ANDES's field and terminal voltages; PST's
    reading (exponential saturation, K_E = 0 -> V_R0 = 0) does not."""
    ss = andes_initialised("npcc")
    g, x1 = ss.GENROU, ss.IEEEX1
    assert x1.n == 24
    recs = [
        r for r in read_dyr(CASES / "npcc" / "npcc_full.dyr") if r.model in ("GENROU", "IEEEX1")
    ]
    keys = [(r.bus, r.id) for r in recs if r.model == "GENROU"]
    gens = [
        dict(number=i + 1, bus=b, id=d, mbase=100.0, ra=0.0, xsource=0.2, pg=1.0, qg=1.0)
        for i, (b, d) in enumerate(keys)
    ]
    # ANDES holds the records in file order: its k-th IEEEX1 is the file's k-th
    number = [keys.index((r.bus, r.id)) + 1 for r in recs if r.model == "IEEEX1"]
    k = [g.idx.v.index(s) for s in x1.syn.v]
    vt = np.array(ss.Bus.v.v)[[ss.Bus.idx.v.index(g.bus.v[i]) for i in k]]
    vref = {}
    for conventions in ("andes", "pst"):
        t = dyr_tables(recs, gens, conventions=conventions)
        rows = np.array([t.exc_con[t.exc_con[:, 1] == n][0] for n in number])
        rows[:, 1] = 1
        assert np.all(rows[:, 0] == 1)  # DC1 both ways (ANDES's limiter keeps VRMAX)
        kundur = load_case("kundur")  # one exciter at a time on its machine 1
        vref[conventions] = np.array(
            [
                exc.initialise(
                    exc.exciter_params(
                        kundur.replace(exciters=ExciterTable.from_matrix(row[None]))
                    ),
                    g.vf0.v[[i]],
                    vt[[j]],
                )[1][0]
                for j, (i, row) in enumerate(zip(k, rows))
            ]
        )
    np.testing.assert_allclose(vref["andes"], x1.vref0.v, atol=1e-12)
    assert np.max(np.abs(vref["pst"] - x1.vref0.v)) > 1e-3


def test_flat_run_with_wecc_esdc2a_has_no_drift(kundur_tables):
    """WECC's ESDC2A read as PSS/E (VRMAX = 0 computed from E2, 5.57019; K_E = 0 computed so
    that V_R0 = VRMAX/10, PAG 15.2.4) on Kundur's machines: equilibrium, V_R0 = 0.557019,
    no drift."""
    recs = read_dyr(WECC_DYR)
    gens = wecc_generators(recs)
    t = dyr_tables(recs, gens)
    n10 = next(g["number"] for g in gens if g["bus"] == 10)
    e = np.tile(t.exc_con[t.exc_con[:, 1] == n10], (4, 1))
    e[:, 1] = [1, 2, 3, 4]
    sim = Simulator(replaced_kundur(e, kundur_tables.tg_con))
    m = sim.model_for([])
    assert m.initial_residual[0] < 1e-9, m.initial_residual[1]
    np.testing.assert_allclose(m.layout.view(m.x0, "exc")[2], 1.049 * 5.31 / 10, rtol=1e-14)
    r = sim.run([], 10.0)
    assert np.abs(r.speed - 1).max() < 1e-9 and np.abs(r.efd - r.efd[0]).max() < 1e-9


def test_exst1_and_ieeeg1_initialisation_match_andes_wecc():
    """ANDES reference (wecc.raw + wecc_full.dyr, solved and initialised by ANDES): from
    ANDES's field voltages, terminal voltages and mechanical powers, stabctl's EXST1 gives
    ANDES's vref0 and IEEEG1 its pref0 (machine base here, system base in ANDES)."""
    ss = andes_initialised("wecc")
    g = ss.GENROU
    gens = [
        dict(number=i + 1, bus=int(b), id="1", mbase=float(sn), ra=0.0, xsource=0.2)
        for i, (b, sn) in enumerate(zip(g.bus.v, g.Sn.v))
    ]
    t = dyr_tables(read_dyr(WECC_DYR), gens)
    st1 = [g.idx.v.index(s) for s in ss.EXST1.syn.v][:4]  # four EXST1 machines
    rows = np.array([t.exc_con[t.exc_con[:, 1] == k + 1][0] for k in st1])
    rows[:, 1] = [1, 2, 3, 4]
    case = load_case("kundur").replace(exciters=ExciterTable.from_matrix(rows))
    vt = ss.Bus.v.v[[ss.Bus.idx.v.index(g.bus.v[k]) for k in st1]]
    _, Vref, _ = exc.initialise(exc.exciter_params(case), g.vf0.v[st1], vt)
    np.testing.assert_allclose(Vref, ss.EXST1.vref0.v[:4], atol=1e-12)
    tg = [g.idx.v.index(s) for s in ss.IEEEG1.syn.v][:4]
    rows = np.array([t.tg_con[t.tg_con[:, 1] == k + 1][0] for k in tg])
    rows[:, 1] = [1, 2, 3, 4]
    case = load_case("kundur").replace(governors=GovernorTable.from_matrix(rows))
    pm = g.tm0.v[tg] * 100 / g.Sn.v[tg]
    _, Pref = gov.initialise(gov.governor_params(case), pm)
    np.testing.assert_allclose(Pref * g.Sn.v[tg] / 100, ss.IEEEG1.pref0.v[:4], rtol=1e-12)
    # ESST3A's source voltage V_E: PST's formula gives ANDES's value when fed, as ANDES
    # does, system-base currents (mac_pot = 1); stabctl feeds machine-base ones (docs 12)
    e = ss.ESST3A
    for i, k in enumerate(g.idx.v.index(s) for s in e.syn.v):
        b = ss.Bus.idx.v.index(g.bus.v[k])
        KP = e.KP.v[i] * np.exp(1j * np.deg2rad(e.THETAP.v[i]))
        VE = exc.st3_source_voltage(
            KP,
            e.KI.v[i],
            e.XL.v[i],
            0.0,
            exc.ST3Machine(
                ss.Bus.v.v[b], np.exp(1j * ss.Bus.a.v[b]), g.Pe.v[k], g.Qe.v[k], 1.0, 0.0
            ),
            True,
        )
        assert VE == pytest.approx(e.VE.v[i], rel=1e-12)


def test_power_input_stabiliser_starts_at_rest_with_armature_resistance(dyr_kundur):
    """Kundur (EXDC2, TGOV1) with r_a = 0.003 and a PSS/E stabiliser on every machine
    whose second input is the electrical power (ICS 3): in a run that input is the air-gap
    power Re(psi" conj(I)), as ANDES's IEEEST (``te``; ``tm0`` at initialisation), so the
    initial washout state is K_2 (P_t + r_a |I|^2) (machine base; closed form from the
    power flow) and the start is an equilibrium.  With the terminal power P_t there it
    started off (9.9e-3 on pss.lag2.G1; IEEE 39 G6: 0.015 on pss.leadlag1) and was refused."""
    rows = np.tile(PSSE_ROW, (4, 1))
    rows[:, 1] = [1, 2, 3, 4]
    m = dyr_kundur.machines.matrix()
    m[:, MACHINE.col("ra") - 1] = 0.003
    case = dyr_kundur.replace(machines=MachineTable.from_matrix(m), pss=PssTable.from_matrix(rows))
    sim = Simulator(case)
    model = sim.model
    mp, op = model.mp, model.op
    S = op.S_gen[mp.bus_idx]
    current = np.abs(S / op.V[mp.bus_idx]) * mp.mac_pot  # machine base
    air_gap = S.real * mp.mac_pot + 0.003 * current**2
    K2 = PSSE_ROW[PSS.col("K2") - 1]
    washout = model.layout.view(model.x0, "pss")[pss_.W_PSSE]
    np.testing.assert_allclose(washout, K2 * air_gap, rtol=1e-12)
    assert np.min(0.003 * current**2) > 1e-3  # the terminal power would differ
    residual, where = model.initial_residual
    assert residual < 1e-9, where
    r = sim.run([], 10.0)
    assert np.abs(r.speed - 1).max() < 1e-9


def test_start_off_equilibrium_is_refused_naming_the_state():
    """WECC's ESST3A read as PST's exc_st3 (``conventions="pst"``) with K_C = 0.2 on
    Kundur's machines: PST's exc_st3 feeds K_C a field current estimated differently
    from the one of its initialisation, so the start is off equilibrium (as in PST):
    refused, with the state and the value; ``off_equilibrium="warn"`` runs it with a
    warning.  Read as PSS/E reads it (the default) it starts at rest."""
    recs = read_dyr(WECC_DYR)
    gens = wecc_generators(recs)
    t = dyr_tables(recs, gens, on_unsupported="skip", conventions="pst")
    n3 = next(g["number"] for g in gens if g["bus"] == 3)
    e = np.tile(t.exc_con[t.exc_con[:, 1] == n3], (4, 1))
    e[:, 1] = [1, 2, 3, 4]
    assert np.all(e[:, 16] > 0)  # K_C
    case = load_case("kundur").replace(exciters=ExciterTable.from_matrix(e), pss=PssTable.empty())
    with pytest.raises(CaseError, match=r"not an equilibrium: \|dexc\.VR\.G\d/dt\| = .*exc_st3"):
        Simulator(case)
    with pytest.warns(UserWarning, match=r"\|dexc\.VR\.G\d/dt\|"):
        sim = Simulator(case, off_equilibrium="warn")
    assert sim.model.initial_residual[0] > 1e-3
    ifd = ExciterTable.columns().index("ifd_machine")
    e[:, ifd] = 1.0  # as conventions="psse" reads ESST3A: the machine's field current
    psse = case.replace(exciters=ExciterTable.from_matrix(e))
    assert Simulator(psse).model.initial_residual[0] < 1e-9
    assert Simulator(load_case("kundur")).model.initial_residual[0] < 1e-12  # 2.7e-13
    assert Simulator(load_case("miniwecc")).model.initial_residual[0] < 1e-11  # 1.9e-12


def test_esac1a_record_lands_in_its_columns(tmp_path):
    """ESAC1A in the PSS/E Model Library's order (TR TB TC KA TA VAMAX VAMIN TE KF TF KC
    KD KE E1 SE(E1) E2 SE(E2) VRMAX VRMIN) becomes an exc_con row of type 9 with each
    value in its declared column (stabctl.models.exciters.EXCITER)."""
    values = [0.02, 0.5, 0.8, 400, 0.02, 14.5, -14.5, 0.8, 0.03, 1.0, 0.2, 0.38, 1.0]
    values += [4.18, 0.1, 3.14, 0.03, 6.03, -5.43]
    text = f"1 {ROUND}1 'ESAC1A' 1 " + " ".join(map(str, values)) + " /\n"
    tab = dyr_tables(read_dyr(write(tmp_path, text)), kundur_generators()[:1])
    e = ExciterTable.from_matrix(tab.exc_con)
    got = [e.TR, e.TB, e.TC, e.KA, e.TA, e.VAmax, e.VAmin, e.VImin, e.KF, e.TF, e.KC, e.KD]
    got += [e.VImax, e.KJ, e.KP, e.thetaP, e.KI, e.Vrmax, e.Vrmin]  # KE, E1, SE1, E2, SE2
    assert e.type[0] == 9 and [g[0] for g in got] == values


def test_ieeet3_and_esst4b_records_land_in_their_columns(tmp_path):
    """IEEET3 in the PSS/E Model Library's order (TR KA TA VRMAX VRMIN TE KF TF KP KI VBMAX
    KE) and ESST4B (TR KPR KIR VRMAX VRMIN TA KPM KIM VMMAX VMMIN KG KP KI VBMAX KC XL
    THETAP) become exc_con rows of types 11 and 12 with each value in its declared column;
    ESST4B's inner-loop feedback is unlimited (PSS/E has no VGMAX), IEEET3's VRMAX = 0 is
    no limit."""
    t3 = [0.02, 5.0, 0.04, 0.0, -7.3, 1.0, 0.1, 1.0, 4.0, 0.1, 18.0, 1.0]
    st4b = [0.01, 1.0, 0.5, 8.0, -1.0, 0.1, 1.5, 0.2, 8.0, -2.0, 1.0, 4.0, 0.1, 18.0, 0.1]
    st4b += [0.01, 5.0]
    text = f"1 {ROUND}2 {ROUND}"
    text += "1 'IEEET3' 1 " + " ".join(map(str, t3)) + " /\n"
    text += "2 'ESST4B' 1 " + " ".join(map(str, st4b)) + " /\n"
    tab = dyr_tables(read_dyr(write(tmp_path, text)), kundur_generators()[:2])
    e = ExciterTable.from_matrix(tab.exc_con)
    got = [e.TR, e.KA, e.TA, e.Vrmax, e.Vrmin, e.VImin, e.KF, e.TF, e.KP, e.KI, e.VBmax]
    got += [e.VImax]  # KE, TE: the DC names of columns 10-11
    assert e.type[0] == 11 and [g[0] for g in got] == [*t3[:3], VRMAX_UNLIMITED, *t3[4:]]
    got = [e.TR, e.Kpid_P, e.Kpid_I, e.Vrmax, e.Vrmin, e.TA, e.KPM, e.KIM, e.VMmax, e.VMmin]
    got += [e.KG, e.KP, e.KI, e.VBmax, e.KC, e.XL, e.thetaP]
    assert e.type[1] == 12 and [g[1] for g in got] == st4b
    assert e.VGmax[1] == VRMAX_UNLIMITED


def test_ieeevc_load_compensator_completes_its_exciter_row(tmp_path):
    """PSS/E's IEEEVC record (BUS 'IEEEVC' ID RC XC, machine base) sets the load
    compensation of the machine's exciter row (exc_con Rcomp, Xcomp), in either order of
    the records; one on a machine without exciter is refused with that reason."""
    text = (
        "1 'IEEEVC' 1 0.02 0.08 /\n"
        f"1 {ROUND}1 'SEXS' 1 0.1 10 100 0.05 -3 3 /\n"
        f"2 {ROUND}2 'IEEEVC' 1 0.0 0.1 /\n"
    )
    recs = read_dyr(write(tmp_path, text))
    t = dyr_tables(recs, kundur_generators()[:2], on_unsupported="skip")
    e = ExciterTable.from_matrix(t.exc_con)
    assert (list(e.machine), list(e.Rcomp), list(e.Xcomp)) == ([1], [0.02], [0.08])
    assert [(r.line, r.model) for r in t.unsupported] == [(5, "IEEEVC")]
    assert "its machine has no (supported) exciter" in t.why[0]


def test_a_second_ieeevc_for_one_machine_is_refused_as_a_second_model(tmp_path):
    """Two IEEEVC records for one generator: the second had overwritten the first's
    Xcomp without a word; it is refused as a second exciter or machine model is, naming
    both records."""
    text = (
        f"1 {ROUND}1 'SEXS' 1 0.1 10 100 0.05 -3 3 /\n"
        "1 'IEEEVC' 1 0.0 0.05 /\n1 'IEEEVC' 1 0.0 0.10 /\n"
    )
    recs = read_dyr(write(tmp_path, text))
    with pytest.raises(CaseError, match=r":4.*second compensator model for this generator.*:3"):
        dyr_tables(recs, kundur_generators()[:1], on_unsupported="skip")


def test_a_record_of_millions_of_fields_is_refused_before_it_is_held(tmp_path):
    """Round 38: a GENCLS record of ten million zeros (20 MB, on one line or one a line)
    was held whole, about 900 MB, before its count was refused.  It is refused once it
    passes MAX_RECORD_FIELDS, naming its line; the lines are read one at a time, as
    `str.splitlines` splits them (its line ends, CR LF, form feeds)."""
    import tracemalloc

    from stabctl.io import dyr

    for sep, line in ((" ", 1), ("\n", dyr.MAX_RECORD_FIELDS - 1)):
        path = tmp_path / "g.dyr"
        path.write_text("1 'GENCLS' 1" + sep + sep.join(["0"] * 2_000_000) + " /\n")
        tracemalloc.start()
        with pytest.raises(CaseError, match=r"g.dyr:1: record 1 'GENCLS' 1 \.\.\. has more "):
            read_dyr(path)
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        assert peak < 40 * path.stat().st_size // 4, peak  # not a list of every field
        with pytest.raises(CaseError, match=rf"than 2000 fields by line {line}, more than any"):
            read_dyr(path)
    for text in ("", "a", "a\n", "a\r\nb", "a\rb\n\nc", "x\x0cy\u2028z\r\n\r\n", "a\r\r\n"):
        assert list(dyr._lines(text)) == text.splitlines()
