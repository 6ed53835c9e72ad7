"""Ambient load fluctuation (stabctl.estimation.ambient): the Ornstein-Uhlenbeck statistics against
their closed forms, and the fluctuation driving the simulator."""

import numpy as np
import pytest
from scipy.stats import chi2

from stabctl.dynamics.driver import Simulator
from stabctl.errors import InputError
from stabctl.estimation import ambient as am
from stabctl.io import load_case

DT, TAU, SD, PATHS = 1 / 60, 2.0, 0.01, 4000


@pytest.fixture(scope="module")
def paths():
    return am.ou_samples(int(6 * TAU / DT) + 1, DT, TAU, SD, PATHS, seed=1)


def variance_bounds(m, var):
    """Two-sided 99.9 % interval of the sample variance of m N(0, var) draws (chi-square)."""
    return var * chi2.ppf(5e-4, m) / m, var * chi2.ppf(1 - 5e-4, m) / m


def test_ou_starts_at_the_power_flow_and_its_variance_grows_as_the_closed_form(paths):
    a = np.exp(-DT / TAU)
    assert np.all(paths[0] == 0.0)
    for k in (6, 60, paths.shape[0] - 1):  # 0.1 s, 1 s, 12 s
        lo, hi = variance_bounds(PATHS, SD**2 * (1 - a ** (2 * k)))
        assert lo < np.mean(paths[k] ** 2) < hi


def test_ou_correlation_decays_over_the_correlation_time(paths):
    k0, lag = paths.shape[0] - 1 - int(TAU / DT), int(TAU / DT)  # stationary by 5 tau
    for step, rho in ((lag, np.exp(-1.0)), (lag // 4, np.exp(-0.25))):
        r = np.corrcoef(paths[k0], paths[k0 + step])[0, 1]
        # Fisher z of a sample correlation: normal, standard deviation 1 / sqrt(m - 3)
        assert abs(np.arctanh(r) - np.arctanh(rho)) < 4 / np.sqrt(PATHS - 3)


def test_same_seed_same_path_and_bad_parameters():
    amb = am.AmbientLoad(pct=2.0, tau_s=1.0, seed=5)
    np.testing.assert_array_equal(amb.deviations(100, DT, 3), amb.deviations(100, DT, 3))
    assert not np.array_equal(
        amb.deviations(100, DT, 3), am.AmbientLoad(2.0, 1.0, seed=6).deviations(100, DT, 3)
    )
    for bad in (dict(pct=-1.0), dict(tau_s=0.0)):
        with pytest.raises(InputError):
            am.AmbientLoad(**bad)


@pytest.fixture(scope="module")
def kundur():
    case = load_case("kundur")
    return case, Simulator(case)


def test_load_fluctuation_drives_the_simulated_speeds(kundur):
    case, sim = kundur
    amb = am.AmbientLoad(pct=1.0, tau_s=TAU, seed=3)
    res = am.simulate(sim, 10.0, amb)
    loads = amb.devices(case)
    assert [d.bus for d in loads] == [int(b) for b in case.buses.number[case.buses.pload > 0]]
    # the power drawn at each load bus is the commanded deviation times the load's P
    x = amb.deviations(601, DT, len(loads))
    k = np.searchsorted(res.t, np.arange(601) * DT + 1e-9)[:-1]  # first point after
    p = np.array([d.pmax_mw for d in loads]) / case.base_mva
    np.testing.assert_allclose(res.pesd[k], x[:-1] * p, rtol=1e-12, atol=1e-15)
    rel = (res.speed - res.coi_speed[:, None]) * case.freq_hz * 1e3  # mHz
    assert 0.5 < rel[res.t > 5].std(axis=0).max() < 20  # moves, well inside 100 mHz
    assert res.stable


def test_zero_amplitude_gives_the_deterministic_run(kundur):
    _case, sim = kundur
    still = am.simulate(sim, 5.0, am.AmbientLoad(pct=0.0))
    flat = sim.run([], t_end=5.0)
    assert np.all(still.pesd == 0.0)
    np.testing.assert_allclose(
        np.interp(flat.t, still.t, still.speed[:, 0]), flat.speed[:, 0], atol=1e-12
    )
    np.testing.assert_allclose(still.speed[-1], flat.speed[-1], atol=1e-12)
