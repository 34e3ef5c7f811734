#!/usr/bin/env python3
"""Independent check of the paper's least squares (`identify --method ls`) and its conversion to continuous time.

Usage:  python oracle_ls_d2c.py RECORD.csv INPUT_COLUMN OUTPUT_COLUMN LS_RESULT.json

RECORD.csv is a flight-data CSV, LS_RESULT.json the `result` object of `flightid identify --method ls --json`
on the same columns (4 poles, 2 zeros). This script refits the discrete ARX model of Sahin & Kalyon (2021)
eq. 59-64 with numpy.linalg.lstsq (4 poles, 4 numerator terms b1..b4, no delay), converts it to continuous
time by the matrix logarithm of the ZOH relation (scipy.linalg.logm on [[Ad, Bd], [0, 1]], an implementation
independent of flightid's), and simulates every model with scipy (cont2discrete ZOH + lfilter). It prints JSON:

- discrete_fit_percent:     the discrete ARX model simulated as a discrete model (the method itself);
- exact_d2c_fit_percent:    its exact continuous equivalent (3 zeros) simulated with a ZOH input (must equal the
                            discrete fit: d2c followed by c2d is the identity);
- flightid_fit_percent:     flightid's continuous ls model simulated here (scipy), to compare with the fit
                            flightid reports;
- flightid_pole_errors:     |flightid pole - oracle d2c pole| per pole, rad/s;
- oracle_poles:             the oracle's continuous poles [re, im].

Fit % is 100 (1 - |y - y_hat| / |y - mean y|), the NRMSE fit flightid reports.
"""
import csv
import json
import sys

import numpy as np
import scipy.linalg
import scipy.signal as sig


def read_columns(path, names):
    with open(path) as f:
        rows = [line for line in f if not line.startswith("#")]
    reader = csv.DictReader(rows)
    data = {n: [] for n in names}
    for row in reader:
        for n in names:
            data[n].append(float(row[n]))
    return {n: np.array(v) for n, v in data.items()}


def fit_percent(y, y_hat):
    return float(100.0 * (1.0 - np.linalg.norm(y - y_hat) / np.linalg.norm(y - y.mean())))


def arx(u, y, n, nb):
    """Eq. 59-64: y(k) = -a1 y(k-1) ... - an y(k-n) + b1 u(k-1) + ... + b_nb u(k-nb)."""
    first = max(n, nb)
    rows = [np.concatenate([-y[k - n:k][::-1], u[k - nb:k][::-1]]) for k in range(first, len(y))]
    theta, *_ = np.linalg.lstsq(np.array(rows), y[first:], rcond=None)
    return np.concatenate([[1.0], theta[:n]]), theta[n:]


def d2c_zoh(num_z, den_z, dt):
    """Exact inverse of the ZOH discretisation via the matrix logarithm of [[Ad, Bd], [0, 1]]."""
    a, b, c, d = sig.tf2ss(num_z, den_z)
    n = a.shape[0]
    m = np.zeros((n + 1, n + 1))
    m[:n, :n] = a
    m[:n, n:] = b
    m[n, n] = 1.0
    log = scipy.linalg.logm(m).real / dt
    return log[:n, :n], log[:n, n:], c, d


def simulate_zoh(num, den, u, dt):
    num_z, den_z, _ = sig.cont2discrete((num, den), dt, method="zoh")
    return sig.lfilter(np.ravel(num_z), den_z, u)


def main():
    path, input_col, output_col, result_path = sys.argv[1:5]
    cols = read_columns(path, ["time_s", input_col, output_col])
    t, u, y = cols["time_s"], cols[input_col], cols[output_col]
    dt = float(np.mean(np.diff(t)))
    # trim = the samples before the input first moves (noise-free record: the input is constant until then)
    still = int(np.argmax(np.abs(u - u[0]) > 0.0)) or 1
    du = u - u[0]
    dy = y - y[:still].mean()
    n = 4
    a, b = arx(du, dy, n, n)
    num_z = np.concatenate([[0.0], b])  # b1 z^-1 ... b4 z^-4 over 1 + a1 z^-1 ...: same-degree polynomials in z
    y_disc = sig.lfilter(num_z, a, du)
    ac, bc, cc, dc = d2c_zoh(num_z, a, dt)
    num_c, den_c = sig.ss2tf(ac, bc, cc, dc)
    num_c = np.ravel(num_c)
    y_exact = simulate_zoh(num_c, den_c, du, dt)
    with open(result_path) as f:
        ls = json.load(f)
    tf = ls["tf"]
    y_flightid = simulate_zoh(tf["num"], tf["den"], du, dt)
    oracle_poles = sorted(np.linalg.eigvals(ac), key=lambda p: (p.real, p.imag))
    flightid_poles = sorted((complex(p[0], p[1]) for p in ls["poles"]), key=lambda p: (p.real, p.imag))
    print(json.dumps({
        "dt_s": dt,
        "discrete_fit_percent": fit_percent(dy, y_disc),
        "exact_d2c_fit_percent": fit_percent(dy, y_exact),
        "flightid_fit_percent": fit_percent(dy, y_flightid),
        "exact_d2c_num": [float(v) for v in num_c],
        "exact_d2c_den": [float(v) for v in den_c],
        "oracle_poles": [[float(p.real), float(p.imag)] for p in oracle_poles],
        "flightid_pole_errors": [abs(p - q) for p, q in zip(flightid_poles, oracle_poles)],
    }, indent=1))


if __name__ == "__main__":
    main()
