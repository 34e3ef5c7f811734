//! A configuration for any JSBSim model flightid has none for, derived from the model itself.
//!
//! An aircraft configuration (`aircraft/NAME.toml`) says which properties the aerodynamics read as each
//! surface's deflection, the surfaces' limits, the engines, the gear and a default trim point. For a model that
//! ships with JSBSim and has no configuration, the bridge loads it and reports the `fcs/…` properties its
//! aerodynamics read and how each moves when the pilot's elevator, aileron and rudder commands are held at
//! −1, −¼, 0, ¼ and 1 (`airframe`). A read belongs to the surface whose command moves it; it is the signed
//! deflection when it moves with the command's sign, the magnitude when it rises either way. Measuring the
//! flight control system instead of reading its XML takes actuators, gains and clips as JSBSim flies them. A
//! model whose aerodynamics read a surface in other units (`…-norm`, `…-deg`, a command), through mixed
//! surfaces (elevons, flaperons) or as left and right surfaces moving apart is refused, naming the property:
//! it wants a configuration written by hand.
//!
//! The default trim point is level flight at the first lift coefficient of [`TRIM_LIFT_COEFFICIENTS`] at which
//! JSBSim's trim succeeds, at 5 000 ft for a wing loading below [`HIGH_WING_LOADING_PSF`] and 15 000 ft above.
//! The configuration is written to the cache directory (`aircraft/NAME.toml`), where it can be read, copied
//! into `FLIGHTID_AIRCRAFT_DIR` and changed.

use super::protocol::ModelFacts;
use super::{SimError, FT_TO_M, KTS_TO_M_S};
use crate::aircraft::{self, AircraftConfig, AircraftError, Drive, SurfaceConfig, TrimDefaults};
use std::collections::{BTreeMap, HashMap};
use std::sync::Mutex;

/// The pilot commands whose responses the bridge measures, with the surface each drives.
const SURFACES: [(&str, &str); 3] = [
    ("elevator", "fcs/elevator-cmd-norm"),
    ("aileron", "fcs/aileron-cmd-norm"),
    ("rudder", "fcs/rudder-cmd-norm"),
];

/// Lift coefficients of the default trim point, in the order they are tried: the first at which JSBSim's trim
/// finds level flight is taken. 0.4 is well below the stall of any wing and above the drag bucket; a model
/// whose engine cannot hold it (JSBSim's pa28 trims at 90 kts but not at 105) trims at another.
pub const TRIM_LIFT_COEFFICIENTS: [f64; 6] = [0.4, 0.5, 0.3, 0.6, 0.7, 0.8];

/// Wing loading above which the default trim point is at 15 000 ft instead of 5 000 ft, lbf/ft² (light aircraft
/// 10–30, transports 80–150).
pub const HIGH_WING_LOADING_PSF: f64 = 40.0;

/// Least change of a property over the command levels for it to count as moved by the command.
const MOVES: f64 = 1e-4;

/// Share of the largest command's movement that another command may move a property by without mixing the
/// surfaces (an FCS drifting while it settles, a feedback loop).
const CROSS_TALK: f64 = 0.1;

/// Configurations derived in this process, by name.
static DERIVED: Mutex<Option<HashMap<String, AircraftConfig>>> = Mutex::new(None);

/// The configuration of `name`: the repository's or the user's (`aircraft::load`), else one derived from the
/// JSBSim model of that name (module doc). A name that is neither is [`AircraftError::Unknown`]; a model whose
/// configuration cannot be derived is [`AircraftError::NotDerived`], naming why.
pub fn aircraft_config(name: &str) -> Result<AircraftConfig, AircraftError> {
    let known = match aircraft::load(name) {
        Err(AircraftError::Unknown { known, .. }) if !name.ends_with(".toml") => known,
        other => return other,
    };
    let mut cache = DERIVED.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(cfg) = cache.get_or_insert_with(HashMap::new).get(name) {
        return Ok(cfg.clone());
    }
    let cfg = derive(name).map_err(|e| match e {
        Derivation::NoModel(why) => AircraftError::Unknown {
            name: name.to_string(),
            known: format!("{known}; nor is it a JSBSim model: {why}"),
        },
        Derivation::Refused(why) => AircraftError::NotDerived {
            name: name.to_string(),
            why,
        },
    })?;
    let written = write_to_cache(&cfg);
    eprintln!(
        "flightid: no configuration named '{name}': derived from JSBSim's model ({}; default trim {:.0} ft, \
         {:.0} kts){}",
        surfaces_summary(&cfg),
        cfg.trim.altitude_ft,
        cfg.trim.speed_kts,
        written.map_or(String::new(), |p| format!(
            "; written to {} (copy it into FLIGHTID_AIRCRAFT_DIR to change it)",
            p.display()
        ))
    );
    cache
        .get_or_insert_with(HashMap::new)
        .insert(name.to_string(), cfg.clone());
    Ok(cfg)
}

/// Why a configuration was not derived.
enum Derivation {
    /// JSBSim has no model of that name (the bridge's message, with the models it has).
    NoModel(String),
    /// The model exists, but its configuration cannot be derived (or the bridge failed).
    Refused(String),
}

/// Loads the model in a bridge of its own and derives its configuration.
fn derive(name: &str) -> Result<AircraftConfig, Derivation> {
    let reply = super::aero_truth::model_airframe(name).map_err(|e| match e {
        SimError::UnknownModel(why) => Derivation::NoModel(why),
        other => Derivation::Refused(format!("loading it in JSBSim failed: {other}")),
    })?;
    let value = |k: &str| reply.values.get(k).copied().unwrap_or(f64::NAN);
    let weight_lbf = value("inertia/mass-slugs") * crate::data::G0_M_S2 / FT_TO_M;
    let candidates =
        trim_candidates(weight_lbf / value("metrics/Sw-sqft")).map_err(Derivation::Refused)?;
    let facts = &reply.model;
    let mut cfg = AircraftConfig {
        name: name.to_string(),
        model: name.to_string(),
        description: format!(
            "{} (JSBSim {name}; configuration derived from the model)",
            if facts.name.is_empty() {
                name
            } else {
                &facts.name
            }
        ),
        drive: Drive::Surface,
        engine_running: facts.engines > 0,
        gear_up: facts.retractable_gear,
        engines: facts.engines.max(1),
        trim: candidates[0].clone(),
        surfaces: surfaces(facts).map_err(Derivation::Refused)?,
        properties: BTreeMap::new(),
    };
    aircraft::validate(&cfg).map_err(|e| Derivation::Refused(e.to_string()))?;
    match first_trimmable(&cfg, &candidates) {
        Some(t) => cfg.trim = t,
        None => eprintln!(
            "flightid: JSBSim's trim finds no level flight of the {name} at {:.0} ft with a lift coefficient of \
             0.3 to 0.8; give --altitude-ft and --speed-kts",
            cfg.trim.altitude_ft
        ),
    }
    Ok(cfg)
}

/// Level flight at each of [`TRIM_LIFT_COEFFICIENTS`] for a wing loading of `psf` lbf/ft²:
/// V = √(2 W/S / (ρ C_L)), rounded to 5 kts.
fn trim_candidates(psf: f64) -> Result<Vec<TrimDefaults>, String> {
    if !(psf.is_finite() && psf > 0.0) {
        return Err(format!("its wing loading is not positive ({psf} lbf/ft²)"));
    }
    let altitude_ft = if psf < HIGH_WING_LOADING_PSF {
        5000.0
    } else {
        15000.0
    };
    let rho = super::atmosphere::density_kg_m3(altitude_ft * FT_TO_M, 0.0).unwrap_or(f64::NAN);
    let loading_pa = psf * PSF_TO_PA;
    Ok(TRIM_LIFT_COEFFICIENTS
        .iter()
        .map(|cl| {
            let speed_m_s = (2.0 * loading_pa / (rho * cl)).sqrt();
            TrimDefaults {
                altitude_ft,
                speed_kts: (speed_m_s / KTS_TO_M_S / 5.0).round() * 5.0,
            }
        })
        .collect())
}

/// The first of `candidates` at which the aircraft of `cfg` trims in JSBSim; `None` when it trims at none of them
/// (or JSBSim does not start).
fn first_trimmable(cfg: &AircraftConfig, candidates: &[TrimDefaults]) -> Option<TrimDefaults> {
    use super::Simulator;
    let mut sim = super::JsbsimSim::start(cfg, TRIM_SEARCH_RATE_HZ).ok()?;
    candidates
        .iter()
        .find(|c| {
            sim.trim(&super::TrimPoint::level(c.altitude_ft, c.speed_kts))
                .is_ok()
        })
        .cloned()
}

/// Simulation rate of the trim search, Hz (a trim does not depend on it).
const TRIM_SEARCH_RATE_HZ: f64 = 120.0;

/// lbf/ft² in Pa.
const PSF_TO_PA: f64 = 47.880_258_98;

/// How one aero read moves with the command that owns it.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Shape {
    /// With the command's sign: the deflection.
    Signed,
    /// Up either way: the deflection's magnitude.
    Magnitude,
}

/// The surfaces from the bridge's measurements (module doc).
fn surfaces(facts: &ModelFacts) -> Result<BTreeMap<String, SurfaceConfig>, String> {
    let level = |x: f64| facts.levels.iter().position(|&l| l == x);
    let (Some(lo), Some(quarter_lo), Some(zero), Some(quarter_hi), Some(hi)) = (
        level(-1.0),
        level(-0.25),
        level(0.0),
        level(0.25),
        level(1.0),
    ) else {
        return Err(format!(
            "the bridge measured the commands at {:?}, not at −1, −0.25, 0, 0.25 and 1",
            facts.levels
        ));
    };
    let at = |surface: &str, k: usize, p: &str| {
        facts
            .responses
            .get(surface)
            .and_then(|v| v.get(k))
            .and_then(|v| v.get(p))
            .copied()
            .unwrap_or(f64::NAN)
    };
    let span = |surface: &str, p: &str| {
        let v: Vec<f64> = (0..facts.levels.len()).map(|k| at(surface, k, p)).collect();
        v.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            - v.iter().copied().fold(f64::INFINITY, f64::min)
    };
    let mut reads: BTreeMap<&str, Vec<(&str, Shape)>> = BTreeMap::new();
    for p in &facts.aero_reads {
        for (s, _) in SURFACES {
            if let Some(k) = (0..facts.levels.len()).find(|&k| !at(s, k, p).is_finite()) {
                return Err(format!(
                    "JSBSim gives no finite value of {p}, which its aerodynamics read, with the {s} command at {}",
                    facts.levels[k]
                ));
            }
        }
        let spans: Vec<f64> = SURFACES.iter().map(|(s, _)| span(s, p)).collect();
        let largest = spans.iter().copied().fold(0.0, f64::max);
        if largest <= MOVES {
            continue; // a flap, a speed brake: no pilot command of the three moves it
        }
        let owners: Vec<&str> = SURFACES
            .iter()
            .zip(&spans)
            .filter(|(_, &s)| s > CROSS_TALK * largest)
            .map(|((s, _), _)| *s)
            .collect();
        if owners.len() > 1 {
            return Err(format!(
                "its aerodynamics read {p}, which the {} commands all move (mixed surfaces)",
                owners.join(" and ")
            ));
        }
        let s = owners[0];
        if p.ends_with("-norm") || p.ends_with("-deg") || p.contains("cmd") {
            return Err(format!(
                "its aerodynamics read the {s} as {p}, not as a deflection in radians, which flightid \
                 cannot drive"
            ));
        }
        let (down, rest, up) = (at(s, lo, p), at(s, zero, p), at(s, hi, p));
        let shape = if (up - rest) * (down - rest) < 0.0 {
            Shape::Signed
        } else if up > rest && down > rest {
            Shape::Magnitude
        } else {
            return Err(format!(
                "its aerodynamics read {p}, which the {s} command moves neither with its sign nor as a \
                 magnitude ({down:.4}, {rest:.4}, {up:.4} rad at −1, 0, 1)"
            ));
        };
        reads.entry(s).or_default().push((p, shape));
    }
    let mut out = BTreeMap::new();
    for (s, command) in SURFACES {
        let all = reads.get(s).cloned().unwrap_or_default();
        let signed: Vec<&str> = all
            .iter()
            .filter(|(_, k)| *k == Shape::Signed)
            .map(|(p, _)| *p)
            .collect();
        let Some(&first) = signed.first() else {
            return Err(format!(
                "its aerodynamics read no property that the {s} command ({command}) moves"
            ));
        };
        let slope = |p: &str| (at(s, quarter_hi, p) - at(s, quarter_lo, p)) / 0.5;
        if let Some(apart) = signed.iter().find(|p| {
            let (a, b) = (slope(first), slope(p));
            a * b <= 0.0 || (a - b).abs() > 0.05 * a.abs()
        }) {
            return Err(format!(
                "its aerodynamics read the {s} as {first} and {apart}, which do not move together (left and \
                 right surfaces moving apart)"
            ));
        }
        let (down, up) = (at(s, lo, first), at(s, hi, first));
        out.insert(
            s.to_string(),
            SurfaceConfig {
                command: command.to_string(),
                aero_reads: signed.iter().map(|p| p.to_string()).collect(),
                aero_reads_abs: all
                    .iter()
                    .filter(|(_, k)| *k == Shape::Magnitude)
                    .map(|(p, _)| p.to_string())
                    .collect(),
                min_rad: down.min(up),
                max_rad: down.max(up),
                rad_per_norm: slope(first),
            },
        );
    }
    Ok(out)
}

/// "elevator fcs/elevator-pos-rad, aileron …" for the note.
fn surfaces_summary(cfg: &AircraftConfig) -> String {
    cfg.surfaces
        .iter()
        .map(|(s, c)| format!("{s} {}", c.aero_reads.join(" + ")))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Writes the configuration to the cache directory's `aircraft/NAME.toml` (through a temporary file, so a reader
/// never sees half of it); `None` where it cannot be written (the configuration is used all the same).
fn write_to_cache(cfg: &AircraftConfig) -> Option<std::path::PathBuf> {
    let dir = super::env::cache_dir().join("aircraft");
    std::fs::create_dir_all(&dir).ok()?;
    let path = dir.join(format!("{}.toml", cfg.name));
    let text = format!(
        "# Derived by flightid from JSBSim's model '{}' (docs/airframe.md, \"Any JSBSim model\").\n{}",
        cfg.model,
        toml::to_string(cfg).ok()?
    );
    let tmp = dir.join(format!(".{}.toml.{}", cfg.name, std::process::id()));
    std::fs::write(&tmp, text).ok()?;
    std::fs::rename(&tmp, &path).ok()?;
    Some(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Facts of a model whose aero reads `reads`, each moving with the commands as `moves` says: (read, surface,
    /// value at command −1, 0, 1; linear between).
    fn facts(moves: &[(&str, &str, [f64; 3])]) -> ModelFacts {
        let levels = vec![-1.0, -0.25, 0.0, 0.25, 1.0];
        let mut responses: BTreeMap<String, Vec<BTreeMap<String, f64>>> = BTreeMap::new();
        for (s, _) in SURFACES {
            let v = levels
                .iter()
                .map(|&l: &f64| {
                    moves
                        .iter()
                        .map(|(p, owner, [down, rest, up])| {
                            let x = if *owner != s {
                                *rest
                            } else if l < 0.0 {
                                rest + (rest - down) * l
                            } else {
                                rest + (up - rest) * l
                            };
                            (p.to_string(), x)
                        })
                        .collect()
                })
                .collect();
            responses.insert(s.to_string(), v);
        }
        ModelFacts {
            name: "test".into(),
            aero_reads: moves.iter().map(|(p, _, _)| p.to_string()).collect(),
            engines: 1,
            retractable_gear: false,
            levels,
            responses,
        }
    }

    const CONVENTIONAL: [(&str, &str, [f64; 3]); 5] = [
        ("fcs/elevator-pos-rad", "elevator", [-0.49, 0.0, 0.40]),
        ("fcs/mag-elevator-pos-rad", "elevator", [0.49, 0.0, 0.40]),
        ("fcs/left-aileron-pos-rad", "aileron", [-0.35, 0.0, 0.26]),
        ("fcs/rudder-pos-rad", "rudder", [-0.28, 0.0, 0.28]),
        ("fcs/flap-pos-deg", "none", [0.0, 0.0, 0.0]),
    ];

    #[test]
    fn each_read_goes_to_the_surface_whose_command_moves_it() {
        let s = surfaces(&facts(&CONVENTIONAL)).expect("derived");
        let e = &s["elevator"];
        assert_eq!(e.aero_reads, vec!["fcs/elevator-pos-rad"]);
        assert_eq!(e.aero_reads_abs, vec!["fcs/mag-elevator-pos-rad"]);
        assert_eq!((e.min_rad, e.max_rad), (-0.49, 0.40));
        assert!((e.rad_per_norm - 0.445).abs() < 1e-9, "{}", e.rad_per_norm);
        assert_eq!(s["aileron"].aero_reads, vec!["fcs/left-aileron-pos-rad"]);
        assert_eq!(s["rudder"].aero_reads, vec!["fcs/rudder-pos-rad"]);
    }

    #[test]
    fn reads_flightid_cannot_drive_are_refused_by_name() {
        let mut norm = CONVENTIONAL.to_vec();
        norm.push(("fcs/elevator-pos-norm", "elevator", [-1.0, 0.0, 1.0]));
        let e = surfaces(&facts(&norm)).expect_err("a normalised read");
        assert!(e.contains("fcs/elevator-pos-norm"), "{e}");
        let mut apart = CONVENTIONAL.to_vec();
        apart.push(("fcs/right-aileron-pos-rad", "aileron", [0.26, 0.0, -0.35]));
        let e = surfaces(&facts(&apart)).expect_err("left and right apart");
        assert!(e.contains("right-aileron") && e.contains("apart"), "{e}");
        let without_rudder: Vec<_> = CONVENTIONAL
            .iter()
            .copied()
            .filter(|m| m.1 != "rudder")
            .collect();
        let e = surfaces(&facts(&without_rudder)).expect_err("no rudder read");
        assert!(e.contains("rudder"), "{e}");
    }

    #[test]
    fn the_default_trim_flies_at_the_lift_coefficient() {
        // c172x: 2 480 lbf on 174 ft² at 5 000 ft (ρ 1.0555 kg/m³): 14.25 psf = 682 Pa; at C_L 0.4
        // V = 56.9 m/s = 110.5 kts, at 0.8 40.2 m/s = 78.2 kts
        let t = trim_candidates(2480.0 / 174.0).expect("a trim");
        assert_eq!((t[0].altitude_ft, t[0].speed_kts), (5000.0, 110.0));
        assert_eq!(t[5].speed_kts, 80.0);
        let jet = trim_candidates(107_000.0 / 1171.0).expect("a trim");
        assert_eq!(jet[0].altitude_ft, 15000.0);
        assert!(trim_candidates(f64::NAN).is_err());
    }
}
