"""The swing filter's packed parameters are read by name (`stabctl.estimation.filters` C, T,
H) and filled from the same declaration; no estimation function takes more than 10
parameters (issue 28)."""

import ast
import inspect

import numpy as np

from stabctl.estimation import filters, reference
from stabctl.estimation.filters import NG, C, H, SwingEKF, T, _packed, _tuning_vector
from stabctl.estimation.models import SwingTuning, machine_models
from stabctl.estimation.pmu import PMUSettings, machine_pmus
from stabctl.io import load_case


def test_each_named_column_holds_its_declared_value():
    case = load_case("kundur")
    m = machine_models(case, machine_pmus(case, "hv"))
    P = _packed(m)
    assert P.shape == (m.n, C.GU + NG)
    np.testing.assert_array_equal(P[:, C.POT], m.pot)
    np.testing.assert_array_equal(P[:, C.ZIM], m.z_emf.imag)
    np.testing.assert_array_equal(P[:, C.QC2], m.qaxis.c[:, 1])
    np.testing.assert_array_equal(P[:, C.GACT], m.governor.active)
    np.testing.assert_array_equal(P[:, C.GC : C.GC + NG], m.governor.c)
    np.testing.assert_array_equal(P[:, C.GU : C.GU + NG], m.governor.g_unit)
    tun, s = SwingTuning(jump_pu=0.25), PMUSettings()
    tv = _tuning_vector(tun, s, 50.0)
    assert tv.shape == (len(T),)
    assert (tv[T.JUMP], tv[T.SIG2], tv[T.SIGF], tv[T.F0]) == (
        0.25,
        s.sigma_phasor**2,
        s.sigma_freq,
        50.0,
    )
    assert SwingEKF(m, s).held.hold.shape == (m.n, len(H))


def test_no_estimation_function_takes_more_than_10_parameters():
    bad = []
    for mod in (filters, reference):
        for node in ast.walk(ast.parse(inspect.getsource(mod))):
            if isinstance(node, ast.FunctionDef):
                a = node.args
                n = len(a.posonlyargs) + len(a.args) + len(a.kwonlyargs)
                if n > 10:
                    bad.append(f"{mod.__name__}.{node.name}: {n}")
    assert not bad, bad
