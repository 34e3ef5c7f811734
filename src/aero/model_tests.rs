//! Tests of `model`.

use super::*;
use crate::aero::params::Derivative;

/// c172x at 4000 ft, 100 KTAS, trimmed by JSBSim 1.3.3 (`scripts/oracle_aero.py`, "flight condition" block:
/// `aero/qbar-psf`, `velocities/vt-fps`, `aero/alpha-rad`, `inertia/*` with the point masses, `metrics/*`).
pub(crate) const V_M_S: f64 = 51.44444444;
pub(crate) const RHO_KG_M3: f64 = 1.087939275;
pub(crate) const ALPHA0_RAD: f64 = 0.01935271377;
pub(crate) const CL_TRIM: f64 = 0.4716539073;
pub(crate) const CD_TRIM: f64 = 0.04761057874;
pub(crate) const G_M_S2: f64 = 9.810440323;

/// Body-axis mass properties (JSBSim `inertia/*-slugs_ft2` after trim, converted to SI; ixz with the textbook
/// sign, the property's negative).
pub(crate) fn c172x_mass_body() -> MassProperties {
    MassProperties {
        mass_kg: 1124.909062,
        ixx_kg_m2: 2841.434964,
        iyy_kg_m2: 2040.522117,
        izz_kg_m2: 4271.422149,
        ixz_kg_m2: -18.37788633,
    }
}

/// `metrics/Sw-sqft`, `metrics/bw-ft`, `metrics/cbarw-ft` (174 ft², 36 ft, 4.9 ft).
pub(crate) fn c172x_geometry() -> Geometry {
    Geometry {
        wing_area_m2: 16.16512896,
        span_m: 10.9728,
        chord_m: 1.49352,
    }
}

/// c172x derivatives about the CG at the trim above (`scripts/oracle_aero.py`): α, β, p, q, r slopes by
/// central differences of JSBSim's own forces and moments (tables included: CLwbh + CLalpha give
/// C_Lα = 9.93, Clr(α) gives 0.114), surfaces and α̇ from the XML constants (Cmde −1.28, Cmadot −5.2,
/// Clda 0.23, …) moved from the AERORP to the CG. Lateral values in body axes; C_Y on the wind-axis
/// side force. The polar is the local equivalent: K = C_Dα/(2 C_L0 C_Lα), C_D0 = C_D − K C_L0².
pub(crate) fn c172x_derivatives_body() -> Derivatives {
    let cd_alpha = 0.359842;
    let cl_alpha = 9.93169;
    let k = cd_alpha / (2.0 * CL_TRIM * cl_alpha);
    Derivatives::from_pairs(&[
        (Derivative::CD0, CD_TRIM - k * CL_TRIM * CL_TRIM),
        (Derivative::CDCL2, k),
        (Derivative::CLalpha, cl_alpha),
        (Derivative::CLde, 0.347),
        (Derivative::CLq, 3.9),
        (Derivative::CLalphadot, 1.7),
        (Derivative::Cmalpha, -1.53513),
        (Derivative::Cmalphadot, -5.14723),
        (Derivative::Cmq, -12.2921),
        (Derivative::Cmde, -1.24473),
        (Derivative::CYbeta, -0.309456),
        (Derivative::CYp, -0.037),
        (Derivative::CYr, 0.21),
        (Derivative::CYda, -0.05),
        (Derivative::CYdr, 0.098),
        (Derivative::Clbeta, -0.108936),
        (Derivative::Clp, -0.472053),
        (Derivative::Clr, 0.1143),
        (Derivative::Clda, 0.227225),
        (Derivative::Cldr, 0.0201383),
        (Derivative::Cnbeta, 0.0631497),
        (Derivative::Cnp, -0.0301961),
        (Derivative::Cnr, -0.097887),
        (Derivative::Cnda, 0.00503501),
        (Derivative::Cndr, -0.0424806),
    ])
}

/// The c172x model in stability axes with the given assumptions.
pub(crate) fn c172x_model(assumptions: Assumptions) -> AeroModel {
    let mass = c172x_mass_body().to_stability_axes(ALPHA0_RAD);
    AeroModel {
        flight: FlightCondition {
            airspeed_m_s: V_M_S,
            air_density_kg_m3: RHO_KG_M3,
            cl_trim: CL_TRIM,
            flight_path_angle_rad: 0.0,
            g_m_s2: G_M_S2,
        },
        mass,
        geometry: c172x_geometry(),
        derivatives: c172x_derivatives_body().body_to_stability(ALPHA0_RAD),
        assumptions,
    }
}

/// JSBSim's own linearization at the same trim (`jsbsim.FGLinearization`, decoupled 4-state submodels,
/// `scripts/oracle_aero.py`): short period and Dutch roll (ωn rad/s, ζ).
const JSBSIM_SHORT_PERIOD: (f64, f64) = (6.1115747, 0.6748321);
const JSBSIM_DUTCH_ROLL: (f64, f64) = (2.1343978, 0.1573628);

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

fn short_period(a: Assumptions) -> (f64, f64) {
    c172x_model(a)
        .longitudinal()
        .unwrap()
        .fastest_oscillation()
        .unwrap()
        .unwrap()
}

fn dutch_roll(a: Assumptions) -> (f64, f64) {
    c172x_model(a)
        .lateral()
        .unwrap()
        .fastest_oscillation()
        .unwrap()
        .unwrap()
}

fn jsbsim_assumptions() -> Assumptions {
    Assumptions {
        side_force_in_wind_axes: true,
        ..Assumptions::textbook()
    }
}

#[test]
fn c172x_short_period_matches_jsbsim_linearization_within_5_percent() {
    // Specification: the paper-structure model from the truth derivatives within 5 % of JSBSim.
    for (label, a) in [
        ("textbook", jsbsim_assumptions()),
        ("paper", Assumptions::paper()),
    ] {
        let (wn, zeta) = short_period(a);
        assert!(rel(wn, JSBSIM_SHORT_PERIOD.0) < 0.05, "{label}: wn {wn}");
        assert!(
            rel(zeta, JSBSIM_SHORT_PERIOD.1) < 0.05,
            "{label}: zeta {zeta}"
        );
    }
    // With every term the model knows the match is at round-off of the finite differences (< 0.3 %).
    let (wn, zeta) = short_period(jsbsim_assumptions());
    assert!(rel(wn, JSBSIM_SHORT_PERIOD.0) < 3e-3 && rel(zeta, JSBSIM_SHORT_PERIOD.1) < 3e-3);
}

#[test]
fn c172x_dutch_roll_matches_jsbsim_linearization_within_5_percent() {
    let (wn, zeta) = dutch_roll(jsbsim_assumptions());
    assert!(rel(wn, JSBSIM_DUTCH_ROLL.0) < 0.05, "wn {wn}");
    assert!(rel(zeta, JSBSIM_DUTCH_ROLL.1) < 0.05, "zeta {zeta}");
}

#[test]
fn c172x_paper_assumptions_cost_dutch_roll_damping() {
    // The paper's side-force equation (no wind-axis drag term, no C_Yp, C_Yr) loses about 5 % of the
    // Dutch-roll damping against JSBSim: the price of its simplifications, reported, not hidden.
    let (wn, zeta) = dutch_roll(Assumptions::paper());
    assert!(rel(wn, JSBSIM_DUTCH_ROLL.0) < 0.05, "wn {wn}");
    assert!(rel(zeta, JSBSIM_DUTCH_ROLL.1) < 0.10, "zeta {zeta}");
}

#[test]
fn c172x_oracle_model_modes_are_reproduced() {
    // The numpy prototype in scripts/oracle_aero.py ("lon full", "lat full + drag in Y") gives
    // short period (6.116, 0.6746) and Dutch roll (2.1349, 0.1573); same equations, so 1e-3. With Ixz of
    // JSBSim's property sign (the textbook one is its negative) it gave (2.1321, 0.1535); the textbook sign
    // matches JSBSim's own linearization, (2.1344, 0.1574).
    let (wn, zeta) = short_period(jsbsim_assumptions());
    assert!(
        rel(wn, 6.116) < 1e-3 && rel(zeta, 0.6746) < 1e-3,
        "{wn} {zeta}"
    );
    let (wn, zeta) = dutch_roll(jsbsim_assumptions());
    assert!(
        rel(wn, 2.1349) < 1e-3 && rel(zeta, 0.1573) < 1e-3,
        "{wn} {zeta}"
    );
}

#[test]
fn transfer_function_poles_are_the_state_space_eigenvalues() {
    // Faddeev–LeVerrier denominator evaluated at each eigenvalue of A must vanish (relative 1e-9).
    let model = c172x_model(jsbsim_assumptions()).lateral().unwrap();
    let tf = model.transfer_function(3, 0).unwrap();
    for (re, im) in model.poles().unwrap() {
        let z = num_complex::Complex::new(re, im);
        let val = tf
            .den
            .iter()
            .fold(num_complex::Complex::new(0.0, 0.0), |acc, &c| acc * z + c);
        let scale = tf
            .den
            .iter()
            .enumerate()
            .map(|(k, c)| c.abs() * z.norm().powi((4 - k) as i32))
            .sum::<f64>();
        assert!(val.norm() < 1e-9 * scale, "den({z}) = {val}");
    }
}

#[test]
fn theta_over_elevator_has_relative_degree_two() {
    // δe acts on q̇; θ = ∫q, so the s³ numerator coefficient is exactly 0 and the s² one is M_δe + …
    let tf = c172x_model(Assumptions::paper())
        .transfer_function(TfOutput::THETA_ELEVATOR)
        .unwrap();
    assert_eq!(tf.num.len(), 4);
    assert_eq!(tf.num[0], 0.0);
    assert!(
        tf.num[1] < 0.0,
        "nose-down pitch for trailing-edge-down elevator: {:?}",
        tf.num
    );
}

#[test]
fn transfer_function_matches_direct_evaluation_of_state_space() {
    // G(jω) = e_θᵀ (jωI − A)⁻¹ B from a complex linear solve must equal num(jω)/den(jω), 1e-10 relative.
    use num_complex::Complex;
    let lin = c172x_model(jsbsim_assumptions()).longitudinal().unwrap();
    let tf = lin.transfer_function(3, 0).unwrap();
    let w = 1.7;
    let s = Complex::new(0.0, w);
    // Solve (sI − A) x = B by complex Gaussian elimination (4×4).
    let mut m: Vec<Vec<Complex<f64>>> = (0..4)
        .map(|i| {
            let mut row: Vec<Complex<f64>> =
                (0..4).map(|j| -Complex::new(lin.a[(i, j)], 0.0)).collect();
            row[i] += s;
            row.push(Complex::new(lin.b[(i, 0)], 0.0));
            row
        })
        .collect();
    for k in 0..4 {
        let p = (k..4)
            .max_by(|&x, &y| m[x][k].norm().total_cmp(&m[y][k].norm()))
            .unwrap();
        m.swap(k, p);
        for i in k + 1..4 {
            let f = m[i][k] / m[k][k];
            let pivot_row = m[k].clone();
            for (dst, src) in m[i].iter_mut().zip(&pivot_row).skip(k) {
                *dst -= f * src;
            }
        }
    }
    let mut x = [Complex::new(0.0, 0.0); 4];
    for i in (0..4).rev() {
        let mut acc = m[i][4];
        for j in i + 1..4 {
            acc -= m[i][j] * x[j];
        }
        x[i] = acc / m[i][i];
    }
    let poly = |c: &[f64]| c.iter().fold(Complex::new(0.0, 0.0), |acc, &v| acc * s + v);
    let g = poly(&tf.num) / poly(&tf.den);
    assert!((g - x[3]).norm() < 1e-10 * x[3].norm(), "{g} vs {}", x[3]);
}

/// Relative change of (short period, Dutch roll, phugoid) ωn and ζ against JSBSim's linearization.
fn modal_errors(m: &AeroModel) -> [f64; 6] {
    let lon = m.longitudinal().unwrap();
    let sp = lon.fastest_oscillation().unwrap().unwrap();
    let ph = lon
        .modes()
        .unwrap()
        .into_iter()
        .rev()
        .filter_map(Mode::oscillation)
        .next()
        .unwrap();
    let dr = m.lateral().unwrap().fastest_oscillation().unwrap().unwrap();
    [
        sp.0 / JSBSIM_SHORT_PERIOD.0 - 1.0,
        sp.1 / JSBSIM_SHORT_PERIOD.1 - 1.0,
        dr.0 / JSBSIM_DUTCH_ROLL.0 - 1.0,
        dr.1 / JSBSIM_DUTCH_ROLL.1 - 1.0,
        ph.0 / JSBSIM_PHUGOID.0 - 1.0,
        ph.1 / JSBSIM_PHUGOID.1 - 1.0,
    ]
}

/// JSBSim phugoid at the same trim (`scripts/oracle_aero.py`).
const JSBSIM_PHUGOID: (f64, f64) = (0.2081529, 0.1380020);

#[test]
fn c172x_cost_of_each_simplifying_assumption() {
    // What each of the paper's simplifications costs on the c172x modal check (documented on
    // `Assumptions`); numbers are relative errors against JSBSim's linearization.
    let base = jsbsim_assumptions();
    let all = modal_errors(&c172x_model(base));
    // Dropping C_Lq, C_Lα̇ from the lift equation: short-period ωn +1.4 % (from +0.1 %).
    let no_lift_rates = modal_errors(&c172x_model(Assumptions {
        lift_rate_terms: false,
        ..base
    }));
    assert!(
        (0.01..0.02).contains(&(no_lift_rates[0] - all[0])),
        "{no_lift_rates:?}"
    );
    // Treating JSBSim's wind-axis C_Yβ as stability-axis (no −C_D): Dutch-roll ζ 2.5 % lower.
    let cy_stab = modal_errors(&c172x_model(Assumptions {
        side_force_in_wind_axes: false,
        ..base
    }));
    assert!(
        (-0.035..-0.02).contains(&(cy_stab[3] - all[3])),
        "{cy_stab:?}"
    );
    // Body-axis lateral derivatives and inertia used as if stability-axis (α0 = 1.1°): Dutch-roll ζ −5.5 %.
    let mut body = c172x_model(base);
    body.mass = c172x_mass_body();
    body.derivatives = c172x_derivatives_body();
    let body = modal_errors(&body);
    assert!(body[3] < -0.04, "{body:?}");
    // Neglecting thrust derivatives (constant thrust) halves the phugoid damping; a constant-power
    // propeller model brings it to −19 %. The phugoid is outside the acceptance, but θ/δe's low-order
    // coefficients carry it, so C_D0 backed out of θ/δe absorbs the missing thrust term.
    assert!(all[5] < -0.4, "{all:?}");
    let power = modal_errors(&c172x_model(Assumptions {
        thrust: ThrustModel::ConstantPower,
        ..base
    }));
    assert!((-0.25..-0.1).contains(&power[5]), "{power:?}");
    // I_xz coupling (stability-axis I_xz = −46 kg·m²) is worth 3 % of Dutch-roll ζ here: with it the model's
    // ζ is within 0.03 % of JSBSim's linearization (with JSBSim's property sign for I_xz it was 2.5 % off).
    let no_ixz = modal_errors(&c172x_model(Assumptions {
        ixz_coupling: false,
        ..base
    }));
    assert!(all[3].abs() < 0.005, "{all:?}");
    assert!(
        (-0.04..-0.02).contains(&(no_ixz[3] - all[3])),
        "{no_ixz:?} {all:?}"
    );
}

#[test]
fn bad_mass_is_a_clear_error() {
    let mut model = c172x_model(Assumptions::paper());
    model.mass.mass_kg = 0.0;
    let err = model.longitudinal().unwrap_err().to_string();
    assert!(err.contains("mass_kg"), "{err}");
    model = c172x_model(Assumptions::paper());
    model.geometry.span_m = f64::NAN;
    assert!(model.lateral().unwrap_err().to_string().contains("span_m"));
}
