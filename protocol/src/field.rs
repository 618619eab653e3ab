//! Reply fields: a constant for each field docs/console.md's "Units of every field" lists
//! ([`FORCE`], [`VOLTS`], ...), with its [`Kind`] (how its value reads) and unit, and
//! [`FIELDS`], all of them. A new reply field is declared here, one row (and its row in the
//! docs' table: a test checks the two agree); [`crate::reply`] reads a declared field by its
//! kind and any other `key=value` by its syntax.
//!
//! The firmware writes each key through its constant ([`Field::first`] `key=`,
//! [`Field::after`] ` key=`), so a key is spelled here only.
//!
//! What it is not: the firmware's writing of each reply (src/app/*), or a field's value.

/// How a field's value reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// One number (`force=0.5000`, `armed=1`), or `-` for none (`settle=-`).
    Number,
    /// Comma-separated numbers, one per joint, channel or component (`volts=1.0,2.0,3.0`);
    /// `-` for a component not measured yet (`thick_meas=1.99,-,-`).
    Numbers,
    /// One word (`fault=none`, `film_check=ok`).
    Word,
    /// Comma-separated words or mixed components (`fmax_end=contact,1`, `units=force:N,...`,
    /// `branches=0.02:0.5,...`).
    Words,
}

/// A declared reply field: its key, how its value reads, its unit (as the docs' table).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Field {
    pub key: &'static str,
    pub kind: Kind,
    pub unit: &'static str,
    /// The key as a line holds it, `key=` first and ` key=` after another field: one text
    /// each, so a reply writes it in one piece.
    first: &'static str,
    after: &'static str,
}

impl Field {
    /// `key=`: the key of a line's first field.
    pub const fn first(self) -> &'static str {
        self.first
    }

    /// ` key=`: the key of a field after another (the space between them).
    pub const fn after(self) -> &'static str {
        self.after
    }
}

use Kind::{Number, Numbers, Word, Words};

/// `NAME: "key", Kind, "unit";` rows: a constant for each field, and [`FIELDS`], every one
/// in the rows' order.
macro_rules! fields {
    ($($(#[$doc:meta])* $name:ident: $key:literal, $kind:ident, $unit:literal;)*) => {
        $($(#[$doc])* pub const $name: Field =
            Field { key: $key, kind: $kind, unit: $unit, first: concat!($key, "="), after: concat!(" ", $key, "=") };)*

        /// Every documented reply field, in the order of docs/console.md's table.
        pub const FIELDS: &[Field] = &[$($name),*];
    };
}

fields! {
    ARMED: "armed", Number, "0/1";
    FORCE: "force", Number, "N";
    VOLTS: "volts", Numbers, "V";
    TARGET: "target", Numbers, "V";
    THICK: "thick", Numbers, "mm";
    THICK_EQ: "thick_eq", Numbers, "mm";
    VMEAS: "vmeas", Numbers, "V";
    IMEAS: "imeas", Numbers, "µA";
    THICK_MEAS: "thick_meas", Numbers, "mm";
    VCEIL: "vceil", Numbers, "V";
    /// per channel: `ok` or `thinner`
    FILM_CHECK: "film_check", Words, "-";
    TRIP_US: "trip_us", Number, "µs";
    TICK_SENSE_US: "tick_sense_us", Number, "µs";
    TICK_SOURCE_US: "tick_source_us", Number, "µs";
    JOINTS: "joints", Numbers, "deg";
    TIP: "tip", Numbers, "mm, mm, deg";
    CABLE: "cable", Number, "mm";
    /// status: the horn's angle; limits: its travel (two)
    SERVO: "servo", Numbers, "deg";
    FAULT: "fault", Word, "name";
    /// the channel whose read-back latched the fault, 1..3
    FAULT_CH: "fault_ch", Number, "channel";
    ENABLE: "enable", Number, "0/1";
    STIFFNESS: "stiffness", Numbers, "N/mm, N/mm, N·mm/rad";
    ITERS: "iters", Number, "count";
    RANGE: "range", Numbers, "N, N";
    SETTLE: "settle", Number, "s";
    FX: "fx", Number, "N";
    FY: "fy", Number, "N";
    POINT: "point", Numbers, "mm, mm";
    /// the stop's force on the tip, x and y (`fx`, `fy`: the tip's on the stop, opposite)
    FORCE_ON_TIP: "force_on_tip", Numbers, "N, N";
    NODES: "nodes", Numbers, "mm, mm, deg per pose";
    HINGES: "hinges", Numbers, "mm, mm, deg per pose";
    VMAX: "vmax", Numbers, "V";
    VPULLIN: "vpullin", Number, "V";
    SUPPLY: "supply", Number, "V";
    MARGIN: "margin", Number, "fraction";
    FMAX: "fmax", Number, "N";
    FMAX_END: "fmax_end", Words, "why, joint";
    SLEW: "slew", Number, "V/s";
    CABLE_MAX: "cable_max", Number, "mm";
    DUTYMAX: "dutymax", Numbers, "counts";
    VMAX_OK: "vmax_ok", Numbers, "V";
    MOVED: "moved", Number, "0/1";
    UNITS: "units", Words, "";
    VHOLD: "vhold", Number, "V";
    G_EQ: "g_eq", Number, "MPa";
    BRANCHES: "branches", Words, "MPa:s";
    EPS_R: "eps_r", Number, "1";
    BREAKDOWN: "breakdown", Number, "V/µm";
    Z0: "z0", Number, "mm";
    S_HOLD: "s_hold", Number, "1";
    CAL: "cal", Numbers, "1 (ea1, ei1: 1/mm)";
    WAITED: "waited", Number, "s";
    SAVED: "saved", Number, "count";
    BYTES: "bytes", Number, "count";
    VERSION: "version", Word, "-";
    NAME: "name", Word, "-";
    BOARD: "board", Word, "-";
    CARD: "card", Word, "name";
    VGAIN: "vgain", Numbers, "1";
    VOFF: "voff", Numbers, "V";
    C0_PF: "c0_pf", Numbers, "pF";
    /// `input`
    EARLY: "early", Word, "-";
    /// min, max
    TICK_PERIOD_US: "tick_period_us", Numbers, "µs";
    /// min, max
    TICK_LATENCY_US: "tick_latency_us", Numbers, "µs";
    TICK_RUN_US: "tick_run_us", Number, "µs";
    TICK_STACK_US: "tick_stack_us", Number, "µs";
    TICKS: "ticks", Number, "count";
    STOP_US: "stop_us", Number, "µs";
    STOPS: "stops", Number, "count";
    /// `word:max` per command word
    CMD_US: "cmd_us", Words, "word:µs";
    PARAMS: "params", Number, "count";
    PRESET: "preset", Word, "name";
    STORE: "store", Word, "-";
    SAVES: "saves", Number, "count";
    BOOT: "boot", Word, "-";
    REASON: "reason", Word, "-";
    FORMAT: "format", Number, "-";
    VALUES: "values", Number, "count";
    DIFFER: "differ", Number, "count";
    /// a parameter's compiled default (`-`: none), in its unit
    DEFAULT: "default", Number, "as the parameter";
    /// always `1`
    FACTORY: "factory", Number, "-";
    /// always `1`: the board reboots once the reply is sent
    RESET: "reset", Number, "-";
    /// the boot banner's, not a reply's
    CONFIG: "config", Word, "-";
    FILM_KPA: "film_kpa", Number, "kPa";
    CURRENT_UA: "current_ua", Numbers, "µA";
    /// status, limits: gravity's magnitude in force (0: off)
    GRAV: "grav", Number, "m/s²";
    /// status, limits: gravity's direction from the straight finger's axis toward the cable side
    GRAV_DIR: "grav_dir", Number, "deg";
}

/// `const_concat!(a, b, ...)`: the `&'static str` constants `a`, `b`, ... end to end, one
/// text built by the compiler: a field's key and a fixed value as one piece
/// (`const_concat!(ARMED.first(), "1")` is `"armed=1"`), where two would each cost a write.
#[macro_export]
macro_rules! const_concat {
    ($($s:expr),+ $(,)?) => {{
        const PARTS: &[&str] = &[$($s),+];
        const BYTES: [u8; $crate::field::joined_len(PARTS)] = $crate::field::joined(PARTS);
        const TEXT: &str = match ::core::str::from_utf8(&BYTES) {
            Ok(t) => t,
            Err(_) => panic!("not UTF-8"),
        };
        TEXT
    }};
}

/// The length of `parts` end to end ([`const_concat!`]).
#[doc(hidden)]
pub const fn joined_len(parts: &[&str]) -> usize {
    let (mut n, mut i) = (0, 0);
    while i < parts.len() {
        n += parts[i].len();
        i += 1;
    }
    n
}

/// `parts` end to end, `N` their length ([`const_concat!`]).
#[doc(hidden)]
pub const fn joined<const N: usize>(parts: &[&str]) -> [u8; N] {
    let mut out = [0u8; N];
    let (mut at, mut i) = (0, 0);
    while i < parts.len() {
        let p = parts[i].as_bytes();
        let mut j = 0;
        while j < p.len() {
            out[at] = p[j];
            at += 1;
            j += 1;
        }
        i += 1;
    }
    assert!(at == N, "N is not the parts' length");
    out
}

/// The declared field of `key`, if any.
pub fn field(key: &str) -> Option<&'static Field> {
    FIELDS.iter().find(|f| f.key == key)
}
