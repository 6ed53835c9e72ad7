"""Section 3 feedback laws on the paper's 15-cycle case."""

import numpy as np
import pytest

from stabctl.errors import InputError
from stabctl.smib.feedback import PAPER_LAWS, FeedbackLaw, settling_time
from stabctl.smib.omib import PAPER_OMIB, simulate

T_CLEAR = 15 / 60


@pytest.fixture(scope="module")
def runs():
    return {law.name: simulate(PAPER_OMIB, T_CLEAR, t_end=10.0, law=law) for law in PAPER_LAWS}


def test_every_paper_law_stabilises_the_15_cycle_case(runs):
    assert not simulate(PAPER_OMIB, T_CLEAR, t_end=10.0).stable
    assert all(r.stable for r in runs.values())


def test_sign_law_gives_smallest_speed_swing_and_fastest_settling(runs):
    post = {n: np.abs(r.omega[r.t >= T_CLEAR]).max() for n, r in runs.items()}
    settle = {n: settling_time(r.t, r.omega, T_CLEAR) for n, r in runs.items()}
    sign = PAPER_LAWS[3].name
    assert min(post, key=post.get) == sign
    assert min(settle, key=settle.get) == sign


@pytest.mark.parametrize("law", PAPER_LAWS)
@pytest.mark.parametrize("f,omega", [(0.3, 2.0), (-0.4, 3.0), (0.2, -1.0), (-0.1, -5.0)])
def test_algebraic_loop_solution_satisfies_the_swing_equation(law, f, omega):
    M = PAPER_OMIB.M
    a, p = law(f, omega, M)
    assert M * a == pytest.approx(f - p, rel=1e-12)
    expected = (
        law.Kv * omega + law.Ka * abs(a) * np.sign(omega)
        if law.sign_law
        else law.Kv * omega + law.Ka * a
    )
    assert p == pytest.approx(expected, rel=1e-12)


def test_sign_law_always_absorbs_swing_energy(runs):
    r = runs[PAPER_LAWS[3].name]
    assert np.all(r.P_C * r.omega >= -1e-12)


def test_singular_algebraic_loop_is_rejected():
    with pytest.raises(InputError):
        FeedbackLaw("too strong", Ka=-0.02).check(PAPER_OMIB.M)
