//! Reading the console's replies (docs/console.md) in the tests: thin wrappers over the
//! protocol crate's one parser (`finger_protocol::reply`), whatever console the test talks to
//! (the simulated board, QEMU). Not a client: tools/finger is what a user runs.
use finger_protocol::reply::Fields;

/// Whether `line` is a final reply (`ok ...` / `err <code>: ...`), as the protocol crate reads it.
pub fn is_final(line: &str) -> bool {
    finger_protocol::Reply::parse(line).is_ok()
}

/// The value of `key=` in a reply, if it has one.
pub fn find<'a>(reply: &'a str, key: &str) -> Option<&'a str> {
    Fields::new(reply).text(key)
}

/// The value of `key=` in a reply (panics if the reply has none).
pub fn val<'a>(reply: &'a str, key: &str) -> &'a str {
    find(reply, key).unwrap_or_else(|| panic!("no {key} in {reply}"))
}

/// A reply's comma-separated list of numbers (panics on a component that is not one).
pub fn nums(s: &str) -> Vec<f64> {
    finger_protocol::Value::of_syntax(s).numbers().map(|x| x.unwrap_or_else(|| panic!("not numbers: {s}"))).collect()
}

/// The value of `key=` in a reply, as numbers (panics if the reply has none).
pub fn field(reply: &str, key: &str) -> Vec<f64> {
    nums(val(reply, key))
}
