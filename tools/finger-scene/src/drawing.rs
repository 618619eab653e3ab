//! The finger drawn as a researcher sketches it: the clamp at the base, the body (links and
//! elliptical-notch hinges, `model::hinge::notch_thickness`), each joint's DE stack on the
//! extensor side coloured by its voltage, the cable at y = +e through its guide holes, the pull
//! on the cable and any tip load as arrows. Shapes only, in mm (base frame, flexor side +y);
//! the caller maps mm to pixels. Also a colour scale for the voltages, and the stand-alone
//! drawing with the finger's dimensions that the README shows (`finger-scene --drawing FILE`).
//!
//! What it is not: a second model. Every pose comes from a solved `Solution`; the hinge shape
//! between its sub-element ends is interpolated for the picture only.

use finger_model::{hinge::notch_thickness, Finger, Method, Params, Pose, Solution};
use std::fmt::Write;

/// Samples per sub-element when the hinge outline is drawn.
const HINGE_SAMPLES: usize = 12;
/// Clamp block, mm: how far it reaches behind the base and past the body on each side.
const CLAMP_DEPTH: f64 = 8.0;
const CLAMP_MARGIN: f64 = 3.0;

/// The colour of a stack at `volts` on a scale 0..`v_max` (white-yellow to deep red).
pub fn volt_colour(volts: f64, v_max: f64) -> String {
    let s = if v_max > 0.0 { (volts / v_max).clamp(0.0, 1.0) } else { 0.0 };
    // 0: #fde8a0 (pale amber), 1: #b2182b (deep red)
    let lerp = |a: f64, b: f64| (a + (b - a) * s).round() as u8;
    format!("#{:02x}{:02x}{:02x}", lerp(253.0, 178.0), lerp(232.0, 24.0), lerp(160.0, 43.0))
}

/// The pose at `frac` (0..=1) of the way along hinge `k` (0-based) of `sol`.
fn hinge_pose(p: &Params<f64>, sol: &Solution<f64>, k: usize, frac: f64) -> Pose<f64> {
    let sub = p.hinge_len() / sol.m as f64;
    let pos = frac.clamp(0.0, 1.0) * sol.m as f64;
    let mut pose = sol.nodes[k];
    for j in 0..sol.m {
        let q = sol.q[k][j];
        let s = (pos - j as f64).clamp(0.0, 1.0);
        if s <= 0.0 {
            break;
        }
        // linear in (axial, transverse, angle) within one sub-element: a picture, not a solve
        pose = pose.then(s * (sub + q[0]), s * q[1], s * q[2]);
    }
    pose
}

/// Points as an SVG `points` attribute through `map` (mm to pixels).
fn points(v: &[[f64; 2]], map: &dyn Fn([f64; 2]) -> [f64; 2]) -> String {
    v.iter().map(|&q| map(q)).map(|q| format!("{:.2},{:.2}", q[0], q[1])).collect::<Vec<_>>().join(" ")
}

/// Every outline point of the drawing (body, clamp, cable), mm: for the plot's bounds.
pub fn extent(p: &Params<f64>, sol: &Solution<f64>) -> Vec<[f64; 2]> {
    let mut v = outline(p, sol);
    let half = p.b / 2.0 + CLAMP_MARGIN;
    v.push([-CLAMP_DEPTH - 10.0, -half]);
    v.push([0.0, half]);
    v
}

/// The body's outline: the flexor edge from base to tip, then the extensor edge back.
fn outline(p: &Params<f64>, sol: &Solution<f64>) -> Vec<[f64; 2]> {
    let lh = p.hinge_len();
    let (mut top, mut bottom) = (Vec::new(), Vec::new());
    for k in 0..sol.n {
        let samples = HINGE_SAMPLES * sol.m;
        for i in 0..=samples {
            let f = i as f64 / samples as f64;
            let pose = hinge_pose(p, sol, k, f);
            let half = notch_thickness(p.b, p.t_min, p.a, f * lh) / 2.0;
            top.push(pose.point(0.0, half));
            bottom.push(pose.point(0.0, -half));
        }
        let tip = sol.nodes[k + 1];
        top.push(tip.point(0.0, p.b / 2.0));
        bottom.push(tip.point(0.0, -p.b / 2.0));
    }
    top.extend(bottom.into_iter().rev());
    top
}

/// The finger of one posture as an SVG group: clamp, body, stacks (coloured by `volts` on
/// 0..`v_max`), cable and the arrows. `map` takes mm (base frame) to pixels; `px_per_mm` sizes
/// the arrow heads and strokes.
pub fn finger_group(p: &Params<f64>, sol: &Solution<f64>, volts: &[f64], v_max: f64, map: &dyn Fn([f64; 2]) -> [f64; 2], px_per_mm: f64) -> String {
    let mut s = String::new();
    let _ = writeln!(s, r#"<g class="finger">"#);
    // clamp: a hatched block behind the base
    let half = p.b / 2.0 + CLAMP_MARGIN;
    let c0 = map([-CLAMP_DEPTH, half]);
    let c1 = map([0.0, -half]);
    let _ = writeln!(
        s,
        r##"<rect class="clamp" x="{:.2}" y="{:.2}" width="{:.2}" height="{:.2}" fill="url(#hatch)" stroke="#444444" stroke-width="1"/>"##,
        c0[0],
        c0[1],
        c1[0] - c0[0],
        c1[1] - c0[1]
    );
    // body: links and hinges in one outline
    let _ = writeln!(
        s,
        r##"<polygon class="body" points="{}" fill="#e6e6e6" fill-opacity="0.85" stroke="#888888" stroke-width="1"/>"##,
        points(&outline(p, sol), map)
    );
    // hinges: the thinnest section marked
    for k in 0..sol.n {
        let mid = hinge_pose(p, sol, k, 0.5);
        let a = map(mid.point(0.0, p.t_min / 2.0));
        let b = map(mid.point(0.0, -p.t_min / 2.0));
        let _ = writeln!(
            s,
            r##"<line class="hinge" data-joint="{}" x1="{:.2}" y1="{:.2}" x2="{:.2}" y2="{:.2}" stroke="#555555" stroke-width="1.5"/>"##,
            k + 1,
            a[0],
            a[1],
            b[0],
            b[1]
        );
    }
    // stacks: on the extensor side of each hinge, from the thinnest section outward
    if p.layers > 0 {
        for k in 0..sol.n {
            let t = sol.thickness[k];
            let samples = HINGE_SAMPLES * sol.m;
            let (mut inner, mut outer) = (Vec::new(), Vec::new());
            for i in 0..=samples {
                let f = i as f64 / samples as f64;
                let pose = hinge_pose(p, sol, k, f);
                inner.push(pose.point(0.0, -p.t_min / 2.0));
                outer.push(pose.point(0.0, -p.t_min / 2.0 - t));
            }
            inner.extend(outer.into_iter().rev());
            let v = volts.get(k).copied().unwrap_or(0.0);
            let _ = writeln!(
                s,
                r##"<polygon class="stack" data-joint="{}" data-volts="{v}" data-thickness-mm="{t}" points="{}" fill="{}" stroke="#7a4a00" stroke-width="0.8"><title>stack {}: {v:.0} V, {t:.3} mm</title></polygon>"##,
                k + 1,
                points(&inner, map),
                volt_colour(v, v_max),
                k + 1
            );
        }
    }
    // cable: guide holes at y = +e on the base, on each link's proximal end and at each node
    let mut cable = vec![[-CLAMP_DEPTH - 10.0, p.e], sol.nodes[0].point(0.0, p.e)];
    for k in 0..sol.n {
        cable.push(hinge_pose(p, sol, k, 1.0).point(0.0, p.e));
        cable.push(sol.nodes[k + 1].point(0.0, p.e));
    }
    let _ = writeln!(s, r##"<polyline class="cable" points="{}" fill="none" stroke="#1a1a1a" stroke-width="1.2"/>"##, points(&cable, map));
    let anchor = map(sol.nodes[sol.n].point(0.0, p.e));
    let _ = writeln!(s, r##"<circle class="cable-anchor" cx="{:.2}" cy="{:.2}" r="2.5" fill="#1a1a1a"/>"##, anchor[0], anchor[1]);
    // the pull on the cable, at its free end behind the clamp
    if sol.tension > 0.0 {
        let from = map([-CLAMP_DEPTH - 2.0, p.e]);
        let to = map([-CLAMP_DEPTH - 10.0, p.e]);
        let _ = writeln!(s, "{}", arrow("load", from, to, px_per_mm, &format!("P = {} N", g4(sol.tension))));
    }
    // an external tip load, drawn at the tip along its direction
    let f = sol.tip_force;
    let fm = (f[0] * f[0] + f[1] * f[1]).sqrt();
    if fm > 0.0 {
        let tip = sol.nodes[sol.n];
        let len = 12.0;
        let to = map([tip.x, tip.y]);
        let from = map([tip.x - len * f[0] / fm, tip.y - len * f[1] / fm]);
        let _ = writeln!(s, "{}", arrow("load contact", from, to, px_per_mm, &format!("F = {} N", g4(fm))));
    }
    let _ = writeln!(s, "</g>");
    s
}

/// A number with up to 4 decimals, trailing zeros dropped.
fn g4(x: f64) -> String {
    let s = format!("{x:.4}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// An arrow from `from` to `to` (pixels) with a label at its tail.
fn arrow(class: &str, from: [f64; 2], to: [f64; 2], _px_per_mm: f64, label: &str) -> String {
    let (dx, dy) = (to[0] - from[0], to[1] - from[1]);
    let l = (dx * dx + dy * dy).sqrt().max(1e-9);
    let (ux, uy) = (dx / l, dy / l);
    let h = 8.0;
    let (bx, by) = (to[0] - h * ux, to[1] - h * uy);
    let (nx, ny) = (-uy * h * 0.45, ux * h * 0.45);
    format!(
        r##"<g class="{class}"><line x1="{:.2}" y1="{:.2}" x2="{bx:.2}" y2="{by:.2}" stroke="#0b5394" stroke-width="2"/><polygon points="{:.2},{:.2} {:.2},{:.2} {:.2},{:.2}" fill="#0b5394"/><text x="{:.2}" y="{:.2}" fill="#0b5394" text-anchor="middle">{label}</text></g>"##,
        from[0],
        from[1],
        to[0],
        to[1],
        bx + nx,
        by + ny,
        bx - nx,
        by - ny,
        (from[0] + to[0]) / 2.0,
        (from[1] + to[1]) / 2.0 - 8.0
    )
}

/// The `<defs>` the finger group uses (the clamp's hatching).
pub fn defs() -> &'static str {
    r##"<defs><pattern id="hatch" width="6" height="6" patternUnits="userSpaceOnUse" patternTransform="rotate(45)"><rect width="6" height="6" fill="#f4f4f4"/><line x1="0" y1="0" x2="0" y2="6" stroke="#777777" stroke-width="1.5"/></pattern></defs>"##
}

/// A vertical colour scale for the stack voltages, 0..`v_max` V, top-left at (x, y) px.
pub fn volt_scale(x: f64, y: f64, v_max: f64) -> String {
    let mut s = String::new();
    let (w, h, steps) = (14.0, 100.0, 20);
    let _ = writeln!(s, r#"<g class="volt-scale">"#);
    let _ = writeln!(s, r#"<text x="{x:.1}" y="{:.1}" font-weight="bold">stack voltage</text>"#, y - 6.0);
    for i in 0..steps {
        let v = v_max * (1.0 - (i as f64 + 0.5) / steps as f64);
        let _ = writeln!(
            s,
            r#"<rect x="{x:.1}" y="{:.2}" width="{w}" height="{:.2}" fill="{}"/>"#,
            y + h * i as f64 / steps as f64,
            h / steps as f64 + 0.3,
            volt_colour(v, v_max)
        );
    }
    let _ = writeln!(s, r##"<rect x="{x:.1}" y="{y:.1}" width="{w}" height="{h}" fill="none" stroke="#444444"/>"##);
    let _ = writeln!(s, r#"<text x="{:.1}" y="{:.1}">{:.1} kV (ceiling)</text>"#, x + w + 6.0, y + 10.0, v_max / 1000.0);
    let _ = writeln!(s, r#"<text x="{:.1}" y="{:.1}">0 V</text>"#, x + w + 6.0, y + h);
    let _ = writeln!(s, "</g>");
    s
}

/// The stand-alone drawing of the default finger (docs/model.md "Geometry") for the front page:
/// straight and unpowered, with its dimensions (l, b, L_h, t_min, e), and bent at `tension` N
/// with its stacks at `volts` (V, all three), both from the model's solve.
pub fn dimensioned(params: Params<f64>, tension: f64, volts: f64) -> Result<String, finger_model::Error> {
    let finger = Finger::new(params)?;
    let p = *finger.params();
    let v = [volts; finger_model::MAX_JOINTS];
    let straight = finger.solve(0.0, &[0.0; finger_model::MAX_JOINTS][..p.n], Method::converged())?;
    let bent = finger.solve(tension, &v[..p.n], Method::converged())?;
    let v_max = finger.voltage_ceiling();
    let scale = 6.0; // px per mm
    let (w_mm, x0) = (p.l * p.n as f64 + 40.0, -CLAMP_DEPTH - 14.0);
    let width = w_mm * scale + 180.0;
    let tip_y = bent.nodes[p.n].y;
    let (ytop, ybot) = (tip_y + p.b + 8.0, -p.b - 20.0);
    let strip = (ytop - ybot) * scale;
    let height = strip + 60.0;
    let map = move |q: [f64; 2]| [20.0 + (q[0] - x0) * scale, 40.0 + (ytop - q[1]) * scale];
    let mut s = String::new();
    let _ = writeln!(s, r#"<?xml version="1.0" encoding="UTF-8"?>"#);
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" version="1.1" width="{width:.0}" height="{height:.0}" viewBox="0 0 {width:.0} {height:.0}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, "{}", defs());
    let _ = writeln!(s, r#"<rect x="0" y="0" width="{width:.0}" height="{height:.0}" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="20" y="22" font-size="15">The finger (the default geometry): straight at 0 N, and at {} N with {:.1} kV on every stack</text>"#,
        g4(tension),
        volts / 1000.0
    );
    let mut g = finger_group(&p, &straight, &[0.0; 3][..p.n], v_max, &map, scale);
    g = g.replacen(r#"<g class="finger">"#, r#"<g class="finger straight" opacity="0.5">"#, 1);
    let _ = write!(s, "{g}");
    let _ = write!(s, "{}", finger_group(&p, &bent, &v[..p.n], v_max, &map, scale));
    // dimensions on the straight finger
    let dim = |s: &mut String, a: [f64; 2], b: [f64; 2], label: &str, vertical: bool| {
        let (pa, pb) = (map(a), map(b));
        let _ = writeln!(
            s,
            r##"<g class="dimension"><line x1="{:.2}" y1="{:.2}" x2="{:.2}" y2="{:.2}" stroke="#0b5394" stroke-width="1" marker-start="url(#tick)" marker-end="url(#tick)"/><text x="{:.2}" y="{:.2}" fill="#0b5394" text-anchor="{}">{label}</text></g>"##,
            pa[0],
            pa[1],
            pb[0],
            pb[1],
            if vertical { pa[0] + 6.0 } else { (pa[0] + pb[0]) / 2.0 },
            if vertical { (pa[1] + pb[1]) / 2.0 + 4.0 } else { pa[1] + 14.0 },
            if vertical { "start" } else { "middle" }
        );
    };
    let _ = writeln!(
        s,
        r##"<defs><marker id="tick" markerWidth="2" markerHeight="10" refX="1" refY="5" orient="auto"><line x1="1" y1="0" x2="1" y2="10" stroke="#0b5394" stroke-width="1.5"/></marker></defs>"##
    );
    let yb = -p.b / 2.0 - 8.0;
    dim(&mut s, [0.0, yb], [p.l, yb], &format!("l = {} mm (pitch)", g4(p.l)), false);
    dim(&mut s, [p.l, yb - 7.0], [p.l + p.hinge_len(), yb - 7.0], &format!("L_h = 2a = {} mm", g4(p.hinge_len())), false);
    let xe = p.l * p.n as f64 + 4.0;
    dim(&mut s, [xe, -p.b / 2.0], [xe, p.b / 2.0], &format!("b = {} mm", g4(p.b)), true);
    dim(&mut s, [xe + 24.0, 0.0], [xe + 24.0, p.e], &format!("e = {} mm (cable)", g4(p.e)), true);
    let xm = 2.0 * p.l + p.a;
    let tl = map([xm, -p.t_min / 2.0 - 0.2]);
    let _ = writeln!(
        s,
        r##"<text class="dimension" x="{:.2}" y="{:.2}" fill="#0b5394" text-anchor="middle">t_min = {} mm</text>"##,
        tl[0],
        map([0.0, -p.b / 2.0 - 3.0])[1] + 2.0,
        g4(p.t_min)
    );
    let lx = map([p.l * p.n as f64 + 8.0, 0.0])[0] + 90.0;
    let _ = write!(s, "{}", volt_scale(lx, 60.0, v_max));
    let _ = writeln!(
        s,
        r##"<text x="20" y="{:.1}" fill="#333333">width out of the plane w = {} mm; {} DE layers per stack, each {} mm; the stacks (colour: voltage) sit on the extensor side, the cable on the flexor side</text>"##,
        height - 12.0,
        g4(p.w),
        p.layers,
        g4(p.z0)
    );
    let _ = writeln!(s, "</svg>");
    Ok(s)
}
