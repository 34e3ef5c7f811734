//! How an error ends the process: each error type says its own exit code.
//!
//! 0 is success; [`FAILURE`] (1) is a failure of the work (the simulator, a numerical step, the file system);
//! [`BAD_INPUT`] (2) is bad usage or bad input (a file, an option, a name the user gave). The binary takes the
//! code of the outermost error in a chain whose type implements [`ExitCode`] (see `cli::exit_code`).

/// Exit code of a failure of the work.
pub const FAILURE: u8 = 1;
/// Exit code of bad usage or bad input.
pub const BAD_INPUT: u8 = 2;

/// An error that knows the process exit code it ends with.
pub trait ExitCode {
    /// [`BAD_INPUT`] when the user's input is at fault, [`FAILURE`] otherwise.
    fn exit_code(&self) -> u8;
}

/// Errors that are always the user's input: a data file, an aircraft or airframe file, a number out of its
/// range, a paper option.
macro_rules! always_bad_input {
    ($($t:ty),+ $(,)?) => {
        $(impl ExitCode for $t {
            fn exit_code(&self) -> u8 {
                BAD_INPUT
            }
        })+
    };
}

always_bad_input!(
    crate::data::DataError,
    crate::aircraft::AircraftError,
    crate::limits::LimitError,
    crate::aero::airframe::AirframeError,
    crate::paper::PaperError,
);

impl ExitCode for crate::sim::SimError {
    /// A crash, a failed trim or a bridge error says nothing about the user's input; a loading the model
    /// cannot take does.
    fn exit_code(&self) -> u8 {
        match self {
            Self::Loading(_) => BAD_INPUT,
            _ => FAILURE,
        }
    }
}

impl ExitCode for crate::report::ReportError {
    fn exit_code(&self) -> u8 {
        match self {
            Self::Refused { .. } => BAD_INPUT,
            Self::Plot { .. } | Self::Io { .. } => FAILURE,
        }
    }
}

impl ExitCode for crate::campaign::CampaignError {
    /// A malformed or meaningless campaign file, or a file that does not exist, is bad input.
    fn exit_code(&self) -> u8 {
        match self {
            Self::Parse { .. } | Self::Invalid { .. } => BAD_INPUT,
            Self::Io { path, .. } if !path.exists() => BAD_INPUT,
            Self::Io { .. } | Self::Run(_) => FAILURE,
        }
    }
}

impl ExitCode for crate::compare::CompareError {
    fn exit_code(&self) -> u8 {
        match self {
            Self::Options(_) => BAD_INPUT,
            Self::Data(e) => e.exit_code(),
            Self::Sim { source, .. } => source.exit_code(),
        }
    }
}

impl ExitCode for crate::diagnose::DiagnoseError {
    fn exit_code(&self) -> u8 {
        match self {
            Self::Sim { source, .. } => source.exit_code(),
            Self::Report(e) => e.exit_code(),
            Self::Aircraft(e) => e.exit_code(),
            Self::TooShort(_)
            | Self::BadData(_)
            | Self::UnknownExtension(_)
            | Self::ExtensionFile { .. }
            | Self::LinearModelFile { .. } => BAD_INPUT,
        }
    }
}

impl ExitCode for crate::aero::AeroError {
    fn exit_code(&self) -> u8 {
        match self {
            Self::BadParameter { .. }
            | Self::UnknownDerivative(_)
            | Self::WrongTfOrder { .. }
            | Self::BadCovariance { .. }
            | Self::NothingToFit(_)
            | Self::BadRecord(_)
            | Self::BadInput(_) => BAD_INPUT,
            Self::Sim(e) => e.exit_code(),
            Self::Numerical(_) | Self::Ident { .. } => FAILURE,
        }
    }
}

impl ExitCode for crate::estimate::EstimateError {
    /// A record that does not fit the model is bad input; an inconsistent problem, a diverging start or a
    /// singular information matrix is a failure of the estimate.
    fn exit_code(&self) -> u8 {
        match self {
            Self::Record { .. } => BAD_INPUT,
            Self::Invalid(_)
            | Self::StartDiverges { .. }
            | Self::Singular(_)
            | Self::Diverged { .. }
            | Self::NotConverged { .. } => FAILURE,
        }
    }
}

impl ExitCode for crate::aero::measured::MeasuredError {
    fn exit_code(&self) -> u8 {
        match self {
            Self::Airframe(e) => e.exit_code(),
            Self::Record { .. } => BAD_INPUT,
            Self::Aero(e) => e.exit_code(),
            Self::Estimate(e) => e.exit_code(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::SimError;

    #[test]
    fn a_crash_inside_a_wrapper_is_a_failure_and_bad_options_are_bad_input() {
        let crash = SimError::Crashed {
            during: "fly".into(),
            status: "signal 9".into(),
            last_output: String::new(),
        };
        let diagnose = crate::diagnose::DiagnoseError::Sim {
            during: "baseline".into(),
            source: crash,
        };
        assert_eq!(diagnose.exit_code(), FAILURE);
        let options = crate::compare::CompareError::Options("--amplitude-deg 0".into());
        assert_eq!(options.exit_code(), BAD_INPUT);
        let missing = crate::campaign::CampaignError::Io {
            path: "/no/such/campaign.toml".into(),
            source: std::io::Error::from(std::io::ErrorKind::NotFound),
        };
        assert_eq!(missing.exit_code(), BAD_INPUT);
        let record = crate::aero::measured::MeasuredError::Estimate(
            crate::estimate::EstimateError::Record {
                record: "a.csv".into(),
                reason: "2 samples".into(),
            },
        );
        assert_eq!(record.exit_code(), BAD_INPUT);
    }
}
