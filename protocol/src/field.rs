//! Reply fields: [`FIELDS`], every field docs/console.md's "Units of every field" lists, with
//! its [`Kind`] (how its value reads) and unit. A new reply field is declared here, one row
//! (and its row in the docs' table: a test checks the two agree); [`crate::reply`] reads a
//! declared field by its kind and any other `key=value` by its syntax.
//!
//! What it is not: the firmware's writing of each reply (src/app/*): the firmware writes the
//! keys; the host tests check every key it writes is declared here.

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
}

const fn f(key: &'static str, kind: Kind, unit: &'static str) -> Field {
    Field { key, kind, unit }
}

use Kind::{Number, Numbers, Word, Words};

/// Every documented reply field, in the order of docs/console.md's table.
pub const FIELDS: &[Field] = &[
    f("armed", Number, "0/1"),
    f("force", Number, "N"),
    f("volts", Numbers, "V"),
    f("target", Numbers, "V"),
    f("thick", Numbers, "mm"),
    f("thick_eq", Numbers, "mm"),
    f("vmeas", Numbers, "V"),
    f("imeas", Numbers, "µA"),
    f("thick_meas", Numbers, "mm"),
    f("vceil", Numbers, "V"),
    // per channel: `ok` or `thinner`
    f("film_check", Words, "-"),
    f("trip_us", Number, "µs"),
    f("tick_sense_us", Number, "µs"),
    f("tick_source_us", Number, "µs"),
    f("joints", Numbers, "deg"),
    f("tip", Numbers, "mm, mm, deg"),
    f("cable", Number, "mm"),
    // status: the horn's angle; limits: its travel (two)
    f("servo", Numbers, "deg"),
    f("fault", Word, "name"),
    f("enable", Number, "0/1"),
    f("stiffness", Numbers, "N/mm, N/mm, N·mm/rad"),
    f("iters", Number, "count"),
    f("range", Numbers, "N, N"),
    f("settle", Number, "s"),
    f("fx", Number, "N"),
    f("fy", Number, "N"),
    f("point", Numbers, "mm, mm"),
    f("nodes", Numbers, "mm, mm, deg per pose"),
    f("hinges", Numbers, "mm, mm, deg per pose"),
    f("vmax", Numbers, "V"),
    f("vpullin", Number, "V"),
    f("supply", Number, "V"),
    f("margin", Number, "fraction"),
    f("fmax", Number, "N"),
    f("fmax_end", Words, "why, joint"),
    f("slew", Number, "V/s"),
    f("cable_max", Number, "mm"),
    f("dutymax", Numbers, "counts"),
    f("vmax_ok", Numbers, "V"),
    f("moved", Number, "0/1"),
    f("units", Words, ""),
    f("vhold", Number, "V"),
    f("g_eq", Number, "MPa"),
    f("branches", Words, "MPa:s"),
    f("eps_r", Number, "1"),
    f("breakdown", Number, "V/µm"),
    f("z0", Number, "mm"),
    f("s_hold", Number, "1"),
    f("cal", Numbers, "1 (ea1, ei1: 1/mm)"),
    f("waited", Number, "s"),
    f("saved", Number, "count"),
    f("bytes", Number, "count"),
];

/// The declared field of `key`, if any.
pub fn field(key: &str) -> Option<&'static Field> {
    FIELDS.iter().find(|f| f.key == key)
}
