//! Records as the core sees them, and the reconstruction of sampled inputs between samples.

/// How a sampled input is reconstructed between its samples.
///
/// Which one matters: on a real 25 Hz elevator record a 2-state short-period model fitted with a
/// zero-order hold moves M_α, M_q and M_δe by +5 % against linear interpolation (the convention of
/// the field's reference implementations, e.g. FVSysID's `interp1`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum InputHold {
    /// Straight line between consecutive samples (default).
    #[default]
    Linear,
    /// Each sample held until the next one (zero-order hold).
    Zoh,
}

impl std::str::FromStr for InputHold {
    type Err = String;
    fn from_str(s: &str) -> Result<InputHold, String> {
        match s.to_ascii_lowercase().as_str() {
            "linear" => Ok(InputHold::Linear),
            "zoh" => Ok(InputHold::Zoh),
            other => Err(format!(
                "unknown input hold '{other}' (expected linear or zoh)"
            )),
        }
    }
}

/// One measured record in the model's terms: inputs and outputs in signature order.
#[derive(Clone, Debug, PartialEq)]
pub struct Record {
    /// Name shown in results (usually the file).
    pub name: String,
    /// Sample times, s, strictly increasing.
    pub time_s: Vec<f64>,
    /// Measured inputs, `[input][k]`.
    pub inputs: Vec<Vec<f64>>,
    /// Measured outputs, `[output][k]`.
    pub outputs: Vec<Vec<f64>>,
    /// Initial state: measured, or the start value when it is estimated.
    pub initial_state: Vec<f64>,
}

impl Record {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.time_s.len()
    }

    /// True when the record has no samples.
    pub fn is_empty(&self) -> bool {
        self.time_s.is_empty()
    }

    /// Duration, s.
    pub fn duration_s(&self) -> f64 {
        match (self.time_s.first(), self.time_s.last()) {
            (Some(a), Some(b)) => b - a,
            _ => 0.0,
        }
    }

    /// The `inputs` and `outputs` columns of a flight record (initial state empty: for models
    /// without named states, such as a subspace fit).
    pub fn from_columns(
        rec: &crate::data::FlightRecord,
        inputs: &[String],
        outputs: &[String],
        name: &str,
    ) -> Result<Record, super::EstimateError> {
        let take = |cols: &[String], what: &str| {
            cols.iter()
                .map(|c| {
                    rec.column(c)
                        .map(<[f64]>::to_vec)
                        .ok_or_else(|| super::EstimateError::Record {
                            record: name.to_string(),
                            reason: format!("{what} '{c}' is not a column"),
                        })
                })
                .collect::<Result<Vec<_>, _>>()
        };
        Ok(Record {
            name: name.to_string(),
            time_s: rec.time_s.clone(),
            inputs: take(inputs, "input")?,
            outputs: take(outputs, "output")?,
            initial_state: Vec::new(),
        })
    }

    /// Median sample interval, s.
    pub fn median_dt_s(&self) -> f64 {
        let mut d: Vec<f64> = self.time_s.windows(2).map(|w| w[1] - w[0]).collect();
        if d.is_empty() {
            return 0.0;
        }
        d.sort_by(f64::total_cmp);
        d[d.len() / 2]
    }
}

/// A record's inputs as a function of time: measured samples, minus the input biases, delayed by
/// the input skews, reconstructed between samples by the declared hold.
///
/// `u_model,i(t) = u_meas,i(t − τ_i) − b_i`; before the first sample (or after the last) the end
/// value is held.
#[derive(Clone, Debug)]
pub struct InputSignal<'a> {
    time_s: &'a [f64],
    channels: &'a [Vec<f64>],
    bias: Vec<f64>,
    skew_s: Vec<f64>,
    hold: InputHold,
}

impl<'a> InputSignal<'a> {
    /// The signal of `channels` sampled at `time_s`, with per-channel biases and skews.
    pub fn new(
        time_s: &'a [f64],
        channels: &'a [Vec<f64>],
        bias: Vec<f64>,
        skew_s: Vec<f64>,
        hold: InputHold,
    ) -> InputSignal<'a> {
        InputSignal {
            time_s,
            channels,
            bias,
            skew_s,
            hold,
        }
    }

    /// The plain measured signal (no bias, no skew).
    pub fn measured(time_s: &'a [f64], channels: &'a [Vec<f64>], hold: InputHold) -> Self {
        let n = channels.len();
        InputSignal::new(time_s, channels, vec![0.0; n], vec![0.0; n], hold)
    }

    /// Number of input channels.
    pub fn n_inputs(&self) -> usize {
        self.channels.len()
    }

    /// The declared hold.
    pub fn hold(&self) -> InputHold {
        self.hold
    }

    /// The per-channel skews, s.
    pub fn skew_s(&self) -> &[f64] {
        &self.skew_s
    }

    /// The inputs at the sample times (biases removed) when no channel is skewed; `None`
    /// otherwise (then use [`InputSignal::at`]).
    pub fn aligned_samples(&self) -> Option<Vec<Vec<f64>>> {
        if self.skew_s.iter().any(|s| *s != 0.0) {
            return None;
        }
        Some(
            self.channels
                .iter()
                .zip(&self.bias)
                .map(|(c, b)| c.iter().map(|v| v - b).collect())
                .collect(),
        )
    }

    /// Value and slope of channel `i` at `t_s`, on the piece of the reconstruction that contains
    /// `t_s` (at a breakpoint, the piece to the right).
    fn piece_at(&self, i: usize, t_s: f64) -> (f64, f64) {
        let times = self.time_s;
        let values = &self.channels[i];
        let local = t_s - self.skew_s[i];
        let n = times.len();
        let j = times.partition_point(|&t| t <= local);
        let bias = self.bias[i];
        if j == 0 {
            return (values[0] - bias, 0.0);
        }
        if j >= n {
            return (values[n - 1] - bias, 0.0);
        }
        let k = j - 1;
        match self.hold {
            InputHold::Zoh => (values[k] - bias, 0.0),
            InputHold::Linear => {
                let slope = (values[k + 1] - values[k]) / (times[k + 1] - times[k]);
                (values[k] - bias + slope * (local - times[k]), slope)
            }
        }
    }

    /// All inputs at time `t_s` (right-continuous at a zero-order hold's steps).
    pub fn at(&self, t_s: f64, u: &mut [f64]) {
        for (i, ui) in u.iter_mut().enumerate() {
            *ui = self.piece_at(i, t_s).0;
        }
    }

    /// The affine piece `u(t) = a + b (t − t_mid_s)` of every channel on the open interval around
    /// `t_mid_s` between two breakpoints (what an integrator step inside that interval should see,
    /// endpoints included as limits).
    pub fn piece(&self, t_mid_s: f64, a: &mut [f64], b: &mut [f64]) {
        for i in 0..self.channels.len() {
            let (ai, bi) = self.piece_at(i, t_mid_s);
            a[i] = ai;
            b[i] = bi;
        }
    }

    /// The first breakpoint of any channel (a sample time shifted by that channel's skew)
    /// strictly after `t_s`.
    pub fn next_breakpoint(&self, t_s: f64) -> Option<f64> {
        let mut best: Option<f64> = None;
        for skew in &self.skew_s {
            let local = t_s - skew;
            let j = self.time_s.partition_point(|&t| t <= local);
            if let Some(t) = self.time_s.get(j) {
                let bp = t + skew;
                best = Some(best.map_or(bp, |b| b.min(bp)));
            }
        }
        best
    }
}

/// One record as a model simulates it.
#[derive(Clone, Debug)]
pub struct Run<'a> {
    /// Index of the record in the fit (for models that keep per-record state, e.g. a trim).
    pub record: usize,
    /// Output sample times, s.
    pub time_s: &'a [f64],
    /// The inputs between and at the samples.
    pub input: InputSignal<'a>,
    /// Largest integration step, s (the integrator also stops at every sample and breakpoint).
    pub max_step_s: f64,
}
