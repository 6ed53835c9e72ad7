"""The machines' shared rotation (`stabctl.models.machines.internal_voltage`): the d-q
components that the field currents and the derivatives take from its exp(j delta),
conjugated, are bit for bit those of exp(-j delta) computed anew (the cosine even, the
sine odd), so that sharing it left every trajectory as it was."""

import numpy as np

from stabctl.dynamics.driver import Simulator
from stabctl.io import load_case
from stabctl.models.machines import _dq, _dq_at, internal_voltage


def test_the_shared_rotation_gives_the_bits_of_a_fresh_one():
    m = Simulator(load_case("kundur")).model
    n = m.mp.n
    rng = np.random.default_rng(7)
    x = m.x0[: 6 * n].reshape(6, n).copy()
    psi, rot = np.empty(n, complex), np.empty(n, complex)
    deltas = np.r_[rng.uniform(-60, 60, 400), rng.uniform(-1e-3, 1e-3, 40), 0.0, -0.0, np.pi]
    for d in deltas.reshape(-1, 1) + np.zeros(n):
        x[0] = d
        internal_voltage(m.params.MP, x, psi, rot)
        for i in range(n):
            X = complex(rng.normal(), rng.normal())
            assert _dq_at(np.conj(rot[i]), X) == _dq(x[0, i], X)
            assert abs(rot[i] - np.exp(1j * x[0, i])) < 1e-15
