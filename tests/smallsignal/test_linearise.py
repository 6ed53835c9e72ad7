"""Linearisation of the simulator's own model (stabctl.smallsignal.linearise) against PSTess
svm_mgen, the nonlinear simulator (ESD power pulse) and its own perturbation error.

References (tests/data/pstess/, copied from shared/reference/pstess; PSTess 1.1 svm_mgen
under GNU Octave, MIT licence, see LICENSE and NOTICE there): kundur_d2asbegp_eigenvalues.csv
(60 states with PSS), kundur_d2asbegp_nopss_eigenvalues.csv (48 states, pss_con = []);
columns index, real, imag, freq_hz, damping_ratio.  PSTess counts 4 lmod/rlmod states that
are inactive in the simulation and absent from our model (docs/modal.md).
"""

from pathlib import Path

import numpy as np
import pytest

from stabctl.case import PssTable
from stabctl.dynamics.driver import Simulator
from stabctl.errors import InputError, SimulationError, UnknownBusError, WrongTypeError
from stabctl.io import load_case
from stabctl.smallsignal.linearise import (
    STATE,
    active_states,
    compare_pulse,
    jacobian_columns,
    linearise,
    linearise_model,
    perturbation_error,
)
from stabctl.smallsignal.modal import match_modes

DATA = Path(__file__).parents[1] / "data" / "pstess"
FREQ_TOL_PCT, DAMPING_TOL = 1.0, 0.01  # the acceptance tolerances
REGRESSION_FREQ_PCT, REGRESSION_DAMPING = 0.05, 1e-3  # we reach 3e-2 % / 2e-4: guard


@pytest.fixture(scope="module")
def kundur_nopss():
    return Simulator(load_case("kundur").replace(pss=PssTable.empty()))


@pytest.fixture(scope="module")
def sys_k(kundur):
    return linearise(kundur)


def pstess_eigenvalues(name):
    ref = np.loadtxt(DATA / name, delimiter=",", skiprows=1)
    return ref[:, 1] + 1j * ref[:, 2]


@pytest.mark.parametrize(
    "sim_name, ref_name, n_states, n_pst",
    [
        ("kundur", "kundur_d2asbegp_eigenvalues.csv", 56, 60),
        ("kundur_nopss", "kundur_d2asbegp_nopss_eigenvalues.csv", 44, 48),
    ],
)
def test_electromechanical_band_matches_pstess(
    sim_name, ref_name, n_states, n_pst, request, record_property
):
    sys = linearise(request.getfixturevalue(sim_name))
    ref = pstess_eigenvalues(ref_name)
    assert sys.nstates == n_states and ref.size == n_pst == n_states + 4  # + lmod/rlmod
    lam = np.linalg.eigvals(sys.A)
    pairs = match_modes(lam, ref)
    assert len(pairs) >= 6
    f_err = max(abs(p["freq_err_pct"]) for p in pairs)
    z_err = max(abs(p["damping_err"]) for p in pairs)
    record_property("worst_freq_err_pct", float(f_err))
    record_property("worst_damping_err", float(z_err))
    print(
        f"{sim_name}: {len(pairs)} modes 0.1-2.5 Hz, worst frequency {f_err:.2e} %, "
        f"damping {z_err:.2e}"
    )
    assert f_err < FREQ_TOL_PCT and z_err < DAMPING_TOL
    assert f_err < REGRESSION_FREQ_PCT and z_err < REGRESSION_DAMPING
    # every PSTess eigenvalue but the four lmod/rlmod lags at -20 has a partner of ours
    rest = ref[np.abs(ref + 20) > 1e-6]
    assert rest.size == n_states
    assert np.max(np.abs(rest[:, None] - lam[None, :]).min(axis=1)) < 1e-3


def test_unstable_interarea_mode_without_pss(kundur_nopss):
    lam = np.linalg.eigvals(linearise(kundur_nopss).A)
    ia = lam[np.argmin(np.abs(lam - 2j * np.pi * 0.634))]
    assert ia.real > 0.05 and abs(ia.imag / (2 * np.pi) - 0.6345) < 1e-3


def test_state_counts_and_inactive_slots(kundur):
    m = kundur.model
    act = active_states(m)
    assert act.sum() == 56 and act.size == 4 * (6 + 3 + 3 + 3)
    unused = [m.state_name(k) for k in np.nonzero(~act)[0]]
    assert unused == [f"exc.VAs.G{g}" for g in (1, 2, 3, 4)]
    # the excluded slots are dummies: zero rows and zero columns of the full Jacobian
    idx = np.arange(act.size)
    J, _, _, _ = jacobian_columns(m, np.full(idx.size, STATE), idx, 1e-4 * np.maximum(abs(m.x0), 1))
    assert np.all(J[:, ~act] == 0) and np.all(J[~act] == 0)
    wecc = linearise(load_case("miniwecc"))
    assert wecc.nstates == 565 - 2 * 64  # PSTess count less 64 lmod + 64 rlmod
    assert not any(n.startswith("exc_VTR") for n in wecc.state_labels)  # T_R = 0


def test_signal_names_and_output_structure(sys_k, kundur):
    assert sys_k.input_labels == [
        "P_esd_B10",
        "P_esd_B20",
        "P_esd_B110",
        "P_esd_B120",
        *[f"Vref_G{g}" for g in range(1, 5)],
        *[f"Pref_G{g}" for g in range(1, 5)],
    ]
    assert sys_k.state_labels[:2] == ["mac_delta_G1", "mac_delta_G2"]
    lab = sys_k.output_labels
    assert lab[:5] == ["omega_G1", "omega_G2", "omega_G3", "omega_G4", "omega_coi"]
    nb = kundur.case.n_bus
    assert len(lab) == 4 + 1 + 4 + 2 * nb
    assert lab[-1] == f"f_bus_B{int(kundur.case.buses.number[-1])}"
    C, D = np.asarray(sys_k.C), np.asarray(sys_k.D)
    w = kundur.inertia / kundur.inertia.sum()
    speeds = [sys_k.state_labels.index(f"mac_omega_G{g}") for g in range(1, 5)]
    np.testing.assert_allclose(C[4, speeds], w, rtol=1e-15)
    np.testing.assert_allclose(C[5:9], C[:4] - C[4], atol=1e-15)
    assert np.all(D[:9] == 0)  # speeds have no feedthrough
    v10 = lab.index("vmag_B10")
    assert D[v10, 0] < 0  # drawing power lowers the voltage


def test_reference_inputs_enter_as_the_equations_say(sys_k):
    """d(dEfd/dt)/dVref = K_A/T_A (smpexc, no lead-lag); d(dtg1/dt)/dPref = 1/T_s."""
    B, s, i = np.asarray(sys_k.B), sys_k.state_labels, sys_k.input_labels
    KA_TA = 200 / 0.05
    assert B[s.index("exc_Efd_G2"), i.index("Vref_G2")] == pytest.approx(KA_TA, rel=1e-9)
    assert B[s.index("tg_servo_G3"), i.index("Pref_G3")] == pytest.approx(1 / 0.1, rel=1e-9)
    assert np.count_nonzero(B[:, i.index("Vref_G2")]) == 1


@pytest.mark.parametrize("case_name, bus", [("kundur", 10), ("kundur", 120), ("miniwecc", 2)])
def test_pulse_response_matches_nonlinear_simulation(case_name, bus, kundur, record_property):
    """Speeds, relative speeds, bus voltages and bus frequencies (the chain-rule outputs,
    against the time derivative of the simulated bus angles) within 1 % of the peak."""
    sim = kundur if case_name == "kundur" else Simulator(load_case(case_name))
    sys = linearise(sim)
    err = compare_pulse(sim, sys, bus, P=0.05)
    for key, (e, peak) in err.items():
        record_property(f"{key}_rel_err", e / peak)
        print(f"{case_name} bus {bus} {key}: peak {peak:.3e}, max error {e:.3e} ({e / peak:.2%})")
        assert peak > 0 and e < 0.01 * peak, (key, e, peak)


def test_perturbation_error_is_negligible(kundur):
    est = perturbation_error(kundur)
    assert est["freq_hz"] < 1e-6 and est["damping"] < 1e-6 and est["eig"] < 1e-5
    assert est["A"] < 1e-9 and est["B"] < 1e-7


def test_limiter_crossing_is_refused(kundur):
    """At rel_step 1e-3 the PSS output of a perturbed speed hits its -0.05 limit: the
    one-sided slopes differ by 60 %, by 11 % at a quarter of the step (the limit falls out
    of reach: not a kink at the point, a smaller step helps)."""
    with pytest.raises(SimulationError, match=r"crosses a limiter .* use a smaller rel_step"):
        linearise(kundur, rel_step=1e-3)


def test_bad_input(kundur):
    with pytest.raises(UnknownBusError):
        linearise(kundur, extra_buses=[999])
    with pytest.raises(InputError, match="rel_step"):
        linearise(kundur, rel_step=0.5)
    # round 44: 1e-16 divided by zero inside the kernel (a numba traceback), 1e-12 blamed
    # a limiter that is not there, a text gave a bare TypeError
    for tiny in (1e-16, 1e-300, 1e-12):
        with pytest.raises(
            InputError, match=r"rel_step must be in \[1e-09, 0.1\), got .* round-off"
        ):
            linearise(kundur, rel_step=tiny)
    with pytest.raises(WrongTypeError, match="rel_step must be a number, got '1e-4'"):
        linearise(kundur, rel_step="1e-4")
    with pytest.raises(InputError, match="not kept"):
        linearise_model(kundur.model, [3])
    sys = linearise(kundur, esd_buses=[3], extra_buses=[13, 3])
    assert [n for n in sys.input_labels if n.startswith("P_esd")] == ["P_esd_B3", "P_esd_B13"]
    with pytest.raises(InputError, match="multiples"):
        compare_pulse(kundur, sys, 3, t_on=0.3)


@pytest.mark.parametrize("name", ["kundur", "miniwecc"])
def test_esd_columns_are_linearise_s_b_columns(name):
    """`esd_columns` (B's ESD columns alone, no A) gives linearise's B columns for the same
    buses to round-off (the same central differences, other columns not taken), and the
    placement's distribution factors from it equal those from the whole model."""
    from stabctl.smallsignal.linearise import default_esd_buses, esd_columns
    from stabctl.stability.sime import distribution_factors

    case = load_case(name)
    sim = Simulator(case)
    buses = default_esd_buses(case)[:4]
    full = linearise(sim, esd_buses=buses)
    cols = esd_columns(sim, buses)
    n = len(buses)
    assert cols.input_labels == full.input_labels[:n]
    assert cols.state_labels == full.state_labels
    B = np.asarray(full.B)[:, :n]
    assert np.max(np.abs(cols.B - B)) <= 1e-12 * np.max(np.abs(B))
    args = (buses, case.machines.number, sim.inertia, case.base_mva)
    beta = distribution_factors(cols, *args)
    assert np.array_equal(beta, distribution_factors(full, *args))
