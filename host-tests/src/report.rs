//! What the reports (examples/*, src/bin/*) share: a generated section written into a doc
//! between its markers, `<!-- NAME:begin ...` and `<!-- NAME:end -->`, the rest of the doc
//! kept as it is. Not the reports' content: each report writes its own.
use std::path::Path;

/// Replace the section `name` of `doc` (a path from the repository's top, e.g.
/// "docs/firmware.md") by `section`, which holds both markers itself.
pub fn write_section(doc: &str, name: &str, section: &str) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(doc);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{doc}: {e}"));
    let (head, rest) = text.split_once(&format!("<!-- {name}:begin")).unwrap_or_else(|| panic!("markers in {doc}"));
    let (_, tail) = rest.split_once(&format!("<!-- {name}:end -->\n")).expect("end marker");
    std::fs::write(&path, format!("{head}{section}{tail}")).unwrap();
}
