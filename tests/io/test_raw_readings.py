"""A PSS/E RAW + DYR read by ANDES's parser (``import-andes``) against PSS/E's reading
(``import-psse``, stabctl's own), and DYR values PSS/E's Model Library does not take.

Round 59 (part BD, benchmarks/reliability_probes_57.py): ANDES's RAW reader drops a line's
line-end shunts, reads a transformer's magnetising admittance as line charging, keeps an
isolated (IDE 4) bus, a generator's remote regulation (IREG) and its step-up transformer
(XT) go, a wind machine's WMOD Q limits are not derived; each went into the case without a
word while ``import-psse`` names it (PSS/E POM, Power Flow Raw Data File Contents).  Now
each is named in the import's ``changed``.  And: two generators holding one bus at two
voltages, machine shares of a zero sum, GENROU's T'qo or T''qo of 0 (PST's "no such
circuit", not PSS/E's model), stabilisers of gain 0 counted as stabilisers."""

import warnings
from pathlib import Path

import pytest

from stabctl.errors import CaseError, InputError
from stabctl.io.psse import import_psse

andes = pytest.importorskip("andes")

from stabctl.io.andes_case import read_andes_case  # noqa: E402

IEEE14 = Path(andes.__file__).parent / "cases" / "ieee14"

#: bus 3's generator record of ANDES's ieee14.raw, and a GENROU for a second unit there
GEN3 = (
    "     3,'1 ',    40.000,    15.000,    15.000,   -10.000,1.01000,     0,   100.000,"
    " 0.00000E+0, 1.30000E-1, 0.00000E+0, 0.00000E+0,1.00000,1,  100.0,    50.000,"
    "    10.000,   1,1.0000\n"
)
GENROU3_2 = """      3 'GENROU' 2     6.5000      0.60000E-01  0.20000      0.50000E-01
          5.0000       0.0000       1.8000       1.7500      0.60000
         0.80000      0.34000      0.15000      0.90000E-01  0.38000      /
"""
GEN8 = (
    "     8,'1 ',    35.000,    10.000,    10.000,    -6.000,1.03000,     0,   100.000,"
    " 0.00000E+0, 1.20000E-1, 0.00000E+0, 0.00000E+0,1.00000,1,  100.0,    50.000,"
    "    10.000,   1,1.0000"
)
BRANCH23 = "     2,      3,'1 ', 4.69900E-2, 1.97970E-1,   0.04380,  100.00,  100.00,    0.00,"
ENDS0 = "  0.00000,  0.00000,  0.00000,  0.00000,1,1,   0.00,   1,1.0000"
DC_LINE = (
    "'DC1', 1, 5.0, 10.0, 500.0, 0.0, 0.0, 0.0,'I', 0.0, 20, 1.0\n"
    " 2, 1, 20.0, 5.0, 0.0, 5.0, 500.0, 1.0, 1.0, 1.5, 0.51, 0.00625, 0, 0, 0,'1', 0.0\n"
    " 4, 1, 20.0, 5.0, 0.0, 5.0, 500.0, 1.0, 1.0, 1.5, 0.51, 0.00625, 0, 0, 0,'1', 0.0\n"
)
DC_END = " 0 /End of Two-terminal dc line data"


def _edited(tmp_path: Path, name: str, old: str, new: str) -> Path:
    """ANDES's ieee14 file ``name`` with ``old`` replaced by ``new`` (which must be there)."""
    text = (IEEE14 / name).read_text()
    assert old in text, old
    out = tmp_path / name
    out.write_text(text.replace(old, new, 1))
    return out


def _changed_by_andes(raw: Path, dyr: Path | None = None) -> list[str]:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return list(read_andes_case(raw, dyr=dyr, on_unsupported="skip").changed)


@pytest.mark.parametrize(
    "old, new, named",
    [
        # BD01: GI 2, BI = BJ 5 pu (POM Non-Transformer Branch Data), dropped by ANDES
        (
            BRANCH23 + ENDS0,
            BRANCH23 + "  2.00000,  5.00000,  0.00000,  5.00000,1,1,   0.00,   1,1.0000",
            "branch 2-3 (circuit 1): ratio 1, phase 0 deg, r 0.04699, x 0.19797, b 0.0438 pu "
            "as ANDES's RAW reader reads it; the file states ratio 1, phase 0 deg, r 0.04699, "
            "x 0.19797, b 0.0438 pu, line-end shunts g, b 2, 5 (from) 0, 5 (to) pu",
        ),
        # BD02: CM 1, MAG1 0.02, MAG2 -0.05 at the winding-1 bus, read by ANDES as charging
        (
            "     4,     7,     0,'1 ',1,1,1, 0.00000E+0, 0.00000E+0,2,",
            "     4,     7,     0,'1 ',1,1,1, 2.00000E-2,-5.00000E-2,2,",
            "branch 4-7 (circuit 1): ratio 0.99677, phase 0 deg, r 0, x 0.20912, b -0.05 pu as "
            "ANDES's RAW reader reads it",
        ),
        # BD03: bus 14 isolated, which PSS/E leaves out with its records
        (
            "    14,'BUS14       ', 138.0000,1,",
            "    14,'BUS14       ', 138.0000,4,",
            "bus 14: isolated (IDE 4), which PSS/E leaves out with the records at it: "
            "ANDES's reading keeps it",
        ),
        # BD04: a two-terminal dc line, which ANDES's reader has not (BD07 next: XT 0.1)
        (DC_END, DC_LINE + DC_END, "DC1"),
        # BD05: the generator at bus 6 regulating load bus 12
        (
            "     6,'1 ',    30.000,    10.000,    10.000,    -6.000,1.03000,     0,",
            "     6,'1 ',    30.000,    10.000,    10.000,    -6.000,1.03000,    12,",
            "generator at bus 6 regulates bus 12's voltage at VS 1.03 (IREG): ANDES's "
            "reading holds bus 6's own",
        ),
        # BD07: a step-up transformer in the generator record
        (
            GEN8,
            GEN8.replace(
                "1.20000E-1, 0.00000E+0, 0.00000E+0,", "1.20000E-1, 0.00000E+0, 1.00000E-1,"
            ),
            "step-up transformer in the generator record (RT, XT)",
        ),
        # BD14: a wind machine, WMOD 2 and WPF 0.9: PSS/E's Q limits
        (
            GEN8,
            GEN8 + ",   0,1.0000,   0,1.0000,   0,1.0000, 2, 0.9",
            "(WMOD 2, PSS/E's rule) instead of QT 10.000, QB -6.000: ANDES's reading keeps "
            "QT and QB",
        ),
    ],
)
def test_what_andes_reads_otherwise_than_pssE_is_named(tmp_path, old, new, named):
    """Each record ANDES's RAW reader makes otherwise than PSS/E is named in ``changed``
    with both readings (none was, round 59 BD01-BD05, BD07, BD14)."""
    raw = _edited(tmp_path, "ieee14.raw", old, new)
    changed = _changed_by_andes(raw)
    assert any(named in c for c in changed), changed
    # the file as shipped: only its two switched shunts, held by both readings (BD06)
    shipped = _changed_by_andes(IEEE14 / "ieee14.raw")
    assert [c.split(":", 2)[1][:27] for c in shipped] == [
        "88 switched shunt at bus 9",
        "89 switched shunt at bus 14",
    ]
    assert all(c.endswith("(ANDES's reading holds it too)") for c in shipped)


def test_two_generators_holding_one_bus_at_two_voltages_are_refused(tmp_path):
    """A second generator at bus 3 with VS 1.05 beside the first's 1.01: ANDES's power flow
    does not converge; the import took the last one's voltage and machine shares from the
    failed iteration (qfrac +-5.3e7, round 59 BD09): refused naming both."""
    g2 = GEN3.replace("3,'1 ',    40.000", "3,'2 ',    10.000").replace("1.01000", "1.05000")
    raw = _edited(tmp_path, "ieee14.raw", GEN3, GEN3 + g2)
    dyr = tmp_path / "ieee14.dyr"
    dyr.write_text((IEEE14 / "ieee14.dyr").read_text().rstrip("\n") + "\n" + GENROU3_2)
    with pytest.raises(CaseError, match=r"both hold bus 3, at v0 1.01 and 1.05 pu"):
        _changed_by_andes(raw, dyr)


def test_machine_shares_of_a_zero_sum_are_refused(tmp_path):
    """Two machines at bus 3 generating +40 and -40 MW (a pumped-storage unit pumping):
    halves of 0 ran both at 0 MW (round 59 BD11); refused naming both."""
    g2 = GEN3.replace("3,'1 ',    40.000", "3,'2 ',   -40.000").replace(
        "    50.000,    10.000,", "    50.000,   -50.000,"
    )
    raw = _edited(tmp_path, "ieee14.raw", GEN3, GEN3 + g2)
    dyr = tmp_path / "ieee14.dyr"
    dyr.write_text((IEEE14 / "ieee14.dyr").read_text().rstrip("\n") + "\n" + GENROU3_2)
    with pytest.raises(CaseError, match=r"bus 3: its generators' PG \('1' 40, '2' -40\) sum to 0"):
        import_psse(raw, dyr, on_unsupported="skip")


@pytest.mark.parametrize(
    "new, name",
    [
        ("      1 'GENROU' 1     6.5000      0.60000E-01  0.20000      0.0", "T''qo"),
        ("      1 'GENROU' 1     6.5000      0.60000E-01  0.0      0.50000E-01", "T'qo"),
    ],
)
def test_genrou_without_a_q_axis_time_constant_is_refused(tmp_path, new, name):
    """GENROU's T'qo or T''qo of 0 ran as PST's "no such circuit" (999 s; x'q as x''d),
    which the Model Library's GENROU is not (round 59 BD12-13): refused by name."""
    old = "      1 'GENROU' 1     6.5000      0.60000E-01  0.20000      0.50000E-01"
    dyr = _edited(tmp_path, "ieee14.dyr", old, new)
    with pytest.raises(CaseError, match=rf"GENROU \(bus 1, id 1\): {name} = 0 s must be > 0"):
        import_psse(IEEE14 / "ieee14.raw", dyr, on_unsupported="skip")


def test_stabilisers_of_gain_zero_are_named(tmp_path):
    """ANDES's own ieee14.dyr: bus 1's ST2CUT has K1 = K2 = 0, and a PSS1A of KS 0: each
    output always 0, counted as stabilisers without a word (round 59 BD18-19), named in
    ``changed`` by both importers."""
    ieeest = (
        "      3 'IEEEST' 1          3            0       0.0000       0.0000\n"
        "          0.0000       0.0000       0.0000       0.0000       0.0000\n"
        "          0.0000       0.0000      0.75000       1.0000       4.2000\n"
        "         -2.0000      0.10000     -0.10000       0.0000       0.0000      /\n"
    )
    pss1a = "      3 'PSS1A' 1 1  0.0 0.0 0.15 0.05 0.15 0.05 1.0 0.02 0.0 0.1 -0.1 0.0 0.0 /\n"
    dyr = _edited(tmp_path, "ieee14.dyr", ieeest, pss1a)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        changed = import_psse(IEEE14 / "ieee14.raw", dyr, on_unsupported="skip").changed
    assert changed == (
        "ieee14.dyr:4 ST2CUT (bus 1, id 1): K1 = K2 = 0: its output is always 0, no effect on "
        "the run",
        "ieee14.dyr:35 PSS1A (bus 3, id 1): KS = 0: its output is always 0, no effect on the run",
    )
    assert any(
        "ST2CUT (bus 1, id GENROU_1): K1 = K2 = 0" in c
        for c in _changed_by_andes(IEEE14 / "ieee14.raw", IEEE14 / "ieee14.dyr")
    )


def test_what_andes_reads_otherwise_than_matpower_is_named(tmp_path):
    """A MATPOWER branch of TAP 0 with SHIFT -5 deg (MATPOWER's makeYbus applies the shift
    at ratio 1) and buses of BASE_KV 0: ANDES's reader drops the shift and reads 110 kV,
    without a word (round 59 BD15-16); each named."""
    text = (IEEE14.parent / "matpower" / "case14.m").read_text()
    old = "\t2\t4\t0.05811\t0.17632\t0.034\t0\t0\t0\t0\t0\t1\t-360\t360;"
    assert old in text
    m = tmp_path / "case14.m"
    m.write_text(text.replace(old, old.replace("\t0\t0\t1\t-360", "\t0\t-5\t1\t-360")))
    changed = _changed_by_andes(m)
    assert changed == [
        "case14.m branch 2-4 (row 4): SHIFT -5 deg with TAP 0 (MATPOWER: ratio 1, the shift "
        "applied): ANDES's MATPOWER reader drops the shift",
        "case14.m: 14 bus(es) of BASE_KV 0 (not given: 1-14): ANDES's MATPOWER reader reads "
        "them as 110 kV",
    ]


def test_data_andes_leaves_unused_is_named(tmp_path):
    """ANDES's ieee14.json with Line_3's to-end shunt g2 0.1, b2 0.3 (ANDES 2.0's Line
    applies g1, b1 at both ends) and PV_2's busr 12 (its power flow holds bus 2 itself):
    run as ANDES runs them, without a word (round 59 BD10, BD17); now named, kept only with
    on_unsupported="skip"."""
    import json

    d = json.loads((IEEE14 / "ieee14.json").read_text())
    line = next(x for x in d["Line"] if x["idx"] == "Line_3")
    line["g2"], line["b2"] = 0.1, 0.3
    pv = next(x for x in d["PV"] if x["bus"] == 2)
    pv["busr"] = 12
    path = tmp_path / "edited.json"
    path.write_text(json.dumps(d))
    with pytest.raises(InputError, match=r"to keep with a change: .*Line \(1: Line_3\)"):
        read_andes_case(path)
    changed = _changed_by_andes(path)
    assert (
        "Line (1: Line_3): to-end shunt g2 0.1, b2 0.3 run as the from-end g1 0, b1 0 (ANDES "
        "2.0's Line applies g1, b1 at both ends)"
    ) in changed
    assert any(
        c.startswith(f"PV (1: {pv['idx']}): busr 12 (remote voltage control) unused")
        for c in changed
    ), changed


def test_a_branch_below_pssEs_zero_impedance_threshold_is_named(tmp_path):
    """A branch of R 0 and X 1e-4 pu is a zero-impedance line in PSS/E (THRSHZ 0.0001: its
    two buses one); stabctl keeps it as the impedance it is, which moved the run by 1e-5
    rad without a word (round 59 BB11): named among the records that look wrong."""
    raw = _edited(
        tmp_path,
        "ieee14.raw",
        BRANCH23,
        BRANCH23.replace(" 4.69900E-2, 1.97970E-1,", " 0.0, 1.0E-4,"),
    )
    with pytest.warns(
        UserWarning,
        match=r"branch 2-3 '1': R 0, X 1.0E-4 pu, at or below PSS/E's zero-impedance "
        r"threshold THRSHZ 0.0001",
    ):
        import_psse(raw, IEEE14 / "ieee14.dyr", on_unsupported="skip")
