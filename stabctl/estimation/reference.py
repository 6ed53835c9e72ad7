"""filterpy reference implementations of the compiled estimators
(`stabctl.estimation.filters`): `FrequencyKFReference` and `SwingEKFReference` run one
filterpy filter per machine (filterpy does the Kalman algebra) on the same one-machine
equations, slowly; tests check that the compiled filters agree with them to rounding
(`benchmarks/bench_estimator.py` times both).  The only module that imports filterpy.
"""

from __future__ import annotations

import numpy as np
from filterpy.common import Q_continuous_white_noise
from filterpy.kalman import ExtendedKalmanFilter, KalmanFilter

from stabctl.estimation.filters import (
    FrequencyKF,
    SwingEKF,
    T,
    swing_begin,
    swing_h,
    swing_inputs,
    swing_measure,
    swing_Q,
    swing_transition,
    wrap_angle,
)


class FrequencyKFReference(FrequencyKF):
    """`FrequencyKF` with one filterpy `KalmanFilter` per machine (reference, slow)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.kfs = [KalmanFilter(dim_x=2, dim_z=2) for _ in range(self.pmu.size)]

    def _advance(self, frame, dt):
        z, ok = self._measure(frame)
        self.nis[:] = np.nan
        for k, kf in enumerate(self.kfs):
            if not self.ready[k]:
                if ok[k]:
                    kf.x, kf.P, self.ready[k] = z[k].copy(), self.R.copy(), True
                    self.x[k], self.P[k] = kf.x, kf.P
                continue
            kf.F, kf.Q = (
                np.array([[1.0, dt], [0.0, 1.0]]),
                Q_continuous_white_noise(2, dt, self.tun.rocof_walk),
            )
            kf.predict()
            if ok[k]:
                kf.update(z[k], R=self.R, H=np.eye(2))
                self.nis[k] = kf.y @ kf.SI @ kf.y
            self.x[k], self.P[k] = kf.x, kf.P


class _SwingEKF1(ExtendedKalmanFilter):
    """filterpy EKF of one machine; its nonlinear transition is evaluated by the shared
    swing equations and handed to `predict` as u."""

    def predict_x(self, u=0):
        self.x = u


class SwingEKFReference(SwingEKF):
    """`SwingEKF` with one filterpy `ExtendedKalmanFilter` per machine (reference, slow),
    on the same one-machine equations (`swing_*`)."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.ekfs = [_SwingEKF1(dim_x=5, dim_z=1) for _ in range(self.m.n)]

    def _advance(self, frame, dt):
        fr = self._frame(frame)
        v, i, ok = fr.v, fr.i, fr.valid
        disc = self._discrete(dt)
        self.nis[:] = np.nan
        for k, ekf in enumerate(self.ekfs):
            pr = self.par[k]
            if not (self.ready[k] or ok[k]):
                continue
            meas = swing_measure(v[k], i[k], pr, self.tv[T.SIG2]) if ok[k] else (np.nan,) * 6
            if not self.ready[k]:
                ekf.x, ekf.P = swing_begin(k, fr, *meas[2:], pr, self.tv, self.held)
                self.ready[k] = True
            else:
                self._predict(ekf, k, fr, meas, dt, disc)
                if ok[k]:
                    self._update(ekf, k, meas[0], meas[1], meas[5])
            self.x[k], self.P[k] = ekf.x, ekf.P

    def _predict(self, ekf, k, fr, meas, dt, disc):
        pr, tv = self.par[k], self.tv
        u = swing_inputs(k, fr, meas[2], meas[3], meas[4], self.held, ekf.x[1], pr, disc, tv)
        Adq, bdq = disc.Adq[k], disc.bdq[k]
        xn, F, gs = swing_transition(ekf.x, u[0], u[1], u[3], u[4], dt, pr, Adq, bdq, tv[T.F0])
        ekf.F, ekf.Q = F, swing_Q(gs, u[2], u[5], bdq, dt, tv)
        ekf.predict(u=xn)

    def _update(self, ekf, k, theta, emag, r):
        pr, tv = self.par[k], self.tv
        ekf.update(
            np.array([theta]),
            HJacobian=lambda x: swing_h(x, emag, pr)[1][None, :],
            Hx=lambda x: np.array([swing_h(x, emag, pr)[0]]),
            R=np.array([[r + tv[T.ANGLE] ** 2]]),
            residual=lambda a, b: np.array([wrap_angle(a[0] - b[0])]),
        )
        self.nis[k] = ekf.y @ ekf.SI @ ekf.y
