//! The console contract (docs/console.md) seen from the host: one command line out, the
//! lines before its final reply and the final `ok ...` or `err <code>: ...` back, typed.
//! Not here: how bytes travel (`link.rs`).
use std::time::Duration;

use finger_protocol::reply::{Fields, Item};
use finger_protocol::Value;

use crate::link::{Link, LinkError};

/// The error codes of docs/console.md (the protocol crate's [`finger_protocol::ErrorCode`]),
/// and any other code a newer firmware may add, kept as it came.
pub type ErrorCode = finger_protocol::ErrorCode<String>;

/// A successful reply: the `key=value` fields of the final `ok` line, and the lines before it.
#[derive(Clone, Debug, PartialEq)]
pub struct Reply {
    pub before: Vec<String>,
    pub line: String,
}

impl Reply {
    /// The `ok` line's fields, read by the protocol crate (none for a line that is not one).
    fn parsed(&self) -> Fields<'_> {
        match finger_protocol::Reply::parse(&self.line) {
            Ok(finger_protocol::Reply::Ok(f)) => f,
            _ => Fields::new(""),
        }
    }

    /// The value of `key` in the `ok` line.
    pub fn get(&self, key: &str) -> Option<&str> {
        self.parsed().text(key)
    }

    /// The comma-separated numbers of `key` (`volts=1.0,2.0,3.0`); `None` when a component is
    /// not a number.
    pub fn numbers(&self, key: &str) -> Option<Vec<f64>> {
        Value::of_syntax(self.get(key)?).numbers().collect()
    }

    /// As [`Reply::numbers`], a component not measured yet (`-`) as NaN.
    pub fn measured(&self, key: &str) -> Option<Vec<f64>> {
        let list = match Value::of_syntax(self.get(key)?) {
            Value::List(l) => l,
            v => return v.number().map(|x| vec![x]).or_else(|| (v == Value::Missing).then(|| vec![f64::NAN])),
        };
        list.items().map(|i| if i == Item::Missing { Some(f64::NAN) } else { i.number() }).collect()
    }

    /// Every `key=value` field, in order.
    pub fn fields(&self) -> impl Iterator<Item = (&str, &str)> {
        self.parsed().pairs()
    }
}

/// Why a command did not give a reply.
#[derive(Debug)]
pub enum CommandError {
    /// The board refused: `err <code>: <message>`.
    Board {
        code: ErrorCode,
        message: String,
    },
    Link(LinkError),
}

impl std::fmt::Display for CommandError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CommandError::Board { code, message } => write!(f, "err {}: {message}", code.as_str()),
            CommandError::Link(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for CommandError {}

impl From<LinkError> for CommandError {
    fn from(e: LinkError) -> Self {
        CommandError::Link(e)
    }
}

/// A board's console: one command at a time, each answered within `timeout`.
pub struct Console {
    link: Link,
    pub timeout: Duration,
}

/// The longest reply a `wait <s>` may take beyond its own duration.
const WAIT_SLACK: Duration = Duration::from_secs(5);

impl Console {
    pub fn new(link: Link, timeout: Duration) -> Console {
        Console { link, timeout }
    }

    /// Send one command line; its reply. A line with a newline inside is refused here, since
    /// the board would answer each part.
    pub fn command(&mut self, line: &str) -> Result<Reply, CommandError> {
        let line = line.trim();
        if line.contains(['\r', '\n']) {
            return Err(CommandError::Board { code: ErrorCode::Usage, message: "one command per line".into() });
        }
        if line.is_empty() {
            return Ok(Reply { before: Vec::new(), line: String::new() });
        }
        self.link.send(format!("{line}\r\n").as_bytes())?;
        let timeout = self.timeout + wait_duration(line).map_or(Duration::ZERO, |w| w + WAIT_SLACK);
        let mut before = Vec::new();
        loop {
            let l = self.link.line(timeout)?;
            match finger_protocol::Reply::parse(&l) {
                Ok(finger_protocol::Reply::Ok(_)) => return Ok(Reply { before, line: l }),
                Ok(finger_protocol::Reply::Err { code, message }) => {
                    return Err(CommandError::Board { code: ErrorCode::parse(code.as_str()), message: message.to_owned() });
                }
                // an `err` line without `<code>:`: its words as the code, no message
                Err(finger_protocol::reply::Error::NoCode) => {
                    let code = l.strip_prefix("err ").unwrap_or(&l).trim();
                    return Err(CommandError::Board { code: ErrorCode::parse(code), message: String::new() });
                }
                // an ok line with a field without its key: still the final line
                Err(finger_protocol::reply::Error::BadValue | finger_protocol::reply::Error::NotAField) => return Ok(Reply { before, line: l }),
                Err(finger_protocol::reply::Error::NotFinal) => before.push(l),
            }
        }
    }
}

/// The duration of a `wait <s>` command, which the board answers only when it ends.
fn wait_duration(line: &str) -> Option<Duration> {
    let mut w = line.split_whitespace();
    if finger_protocol::Command::parse(w.next()?.to_ascii_lowercase().as_bytes()) != Some(finger_protocol::Command::Wait) {
        return None;
    }
    let s: f64 = w.next()?.parse().ok()?;
    (s.is_finite() && s >= 0.0).then(|| Duration::from_secs_f64(s.min(3600.0)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_and_numbers_of_an_ok_line() {
        let r = Reply { before: vec![], line: "ok force=0.500 volts=1.0,2.0,3.0 armed=1".into() };
        assert_eq!(r.get("force"), Some("0.500"));
        assert_eq!(r.get("forc"), None);
        assert_eq!(r.numbers("volts"), Some(vec![1.0, 2.0, 3.0]));
        assert_eq!(r.fields().count(), 3);
    }

    #[test]
    fn error_codes_round_trip() {
        for c in ["unknown", "usage", "bad-number", "too-long", "limit", "not-armed", "armed", "unreachable", "fault", "overrun", "stopped", "new-one"] {
            assert_eq!(ErrorCode::parse(c).as_str(), c);
        }
        assert_eq!(ErrorCode::parse("limit"), ErrorCode::Limit);
        assert_eq!(ErrorCode::parse("stopped"), ErrorCode::Stopped);
    }

    #[test]
    fn wait_extends_the_time_out() {
        assert_eq!(wait_duration("WAIT 2.5"), Some(Duration::from_millis(2500)));
        assert_eq!(wait_duration("status"), None);
        assert_eq!(wait_duration("wait nan"), None);
    }
}
