//! Column and unit mapping: a foreign CSV's column names and units onto the flight-data schema.
//!
//! A map file (`--columns MAP.toml` on every command that reads a CSV) names, for each foreign
//! column, the schema column it becomes and the unit it is recorded in:
//!
//! ```toml
//! [columns]
//! TIME = { to = "time_s" }                          # no unit: already the schema's unit
//! DELV = { to = "elevator_rad", unit = "deg", scale = -1.0 }   # scale: sign or gain after the unit
//! VTAS = { to = "airspeed_m_s", unit = "kts" }
//! ```
//!
//! A schema column can also be a weighted sum of foreign columns, for a log that records what the schema
//! has as one column in several (the left and right ailerons of a transport aircraft):
//!
//! ```toml
//! [derived]
//! aileron_rad = { from = { DAL = 0.5, DAR = -0.5 }, unit = "deg" }   # ½(left − right), then deg → rad
//! ```
//!
//! A log whose airspeed is equivalent (or calibrated, or indicated) airspeed, as most autopilots and air-data
//! computers record it, says so with `airspeed = "equivalent"` above the tables: the reader makes it true airspeed,
//! the schema's, with the logged `density_kg_m3` where there is one and the standard atmosphere at `altitude_m`
//! otherwise, V_true = V_eq √(ρ₀/ρ). Read as true, such a record at 2 800 ft replays 4 % slow, and the trim's
//! α and elevator differ from the model's as a `Cm_0` error would (one was named, ×2.09, by `diagnose`).
//!
//! Units: rad, deg, m, ft, m/s, ft/s, kts, g, m/s2, deg/s, rad/s, deg/s2, rad/s2, N, lbf, Pa, psf, kg/m3,
//! slug/ft3, s, ms,
//! percent, and the spellings of autopilot logs: us, cdeg, mrad/s, mg, cm, cm/s, kt, km/h, mph, hPa, mbar.
//! A unit must measure what its target column measures (`deg` cannot go to `airspeed_m_s`).
//! The reader renames and converts while reading, so every command sees SI columns.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use super::error::DataError;
use super::record::{FlightRecord, G0_M_S2, SCHEMA_COLUMNS};

/// What a column measures; a unit converts only into columns of its own dimension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Dimension {
    /// Seconds.
    Time,
    /// Radians.
    Angle,
    /// Radians per second.
    AngularRate,
    /// Metres.
    Length,
    /// Metres per second.
    Speed,
    /// Metres per second squared (specific force).
    Acceleration,
    /// Newtons.
    Force,
    /// Pascals.
    Pressure,
    /// Kilograms per cubic metre.
    Density,
    /// Radians per second squared.
    AngularAcceleration,
    /// A fraction (throttle 0..1).
    Fraction,
}

impl Dimension {
    /// The dimension of a schema column, from its unit suffix.
    pub fn of_column(column: &str) -> Option<Dimension> {
        if !SCHEMA_COLUMNS.contains(&column) {
            return None;
        }
        Some(match column {
            "time_s" => Dimension::Time,
            "throttle" => Dimension::Fraction,
            "airspeed_m_s" => Dimension::Speed,
            "altitude_m" => Dimension::Length,
            "thrust_n" => Dimension::Force,
            "qbar_pa" => Dimension::Pressure,
            "density_kg_m3" => Dimension::Density,
            c if c.ends_with("_rad_s") => Dimension::AngularRate,
            c if c.ends_with("_rad_s2") => Dimension::AngularAcceleration,
            c if c.ends_with("_rad") => Dimension::Angle,
            c if c.ends_with("_m_s2") => Dimension::Acceleration,
            _ => return None,
        })
    }

    fn name(self) -> &'static str {
        match self {
            Dimension::Time => "a time",
            Dimension::Angle => "an angle",
            Dimension::AngularRate => "an angular rate",
            Dimension::Length => "a length",
            Dimension::Speed => "a speed",
            Dimension::Acceleration => "an acceleration",
            Dimension::Force => "a force",
            Dimension::Pressure => "a pressure",
            Dimension::Density => "a density",
            Dimension::AngularAcceleration => "an angular acceleration",
            Dimension::Fraction => "a fraction",
        }
    }
}

/// The units a map may name: (spelling, dimension, factor to SI).
const UNITS: &[(&str, Dimension, f64)] = &[
    ("s", Dimension::Time, 1.0),
    ("ms", Dimension::Time, 1e-3),
    // microseconds: ArduPilot's TimeUS, PX4's timestamp
    ("us", Dimension::Time, 1e-6),
    ("rad", Dimension::Angle, 1.0),
    ("deg", Dimension::Angle, std::f64::consts::PI / 180.0),
    // centidegrees: ArduPilot's integer attitudes and surface outputs
    ("cdeg", Dimension::Angle, std::f64::consts::PI / 18000.0),
    ("rad/s", Dimension::AngularRate, 1.0),
    // milliradians per second: MAVLink RAW_IMU / SCALED_IMU gyros
    ("mrad/s", Dimension::AngularRate, 1e-3),
    (
        "deg/s",
        Dimension::AngularRate,
        std::f64::consts::PI / 180.0,
    ),
    ("rad/s2", Dimension::AngularAcceleration, 1.0),
    (
        "deg/s2",
        Dimension::AngularAcceleration,
        std::f64::consts::PI / 180.0,
    ),
    ("m", Dimension::Length, 1.0),
    ("cm", Dimension::Length, 0.01),
    ("ft", Dimension::Length, 0.3048),
    ("m/s", Dimension::Speed, 1.0),
    ("cm/s", Dimension::Speed, 0.01),
    ("ft/s", Dimension::Speed, 0.3048),
    ("kts", Dimension::Speed, 1852.0 / 3600.0),
    ("kt", Dimension::Speed, 1852.0 / 3600.0),
    ("km/h", Dimension::Speed, 1.0 / 3.6),
    ("mph", Dimension::Speed, 0.44704),
    ("m/s2", Dimension::Acceleration, 1.0),
    ("g", Dimension::Acceleration, G0_M_S2),
    // milli-g: MAVLink SCALED_IMU accelerometers
    ("mg", Dimension::Acceleration, G0_M_S2 * 1e-3),
    ("N", Dimension::Force, 1.0),
    ("lbf", Dimension::Force, 4.448_221_615_260_5),
    ("Pa", Dimension::Pressure, 1.0),
    ("hPa", Dimension::Pressure, 100.0),
    ("mbar", Dimension::Pressure, 100.0),
    // 1 lbf/ft² = 4.4482216152605 N / 0.09290304 m².
    ("psf", Dimension::Pressure, 47.880_258_980_335_84),
    ("kg/m3", Dimension::Density, 1.0),
    // 1 slug/ft³ = 14.593902937 kg / 0.028316846592 m³.
    ("slug/ft3", Dimension::Density, 515.378_818_393_183_3),
    ("1", Dimension::Fraction, 1.0),
    ("percent", Dimension::Fraction, 0.01),
];

/// The unit spellings a map accepts, for messages.
pub fn unit_names() -> Vec<&'static str> {
    UNITS.iter().map(|u| u.0).collect()
}

/// One mapped column.
#[derive(Debug, Clone, PartialEq)]
pub struct ColumnMapping {
    /// The column's name in the foreign file.
    pub from: String,
    /// The schema column it becomes.
    pub to: String,
    /// The unit as written in the map (the target's own unit when the map gives none).
    pub unit: String,
    /// Multiplier taking a file value to SI: unit factor × the map's `scale`.
    pub factor: f64,
}

/// A column map (see the module documentation), checked against the schema on loading.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ColumnMap {
    /// The map file, for messages.
    pub file: PathBuf,
    /// The mappings, by foreign column name.
    pub columns: Vec<ColumnMapping>,
    /// Schema columns formed as weighted sums of foreign columns (`[derived]`).
    pub derived: Vec<DerivedColumn>,
    /// The file's airspeed is equivalent airspeed, made true on reading (`airspeed = "equivalent"`).
    pub airspeed_equivalent: bool,
}

/// A schema column that is a weighted sum of foreign columns, converted to SI after summing.
#[derive(Debug, Clone, PartialEq)]
pub struct DerivedColumn {
    /// The schema column it becomes.
    pub to: String,
    /// The foreign columns (as named in the file, before any renaming) and their weights.
    pub terms: Vec<(String, f64)>,
    /// The unit of the sum as written in the map (the target's own unit when the map gives none).
    pub unit: String,
    /// Multiplier taking the weighted sum to SI.
    pub factor: f64,
}

/// A header after the map: the schema names, each column's factor to SI, and the derived columns.
#[derive(Debug, Clone, PartialEq)]
pub struct MappedHeader {
    /// The column names, renamed where the map says.
    pub names: Vec<String>,
    /// Per column: the factor taking file values to SI.
    pub factors: Vec<f64>,
    /// The derived columns, placed among the file's columns.
    pub derived: Vec<PlacedDerivedColumn>,
}

/// A derived column placed in a header: the indices of its terms among the file's columns.
#[derive(Debug, Clone, PartialEq)]
pub struct PlacedDerivedColumn {
    /// The schema column it becomes.
    pub to: String,
    /// (column index in the file, weight × the unit's factor).
    pub terms: Vec<(usize, f64)>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct MapFile {
    airspeed: Option<String>,
    #[serde(default)]
    columns: BTreeMap<String, MapEntry>,
    #[serde(default)]
    derived: BTreeMap<String, DerivedEntry>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct DerivedEntry {
    from: BTreeMap<String, f64>,
    unit: Option<String>,
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct MapEntry {
    to: String,
    unit: Option<String>,
    scale: Option<f64>,
}

impl ColumnMap {
    /// Reads and checks a map file: every target a schema column, every unit known and of the
    /// target's dimension, no target named twice.
    pub fn load(path: &Path) -> Result<ColumnMap, DataError> {
        let text = std::fs::read_to_string(path)
            .map_err(DataError::io(path, "cannot read the column map"))?;
        Self::parse(&text, path)
    }

    /// Parses map text; `path` names it in messages.
    pub fn parse(text: &str, path: &Path) -> Result<ColumnMap, DataError> {
        let bad = |message: String| DataError::ColumnMap {
            map: path.to_path_buf(),
            message,
        };
        let raw: MapFile = toml::from_str(text).map_err(|e| {
            bad(format!(
                "{} (expected `[columns]` with entries like `DELV = {{ to = \"elevator_rad\", unit = \"deg\" }}`)",
                e.message()
            ))
        })?;
        let mut columns = Vec::with_capacity(raw.columns.len());
        let mut errors = Vec::new();
        for (from, entry) in raw.columns {
            let (unit, unit_factor, dim) = match target_unit(&entry.to, entry.unit.as_deref()) {
                Ok(u) => u,
                Err(e) => {
                    errors.push(format!("`{from}`: {e}"));
                    continue;
                }
            };
            let scale = entry.scale.unwrap_or(1.0);
            if !(scale.is_finite() && scale != 0.0) || (dim == Dimension::Time && scale < 0.0) {
                errors.push(format!(
                    "`{from}`: scale must be a finite non-zero number (positive for time), got {scale}"
                ));
                continue;
            }
            columns.push(ColumnMapping {
                from,
                to: entry.to,
                unit,
                factor: unit_factor * scale,
            });
        }
        let mut derived = Vec::with_capacity(raw.derived.len());
        for (to, entry) in raw.derived {
            let (unit, factor, _) = match target_unit(&to, entry.unit.as_deref()) {
                Ok(u) => u,
                Err(e) => {
                    errors.push(format!("[derived] `{to}`: {e}"));
                    continue;
                }
            };
            if entry.from.is_empty() || entry.from.values().any(|w| !w.is_finite()) {
                errors.push(format!(
                    "[derived] `{to}`: `from` needs at least one column with a finite weight, \
                     e.g. `from = {{ DAR = 0.5, DAL = -0.5 }}`"
                ));
                continue;
            }
            if to == "time_s" {
                errors.push("[derived] `time_s`: time must be a column of the file".to_string());
                continue;
            }
            derived.push(DerivedColumn {
                to,
                terms: entry.from.into_iter().collect(),
                unit,
                factor,
            });
        }
        let targets: Vec<(&str, &str)> = columns
            .iter()
            .map(|m| (m.from.as_str(), m.to.as_str()))
            .chain(derived.iter().map(|d| ("[derived]", d.to.as_str())))
            .collect();
        for (i, a) in targets.iter().enumerate() {
            if let Some(b) = targets[..i].iter().find(|b| b.1 == a.1) {
                errors.push(format!("`{}` and `{}` both map to `{}`", b.0, a.0, a.1));
            }
        }
        let airspeed_equivalent = match raw.airspeed.as_deref() {
            None | Some("true") => false,
            Some("equivalent" | "calibrated" | "indicated") => true,
            Some(other) => {
                errors.push(format!(
                    "airspeed = \"{other}\": expected \"true\" (the default) or \"equivalent\" (also \"calibrated\", \
                     \"indicated\")"
                ));
                false
            }
        };
        if !errors.is_empty() {
            return Err(bad(errors.join("; ")));
        }
        Ok(ColumnMap {
            file: path.to_path_buf(),
            columns,
            derived,
            airspeed_equivalent,
        })
    }

    /// What the map does to a whole record once its columns are read: an equivalent airspeed made true (module
    /// documentation), with a note in the record's metadata. A record without the columns that needs fails,
    /// naming them.
    pub fn finish(&self, rec: &mut FlightRecord, file: &str) -> Result<(), DataError> {
        if !self.airspeed_equivalent {
            return Ok(());
        }
        let bad = |message: String| DataError::ColumnMap {
            map: self.file.clone(),
            message: format!("{file}: {message}"),
        };
        let v = rec.column("airspeed_m_s").ok_or_else(|| {
            bad("airspeed = \"equivalent\" but the record has no airspeed_m_s".into())
        })?;
        let (ratio, source): (Vec<f64>, &str) = if let Some(rho) = rec.column("density_kg_m3") {
            let rho0 = crate::sim::atmosphere::density_kg_m3(0.0, 0.0).unwrap_or(1.225);
            (
                rho.iter().map(|r| (rho0 / r).sqrt()).collect(),
                "the logged density_kg_m3",
            )
        } else if let Some(h) = rec.column("altitude_m") {
            let ratio = h
                .iter()
                .map(|h| super::tlog::true_from_equivalent(1.0, *h))
                .collect();
            (ratio, "the standard atmosphere at the logged altitude_m")
        } else {
            return Err(bad(
                "airspeed = \"equivalent\" needs density_kg_m3 or altitude_m to make it true airspeed".into(),
            ));
        };
        let true_airspeed: Vec<f64> = v.iter().zip(&ratio).map(|(v, k)| v * k).collect();
        rec.push_column("airspeed_m_s", true_airspeed);
        rec.metadata.push(format!(
            " airspeed_m_s: equivalent airspeed made true with {source} (x{:.4} at the start; the column map's \
             airspeed = \"equivalent\")",
            ratio.first().copied().unwrap_or(f64::NAN)
        ));
        Ok(())
    }

    /// Applies the map to a header: the renamed header, each column's factor to SI, and the derived
    /// columns placed among the file's columns. Fails naming every mapped or summed column the header
    /// lacks, and a target the file already has under its own name.
    pub fn apply_to_header(&self, names: &[String], file: &str) -> Result<MappedHeader, DataError> {
        let mut missing: Vec<&str> = self
            .columns
            .iter()
            .map(|m| m.from.as_str())
            .chain(
                self.derived
                    .iter()
                    .flat_map(|d| d.terms.iter().map(|t| t.0.as_str())),
            )
            .filter(|from| !names.iter().any(|n| n == from))
            .collect();
        missing.sort_unstable();
        missing.dedup();
        if !missing.is_empty() {
            return Err(DataError::MapColumnMissing {
                file: file.to_string(),
                map: self.file.clone(),
                columns: missing
                    .iter()
                    .map(|c| format!("`{c}`"))
                    .collect::<Vec<_>>()
                    .join(", "),
                present: names.join(", "),
            });
        }
        let taken = |name: &str, by: &str| {
            DataError::ColumnMap {
            map: self.file.clone(),
            message: format!(
                "{file} already has a column `{name}`, and the map also maps {by} onto it; drop one of them"
            ),
        }
        };
        let mut out = Vec::with_capacity(names.len());
        let mut factors = Vec::with_capacity(names.len());
        for name in names {
            match self.columns.iter().find(|m| &m.from == name) {
                Some(m) => {
                    out.push(m.to.clone());
                    factors.push(m.factor);
                }
                None => {
                    if let Some(m) = self.columns.iter().find(|m| &m.to == name) {
                        return Err(taken(name, &format!("`{}`", m.from)));
                    }
                    out.push(name.clone());
                    factors.push(1.0);
                }
            }
        }
        let mut derived = Vec::with_capacity(self.derived.len());
        for d in &self.derived {
            if out.contains(&d.to) {
                return Err(taken(&d.to, "a `[derived]` sum"));
            }
            let terms = d
                .terms
                .iter()
                .map(|(from, w)| {
                    let k = names.iter().position(|n| n == from).expect("checked above");
                    (k, w * d.factor)
                })
                .collect();
            derived.push(PlacedDerivedColumn {
                to: d.to.clone(),
                terms,
            });
        }
        Ok(MappedHeader {
            names: out,
            factors,
            derived,
        })
    }
}

/// The unit of a map entry onto schema column `to`: its name, its factor to SI and the target's dimension
/// (the target's own unit when `unit` is `None`). The error says what is wrong, for the entry's message.
fn target_unit(to: &str, unit: Option<&str>) -> Result<(String, f64, Dimension), String> {
    let Some(dim) = Dimension::of_column(to) else {
        let hint = did_you_mean(to, SCHEMA_COLUMNS.iter().copied())
            .map(|c| format!("; did you mean `{c}`?"))
            .unwrap_or_default();
        return Err(format!(
            "unknown target column `{to}`{hint} (schema columns: {})",
            SCHEMA_COLUMNS.join(", ")
        ));
    };
    match unit {
        None => Ok((default_unit(dim).to_string(), 1.0, dim)),
        Some(u) => match UNITS.iter().find(|x| x.0 == u.trim()) {
            Some(&(name, d, f)) if d == dim => Ok((name.to_string(), f, dim)),
            Some(&(name, d, _)) => Err(format!(
                "unit `{name}` measures {} but `{to}` is {}",
                d.name(),
                dim.name()
            )),
            None => {
                let hint = did_you_mean(u, UNITS.iter().map(|x| x.0))
                    .map(|c| format!("; did you mean `{c}`?"))
                    .unwrap_or_default();
                Err(format!(
                    "unknown unit `{u}`{hint} (units: {})",
                    unit_names().join(", ")
                ))
            }
        },
    }
}

/// The SI unit of a dimension, as a map would spell it.
fn default_unit(dim: Dimension) -> &'static str {
    match dim {
        Dimension::Time => "s",
        Dimension::Angle => "rad",
        Dimension::AngularRate => "rad/s",
        Dimension::Length => "m",
        Dimension::Speed => "m/s",
        Dimension::Acceleration => "m/s2",
        Dimension::Force => "N",
        Dimension::Pressure => "Pa",
        Dimension::Density => "kg/m3",
        Dimension::AngularAcceleration => "rad/s2",
        Dimension::Fraction => "1",
    }
}

/// The closest candidate to `name` (case-insensitive edit distance at most a third of its
/// length, at least 2), if any.
pub fn did_you_mean<'a>(name: &str, candidates: impl Iterator<Item = &'a str>) -> Option<&'a str> {
    let lower = name.to_ascii_lowercase();
    let limit = (lower.len() / 3).max(2);
    candidates
        .map(|c| {
            let other = c.to_ascii_lowercase();
            // A name that begins the other (`deg` in `degrees`) is as good as one edit away.
            let prefix = other.len() >= 2
                && lower.len() >= 2
                && (lower.starts_with(&other) || other.starts_with(&lower));
            let d = edit_distance(&lower, &other);
            (if prefix { d.min(1) } else { d }, c)
        })
        .filter(|(d, _)| *d <= limit)
        .min_by_key(|(d, _)| *d)
        .map(|(_, c)| c)
}

/// Levenshtein distance (byte-wise; names are ASCII).
fn edit_distance(a: &str, b: &str) -> usize {
    let (a, b) = (a.as_bytes(), b.as_bytes());
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    let mut cur = vec![0; b.len() + 1];
    for i in 1..=a.len() {
        cur[0] = i;
        for j in 1..=b.len() {
            let sub = prev[j - 1] + usize::from(a[i - 1] != b[j - 1]);
            cur[j] = sub.min(prev[j] + 1).min(cur[j - 1] + 1);
        }
        std::mem::swap(&mut prev, &mut cur);
    }
    prev[b.len()]
}

/// The record column a user's name refers to: the name itself; else the one column whose name is
/// the given name plus a unit suffix (`theta` → `theta_rad`, `q` → `q_rad_s`); else an error with
/// the closest name.
pub fn resolve_column(present: &[&str], name: &str, why: &str) -> Result<String, DataError> {
    if present.contains(&name) {
        return Ok(name.to_string());
    }
    const SUFFIXES: &[&str] = &["_rad", "_rad_s", "_m_s", "_m", "_m_s2", "_n", "_pa", "_s"];
    let with_unit: Vec<&str> = present
        .iter()
        .copied()
        .filter(|c| {
            c.strip_prefix(name)
                .is_some_and(|rest| SUFFIXES.contains(&rest))
        })
        .collect();
    if with_unit.len() == 1 {
        return Ok(with_unit[0].to_string());
    }
    let hint = if with_unit.len() > 1 {
        format!(" (ambiguous: {})", with_unit.join(", "))
    } else {
        did_you_mean(name, present.iter().copied())
            .map(|c| format!("; did you mean `{c}`?"))
            .unwrap_or_default()
    };
    Err(DataError::MissingColumn {
        column: name.to_string(),
        why: format!("{why}{hint}"),
        present: present.join(", "),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> Result<ColumnMap, DataError> {
        ColumnMap::parse(text, Path::new("map.toml"))
    }

    /// The message of the error a map that must be refused gives.
    fn refusal(text: &str) -> String {
        parse(text).unwrap_err().to_string()
    }

    #[test]
    fn units_convert_to_si_with_the_maps_scale() {
        let m = parse(
            "[columns]\nDELV = { to = \"elevator_rad\", unit = \"deg\", scale = -1.0 }\n\
             V = { to = \"airspeed_m_s\", unit = \"kts\" }\nQBAR = { to = \"qbar_pa\", unit = \"psf\" }\n\
             T = { to = \"time_s\" }\nF = { to = \"thrust_n\", unit = \"lbf\" }\n",
        )
        .unwrap();
        let f = |from: &str| m.columns.iter().find(|c| c.from == from).unwrap().factor;
        assert!((f("DELV") + 0.017_453_292_519_943_295).abs() < 1e-15);
        assert!((f("V") - 0.514_444_444).abs() < 1e-9);
        assert!((f("QBAR") - 47.880_26).abs() < 1e-4);
        assert!((f("F") - 4.448_222).abs() < 1e-6);
        assert_eq!(f("T"), 1.0);
    }

    #[test]
    fn the_units_of_autopilot_logs_convert() {
        // ArduPilot and MAVLink spellings: TimeUS, centidegrees, mrad/s gyros, milli-g accelerometers, cm
        let m = parse(
            "[columns]\nTimeUS = { to = \"time_s\", unit = \"us\" }\nRoll = { to = \"phi_rad\", unit = \"cdeg\" }\n\
             xgyro = { to = \"p_rad_s\", unit = \"mrad/s\" }\nzacc = { to = \"az_m_s2\", unit = \"mg\" }\n\
             Alt = { to = \"altitude_m\", unit = \"cm\" }\nGS = { to = \"airspeed_m_s\", unit = \"km/h\" }\n\
             Press = { to = \"qbar_pa\", unit = \"hPa\" }\n",
        )
        .unwrap();
        let f = |from: &str| m.columns.iter().find(|c| c.from == from).unwrap().factor;
        assert_eq!(f("TimeUS"), 1e-6);
        assert!((f("Roll") * 9000.0 - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        assert_eq!(f("xgyro"), 1e-3);
        assert!((f("zacc") - 0.009_806_65).abs() < 1e-12);
        assert_eq!(f("Alt"), 0.01);
        assert!((f("GS") * 36.0 - 10.0).abs() < 1e-12);
        assert_eq!(f("Press"), 100.0);
    }

    #[test]
    fn bad_maps_name_the_entry_the_unit_and_the_target() {
        let e = refusal("[columns]\nA = { to = \"alpha_rad\", unit = \"degree\" }\n");
        assert!(
            e.contains("`A`") && e.contains("unknown unit `degree`") && e.contains("deg"),
            "{e}"
        );
        let e = refusal("[columns]\nA = { to = \"alpha\", unit = \"deg\" }\n");
        assert!(
            e.contains("unknown target column `alpha`") && e.contains("alpha_rad"),
            "{e}"
        );
        let e = refusal("[columns]\nV = { to = \"airspeed_m_s\", unit = \"deg\" }\n");
        assert!(
            e.contains("measures an angle") && e.contains("a speed"),
            "{e}"
        );
        let e = refusal("[columns]\nA = { to = \"alpha_rad\" }\nB = { to = \"alpha_rad\" }\n");
        assert!(e.contains("both map to `alpha_rad`"), "{e}");
    }

    #[test]
    fn derived_sums_are_checked_like_mapped_columns() {
        let e =
            refusal("[derived]\naileron = { from = { DAR = 0.5, DAL = -0.5 }, unit = \"deg\" }\n");
        assert!(
            e.contains("[derived] `aileron`: unknown target column") && e.contains("aileron_rad"),
            "{e}"
        );
        let e = refusal("[derived]\naileron_rad = { from = {}, unit = \"deg\" }\n");
        assert!(e.contains("at least one column"), "{e}");
        let e = refusal(
            "[columns]\nDA = { to = \"aileron_rad\" }\n[derived]\naileron_rad = { from = { DAR = 1.0 } }\n",
        );
        assert!(e.contains("both map to `aileron_rad`"), "{e}");
        let m = parse(
            "[derived]\naileron_rad = { from = { DAR = 0.5, DAL = -0.5 }, unit = \"deg\" }\n",
        )
        .unwrap();
        let names = vec!["t".to_string(), "DAL".to_string()];
        let e = m.apply_to_header(&names, "f.csv").unwrap_err().to_string();
        assert!(
            e.contains("names `DAR`, which the file does not have"),
            "{e}"
        );
        let names = vec!["t".to_string(), "DAL".to_string(), "DAR".to_string()];
        let placed = m.apply_to_header(&names, "f.csv").unwrap().derived;
        let deg = std::f64::consts::PI / 180.0;
        assert_eq!(placed[0].terms, vec![(1, -0.5 * deg), (2, 0.5 * deg)]);
    }

    /// Equivalent airspeed is made true with the logged density where there is one (ρ = ρ₀/4 doubles it) and the
    /// standard atmosphere at the altitude otherwise (×1.0601 at 1 200 m: ρ/ρ₀ = 0.8898, `true_from_equivalent`); a record
    /// without either, an unknown kind, and a map without the key (true airspeed, left alone) are checked too.
    #[test]
    fn an_equivalent_airspeed_is_made_true_airspeed() {
        let m = parse("airspeed = \"equivalent\"\n[columns]\n").unwrap();
        let record = |extra: (&str, f64)| {
            let mut rec = FlightRecord::new(vec![0.0, 0.1]);
            rec.columns = vec![
                ("airspeed_m_s".into(), vec![50.0, 60.0]),
                (extra.0.into(), vec![extra.1; 2]),
            ];
            rec
        };
        let mut rec = record(("density_kg_m3", 1.225 / 4.0));
        m.finish(&mut rec, "f.csv").unwrap();
        let v = rec.column("airspeed_m_s").unwrap();
        assert!(
            (v[0] - 100.0).abs() < 0.1 && (v[1] - 120.0).abs() < 0.1,
            "{v:?}"
        );
        let mut rec = record(("altitude_m", 1200.0));
        m.finish(&mut rec, "f.csv").unwrap();
        let v = rec.column("airspeed_m_s").unwrap()[0];
        assert!((v / 50.0 - 1.0601).abs() < 5e-4, "{v}");
        let mut rec = record(("q_rad_s", 0.0));
        let e = m.finish(&mut rec, "f.csv").unwrap_err().to_string();
        assert!(e.contains("needs density_kg_m3 or altitude_m"), "{e}");
        assert!(refusal("airspeed = \"fast\"\n").contains("airspeed = \"fast\""));
        let plain = parse("[columns]\n").unwrap();
        let mut rec = record(("altitude_m", 1200.0));
        plain.finish(&mut rec, "f.csv").unwrap();
        assert_eq!(rec.column("airspeed_m_s").unwrap(), [50.0, 60.0]);
    }

    #[test]
    fn header_mapping_reports_every_missing_column() {
        let m = parse(
            "[columns]\nA = { to = \"alpha_rad\", unit = \"deg\" }\nB = { to = \"beta_rad\", unit = \"deg\" }\n",
        )
        .unwrap();
        let names = vec!["t".to_string(), "C".to_string()];
        let e = m.apply_to_header(&names, "f.csv").unwrap_err().to_string();
        assert!(
            e.contains("`A`, `B`") && e.contains("f.csv") && e.contains("map.toml"),
            "{e}"
        );
    }

    #[test]
    fn names_without_unit_suffix_resolve_when_unambiguous() {
        let cols = ["time_s", "theta_rad", "q_rad_s", "elevator_rad"];
        assert_eq!(resolve_column(&cols, "theta", "x").unwrap(), "theta_rad");
        assert_eq!(resolve_column(&cols, "q", "x").unwrap(), "q_rad_s");
        let e = resolve_column(&cols, "thetta_rad", "x")
            .unwrap_err()
            .to_string();
        assert!(e.contains("did you mean `theta_rad`"), "{e}");
    }
}
