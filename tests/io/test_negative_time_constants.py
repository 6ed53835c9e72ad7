"""Every DYR model stabctl reads refuses each of its time constants set negative, naming
the record and the parameter (round 42: IEESGO T4 = -0.3 ran as T4 = 0, TGOV1 T2, DEGOV
T4, DEGOV1 T3 and T4 ran as given, all without a word; import-andes refused them).

A time constant is >= 0 in every model's source (PSS/E Model Library; IEEE Std 421.5;
ANDES 2.0 for its own TG2 and HYGOV4): 0 bypasses its block where the model allows it,
a negative value is no block of the model (a lead of negative time constant is a right
half-plane zero, a lag an unstable pole).  Each variant is one valid record of the test
data (tests/data/psse_runs/*/*.dyr, tests/data/psse/*.dyr, as the PSS/E runs wrote them)
or, for the models no data file has, `INLINE`'s record on the SMIB case, with one
time-constant parameter set to minus its value (-0.5 where it is 0).
"""

import re
from pathlib import Path

import pytest

from stabctl.errors import CaseError
from stabctl.io.dyr import CONVERTER_DYR, DYR_MODELS, FAMILY, SVC_DYR, TEXT_FIELDS, read_dyr
from stabctl.io.psse import import_psse

DATA = Path(__file__).parents[1] / "data"
SMIB = DATA / "psse" / "smib_v33.raw"
ALL = DYR_MODELS | CONVERTER_DYR | SVC_DYR
#: the SMIB case's machine (tests/io/test_error_source.py's GENROU) and an IEEET1 for a
#: stabiliser's machine
GENROU = (
    "4.6385 0.0626 0.4384 0.0541 6.5385 0 1.8689 1.7795 0.2426 0.2884 0.1508 0.1158 0.1152 0.441"
)
IEEET1 = "0 50 0.04 5 -5 1 0.5 0.04 1 0 2.8 0.04 3.73 0.33"
#: a valid record (PSS/E Model Library order; ANDES 2.0's parameter order for its TG2 and
#: HYGOV4) of each model no test data file has: the values of this repository's other
#: tests where they have one (IEEET3, ESST4B, EXDC2: tests/io/test_dyr.py; AC8B:
#: test_error_source.py; PSS1A: IEEE Std 421.5-2005's sample data, tests/models/
#: test_pss1a.py), else typical values within each model's limits
INLINE = {
    "IEEET1": IEEET1,
    "IEEET3": "0.02 5.0 0.04 0.0 -7.3 1.0 0.1 1.0 4.0 0.1 18.0 1.0",
    "ESST4B": "0.01 1.0 0.5 8.0 -1.0 0.1 1.5 0.2 8.0 -2.0 1.0 4.0 0.1 18.0 0.1 0.01 5.0",
    "EXDC2": "0.02 20 0.02 1 1 5.2 -4.16 1 0.83 0.0754 1.246 0 3.1 0.33 2.3 0.1",
    "ESDC2A": "0.0 400 0.04 0 0 7.3 -7.3 1.0 0.8 0.03 1.0 0 3.1 0.33 2.3 0.1",
    "ESDC1A": "0.0 400 0.04 0 0 7.3 -7.3 1.0 0.8 0.03 1.0 0 3.1 0.33 2.3 0.1",
    "AC8B": "0 80 5 10 0.1 1 0 35 0 1 0.5 0.02 1 1.2 0.55 1.1 1 6.5 0.3 9 3",
    "ESAC6A": (
        "0 536 0.086 0.18 9 3 75 -75 44 -36 1 19 0 75 0.08 0.02 0.173 1.91 1.6 7.4 0.214 5.55 0.044"
    ),
    "EXAC4": "0 10 -10 1 10 200 0.015 5.64 -4.53 0",
    "EXPIC1": "0 100 0.1 5 -5 1 0.1 0.1 5 -5 0 1 1 5 -5 1 0.5 3 0.1 4 0.3 1 0 0",
    "PSS1A": "1 0.061 0.0017 0.3 0.03 0.3 0.03 10 0.05 5 0.05 -0.05 0 0",
    "GGOV1": (
        "1 1 0.04 1 0.05 -0.05 10 2 0 1 1 0.15 0.5 1.5 0.2 0.1 0 0 3 2 0.67 1 0 0.1 -0.1 0 "
        "0.01 10 0.1 0 0 4 5 99 -99"
    ),
    "IEEEG2": "20 1 0.5 2 1 0 1",
    "IEEEG3": "0.05 0.04 0.1 -0.1 1 0 0.04 0.3 5 1 0.5 1 1.5 1",
    "TG2": "0.05 1 1.2 0 0.2 10",
    "ANDES_HYGOV4": "1 0.05 0.3 0.2 -0.2 1 0 0.05 0.5 5 1 1.2 0.5 0.08",
    # ANDES 2.0's cases (andes/cases: ieee14_ieeevc.dyr, N44_BC.dyr, npcc_full.dyr; ST2CUT
    # with K1 = 20 for its zero gains)
    "ST2CUT": "1 0 0 0 20 0 0 0 30 30 0.23 0.025 0.23 0.025 0 0 0.06 -0.06 0 0",
    "ESST3A": "0.02 0.2 -0.2 8 1 5 20 0 99 -99 1 3.67 0.435 5.48 0.01 0.0098 3.86 3.33 0.4 99 0",
    "IEEEG1": "0 0 20 0.1 0 0.2 1 -1 0.95 0 0.1 0 0 0 0 0 0 0.3 0 8.72 0.7 0",
    "STAB2A": "1 2 0 2 0.55 1 0.01 0.03",
    "IEEET2": "0 729 0.04 5.32 -4.05 1 0.44 0.0667 2 0.44 6.5 0.054 8 0.202",
    "IEESGO": "0.01 0 0.15 0.3 8 0.4 0 0.7 0.43 1 0",
    "IEEEX1": "0 50 0.06 0 0 1 -1 -0.02 0.5 0.08 1 0 2 0.0016 3 1.73",
}
#: T-named parameters that are no time constant: limits, an angle, a rating, a flag, a
#: ratio (SEXS TA/TB: refused negative by its own limit, as a time constant's ratio)
_NOT_TIME = {"TMAX", "TMIN", "THETAP", "TRATE", "TETAMAX", "TETAMIN", "TFLAG"}
#: the unit of each DYR parameter copied to a declared column
_UNITS = {
    (m.name, src): fam.param(col).unit
    for fam in FAMILY.values()
    for m in fam.dyr
    for col, src in m.copy.items()
}


def _time_constants(model: str) -> list[str]:
    """The parameters of `model` that are time constants: copied to a column in seconds,
    or (computed by the mapper) named T... and not in `_NOT_TIME`."""
    out = []
    for name in ALL[model].fields:
        unit = _UNITS.get((model, name))
        if name[:1] in "Tt" and (unit == "s" or (unit is None and name.upper() not in _NOT_TIME)):
            out.append(name)
    return out


def _raw_of(dyr: Path) -> Path:
    """The RAW file a data DYR file runs with: the one of its name (3_BUS_System_SVC),
    the SMIB's for the SMIB records, else its folder's."""
    same = dyr.with_suffix(".raw")
    if same.exists():
        return same
    if dyr.name.startswith("smib"):
        return SMIB
    return sorted(dyr.parent.glob("*.raw"))[0]


def _bases() -> dict:
    """Model -> (RAW file, DYR lines before the record, the record's bus, id and values as
    text, DYR lines after it): the first record of each model in the data files, then
    `INLINE`."""
    bases: dict = {}
    for dyr in sorted(DATA.glob("psse*/**/*.dyr")):
        lines = dyr.read_text().splitlines()
        for rec in read_dyr(dyr):
            if rec.model not in ALL or rec.model in bases:
                continue
            end = next(j for j in range(rec.line - 1, len(lines)) if "/" in lines[j])
            text = iter(rec.text)
            fields = TEXT_FIELDS.get(rec.model, ())
            values = [
                f"'{next(text)}'" if name in fields else repr(v)
                for name, v in zip(ALL[rec.model].fields, rec.params)
            ]
            bases[rec.model] = (
                _raw_of(dyr),
                lines[: rec.line - 1],
                rec.bus,
                rec.id,
                values,
                lines[end + 1 :],
            )
    for model, values in INLINE.items():
        assert model not in bases, model  # a data file has it: take that
        machine = [f"1 'GENROU' 1 {GENROU} /", "2 'GENCLS' 1 0 0 /"]
        pss = model in {m.name for m in FAMILY["pss"].dyr}
        bases[model] = (
            SMIB,
            machine + [f"1 'IEEET1' 1 {IEEET1} /"] * pss,
            1,
            "1",
            values.split(),
            [],
        )
    return bases


BASES = _bases()
#: the machine models (their time constants are the machine table's, refused by it) are
#: in the sweep as every other family
VARIANTS = [(model, name) for model in sorted(BASES) for name in _time_constants(model)]


def _dyr(tmp_path, model: str, change: dict) -> tuple[Path, Path]:
    raw, before, bus, mid, values, after = BASES[model]
    values = list(values)
    for name, v in change.items():
        values[ALL[model].fields.index(name)] = repr(v)
    record = f"{bus} '{model}' '{mid}' {' '.join(values)} /"
    path = tmp_path / "negative.dyr"
    path.write_text("\n".join([*before, record, *after]) + "\n")
    return raw, path


def test_every_model_stabctl_reads_is_in_the_sweep():
    """Each DYR model of `ALL` has a record here (the test data's or `INLINE`'s) but the
    ones left out below, each with why; and every base record imports."""
    # not swept: the wind turbine records need a REECA1 plant (no data file has one), a
    # REECA1's and REECD1's and REGCB1's records are the converter family's
    # (tests/io/test_dyr_converters.py builds them); IEEEVC has no time constant
    left = {"REECA1", "REECD1", "REGCB1", "WTARA1", "WTDTA1", "WTPTA1", "WTTQA1", "IEEEVC"}
    assert set(ALL) - set(BASES) == left - set(BASES)


@pytest.mark.parametrize("model", sorted(INLINE))
def test_each_inline_base_record_imports(tmp_path, model):
    """`INLINE`'s records are valid: the SMIB case imports with each."""
    raw, dyr = _dyr(tmp_path, model, {})
    import_psse(raw, dyr)


@pytest.mark.parametrize("model, name", VARIANTS)
def test_a_negative_time_constant_is_refused_naming_its_record(tmp_path, model, name):
    """-T (or -0.5 where T = 0) is refused: one CaseError naming the file, line, model,
    bus and id, and the parameter as the DYR record names it (STAB1's T1/T3)."""
    raw, before, bus, mid, values, _ = BASES[model]
    v = float(values[ALL[model].fields.index(name)])
    neg = -abs(v) if v else -0.5
    raw, dyr = _dyr(tmp_path, model, {name: neg})
    with pytest.raises(CaseError) as err:
        import_psse(raw, dyr)
    msg = str(err.value)
    assert f"negative.dyr:{len(before) + 1} {model} (bus {bus}, id {mid})" in msg, msg
    assert re.search(rf"(^|[\s(,]){re.escape(name.replace('_', '/'))} = ", msg), msg
