//! Typed errors of the model: every failure says what is wrong and names the parameter,
//! input or joint. The model never panics and never returns NaN or infinity as a result.
//! Each error's console code and message are written here once ([`Message`], from the
//! console protocol crate): the model's `Display` and the firmware's replies both render it.

use core::fmt;

use finger_protocol::message::{Message, Pieces};
use finger_protocol::ErrorCode;

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
    /// `contact`: at this tension the stop would pull on the tip (`force` N along the tip's
    /// approach, > 0): the tip leaves the stop, which can only push.
    PullingStop { tension: f64, force: f64 },
    /// The converged solver did not reach its tolerance.
    NotConverged { iterations: u32, residual: f64 },
    /// A linear system was singular (should not happen on valid parameters).
    Singular { what: &'static str },
    /// A posture the inverse model cannot hold: joint, the compliance it would need and the
    /// range the ceiling allows (rad/N·mm).
    Unreachable { joint: usize, needed: f64, min: f64, max: f64 },
}

impl Message for Error {
    /// Its console code.
    fn code(&self) -> ErrorCode {
        match self {
            Error::Param { .. } => ErrorCode::Usage,
            Error::NonFinite { .. } => ErrorCode::BadNumber,
            Error::Input { .. } => ErrorCode::Usage,
            Error::VoltageCeiling { .. } | Error::ThicknessLimit { .. } | Error::PullIn { .. } => ErrorCode::Limit,
            Error::Contact { .. } | Error::LimitPoint { .. } | Error::ForceLimit { .. } | Error::PullingStop { .. } => ErrorCode::Limit,
            Error::NotConverged { .. } | Error::Singular { .. } => ErrorCode::Fault,
            Error::Unreachable { .. } => ErrorCode::Unreachable,
        }
    }

    /// The one table of the model's messages (exhaustive: a new variant does not compile
    /// without one). `Display` renders it with core's formatting, the firmware with its own
    /// number formats (src/num.rs).
    fn message<P: Pieces + ?Sized>(&self, o: &mut P) {
        match *self {
            Error::Param { name, range } => {
                o.text("parameter ");
                o.text(name);
                o.text(" out of range: ");
                o.text(range);
            }
            Error::NonFinite { input } => {
                o.text(input);
                o.text(" is not a finite number");
            }
            Error::Input { input, reason } => {
                o.text(input);
                o.text(": ");
                o.text(reason);
            }
            Error::VoltageCeiling { joint, volts, ceiling } => {
                o.joint(joint);
                o.text(": ");
                o.fixed(volts, 0);
                o.text(" V is at or past the ceiling ");
                o.fixed(ceiling, 0);
                o.text(" V (33 % pull-in limit with margin, or supply)");
            }
            Error::ThicknessLimit { joint, requested_mm, limit_mm } => {
                o.joint(joint);
                o.text(": stack thickness ");
                o.fixed(requested_mm, 3);
                o.text(" mm is past the 33 % pull-in limit (");
                o.fixed(limit_mm, 3);
                o.text(" mm)");
            }
            Error::PullIn { volts, pull_in } => {
                o.fixed(volts, 0);
                o.text(" V is at or past the film's pull-in ");
                o.fixed(pull_in, 0);
                o.text(" V in its present state");
            }
            Error::Contact { joint, tension } => {
                o.joint(joint);
                o.text(": links in contact (cable span at its floor) at ");
                o.fixed(tension, 3);
                o.text(" N");
            }
            Error::LimitPoint { joint, tension } => {
                o.joint(joint);
                o.text(": equilibrium limit point (singular tangent) at ");
                o.fixed(tension, 3);
                o.text(" N");
            }
            Error::ForceLimit { tension, fmax } => {
                o.text("tension ");
                o.fixed(tension, 3);
                o.text(" N is past the end of the equilibrium branch fmax=");
                // `limits`' digits: the one figure of the limit
                o.fixed(fmax, 4);
                o.text(" N");
            }
            Error::PullingStop { tension, force } => {
                o.text("the stop would pull on the tip (");
                o.fixed(force, 4);
                o.text(" N along its approach) at ");
                o.fixed(tension, 3);
                o.text(" N: the tip leaves it");
            }
            Error::NotConverged { iterations, residual } => {
                o.text("solver did not converge: ");
                o.count(iterations);
                o.text(" iterations, residual ");
                o.exp(residual, 3);
            }
            Error::Singular { what } => {
                o.text("singular ");
                o.text(what);
            }
            Error::Unreachable { joint, needed, min, max } => {
                o.joint(joint);
                o.text(": needs compliance ");
                o.exp(needed, 4);
                o.text(" rad/Nmm, the ceiling allows ");
                o.exp(min, 4);
                o.text("..");
                o.exp(max, 4);
            }
        }
    }
}

impl Error {
    /// Its console code ([`Message::code`], here without importing the trait).
    pub fn code(&self) -> ErrorCode {
        Message::code(self)
    }
}

/// The message with core's formatting (the firmware never calls this: it links core's float
/// formatting; it renders [`Message::message`] with its own numbers).
impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        finger_protocol::message::display(self, f)
    }
}
