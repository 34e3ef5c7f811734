#!/usr/bin/env python3
"""Oracle numbers for src/aero tests: c172x at 4000 ft, 100 KTAS (JSBSim 1.3.3).

Prints (1) the trim flight condition, mass, inertia and geometry, (2) local derivatives of the JSBSim aero
forces and moments about the CG, by central differences of run_ic states (alpha, beta, p, q, r) and from the
XML constants for the surfaces and alpha-dot, (3) JSBSim's own linearization, reduced to the decoupled 4-state
longitudinal (Vt, alpha, q, theta) and lateral (beta, p, r, phi) submodels, and their modes.

Run: /tmp/jsbvenv/bin/python scripts/oracle_aero.py
"""
import os, sys, tempfile, contextlib
import numpy as np
import jsbsim

FT = 0.3048
SLUG = 14.593902937
SLUGFT2 = SLUG * FT * FT
LBF = 4.4482216152605
PSF = LBF / FT**2


@contextlib.contextmanager
def quiet():
    fd = sys.stdout.fileno(); saved = os.dup(fd)
    with open(os.devnull, 'w') as dn:
        os.dup2(dn.fileno(), fd)
        try:
            yield
        finally:
            os.dup2(saved, fd); os.close(saved)


def make():
    d = tempfile.mkdtemp()
    with quiet():
        fdm = jsbsim.FGFDMExec(None)
        fdm.set_debug_level(0)
        fdm.set_output_path(d); fdm.set_dt(1 / 120)
        fdm.load_model('c172x'); fdm.disable_output()
    return fdm


def trim(fdm):
    fdm['ic/h-sl-ft'] = 4000; fdm['ic/vt-kts'] = 100
    with quiet():
        fdm.run_ic(); fdm['propulsion/set-running'] = -1
        fdm['simulation/do_simple_trim'] = 1


fdm = make(); trim(fdm)
P = lambda n: fdm[n]
alpha0 = P('aero/alpha-rad'); V = P('velocities/vt-fps') * FT
rho = P('atmosphere/rho-slugs_ft3') * SLUG / FT**3
qbar = P('aero/qbar-psf') * PSF
S = P('metrics/Sw-sqft') * FT**2; b = P('metrics/bw-ft') * FT; c = P('metrics/cbarw-ft') * FT
m = P('inertia/mass-slugs') * SLUG
g = P('accelerations/gravity-ft_sec2') * FT
I = {k: P(f'inertia/{k}-slugs_ft2') * SLUGFT2 for k in ['ixx', 'iyy', 'izz', 'ixz']}
# ∫xz dm (Ixx ṗ − Ixz ṙ = L): JSBSim's property has the other sign (its tensor holds ixz where Ixz's is −Ixz)
I['ixz'] = -I['ixz']
theta0 = P('attitude/theta-rad')
CL0 = P('forces/fwz-aero-lbs') * LBF / (qbar * S)
CD0trim = P('forces/fwx-aero-lbs') * LBF / (qbar * S)
de0 = P('fcs/elevator-pos-rad')
print('# flight condition')
for k, v in dict(V_m_s=V, rho_kg_m3=rho, qbar_pa=qbar, alpha0_rad=alpha0, theta0_rad=theta0, g_m_s2=g,
                 CL_trim=CL0, CD_trim=CD0trim, elevator_trim_rad=de0, mass_kg=m, S_m2=S, b_m=b, cbar_m=c,
                 **{k + '_kg_m2': v for k, v in I.items()},
                 thrust_n=P('propulsion/engine/thrust-lbs') * LBF).items():
    print(f'{k} = {v:.10g}')

# ---- local derivatives of the aero forces (wind axes) and moments (body axes, about the CG)
# Aero reference point minus CG in body axes (x forward, z down), ft; structural frame is x aft, z up, inches.
ARM_X_FT = -(43.2 - fdm['inertia/cg-x-in']) / 12.0
ARM_Y_FT = (0.0 - fdm['inertia/cg-y-in']) / 12.0
ARM_Z_FT = -(59.4 - fdm['inertia/cg-z-in']) / 12.0
print(f'# AERORP - CG, body axes, ft: {ARM_X_FT:.4f} {ARM_Y_FT:.4f} {ARM_Z_FT:.4f}')
state0 = {'ic/alpha-rad': alpha0, 'ic/beta-rad': 0.0, 'ic/p-rad_sec': 0.0, 'ic/q-rad_sec': 0.0, 'ic/r-rad_sec': 0.0}


def aero_at(**over):
    f = make()
    f['ic/h-sl-ft'] = 4000; f['ic/vt-kts'] = 100
    st = dict(state0); st.update({f'ic/{k}': v for k, v in over.items()})
    for k, v in st.items():
        f[k] = v
    f['ic/theta-rad'] = theta0
    f['fcs/pitch-trim-cmd-norm'] = fdm['fcs/pitch-trim-cmd-norm']
    with quiet():
        f.run_ic()
    qs = f['aero/qbar-psf'] * PSF * S
    # run_ic leaves a spurious alpha-dot when alpha or q is changed: remove the CLadot and Cmadot terms
    # (the lift term moved to the CG with the x arm between AERORP and CG).
    cladot = f['aero/coefficient/CLadot'] * LBF / qs
    cmadot = f['aero/coefficient/Cmadot'] * LBF * FT / (qs * c) + cladot * ARM_X_FT * FT / c
    return dict(L=f['forces/fwz-aero-lbs'] * LBF / qs - cladot, D=f['forces/fwx-aero-lbs'] * LBF / qs,
                Y=f['forces/fwy-aero-lbs'] * LBF / qs,
                l=f['moments/l-aero-lbsft'] * LBF * FT / (qs * b), m=f['moments/m-aero-lbsft'] * LBF * FT / (qs * c) - cmadot,
                n=f['moments/n-aero-lbsft'] * LBF * FT / (qs * b), adot=f['aero/alphadot-rad_sec'],
                de=f['fcs/elevator-pos-rad'], alpha=f['aero/alpha-rad'])


base = aero_at()
print('# base state check: alpha', base['alpha'], 'elevator', base['de'], 'alphadot', base['adot'])
print(f"CL_base = {base['L']:.10g}  CD_base = {base['D']:.10g}  Cm_base = {base['m']:.10g}")
d = {}
h = 1e-3
for var, key, scale in [('alpha-rad', 'alpha', 1.0), ('beta-rad', 'beta', 1.0),
                        ('p-rad_sec', 'p', b / (2 * V)), ('q-rad_sec', 'q', c / (2 * V)), ('r-rad_sec', 'r', b / (2 * V))]:
    x0 = state0[f'ic/{var}']
    up = aero_at(**{var: x0 + h}); dn = aero_at(**{var: x0 - h})
    for coef in ['L', 'D', 'Y', 'l', 'm', 'n']:
        d[f'C{coef}_{key}'] = (up[coef] - dn[coef]) / (2 * h) / scale
    print(f'# {key}: alphadot during FD {up["adot"]:.3g} {dn["adot"]:.3g}')
print('# derivatives by central differences (forces wind axes, moments body axes about the CG)')
for k, v in d.items():
    print(f'{k} = {v:.6g}')

# ---- JSBSim linearization, decoupled 4-state submodels
lin = jsbsim.FGLinearization(fdm)
A = np.array(lin.system_matrix); B = np.array(lin.input_matrix)
xs = list(lin.x_names); us = list(lin.u_names)
print('# states', xs); print('# inputs', us)


def sub(names):
    idx = [xs.index(n) for n in names]
    return A[np.ix_(idx, idx)], idx


def modes(Asub):
    out = []
    for lam in np.linalg.eigvals(Asub):
        if lam.imag > 1e-9:
            wn = abs(lam); out.append(('osc', wn, -lam.real / wn))
        elif abs(lam.imag) <= 1e-9:
            out.append(('real', lam.real, None))
    return out


lon_names = ['Vt', 'Alpha', 'Q', 'Theta']
lat_names = ['Beta', 'P', 'R', 'Phi']
for label, names in [('longitudinal', lon_names), ('lateral', lat_names)]:
    As, _ = sub(names)
    print(f'# {label} {names}')
    for mo in modes(As):
        print('  ', mo)

# ---- surface and alpha-dot derivatives: XML constants moved from AERORP to the CG (M_cg = M_rp + r x F)
ca, sa = np.cos(alpha0), np.sin(alpha0)
rx, ry, rz = ARM_X_FT * FT, ARM_Y_FT * FT, ARM_Z_FT * FT


def dcm_from_wind(CL, CD):
    CX = -CD * ca + CL * sa; CZ = -CL * ca - CD * sa
    return (rz * CX - rx * CZ) / c


extra = dict(
    CL_de=0.347, CD_de=0.06, Cm_de=-1.28 + dcm_from_wind(0.347, 0.06),
    CL_adot=1.7, Cm_adot=-5.2 + dcm_from_wind(1.7, 0.0),
    CY_da=-0.05, CY_dr=0.098,
    Cl_da=0.23 - rz * (-0.05) / b, Cn_da=0.0053 + rx * (-0.05) / b,
    Cl_dr=0.0147 - rz * 0.098 / b, Cn_dr=-0.043 + rx * 0.098 / b)
print('# surface and alpha-dot derivatives about the CG (XML constants + AERORP->CG transfer)')
for k, v in extra.items():
    print(f'{k} = {v:.6g}')
d.update(extra)

# ---- prototype of the paper-structure model (the Rust src/aero model is checked against these numbers)
Ixx, Iyy, Izz, Ixz = I['ixx'], I['iyy'], I['izz'], I['ixz']


def lon_model(CL_q=True, CL_adot=True, thrust='none', drag_in_z=True, CD_de=True):
    qS = qbar * S; k = c / (2 * V)
    K = d['CD_alpha'] / (2 * CL0 * d['CL_alpha'])  # equivalent induced-drag factor
    Xu = -2 * qS * CD0trim / (m * V) + (-(P('propulsion/engine/thrust-lbs') * LBF) / (m * V) if thrust == 'power' else 0)
    Xa = qS * (CL0 - d['CD_alpha']) / m
    Xde = -qS * (d['CD_de'] if CD_de else 0) / m
    Zu = -2 * qS * CL0 / (m * V)
    Za = -qS * (d['CL_alpha'] + (CD0trim if drag_in_z else 0)) / m
    Zq = -qS * k * (d['CL_q'] if CL_q else 0) / m
    Zad = -qS * k * (d['CL_adot'] if CL_adot else 0) / m
    Zde = -qS * d['CL_de'] / m
    Ma = qS * c * d['Cm_alpha'] / Iyy; Mq = qS * c * k * d['Cm_q'] / Iyy; Mad = qS * c * k * d['Cm_adot'] / Iyy
    Mde = qS * c * d['Cm_de'] / Iyy
    # C xdot = A x + B de, x = [u, alpha, q, theta]
    C = np.eye(4); C[1, 1] = V - Zad; C[2, 1] = -Mad
    A = np.array([[Xu, Xa, 0, -g * np.cos(theta0 - alpha0)],
                  [Zu, Za, V + Zq, -g * np.sin(theta0 - alpha0)],
                  [0, Ma, Mq, 0], [0, 0, 1, 0]])
    B = np.array([Xde, Zde, Mde, 0])
    return np.linalg.solve(C, A), np.linalg.solve(C, B)


def lat_model(stab=True, ixz=True, CY_pr=True):
    qS = qbar * S; k = b / (2 * V)
    names = ['Cl_beta', 'Cl_p', 'Cl_r', 'Cn_beta', 'Cn_p', 'Cn_r', 'Cl_da', 'Cl_dr', 'Cn_da', 'Cn_dr', 'CY_p', 'CY_r']
    D = {n: d[n] for n in names}
    ix, iz, ixz_ = Ixx, Izz, Ixz
    if stab:
        a = alpha0; C_, S_ = np.cos(a), np.sin(a)
        D['Cl_beta'] = d['Cl_beta'] * C_ + d['Cn_beta'] * S_; D['Cn_beta'] = d['Cn_beta'] * C_ - d['Cl_beta'] * S_
        D['Cl_p'] = d['Cl_p'] * C_**2 + (d['Cl_r'] + d['Cn_p']) * S_ * C_ + d['Cn_r'] * S_**2
        D['Cl_r'] = d['Cl_r'] * C_**2 - (d['Cl_p'] - d['Cn_r']) * S_ * C_ - d['Cn_p'] * S_**2
        D['Cn_p'] = d['Cn_p'] * C_**2 - (d['Cl_p'] - d['Cn_r']) * S_ * C_ - d['Cl_r'] * S_**2
        D['Cn_r'] = d['Cn_r'] * C_**2 - (d['Cl_r'] + d['Cn_p']) * S_ * C_ + d['Cl_p'] * S_**2
        for s_ in ['da', 'dr']:
            D['Cl_' + s_] = d['Cl_' + s_] * C_ + d['Cn_' + s_] * S_; D['Cn_' + s_] = d['Cn_' + s_] * C_ - d['Cl_' + s_] * S_
        D['CY_p'] = d['CY_p'] * C_ + d['CY_r'] * S_; D['CY_r'] = d['CY_r'] * C_ - d['CY_p'] * S_
        ix = Ixx * C_**2 + Izz * S_**2 - Ixz * np.sin(2 * a); iz = Ixx * S_**2 + Izz * C_**2 + Ixz * np.sin(2 * a)
        ixz_ = 0.5 * (Ixx - Izz) * np.sin(2 * a) + Ixz * np.cos(2 * a)
    if not ixz:
        ixz_ = 0.0
    if not CY_pr:
        D['CY_p'] = 0; D['CY_r'] = 0
    Yb = qS * d['CY_beta'] / m; Yp = qS * k * D['CY_p'] / m; Yr = qS * k * D['CY_r'] / m
    Ydr = qS * d['CY_dr'] / m; Yda = qS * d['CY_da'] / m
    L = lambda n: qS * b * D[n] / ix * (k if n[-1] in 'pr' and n[-2] == '_' else 1)
    N = lambda n: qS * b * D[n] / iz * (k if n[-1] in 'pr' and n[-2] == '_' else 1)
    gam0 = theta0 - alpha0
    C = np.eye(4); C[1, 2] = -ixz_ / ix; C[2, 1] = -ixz_ / iz
    A = np.array([[Yb / V, Yp / V, Yr / V - 1, g * np.cos(gam0) / V],
                  [L('Cl_beta'), L('Cl_p'), L('Cl_r'), 0],
                  [N('Cn_beta'), N('Cn_p'), N('Cn_r'), 0],
                  [0, 1, np.tan(gam0), 0]])
    B = np.array([[Yda / V, Ydr / V], [L('Cl_da'), L('Cl_dr')], [N('Cn_da'), N('Cn_dr')], [0, 0]])
    return np.linalg.solve(C, A), np.linalg.solve(C, B)


def pr(label, Am):
    print('  ', label, [(round(x[1], 4), None if x[2] is None else round(x[2], 4)) for x in modes(Am)])


print('# paper-structure model modes (osc: omega_n, zeta; real: pole)')
pr('lon full', lon_model()[0])
pr('lon no CLq', lon_model(CL_q=False)[0])
pr('lon no CLq CLadot', lon_model(CL_q=False, CL_adot=False)[0])
pr('lon no drag in Z', lon_model(drag_in_z=False)[0])
pr('lon const power thrust', lon_model(thrust='power')[0])
pr('lon no CDde', lon_model(CD_de=False)[0])
pr('lat full', lat_model()[0])
pr('lat body axes', lat_model(stab=False)[0])
pr('lat no Ixz', lat_model(ixz=False)[0])
pr('lat no CYp CYr', lat_model(CY_pr=False)[0])
# JSBSim's CYb is on the wind-axis SIDE force: the stability-axis side-force slope is C_Yb - C_D (the Rust
# model's `side_force_in_wind_axes`); this is the configuration the Rust tests compare with.
d['CY_beta'] -= CD0trim
pr('lat full + drag in Y', lat_model()[0])
