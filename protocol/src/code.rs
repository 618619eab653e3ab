//! Error codes: the `<code>` of an `err <code>: <message>` reply (docs/console.md "Error
//! codes"). [`ErrorCode`] has one variant per code; [`ErrorCode::as_str`] and
//! [`ErrorCode::emit`] write it, [`ErrorCode::parse`] and [`ErrorCode::known`] read it.
//!
//! A code is added here: a variant, its index, its text in `NAMES` and its row in `KNOWN` (the
//! compiler asks for the index and the arrays' length); nothing else names the text.
//!
//! What it is not: the reply line around the code ([`crate::reply`]).

use core::fmt;

/// A type with no values: the `S` of [`ErrorCode`] where no unknown code can occur (the
/// firmware emits only codes it knows).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Never {}

impl AsRef<str> for Never {
    fn as_ref(&self) -> &str {
        match *self {}
    }
}

/// An error code. `S` holds the text of a code this crate does not know (a newer firmware's):
/// `&str` borrowed from a line, `String` in a client that keeps it, or [`Never`] (the
/// default: the firmware, where every code is one of these).
///
/// Its layout is the firmware's flash: a word whose values (`u32::MAX - 12..=u32::MAX`) leave
/// 0 free, so a `Result<T, E>` of an error `E` holding a code (the firmware's `CmdError`) is
/// `Ok` when that word is 0, read with its payload in one load and tested by one
/// compare-with-zero, as a `&'static str` code was (the Cortex-M3 image's budget).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[repr(u32)]
pub enum ErrorCode<S = Never> {
    /// A command this build does not have.
    Unknown = u32::MAX - 11,
    /// Wrong arguments, a value outside its range.
    Usage,
    /// A number that does not parse (NaN, infinity, hex, trailing characters).
    BadNumber,
    /// A line longer than the receive buffer.
    TooLong,
    /// A voltage, force or thinning at or past its limit; a save that would raise the ceiling.
    Limit,
    /// `volt` or `force` while disarmed.
    NotArmed,
    /// A change that needs disarmed, while armed.
    Armed,
    /// `pose`: no tension and voltages inside the ceilings hold the posture.
    Unreachable,
    /// A line lost while receiving.
    Overrun,
    /// A line received before a `stop` and dropped by it.
    Stopped,
    /// A latched fault, or the model did not converge.
    Fault,
    /// The settings store's flash failed.
    Store,
    /// A code not listed here (a newer firmware's), as it came.
    Other(S) = u32::MAX - 12,
}

/// Each known code's text, in the order of docs/console.md's table: the row of a code is its
/// [`ErrorCode::index`].
const NAMES: [&str; 12] = ["unknown", "usage", "bad-number", "too-long", "limit", "not-armed", "armed", "unreachable", "overrun", "stopped", "fault", "store"];

/// `NAMES` end to end, and where each ends: what the image holds (one string and 13 bytes, not
/// 12 string slices: the Cortex-M3 image's flash). The build checks it is `NAMES`.
const TEXT: &str = "unknownusagebad-numbertoo-longlimitnot-armedarmedunreachableoverrunstoppedfaultstore";
const ENDS: [u8; NAMES.len() + 1] = ends(TEXT, &NAMES);

/// Where each of `names` ends in `text` (their concatenation; the build fails otherwise).
pub(crate) const fn ends<const N: usize, const M: usize>(text: &str, names: &[&str; N]) -> [u8; M] {
    assert!(M == N + 1);
    let mut ends = [0u8; M];
    let (t, mut at, mut i) = (text.as_bytes(), 0, 0);
    while i < N {
        let n = names[i].as_bytes();
        let mut j = 0;
        while j < n.len() {
            assert!(at + j < t.len() && t[at + j] == n[j], "the text is not the names end to end");
            j += 1;
        }
        at += n.len();
        ends[i + 1] = at as u8;
        i += 1;
    }
    assert!(at == t.len(), "the text is not the names end to end");
    ends
}

impl<S> ErrorCode<S> {
    /// The known codes by row (the row of each is its [`ErrorCode::index`]).
    const KNOWN: [ErrorCode<S>; NAMES.len()] = [
        ErrorCode::Unknown,
        ErrorCode::Usage,
        ErrorCode::BadNumber,
        ErrorCode::TooLong,
        ErrorCode::Limit,
        ErrorCode::NotArmed,
        ErrorCode::Armed,
        ErrorCode::Unreachable,
        ErrorCode::Overrun,
        ErrorCode::Stopped,
        ErrorCode::Fault,
        ErrorCode::Store,
    ];
}

impl ErrorCode {
    /// Every known code, in the order of docs/console.md's table.
    pub const ALL: [ErrorCode; NAMES.len()] = Self::KNOWN;
}

impl<S> ErrorCode<S> {
    /// The row of a known code in `NAMES` (exhaustive: a new variant does not compile without
    /// its row); `None` for [`ErrorCode::Other`].
    pub const fn index(&self) -> Option<usize> {
        Some(match self {
            ErrorCode::Unknown => 0,
            ErrorCode::Usage => 1,
            ErrorCode::BadNumber => 2,
            ErrorCode::TooLong => 3,
            ErrorCode::Limit => 4,
            ErrorCode::NotArmed => 5,
            ErrorCode::Armed => 6,
            ErrorCode::Unreachable => 7,
            ErrorCode::Overrun => 8,
            ErrorCode::Stopped => 9,
            ErrorCode::Fault => 10,
            ErrorCode::Store => 11,
            ErrorCode::Other(_) => return None,
        })
    }

    /// The code's text, as the wire has it.
    pub fn as_str(&self) -> &str
    where
        S: AsRef<str>,
    {
        match (self.index(), self) {
            (Some(i), _) => TEXT.get(ENDS[i] as usize..ENDS[i + 1] as usize).unwrap_or(""),
            (None, ErrorCode::Other(s)) => s.as_ref(),
            (None, _) => "",
        }
    }

    /// Write the code's text.
    pub fn emit(&self, w: &mut dyn fmt::Write) -> fmt::Result
    where
        S: AsRef<str>,
    {
        w.write_str(self.as_str())
    }

    /// A known code from its text (exact, lowercase as the board sends it); `None` for any
    /// other text.
    pub fn known(text: &str) -> Option<ErrorCode<S>> {
        let i = NAMES.iter().position(|n| *n == text)?;
        Self::KNOWN.into_iter().nth(i)
    }

    /// A code from its text: a known one, or [`ErrorCode::Other`] holding the text.
    pub fn parse<'a>(text: &'a str) -> ErrorCode<S>
    where
        S: From<&'a str>,
    {
        Self::known(text).unwrap_or_else(|| ErrorCode::Other(S::from(text)))
    }

    /// The known code, if this is one, as the firmware's type.
    pub fn to_known(&self) -> Option<ErrorCode> {
        self.index().map(|i| ErrorCode::ALL[i])
    }
}

impl<S: AsRef<str>> fmt::Display for ErrorCode<S> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}
