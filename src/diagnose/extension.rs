//! The catalogue of model extensions: one small type per effect (docs/diagnose.md vocabulary).
//!
//! An extension acts at one of three places of the replay: on the model before trimming (aerodynamic
//! coefficient scales), on the surface inputs before simulating (signal path), or on the simulated
//! outputs (sensors). What an effect is (its name, stage, targets and parameter) is one row of
//! [`REGISTRY`]; how it changes the replay is one type implementing [`Effect`]. The search in
//! [`super::search`] sees a row on one target through the [`Extension`] trait.

use super::simulator::ReplaySim;
use super::DiagnoseError;
use crate::data::{Channel, FlightRecord};
use crate::signal::lever_arm_acceleration;
use crate::sim::SimError;

/// Where in the replay an extension acts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// On the model, before trimming (needs a new trim and a new simulation).
    Model,
    /// On a surface input sequence, before simulating (needs a new simulation).
    Input,
    /// On a simulated output column (no new simulation).
    Output,
}

/// One parameter of an extension: the value that means "no effect", its bounds and a finite-difference step.
#[derive(Debug, Clone, Copy)]
pub struct ParamSpec {
    /// Value at which the extension changes nothing.
    pub null: f64,
    /// Lower bound.
    pub min: f64,
    /// Upper bound.
    pub max: f64,
    /// Finite-difference step for sensitivities (parameter units).
    pub fd_step: f64,
    /// Smallest departure from `null` worth naming (parameter units): an effect is named only when it is at
    /// least this large and the record determines it to a third of this (Cramér–Rao bound).
    pub resolution: f64,
}

/// A model extension as the search sees it: an effect on a target with parameters fitted by output error.
pub trait Extension: Send + Sync {
    /// Effect name from the docs/diagnose.md vocabulary (`input_delay`, `sensor_bias`, ...).
    fn effect(&self) -> &'static str;
    /// Target: a surface, a CSV column or a derivative name.
    fn target(&self) -> &str;
    /// `effect/target`, the name candidates and ambiguity groups are reported by.
    fn key(&self) -> String {
        format!("{}/{}", self.effect(), self.target())
    }
    /// Where the extension acts.
    fn stage(&self) -> Stage;
    /// Parameter specifications (the first one is the reported `value`).
    fn params(&self) -> Vec<ParamSpec>;
    /// CSV columns the extension needs in the measured record.
    fn required_columns(&self) -> Vec<String>;
    /// CSV columns of which the measured record needs at least one (empty: no such condition).
    fn required_one_of(&self) -> Vec<String> {
        Vec::new()
    }
    /// Changes the model before trimming (Stage::Model).
    fn apply_model(&self, p: &[f64], sim: &mut dyn ReplaySim) -> Result<(), SimError>;
    /// Changes the deviation sequence of `surface` (sampled at `dt_s`, sample 0 = initial condition, value 0).
    fn apply_input(&self, p: &[f64], surface: &str, dev: &mut [f64], dt_s: f64);
    /// Changes the simulated record (Stage::Output).
    fn apply_output(&self, p: &[f64], rec: &mut FlightRecord);
    /// The catalogue entry (effect, target) whose linear term this one refines, e.g. `aero_derivative/CL_alpha`
    /// for `CL_alpha2`. Near a trim point a refinement acts mostly as a change of that term, so its smallest
    /// effect worth naming is measured against that term's resolution on the record (see `select`).
    fn refines(&self) -> Option<(&'static str, String)>;
    /// The inputs of which at least one must move for the record to excite the effect (empty: any motion
    /// does). A signal-path effect needs its own surface. An aerodynamic derivative needs an input of its
    /// axis: without one, that axis moves only by the gusts and the segments' initial states, which an
    /// open-loop replay follows no better with the derivative changed than without.
    fn excited_by(&self) -> Vec<String> {
        if self.target() == ALL_SURFACES {
            return ["elevator", "aileron", "rudder"].map(String::from).to_vec();
        }
        if self.stage() == Stage::Input {
            return vec![self.target().to_string()];
        }
        if !matches!(self.effect(), "aero_derivative" | "aero_nonlinearity") {
            return Vec::new();
        }
        let axis: &[&str] = match self.target().split('_').next() {
            Some("Cl" | "Cn" | "CY") => &["aileron", "rudder"],
            Some("CL" | "CD" | "Cm") => &["elevator", "throttle"],
            _ => &[],
        };
        axis.iter().map(|s| s.to_string()).collect()
    }
    /// How many of [`Extension::excited_by`]'s inputs must move: one, except for an effect common to every
    /// surface, which a record can tell from a delay on one surface only where two or more move.
    fn excited_count(&self) -> usize {
        if self.target() == ALL_SURFACES {
            2
        } else {
            1
        }
    }
}

/// How an effect changes the replay on its target. An effect type implements the one method of its stage
/// ([`EffectKind::stage`]); the others change nothing.
pub trait Effect: Send + Sync {
    /// Changes the simulation before trimming (Stage::Model).
    fn apply_model(&self, _p: &[f64], _sim: &mut dyn ReplaySim) -> Result<(), SimError> {
        Ok(())
    }
    /// Changes the deviation sequence of the target surface, sampled at `dt_s` (sample 0 = initial
    /// condition, value 0) (Stage::Input).
    fn apply_input(&self, _p: &[f64], _dev: &mut [f64], _dt_s: f64) {}
    /// Changes the simulated record: its `target` column, or the columns the effect acts on (Stage::Output).
    fn apply_output(&self, _p: &[f64], _target: &str, _rec: &mut FlightRecord) {}
}

/// Pure time delay of a surface deflection: the aircraft responds to δ(t − τ). Value: τ, s.
pub struct InputDelay;
/// First-order actuator lag τ ẋ = δ − x between the measured deflection and the one the aero model sees. Value: τ, s.
pub struct ActuatorLag;
/// Factor on a surface's aerodynamic effect (the deflection deviation the model sees is k·δ). Value: k.
pub struct ControlEffectiveness;
/// Additive offset on a measured column. Value: offset in column units.
pub struct SensorBias;
/// Factor on a measured column (measured = k · true). Value: k.
pub struct SensorScale;
/// Factor on one aerodynamic coefficient function of the simulation. Value: factor.
pub struct AeroDerivative {
    /// The simulation's coefficient (knob) name, e.g. `Cmalpha`.
    pub knob: String,
}
/// An added aerodynamic term the simulation's model lacks, e.g. `Cm_alpha2`: ΔC_m = k α² (α in rad).
/// Value: the coefficient k.
pub struct AeroNonlinearity {
    /// The simulation's name of the added term, e.g. `Cm_alpha2`.
    pub term: String,
}

impl Effect for InputDelay {
    fn apply_input(&self, p: &[f64], dev: &mut [f64], dt_s: f64) {
        // δ_d(t_k) = δ(t_k − τ), linear interpolation between samples, δ = 0 before the record and its last
        // value after it. A negative τ (a `time_skew` whose surfaces are stamped later than the response) reads
        // ahead.
        let src = dev.to_vec();
        let at = |j: isize| -> f64 {
            if j < 0 {
                0.0
            } else {
                src[(j as usize).min(src.len() - 1)]
            }
        };
        for (k, v) in dev.iter_mut().enumerate() {
            let x = k as f64 - p[0] / dt_s;
            let j = x.floor();
            let frac = x - j;
            *v = (1.0 - frac) * at(j as isize) + frac * at(j as isize + 1);
        }
    }
}

impl Effect for ActuatorLag {
    fn apply_input(&self, p: &[f64], dev: &mut [f64], dt_s: f64) {
        if p[0] <= 0.0 {
            return;
        }
        // τ ẋ = δ − x, discretised exactly for the input the replay applies, straight lines between the
        // samples (the triangle-hold equivalent; Franklin, Powell & Workman, Digital Control of Dynamic
        // Systems, §6.3.2): x_k = a x_{k−1} + (1 − a) δ_{k−1} + b (δ_k − δ_{k−1}),
        // a = e^{−Δt/τ}, b = 1 − (τ/Δt)(1 − a).
        let a = (-dt_s / p[0]).exp();
        let b = 1.0 - p[0] / dt_s * (1.0 - a);
        let (mut x, mut prev) = (0.0, 0.0);
        for v in dev.iter_mut() {
            let u = *v;
            x = a * x + (1.0 - a) * prev + b * (u - prev);
            prev = u;
            *v = x;
        }
    }
}

impl Effect for ControlEffectiveness {
    fn apply_input(&self, p: &[f64], dev: &mut [f64], _dt_s: f64) {
        dev.iter_mut().for_each(|v| *v *= p[0]);
    }
}

impl Effect for SensorBias {
    fn apply_output(&self, p: &[f64], target: &str, rec: &mut FlightRecord) {
        if let Some(column) = rec.column_mut(target) {
            column.iter_mut().for_each(|v| *v += p[0]);
        }
    }
}

impl Effect for SensorScale {
    fn apply_output(&self, p: &[f64], target: &str, rec: &mut FlightRecord) {
        if let Some(column) = rec.column_mut(target) {
            column.iter_mut().for_each(|v| *v *= p[0]);
        }
    }
}

impl Effect for AeroDerivative {
    fn apply_model(&self, p: &[f64], sim: &mut dyn ReplaySim) -> Result<(), SimError> {
        sim.set_coefficient_scale(&self.knob, p[0])
    }
}

impl Effect for AeroNonlinearity {
    fn apply_model(&self, p: &[f64], sim: &mut dyn ReplaySim) -> Result<(), SimError> {
        sim.set_added_term(&self.term, p[0])
    }
}

/// The effect name of the accelerometers' position along one body axis.
pub const ACCELEROMETER_POSITION: &str = "accelerometer_position";

/// The columns the position needs in the record: the body rates.
pub const REQUIRED: [Channel; 3] = [Channel::P, Channel::Q, Channel::R];

/// The accelerometer channels, in the order of the components of [`lever_arm_acceleration`].
const ACCELEROMETERS: [Channel; 3] = [Channel::Ax, Channel::Ay, Channel::Az];

/// The accelerometers `value` metres along one body axis from where the model reads its accelerations. Value: m.
pub struct AccelerometerPosition {
    /// 0, 1, 2 for x (forward), y (right), z (down).
    axis: usize,
}

impl AccelerometerPosition {
    /// The position along `axis` (`x`, `y` or `z`; another name is taken as `x`, which `extension::make` never
    /// passes).
    pub fn along(axis: &str) -> Self {
        AccelerometerPosition {
            axis: BODY_AXES.iter().position(|a| *a == axis).unwrap_or(0),
        }
    }
}

impl Effect for AccelerometerPosition {
    fn apply_output(&self, p: &[f64], _target: &str, rec: &mut FlightRecord) {
        let n = rec.len();
        let Some(dt) = rec.dt_s() else {
            return;
        };
        if p[0] == 0.0 || n < 3 {
            return;
        }
        let rates: Vec<Vec<f64>> = REQUIRED
            .iter()
            .map(|c| rec.column(c).map_or_else(|| vec![0.0; n], <[f64]>::to_vec))
            .collect();
        // The simulated rates are smooth: ω̇ by central differences (one-sided at the ends).
        let derivative = |x: &[f64], k: usize| {
            let (a, b) = (k.saturating_sub(1), (k + 1).min(n - 1));
            (x[b] - x[a]) / ((b - a) as f64 * dt)
        };
        let mut r = [0.0; 3];
        r[self.axis] = p[0];
        let extra: Vec<[f64; 3]> = (0..n)
            .map(|k| {
                let w = [rates[0][k], rates[1][k], rates[2][k]];
                let w_dot = [0, 1, 2].map(|i| derivative(&rates[i], k));
                lever_arm_acceleration(w, w_dot, r)
            })
            .collect();
        for (i, channel) in ACCELEROMETERS.iter().enumerate() {
            if let Some(column) = rec.column_mut(channel) {
                column.iter_mut().zip(&extra).for_each(|(v, e)| *v += e[i]);
            }
        }
    }
}

/// Smallest sensor bias worth naming, by the column's unit: 0.3° for an angle, 0.17°/s for a rate,
/// 0.05 m/s² for an acceleration.
fn bias_resolution(column: &str) -> f64 {
    if column.ends_with("_rad_s") {
        0.003
    } else if column.ends_with("_rad") {
        0.005
    } else if column.ends_with("_m_s2") {
        0.05
    } else {
        1e-3
    }
}

/// docs/diagnose.md derivative names, each with the names JSBSim's aircraft give the coefficient function that
/// carries it (`aero/coefficient/<name>`): the c172x's first, then those of the 737, c310, pa28, A320, f15 and
/// f16 where they differ. The first name the simulation has is the one scaled ([`knob_of`]); an aircraft with
/// none of them leaves the derivative out of the catalogue, with the names looked for.
pub const DERIVATIVE_KNOBS: [(&str, &[&str]); 18] = [
    ("CL_alpha", &["CLwbh", "CLalpha"]),
    ("CD_0", &["CDo", "CD0"]),
    ("Cm_0", &["Cmo", "Cm0"]),
    ("Cm_alpha", &["Cmalpha"]),
    ("Cm_q", &["Cmq"]),
    ("Cm_alphadot", &["Cmadot", "Cmalphadot"]),
    ("Cm_de", &["Cmde", "CmDe"]),
    ("CY_beta", &["CYb", "CYbeta"]),
    ("Cl_beta", &["Clb", "Clbeta"]),
    ("Cl_p", &["Clp"]),
    ("Cl_r", &["Clr"]),
    ("Cl_da", &["Clda", "ClDa"]),
    ("Cl_dr", &["Cldr", "ClDr"]),
    ("Cn_beta", &["Cnb", "Cnbeta"]),
    ("Cn_p", &["Cnp"]),
    ("Cn_r", &["Cnr"]),
    ("Cn_da", &["Cnda", "CnDa"]),
    ("Cn_dr", &["Cndr", "CnDr"]),
];

/// Output columns that may carry a sensor bias or scale. Airspeed and altitude are not among them: they set
/// the trim point of the replay, so an error in them shows as a trim mismatch instead.
pub const SENSOR_COLUMNS: [Channel; 10] = [
    Channel::Phi,
    Channel::Theta,
    Channel::P,
    Channel::Q,
    Channel::R,
    Channel::Alpha,
    Channel::Beta,
    Channel::Ax,
    Channel::Ay,
    Channel::Az,
];

/// Which targets an effect applies to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Targets {
    /// The surfaces of the schema (elevator, aileron, rudder, throttle).
    Surfaces,
    /// Every surface at once: one target, [`ALL_SURFACES`].
    AllSurfaces,
    /// The body axes `x`, `y`, `z` (forward, right, down).
    BodyAxes,
    /// The columns that may carry a sensor error ([`SENSOR_COLUMNS`]).
    SensorColumns,
    /// The derivatives of [`DERIVATIVE_KNOBS`] whose coefficient the simulation can scale.
    Derivatives,
    /// The added terms the simulation offers.
    AddedTerms,
}

impl Targets {
    /// The measured columns an effect on `target` needs: a surface's deflection column, a sensor column
    /// itself; none for a change of the model.
    fn required_columns(self, target: &str) -> Vec<String> {
        match self {
            Targets::Surfaces => Channel::of_surface(target)
                .map(|c| c.to_string())
                .into_iter()
                .collect(),
            Targets::SensorColumns => vec![target.to_string()],
            Targets::BodyAxes => REQUIRED.iter().map(|c| c.to_string()).collect(),
            Targets::AllSurfaces | Targets::Derivatives | Targets::AddedTerms => Vec::new(),
        }
    }
}

/// One row of the catalogue: what an effect is and how to build it for one target (the target name and, for
/// derivatives, the simulation's coefficient name).
pub struct EffectKind {
    /// Effect name of the vocabulary.
    pub effect: &'static str,
    /// Where it acts.
    pub stage: Stage,
    /// Targets it applies to.
    pub targets: Targets,
    /// Its one parameter (the reported value) on a target.
    pub param: fn(&str) -> ParamSpec,
    /// The catalogue entry (effect, target) whose linear term it refines on a target ([`Extension::refines`]).
    pub refines: fn(&str) -> Option<(&'static str, String)>,
    /// Builds its [`Effect`] for a target and coefficient name.
    pub build: fn(&str, &str) -> Box<dyn Effect>,
}

/// The target of an effect on every surface at once ([`Targets::AllSurfaces`]).
pub const ALL_SURFACES: &str = "surfaces";

/// The effect name of a time skew common to every surface: the response follows every surface by the same time
/// (a data system stamping its sensor channels late, or sensor filters that lag every channel alike). It is the
/// record's timing, not a cause (`super::skew`).
pub const TIME_SKEW: &str = "time_skew";

/// The targets of an effect along a body axis ([`Targets::BodyAxes`]).
pub const BODY_AXES: [&str; 3] = ["x", "y", "z"];

/// A pure delay's parameter, s: up to 1 s, named from 20 ms on.
fn delay_param(_: &str) -> ParamSpec {
    ParamSpec {
        null: 0.0,
        min: 0.0,
        max: 1.0,
        fd_step: 0.005,
        resolution: 0.02,
    }
}

/// The catalogue: a new effect is one type implementing [`Effect`] and one row here.
pub const REGISTRY: [EffectKind; 9] = [
    EffectKind {
        effect: "input_delay",
        stage: Stage::Input,
        targets: Targets::Surfaces,
        param: delay_param,
        refines: |_| None,
        build: |_, _| Box::new(InputDelay),
    },
    // The same delay on every surface: one parameter where `input_delay` would need one per surface. A skew of
    // the record's timing costs every surface that moves alike, so it is told from a delay on one surface. It may
    // be negative: a data system can stamp its surfaces later than its sensors, as well as the other way round.
    EffectKind {
        effect: TIME_SKEW,
        stage: Stage::Input,
        targets: Targets::AllSurfaces,
        param: |target| ParamSpec {
            min: -0.5,
            ..delay_param(target)
        },
        refines: |_| None,
        build: |_, _| Box::new(InputDelay),
    },
    EffectKind {
        effect: "actuator_lag",
        stage: Stage::Input,
        targets: Targets::Surfaces,
        param: |_| ParamSpec {
            null: 0.0,
            min: 0.0,
            max: 2.0,
            fd_step: 0.005,
            resolution: 0.03,
        },
        refines: |_| None,
        build: |_, _| Box::new(ActuatorLag),
    },
    EffectKind {
        effect: "control_effectiveness",
        stage: Stage::Input,
        targets: Targets::Surfaces,
        param: |_| ParamSpec {
            null: 1.0,
            min: 0.1,
            max: 3.0,
            fd_step: 0.01,
            resolution: 0.1,
        },
        refines: |_| None,
        build: |_, _| Box::new(ControlEffectiveness),
    },
    EffectKind {
        effect: "sensor_bias",
        stage: Stage::Output,
        targets: Targets::SensorColumns,
        param: |column| ParamSpec {
            null: 0.0,
            min: -1e6,
            max: 1e6,
            fd_step: 1e-3,
            resolution: bias_resolution(column),
        },
        refines: |_| None,
        build: |_, _| Box::new(SensorBias),
    },
    EffectKind {
        effect: "sensor_scale",
        stage: Stage::Output,
        targets: Targets::SensorColumns,
        param: |_| ParamSpec {
            null: 1.0,
            min: 0.2,
            max: 5.0,
            fd_step: 0.01,
            resolution: 0.03,
        },
        refines: |_| None,
        build: |_, _| Box::new(SensorScale),
    },
    // Where the accelerometers sit, along one body axis, from the point the model reads its accelerations at: a
    // finding about the record's installation, reported apart from the causes (`super::lever_arm`).
    EffectKind {
        effect: ACCELEROMETER_POSITION,
        stage: Stage::Output,
        targets: Targets::BodyAxes,
        param: |_| ParamSpec {
            null: 0.0,
            min: -50.0,
            max: 50.0,
            fd_step: 0.05,
            resolution: 0.1,
        },
        refines: |_| None,
        build: |axis, _| Box::new(AccelerometerPosition::along(axis)),
    },
    EffectKind {
        effect: "aero_derivative",
        stage: Stage::Model,
        targets: Targets::Derivatives,
        param: |_| ParamSpec {
            null: 1.0,
            min: 0.2,
            max: 4.0,
            fd_step: 0.02,
            resolution: 0.15,
        },
        refines: |_| None,
        build: |_, knob| Box::new(AeroDerivative { knob: knob.into() }),
    },
    EffectKind {
        effect: "aero_nonlinearity",
        stage: Stage::Model,
        targets: Targets::AddedTerms,
        // |k| ≤ 100: at α = 0.2 rad that is a ΔC of 4, far beyond any plausible correction.
        param: |_| ParamSpec {
            null: 0.0,
            min: -100.0,
            max: 100.0,
            fd_step: 0.2,
            resolution: 1.0,
        },
        // `Cm_alpha2` (k α²) refines `Cm_alpha`: around α₀ it adds the slope 2kα₀ and the offset kα₀².
        refines: |term| {
            term.strip_suffix('2')
                .map(|linear| ("aero_derivative", linear.to_string()))
        },
        build: |term, _| Box::new(AeroNonlinearity { term: term.into() }),
    },
];

/// One row of [`REGISTRY`] on one target: the [`Extension`] the search fits.
pub struct Entry {
    kind: &'static EffectKind,
    target: String,
    effect: Box<dyn Effect>,
}

impl Entry {
    /// The row `kind` on `target` (`knob`: the simulation's coefficient name for a derivative).
    pub fn new(kind: &'static EffectKind, target: &str, knob: &str) -> Self {
        Entry {
            kind,
            target: target.to_string(),
            effect: (kind.build)(target, knob),
        }
    }
}

impl Extension for Entry {
    fn effect(&self) -> &'static str {
        self.kind.effect
    }
    fn target(&self) -> &str {
        &self.target
    }
    fn stage(&self) -> Stage {
        self.kind.stage
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![(self.kind.param)(&self.target)]
    }
    fn required_columns(&self) -> Vec<String> {
        self.kind.targets.required_columns(&self.target)
    }
    fn required_one_of(&self) -> Vec<String> {
        if self.kind.targets == Targets::BodyAxes {
            ACCELEROMETERS.iter().map(|c| c.to_string()).collect()
        } else {
            Vec::new()
        }
    }
    fn apply_model(&self, p: &[f64], sim: &mut dyn ReplaySim) -> Result<(), SimError> {
        self.effect.apply_model(p, sim)
    }
    fn apply_input(&self, p: &[f64], surface: &str, dev: &mut [f64], dt_s: f64) {
        if surface == self.target || self.kind.targets == Targets::AllSurfaces {
            self.effect.apply_input(p, dev, dt_s);
        }
    }
    fn apply_output(&self, p: &[f64], rec: &mut FlightRecord) {
        self.effect.apply_output(p, &self.target, rec);
    }
    fn refines(&self) -> Option<(&'static str, String)> {
        (self.kind.refines)(&self.target)
    }
}

/// The coefficient function that carries derivative `target` in a simulation with `coefficient_names`: the first
/// of its [`DERIVATIVE_KNOBS`] names the simulation has (a name not in the table stands for itself); `Err` with
/// the names looked for when it has none.
fn knob_of(target: &str, coefficient_names: &[String]) -> Result<String, String> {
    let names: Vec<&str> = DERIVATIVE_KNOBS
        .iter()
        .find(|(n, _)| *n == target)
        .map_or_else(|| vec![target], |(_, k)| k.to_vec());
    names
        .iter()
        .find(|n| coefficient_names.iter().any(|c| c == *n))
        .map(|n| n.to_string())
        .ok_or_else(|| names.join(", "))
}

/// Builds one extension from its effect and target names (the `--extension` file and the catalogue use it).
pub fn make(
    effect: &str,
    target: &str,
    coefficient_names: &[String],
) -> Result<Box<dyn Extension>, DiagnoseError> {
    let Some(kind) = REGISTRY.iter().find(|k| k.effect == effect) else {
        let known: Vec<&str> = REGISTRY.iter().map(|k| k.effect).collect();
        return Err(DiagnoseError::UnknownExtension(format!(
            "unknown effect '{effect}' (known: {})",
            known.join(", ")
        )));
    };
    match kind.targets {
        Targets::Surfaces if Channel::of_surface(target).is_none() => {
            Err(DiagnoseError::UnknownExtension(format!(
                "{effect} needs a surface target (elevator, aileron, rudder, throttle), got '{target}'"
            )))
        }
        Targets::BodyAxes if !BODY_AXES.contains(&target) => Err(DiagnoseError::UnknownExtension(format!(
            "{effect} needs a body axis target ({}), got '{target}'",
            BODY_AXES.join(", ")
        ))),
        Targets::AllSurfaces if target != ALL_SURFACES => Err(DiagnoseError::UnknownExtension(format!(
            "{effect} acts on every surface at once: its target is '{ALL_SURFACES}', got '{target}'"
        ))),
        Targets::Derivatives => match knob_of(target, coefficient_names) {
            Ok(knob) => Ok(Box::new(Entry::new(kind, target, &knob))),
            Err(looked_for) => Err(DiagnoseError::UnknownExtension(format!(
                "the simulation has no aerodynamic coefficient for '{target}' (looked for {looked_for})"
            ))),
        },
        _ => Ok(Box::new(Entry::new(kind, target, target))),
    }
}

/// A catalogue entry left out: (effect, target, reason).
pub type SkippedEntry = (String, String, String);

/// The full catalogue for a record and a simulation: every row of [`REGISTRY`] on each of its targets.
/// Returns the usable extensions and the skipped ones with the reason.
pub fn catalogue(
    record: &FlightRecord,
    coefficient_names: &[String],
    added_terms: &[String],
) -> (Vec<Box<dyn Extension>>, Vec<SkippedEntry>) {
    let mut all: Vec<Box<dyn Extension>> = Vec::new();
    let mut skipped = Vec::new();
    for kind in &REGISTRY {
        let targets: Vec<(String, String)> = match kind.targets {
            Targets::Surfaces => Channel::CONTROLS
                .iter()
                .filter_map(|c| c.surface())
                .map(|s| (s.to_string(), String::new()))
                .collect(),
            Targets::AllSurfaces => vec![(ALL_SURFACES.to_string(), String::new())],
            Targets::BodyAxes => BODY_AXES
                .iter()
                .map(|a| (a.to_string(), String::new()))
                .collect(),
            Targets::SensorColumns => SENSOR_COLUMNS
                .iter()
                .map(|c| (c.to_string(), String::new()))
                .collect(),
            Targets::Derivatives => DERIVATIVE_KNOBS
                .iter()
                .filter_map(|(name, _)| match knob_of(name, coefficient_names) {
                    Ok(knob) => Some((name.to_string(), knob)),
                    Err(looked_for) => {
                        skipped.push((
                            kind.effect.to_string(),
                            name.to_string(),
                            format!("the simulation has no coefficient function {looked_for}"),
                        ));
                        None
                    }
                })
                .collect(),
            Targets::AddedTerms => added_terms
                .iter()
                .map(|t| (t.clone(), String::new()))
                .collect(),
        };
        all.extend(
            targets
                .iter()
                .map(|(t, k)| Box::new(Entry::new(kind, t, k)) as Box<dyn Extension>),
        );
    }
    let mut usable = Vec::new();
    for e in all {
        let missing: Vec<String> = e
            .required_columns()
            .into_iter()
            .filter(|c| record.column(c).is_none())
            .collect();
        let one_of = e.required_one_of();
        let why = if !missing.is_empty() {
            format!("the data have no column {}", missing.join(", "))
        } else if !one_of.is_empty() && one_of.iter().all(|c| record.column(c).is_none()) {
            format!("the data have none of the columns {}", one_of.join(", "))
        } else {
            usable.push(e);
            continue;
        };
        skipped.push((e.effect().to_string(), e.target().to_string(), why));
    }
    (usable, skipped)
}

mod file;
pub use file::{BuiltEffects, ExtensionFile, FittedEffect};

#[cfg(test)]
mod tests;
