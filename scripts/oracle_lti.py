#!/usr/bin/env python3
"""Reference numbers for flightid's `lti` module, from scipy and python-control.

Run:  /tmp/jsbvenv/bin/python scripts/oracle_lti.py
The printed values are pasted into the unit tests of src/lti (see `tests.rs`), so the Rust
tests stay fast and need no Python at test time.

TFs are those of Şahin & Kalyon (2021), eq. 65 and 67 (the paper's "original" models).
"""
import numpy as np
import scipy.signal as sig
import control

np.set_printoptions(precision=17)

THETA_NUM = [-24.7885, -18.2186, -0.4659]
THETA_DEN = [1.0, 2.0072, 32.5269, 0.8638, 0.0179]
PHI_A_NUM = [26.8666, 0.4725, 94.0527]
PHI_A_DEN = [1.0, 1.8683, 3.6856, 6.2648, -0.0085]


def show(name, values):
    print(f"{name} = [" + ", ".join(repr(float(v)) for v in values) + "]")


def modes(name, den):
    poles = np.roots(den)
    wn, zeta, p = control.damp(control.tf([1.0], den), doprint=False)
    print(f"--- {name}: poles, wn, zeta (python-control damp)")
    for pi, wi, zi in sorted(zip(p, wn, zeta), key=lambda x: -x[1]):
        if pi.imag >= 0:
            print(f"pole {float(pi.real)!r} {float(pi.imag)!r}  wn {float(wi)!r}  zeta {float(zi)!r}")


modes("theta/elevator", THETA_DEN)
modes("phi/aileron", PHI_A_DEN)

print("--- c2d ZOH theta/elevator, dt = 0.01 s (scipy cont2discrete)")
num_d, den_d, _ = sig.cont2discrete((THETA_NUM, THETA_DEN), 0.01, method="zoh")
show("num_z", np.ravel(num_d))
show("den_z", den_d)

print("--- c2d Tustin theta/elevator, dt = 0.05 s (scipy cont2discrete bilinear)")
num_t, den_t, _ = sig.cont2discrete((THETA_NUM, THETA_DEN), 0.05, method="bilinear")
show("num_z", np.ravel(num_t))
show("den_z", den_t)

print("--- bode theta/elevator at w = 0.1, 1, 5.7, 30 rad/s (python-control, unwrapped)")
mag, phase, w = control.frequency_response(
    control.tf(THETA_NUM, THETA_DEN), [0.1, 1.0, 5.7, 30.0]
)
show("mag_db", 20 * np.log10(mag))
show("phase_deg", np.degrees(phase))
print(f"dc_gain = {float(control.dcgain(control.tf(THETA_NUM, THETA_DEN)))!r}")

print("--- lsim phi/aileron, doublet 1 s pulses from t = 1 s, dt = 0.01 s, 60 s, ZOH (interp=False)")
dt = 0.01
t = np.arange(6001) * dt
u = np.zeros_like(t)
u[100:200] = 1.0
u[200:300] = -1.0
_, y, _ = sig.lsim((PHI_A_NUM, PHI_A_DEN), u, t, interp=False)
idx = [150, 300, 1000, 3000, 6000]
print("indices", idx)
show("y", y[idx])
