"""Dryden turbulence (MIL-F-8785C forms) as sampled time series, for the independent record generators.

A gust component is white noise through a shaping filter: along the flight path H_u(s) = sigma sqrt(2T)/(1 + Ts),
across it H_v(s) = H_w(s) = sigma sqrt(T) (1 + sqrt(3) T s)/(1 + T s)^2, with T = L/V (scale length over the
speed the frozen field is flown through). Each filter is discretised exactly (Van Loan: one matrix exponential
gives the transition and the process-noise covariance of the sample interval) and started from its stationary
distribution, so every sample of the series has the Dryden variance sigma^2. numpy and scipy only.
"""

import math

import numpy as np
import scipy.linalg


def _form(kind, sigma, T):
    """State-space (A, B, C) of the shaping filter of a component: "u" (first order) or "w" (second order)."""
    if kind == "u":
        # x' = -x/T + eta, u = sigma sqrt(2T)/T x
        return (np.array([[-1.0 / T]]), np.array([[1.0]]), np.array([[sigma * math.sqrt(2.0 * T) / T]]))
    # controllable canonical form of sigma sqrt(T) (1 + sqrt(3) T s)/(T s + 1)^2
    return (np.array([[0.0, 1.0], [-1.0 / T**2, -2.0 / T]]), np.array([[0.0], [1.0]]),
            np.array([[1.0, math.sqrt(3.0) * T]]) * sigma * math.sqrt(T) / T**2)


def dryden_series(kinds, sigma, T, n, dt, rng):
    """One series of n samples dt apart per entry of `kinds` ("u" or "w"; a lateral gust takes the "w" form),
    drawn in that order from `rng` (each: its initial state, then its n steps); zeros when sigma == 0 (the
    draws are made anyway, so other draws of `rng` do not depend on it)."""
    out = []
    for kind in kinds:
        A, B, C = _form(kind, sigma, T)
        k = A.shape[0]
        M = np.zeros((2 * k, 2 * k))
        M[:k, :k] = -A
        M[:k, k:] = B @ B.T
        M[k:, k:] = A.T
        E = scipy.linalg.expm(M * dt)
        Phi = E[k:, k:].T
        Qd = Phi @ E[:k, k:]
        Qd = 0.5 * (Qd + Qd.T)
        Lq = np.linalg.cholesky(Qd + 1e-30 * np.eye(k))
        Lp = np.linalg.cholesky(scipy.linalg.solve_continuous_lyapunov(A, -B @ B.T))
        x = Lp @ rng.standard_normal(k)
        w = rng.standard_normal((n, k))
        y = np.empty(n)
        for i in range(n):
            y[i] = (C @ x)[0]
            x = Phi @ x + Lq @ w[i]
        out.append(y)
    return out
