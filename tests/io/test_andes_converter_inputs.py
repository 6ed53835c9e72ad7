"""Converter, wind and battery data checked before ANDES fills its defaults (issue 54,
item 8): a value ANDES would replace by its default (0 where it must be non-zero, a sign
it must not have) and data that cannot be (REECA1 Imax <= 0, Vdip >= Vup; ESD1 En <= 0,
SOC limits out of order or above 100 %) are refused naming file, model, row and
parameter; a parameter the file leaves out is run with ANDES's default and named.
Converters taking other than all of their static generator's power: the import's summary
states what the written case holds."""

import json
import re
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from stabctl.cli import main
from stabctl.dynamics.driver import Simulator
from stabctl.errors import CaseError, InputError
from stabctl.io import load_case
from stabctl.io.andes_case import read_andes_case
from stabctl.models.converters import CONVERTER

andes = pytest.importorskip("andes")
pd = pytest.importorskip("pandas")


WT3, ESD1, PVD1 = "ieee14/ieee14_wt3.xlsx", "ieee14/ieee14_esd1.xlsx", "ieee14/ieee14_pvd1.xlsx"
SOLAR = "ieee14/ieee14_solar.xlsx"


def edited(tmp_path, case: str, model: str, **values):
    """ANDES's case file with `values` written into every row of `model`'s sheet."""
    sheets = pd.read_excel(andes.get_case(case), sheet_name=None)
    for name, v in values.items():
        sheets[model][name] = v
    out = tmp_path / f"{model}_{'_'.join(values)}.xlsx"
    with pd.ExcelWriter(out) as w:
        for name, rows in sheets.items():
            rows.to_excel(w, sheet_name=name, index=False)
    return out


@pytest.mark.parametrize(
    "case, model, values, needle",
    [
        # ANDES would replace them by its defaults (the findings: 1.3, 3 s)
        ("ieee14/ieee14_pvd1.xlsx", "PVD1", {"ialim": 0.0}, "ialim = 0 (must not be 0"),
        ("ieee14/ieee14_pvd1.xlsx", "PVD1", {"ialim": -1.1}, "ialim = -1.1 (must not be negative"),
        ("kundur/kundur_wtdta1.xlsx", "WTDTA1", {"H": 0.0}, "H = 0 (must not be 0: ANDES would"),
        # impossible data ANDES runs
        ("kundur/kundur_reg.xlsx", "REECA1", {"Imax": -10.0}, "Imax = -10: it must be Imax > 0"),
        (
            "kundur/kundur_reg.xlsx",
            "REECA1",
            {"Vdip": 1.2, "Vup": 0.9},
            "Vdip = 1.2, Vup = 0.9: it must be Vdip < Vup",
        ),
        ("ieee14/ieee14_esd1.xlsx", "ESD1", {"En": -10.0}, "En = -10: it must be En > 0"),
        (
            "ieee14/ieee14_esd1.xlsx",
            "ESD1",
            {"SOCmin": 0.9, "SOCmax": 0.2},
            "SOCmin = 0.9, SOCmax = 0.2: it must be SOCmin < SOCmax",
        ),
        (
            "ieee14/ieee14_esd1.xlsx",
            "ESD1",
            {"SOCmax": 2.0},
            "SOCmax = 2: it must be SOCmax <= 1",
        ),
        # REGCA1's Iq rate limits hold the rest point's rate 0 between them (the table's rule,
        # the same for a case file's ibr_con)
        (
            "kundur/kundur_reg.xlsx",
            "REGCA1",
            {"Iqrmax": -999.0},
            "Iqrmax = -999, Iqrmin = -999: it must be Iqrmin <= 0 <= Iqrmax",
        ),
        ("kundur/kundur_reg.xlsx", "REGCA1", {"Iolim": 1.3}, "Iolim = 1.3: it must be Iolim <= 0"),
        # limit pairs out of order, rates excluding the rest rate 0, a lag of 0, a negative
        # droop, no shaft, an efficiency above 1, a flag or frequency out of its range:
        # each imported and ran without a word
        (
            WT3,
            "REECA1",
            {"QMax": -1000.0},
            "QMax = -1000, QMin = -999: it must be QMax >= QMin (the limits of the Q reference)",
        ),
        (WT3, "REECA1", {"Iqh1": -1000.0}, "Iqh1 = -1000, Iql1 = -999: it must be Iqh1 >= Iql1"),
        (WT3, "REECA1", {"dPmax": -1000.0}, "it must be dPmin <= 0 <= dPmax"),
        (WT3, "REECA1", {"Tpord": 0.0}, "Tpord = 0: it must be Tpord >= 0.001 s"),
        (WT3, "REPCA1", {"emax": -1000.0}, "emax = -1000, emin = -999: it must be emax >= emin"),
        (WT3, "REPCA1", {"Kc": -1.0}, "Kc = -1: it must be Kc >= 0 (a reactive droop gain)"),
        (WT3, "WTDTA1", {"Dshaft": -1.0}, "Dshaft = -1: it must be Dshaft >= 0"),
        (WT3, "WTDTA1", {"Freq1": 0.0}, "Freq1 = 0: it must be Freq1 > 0"),
        (WT3, "WTDTA1", {"w0": 0.0}, "w0 = 0: it must be w0 > 0"),
        (WT3, "WTPTA1", {"thmax": -10.0}, "thmax = -10, thmin = 0: it must be thmax >= thmin"),
        (WT3, "WTPTA1", {"Tp": 0.0}, "Tp = 0: it must be Tp >= 0.001 s"),
        (WT3, "WTTQA1", {"Temax": -1.0}, "Temax = -1, Temin = 0: it must be Temax >= Temin"),
        (
            WT3,
            "WTTQA1",
            {"p2": 0.1},
            "p1 = 0.2, p2 = 0.1, p3 = 0.6, p4 = 0.8: it must be p1 < p2 < p3 < p4",
        ),
        (ESD1, "ESD1", {"EtaC": 1.5}, "EtaC = 1.5: it must be 0 < EtaC <= 1 (an efficiency)"),
        (ESD1, "ESD1", {"qmx": -0.5}, "qmx = -0.5, qmn = "),
        (ESD1, "ESD1", {"pmx": -1.0}, "pmx = -1: it must be pmx >= 0"),
        (PVD1, "PVD1", {"v0": 1.2}, "v0 = 1.2, v1 = 1.1: it must be v0 <= v1"),
        (PVD1, "PVD1", {"fn": 0.0}, "fn = 0: it must be fn > 0 (the rated frequency)"),
        (PVD1, "PVD1", {"frflag": 2.0}, "frflag = 2: it must be 0 <= frflag <= 1"),
        # a share of the static generator's power out of [0, 1] (summed, it was the only
        # figure named, without the device or value)
        (ESD1, "ESD1", {"gammap": -0.1}, "gammap = -0.1: it must be 0 <= gammap <= 1 (a share"),
        (SOLAR, "REGCA1", {"gammaq": 1.5}, "gammaq = 1.5: it must be 0 <= gammaq <= 1"),
        # a VDL curve whose points fall: ANDES (and stabctl) took it out of service silently
        (
            WT3,
            "REECA1",
            {"Vq2": 0.1},
            "Vq1 = 0.2, Vq2 = 0.1, Vq3 = 0.8, Vq4 = 1: it must be Vq1 <= Vq2 <= Vq3 <= Vq4 "
            "(the points of the VDL1 curve: ANDES takes the curve out of service",
        ),
        (WT3, "REECA1", {"Vp4": 0.7}, "Vp3 = 0.8, Vp4 = 0.7: it must be Vp1 <= Vp2 <= Vp3 <= Vp4"),
        (WT3, "REECA1", {"Ip1": 5.0}, "Ip1 = 5, Ip2 = 4, Ip3 = 8, Ip4 = 10: it must be Ip1 <= "),
        # round 43: a curve all 0 (ANDES limits the current to 0; the table's route reads
        # it as no curve, Imax alone): refused, not run otherwise than ANDES
        (
            WT3,
            "REECA1",
            {f"{x}{j}": 0.0 for x in ("Vq", "Iq") for j in range(1, 5)},
            "it must be not all 0 (the points of the VDL1 curve: ANDES then limits the current",
        ),
        # a link to a device the case does not hold (ANDES's own message named neither sheet
        # nor row, at times another model: WTPTA1 for a WTARA1's rego, as 99.0)
        (ESD1, "ESD1", {"bus": 999}, "bus = 999: no ACNode (Bus) of that idx in the case (ANDES"),
        (PVD1, "PVD1", {"bus": "four"}, "bus = 'four': no ACNode (Bus) of that idx in the case"),
        (SOLAR, "REGCA1", {"bus": 77}, "bus = 77: no ACNode (Bus) of that idx in the case"),
        (WT3, "WTARA1", {"rego": 99}, "rego = 99: no RenGovernor (WTDTA1) of that idx in the case"),
        (WT3, "REECA1", {"reg": 99}, "reg = 99: no RenGen (REGCA1) of that idx in the case"),
        # a "no limit" written 1e30, read back as an integer beyond int64: a traceback
        (ESD1, "ESD1", {"SOCmax": 1e30}, "SOCmax = 1e+30: it must be SOCmax <= 1"),
    ],
)
def test_converter_data_andes_would_default_or_that_cannot_be_is_refused(
    tmp_path, case, model, values, needle
):
    path = edited(tmp_path, case, model, **values)
    with pytest.raises(
        CaseError, match=rf"{path.name}: {model} row 1 \(idx .*; spreadsheet row 2\): "
    ) as err:
        read_andes_case(path, on_unsupported="skip")
    assert needle in str(err.value)


@pytest.mark.parametrize(
    "case, model, name",
    [(WT3, "REECA1", "Imax"), (WT3, "REGCA1", "Iqrmax"), (SOLAR, "REECA1", "Imax")],
)
def test_a_no_limit_of_1e30_is_refused_by_name_not_a_traceback(tmp_path, case, model, name):
    """A converter limit written 1e30 (a "no limit" of other tools), which the sheet reader
    hands on as an integer beyond int64: `import-andes` stopped with numpy's TypeError
    (isfinite of an object).  It is refused, as any value beyond 1e15, naming the row and
    the parameter."""
    path = edited(tmp_path, case, model, **{name: 1e30})
    with pytest.raises(CaseError) as err:
        read_andes_case(path, on_unsupported="skip")
    assert f"{path.name}: {model} row 1 (idx " in str(err.value)
    assert f"{name} = 1e+30: 1e+30 is beyond +-1e+15: no datum is that large" in str(err.value)


def test_parameters_left_out_are_named_with_andes_s_default(tmp_path):
    """kundur_reg.xlsx with REGCA1's Tg emptied (the finding: run at ANDES's 0.1 s without a
    word): the import names it, with the default and the row."""
    path = edited(tmp_path, "kundur/kundur_reg.xlsx", "REGCA1", Tg=float("nan"))
    got = read_andes_case(path, on_unsupported="skip")
    assert "REGCA1 Tg = 0.1 (row 1: empty in the file)" in got.defaulted
    assert not any(
        d.startswith("REGCA1 Tg = ")
        for d in read_andes_case(
            andes.get_case("kundur/kundur_reg.xlsx"), on_unsupported="skip"
        ).defaulted
    )


@pytest.mark.parametrize("text", ["NaN", "N/A", "null"])
def test_a_cell_whose_text_reads_as_nan_is_named_as_that_text_not_as_empty(tmp_path, text):
    """A cell holding the text "NaN" (or another text the sheet reader takes for NaN) was
    summarised as "empty in the file": it is named as the text it holds, run at ANDES's
    default as ANDES runs it; an empty cell stays "empty"."""
    path = edited(tmp_path, "kundur/kundur_reg.xlsx", "REGCA1", Tg=text)
    got = read_andes_case(path, on_unsupported="skip")
    assert f"REGCA1 Tg = 0.1 (row 1: the text {text!r} in the file, read as NaN)" in got.defaulted
    assert not any("empty in the file" in d for d in got.defaulted if d.startswith("REGCA1 Tg"))


def test_the_summary_says_how_a_file_leaves_a_parameter_out_and_what_andes_uses(tmp_path):
    """A NaN in a json file was summarised as "not in the file"; a default that is no
    number as "REPCA1 Rc = None", "WTTQA1 Tn = nan": each says how the file leaves it out
    and, for those, the value ANDES takes instead (its NumSelect fallback)."""
    data = json.loads(Path(andes.get_case("ieee14/ieee14_pvd1.json")).read_text())
    data["PVD1"][0]["tip"] = float("nan")
    data["PVD1"][0].pop("tiq", None)
    path = tmp_path / "pvd1_nan.json"
    path.write_text(json.dumps(data))
    got = read_andes_case(path, on_unsupported="skip").defaulted
    assert "PVD1 tip = 0.02 (row 1: NaN in the file)" in got
    assert "PVD1 tiq = 0.02 (row 1: not in the file)" in got
    wt3 = read_andes_case(andes.get_case(WT3), on_unsupported="skip").defaulted
    tn = [d for d in wt3 if d.startswith("WTTQA1 Tn")]
    assert tn == [
        "WTTQA1 Tn = Sngo, ANDES's value where Tn is not given (Turbine or RenGovernor "
        "rating) (row 1: empty in the file)"
    ]


@pytest.mark.parametrize("case, model", [(PVD1, "PVD1"), (ESD1, "ESD1"), (WT3, "REPCA1")])
def test_a_busf_naming_no_busfreq_of_the_case_is_refused(tmp_path, case, model):
    """A busf naming a BusFreq the case does not hold: ANDES adds one with its defaults at
    the bus instead (its DeviceFinder), and the import ran without a word."""
    path = edited(tmp_path, case, model, busf="BusFreq_99")
    with pytest.raises(
        CaseError, match=rf"{model} row 1 \(idx .*; spreadsheet row 2\): busf = 'BusFreq_99': no "
    ):
        read_andes_case(path, on_unsupported="skip")


def test_a_converter_at_another_rated_frequency_is_refused_naming_fn(tmp_path):
    """A PVD1 of fn 50 Hz in the 60 Hz case (ANDES reads its frequency trip points, in Hz,
    at fn times the per-unit frequency) was imported at 60 Hz without a word."""
    path = edited(tmp_path, PVD1, "PVD1", fn=50.0)
    with pytest.raises(InputError, match=r"PVD1 1: fn = 50 Hz differs from the system freq"):
        read_andes_case(path)


def test_values_andes_copies_from_linked_devices_are_not_called_defaults():
    """The stock ieee14_solar.xlsx: its REECA1's bus, gen and Sn and its REPCA1's reg, bus,
    bus1, bus2 and monitored line's r and x are ANDES ``ExtParam`` values taken from the
    linked devices, not parameters of the file run at a default: none is listed (they were,
    as "REECA1 bus = None", "REPCA1 r = 1.0"); the parameters the file leaves out still
    are (REGCA1's gammap, with ANDES's 1.0)."""
    from andes.core.param import ExtParam

    got = read_andes_case(andes.get_case("ieee14/ieee14_solar.xlsx"), on_unsupported="skip")
    ss = andes.load(
        andes.get_case("ieee14/ieee14_solar.xlsx"), setup=False, no_output=True,
        default_config=True,
    )  # fmt: skip
    linked = {
        f"{model} {name} "
        for model in ("REGCA1", "REECA1", "REPCA1")
        for name, p in ss.models[model].params.items()
        if isinstance(p, ExtParam)
    }
    assert "REPCA1 r " in linked and "REECA1 bus " in linked
    assert not [d for d in got.defaulted if any(d.startswith(x) for x in linked)]
    assert "REGCA1 gammap = 1.0 (row 1: not in the file)" in got.defaulted


def test_a_pvd1_naming_a_missing_generator_is_refused(tmp_path):
    """A PVD1 whose gen is no static generator of the case (the finding: a ValueError
    traceback from list.index): refused naming the file, the device and the generator."""
    path = edited(tmp_path, "ieee14/ieee14_pvd1.xlsx", "PVD1", gen=9999)
    with pytest.raises(
        CaseError,
        match=r"^PVD1_gen\.xlsx: PVD1 row 1 \(idx \S+; spreadsheet row 2\): gen = 9999: no "
        r"StaticGen \(PV, Slack\) of that idx in the case",
    ):
        read_andes_case(path, on_unsupported="skip")


#: a share statement of the summary: its devices, shares, bus and rest
SHARE = re.compile(
    r"^(?P<devs>.+): take gammap (?P<fp>\S+), gammaq (?P<fq>\S+) \(summed: ibr_con pfrac, "
    r"qfrac\) of the generation of bus "
    r"(?P<bus>\d+), which has no machine; the rest, (?P<rp>\S+) of its P and (?P<rq>\S+) "
    r"of its Q \(power flow\), netted into the bus's load in runs"
)


def test_a_regca1_share_below_one_is_summarised_as_the_written_case_holds(tmp_path):
    """ieee14_solar with its REGCA1 taking gammap 0.5, gammaq 0.25 of the bus-8 generator
    (the finding: `import-andes --skip-unsupported` said it was left out while the written
    case held it with those shares).  The --json summary names it as kept, with the shares
    and the rest the written case holds (its converter table; the bus has no machine, so a
    run nets the rest into the bus's load: the case starts flat)."""
    path = edited(tmp_path, "ieee14/ieee14_solar.xlsx", "REGCA1", gammap=0.5, gammaq=0.25)
    out = tmp_path / "out.json"
    res = CliRunner().invoke(
        main, ["import-andes", str(path), "-o", str(out), "--skip-unsupported", "--json"]
    )
    assert res.exit_code == 0, res.output
    summary = json.loads(res.stdout)
    case = load_case(out)
    conv = case.converters
    assert summary["converters"] == len(conv) == 1
    assert not [t for t in summary["left_out"] if "REGCA1" in t]
    found = [m for m in map(SHARE.match, summary["changed"]) if m]
    assert len(found) == 1
    m = found[0]
    k = int(np.flatnonzero(conv.bus == int(m["bus"]))[0])
    assert m["devs"] == f"REGCA1 1 (converter {int(conv.number[k])})"
    assert int(m["bus"]) not in set(case.machines.bus.astype(int))
    np.testing.assert_allclose(
        [float(m[g]) for g in ("fp", "fq", "rp", "rq")],
        [conv.pfrac[k], conv.qfrac[k], 1 - conv.pfrac[k], 1 - conv.qfrac[k]],
        rtol=1e-12,
    )
    Simulator(case)  # off_equilibrium="refuse": the rest netted, the case starts flat


def test_a_change_stops_the_import_without_skip_unsupported_as_its_help_says(tmp_path):
    """ieee14_solar with its REGCA1 taking gammap 0.5 of the bus-8 generator: kept with a
    change only with --skip-unsupported; without it the import stops naming the change
    (exit 2, nothing written), and the help of --skip-unsupported says both."""
    path = edited(tmp_path, SOLAR, "REGCA1", gammap=0.5, gammaq=0.25)
    out = tmp_path / "out.json"
    res = CliRunner().invoke(main, ["import-andes", str(path), "-o", str(out)])
    assert res.exit_code == 2 and not out.exists(), res.output
    assert "to keep with a change: REGCA1 1" in res.stderr
    assert "(--skip-unsupported leaves them out or keeps them changed)" in res.stderr
    helped = " ".join(CliRunner().invoke(main, ["import-andes", "--help"]).output.split())
    option = helped.split("Options:")[1].split("--skip-unsupported ")[1].split(" --")[0]
    assert "keep the devices stabctl keeps only with a change" in option
    assert "without it either stops the import" in option


def test_machine_and_converter_shares_not_adding_to_one_are_refused(tmp_path):
    """ieee14_wt3n with the bus-1 turbine taking gammap 0.7 and its GENCLS 0.2 of the
    Slack (the finding: summarised as left out, written with both; the rest, lost at a
    machine's bus, started the case off its power flow): refused, nothing written."""
    sheets = pd.read_excel(andes.get_case("ieee14/ieee14_wt3n.xlsx"), sheet_name=None)
    reg = sheets["REGCA1"]
    reg[["gammap", "gammaq"]] = reg[["gammap", "gammaq"]].astype(float)
    turbine, machine = 0.7, 0.2
    reg.loc[reg["gen"] == 1, ["gammap", "gammaq"]] = turbine
    sheets["GENCLS"][["gammap", "gammaq"]] = machine
    path = tmp_path / "wt3n_shares.xlsx"
    with pd.ExcelWriter(path) as w:
        for name, rows in sheets.items():
            rows.to_excel(w, sheet_name=name, index=False)
    assert re.search(
        r"static generator 1: its machines and converters \(REGCA1 REGCA1_5, GENCLS "
        rf"GENCLS_1\) take gammap {turbine + machine:g} and gammaq {turbine + machine:g} "
        r"of its power, not 1",
        refused_when_skipping(path),
    )


def refused_when_skipping(path: Path) -> str:
    """What `import-andes --skip-unsupported` of ``path`` says as it refuses it (exit 2,
    nothing written)."""
    out = path.with_suffix(".out.json")
    res = CliRunner().invoke(
        main, ["import-andes", str(path), "-o", str(out), "--skip-unsupported"]
    )
    assert res.exit_code == 2 and not out.exists()
    return res.output


def test_converters_taking_more_than_all_of_their_generator_s_power_are_refused(tmp_path):
    """ieee14_esd1's ten ESD1 on one static generator, each taking gammap 0.5 of its power
    (each share in [0, 1]; summed 5): refused naming the generator, the devices and the
    sums, with --skip-unsupported too (it was kept with the rest, -4 of the bus's P,
    netted into its load), nothing written."""
    path = edited(tmp_path, ESD1, "ESD1", gammap=0.5)
    assert re.search(
        r"ESD1_gammap\.xlsx: static generator 6: its converters \(ESD1 1, ESD1 2, .*ESD1 10\) "
        r"take gammap 5 and gammaq 1 of its power: more than all of it \(at most 1\)",
        refused_when_skipping(path),
    )


@pytest.mark.parametrize("name", ["ieee14/ieee14_pvd1.xlsx", "ieee14/ieee14_esd1.xlsx"])
def test_a_start_refused_at_the_q_limits_names_the_held_buses_and_no_q_limits(name):
    """ANDES's ieee14_pvd1 and ieee14_esd1 as import-andes reads them (its power flow
    compared with ANDES's, Q limits off in both): stabctl's default power flow holds PV
    buses at their Q limits, the PVD1's Q droop then acts at the start and the start is
    refused; the refusal names the buses held and q_limits=False (--no-q-limits from the
    command line; it said neither), with which the case starts.  A start refused for a
    cause of its own (a current limit ialim of 0.001 pu) is refused without that hint."""
    case = read_andes_case(andes.get_case(name)).case
    with pytest.raises(
        CaseError,
        match=r"converter C1 \(bus \d+, ibr_con row 1\): the converter cannot start at its "
        r"power-flow point .*; the "
        r"power flow held buses 2, 3, 4, 6 at their Q limits, and without Q limits the case "
        r"starts at rest: q_limits=False solves the power flow as ANDES does",
    ):
        Simulator(case, background_compile=False)
    Simulator(case, q_limits=False, background_compile=False)
    t = case.converters
    limited = case.replace(converters=t.replace(ialim=np.full(len(t), 0.001)))
    with pytest.raises(CaseError, match=r"cannot start") as err:
        Simulator(limited, background_compile=False)
    assert "Q limit" not in str(err.value) and "q_limits" not in str(err.value)


def test_converter_columns_are_named_with_their_buses(tmp_path, monkeypatch):
    """`simulate --out` writes a converter's P and Q as pibr_pu.C<k>, qibr_pu.C<k>, which
    nothing mapped to its plant: `simulate --json` now gives each one's bus
    (`converter_names`) and `cases --bus-table` lists them at theirs, as the case's own
    converter table places them (ANDES's ieee14_pvd1: ten PVD1 at bus 4)."""
    from stabctl.io.pst import write_case_json

    monkeypatch.chdir(tmp_path)
    case = read_andes_case(andes.get_case(PVD1)).case
    write_case_json(case, "p.json")
    expected = {
        str(int(k)): f"C{int(k)} (bus {int(b)})"
        for k, b in zip(case.converters.number, case.converters.bus)
    }
    assert expected
    res = CliRunner().invoke(
        main, ["simulate", "p.json", "--tf", "0.05", "--no-q-limits", "--json"]
    )
    assert res.exit_code == 0, res.output
    assert json.loads(res.stdout)["converter_names"] == expected
    table = CliRunner().invoke(main, ["cases", "p.json", "--bus-table", "--json"])
    at = {r["bus"]: r["converters"] for r in json.loads(table.stdout)["buses"] if r["converters"]}
    placed: dict[int, list[str]] = {}
    for k, b in zip(case.converters.number, case.converters.bus):
        placed.setdefault(int(b), []).append(f"C{int(k)}")
    assert at == {b: ",".join(names) for b, names in placed.items()} and len(placed[4]) == 10


def test_a_regulated_bus_naming_the_device_s_own_is_its_own_bus(tmp_path):
    """Round 43: a REECA1 (REPCA1) whose busr names its REGCA1's own bus (ieee14_wt3: bus
    8) was refused as regulating a remote bus; ANDES regulates that same bus as with busr
    empty (PSS/E: IREG of its own bus, as 0).  It reads as the file without busr, column
    for column; another bus is still refused by name."""
    plain = read_andes_case(andes.get_case(WT3), on_unsupported="skip").case.converters
    for model in ("REECA1", "REPCA1"):
        own = read_andes_case(edited(tmp_path, WT3, model, busr=8), on_unsupported="skip")
        got = own.case.converters
        differ = [
            p.name
            for p in CONVERTER.params
            if not np.array_equal(getattr(got, p.name), getattr(plain, p.name))
        ]
        assert differ == [], model
    with pytest.raises(InputError, match=r"REGCA1 1: its REECA1 regulates remote bus busr = 4"):
        read_andes_case(edited(tmp_path, WT3, "REECA1", busr=4))
