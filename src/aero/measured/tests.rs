//! Unit tests of the measured-data derivatives: sensors moved to the CG, axis detection.

use super::*;

#[test]
fn isa_density_matches_the_standard_table() {
    // ICAO standard atmosphere: 1.2250 at 0 m, 1.0066 at 2000 m, 0.7364 at 5000 m (4 digits).
    for (h, rho) in [(0.0, 1.2250), (2000.0, 1.0066), (5000.0, 0.7364)] {
        assert!((standard_density_kg_m3(h) - rho).abs() < 6e-4, "{h}");
    }
}

#[test]
fn sensors_ahead_of_the_cg_are_moved_back_exactly_for_steady_rates() {
    // Steady pull-up q = 0.1 rad/s at 50 m/s; vane 3 m ahead reads α − q x/V; IMU 1 m ahead and 0.5 m
    // below reads a_z − q² z (no q̇), a_x − q² x.
    let n = 50;
    let t: Vec<f64> = (0..n).map(|i| i as f64 * 0.02).collect();
    let mut rec = data::FlightRecord::new(t);
    let (q, v, x, z) = (0.1, 50.0, 1.0, 0.5);
    rec.push_column("q_rad_s", vec![q; n]);
    rec.push_column("airspeed_m_s", vec![v; n]);
    rec.push_column("alpha_rad", vec![0.05 - q * 3.0 / v; n]);
    rec.push_column("ax_m_s2", vec![1.0 - q * q * x; n]);
    rec.push_column("az_m_s2", vec![-9.0 - q * q * z; n]);
    let sensors = SensorPositions {
        imu_m: [x, 0.0, z],
        alpha_vane_m: [3.0, 0.0, 0.0],
        beta_vane_m: [0.0; 3],
    };
    let cg = moved_to_cg(&rec, &sensors).unwrap();
    let at = |c: &str| cg.column(c).unwrap()[25];
    assert!((at("alpha_rad") - 0.05).abs() < 1e-12);
    assert!((at("ax_m_s2") - 1.0).abs() < 1e-9);
    assert!((at("az_m_s2") + 9.0).abs() < 1e-9);
}

#[test]
fn a_still_surface_with_noise_does_not_count_as_excitation() {
    let quiet: Vec<f64> = (0..500)
        .map(|i| 0.02 + 1e-4 * ((i * 7919) % 13) as f64)
        .collect();
    assert!(!surface_moves(&quiet));
    let doublet: Vec<f64> = (0..500)
        .map(|i| {
            if (100..150).contains(&i) {
                0.02 + 0.03
            } else {
                0.02
            }
        })
        .collect();
    assert!(surface_moves(&doublet));
}

/// A short, slowly logged pulse train: five steps of 3.2° in 500 samples (a 3-2-1-1 of ±1.6° at 25 Hz,
/// the elevator record of a transport) moves the surface. Counted as noise, its steps once made it 0.2°
/// of "noise" and the record read as still; a noise of 0.2° itself does not move it.
#[test]
fn a_slowly_logged_pulse_train_is_excitation_and_its_steps_are_not_noise() {
    let step = 1.6f64.to_radians();
    let noise = |i: usize| 0.01f64.to_radians() * (((i * 7919) % 101) as f64 / 50.0 - 1.0);
    let pulses: Vec<f64> = (0..500)
        .map(|i| {
            let t = i as f64 / 25.0;
            let u = match t {
                t if (2.0..4.25).contains(&t) => step,
                t if (4.25..5.75).contains(&t) => -step,
                t if (5.75..6.5).contains(&t) => step,
                t if (6.5..7.25).contains(&t) => -step,
                _ => 0.0,
            };
            0.0036 + u + noise(i)
        })
        .collect();
    assert!(surface_moves(&pulses));
    let noisy: Vec<f64> = (0..500).map(|i| 20.0 * noise(i)).collect();
    assert!(!surface_moves(&noisy));
}

/// The primed derivatives solve the coupled moment equations: I_xx ṗ − I_xz ṙ = I_xx L and
/// I_zz ṙ − I_xz ṗ = I_zz N with ṗ = L′, ṙ = N′ (per unit of each variable), to rounding.
#[test]
fn primed_roll_and_yaw_derivatives_fold_in_the_product_of_inertia() {
    let airframe = Airframe::from_toml_str(
        "name = \"t\"\nmass_kg = 17631.0\ninertia_kg_m2 = { ixx = 133367.0, iyy = 252687.0, izz = 359593.0, \
         ixz = 11442.0 }\nwing = { area_m2 = 64.0, span_m = 21.5, mac_m = 3.159 }\n",
        "t.toml",
    )
    .unwrap();
    let cond = ReferenceCondition {
        airspeed_m_s: 129.0,
        density_kg_m3: 0.705,
        alpha_rad: 0.05,
        theta_rad: 0.05,
        elevator_rad: 0.0,
        thrust_n: 0.0,
    };
    let est: BTreeMap<String, Estimate> = [
        ("Cl_da", 0.096, 0.001),
        ("Cn_da", 0.005, 0.002),
        ("Cl_p", -0.385, 0.004),
    ]
    .into_iter()
    .map(|(n, v, s)| {
        (
            n.to_string(),
            Estimate {
                value: v,
                std_error: s,
            },
        )
    })
    .collect();
    let d = dimensional(&est, &airframe, &cond);
    let i = airframe.inertia_kg_m2;
    for x in ["da", "p"] {
        let at = |n: &str| d.get(&format!("{n}_{x}")).map_or(0.0, |e| e.value);
        let (l, n, lp, np) = (at("L"), at("N"), at("Lprime"), at("Nprime"));
        assert!(
            (i.ixx * lp - i.ixz * np - i.ixx * l).abs() < 1e-9 * (i.ixx * l).abs().max(1.0),
            "{x}"
        );
        assert!(
            (i.izz * np - i.ixz * lp - i.izz * n).abs() < 1e-9 * (i.izz * l).abs().max(1.0),
            "{x}"
        );
    }
    // N′_δa: the aileron's rolling moment reaches the yaw through I_xz (here three times N_δa).
    assert!(d["Nprime_da"].value > 2.5 * d["N_da"].value);
    assert!(d["Nprime_da"].std_error >= d["N_da"].std_error);
}
