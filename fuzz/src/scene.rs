//! The scene target: arbitrary text into finger-scene's reader (`finger_scene::scene::parse`).
//!
//! Invariants: an answer or an error, never a panic; an error names a place inside the text
//! (line 1.. and a column within that line, 1-based) or the scene as a whole (line 0, column 0).
//!
//! What it is not: the scene runner (the model target covers the solves).

/// Runs one input; panics when an invariant breaks. Bytes that are not UTF-8 are read
/// lossily (the file reader refuses them before parsing).
pub fn check(data: &[u8]) {
    let text = String::from_utf8_lossy(data);
    if let Err(e) = finger_scene::scene::parse("fuzz", &text) {
        let pos = e.pos();
        let lines: Vec<&str> = text.split('\n').collect();
        if pos.line == 0 {
            assert_eq!(pos.column, 0, "a whole-scene error with a column: {e}");
        } else {
            assert!(pos.line <= lines.len(), "error at line {} of {}: {e}", pos.line, lines.len());
            // the line as the reader sees it: a bare CR (even several before the LF) is a
            // character the error may point at
            let chars = lines[pos.line - 1].chars().count();
            assert!(pos.column >= 1 && pos.column <= chars + 2, "error at {}:{} (line of {chars} chars): {e}", pos.line, pos.column);
        }
    }
}
