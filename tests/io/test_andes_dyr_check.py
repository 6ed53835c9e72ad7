"""import-andes of a RAW + DYR pair checks every device ANDES built against the DYR record
it came from (`stabctl.io.andes_case._dyr_against_andes`); where the devices of an ANDES
model cannot be matched to the records one to one, the import says so instead of
skipping the check silently.  Skipped without ANDES."""

from pathlib import Path
from types import SimpleNamespace

import pytest

andes = pytest.importorskip("andes")

from stabctl.io.andes import _andes  # noqa: E402
from stabctl.io.andes_case import _dyr_against_andes  # noqa: E402


def test_devices_not_matched_to_records_are_named_not_checked(tmp_path):
    """Kundur's RAW + DYR (4 GENROU, 4 EXDC2 records): every device matched to its record;
    with ANDES's EXDC2 count made 3, its 4 records are named as not checked."""
    raw = andes.get_case("kundur/kundur.raw")
    dyr = tmp_path / "kundur.dyr"
    lines = Path(andes.get_case("kundur/kundur_full.dyr")).read_text().splitlines()
    dyr.write_text("\n".join(ln for ln in lines if "TOGGLE" not in ln.upper()) + "\n")
    _andes()  # ANDES's logger as stabctl sets it (no log directory left behind)
    ss = andes.load(str(raw), addfile=str(dyr), default_config=True, no_output=True)
    dropped, by_device, unchecked = _dyr_against_andes(ss, dyr)
    assert dropped == [] and unchecked == []
    assert sorted(k for (dest, k) in by_device if dest == "EXDC2") == [0, 1, 2, 3]
    fewer = SimpleNamespace(models={**ss.models, "EXDC2": SimpleNamespace(n=3)}, groups=ss.groups)
    _, by_device, unchecked = _dyr_against_andes(fewer, dyr)
    assert not any(dest == "EXDC2" for dest, _ in by_device)
    assert unchecked == [
        "EXDC2 (3 devices): values not checked against the DYR file's 4 EXDC2 record(s) "
        "(ANDES built another number of devices, so a device cannot be matched to its "
        "record); run as ANDES read them"
    ]
