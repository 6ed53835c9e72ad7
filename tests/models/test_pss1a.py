"""PSS/E's PSS1A, read into stabctl's PSS/E stabiliser (pss_con type 3,
stabctl.models.pss.ieeest) by a mapping of its parameters: the record fills the type's
columns, and the stabiliser's transfer function is PSS1A's closed form (IEEE Std
421.5-2005 section 8.1: 1/(1 + s T6), K_S s T5/(1 + s T5), 1/(1 + A1 s + A2 s^2), two
lead-lags), its high-frequency jump and its limit too.  No PSS/E or ANDES run of PSS1A
is stored (ANDES 2.0 has no PSS1A)."""

from pathlib import Path

import numpy as np
import pytest

from stabctl.case import PssTable
from stabctl.dynamics.driver import Simulator
from stabctl.errors import StabctlError
from stabctl.io import load_case
from stabctl.io.psse import load_psse
from stabctl.models import pss as pss_

SCRX = Path(__file__).parents[1] / "data" / "psse_runs" / "SCRX"
#: PSS1A: ICS A1 A2 T1 T2 T3 T4 T5 T6 KS LSMAX LSMIN VCU VCL (IEEE 421.5-2005's sample
#: data for A1, A2, T1..T4, T5 = 10 s, T6 = 0.05 s, KS = 5)
VALUES = dict(ICS=1, A1=0.061, A2=0.0017, T1=0.3, T2=0.03, T3=0.3, T4=0.03, T5=10.0)
VALUES.update(T6=0.05, KS=5.0, LSMAX=0.05, LSMIN=-0.05, VCU=0.0, VCL=0.0)
OMEGA0, PE0 = 1.0, 0.7


def dyr(tmp_path, **changed) -> Path:
    """PSS/E's ThreeBus SCRX run's DYR with a PSS1A on its GENROU (bus 102)."""
    v = {**VALUES, **changed}
    record = "    102 'PSS1A' 1 " + " ".join(f"{x:g}" for x in v.values()) + " /\n"
    path = tmp_path / "ThreeBus_SCRX_PSS1A.dyr"
    path.write_text((SCRX / "ThreeBus_SCRX.dyr").read_text() + record)
    return path


@pytest.fixture(scope="module")
def imported(tmp_path_factory):
    return load_psse(SCRX / "ThreeBusMulti.raw", dyr(tmp_path_factory.mktemp("pss1a")))


def test_record_fills_the_psse_stabiliser_s_columns(imported):
    """Type 3: input 1 its ICS through K1 = 1 and the lag Tr1 = T6; K_w = KS T5, T_w = T5;
    the filter A1, A2 (A3..A6 0); lead-lags T1/T2, T3/T4 (T5, T6 0); limits, cut-off."""
    s = imported.pss
    got = {n: float(getattr(s, n)[0]) for n in ("type", "input1", "K1", "Tr1", "KTw", "Tw")}
    assert got == dict(type=3, input1=1, K1=1.0, Tr1=0.05, KTw=50.0, Tw=10.0)
    assert [s.A1[0], s.A2[0], s.A3[0], s.A4[0], s.A5[0], s.A6[0]] == [0.061, 0.0017, 0, 0, 0, 0]
    assert [s.T1[0], s.T2[0], s.T3[0], s.T4[0], s.T5[0], s.T6[0]] == [0.3, 0.03, 0.3, 0.03, 0, 0]
    assert [s.ymax[0], s.ymin[0], s.VCU[0], s.VCL[0]] == [0.05, -0.05, 0.0, 0.0]


def test_imported_case_starts_at_rest(imported):
    """The whole case (GENROU, SCRX, PSS1A) at its initial point: every derivative 0."""
    residual, where = Simulator(imported, background_compile=False).model.initial_residual
    assert residual < 1e-10, where


def _started(row):
    """(P, x) of the row on Kundur's machine 1, at rest at OMEGA0, PE0."""
    row = list(row)
    row[1] = 1
    p = pss_.pss_params(load_case("kundur").replace(pss=PssTable.from_matrix([row])))
    u1, u2 = pss_.pss_inputs(p, np.array([OMEGA0]), np.array([PE0]))
    return p.packed(), pss_.initialise(p, u1, u2, np.array([PE0]))


def _out(P, x, omega):
    dx = np.zeros_like(x)
    y = pss_.output_and_derivatives(P, x, 0, omega, PE0, 1.0, dx)
    return y, dx[:, 0].copy()


def _state_space(P, x0, h=1e-6):
    """(A, B, C, D) of the stabiliser on the speed deviation, by central differences
    (its blocks are linear inside the output limit)."""
    n = x0.shape[0]
    A, C = np.zeros((n, n)), np.zeros(n)
    for j in range(n):
        xp, xm = x0.copy(), x0.copy()
        xp[j, 0] += h
        xm[j, 0] -= h
        (yp, fp), (ym, fm) = _out(P, xp, OMEGA0), _out(P, xm, OMEGA0)
        A[:, j], C[j] = (fp - fm) / (2 * h), (yp - ym) / (2 * h)
    (yp, fp), (ym, fm) = _out(P, x0.copy(), OMEGA0 + h), _out(P, x0.copy(), OMEGA0 - h)
    return A, (fp - fm) / (2 * h), C, (yp - ym) / (2 * h)


def _pss1a(s, v=VALUES):
    """PSS1A's transfer function from the speed deviation at s (IEEE 421.5-2005 8.1)."""
    return (
        1 / (1 + s * v["T6"])
        * v["KS"] * s * v["T5"] / (1 + s * v["T5"])
        / (1 + v["A1"] * s + v["A2"] * s * s)
        * (1 + s * v["T1"]) / (1 + s * v["T2"])
        * (1 + s * v["T3"]) / (1 + s * v["T4"])
    )  # fmt: skip


def test_transfer_function_is_pss1a_s(imported):
    """From 0.01 to 20 Hz the mapped stabiliser's frequency response is PSS1A's closed
    form within 1e-7 (relative; its output limits widened to +-1e3 for the central
    differences, whose state steps move the output by up to 5e4 times the step); at rest
    the washout gives it zero gain."""
    row = [imported.pss.col(k)[0] for k in range(1, len(pss_.PSS.names) + 1)]
    row[pss_.PSS.col("ymax") - 1], row[pss_.PSS.col("ymin") - 1] = 1e3, -1e3
    P, x0 = _started(row)
    A, B, C, D = _state_space(P, x0)
    for f in (0.01, 0.1, 0.5, 1.0, 2.0, 5.0, 20.0):
        s = 2j * np.pi * f
        H = C @ np.linalg.solve(s * np.eye(A.shape[0]) - A, B) + D
        assert abs(H - _pss1a(s)) < 1e-7 * abs(_pss1a(s)), f
    assert _out(P, x0.copy(), OMEGA0)[0] == 0.0


def test_speed_step_jumps_by_the_lead_lags_high_frequency_gain(imported):
    """Without the transducer and the filter (T6 = A1 = A2 = 0) a speed step dw moves the
    output at once by KS dw T1 T3/(T2 T4), and a large one is held at LSMAX, LSMIN."""
    row = [imported.pss.col(k)[0] for k in range(1, len(pss_.PSS.names) + 1)]
    for name in ("Tr1", "A1", "A2"):
        row[pss_.PSS.col(name) - 1] = 0.0
    P, x0 = _started(row)
    dw = 1e-5
    assert _out(P, x0.copy(), OMEGA0 + dw)[0] == pytest.approx(
        5.0 * dw * 0.3 * 0.3 / (0.03 * 0.03), rel=1e-9
    )
    assert _out(P, x0.copy(), OMEGA0 + 1e-2)[0] == 0.05
    assert _out(P, x0.copy(), OMEGA0 - 1e-2)[0] == -0.05


@pytest.mark.parametrize(
    "changed,why",
    [
        (dict(ICS=2), "input code 2"),
        (dict(ICS=0), "no input"),
        (dict(T5=0.0), "washout"),
    ],
)
def test_options_it_does_not_model_are_named(tmp_path, changed, why):
    """Inputs other than speed (1) and electrical power (3), and a washout T5 below 1e-3
    s, are named unsupported with the record."""
    with pytest.raises(StabctlError, match=rf"_PSS1A.dyr:6 PSS1A at bus 102 '1': .*{why}"):
        load_psse(SCRX / "ThreeBusMulti.raw", dyr(tmp_path, **changed))
