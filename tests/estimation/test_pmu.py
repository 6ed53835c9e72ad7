"""PMU measurement model: C37.118.1 noise statistics, seeds, dropped frames, latency, rates,
bus frequency, and the true phasors taken from a simulation (generator and device
currents)."""

import dataclasses

import numpy as np
import pytest

from stabctl.dynamics.driver import Simulator
from stabctl.dynamics.events import fault_with_clearing
from stabctl.errors import InputError
from stabctl.estimation import pmu
from stabctl.io import load_case
from stabctl.storage.devices import uniform_fleet


def constant_truth(n_pmu=2, t_end=100.0, f=60.0):
    """Steady phasors on a 1 kHz grid: V = 1.02 at 0.3 rad, I = 0.8 at -0.2 rad."""
    t = np.linspace(0.0, t_end, int(t_end * 1000) + 1)
    ones = np.ones((t.size, n_pmu))
    return pmu.PhasorTruth(
        t=t,
        pmus=tuple(pmu.PMU(bus=b + 1, machine=b + 1) for b in range(n_pmu)),
        v=1.02 * np.exp(0.3j) * ones,
        i=0.8 * np.exp(-0.2j) * ones,
        freq=f * ones,
        rocof=0 * ones,
        f0=60.0,
    )


@pytest.fixture(scope="module")
def steady_stream():
    return pmu.measure(constant_truth(), pmu.PMUSettings(), seed=7)


def test_phasor_noise_matches_the_tve_limit_as_a_3_sigma_bound(steady_stream):
    s = steady_stream
    e = s.v / s.true.v - 1  # relative phasor error
    sigma = 0.01 / (3 * np.sqrt(2))  # 0.236 %
    assert np.std(np.abs(s.v) / np.abs(s.true.v) - 1) == pytest.approx(sigma, rel=0.03)
    assert np.std(np.angle(s.v / s.true.v)) == pytest.approx(sigma, rel=0.03)  # rad
    assert abs(np.mean(e.real)) < 4 * sigma / np.sqrt(e.size)
    tve = np.abs(e)
    assert np.sqrt(np.mean(tve**2)) == pytest.approx(0.01 / 3, rel=0.03)  # RMS = limit/k
    assert np.mean(tve <= 0.01) > 0.999  # P(TVE > 1 %) = exp(-9)
    ei = s.i / s.true.i - 1
    assert np.std(ei.imag) == pytest.approx(sigma, rel=0.03)
    assert abs(np.corrcoef(e.real.ravel(), ei.real.ravel())[0, 1]) < 0.03  # independent


def test_frequency_and_rocof_noise(steady_stream):
    s = steady_stream
    assert np.std(s.freq - 60.0) == pytest.approx(0.005 / 3, rel=0.03)
    assert np.std(s.rocof) == pytest.approx(0.01 / 3, rel=0.03)
    assert np.mean(np.abs(s.freq - 60.0) <= 0.005) > 0.99


def test_user_limits_and_sigma_level():
    st = pmu.PMUSettings(tve=0.002, fe_hz=0.001, rfe_hz_s=0.1, k_sigma=1.0)
    s = pmu.measure(constant_truth(1, 20.0), st, seed=1)
    assert np.std(np.angle(s.v / s.true.v)) == pytest.approx(0.002 / np.sqrt(2), rel=0.05)
    assert np.std(s.freq - 60) == pytest.approx(0.001, rel=0.05)
    assert np.std(s.rocof) == pytest.approx(0.1, rel=0.05)


def test_same_seed_same_stream_and_independent_pmus():
    truth = constant_truth(3, 5.0)
    a, b = pmu.measure(truth, seed=11), pmu.measure(truth, seed=11)
    c = pmu.measure(truth, seed=12)
    for name in ("v", "i", "freq", "rocof", "valid"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert not np.allclose(a.freq, c.freq)
    more = pmu.measure(constant_truth(4, 5.0), seed=11)  # a PMU added at the end
    np.testing.assert_array_equal(more.freq[:, :3], a.freq)
    assert abs(np.corrcoef(a.freq[:, 0], a.freq[:, 1])[0, 1]) < 0.15


def test_dropped_frames_are_nan_invalid_and_never_arrive():
    s = pmu.measure(constant_truth(2, 50.0), pmu.PMUSettings(drop_prob=0.2), seed=3)
    lost = ~s.valid
    assert lost.mean() == pytest.approx(0.2, abs=0.01)
    assert np.all(np.isnan(s.v[lost])) and np.all(np.isnan(s.freq[lost]))
    assert np.all(np.isinf(s.arrival[lost]))
    assert np.all(np.isfinite(s.v[s.valid]))


@pytest.mark.parametrize("latency", [0.0, 0.05, 0.2])
def test_latency_shifts_arrivals(latency):
    s = pmu.measure(constant_truth(2, 2.0), pmu.PMUSettings(latency_s=latency), seed=0)
    np.testing.assert_allclose(s.arrival, np.broadcast_to(s.t[:, None] + latency, s.arrival.shape))
    fr = s.frame(5)
    assert fr.t == s.t[5] and fr.v.shape == (2,)


@pytest.mark.parametrize("rate", [30.0, 60.0, 120.0])
def test_reporting_rates(rate):
    s = pmu.measure(constant_truth(1, 2.0), pmu.PMUSettings(rate=rate), seed=0)
    assert len(s) == int(2 * rate) + 1
    np.testing.assert_allclose(np.diff(s.t), 1 / rate)
    assert 60 / rate * s.t[int(rate)] == pytest.approx(60.0 / rate)


@pytest.mark.parametrize(
    "bad",
    [
        dict(rate=45.0),
        dict(rate=24.0),
        dict(tve=-0.01),
        dict(drop_prob=1.0),
        dict(latency_s=-1.0),
        dict(k_sigma=0.0),
        dict(window_cycles=-1.0),
    ],
)
def test_bad_settings(bad):
    with pytest.raises(InputError):
        pmu.PMUSettings(**bad)


def test_reporting_rates_per_nominal_frequency():
    """C37.118.1-2011 Table 1 (with the higher rates of clause 5.3): 10-60 (120) frames/s
    at 60 Hz, 10, 25, 50 (100) at 50 Hz.  `PMUSettings` takes either (it knows no case);
    `check_rate` holds a rate to its case's frequency, suggesting one frame per cycle."""
    from stabctl.estimation import settings as ps

    assert ps.rates_at(60) == (10, 12, 15, 20, 30, 60, 120)
    assert ps.rates_at(50.0) == (10, 25, 50, 100)
    assert (ps.nominal_rate(60), ps.nominal_rate(50)) == (60, 50)
    assert ps.nominal_rate(16.7) == 15 and ps.rates_at(16.7) == ps.RATES  # no list there
    for rate in (25.0, 50.0, 100.0, 120.0):
        assert pmu.PMUSettings(rate=rate).rate == rate
    ps.check_rate(25, 50)
    ps.check_rate(120, 60)
    with pytest.raises(InputError) as bad:
        ps.check_rate(60, 50, "--rate {}", "give {}")
    assert str(bad.value) == (
        "--rate 60: must be one of 10, 25, 50, 100 frames/s on a 50 Hz system (C37.118.1-2011 "
        "Table 1 reporting rates at 50 Hz, with the higher rate of clause 5.3); 60 frames/s "
        "is a rate of 60 Hz systems: give --rate 50, one frame per cycle"
    )
    with pytest.raises(InputError, match=r"PMUSettings\(rate=100\): .* 60 Hz system .* "):
        ps.check_rate(100, 60)


def test_measure_refuses_a_rate_not_of_the_truth_s_frequency():
    """The default 60 frames/s on a 50 Hz truth is refused naming the setting to pass;
    50 and 25 frames/s are measured there, frame k at k / rate."""
    truth = dataclasses.replace(constant_truth(1, 2.0, f=50.0), f0=50.0)
    with pytest.raises(InputError, match=r"PMUSettings\(rate=60\).* pass PMUSettings\(rate=50\)"):
        pmu.measure(truth)
    for rate in (25.0, 50.0):
        s = pmu.measure(truth, pmu.PMUSettings(rate=rate), seed=0)
        assert len(s) == int(2 * rate) + 1
        np.testing.assert_allclose(np.diff(s.t), 1 / rate)


def test_window_frequency_of_an_angle_parabola_is_exact():
    # theta = 2 pi 0.5 t + a t^2: f = 60.5 + a t / pi Hz, ROCOF a / pi Hz/s.  The window
    # difference of a parabola is its derivative at the window centre, exactly.
    t = np.linspace(0, 2, 2001)
    a = 0.1
    ang = 2 * np.pi * 0.5 * t + a * t**2
    st = pmu.PMUSettings()
    w = st.window_s(60.0)
    c = np.array([0.5, 1.0, 1.5])
    f, r = pmu.window_estimates(t, np.angle(np.exp(1j * ang))[:, None], c, c, w, 60.0)
    np.testing.assert_allclose(f[:, 0], 60.5 + a * c / np.pi, atol=1e-6)  # linear interp.
    np.testing.assert_allclose(r[:, 0], a / np.pi, atol=1e-4)
    with pytest.raises(InputError):
        pmu.window_estimates(t[::-1], ang[:, None], c, c, w, 60.0)
    with pytest.raises(InputError):
        pmu.window_estimates(t, ang[:, None], c, c, 0.0, 60.0)
    with pytest.raises(InputError):
        pmu.PMUSettings(window_cycles=0.0)


@pytest.mark.parametrize("cycles", [1.0, 2.0, 4.0])
def test_an_angle_jump_adds_jump_over_2_pi_window_whatever_the_step(cycles):
    # A ramp at 60.3 Hz whose angle jumps by d at t_j (a network event, grid point kept
    # with its last value, as phasor_truth keeps it).  Frames whose window misses the jump
    # read the ramp's 60.3 Hz; those whose window holds it read 60.3 + d / (2 pi W) at most,
    # at every step h: the error does not grow as 1/h.
    d, t_j, f_ramp = 0.05, 1.0, 60.3
    w = pmu.PMUSettings(window_cycles=cycles).window_s(60.0)
    frames = pmu.frame_times(2.0, 60.0)
    bound = d / (2 * np.pi * w)
    for h in (1 / 200, 1 / 240, 1 / 480, 1 / 960, 1 / 3840):
        t = np.unique(np.r_[np.arange(0, 2 + h / 2, h), t_j])
        ang = 2 * np.pi * (f_ramp - 60.0) * t + np.where(t >= t_j, d, 0.0)
        f, r = pmu.centred_estimates(t, ang[:, None], frames, w, 60.0)
        err = f[:, 0] - f_ramp
        away = np.abs(frames - t_j) >= w / 2 + h  # window clear of the smeared jump
        np.testing.assert_allclose(err[away], 0.0, atol=1e-9)
        assert np.all((err > -1e-9) & (err <= bound + 1e-9))
        assert err.max() == pytest.approx(bound, rel=1e-9)  # the frame at the jump
        assert np.abs(r[:, 0]).max() <= bound / w + 1e-6  # ROCOF: one window more


def test_truth_frequency_is_evaluated_at_the_frames_and_checks_the_window():
    t = np.linspace(0, 2, 2001)
    v = np.exp(1j * 2 * np.pi * 0.2 * t)[:, None]  # 60.2 Hz
    w = pmu.PMUSettings().window_s(60.0)
    truth = pmu.angle_truth(t, (pmu.PMU(bus=1),), v, v * np.nan, 60.0, w)
    s = pmu.measure(truth, pmu.PMUSettings(fe_hz=0.0, rfe_hz_s=0.0), seed=0)
    np.testing.assert_allclose(s.true.freq, 60.2, atol=1e-9)  # ends included
    np.testing.assert_allclose(s.true.rocof, 0.0, atol=1e-6)
    with pytest.raises(InputError, match="window"):
        pmu.measure(truth, pmu.PMUSettings(window_cycles=4.0), seed=0)


@pytest.fixture(scope="module")
def kundur_esd():
    case = load_case("kundur")
    fleet = uniform_fleet(case, 5)
    res = Simulator(case, injection_buses=fleet.buses).run(
        [fault_with_clearing(case, 3, 101, 1.0, 6)], t_end=3.0, storage=fleet
    )
    return case, res


@pytest.mark.parametrize("at", ["terminal", "hv"])
def test_generator_currents_carry_the_simulated_power(kundur_esd, at):
    case, res = kundur_esd
    pmus = pmu.machine_pmus(case, at)
    assert [p.bus for p in pmus] == ([1, 2, 11, 12] if at == "terminal" else [10, 20, 110, 120])
    truth = pmu.phasor_truth(case, res, pmus)
    keep = np.r_[np.diff(res.t) > 0, True]  # the repeated clearing instant
    P = (truth.v * np.conj(truth.i)).real
    np.testing.assert_allclose(P, res.pelect[keep], atol=1e-9)  # lossless step-up branches
    np.testing.assert_allclose(truth.freq[0], 60.0, atol=1e-9)


def test_device_current_and_labels(kundur_esd):
    case, res = kundur_esd
    pmus = (pmu.PMU(bus=10, device=1), pmu.PMU(bus=20))
    truth = pmu.phasor_truth(case, res, pmus)
    keep = np.r_[np.diff(res.t) > 0, True]
    np.testing.assert_allclose(
        (truth.v[:, 0] * np.conj(truth.i[:, 0])).real, -res.pesd[keep, 0], atol=1e-12
    )  # absorbing is + for ESDs
    assert np.all(np.isnan(truth.i[:, 1]))
    s = pmu.measure(truth, seed=0)
    assert s.labels == ["B10:D1", "B20:V"]
    assert np.all(np.isnan(s.power[:, 1]))


@pytest.mark.parametrize(
    "p, match",
    [
        (pmu.PMU(bus=20, device=1), "device 1 is at bus 10"),
        (pmu.PMU(bus=10, device=9), "device 9 is not in the result"),
        (pmu.PMU(bus=3, machine=1), "no branch joins it"),
    ],
)
def test_bad_pmus(kundur_esd, p, match):
    case, res = kundur_esd
    with pytest.raises(InputError, match=match):
        pmu.phasor_truth(case, res, (p,))
    with pytest.raises(InputError):
        pmu.PMU(bus=1, machine=1, device=1)
