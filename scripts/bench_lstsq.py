#!/usr/bin/env python3
"""Times numpy.linalg.lstsq on an ARX(4, 4) regressor of 200,000 rows x 8 columns, the same
size and structure as the `arx_ls_200k_samples_8_params` bench in benches/ident.rs (theta/elevator
doublet response, 100 Hz, 1 % uniform noise). Prints the median of 20 runs in milliseconds.

Usage: python scripts/bench_lstsq.py
"""
import time

import numpy as np
import scipy.signal as ss

DT = 0.01
N = 200_000


def main():
    t = np.arange(N) * DT
    u = np.where((t >= 1) & (t < 2), 1.0, 0.0) - np.where((t >= 2) & (t < 3), 1.0, 0.0)
    sys = ss.cont2discrete(ss.tf2ss([-24.7885, -18.2186, -0.4659],
                                    [1, 2.0072, 32.5269, 0.8638, 0.0179]), DT, "zoh")
    _, y, _ = ss.dlsim(sys[:4] + (DT,), u)
    y = y[:, 0]
    y = y + 0.01 * y.std() * (np.random.default_rng(1).random(N) - 0.5) * np.sqrt(12)
    k = np.arange(4, N)
    phi = np.column_stack([-y[k - 1 - i] for i in range(4)] + [u[k - 1 - j] for j in range(4)])
    target = y[k]
    times = []
    for _ in range(20):
        t0 = time.perf_counter()
        np.linalg.lstsq(phi, target, rcond=None)
        times.append(time.perf_counter() - t0)
    times.sort()
    lstsq_times = times
    print(f"numpy.linalg.lstsq {phi.shape[0]}x{phi.shape[1]}: median {1e3 * times[10]:.2f} ms "
          f"(min {1e3 * times[0]:.2f} ms)")
    # with the regressor build included, for a like-for-like comparison with the Rust bench
    times = []
    for _ in range(10):
        t0 = time.perf_counter()
        phi = np.column_stack([-y[k - 1 - i] for i in range(4)] + [u[k - 1 - j] for j in range(4)])
        np.linalg.lstsq(phi, y[k], rcond=None)
        times.append(time.perf_counter() - t0)
    times.sort()
    build_ms = 1e3 * times[5]
    print(f"regressor build + lstsq: median {build_ms:.2f} ms")
    # machine-readable line for benches/paper.rs
    print(f"RESULT lstsq_ms={1e3 * lstsq_times[10]:.3f} build_lstsq_ms={build_ms:.3f}")


if __name__ == "__main__":
    main()
