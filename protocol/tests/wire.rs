//! The protocol crate's wire formats: every error code and reply line parses back to what was
//! emitted, and emits back to the line it was parsed from; the field table is the docs'.
use std::collections::BTreeSet;

use finger_protocol::field::{field, FIELDS};
use finger_protocol::message::{Formatted, Pieces};
use finger_protocol::reply::{Error, Fields, Item, List};
use finger_protocol::{ErrorCode, Kind, Reply, Value};

fn emitted(f: impl Fn(&mut String) -> std::fmt::Result) -> String {
    let mut s = String::new();
    f(&mut s).unwrap();
    s
}

#[test]
fn every_code_round_trips() {
    let mut seen = BTreeSet::new();
    for (i, c) in ErrorCode::ALL.into_iter().enumerate() {
        assert_eq!(c.index(), Some(i), "{c:?}");
        let text = emitted(|s| c.emit(s));
        assert_eq!(text, c.as_str());
        assert_eq!(c.to_string(), text);
        assert!(!text.is_empty() && text.bytes().all(|b| b.is_ascii_lowercase() || b == b'-'), "{text}");
        assert!(seen.insert(text.clone()), "{text} twice");
        assert_eq!(ErrorCode::known(&text), Some(c));
        assert_eq!(ErrorCode::<&str>::parse(&text), c_widened(c));
        assert_eq!(ErrorCode::<String>::parse(&text).to_known(), Some(c));
        // and as an error line
        let line = emitted(|s| Reply::Err { code: c_widened(c), message: "why" }.emit(s));
        assert_eq!(line, format!("err {text}: why"));
        assert_eq!(Reply::parse(&line), Ok(Reply::Err { code: c_widened(c), message: "why" }));
    }
    assert_eq!(seen.len(), 12);
}

fn c_widened(c: ErrorCode) -> ErrorCode<&'static str> {
    ErrorCode::known(c.as_str()).unwrap()
}

#[test]
fn an_unknown_code_is_kept() {
    assert_eq!(ErrorCode::<&str>::parse("new-one"), ErrorCode::Other("new-one"));
    assert_eq!(ErrorCode::<String>::parse("new-one").as_str(), "new-one");
    assert_eq!(ErrorCode::<&str>::known("new-one"), None);
    assert_eq!(ErrorCode::Other("new-one").to_known(), None);
    assert_eq!(ErrorCode::<&str>::known("Usage"), None, "codes are lowercase on the wire");
    let r = Reply::parse("err new-one: a newer firmware's").unwrap();
    assert_eq!(r, Reply::Err { code: ErrorCode::Other("new-one"), message: "a newer firmware's" });
}

#[test]
fn an_ok_line_reads_typed_and_emits_back() {
    let line =
        "ok armed=1 force=0.5000 volts=1.0,2.0,3.0 thick_meas=1.9950,-,- settle=- fault=none fmax_end=contact,2 units=force:N,volts:V version=0.1.0 l=30";
    let Reply::Ok(f) = Reply::parse(line).unwrap() else { panic!() };
    assert_eq!(f.check(), Ok(()));
    assert_eq!(f.get("armed"), Some(Value::Number(1.0)));
    assert_eq!(f.get("force").and_then(|v| v.number()), Some(0.5));
    assert_eq!(f.get("volts").unwrap().numbers().collect::<Vec<_>>(), [Some(1.0), Some(2.0), Some(3.0)]);
    assert_eq!(f.get("thick_meas").unwrap().numbers().collect::<Vec<_>>(), [Some(1.995), None, None]);
    assert_eq!(f.get("settle"), Some(Value::Missing));
    assert_eq!(f.get("fault"), Some(Value::Word("none")));
    let Some(Value::List(end)) = f.get("fmax_end") else { panic!() };
    assert_eq!(end.items().collect::<Vec<_>>(), [Item::Word("contact"), Item::Number(2.0)]);
    assert_eq!(f.text("units"), Some("force:N,volts:V"));
    // undeclared fields read by their syntax
    assert_eq!(f.get("version"), Some(Value::Word("0.1.0")));
    assert_eq!(f.get("l"), Some(Value::Number(30.0)));
    assert_eq!(f.get("forc"), None);
    assert_eq!(f.iter().count(), 10);
    assert_eq!(emitted(|s| Reply::Ok(f).emit(s)), line);
    // one number is a list of one
    assert_eq!(Fields::new("servo=12.50").get("servo").unwrap().numbers().collect::<Vec<_>>(), [Some(12.5)]);
}

#[test]
fn lines_round_trip() {
    for line in [
        "ok",
        "ok stopped",
        "ok waited=0.25 early=input",
        "ok armed=0 force=0.000 volts=0.0,0.0,0.0 fault=board card enable=0",
        "ok vmax=5400.0,5400.0,5400.0 fmax=1.2345 fmax_end=limit-point,3",
        "err usage: pose <d1> <d2> <d3> [<P>]",
        "err limit: joint 2: 6000 V is at or past the ceiling 5400 V (33 % pull-in limit with margin, or supply)",
        "err too-long: line longer than 128 bytes discarded",
    ] {
        let r = Reply::parse(line).unwrap_or_else(|e| panic!("{line}: {e}"));
        assert_eq!(emitted(|s| r.emit(s)), line);
    }
    // a value with a space runs to the next key=
    let Reply::Ok(f) = Reply::parse("ok fault=board card enable=0").unwrap() else { panic!() };
    assert_eq!(f.get("fault"), Some(Value::Word("board card")));
    assert_eq!(f.get("enable"), Some(Value::Number(0.0)));
    assert_eq!(Fields::new("fault=none\nnext line").text("fault"), Some("none"));
    let Reply::Ok(f) = Reply::parse("ok stopped").unwrap() else { panic!() };
    assert_eq!(f.raw().collect::<Vec<_>>(), [("stopped", "")]);
}

#[test]
fn what_is_not_a_reply() {
    assert_eq!(Reply::parse("okay"), Err(Error::NotFinal));
    assert_eq!(Reply::parse("  l = 30 mm (1e-3..1e4)"), Err(Error::NotFinal));
    assert_eq!(Reply::parse("err usage"), Err(Error::NoCode));
    assert_eq!(Reply::parse("err : x"), Err(Error::NoCode));
    assert_eq!(Reply::parse("ok =3"), Err(Error::NotAField));
    // a declared field that does not read as its kind: the line parses, its check says so
    for bad in ["ok volts=1,x,3", "ok force=lots", "ok fault=a,b"] {
        let Ok(Reply::Ok(f)) = Reply::parse(bad) else { panic!("{bad}") };
        assert_eq!(f.check(), Err(Error::BadValue), "{bad}");
        assert_eq!(f.get(bad[3..].split('=').next().unwrap()), None, "{bad}");
    }
    let Ok(Reply::Ok(f)) = Reply::parse("ok stopped a=1") else { panic!() };
    assert_eq!(f.pairs().collect::<Vec<_>>(), [("a", "1")]);
    assert_eq!(f.check(), Ok(()));
    // fields of a line that is not a final one
    assert_eq!(Fields::new("params=22 slew=1000").text("slew"), Some("1000"));
    assert_eq!(
        List::items(&match Value::of_syntax("1,-,x") {
            Value::List(l) => l,
            _ => panic!(),
        })
        .collect::<Vec<_>>(),
        [Item::Number(1.0), Item::Missing, Item::Word("x")]
    );
}

#[test]
fn formatted_pieces_are_cores_formatting() {
    let mut s = String::new();
    let mut p = Formatted::new(&mut s);
    p.joint(2);
    p.text(": ");
    p.fixed(5399.6, 0);
    p.text(" ");
    p.fixed(0.12345, 3);
    p.text(" ");
    p.exp(1.5e-5, 3);
    p.text(" ");
    p.count(7);
    p.text(" ");
    p.joint(0);
    p.finish().unwrap();
    assert_eq!(s, "joint 2: 5400 0.123 1.500e-5 7 the tip-loaded finger");
}

/// The field table is docs/console.md's "Units of every field": the same keys, and each key's
/// unit among its rows' units.
#[test]
fn the_field_table_is_the_docs_table() {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/console.md")).unwrap();
    let table = doc.split("## Units of every field").nth(1).unwrap().split("\n## ").next().unwrap();
    let mut keys = BTreeSet::new();
    let mut units_of = std::collections::BTreeMap::new();
    for row in table.lines().filter(|l| l.starts_with("| `")) {
        let cols: Vec<&str> = row.split('|').map(str::trim).collect();
        let unit = cols[3];
        let names: Vec<&str> = cols[1].split(',').map(|n| n.trim().trim_matches('`')).collect();
        // several names share a row: their units `;`- or `,`-separated, or one for all
        let split = |sep: char| Some(unit.split(sep).map(str::trim).collect::<Vec<_>>()).filter(|u| names.len() > 1 && u.len() == names.len());
        let units = split(';').or_else(|| split(',')).unwrap_or_else(|| vec![unit; names.len()]);
        for (n, u) in names.iter().zip(units) {
            assert!(field(n).is_some(), "docs/console.md's field {n} is not in FIELDS");
            units_of.entry(n.to_string()).or_insert_with(Vec::new).push(u.to_string());
            keys.insert(n.to_string());
        }
    }
    for f in FIELDS {
        let doc = units_of.get(f.key).map(Vec::as_slice).unwrap_or_default();
        assert!(doc.iter().any(|u| u == f.unit), "{}: unit {:?}, the docs' {doc:?}", f.key, f.unit);
    }
    let table_keys: BTreeSet<String> = FIELDS.iter().map(|f| f.key.to_string()).collect();
    assert_eq!(keys, table_keys, "FIELDS and docs/console.md's table list the same fields");
    assert_eq!(FIELDS.len(), table_keys.len(), "a key declared twice");
    assert!(FIELDS.iter().filter(|f| f.kind == Kind::Numbers).count() > 10);
}

/// Each field's key as a line holds it: `key=` first, ` key=` after another field.
#[test]
fn each_fields_key_is_written_as_the_line_holds_it() {
    for f in FIELDS {
        assert_eq!(f.first(), format!("{}=", f.key));
        assert_eq!(f.after(), format!(" {}=", f.key));
        assert!(!f.key.is_empty() && f.key.bytes().all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'_'), "{}", f.key);
    }
    assert_eq!(finger_protocol::field::FORCE.after(), " force=");
}

#[test]
fn every_command_round_trips() {
    use finger_protocol::Command;
    let mut seen = BTreeSet::new();
    for c in Command::ALL {
        let w = c.as_str();
        assert!(!w.is_empty() && w.bytes().all(|b| b.is_ascii_lowercase()), "{c:?}: {w}");
        assert!(seen.insert(w), "{w} twice");
        assert_eq!(Command::parse(w.as_bytes()), Some(c));
        assert_eq!(format!("{c:?}").to_ascii_lowercase(), w);
    }
    assert_eq!(Command::parse(b"frobnicate"), None);
    assert_eq!(Command::parse(b"Help"), None, "the board's line buffer is lowercase");
    assert_eq!(Command::parse(b""), None);
    assert_eq!(Command::parse(b"helpversion"), None);
}

/// A key and a fixed value as one text, built by the compiler.
#[test]
fn const_concat_joins_a_key_and_its_value() {
    use finger_protocol::field::{ARMED, FMAX, FMAX_END};
    const ARMED_1: &str = finger_protocol::const_concat!(ARMED.first(), "1");
    assert_eq!(ARMED_1, "armed=1");
    assert_eq!(finger_protocol::const_concat!(FMAX.after(), "-", FMAX_END.after(), "error"), " fmax=- fmax_end=error");
    assert_eq!(finger_protocol::const_concat!("µ"), "µ");
}
