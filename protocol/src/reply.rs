//! A final reply line (docs/console.md "Lines"): `ok`, `ok k=v k=v ...` or `err <code>:
//! <message>`. [`Reply::parse`] reads one in place, [`Reply::emit`] writes one; a field's
//! value reads by its declared [`Kind`] ([`crate::field`]) or, undeclared, by its syntax.
//!
//! A value with a space (a fault's name) runs to the next `key=` word ([`Fields`]).
//!
//! What it is not: the lines before a final line (`help`, the `param` list), or the
//! commands.

use core::fmt;

use crate::field::{field, Kind};
use crate::ErrorCode;

/// A final reply line, parsed in place.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reply<'a> {
    /// `ok` and its `key=value` fields.
    Ok(Fields<'a>),
    /// `err <code>: <message>`, the message for a human.
    Err { code: ErrorCode<&'a str>, message: &'a str },
}

/// Why a line is not a final reply.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Error {
    /// Neither `ok` nor `err ` at its start: a line before a final line (or noise).
    NotFinal,
    /// An `err` line without `<code>:`.
    NoCode,
    /// A word of an `ok` line that is not `key=value` (its text).
    NotAField,
    /// A declared field whose value does not read as its kind ([`Fields::check`]).
    BadValue,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Error::NotFinal => "not a final reply line (ok ... / err <code>: ...)",
            Error::NoCode => "an err line without <code>:",
            Error::NotAField => "a field of an ok line with an empty key",
            Error::BadValue => "a field whose value does not read as its kind",
        })
    }
}

/// The head of an error reply, `err <code>: `; the message follows.
pub fn emit_err_head<S: AsRef<str>>(w: &mut dyn fmt::Write, code: &ErrorCode<S>) -> fmt::Result {
    w.write_str("err ")?;
    code.emit(w)?;
    w.write_str(": ")
}

impl<'a> Reply<'a> {
    /// A final line (without its line ending; surrounding spaces are ignored). Its grammar
    /// only: a field's value is read when asked for ([`Fields::get`]; [`Fields::check`] reads
    /// them all), so a client reads what it knows of a newer firmware's line.
    pub fn parse(line: &'a str) -> Result<Reply<'a>, Error> {
        let line = line.trim();
        if let Some(rest) = line.strip_prefix("err ") {
            let (code, message) = rest.split_once(':').ok_or(Error::NoCode)?;
            let code = code.trim();
            if code.is_empty() || code.contains(char::is_whitespace) {
                return Err(Error::NoCode);
            }
            return Ok(Reply::Err { code: ErrorCode::parse(code), message: message.trim() });
        }
        let rest = match line.strip_prefix("ok") {
            Some(r) if r.is_empty() || r.starts_with(char::is_whitespace) => r.trim_start(),
            _ => return Err(Error::NotFinal),
        };
        let fields = Fields(rest);
        if fields.raw().any(|(k, _)| k.is_empty()) {
            return Err(Error::NotAField);
        }
        Ok(Reply::Ok(fields))
    }

    /// Write the line (without a line ending): `ok`, `ok <fields>`, `err <code>: <message>`.
    pub fn emit(&self, w: &mut dyn fmt::Write) -> fmt::Result {
        match self {
            Reply::Ok(f) if f.0.is_empty() => w.write_str("ok"),
            Reply::Ok(f) => {
                w.write_str("ok ")?;
                w.write_str(f.0)
            }
            Reply::Err { code, message } => {
                emit_err_head(w, code)?;
                w.write_str(message)
            }
        }
    }

    /// The fields of an `ok` line (`None` for an `err`).
    pub fn fields(&self) -> Option<Fields<'a>> {
        match self {
            Reply::Ok(f) => Some(*f),
            Reply::Err { .. } => None,
        }
    }
}

/// The fields of a line, read in place: each word `key=value` starts a field; a word without
/// `=` continues the value before it (a fault's name with a space, `fault=board card`), or
/// before any field is a field of its own with an empty value (`ok stopped`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Fields<'a>(&'a str);

impl<'a> Fields<'a> {
    pub fn new(text: &'a str) -> Self {
        Fields(text)
    }

    /// The text they are read from.
    pub fn as_str(&self) -> &'a str {
        self.0
    }

    /// Every field, in order, as text: key and value.
    pub fn raw(&self) -> Raw<'a> {
        Raw { rest: self.0 }
    }

    /// The `key=value` fields as text, without the words before any field (`ok stopped`'s).
    pub fn pairs(self) -> impl Iterator<Item = (&'a str, &'a str)> + 'a {
        let text = self.0;
        self.raw().filter(move |(k, _)| {
            let end = k.as_ptr() as usize - text.as_ptr() as usize + k.len();
            text.as_bytes().get(end) == Some(&b'=')
        })
    }

    /// Every declared field reads as its kind ([`crate::field::FIELDS`]): what the firmware's
    /// tests hold each reply to.
    pub fn check(&self) -> Result<(), Error> {
        for (k, v) in self.raw() {
            Value::read(k, v).ok_or(Error::BadValue)?;
        }
        Ok(())
    }

    /// Every field, in order, its value read (a declared field whose value does not read as
    /// its kind: as its syntax).
    pub fn iter(&self) -> impl Iterator<Item = (&'a str, Value<'a>)> {
        self.raw().map(|(k, v)| (k, Value::read(k, v).unwrap_or_else(|| Value::of_syntax(v))))
    }

    /// The text of `key`'s value (the first, if repeated).
    pub fn text(&self, key: &str) -> Option<&'a str> {
        self.raw().find(|(k, _)| *k == key).map(|(_, v)| v)
    }

    /// `key`'s value, read; `None` when absent or not reading as its declared kind.
    pub fn get(&self, key: &str) -> Option<Value<'a>> {
        Value::read(key, self.text(key)?)
    }
}

/// The fields of a line as text ([`Fields::raw`]).
pub struct Raw<'a> {
    rest: &'a str,
}

impl<'a> Iterator for Raw<'a> {
    type Item = (&'a str, &'a str);

    fn next(&mut self) -> Option<(&'a str, &'a str)> {
        let s = self.rest.trim_start();
        if s.is_empty() {
            self.rest = s;
            return None;
        }
        let word_end = |t: &str| t.find(char::is_whitespace).unwrap_or(t.len());
        let first = &s[..word_end(s)];
        let Some(eq) = first.find('=') else {
            // a word before any field
            self.rest = &s[first.len()..];
            return Some((first, ""));
        };
        // the value runs over the words without `=` that follow
        let mut end = first.len();
        loop {
            let after = &s[end..];
            let next = after.trim_start();
            let w = &next[..word_end(next)];
            // (never past the line's end: one line's fields)
            if w.is_empty() || w.contains('=') || after[..after.len() - next.len()].contains(['\n', '\r']) {
                break;
            }
            end = s.len() - next.len() + w.len();
        }
        self.rest = &s[end..];
        Some((&s[..eq], &s[eq + 1..end]))
    }
}

/// A field's value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value<'a> {
    /// One number.
    Number(f64),
    /// `-`: none (not measured, no time).
    Missing,
    /// One word.
    Word(&'a str),
    /// Comma-separated components.
    List(List<'a>),
}

impl<'a> Value<'a> {
    /// `text` as the value of `key`: by the key's declared kind, else by its syntax. `None`
    /// when a declared field's text does not read as its kind.
    pub fn read(key: &str, text: &'a str) -> Option<Value<'a>> {
        let Some(f) = field(key) else { return Some(Self::of_syntax(text)) };
        match f.kind {
            Kind::Number if text == "-" => Some(Value::Missing),
            Kind::Number => number(text).map(Value::Number),
            Kind::Numbers => {
                let l = List(text);
                l.items().all(|i| !matches!(i, Item::Word(_))).then_some(Value::List(l))
            }
            Kind::Word => (!text.is_empty() && !text.contains(',')).then_some(Value::Word(text)),
            Kind::Words => Some(Value::List(List(text))),
        }
    }

    /// `text` by its syntax: a list when it has a comma, `-`, a number, else a word.
    pub fn of_syntax(text: &'a str) -> Value<'a> {
        if text.contains(',') {
            Value::List(List(text))
        } else if text == "-" {
            Value::Missing
        } else {
            number(text).map_or(Value::Word(text), Value::Number)
        }
    }

    /// The number, or a list's numbers as an iterator (a single number is a list of one);
    /// `None` components for `-` or a word.
    pub fn numbers(&self) -> impl Iterator<Item = Option<f64>> + 'a {
        let (one, list) = match *self {
            Value::Number(x) => (Some(Some(x)), None),
            Value::Missing => (Some(None), None),
            Value::Word(_) => (Some(None), None),
            Value::List(l) => (None, Some(l)),
        };
        one.into_iter().chain(list.into_iter().flat_map(|l| l.items().map(|i| i.number())))
    }

    /// The one number (`None` for anything else).
    pub fn number(&self) -> Option<f64> {
        match *self {
            Value::Number(x) => Some(x),
            _ => None,
        }
    }
}

/// A number as the board writes it (decimal, optional sign, fraction and exponent; `NaN`,
/// `inf`).
fn number(text: &str) -> Option<f64> {
    if text.is_empty() || !text.bytes().all(|c| c.is_ascii_alphanumeric() || matches!(c, b'.' | b'-' | b'+')) {
        return None;
    }
    text.parse().ok()
}

/// Comma-separated components, read in place.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct List<'a>(&'a str);

/// One component of a [`List`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Item<'a> {
    Number(f64),
    Missing,
    Word(&'a str),
}

impl Item<'_> {
    /// The number (`None` for `-` or a word).
    pub fn number(&self) -> Option<f64> {
        match *self {
            Item::Number(x) => Some(x),
            _ => None,
        }
    }
}

impl<'a> List<'a> {
    /// The list's text.
    pub fn as_str(&self) -> &'a str {
        self.0
    }

    /// Its components, in order.
    pub fn items(&self) -> impl Iterator<Item = Item<'a>> + 'a {
        self.0.split(',').map(|t| match Value::of_syntax(t) {
            Value::Number(x) => Item::Number(x),
            Value::Missing => Item::Missing,
            _ => Item::Word(t),
        })
    }
}
