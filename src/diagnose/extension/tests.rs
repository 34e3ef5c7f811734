use super::*;

/// Every row builds on a target of its kind, with the stage, parameter and columns of the row.
#[test]
fn every_registry_row_builds_an_extension_with_its_metadata() {
    let coefficients: Vec<String> = DERIVATIVE_KNOBS
        .iter()
        .map(|(_, k)| k[0].to_string())
        .collect();
    for kind in &REGISTRY {
        let target = match kind.targets {
            Targets::Surfaces => "elevator",
            Targets::AllSurfaces => ALL_SURFACES,
            Targets::BodyAxes => "x",
            Targets::SensorColumns => "q_rad_s",
            Targets::Derivatives => "Cm_alpha",
            Targets::AddedTerms => "Cm_alpha2",
        };
        let e = make(kind.effect, target, &coefficients).unwrap();
        assert_eq!(
            (e.effect(), e.target(), e.stage()),
            (kind.effect, target, kind.stage)
        );
        let spec = e.params()[0];
        assert!(
            spec.min <= spec.null && spec.null <= spec.max,
            "{}",
            kind.effect
        );
        assert!(
            spec.fd_step > 0.0 && spec.resolution > 0.0,
            "{}",
            kind.effect
        );
        let columns = e.required_columns();
        match kind.targets {
            Targets::Surfaces => assert_eq!(columns, ["elevator_rad"]),
            Targets::SensorColumns => assert_eq!(columns, ["q_rad_s"]),
            Targets::BodyAxes => assert_eq!(columns, ["p_rad_s", "q_rad_s", "r_rad_s"]),
            _ => assert!(columns.is_empty()),
        }
    }
}

/// At its "no effect" value a signal-path or sensor effect leaves the sequence exactly as it was, and it
/// never touches another surface or column: exact equality, since these are the identity operations.
#[test]
fn a_null_parameter_and_another_target_change_nothing() {
    let dev: Vec<f64> = (0..50).map(|k| (0.3 * k as f64).sin() * 0.05).collect();
    for kind in REGISTRY.iter().filter(|k| k.targets == Targets::Surfaces) {
        let e = make(kind.effect, "elevator", &[]).unwrap();
        let null = [e.params()[0].null];
        let mut d = dev.clone();
        e.apply_input(&null, "elevator", &mut d, 0.02);
        assert_eq!(d, dev, "{} at its null value", kind.effect);
        let mut other = dev.clone();
        e.apply_input(&[0.7], "aileron", &mut other, 0.02);
        assert_eq!(other, dev, "{} on another surface", kind.effect);
    }
    for kind in REGISTRY
        .iter()
        .filter(|k| k.targets == Targets::SensorColumns)
    {
        let e = make(kind.effect, "q_rad_s", &[]).unwrap();
        let mut rec = FlightRecord::new((0..3).map(|k| k as f64 * 0.02).collect());
        rec.columns = vec![
            ("q_rad_s".into(), vec![0.1, -0.2, 0.3]),
            ("p_rad_s".into(), vec![1.0; 3]),
        ];
        let before = rec.columns.clone();
        e.apply_output(&[e.params()[0].null], &mut rec);
        assert_eq!(rec.columns, before, "{} at its null value", kind.effect);
        e.apply_output(&[2.0], &mut rec);
        assert_ne!(
            rec.columns[0], before[0],
            "{} on its own column",
            kind.effect
        );
        assert_eq!(
            rec.columns[1], before[1],
            "{} on another column",
            kind.effect
        );
    }
}

/// A square term refines the linear derivative of the same name; nothing else refines anything.
#[test]
fn only_a_square_term_refines_a_linear_derivative() {
    let e = make("aero_nonlinearity", "CL_alpha2", &[]).unwrap();
    assert_eq!(
        e.refines(),
        Some(("aero_derivative", "CL_alpha".to_string()))
    );
    let d = make("sensor_bias", "q_rad_s", &[]).unwrap();
    assert_eq!(d.refines(), None);
}

/// A derivative is found under the name the aircraft gives its coefficient function: the 737's lift is
/// `CLalpha` and its zero-lift drag `CD0`, the c310's `CmDe` and `Clbeta`; an aircraft with none of the names
/// gets the derivative skipped with the names looked for, and the c172x keeps its own.
#[test]
fn a_derivative_is_found_under_each_aircraft_s_coefficient_name() {
    let names = |v: &[&str]| v.iter().map(|n| n.to_string()).collect::<Vec<_>>();
    let b737 = names(&["CD0", "CLalpha", "Cmalpha", "Cmde", "Clb", "Cnb"]);
    let c310 = names(&["CDo", "CLalpha", "CmDe", "Clbeta", "Cnbeta", "CnDr"]);
    let c172x = names(&["CLwbh", "CLalpha", "CDo"]);
    assert_eq!(knob_of("CL_alpha", &b737), Ok("CLalpha".into()));
    assert_eq!(knob_of("CD_0", &b737), Ok("CD0".into()));
    assert_eq!(knob_of("Cm_de", &c310), Ok("CmDe".into()));
    assert_eq!(knob_of("Cl_beta", &c310), Ok("Clbeta".into()));
    assert_eq!(knob_of("Cn_dr", &c310), Ok("CnDr".into()));
    assert_eq!(knob_of("CL_alpha", &c172x), Ok("CLwbh".into()));
    assert_eq!(knob_of("Cm_0", &b737), Err("Cmo, Cm0".into()));
    let rec = FlightRecord {
        time_s: vec![0.0, 0.1],
        columns: Vec::new(),
        metadata: Vec::new(),
    };
    let (usable, skipped) = catalogue(&rec, &b737, &[]);
    assert!(usable
        .iter()
        .any(|e| e.effect() == "aero_derivative" && e.target() == "CL_alpha"));
    assert!(skipped
        .iter()
        .any(|(e, t, why)| e == "aero_derivative" && t == "Cm_0" && why.contains("Cmo, Cm0")));
    let e = make("aero_derivative", "Cm_q", &b737)
        .err()
        .expect("no Cmq in the list");
    assert!(e.to_string().contains("looked for Cmq"), "{e}");
}

/// `time_skew` delays every surface by the same time, exactly as `input_delay` delays its one surface, and it is
/// built only on its one target.
#[test]
fn a_time_skew_delays_every_surface_alike() {
    let dev: Vec<f64> = (0..50).map(|k| (0.3 * k as f64).sin() * 0.05).collect();
    let skew = make(TIME_SKEW, ALL_SURFACES, &[]).unwrap();
    for surface in ["elevator", "aileron", "rudder"] {
        let delay = make("input_delay", surface, &[]).unwrap();
        let (mut by_skew, mut by_delay) = (dev.clone(), dev.clone());
        skew.apply_input(&[0.05], surface, &mut by_skew, 0.02);
        delay.apply_input(&[0.05], surface, &mut by_delay, 0.02);
        assert_eq!(by_skew, by_delay, "{surface}");
        assert_ne!(by_skew, dev, "{surface}");
    }
    assert_eq!(skew.excited_count(), 2);
    // A negative skew reads ahead: 1.5 samples ahead is the mean of the samples 1 and 2 ahead, and the last
    // sample is held past the record's end. Only the skew may be negative; a surface's own delay may not.
    let mut ahead = dev.clone();
    skew.apply_input(&[-0.03], "elevator", &mut ahead, 0.02);
    for k in 0..47 {
        assert!(
            (ahead[k] - 0.5 * (dev[k + 1] + dev[k + 2])).abs() < 1e-15,
            "sample {k}"
        );
    }
    assert_eq!(ahead[48..], [dev[49], dev[49]]);
    assert!(skew.params()[0].min < 0.0);
    assert_eq!(
        make("input_delay", "elevator", &[]).unwrap().params()[0].min,
        0.0
    );
    let e = make(TIME_SKEW, "elevator", &[])
        .err()
        .expect("one target only");
    assert!(e.to_string().contains("'surfaces'"), "{e}");
}

/// The accelerometers 1 m ahead of the reading point, in a steady pull-up (q̇ = 0.5 rad/s², q = 0.2 rad/s): a_x
/// reads −q² x more and a_z −q̇ x more (ω̇ × r + ω × (ω × r) with r = (1, 0, 0)); at its null value nothing
/// changes, and a record without accelerometers is left as it was.
#[test]
fn an_accelerometer_ahead_of_the_reading_point_reads_the_pitch_acceleration() {
    let n = 11;
    let dt = 0.02;
    let mut rec = FlightRecord::new((0..n).map(|k| k as f64 * dt).collect());
    let q: Vec<f64> = (0..n).map(|k| 0.2 + 0.5 * (k as f64 * dt - 0.1)).collect();
    rec.columns = vec![
        ("p_rad_s".into(), vec![0.0; n]),
        ("q_rad_s".into(), q.clone()),
        ("r_rad_s".into(), vec![0.0; n]),
        ("ax_m_s2".into(), vec![0.0; n]),
        ("ay_m_s2".into(), vec![0.0; n]),
        ("az_m_s2".into(), vec![-9.8; n]),
    ];
    let e = make(ACCELEROMETER_POSITION, "x", &[]).unwrap();
    let before = rec.columns.clone();
    e.apply_output(&[0.0], &mut rec);
    assert_eq!(rec.columns, before);
    e.apply_output(&[1.0], &mut rec);
    let col = |name: &str| rec.column(name).unwrap().to_vec();
    let mid = n / 2;
    assert!(
        (col("ax_m_s2")[mid] + q[mid] * q[mid]).abs() < 1e-12,
        "{:?}",
        col("ax_m_s2")
    );
    assert!(
        (col("az_m_s2")[mid] + 9.8 + 0.5).abs() < 1e-9,
        "{:?}",
        col("az_m_s2")
    );
    assert_eq!(col("ay_m_s2"), vec![0.0; n]);
    assert!(make(ACCELEROMETER_POSITION, "w", &[]).is_err());
}

/// A record without accelerometers cannot place them: the position is skipped for the columns it lacks (it was
/// skipped for a Cramér–Rao σ of ∞), and one accelerometer is enough to keep it.
#[test]
fn the_accelerometer_position_needs_an_accelerometer() {
    let with = |names: &[&str]| FlightRecord {
        time_s: vec![0.0, 0.1],
        columns: names
            .iter()
            .map(|n| (n.to_string(), vec![0.0; 2]))
            .collect(),
        metadata: Vec::new(),
    };
    let gyros = ["p_rad_s", "q_rad_s", "r_rad_s"];
    let (usable, skipped) = catalogue(&with(&gyros), &[], &[]);
    assert!(usable.iter().all(|e| e.effect() != ACCELEROMETER_POSITION));
    let reasons: Vec<&str> = skipped
        .iter()
        .filter(|(e, _, _)| e == ACCELEROMETER_POSITION)
        .map(|(_, _, why)| why.as_str())
        .collect();
    assert_eq!(reasons.len(), 3, "{skipped:?}");
    assert!(reasons
        .iter()
        .all(|w| *w == "the data have none of the columns ax_m_s2, ay_m_s2, az_m_s2"));
    let (usable, _) = catalogue(&with(&[&gyros[..], &["az_m_s2"]].concat()), &[], &[]);
    assert_eq!(
        usable
            .iter()
            .filter(|e| e.effect() == ACCELEROMETER_POSITION)
            .count(),
        3
    );
}
