//! Every error code the firmware can emit is the protocol crate's and parses back through it:
//! the firmware's source names codes only as `finger_protocol::ErrorCode` variants (no
//! `"err <code>` text of its own), and the simulated board's refusals, one per code it can give
//! here, parse to their code. Every reply of a session parses as a final line, its declared
//! fields as their kinds. Every key the firmware writes is a declared field: the source writes
//! none as text (each is a `finger_protocol::field` constant, so the compiler proves it
//! declared), and a session's replies hold no other.
use std::path::Path;

use finger_fw::sim::SimBoard;
use finger_fw::App;
use finger_protocol::{ErrorCode, Reply};
use host_tests::sim_console::{cmd, feed, Out};

fn sources(dir: &Path, out: &mut Vec<(String, String)>) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            sources(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push((p.display().to_string(), std::fs::read_to_string(&p).unwrap()));
        }
    }
}

/// The identifier after each `pat` in `text`.
fn names_after<'a>(text: &'a str, pat: &str) -> Vec<&'a str> {
    text.match_indices(pat)
        .map(|(i, _)| {
            let rest = &text[i + pat.len()..];
            &rest[..rest.find(|c: char| !c.is_ascii_alphanumeric()).unwrap_or(rest.len())]
        })
        .collect()
}

#[test]
fn every_code_the_firmware_names_is_the_protocols_and_parses() {
    let mut files = Vec::new();
    sources(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../src"), &mut files);
    let known: Vec<String> = ErrorCode::ALL.iter().map(|c| format!("{c:?}")).collect();
    let mut used = std::collections::BTreeSet::new();
    for (path, text) in &files {
        // the code, not its comments
        let text: String = text.lines().filter(|l| !l.trim_start().starts_with("//")).collect::<Vec<_>>().join("\n");
        // an error line's head is the protocol's (src/app/errors.rs `head`), never text
        assert!(!text.contains("\"err "), "{path}: an `err <code>` line written as text");
        // (`ErrorCode::$code`: the macro's own)
        for n in names_after(&text, "err!(").into_iter().chain(names_after(&text, "ErrorCode::")).filter(|n| !n.is_empty()) {
            assert!(known.iter().any(|k| k == n), "{path}: `{n}` is not a code of finger_protocol::ErrorCode");
            used.insert(n.to_string());
        }
    }
    assert!(used.len() >= 10, "{used:?}");
    for c in ErrorCode::ALL {
        let line = format!("err {c}: message");
        assert_eq!(
            Reply::parse(&line).map(|r| match r {
                Reply::Err { code, .. } => code.to_known(),
                _ => None,
            }),
            Ok(Some(c)),
            "{line}"
        );
    }
    // the model's errors' codes are among them (their table is exhaustive by construction)
    let e = finger_model::Error::Singular { what: "tangent" };
    assert_eq!(e.code(), ErrorCode::Fault);
    assert_eq!(e.to_string(), "singular tangent");
}

/// The string literals of Rust source `text` outside comments (their text as written, escapes
/// kept; no raw strings or `'"'` in src/).
fn literals(text: &str) -> Vec<&str> {
    let mut out = Vec::new();
    for line in text.lines() {
        let b = line.as_bytes();
        let (mut i, mut start) = (0, None);
        while i < b.len() {
            match (start, b[i]) {
                (None, b'/') if b.get(i + 1) == Some(&b'/') => break,
                (None, b'"') => start = Some(i + 1),
                (Some(_), b'\\') => i += 1,
                (Some(s), b'"') => {
                    out.push(&line[s..i]);
                    start = None;
                }
                _ => {}
            }
            i += 1;
        }
    }
    out
}

/// The `key=` words of `text`: a key at its start or after a space, then `=`.
fn keys_in(text: &str) -> Vec<&str> {
    text.split(' ')
        .filter_map(|w| w.split_once('='))
        .map(|(k, _)| k)
        .filter(|k| !k.is_empty() && k.bytes().all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == b'_'))
        .collect()
}

/// The firmware writes no reply key as text: each one is a `finger_protocol::field` constant
/// (`field::FORCE.after()`, `const_concat!(field::ARMED.first(), "1")`), so every key it writes
/// is declared (FIELDS, docs/console.md's units table) or it does not build. A string literal
/// of src/ holding a `key=` word fails here.
#[test]
fn the_firmware_writes_every_key_through_the_protocols_fields() {
    let mut files = Vec::new();
    sources(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../src"), &mut files);
    let mut through = 0;
    for (path, text) in &files {
        for l in literals(text) {
            assert!(keys_in(l).is_empty(), "{path}: {l:?} writes a key as text (finger_protocol::field has each key)");
        }
        through += text.matches("field::").count();
    }
    assert!(through > 100, "{through} keys written through finger_protocol::field");
    assert_eq!(keys_in("ok force=1 volts=2"), ["force", "volts"]);
    assert_eq!(literals(r#"w!(r; " thick=", "a\"b", "c"); // "x=""#), [" thick=", "a\\\"b", "c"]);
}

/// Every key of a session's final replies (the simulated board with its plant behind the
/// read-back) is a declared field.
#[test]
fn every_key_of_a_session_is_declared() {
    let mut a = App::new(SimBoard::with_plant(finger_fw::plant::Plant::new(3).unwrap()));
    let mut seen = std::collections::BTreeSet::new();
    for line in [
        "version",
        "status",
        "limits",
        "material",
        "solve 0.5 100 0 0",
        "shape 0.5 0 0 0",
        "pose 4.66 5.35 6.21",
        "contact 0.1 0.3",
        "param",
        "preset default",
        "cal",
        "cal show",
        "wait 0",
        "plant status",
        "config",
        "factory",
        "arm",
        "volt all 100",
        "force 0.3",
        "pose 4.66 5.35 6.21",
        "wait 0.1",
        "status",
        "disarm",
        "stop",
    ] {
        let r = cmd(&mut a, line);
        let Ok(Reply::Ok(f)) = Reply::parse(&r) else { panic!("{line:?} -> {r:?}") };
        assert_eq!(f.check(), Ok(()), "{line:?} -> {r}: a declared field does not read as its kind");
        for (k, _) in f.pairs() {
            assert!(finger_protocol::field::field(k).is_some(), "{line:?} -> {r}: {k} is not a declared field");
            seen.insert(k.to_string());
        }
    }
    assert!(seen.len() > 60, "{seen:?}");
}

fn app() -> App<SimBoard> {
    App::new(SimBoard::default())
}

/// `line`'s reply, parsed: its code.
fn code_of(a: &mut App<SimBoard>, line: &str) -> ErrorCode {
    let r = cmd(a, line);
    match Reply::parse(&r) {
        Ok(Reply::Err { code, message }) => {
            assert!(!message.is_empty(), "{r}");
            code.to_known().unwrap_or_else(|| panic!("{r}: not a known code"))
        }
        other => panic!("{line:?} -> {r:?}: {other:?}"),
    }
}

#[test]
fn the_simulated_boards_refusals_parse_to_their_codes() {
    let mut a = app();
    assert_eq!(code_of(&mut a, "frobnicate"), ErrorCode::Unknown);
    assert_eq!(code_of(&mut a, "solve 1"), ErrorCode::Usage);
    assert_eq!(code_of(&mut a, "solve nan 0 0 0"), ErrorCode::BadNumber);
    assert_eq!(code_of(&mut a, &format!("solve {}", "1 ".repeat(100))), ErrorCode::TooLong);
    assert_eq!(code_of(&mut a, "a b c d e f g h i j"), ErrorCode::Usage);
    assert_eq!(code_of(&mut a, "volt 1 100"), ErrorCode::NotArmed);
    assert_eq!(code_of(&mut a, "pose -5 1 1"), ErrorCode::Unreachable);
    assert!(cmd(&mut a, "arm").starts_with("ok"));
    assert_eq!(code_of(&mut a, "volt 1 1e6"), ErrorCode::Limit);
    assert_eq!(code_of(&mut a, "param l 30"), ErrorCode::Armed);
    // a model error, through the one table of messages
    assert_eq!(code_of(&mut a, "force 1e7"), ErrorCode::Limit);
    // a lost line, and lines a stop drops
    a.input_overrun();
    let lines = feed(&mut a, b"status\n");
    assert!(matches!(Reply::parse(&lines[0]), Ok(Reply::Err { code: ErrorCode::Overrun, .. })), "{lines:?}");
    let mut out = Out(String::new());
    for &b in b"status\nstatus\nstop\n" {
        a.receive(b, &mut out);
    }
    a.run_commands(&mut out);
    let stopped = out.0.lines().filter(|l| matches!(Reply::parse(l), Ok(Reply::Err { code: ErrorCode::Stopped, .. }))).count();
    assert_eq!(stopped, 2, "{}", out.0);
    // a latched fault
    assert!(a.write_hv_duty(3, 0).is_err());
    assert_eq!(code_of(&mut a, "arm"), ErrorCode::Fault);
}

/// Every command word the firmware's `help` lists is a [`finger_protocol::Command`], and every
/// command this build lacks answers `err unknown`.
#[test]
fn every_command_of_help_is_the_protocols() {
    let mut a = app();
    let help = host_tests::sim_console::feed(&mut a, b"help\n");
    for l in help.iter().filter(|l| !l.starts_with("ok")) {
        let w = l.split_whitespace().next().unwrap();
        assert!(finger_protocol::Command::parse(w.as_bytes()).is_some(), "help's {w}");
    }
    for c in finger_protocol::Command::ALL {
        if !finger_fw::app::is_command(c.as_str().as_bytes()) {
            assert!(cmd(&mut a, c.as_str()).starts_with("err unknown: "), "{c:?}");
        }
    }
}

/// Each reply of a session is a final line that parses, every declared field reading as its
/// kind ([`finger_protocol::field::FIELDS`]), and emits back to itself.
#[test]
fn every_reply_of_a_session_parses() {
    let mut a = app();
    for line in [
        "help",
        "version",
        "status",
        "limits",
        "material",
        "solve 0.5 100 0 0",
        "shape 0.5 0 0 0",
        "pose 4.66 5.35 6.21",
        "contact 0.2 0.5",
        "param",
        "param l",
        "cal",
        "cal show",
        "arm",
        "volt all 100",
        "force 0.3",
        "wait 0.1",
        "status",
        "disarm",
        "stop",
    ] {
        let r = cmd(&mut a, line);
        let p = Reply::parse(&r).unwrap_or_else(|e| panic!("{line:?} -> {r:?}: {e}"));
        let mut back = String::new();
        p.emit(&mut back).unwrap();
        assert_eq!(back, r.trim_end());
        if let Reply::Ok(f) = p {
            assert_eq!(f.check(), Ok(()), "{line:?} -> {r}: a declared field does not read as its kind");
        }
    }
}
