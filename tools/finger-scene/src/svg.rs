//! Posture plots as hand-written SVG, like the paper's figure 4: the finger itself drawn at the
//! scene's largest tension (body, hinges, stacks coloured by voltage with a scale, clamp, cable,
//! the pull: `crate::drawing`), each posture a polyline through the node and hinge-end positions
//! (class `posture`) with its own colour, dash and node marker so coinciding curves stay
//! apart, a legend in words, axes in mm with equal aspect (x right, y up: the flexor side is
//! up), and a tip-stiffness panel when the scene asks for the tip stiffness. A continuum
//! reference, when the scene asks for one, is drawn dashed in its posture's colour (class
//! `reference`).
//!
//! What it is not: a plotting library. No dependency; the output is plain SVG 1.1.

use crate::drawing;
use crate::run::{Kind, SceneResult};
use std::fmt::Write;

/// Node marker shapes, one per posture in turn, so coinciding curves stay apart.
const MARKERS: &[&str] = &["circle", "square", "triangle", "diamond", "down", "cross"];

/// A node marker of `shape` at (x, y) px in colour `c`.
fn marker(shape: &str, x: f64, y: f64, c: &str) -> String {
    let r = 3.5;
    match shape {
        "square" => format!(r#"<rect class="node" x="{:.3}" y="{:.3}" width="{:.1}" height="{:.1}" fill="{c}"/>"#, x - r, y - r, 2.0 * r, 2.0 * r),
        "triangle" => format!(
            r#"<polygon class="node" points="{:.3},{:.3} {:.3},{:.3} {:.3},{:.3}" fill="{c}"/>"#,
            x,
            y - r * 1.2,
            x - r * 1.1,
            y + r * 0.8,
            x + r * 1.1,
            y + r * 0.8
        ),
        "down" => format!(
            r#"<polygon class="node" points="{:.3},{:.3} {:.3},{:.3} {:.3},{:.3}" fill="{c}"/>"#,
            x,
            y + r * 1.2,
            x - r * 1.1,
            y - r * 0.8,
            x + r * 1.1,
            y - r * 0.8
        ),
        "diamond" => format!(
            r#"<polygon class="node" points="{:.3},{:.3} {:.3},{:.3} {:.3},{:.3} {:.3},{:.3}" fill="{c}"/>"#,
            x,
            y - r * 1.3,
            x + r * 1.3,
            y,
            x,
            y + r * 1.3,
            x - r * 1.3,
            y
        ),
        "cross" => format!(
            r#"<path class="node" d="M{:.3},{:.3}L{:.3},{:.3}M{:.3},{:.3}L{:.3},{:.3}" stroke="{c}" stroke-width="2"/>"#,
            x - r,
            y - r,
            x + r,
            y + r,
            x - r,
            y + r,
            x + r,
            y - r
        ),
        _ => format!(r#"<circle class="node" cx="{x:.3}" cy="{y:.3}" r="{:.1}" fill="{c}"/>"#, r * 0.85),
    }
}

/// Each posture's line style: (dash attribute, stroke width, opacity). A matched posture is
/// drawn wide and pale under the others, the posture it matches dotted on top of it.
fn style(kind: Kind, i: usize) -> (&'static str, f64, f64) {
    const DASHES: &[&str] = &["", r#" stroke-dasharray="9 3""#, r#" stroke-dasharray="3 2""#, r#" stroke-dasharray="9 3 2 3""#];
    match kind {
        Kind::Tension => (DASHES[i % DASHES.len()], 2.0, 1.0),
        Kind::Matched => ("", 5.0, 0.55),
        Kind::MatchTarget => (r#" stroke-dasharray="2 3""#, 2.0, 1.0),
    }
}

/// Colours for the scene's tensions, in order (the paper's purple and green are kept for the
/// match postures).
const PALETTE: &[&str] = &["#1f77b4", "#ff7f0e", "#d62728", "#8c564b", "#17becf", "#e377c2", "#7f7f7f", "#bcbd22"];
const MATCHED: &str = "#9467bd";
const TARGET: &str = "#2ca02c";

/// Escape text for SVG content and attribute values.
pub fn escape(s: &str) -> String {
    let mut o = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => o.push_str("&amp;"),
            '<' => o.push_str("&lt;"),
            '>' => o.push_str("&gt;"),
            '"' => o.push_str("&quot;"),
            '\'' => o.push_str("&apos;"),
            _ => o.push(c),
        }
    }
    o
}

/// A tick step that gives about 4..10 ticks over `range` mm.
fn tick_step(range: f64) -> f64 {
    for s in [1.0, 2.0, 5.0, 10.0, 20.0, 25.0, 50.0, 100.0, 200.0, 500.0] {
        if range / s <= 10.0 {
            return s;
        }
    }
    1000.0
}

/// The colour of each posture.
pub fn colours(r: &SceneResult) -> Vec<&'static str> {
    let mut i = 0;
    r.postures
        .iter()
        .map(|p| match p.kind {
            Kind::Tension => {
                let c = PALETTE[i % PALETTE.len()];
                i += 1;
                c
            }
            Kind::Matched => MATCHED,
            Kind::MatchTarget => TARGET,
        })
        .collect()
}

/// Draw a run scene's postures, with the continuum reference when the scene asked for it.
pub fn plot(r: &SceneResult) -> String {
    plot_overlay(r, "continuum reference")
}

/// Draw a run scene's postures; each posture's `reference` (another model's or a board's
/// answer) dashed in its colour, named `overlay` in the legend. An overlay of one point (a
/// tip alone) is drawn as a ring.
pub fn plot_overlay(r: &SceneResult, overlay: &str) -> String {
    // the finger drawn at the scene's largest tension
    let params = r.scene.finger.params;
    let shown = r.postures.iter().filter(|p| p.kind == Kind::Tension).max_by(|a, b| a.tension.total_cmp(&b.tension));
    let v_max = finger_model::Finger::new(params).map(|f| f.voltage_ceiling()).unwrap_or(0.0);
    let mut xs = vec![0.0f64];
    let mut ys = vec![0.0f64];
    if let Some(p) = shown {
        for q in drawing::extent(&params, &p.solution) {
            xs.push(q[0]);
            ys.push(q[1]);
        }
    }
    for p in &r.postures {
        for pt in p.points.iter().chain(p.reference.iter().flat_map(|rf| rf.points.iter())) {
            if pt[0].is_finite() && pt[1].is_finite() {
                xs.push(pt[0]);
                ys.push(pt[1]);
            }
        }
    }
    let (xmin, xmax) = xs.iter().fold((f64::MAX, f64::MIN), |(a, b), &x| (a.min(x), b.max(x)));
    let (ymin, ymax) = ys.iter().fold((f64::MAX, f64::MIN), |(a, b), &y| (a.min(y), b.max(y)));
    let step = tick_step((xmax - xmin).max(ymax - ymin).max(1.0));
    let x0 = (xmin / step).floor() * step;
    let x1 = (xmax / step).ceil() * step;
    let mut y0 = (ymin / step).floor() * step;
    let mut y1 = (ymax / step).ceil() * step;
    if y1 - y0 < step {
        y0 -= step;
        y1 += step;
    }
    let (x0, x1) = if x1 - x0 < step { (x0 - step, x1 + step) } else { (x0, x1) };
    // equal aspect: one scale for both axes
    let scale = (640.0 / (x1 - x0)).min(560.0 / (y1 - y0));
    let (ml, mt, mb) = (64.0, 48.0, 52.0);
    let pw = (x1 - x0) * scale;
    let ph = (y1 - y0) * scale;
    let longest = r.postures.iter().map(|p| p.label.chars().count()).max().unwrap_or(0).max(24);
    let legend_w = 48.0 + 7.0 * longest as f64;
    let width = ml + pw + 24.0 + legend_w;
    let with_stiffness = r.postures.iter().any(|p| p.stiffness.is_some());
    let legend_h = 24.0 * (r.postures.len() as f64 + 3.0) + if params.layers > 0 { 150.0 } else { 0.0 };
    let panel_h = if with_stiffness { 230.0 } else { 0.0 };
    let height = (mt + ph + mb).max(mt + legend_h) + panel_h;
    let px = |x: f64| ml + (x - x0) * scale;
    let py = |y: f64| mt + (y1 - y) * scale;

    let mut s = String::new();
    let _ = writeln!(s, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" version="1.1" width="{width:.0}" height="{height:.0}" viewBox="0 0 {width:.0} {height:.0}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, "{}", drawing::defs());
    let _ = writeln!(s, r#"<rect x="0" y="0" width="{width:.0}" height="{height:.0}" fill="white"/>"#);
    let _ = writeln!(s, r#"<text x="{ml:.1}" y="24" font-size="15">{}</text>"#, escape(&r.scene.title));
    // grid and ticks
    let _ = writeln!(s, r##"<g class="axes" stroke="#dddddd" stroke-width="1">"##);
    let mut x = x0;
    while x <= x1 + 1e-9 {
        let _ = writeln!(s, r#"<line x1="{:.2}" y1="{:.2}" x2="{:.2}" y2="{:.2}"/>"#, px(x), py(y0), px(x), py(y1));
        x += step;
    }
    let mut y = y0;
    while y <= y1 + 1e-9 {
        let _ = writeln!(s, r#"<line x1="{:.2}" y1="{:.2}" x2="{:.2}" y2="{:.2}"/>"#, px(x0), py(y), px(x1), py(y));
        y += step;
    }
    let _ = writeln!(s, "</g>");
    if let Some(p) = shown {
        let map = |q: [f64; 2]| [px(q[0]), py(q[1])];
        let _ = write!(s, "{}", drawing::finger_group(&params, &p.solution, &p.volts, v_max, &map, scale));
    }
    let _ = writeln!(s, r#"<rect x="{:.2}" y="{:.2}" width="{pw:.2}" height="{ph:.2}" fill="none" stroke="black" stroke-width="1"/>"#, px(x0), py(y1));
    let _ = writeln!(s, r#"<g class="ticks" fill="black">"#);
    let mut x = x0;
    while x <= x1 + 1e-9 {
        let _ = writeln!(s, r#"<text x="{:.2}" y="{:.2}" text-anchor="middle">{}</text>"#, px(x), py(y0) + 16.0, x);
        x += step;
    }
    let mut y = y0;
    while y <= y1 + 1e-9 {
        let _ = writeln!(s, r#"<text x="{:.2}" y="{:.2}" text-anchor="end">{}</text>"#, px(x0) - 6.0, py(y) + 4.0, y);
        y += step;
    }
    let _ = writeln!(s, r#"<text x="{:.2}" y="{:.2}" text-anchor="middle">x (mm)</text>"#, ml + pw / 2.0, py(y0) + 36.0);
    let _ = writeln!(
        s,
        r#"<text x="16" y="{:.2}" text-anchor="middle" transform="rotate(-90 16 {:.2})">y (mm), flexor side up</text>"#,
        mt + ph / 2.0,
        mt + ph / 2.0
    );
    let _ = writeln!(s, "</g>");

    let cols = colours(r);
    let pts = |v: &[[f64; 2]]| v.iter().map(|p| format!("{:.3},{:.3}", px(p[0]), py(p[1]))).collect::<Vec<_>>().join(" ");
    for (p, c) in r.postures.iter().zip(&cols) {
        if let Some(rf) = p.reference.as_ref().filter(|rf| rf.points.len() == 1) {
            let _ = writeln!(
                s,
                r#"<circle class="reference-tip" data-tension="{}" cx="{:.3}" cy="{:.3}" r="5" fill="none" stroke="{c}" stroke-width="1.5"/>"#,
                p.tension,
                px(rf.points[0][0]),
                py(rf.points[0][1])
            );
        } else if let Some(rf) = &p.reference {
            let _ = writeln!(
                s,
                r#"<polyline class="reference" data-tension="{}" points="{}" fill="none" stroke="{c}" stroke-width="1.2" stroke-opacity="0.8" stroke-dasharray="6 4"/>"#,
                p.tension,
                pts(&rf.points)
            );
        }
    }
    // a matched posture is wide and pale, and what it matches comes after it (dotted on top)
    for (i, (p, c)) in r.postures.iter().zip(cols.iter().copied()).enumerate() {
        let (dash, width, opacity) = style(p.kind, i);
        let _ = writeln!(
            s,
            r#"<polyline class="posture" data-tension="{}" points="{}" fill="none" stroke="{c}" stroke-width="{width}" stroke-opacity="{opacity}"{dash}/>"#,
            p.tension,
            pts(&p.points)
        );
        for node in &p.solution.nodes[..=p.solution.n] {
            let _ = writeln!(s, "{}", marker(MARKERS[i % MARKERS.len()], px(node.x), py(node.y), c));
        }
    }
    // legend
    let lx = ml + pw + 24.0;
    let mut ly = mt + 8.0;
    let _ = writeln!(s, r#"<g class="legend">"#);
    let _ = writeln!(s, r#"<text x="{lx:.1}" y="{ly:.1}" font-weight="bold">cable tension</text>"#);
    ly += 20.0;
    for (i, (p, c)) in r.postures.iter().zip(&cols).enumerate() {
        let (dash, width, opacity) = style(p.kind, i);
        let _ = writeln!(
            s,
            r#"<line x1="{lx:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{c}" stroke-width="{width}" stroke-opacity="{opacity}"{dash}/>"#,
            ly - 4.0,
            lx + 28.0,
            ly - 4.0
        );
        let _ = writeln!(s, "{}", marker(MARKERS[i % MARKERS.len()], lx + 14.0, ly - 4.0, c));
        let _ = writeln!(s, r#"<text x="{:.1}" y="{ly:.1}">{}</text>"#, lx + 36.0, escape(&p.label));
        ly += 20.0;
    }
    if r.postures.iter().any(|p| p.reference.is_some()) {
        let _ = writeln!(
            s,
            r#"<line x1="{lx:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="black" stroke-width="1.5" stroke-dasharray="6 4"/>"#,
            ly - 4.0,
            lx + 28.0,
            ly - 4.0
        );
        let _ = writeln!(s, r#"<text x="{:.1}" y="{ly:.1}">{}</text>"#, lx + 36.0, escape(overlay));
        ly += 20.0;
    }
    if let Some(p) = shown {
        let _ = writeln!(s, r##"<text x="{lx:.1}" y="{ly:.1}" fill="#555555">grey body: the finger at {} N</text>"##, p.tension);
        ly += 36.0;
        if params.layers > 0 {
            let _ = write!(s, "{}", drawing::volt_scale(lx, ly, v_max));
        }
    }
    let _ = writeln!(s, "</g>");
    if with_stiffness {
        let top = height - panel_h + 10.0;
        let _ = write!(s, "{}", stiffness_panel(r, &cols, ml, top, pw.max(420.0), panel_h - 20.0));
    }
    let _ = writeln!(s, "</svg>");
    s
}

/// The tip-stiffness panel: for each posture with a stiffness, its three diagonal terms
/// (k_xx, k_yy in N/mm, k_θθ in N·mm/rad, base frame) as bars, one small chart per term.
fn stiffness_panel(r: &SceneResult, cols: &[&str], x: f64, y: f64, w: f64, h: f64) -> String {
    let mut s = String::new();
    let _ = writeln!(s, r#"<g class="stiffness-panel">"#);
    let _ = writeln!(s, r#"<text x="{x:.1}" y="{:.1}" font-size="14">Tip stiffness (linearised, base frame)</text>"#, y + 4.0);
    let terms = [(0, "k_xx (N/mm)"), (1, "k_yy (N/mm)"), (2, "k_θθ (N·mm/rad)")];
    let with: Vec<usize> = (0..r.postures.len()).filter(|&i| r.postures[i].stiffness.is_some()).collect();
    let cw = w / 3.0;
    let (ct, cb) = (y + 36.0, y + h - 24.0);
    for (j, (d, name)) in terms.iter().enumerate() {
        let cx = x + j as f64 * cw;
        let vmax = with.iter().map(|&i| r.postures[i].stiffness.unwrap()[*d][*d]).fold(0.0f64, f64::max);
        let _ = writeln!(s, r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{name}</text>"#, cx + cw / 2.0, ct - 10.0);
        let _ = writeln!(s, r#"<line x1="{:.1}" y1="{cb:.1}" x2="{:.1}" y2="{cb:.1}" stroke="black"/>"#, cx + 8.0, cx + cw - 16.0);
        let bw = (cw - 32.0) / with.len().max(1) as f64;
        for (b, &i) in with.iter().enumerate() {
            let v = r.postures[i].stiffness.unwrap()[*d][*d];
            let bh = if vmax > 0.0 && v.is_finite() { (v / vmax).max(0.0) * (cb - ct - 14.0) } else { 0.0 };
            let bx = cx + 12.0 + b as f64 * bw;
            let _ = writeln!(
                s,
                r#"<rect class="stiffness-bar" data-term="{d}" data-tension="{}" x="{bx:.1}" y="{:.1}" width="{:.1}" height="{bh:.1}" fill="{}"/>"#,
                r.postures[i].tension,
                cb - bh,
                bw * 0.8,
                cols[i]
            );
            let _ = writeln!(s, r#"<text x="{:.1}" y="{:.1}" text-anchor="middle" font-size="10">{}</text>"#, bx + bw * 0.4, cb - bh - 3.0, sig3(v));
            let _ = writeln!(
                s,
                r#"<text x="{:.1}" y="{:.1}" text-anchor="middle" font-size="10">{} N</text>"#,
                bx + bw * 0.4,
                cb + 13.0,
                trimmed(r.postures[i].tension)
            );
        }
    }
    let _ = writeln!(s, "</g>");
    s
}

/// Up to 4 decimals, trailing zeros dropped.
fn trimmed(v: f64) -> String {
    let s = format!("{v:.4}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// Three significant figures.
fn sig3(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let d = (2 - v.abs().log10().floor() as i32).max(0) as usize;
    format!("{v:.d$}")
}
