#!/usr/bin/env python3
"""Independent reference for `flightid linearize`: python-control's ss2tf on the decoupled 4-state submodels.

Usage: oracle_linearize.py LIN.json   (a serialised flightid Linearization: states, inputs, A, B)
Prints {"theta/elevator": {"num": [...], "den": [...]}, ...} with monic denominators and numerically-zero
leading numerator terms (below 1e-10 of the largest) removed.
"""
import json
import sys

import control
import numpy as np

LON = ["Vt", "Alpha", "Theta", "Q"]
LAT = ["Beta", "Phi", "P", "R"]
TFS = [("theta/elevator", LON, "elevator", "Theta"), ("phi/aileron", LAT, "aileron", "Phi"),
       ("phi/rudder", LAT, "rudder", "Phi")]

lin = json.load(open(sys.argv[1]))
A = np.array(lin["A"])
B = np.array(lin["B"])
out = {}
for key, states, inp, outp in TFS:
    idx = [lin["states"].index(s) for s in states]
    j = lin["inputs"].index(inp)
    a = A[np.ix_(idx, idx)]
    b = B[np.ix_(idx, [j])]
    c = np.zeros((1, 4))
    c[0, states.index(outp)] = 1.0
    tf = control.ss2tf(a, b, c, np.zeros((1, 1)))
    num = np.array(tf.num[0][0], dtype=float)
    den = np.array(tf.den[0][0], dtype=float)
    num, den = num / den[0], den / den[0]
    big = np.max(np.abs(num))
    while len(num) > 1 and abs(num[0]) < 1e-10 * big:
        num = num[1:]
    out[key] = {"num": num.tolist(), "den": den.tolist()}
print(json.dumps(out))
