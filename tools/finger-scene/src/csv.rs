//! The CSV tables of a run scene: one row per posture (summary), one row per plotted point
//! (postures). Numbers in Rust's shortest round-trip form: a reader gets the model's f64
//! values exactly.

use crate::run::SceneResult;
use crate::scene::Reference;

/// One row per posture: tension, voltages, thicknesses, joint angles, tip pose, and what the
/// scene asked for (cable excursion, tip stiffness, reference errors). Numbers are written in
/// Rust's shortest round-trip form, so a reader gets the model's f64 values exactly.
pub fn summary_csv(r: &SceneResult) -> String {
    let n = r.n;
    let o = &r.scene.output;
    let mut head = vec!["scene".to_string(), "label".into(), "kind".into(), "tension_N".into()];
    head.extend((1..=n).map(|k| format!("volts{k}_V")));
    head.extend((1..=n).map(|k| format!("thickness{k}_mm")));
    head.extend((1..=n).map(|k| format!("joint{k}_deg")));
    head.extend(["tip_x_mm", "tip_y_mm", "tip_deg"].map(String::from));
    if o.cable_excursion {
        head.push("cable_excursion_mm".into());
    }
    if o.tip_stiffness {
        head.extend(["k_xx_N_per_mm", "k_yy_N_per_mm", "k_tt_Nmm_per_rad", "k_xy_N_per_mm", "k_xt_N_per_rad", "k_yt_N_per_rad"].map(String::from));
    }
    if o.reference != Reference::None {
        head.extend((1..=n).map(|k| format!("ref_joint{k}_deg")));
        head.extend(["ref_tip_x_mm", "ref_tip_y_mm", "ref_tip_deg", "err_tip_mm", "err_tip_deg"].map(String::from));
        head.extend((1..=n).map(|k| format!("err_joint{k}_deg")));
    }
    head.extend(["iterations", "residual_mm"].map(String::from));
    let mut out = head.join(",");
    out.push('\n');
    for p in &r.postures {
        let s = &p.solution;
        let mut row = vec![r.scene.name.clone(), csv_text(&p.label), p.kind.name().into(), p.tension.to_string()];
        row.extend(p.volts.iter().map(|v| v.to_string()));
        row.extend(p.thickness.iter().map(|v| v.to_string()));
        row.extend(p.joint_angles().iter().map(|a| a.to_degrees().to_string()));
        let tip = p.tip();
        row.extend([tip.x, tip.y, tip.theta.to_degrees()].map(|v| v.to_string()));
        if o.cable_excursion {
            row.push(s.cable_excursion.to_string());
        }
        if o.tip_stiffness {
            let k = p.stiffness.unwrap_or([[f64::NAN; 3]; 3]);
            row.extend([k[0][0], k[1][1], k[2][2], k[0][1], k[0][2], k[1][2]].map(|v| v.to_string()));
        }
        if o.reference != Reference::None {
            match &p.reference {
                Some(rf) => {
                    row.extend(rf.joint_angles.iter().map(|a| a.to_degrees().to_string()));
                    let e = ((tip.x - rf.tip.x).powi(2) + (tip.y - rf.tip.y).powi(2)).sqrt();
                    row.extend([rf.tip.x, rf.tip.y, rf.tip.theta.to_degrees(), e, (tip.theta - rf.tip.theta).to_degrees()].map(|v| v.to_string()));
                    row.extend(p.joint_angles().iter().zip(&rf.joint_angles).map(|(a, b)| (a - b).to_degrees().to_string()));
                }
                None => row.extend(std::iter::repeat_n(String::new(), 2 * n + 5)),
            }
        }
        row.push(s.iterations.to_string());
        row.push(s.residual.to_string());
        out.push_str(&row.join(","));
        out.push('\n');
    }
    out
}

/// One row per polyline point: the posture's label, tension, point index, what the point is
/// (node k / hinge k end), x, y (mm). With a reference, its points follow with source=reference.
pub fn postures_csv(r: &SceneResult) -> String {
    let mut out = String::from("scene,posture,label,tension_N,source,point,what,x_mm,y_mm\n");
    for (i, p) in r.postures.iter().enumerate() {
        let m = p.solution.m;
        // one row: what is empty for the reference's points
        let mut row = |source: &str, j: usize, what: &str, pt: &[f64; 2]| {
            out.push_str(&format!("{},{},{},{},{},{},{},{},{}\n", r.scene.name, i + 1, csv_text(&p.label), p.tension, source, j, what, pt[0], pt[1]))
        };
        for (j, pt) in p.points.iter().enumerate() {
            let what = if j == 0 {
                "node 0".to_string()
            } else {
                let k = (j - 1) / (m + 1) + 1;
                let r = (j - 1) % (m + 1);
                if r == m {
                    format!("node {k}")
                } else if r + 1 == m {
                    format!("hinge {k} end")
                } else {
                    format!("hinge {k} sub {}", r + 1)
                }
            };
            row("model", j, &what, pt);
        }
        if let Some(rf) = &p.reference {
            for (j, pt) in rf.points.iter().enumerate() {
                row("reference", j, "", pt);
            }
        }
    }
    out
}

fn csv_text(s: &str) -> String {
    if s.contains(',') || s.contains('"') {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}
