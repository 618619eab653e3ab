//! Reading the console's replies (docs/console.md): `key=value` words and comma-separated
//! numbers. The one parser every test and report uses, whatever console it talks to (the
//! simulated board, QEMU). Not a client: tools/finger is what a user runs.

/// The value of `key=` in a reply, if it has one.
pub fn find<'a>(reply: &'a str, key: &str) -> Option<&'a str> {
    reply.split_whitespace().find_map(|kv| kv.strip_prefix(key).and_then(|r| r.strip_prefix('=')))
}

/// The value of `key=` in a reply (panics if the reply has none).
pub fn val<'a>(reply: &'a str, key: &str) -> &'a str {
    find(reply, key).unwrap_or_else(|| panic!("no {key} in {reply}"))
}

/// A reply's comma-separated list of numbers.
pub fn nums(s: &str) -> Vec<f64> {
    s.split(',').map(|x| x.parse().unwrap()).collect()
}

/// The value of `key=` in a reply, as numbers (panics if the reply has none).
pub fn field(reply: &str, key: &str) -> Vec<f64> {
    nums(val(reply, key))
}
