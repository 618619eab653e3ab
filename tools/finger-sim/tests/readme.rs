//! The README's quick start prints what the README shows: its transcript's typed lines go to
//! finger-sim, and every reply must equal the README's line for it. When the model or the
//! grammar changes a reply on purpose, `UPDATE_README=1 cargo test --test readme` rewrites
//! the transcript's replies from a real run (and the test still fails once, to be looked at).

use std::io::Write;
use std::path::PathBuf;
use std::process::{Command, Stdio};

const BEGIN: &str = "<!-- quick start: tools/finger-sim/tests/readme.rs runs this transcript -->";

fn readme() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../README.md")
}

/// A reply line (everything finger-sim prints), as opposed to a typed one.
fn is_reply(l: &str) -> bool {
    l.starts_with("ok") || l.starts_with("err ") || l.starts_with("# ")
}

#[test]
fn the_quick_start_prints_what_the_readme_shows() {
    let text = std::fs::read_to_string(readme()).unwrap();
    let start = text.find(BEGIN).expect("README has the quick start marker");
    let after = &text[start..];
    let open = after.find("```text\n").expect("a ```text block after the marker") + "```text\n".len();
    let close = open + after[open..].find("```").unwrap();
    let block = &after[open..close];
    let mut lines = block.lines();
    let first = lines.next().unwrap();
    assert!(first.starts_with("$ ") && first.contains("cargo run"), "{first}");
    let banner = lines.next().unwrap();
    assert!(banner.starts_with("finger-sim ") && banner.contains("Type `help`"), "{banner}");
    let body: Vec<&str> = lines.collect();
    let typed: Vec<&str> = body.iter().copied().filter(|l| !is_reply(l)).collect();
    assert!(typed.len() >= 5, "a quick start of a few commands");

    let mut c = Command::new(env!("CARGO_BIN_EXE_finger-sim")).stdin(Stdio::piped()).stdout(Stdio::piped()).spawn().unwrap();
    c.stdin.take().unwrap().write_all((typed.join("\n") + "\n").as_bytes()).unwrap();
    let out = c.wait_with_output().unwrap();
    assert!(out.status.success());
    let replies = String::from_utf8(out.stdout).unwrap();
    let replies: Vec<&str> = replies.lines().collect();
    assert_eq!(replies.len(), typed.len(), "one reply a line: {replies:?}");

    // the transcript as a run gives it
    let mut want = vec![first.to_string(), banner.to_string()];
    for (t, r) in typed.iter().zip(&replies) {
        want.push(t.to_string());
        want.push(r.to_string());
    }
    let want = want.join("\n") + "\n";
    let shown = format!("{first}\n{banner}\n{}\n", body.join("\n"));
    if want != shown && std::env::var_os("UPDATE_README").is_some() {
        let abs = start + open;
        let new = format!("{}{}{}", &text[..abs], want, &text[abs + block.len()..]);
        std::fs::write(readme(), new).unwrap();
        panic!("README's quick start rewritten from a run: look at the diff");
    }
    assert_eq!(shown, want, "README's quick start differs from a run (UPDATE_README=1 rewrites it)");
}
