//! Typed errors of the model: every failure says what is wrong and names the parameter,
//! input or joint. The model never panics and never returns NaN or infinity as a result.

use core::fmt;

/// What went wrong, with the name of the offending parameter or input.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Error {
    /// A parameter is outside its valid range. `range` is a human-readable statement of it.
    Param { name: &'static str, range: &'static str },
    /// An input is NaN or infinite.
    NonFinite { input: &'static str },
    /// An input is outside its domain (negative tension, wrong number of channels, ...).
    Input { input: &'static str, reason: &'static str },
    /// A channel voltage at or past its ceiling (min(margin x V_pi, supply)).
    VoltageCeiling { joint: usize, volts: f64, ceiling: f64 },
    /// A requested stack thickness beyond the 33 % pull-in limit (z < 2/3 z0), e.g. the
    /// paper's "2 mm to 1 mm".
    ThicknessLimit { joint: usize, requested_mm: f64, limit_mm: f64 },
    /// A film voltage at or past the film's pull-in in its present state (the stable branch of
    /// the film balance ends at `pull_in` volts).
    PullIn { volts: f64, pull_in: f64 },
    /// A cable span closed to its floor: the links touch (contact) at this joint.
    Contact { joint: usize, tension: f64 },
    /// The equilibrium branch ends (limit point: singular tangent) before this tension.
    LimitPoint { joint: usize, tension: f64 },
    /// A tension past the end of the equilibrium branch (contact or limit point).
    ForceLimit { tension: f64, fmax: f64 },
    /// The converged solver did not reach its tolerance.
    NotConverged { iterations: u32, residual: f64 },
    /// A linear system was singular (should not happen on valid parameters).
    Singular { what: &'static str },
    /// A posture the inverse model cannot hold: joint, the compliance it would need and the
    /// range the ceiling allows (rad/N·mm).
    Unreachable { joint: usize, needed: f64, min: f64, max: f64 },
}

impl Error {
    /// A short code, as the console uses.
    pub fn code(&self) -> &'static str {
        match self {
            Error::Param { .. } => "usage",
            Error::NonFinite { .. } => "bad-number",
            Error::Input { .. } => "usage",
            Error::VoltageCeiling { .. } | Error::ThicknessLimit { .. } | Error::PullIn { .. } => "limit",
            Error::Contact { .. } | Error::LimitPoint { .. } | Error::ForceLimit { .. } => "limit",
            Error::NotConverged { .. } | Error::Singular { .. } => "fault",
            Error::Unreachable { .. } => "unreachable",
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Error::Param { name, range } => write!(f, "parameter {name} out of range: {range}"),
            Error::NonFinite { input } => write!(f, "{input} is not a finite number"),
            Error::Input { input, reason } => write!(f, "{input}: {reason}"),
            Error::VoltageCeiling { joint, volts, ceiling } => write!(
                f,
                "joint {joint}: {volts:.0} V is at or past the ceiling {ceiling:.0} V (33 % pull-in limit with margin, or supply)"
            ),
            Error::ThicknessLimit { joint, requested_mm, limit_mm } => write!(
                f,
                "joint {joint}: stack thickness {requested_mm:.3} mm is past the 33 % pull-in limit ({limit_mm:.3} mm)"
            ),
            Error::PullIn { volts, pull_in } => {
                write!(f, "{volts:.0} V is at or past the film's pull-in {pull_in:.0} V in its present state")
            }
            Error::Contact { joint, tension } => {
                write!(f, "joint {joint}: links in contact (cable span at its floor) at {tension:.3} N")
            }
            Error::LimitPoint { joint, tension } => {
                write!(f, "joint {joint}: equilibrium limit point (singular tangent) at {tension:.3} N")
            }
            Error::ForceLimit { tension, fmax } => {
                write!(f, "tension {tension:.3} N is past the end of the equilibrium branch fmax={fmax:.3} N")
            }
            Error::NotConverged { iterations, residual } => {
                write!(f, "solver did not converge: {iterations} iterations, residual {residual:.3e}")
            }
            Error::Singular { what } => write!(f, "singular {what}"),
            Error::Unreachable { joint, needed, min, max } => write!(
                f,
                "joint {joint}: needs compliance {needed:.4e} rad/Nmm, the ceiling allows {min:.4e}..{max:.4e}"
            ),
        }
    }
}
