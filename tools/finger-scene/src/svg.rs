//! Posture plots as hand-written SVG, like the paper's figure 4: each posture a polyline
//! through the node and hinge-end positions (class `posture`), one colour per tension, a
//! legend, axes in mm with equal aspect (x right, y up: the flexor side is up). A continuum
//! reference, when the scene asks for one, is drawn dashed in its posture's colour (class
//! `reference`).
//!
//! What it is not: a plotting library. No dependency; the output is plain SVG 1.1.

use crate::run::{Kind, SceneResult};
use std::fmt::Write;

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
    let mut xs = vec![0.0f64];
    let mut ys = vec![0.0f64];
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
    let scale = (560.0 / (x1 - x0)).min(560.0 / (y1 - y0));
    let (ml, mt, mb) = (64.0, 48.0, 52.0);
    let pw = (x1 - x0) * scale;
    let ph = (y1 - y0) * scale;
    let longest = r.postures.iter().map(|p| p.label.chars().count()).max().unwrap_or(0).max(20);
    let legend_w = 48.0 + 7.0 * longest as f64;
    let width = ml + pw + 24.0 + legend_w;
    let height = (mt + ph + mb).max(mt + 24.0 * (r.postures.len() as f64 + 2.0));
    let px = |x: f64| ml + (x - x0) * scale;
    let py = |y: f64| mt + (y1 - y) * scale;

    let mut s = String::new();
    let _ = writeln!(s, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" version="1.1" width="{width:.0}" height="{height:.0}" viewBox="0 0 {width:.0} {height:.0}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect x="0" y="0" width="{width:.0}" height="{height:.0}" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{ml:.1}" y="24" font-size="15">{}</text>"#,
        escape(&r.scene.title)
    );
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
    let _ = writeln!(
        s,
        r#"<rect x="{:.2}" y="{:.2}" width="{pw:.2}" height="{ph:.2}" fill="none" stroke="black" stroke-width="1"/>"#,
        px(x0),
        py(y1)
    );
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
    let _ = writeln!(
        s,
        r#"<text x="{:.2}" y="{:.2}" text-anchor="middle">x (mm)</text>"#,
        ml + pw / 2.0,
        py(y0) + 36.0
    );
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
                r#"<polyline class="reference" data-tension="{}" points="{}" fill="none" stroke="{c}" stroke-width="1.5" stroke-dasharray="6 4"/>"#,
                p.tension,
                pts(&rf.points)
            );
        }
    }
    for (p, c) in r.postures.iter().zip(&cols) {
        let dash = if p.kind == Kind::MatchTarget { r#" stroke-dasharray="2 3""# } else { "" };
        let _ = writeln!(
            s,
            r#"<polyline class="posture" data-tension="{}" points="{}" fill="none" stroke="{c}" stroke-width="2"{dash}/>"#,
            p.tension,
            pts(&p.points)
        );
        for node in &p.solution.nodes[..=p.solution.n] {
            let _ = writeln!(
                s,
                r#"<circle class="node" cx="{:.3}" cy="{:.3}" r="2.5" fill="{c}"/>"#,
                px(node.x),
                py(node.y)
            );
        }
    }
    // legend
    let lx = ml + pw + 24.0;
    let mut ly = mt + 8.0;
    let _ = writeln!(s, r#"<g class="legend">"#);
    let _ = writeln!(s, r#"<text x="{lx:.1}" y="{ly:.1}" font-weight="bold">cable tension</text>"#);
    ly += 20.0;
    for (p, c) in r.postures.iter().zip(&cols) {
        let dash = if p.kind == Kind::MatchTarget { r#" stroke-dasharray="2 3""# } else { "" };
        let _ = writeln!(
            s,
            r#"<line x1="{lx:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="{c}" stroke-width="2"{dash}/>"#,
            ly - 4.0,
            lx + 28.0,
            ly - 4.0
        );
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
    }
    let _ = writeln!(s, "</g>");
    let _ = writeln!(s, "</svg>");
    s
}
