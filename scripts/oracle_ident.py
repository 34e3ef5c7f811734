#!/usr/bin/env python3
"""Oracle numbers for src/ident tests (run with the project's Python: numpy + scipy).

Builds the paper's doublet record for theta/elevator (Sahin & Kalyon 2021, eq. 65):
60 s at 100 Hz, unit doublet +1 on [1 s, 2 s), -1 on [2 s, 3 s), simulated exactly for a
zero-order-hold input (scipy cont2discrete 'zoh'), then fits the ARX model of eq. 59 with
n = nb = 4 on the same regressor as flightid (rows k = 4..N-1:
[-y(k-1) .. -y(k-4), u(k-1) .. u(k-4)]) with numpy.linalg.lstsq.

Prints the ARX parameters and a few output samples, which the Rust tests hold as constants.
"""
import numpy as np
import scipy.signal as ss

NUM = [-24.7885, -18.2186, -0.4659]
DEN = [1.0, 2.0072, 32.5269, 0.8638, 0.0179]
DT = 0.01
N = 6001


def doublet(n, dt):
    t = np.arange(n) * dt
    return np.where((t >= 1) & (t < 2), 1.0, 0.0) - np.where((t >= 2) & (t < 3), 1.0, 0.0)


def simulate(num, den, u, dt):
    a, b, c, d = ss.tf2ss(num, den)
    ad, bd, cd, _, _ = ss.cont2discrete((a, b, c, d), dt, "zoh")
    x = np.zeros(ad.shape[0])
    y = np.zeros(len(u))
    for k in range(len(u)):
        y[k] = (cd @ x)[0]
        x = ad @ x + bd[:, 0] * u[k]
    return y


def arx_regressor(u, y, n, nb):
    rows = [np.r_[[-y[k - 1 - i] for i in range(n)], [u[k - 1 - j] for j in range(nb)]]
            for k in range(max(n, nb), len(y))]
    return np.array(rows), y[max(n, nb):]


def main():
    u = doublet(N, DT)
    y = simulate(NUM, DEN, u, DT)
    phi, target = arx_regressor(u, y, 4, 4)
    theta, _, _, sv = np.linalg.lstsq(phi, target, rcond=None)
    print("condition number:", sv[0] / sv[-1])
    print("theta (a1..a4, b1..b4):")
    print("[" + ", ".join(f"{v:.15e}" for v in theta) + "]")
    for k in (150, 300, 1000, 6000):
        print(f"y[{k}] = {y[k]:.15e}")


if __name__ == "__main__":
    main()
