//! Scenes: parsing, errors with line numbers, every shipped scene runs, the refused
//! scene is refused with no output file, the CSV is the model's own numbers, the SVG is
//! well-formed with one polyline per posture.

use finger_model::{de, Error, Finger, Method, Params};
use finger_scene::{self as scene, Drive, Kind, Pos, Reference, SceneResult, SolverSpec};
use std::path::{Path, PathBuf};

fn top() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// `finger-scene <scene> --out <out>`, as a user runs it.
fn run_cli(scene: &Path, out: &Path) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_finger-scene")).arg(scene).arg("--out").arg(out).output().unwrap()
}

fn shipped(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).filter(|p| p.extension().is_some_and(|x| x == "toml")).collect();
    v.sort();
    v
}

/// A shipped scene run without its continuum overlay (for tests of the model's side only).
fn without_reference(name: &str) -> SceneResult {
    let text = std::fs::read_to_string(top().join(format!("scenes/{name}.toml"))).unwrap();
    let mut s = scene::parse(name, &text).unwrap();
    s.output.reference = Reference::None;
    scene::run(&s, None).unwrap()
}

fn run_text(text: &str) -> Result<SceneResult, scene::SceneError> {
    let s = scene::parse("t", text)?;
    scene::run(&s, None)
}

/// Parse a CSV (no quoted commas in the columns read here) into header + rows.
fn csv(text: &str) -> (Vec<String>, Vec<Vec<String>>) {
    let mut lines = text.lines();
    let head = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines.map(|l| l.split(',').map(String::from).collect()).collect();
    (head, rows)
}

fn col(head: &[String], name: &str) -> usize {
    head.iter().position(|h| h == name).unwrap_or_else(|| panic!("no column {name} in {head:?}"))
}

#[test]
fn parses_every_section() {
    let text = "# comment\ntitle = \"Hello\"\n[finger]\npreset = \"paper\"\nlayers = 4   # trailing comment\nw = 18\n\
                thickness = [1.9, 2.0, 1.95]\n[drive]\ntensions = [0, 0.25,1]\n[solver]\nmethod = \"stepping\"\nn_inc = 7\n\
                [output]\npostures = false\ntip_stiffness = true\ncable_excursion = false\nreference = \"none\"\n";
    let s = scene::parse("x", text).unwrap();
    assert_eq!(s.title, "Hello");
    assert_eq!(s.finger.params.de_rule, Params::<f64>::paper().de_rule);
    assert_eq!(s.finger.params.layers, 4);
    assert_eq!(s.finger.params.w, 18.0);
    assert_eq!(s.finger.drive, Drive::Thickness(vec![1.9, 2.0, 1.95]));
    assert_eq!(s.finger.drive_at, Pos { line: 7, column: 1 });
    assert_eq!(s.tensions, vec![0.0, 0.25, 1.0]);
    assert_eq!(s.solver, SolverSpec::Stepping { n_inc: 7 });
    assert!(!s.output.postures && s.output.tip_stiffness && !s.output.cable_excursion);
    assert_eq!(s.output.reference, Reference::None);

    // defaults: the default preset, 0 V, converged, postures and excursion, no stiffness
    let d = scene::parse("d", "[drive]\ntensions = 0.5\n").unwrap();
    assert_eq!(d.finger.params, Params::<f64>::default());
    assert_eq!(d.finger.drive, Drive::Volts(vec![0.0; 3]));
    assert!(matches!(d.solver, SolverSpec::Converged { .. }));
    assert!(d.output.postures && d.output.cable_excursion && !d.output.tip_stiffness);

    // one value for every joint
    let u = scene::parse("u", "[finger]\nvolts = 500\n[drive]\ntensions = [1]\n").unwrap();
    assert_eq!(u.finger.drive, Drive::Volts(vec![500.0; 3]));
}

#[test]
fn overrides_apply_whatever_their_order() {
    // `a = 15` alone breaks 2a < l = 27; with `l = 40` after it the set is valid.
    let s = scene::parse("o", "[finger]\na = 15\nl = 40\n[drive]\ntensions = [0.1]\n").unwrap();
    assert_eq!((s.finger.params.a, s.finger.params.l), (15.0, 40.0));
    // alone, it is refused at its line, naming the parameter
    let e = scene::parse("o", "[finger]\nb = 12\n  a = 15\n[drive]\ntensions = 0.1\n").unwrap_err();
    assert_eq!((e.line, e.column), (3, 3), "{e}");
    assert!(matches!(e.model, Some(Error::Param { name: "a", .. })), "{e:?}");
}

#[test]
fn errors_name_their_line_and_column() {
    // (text, line, column, what): toml's errors at toml's span, ours at the key
    let cases: &[(&str, usize, usize, &str)] = &[
        ("[drive]\ntensions = 1\n[bogus]\n", 3, 2, "unknown section [bogus]"),
        ("[drive]\ntensions = 1\ncolour = \"red\"\n", 3, 1, "unknown key `colour` in [drive]"),
        ("[finger]\nlayers = \"four\"\n[drive]\ntensions = 1\n", 2, 1, "not a number"),
        ("[finger]\nlayers = 4\nlayers = 3\n[drive]\ntensions = 1\n", 3, 1, "duplicate key `layers` (first on line 2)"),
        ("[drive]\ntensions = 1\njust words\n", 3, 6, "expected"),
        ("[finger]\nvolts = [0,0,0]\nthickness = [2,2,2]\n[drive]\ntensions = 1\n", 3, 1, "already given on line 2"),
        ("[finger]\n  volts = [0, 0]\n[drive]\ntensions = 1\n", 2, 3, "2 values for 3 joints"),
        ("[drive]\ntensions = [0.5, -1]\n", 2, 1, "cannot push"),
        ("[drive]\ntensions = 1\ntension = 2\n", 3, 1, "tensions are already given on line 2"),
        ("[drive]\ntensions = [1, nan]\n", 2, 1, "not a finite number"),
        ("[drive]\ntensions = 1\n[solver]\nn_inc = 10\n", 4, 1, "only for method = \"stepping\""),
        ("[drive]\ntensions = 1\n[solver]\nmethod = \"newton\"\n", 4, 10, "unknown variant `newton`, expected `converged` or `stepping`"),
        ("[finger]\nt_min = 20\n[drive]\ntensions = 1\n", 2, 1, "t_min"),
        ("[finger]\nnu = 0.7\n[drive]\ntensions = 1\n", 2, 1, "nu"),
        ("[drive]\ntensions = 1\n[drive]\n", 3, 2, "duplicate key `drive` (first on line 1)"),
        ("[drive]\ntensions = 1\n[output]\npostures = \"maybe\"\n", 4, 12, "expected a boolean"),
        ("[drive]\ntensions = 1\n[match]\nlayers = 0\n", 3, 1, "needs `tension"),
        ("[finger]\npreset = \"fancy\"\n[drive]\ntensions = 1\n", 2, 1, "not \"default\" or \"paper\""),
        ("title = \"x\"\n", 0, 0, "no tensions"),
    ];
    for (text, line, column, what) in cases {
        let e = scene::parse("e", text).unwrap_err();
        assert_eq!((e.line, e.column), (*line, *column), "{text:?}: {e}");
        assert!(e.to_string().contains(what), "{text:?}: `{e}` lacks `{what}`");
        if *line > 0 {
            assert!(e.to_string().starts_with(&format!("line {line}, column {column}: ")), "{e}");
        }
    }
}

#[test]
fn the_old_format_is_refused_with_a_pointer_to_the_new_one() {
    // INI content: toml's error at its place, and the pointer
    let old = "[finger]\npreset = paper\nvolts = 0, 0, 0\n[drive]\ntensions = 0, 0.2\n";
    let e = scene::parse("old", old).unwrap_err();
    assert_eq!((e.line, e.column), (2, 10), "{e}");
    assert!(e.message.contains("old INI scene format") && e.message.contains("docs/scenes.md"), "{e}");
    // a .scene file, whatever it holds, is refused before it is read
    let dir = std::env::temp_dir().join(format!("finger-scene-old-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let f = dir.join("x.scene");
    std::fs::write(&f, "[drive]\ntensions = 1\n").unwrap();
    let e = scene::run_file(&f, None).unwrap_err();
    assert!(e.message.contains("x.scene") && e.message.contains("TOML") && e.message.contains("docs/scenes.md"), "{e}");
    // and the command says so, writing nothing
    let out = dir.join("out");
    let o = run_cli(&f, &out);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("docs/scenes.md"));
    assert!(!out.exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn model_refusals_name_joint_limit_and_line() {
    // a voltage past the ceiling at joint 2
    let p = Params::<f64>::default();
    let ceiling = de::voltage_ceiling(&p);
    let text = format!("[finger]\nvolts = [0, {}, 0]\n[drive]\ntensions = 1\n", ceiling * 1.01);
    let e = run_text(&text).unwrap_err();
    assert_eq!(e.line, 2);
    assert!(matches!(e.model, Some(Error::VoltageCeiling { joint: 2, .. })), "{e:?}");
    // a thickness past 33 % at joint 3
    let limit = p.layers as f64 * p.z0 * 2.0 / 3.0;
    let text = format!("[finger]\n thickness = [2, 2, {}]\n[drive]\ntensions = 1\n", limit * 0.99);
    let e = run_text(&text).unwrap_err();
    assert_eq!((e.line, e.column), (2, 2));
    match e.model {
        Some(Error::ThicknessLimit { joint, limit_mm, .. }) => {
            assert_eq!(joint, 3);
            assert!((limit_mm - limit).abs() < 1e-12);
        }
        other => panic!("{other:?}"),
    }
    assert!(e.to_string().contains("joint 3") && e.to_string().contains(&format!("{limit:.3}")), "{e}");
}

#[test]
fn every_shipped_scene_runs_and_the_refused_one_is_refused() {
    let dir = top().join("scenes");
    let files = shipped(&dir);
    assert!(files.len() >= 6, "scenes/ holds {} scenes", files.len());
    let reference = scene::reference_solver();
    for f in &files {
        let r = scene::run_file(f, reference.as_deref()).unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        assert_eq!(r.postures.len(), r.scene.tensions.len() + r.scene.matching.as_ref().map_or(0, |m| 1 + m.show as usize));
        for p in &r.postures {
            assert!(p.points.iter().flatten().all(|x| x.is_finite()));
        }
        assert!(!scene::outputs(&r).is_empty());
    }
    let refused = shipped(&dir.join("refused"));
    assert!(!refused.is_empty());
    for f in &refused {
        let e = scene::run_file(f, None).unwrap_err();
        assert!(matches!(e.model, Some(Error::ThicknessLimit { .. })), "{}: {e:?}", f.display());
        assert!(e.line > 0);
    }
}

#[test]
fn the_papers_2mm_to_1mm_request_writes_no_file_and_exits_nonzero() {
    let out = std::env::temp_dir().join(format!("finger-scene-refused-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out);
    let scene = top().join("scenes/refused/paper-2mm-to-1mm.toml");
    let o = run_cli(&scene, &out);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "stderr: {err}");
    let p = Params::<f64>::paper();
    let limit = p.layers as f64 * p.z0 * 2.0 / 3.0;
    assert!(err.contains("joint 1"), "{err}");
    assert!(err.contains(&format!("{limit:.3} mm")), "{err}");
    assert!(err.contains("paper-2mm-to-1mm.toml:9:1: thickness: joint 1"), "{err}");
    assert!(!out.exists(), "a refused scene created {}", out.display());

    // the same command on a good scene writes its three files
    let good = top().join("scenes/paper-de-0v.toml");
    let o = run_cli(&good, &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["paper-de-0v.csv", "paper-de-0v-postures.csv", "paper-de-0v.svg"] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let _ = std::fs::remove_dir_all(&out);

    // usage errors are status 2
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_finger-scene")).output().unwrap();
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn csv_is_the_models_own_solution() {
    let path = top().join("scenes/paper-de-joint1-thin.toml");
    let r = scene::run_file(&path, scene::reference_solver().as_deref()).unwrap();
    let Drive::Thickness(th) = &r.scene.finger.drive else { panic!("scene drives by thickness") };
    let p = r.scene.finger.params;
    let f = Finger::new(p).unwrap();
    let volts: Vec<f64> = th.iter().enumerate().map(|(k, &t)| de::voltage_for_thickness(&p, k + 1, t).unwrap()).collect();
    let (head, rows) = csv(&scene::summary_csv(&r));
    assert_eq!(rows.len(), r.scene.tensions.len());
    let num = |row: &Vec<String>, name: &str| -> f64 { row[col(&head, name)].parse().unwrap() };
    for (row, &t) in rows.iter().zip(&r.scene.tensions) {
        let s = f.solve(t, &volts, Method::converged()).unwrap();
        assert_eq!(num(row, "tension_N"), t);
        for k in 0..3 {
            assert_eq!(num(row, &format!("volts{}_V", k + 1)), volts[k]);
            assert_eq!(num(row, &format!("joint{}_deg", k + 1)), s.joint_angle[k].to_degrees());
            // the stack is the thickness asked for
            assert!((num(row, &format!("thickness{}_mm", k + 1)) - th[k]).abs() < 1e-9);
        }
        assert_eq!(num(row, "tip_x_mm"), s.tip().x);
        assert_eq!(num(row, "tip_y_mm"), s.tip().y);
        assert_eq!(num(row, "tip_deg"), s.tip().theta.to_degrees());
        assert_eq!(num(row, "cable_excursion_mm"), s.cable_excursion);
    }
    // the postures CSV: its node rows are the solution's nodes
    let (head, rows) = csv(&scene::postures_csv(&r));
    for (i, &t) in r.scene.tensions.iter().enumerate() {
        let s = f.solve(t, &volts, Method::converged()).unwrap();
        let nodes: Vec<&Vec<String>> =
            rows.iter().filter(|row| row[col(&head, "posture")] == (i + 1).to_string() && row[col(&head, "what")].starts_with("node")).collect();
        assert_eq!(nodes.len(), 4);
        for (k, row) in nodes.iter().enumerate() {
            assert_eq!(row[col(&head, "x_mm")].parse::<f64>().unwrap(), s.nodes[k].x);
            assert_eq!(row[col(&head, "y_mm")].parse::<f64>().unwrap(), s.nodes[k].y);
        }
    }
}

#[test]
fn stiffness_only_when_asked_and_equal_to_the_models() {
    let base = "[finger]\npreset = \"paper\"\n[drive]\ntensions = [0.3, 0.9]\n";
    let r = run_text(base).unwrap();
    assert!(r.postures.iter().all(|p| p.stiffness.is_none()));
    assert!(!scene::summary_csv(&r).contains("k_yy"));
    let r = run_text(&format!("{base}[output]\ntip_stiffness = true\ncable_excursion = false\npostures = false\n")).unwrap();
    let f = Finger::new(Params::<f64>::paper()).unwrap();
    let (head, rows) = csv(&scene::summary_csv(&r));
    assert!(!head.iter().any(|h| h == "cable_excursion_mm"));
    for (row, t) in rows.iter().zip([0.3, 0.9]) {
        let k = f.tip_stiffness(&f.solve(t, &[0.0; 3], Method::converged()).unwrap()).unwrap();
        assert_eq!(row[col(&head, "k_yy_N_per_mm")].parse::<f64>().unwrap(), k[1][1]);
        assert_eq!(row[col(&head, "k_tt_Nmm_per_rad")].parse::<f64>().unwrap(), k[2][2]);
    }
    // postures = no: only the summary CSV
    let files = scene::outputs(&r);
    assert_eq!(files.len(), 1);
    assert!(files[0].0.ends_with(".csv"));
}

#[test]
fn stepping_scene_is_the_papers_stepping() {
    let r = without_reference("paper-no-de-stepping");
    let SolverSpec::Stepping { n_inc } = r.scene.solver else { panic!("stepping scene") };
    let f = Finger::new(r.scene.finger.params).unwrap();
    for p in &r.postures {
        let s = f.solve(p.tension, &[0.0; 3], Method::Stepping { n_inc }).unwrap();
        assert_eq!(p.tip().y, s.tip().y);
        assert_eq!(p.solution.iterations, n_inc);
    }
}

#[test]
fn match_finds_the_tension_of_equal_tip_angle() {
    let r = without_reference("paper-no-de");
    let m = r.scene.matching.as_ref().unwrap();
    let tm = r.matched_tension.unwrap();
    let matched = r.postures.iter().find(|p| p.kind == Kind::Matched).unwrap();
    let target = r.postures.iter().find(|p| p.kind == Kind::MatchTarget).unwrap();
    assert_eq!(matched.tension, tm);
    assert_eq!(target.tension, m.tension);
    assert!((matched.tip().theta - target.tip().theta).abs() < 1e-9);
    // the stacks stiffen the finger: the finger without them needs less tension
    assert!(tm > 0.0 && tm < m.tension, "{tm}");
    // and, the joints being alike and decoupled, every joint angle matches
    for (a, b) in matched.joint_angles().iter().zip(target.joint_angles()) {
        assert!((a - b).abs() < 1e-9, "{a} {b}");
    }
}

#[test]
fn reference_without_a_solver_is_a_clear_error() {
    let e = run_text("[drive]\ntensions = 1\n[output]\nreference = \"continuum\"\n").unwrap_err();
    assert_eq!(e.line, 3);
    assert!(e.to_string().contains("continuum"));
}

/// A small XML well-formedness check: balanced tags, one root, quoted attributes, no raw `<`
/// or stray `&` in text or attribute values.
fn check_xml(s: &str) -> Result<usize, String> {
    let b = s.as_bytes();
    let mut i = 0;
    let mut stack: Vec<String> = Vec::new();
    let mut roots = 0;
    let entity_ok = |rest: &str| ["&amp;", "&lt;", "&gt;", "&quot;", "&apos;"].iter().any(|e| rest.starts_with(e));
    let mut elements = 0;
    while i < b.len() {
        if b[i] == b'<' {
            if s[i..].starts_with("<?") {
                i += s[i..].find("?>").ok_or("unclosed <?")? + 2;
                continue;
            }
            let end = i + s[i..].find('>').ok_or("unclosed tag")?;
            let tag = &s[i + 1..end];
            if let Some(name) = tag.strip_prefix('/') {
                let open = stack.pop().ok_or(format!("stray </{name}>"))?;
                if open != name.trim() {
                    return Err(format!("<{open}> closed by </{name}>"));
                }
            } else {
                let selfclose = tag.ends_with('/');
                let body = tag.trim_end_matches('/');
                let name: String = body.chars().take_while(|c| !c.is_whitespace()).collect();
                if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == ':') {
                    return Err(format!("bad tag name in <{tag}>"));
                }
                // attributes: name="value"
                let mut rest = body[name.len()..].trim();
                while !rest.is_empty() {
                    let eq = rest.find('=').ok_or(format!("attribute without value in <{tag}>"))?;
                    let an = rest[..eq].trim();
                    if an.is_empty() || an.contains(char::is_whitespace) {
                        return Err(format!("bad attribute name in <{tag}>"));
                    }
                    let v = rest[eq + 1..].trim_start();
                    let v = v.strip_prefix('"').ok_or(format!("unquoted attribute in <{tag}>"))?;
                    let close = v.find('"').ok_or("unclosed attribute")?;
                    let val = &v[..close];
                    if val.contains('<') {
                        return Err(format!("< in attribute of <{tag}>"));
                    }
                    for (j, _) in val.match_indices('&') {
                        if !entity_ok(&val[j..]) {
                            return Err(format!("bare & in <{tag}>"));
                        }
                    }
                    rest = v[close + 1..].trim_start();
                }
                if stack.is_empty() {
                    roots += 1;
                }
                elements += 1;
                if !selfclose {
                    stack.push(name);
                }
            }
            i = end + 1;
        } else {
            if b[i] == b'&' && !entity_ok(&s[i..]) {
                return Err("bare & in text".into());
            }
            if b[i] == b'>' && !stack.is_empty() {
                // a '>' in text is legal XML; nothing to do
            }
            i += 1;
        }
    }
    if !stack.is_empty() {
        return Err(format!("unclosed <{}>", stack.last().unwrap()));
    }
    if roots != 1 {
        return Err(format!("{roots} root elements"));
    }
    Ok(elements)
}

#[test]
fn the_xml_checker_catches_what_it_should() {
    assert!(check_xml("<svg><g></g></svg>").is_ok());
    assert!(check_xml("<svg><g></svg>").is_err());
    assert!(check_xml("<svg a=b/>").is_err());
    assert!(check_xml("<svg>a & b</svg>").is_err());
    assert!(check_xml("<svg/><svg/>").is_err());
}

#[test]
fn svg_is_well_formed_with_one_polyline_per_posture() {
    let reference = scene::reference_solver();
    for name in ["paper-no-de", "paper-de-uniform"] {
        let r = scene::run_file(&top().join(format!("scenes/{name}.toml")), reference.as_deref()).unwrap();
        let svg = finger_scene::svg::plot(&r);
        check_xml(&svg).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(svg.contains("<svg xmlns=\"http://www.w3.org/2000/svg\""));
        let polys: Vec<&str> = svg.lines().filter(|l| l.contains("<polyline class=\"posture\"")).collect();
        assert_eq!(polys.len(), r.postures.len(), "{name}");
        // the continuum overlay: one dashed polyline per posture, when asked
        let refs = svg.lines().filter(|l| l.contains("<polyline class=\"reference\"")).count();
        let asked = r.scene.output.reference == Reference::Continuum;
        assert_eq!(refs, if asked { r.postures.len() } else { 0 }, "{name}");
        for (line, p) in polys.iter().zip(&r.postures) {
            let pts = line.split("points=\"").nth(1).unwrap().split('"').next().unwrap();
            assert_eq!(pts.split(' ').count(), p.points.len());
            assert!(line.contains(&format!("data-tension=\"{}\"", p.tension)));
        }
        // a legend entry for each posture, and the axes in mm
        for p in &r.postures {
            assert!(svg.contains(&finger_scene::svg::escape(&p.label)));
        }
        assert!(svg.contains("x (mm)") && svg.contains("y (mm)"));
        // one colour per posture
        let cols = finger_scene::svg::colours(&r);
        let mut uniq = cols.clone();
        uniq.sort();
        uniq.dedup();
        assert_eq!(uniq.len(), cols.len());
    }
}

/// The (x, y) pixel points of an SVG `<polyline ... points="x,y x,y ...">` line.
fn polyline_points(line: &str) -> Vec<[f64; 2]> {
    let pts = line.split("points=\"").nth(1).unwrap().split('"').next().unwrap();
    pts.split(' ')
        .map(|p| {
            let mut it = p.split(',').map(|v| v.parse::<f64>().unwrap());
            [it.next().unwrap(), it.next().unwrap()]
        })
        .collect()
}

#[test]
fn svg_has_equal_aspect() {
    // the straight finger (0 N) spans n*l mm along x; the plotted polyline must span the same
    // number of pixels per mm as a vertical segment of the grid
    let r = run_text("[drive]\ntensions = [0, 2]\n").unwrap();
    let svg = finger_scene::svg::plot(&r);
    let line = svg.lines().find(|l| l.contains("class=\"posture\"")).unwrap();
    let pts = polyline_points(line);
    let sx = (pts.last().unwrap()[0] - pts[0][0]) / (3.0 * 27.0);
    // the second posture's tip: its pixel offsets over its mm offsets in x and y agree
    let line2 = svg.lines().filter(|l| l.contains("class=\"posture\"")).nth(1).unwrap();
    let p2 = polyline_points(line2);
    let tip = r.postures[1].tip();
    let sy = -(p2.last().unwrap()[1] - p2[0][1]) / tip.y;
    let sx2 = (p2.last().unwrap()[0] - p2[0][0]) / tip.x;
    assert!((sx - sy).abs() < 1e-3 * sx && (sx - sx2).abs() < 1e-3 * sx, "{sx} {sy} {sx2}");
}

#[test]
fn shipped_scenes_show_the_papers_statements() {
    let run = |n: &str| {
        let mut s = scene::parse(n, &std::fs::read_to_string(top().join(format!("scenes/{n}.toml"))).unwrap()).unwrap();
        s.output.reference = Reference::None;
        scene::run(&s, None).unwrap()
    };
    let at = |r: &SceneResult, t: f64| r.postures.iter().find(|p| p.kind == Kind::Tension && p.tension == t).unwrap().clone();
    // DE layers stiffen the finger (Fig. 4 (a) against (b))
    let no_de = run("paper-no-de");
    let de0 = run("paper-de-0v");
    assert!(at(&de0, 1.0).tip().theta < at(&no_de, 1.0).tip().theta);
    // the least stiff (thinned) joint bends most (Fig. 4 (d)-(f))
    for j in 1..=3 {
        let r = run(&format!("paper-de-joint{j}-thin"));
        for p in r.postures.iter().filter(|p| p.tension > 0.0) {
            let a = p.joint_angles();
            for k in 0..3 {
                if k != j - 1 {
                    assert!(a[j - 1] > a[k], "joint {j} thinned: angles {a:?} at {} N", p.tension);
                }
            }
        }
    }
    // uniform thinning: equal joints at every load (one bending path), softer than at 0 V
    let u = run("paper-de-uniform");
    for p in &u.postures {
        let a = p.joint_angles();
        assert!((a[0] - a[1]).abs() < 1e-12 && (a[1] - a[2]).abs() < 1e-12, "{a:?}");
    }
    let (ku, k0) = (at(&u, 1.0).stiffness.unwrap(), at(&de0, 0.0).stiffness.unwrap());
    assert!(at(&u, 0.0).stiffness.unwrap()[2][2] < k0[2][2], "thinner stacks, lower rotational stiffness");
    assert!(ku[2][2].is_finite());
}

/// Counts the reference solves a scene asks for.
struct Counting(std::cell::Cell<usize>);

impl scene::ReferenceSolver for Counting {
    fn solve(&self, _: &Params<f64>, _: f64, _: &[f64], _: &[f64]) -> Result<scene::RefPosture, String> {
        self.0.set(self.0.get() + 1);
        Err("counted".into())
    }
}

#[test]
fn the_reference_is_solved_only_when_asked() {
    let c = Counting(std::cell::Cell::new(0));
    let s = scene::parse("c", "[drive]\ntensions = [0.2, 0.4]\n").unwrap();
    scene::run(&s, Some(&c)).unwrap();
    assert_eq!(c.0.get(), 0);
    let s = scene::parse("c", "[drive]\ntensions = [0.2, 0.4]\n[output]\nreference = \"continuum\"\n").unwrap();
    let e = scene::run(&s, Some(&c)).unwrap_err();
    assert_eq!(c.0.get(), 1);
    assert_eq!(e.line, 3);
    assert!(e.to_string().contains("counted"), "{e}");
}

#[test]
fn continuum_overlay_is_the_continuum_models_solution() {
    let path = top().join("scenes/paper-de-joint1-thin.toml");
    let r = scene::run_file(&path, scene::reference_solver().as_deref()).unwrap();
    assert_eq!(r.scene.output.reference, Reference::Continuum);
    let cp = scene::continuum_params(&r.scene.finger.params);
    assert_eq!(cp.e_de, r.scene.finger.params.e_de());
    let (head, rows) = csv(&scene::summary_csv(&r));
    let num = |row: &Vec<String>, name: &str| -> f64 { row[col(&head, name)].parse().unwrap() };
    for (p, row) in r.postures.iter().zip(&rows) {
        let direct = continuum::solve(&cp, p.tension, &p.thickness, [0.0, 0.0], continuum::Discretisation::default()).unwrap();
        let rf = p.reference.as_ref().unwrap();
        assert_eq!(rf.tip.x, direct.tip.x);
        assert_eq!(rf.tip.y, direct.tip.y);
        assert_eq!(num(row, "ref_tip_deg"), direct.tip.theta.to_degrees());
        let tip = p.tip();
        let err = ((tip.x - direct.tip.x).powi(2) + (tip.y - direct.tip.y).powi(2)).sqrt();
        assert_eq!(num(row, "err_tip_mm"), err);
        for k in 0..3 {
            assert_eq!(num(row, &format!("err_joint{}_deg", k + 1)), (p.joint_angles()[k] - direct.joint_angles[k]).to_degrees());
        }
        // the overlay starts at the clamp and ends at the reference's tip
        assert_eq!(rf.points[0], [0.0, 0.0]);
        let last = rf.points.last().unwrap();
        assert!((last[0] - direct.tip.x).abs() < 1e-9 && (last[1] - direct.tip.y).abs() < 1e-9);
    }
    // the postures CSV carries the reference's points too
    let pc = scene::postures_csv(&r);
    assert_eq!(pc.lines().filter(|l| l.contains(",reference,")).count(), r.postures.iter().map(|p| p.reference.as_ref().unwrap().points.len()).sum::<usize>());
}

#[test]
fn svg_draws_the_finger_body_cable_and_clamp() {
    // the body, one stack per joint coloured by voltage, the clamp, the cable and the pull
    let c = Finger::new(Params::<f64>::default()).unwrap().voltage_ceiling();
    let text = format!("[finger]\nvolts = [{}, {}, {}]\n[drive]\ntensions = [0, 0.5]\n", 0.1 * c, 0.5 * c, 0.9 * c);
    let r = run_text(&text).unwrap();
    let svg = finger_scene::svg::plot(&r);
    check_xml(&svg).unwrap();
    for class in ["class=\"body\"", "class=\"clamp\"", "class=\"cable\"", "class=\"load\"", "class=\"volt-scale\""] {
        assert!(svg.contains(class), "missing {class}");
    }
    let stacks: Vec<&str> = svg.lines().filter(|l| l.contains("class=\"stack\"")).collect();
    assert_eq!(stacks.len(), 3);
    // a different voltage, a different colour
    let fill = |l: &str| l.split("fill=\"").nth(1).unwrap().split('"').next().unwrap().to_string();
    assert_ne!(fill(stacks[0]), fill(stacks[2]));
    assert_eq!(svg.matches("class=\"hinge\"").count(), 3);
    // the pull is the largest tension's
    assert!(svg.contains("P = 0.5 N"));
    // a finger without stacks draws none and has no voltage scale
    let r = run_text("[finger]\nlayers = 0\n[drive]\ntensions = [0.5]\n").unwrap();
    let svg = finger_scene::svg::plot(&r);
    assert!(svg.contains("class=\"body\"") && svg.contains("class=\"cable\""));
    assert!(!svg.contains("class=\"stack\"") && !svg.contains("class=\"volt-scale\""));
}

#[test]
fn svg_has_a_stiffness_panel_exactly_when_asked() {
    let asked = run_text("[drive]\ntensions = [0, 0.5, 1]\n[output]\ntip_stiffness = true\n").unwrap();
    let svg = finger_scene::svg::plot(&asked);
    check_xml(&svg).unwrap();
    assert!(svg.contains("class=\"stiffness-panel\""));
    // three terms, a bar per posture each, with their units
    assert_eq!(svg.matches("class=\"stiffness-bar\"").count(), 3 * asked.postures.len());
    assert!(svg.contains("k_yy (N/mm)") && svg.contains("k_θθ (N·mm/rad)"));
    let not = run_text("[drive]\ntensions = [0, 0.5, 1]\n[output]\ntip_stiffness = false\n").unwrap();
    assert!(!finger_scene::svg::plot(&not).contains("stiffness-panel"));
}

#[test]
fn svg_tells_coinciding_curves_apart_in_plain_words() {
    let reference = scene::reference_solver();
    let r = scene::run_file(&top().join("scenes/paper-no-de.toml"), reference.as_deref()).unwrap();
    let svg = finger_scene::svg::plot(&r);
    // no TOML section names in the legend
    assert!(!svg.contains("[match]"), "legend shows TOML jargon");
    // every posture line has its own (dash, width) style and node marker shape
    let polys: Vec<&str> = svg.lines().filter(|l| l.contains("<polyline class=\"posture\"")).collect();
    let style = |l: &str| {
        let dash = l.split("stroke-dasharray=\"").nth(1).map(|d| d.split('"').next().unwrap().to_string());
        let width = l.split("stroke-width=\"").nth(1).unwrap().split('"').next().unwrap().to_string();
        (dash, width)
    };
    let matched = polys.iter().position(|l| l.contains(&format!("data-tension=\"{}\"", r.matched_tension.unwrap()))).unwrap();
    for (i, l) in polys.iter().enumerate() {
        if i != matched {
            assert_ne!(style(l), style(polys[matched]), "a posture drawn like the matched one");
        }
    }
}

#[test]
fn drawing_shows_the_finger_with_its_dimensions() {
    let svg = finger_scene::drawing::dimensioned(finger_model::Params::default(), 1.0, 1000.0).unwrap();
    check_xml(&svg).unwrap();
    for what in ["class=\"body\"", "class=\"clamp\"", "class=\"cable\"", "class=\"stack\"", "l = 27 mm", "b = 10 mm", "t_min = 1.5 mm", "e = 5 mm"] {
        assert!(svg.contains(what), "missing {what}");
    }
    // the straight finger and the bent one
    assert_eq!(svg.matches("<g class=\"finger").count(), 2);
    // the front page's drawing is the board's finger: its colour bar ends at the board film's
    // ceiling, not the default film's
    let front = std::fs::read_to_string(top().join("docs/finger.svg")).unwrap();
    let vhb = finger_model::Finger::new(finger_model::Params::<f64>::vhb4905()).unwrap().voltage_ceiling();
    let default = finger_model::Finger::new(finger_model::Params::<f64>::default()).unwrap().voltage_ceiling();
    assert!(vhb < default);
    assert!(front.contains(&format!(">{:.1} kV (ceiling)<", vhb / 1000.0)), "docs/finger.svg's colour bar");
}

#[test]
fn a_scene_without_out_writes_under_target_not_into_the_current_directory() {
    let cwd = std::env::temp_dir().join(format!("finger-scene-cwd-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&cwd);
    std::fs::create_dir_all(&cwd).unwrap();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_finger-scene")).current_dir(&cwd).arg(top().join("scenes/paper-de-0v.toml")).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(std::fs::read_dir(&cwd).unwrap().count(), 0, "wrote into the current directory");
    let svg = top().join("target/scenes/paper-de-0v.svg");
    assert!(svg.is_file());
    let st = std::process::Command::new("git").arg("-C").arg(top()).args(["check-ignore", "-q"]).arg(&svg).status().unwrap();
    assert!(st.success(), "{} is not git-ignored", svg.display());
    let _ = std::fs::remove_dir_all(&cwd);
}

#[test]
fn gravity_keys_take_the_orientation_and_are_refused_at_their_line() {
    let s = scene::parse("g", "[finger]\ngrav = 9.81\ngrav_dir = -90\nrho_b = 1.3\n[drive]\ntensions = [0.5]\n").unwrap();
    let p = s.finger.params;
    assert_eq!((p.grav, p.grav_dir, p.rho_b), (9.81, -90.0, 1.3));
    assert_eq!(p, Params { rho_b: 1.3, ..Params::<f64>::default().with_gravity(9.81, -90.0) });
    // the paper's preset with an orientation, and the default's: no gravity
    let s = scene::parse("g", "[finger]\npreset = \"paper\"\ngrav_dir = 90\ngrav = 9.81\n[drive]\ntensions = [0.5]\n").unwrap();
    assert_eq!((s.finger.params.grav, s.finger.params.grav_dir), (9.81, 90.0));
    assert_eq!(scene::parse("d", "[drive]\ntensions = 0.5\n").unwrap().finger.params.grav, 0.0);
    // the scene runs in it
    assert_eq!(scene::run(&s, None).unwrap().postures.len(), 1);
    for (text, line, name) in [
        ("[finger]\ngrav = 25\n[drive]\ntensions = 1\n", 2, "grav"),
        ("[finger]\nlayers = 4\ngrav_dir = 200\n[drive]\ntensions = 1\n", 3, "grav_dir"),
        ("[finger]\n  grav_dir = -181\n[drive]\ntensions = 1\n", 2, "grav_dir"),
        ("[finger]\nrho_b = -1\n[drive]\ntensions = 1\n", 2, "rho_b"),
        ("[finger]\ngrav = nan\n[drive]\ntensions = 1\n", 2, "grav"),
    ] {
        let e = scene::parse("e", text).unwrap_err();
        assert_eq!(e.line, line, "{text:?}: {e}");
        assert!(e.to_string().contains(name), "{text:?}: {e}");
    }
}
