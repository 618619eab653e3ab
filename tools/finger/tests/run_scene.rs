//! `finger run scene.toml` as a user runs it, against finger-sim (pipes; it has `shape`) and the
//! firmware's emulator image in QEMU (socket; no `shape`): the CSV holds the host's f64 model
//! exactly and the board's answers, which agree with it to the board's f32 and print precision;
//! the board gets the scene's finger; `--drive` arms, drives, reads back and stops; a scene
//! the model refuses never reaches a board.
use std::path::{Path, PathBuf};
use std::process::Command;

mod common;
use common::{finger, image, root, scratch, shell_board, sim, text};

use finger_model::{Finger, Method, Params};

fn csv(path: &Path) -> (Vec<String>, Vec<Vec<String>>) {
    let t = std::fs::read_to_string(path).unwrap();
    let mut l = t.lines();
    let head = l.next().unwrap().split(',').map(String::from).collect();
    (head, l.map(|r| r.split(',').map(String::from).collect()).collect())
}

fn get(head: &[String], row: &[String], name: &str) -> f64 {
    let i = head.iter().position(|h| h == name).unwrap_or_else(|| panic!("no column {name}"));
    row[i].parse().unwrap_or_else(|_| panic!("{name} = {:?}", row[i]))
}

/// A run's CSV: the host columns are the f64 model's own numbers, the board's agree with them
/// to the console's print precision (3 decimals) plus f32.
fn check_against_host(csv_path: &Path, params: Params<f64>, volts: &[f64], tensions: &[f64]) {
    let (head, rows) = csv(csv_path);
    assert_eq!(rows.len(), tensions.len());
    let f = Finger::new(params).unwrap();
    for (row, &t) in rows.iter().zip(tensions) {
        let s = f.solve(t, volts, Method::Converged { tol: 1e-9, max_iter: 200 }).unwrap();
        assert_eq!(get(&head, row, "tension_N"), t);
        for k in 0..3 {
            let host = get(&head, row, &format!("host_joint{}_deg", k + 1));
            assert_eq!(host, s.joint_angles()[k].to_degrees());
            let board = get(&head, row, &format!("board_joint{}_deg", k + 1));
            assert!((board - host).abs() < 2e-3, "joint {}: board {board} host {host} at {t} N", k + 1);
            assert_eq!(get(&head, row, &format!("diff_joint{}_deg", k + 1)), board - host);
            let th = get(&head, row, &format!("board_thickness{}_mm", k + 1));
            assert!((th - s.thickness[k]).abs() < 2e-4, "stack {}: board {th} host {}", k + 1, s.thickness[k]);
        }
        assert!(get(&head, row, "diff_tip_mm") < 5e-3, "{row:?}");
    }
}

#[test]
fn a_scene_on_the_sim_is_the_host_model_to_print_precision() {
    let dir = scratch("run-sim");
    // the shipped paper-de-joint1-thin scene with joint 1 at 1.96 mm instead of 1.8: the paper
    // preset needs about 9.9 kV for 1.8 mm, past the board film's hold ceiling, which no
    // preset raises; 1.96 mm needs about 4.8 kV
    let shipped = std::fs::read_to_string(root().join("scenes/paper-de-joint1-thin.toml")).unwrap();
    assert!(shipped.contains("thickness = [1.8, 2.0, 2.0]"));
    let scene = dir.join("paper-de-joint1-thin.toml");
    assert!(shipped.contains("board = false"));
    let reachable = shipped.replace("thickness = [1.8, 2.0, 2.0]", "thickness = [1.96, 2.0, 2.0]").replace("board = false", "board = true");
    std::fs::write(&scene, reachable).unwrap();
    let out = finger(&["--sim", "--sim-bin", sim().to_str().unwrap(), "run", scene.to_str().unwrap(), "--out", dir.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    // the paper preset with 4 layers and joint 1 at 1.96 mm: the board computed that finger
    let s = finger_scene::read_file(&scene).unwrap();
    let volts = finger_scene::scene::volts_of(&s.finger).unwrap();
    check_against_host(&dir.join("paper-de-joint1-thin-board.csv"), s.finger.params, &volts, &s.tensions);
    let (head, rows) = csv(&dir.join("paper-de-joint1-thin-board.csv"));
    assert!((get(&head, &rows[0], "board_thickness1_mm") - 1.96).abs() < 1e-3);
    assert!(!head.iter().any(|h| h.starts_with("driven_")), "model only: nothing driven");
    // the plot: the host's postures and the board's `shape` centrelines (n + 1 nodes, n hinges)
    let svg = std::fs::read_to_string(dir.join("paper-de-joint1-thin-board.svg")).unwrap();
    let boards: Vec<&str> = svg.lines().filter(|l| l.contains("<polyline class=\"reference\"")).collect();
    assert_eq!(boards.len(), s.tensions.len());
    for l in boards {
        let pts = l.split("points=\"").nth(1).unwrap().split('"').next().unwrap();
        assert_eq!(pts.split(' ').count(), 7, "{l}");
    }
    assert_eq!(svg.matches("<polyline class=\"posture\"").count(), s.tensions.len());
    assert!(svg.contains(">board (shape)<"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A scene small enough to drive quickly (600 V at 2000 V/s).
const DRIVE_SCENE: &str = "title = \"drive\"\n[finger]\nvolts = [600, 300, 0]\n[drive]\ntensions = [0.3, 0.8]\n";

/// A scratch directory holding [`DRIVE_SCENE`] as drive.toml: (the directory, the scene).
fn drive_scene(what: &str) -> (PathBuf, PathBuf) {
    let dir = scratch(what);
    let scene = dir.join("drive.toml");
    std::fs::write(&scene, DRIVE_SCENE).unwrap();
    (dir, scene)
}

/// finger-sim behind a shell script `dir/name` that logs its input to `dir/in.log` and passes
/// it through `between` (a shell pipeline stage, or ""): (the script, the log).
fn logged_sim(dir: &Path, name: &str, between: &str) -> (PathBuf, PathBuf) {
    let (board, log) = (dir.join(name), dir.join("in.log"));
    shell_board(&board, &format!("tee {} | {between}{}", log.display(), sim().display()));
    (board, log)
}

fn check_driven(dir: &Path) {
    let (head, rows) = csv(&dir.join("drive-board.csv"));
    assert_eq!(rows.len(), 2);
    for (row, t) in rows.iter().zip([0.3, 0.8]) {
        assert_eq!(get(&head, row, "driven_force_N"), t);
        for (k, v) in [600.0, 300.0, 0.0].iter().enumerate() {
            assert!((get(&head, row, &format!("driven_volts{}_V", k + 1)) - v).abs() <= 0.5, "{row:?}");
            // driven there, the board's state is its own `solve` of the posture
            let d = get(&head, row, &format!("driven_joint{}_deg", k + 1));
            let b = get(&head, row, &format!("board_joint{}_deg", k + 1));
            assert!((d - b).abs() < 2e-3, "joint {}: driven {d} solve {b}", k + 1);
        }
    }
}

/// finger-sim runs against the plant: each driven posture carries the read-back, the measured
/// voltage near the command (the hold ripple is up to 100 V below it), a current inside the
/// watchdog's bound, the sensed thickness of a stack near its rest (NaN until measured).
fn check_readback(dir: &Path) {
    let (head, rows) = csv(&dir.join("drive-board.csv"));
    for row in &rows {
        for (k, v) in [600.0, 300.0, 0.0].iter().enumerate() {
            let vm = get(&head, row, &format!("driven_vmeas{}_V", k + 1));
            assert!(vm > v - 160.0 && vm < v + 40.0, "channel {}: vmeas {vm} V for {v} V", k + 1);
            let im = get(&head, row, &format!("driven_imeas{}_uA", k + 1));
            assert!(im.abs() < 30.0, "channel {}: imeas {im} µA", k + 1);
            let t = get(&head, row, &format!("driven_thick_meas{}_mm", k + 1));
            assert!(t.is_nan() || (t > 0.5 && t < 3.0), "channel {}: thick_meas {t} mm", k + 1);
        }
    }
}

#[test]
fn the_status_readback_is_parsed_with_unmeasured_thickness_as_nan() {
    let r = finger::Reply {
        before: vec![],
        line: "ok volts=1,2,3 thick=2.0000,2.0000,2.0000 vmeas=598.2,301.0,0.0 imeas=0.120,-0.050,0.000 thick_meas=1.9950,-,- vceil=5400.0,5400.0,5400.0"
            .into(),
    };
    let rb = finger::run::Readback::of(&r).expect("a read-back");
    assert_eq!(rb.vmeas_v, vec![598.2, 301.0, 0.0]);
    assert_eq!(rb.imeas_ua, vec![0.12, -0.05, 0.0]);
    assert_eq!(rb.thick_meas_mm[0], 1.995);
    assert!(rb.thick_meas_mm[1].is_nan() && rb.thick_meas_mm[2].is_nan());
    let plain = finger::Reply { before: vec![], line: "ok volts=1,2,3 thick=2.0000,2.0000,2.0000".into() };
    assert_eq!(finger::run::Readback::of(&plain), None);
}

#[test]
fn drive_arms_drives_reads_back_and_stops_on_the_sim() {
    let (dir, scene) = drive_scene("run-drive");
    // the board's input, as it arrives
    let (board, log) = logged_sim(&dir, "board.sh", "");
    let out = finger(&["--sim", "--sim-bin", board.to_str().unwrap(), "run", "--drive", scene.to_str().unwrap(), "--out", dir.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let p = Params::<f64>::default();
    check_against_host(&dir.join("drive-board.csv"), p, &[600.0, 300.0, 0.0], &[0.3, 0.8]);
    check_driven(&dir);
    check_readback(&dir);
    let sent = std::fs::read_to_string(&log).unwrap();
    let lines: Vec<&str> = sent.lines().map(str::trim).collect();
    let arm = lines.iter().position(|l| *l == "arm").expect("armed");
    assert!(lines[..arm].iter().any(|l| l.starts_with("preset default")), "{sent}");
    // the scene's finger is the uncalibrated model: the board's FE calibration is cleared
    assert!(lines[..arm].contains(&"cal none"), "{sent}");
    assert!(lines[arm..].contains(&"force 0.8") && lines[arm..].contains(&"volt 1 600"), "{sent}");
    assert_eq!(lines.last(), Some(&"stop"), "{sent}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_qemu_image_runs_and_drives_the_same_scene() {
    let (dir, scene) = drive_scene("run-qemu");
    let log = dir.join("defmt.bin");
    let out = finger(&[
        "--qemu",
        "--elf",
        image().to_str().unwrap(),
        "--defmt-log",
        log.to_str().unwrap(),
        "run",
        "--drive",
        scene.to_str().unwrap(),
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    check_against_host(&dir.join("drive-board.csv"), Params::<f64>::default(), &[600.0, 300.0, 0.0], &[0.3, 0.8]);
    check_driven(&dir);
    // the image has no `shape`: the board's tips are drawn as rings
    let svg = std::fs::read_to_string(dir.join("drive-board.svg")).unwrap();
    assert_eq!(svg.matches("<circle class=\"reference-tip\"").count(), 2);
    assert!(svg.contains(">board tip (solve)<"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_refused_scene_never_reaches_a_board() {
    let dir = scratch("run-refused");
    let out_dir = dir.join("out");
    // the model refuses it; the named board does not even exist
    let scene = root().join("scenes/refused/paper-2mm-to-1mm.toml");
    let out = finger(&["--sim", "--sim-bin", "/nonexistent/board", "run", scene.to_str().unwrap(), "--out", out_dir.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    let err = text(&out.stderr);
    assert!(err.contains("line 9, column 1: thickness: joint 1") && err.contains("1.333 mm"), "{err}");
    // so is the old format, with the pointer to the new one
    let old = dir.join("old.scene");
    std::fs::write(&old, "[drive]\ntensions = 1\n").unwrap();
    let out = finger(&["--sim", "--sim-bin", "/nonexistent/board", "run", old.to_str().unwrap(), "--out", out_dir.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("docs/scenes.md"));
    assert!(!out_dir.exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn ctrl_c_during_a_driven_run_still_stops_the_board() {
    let (dir, scene) = drive_scene("run-interrupt");
    // a slow board: each line reaches finger-sim 0.2 s late; what finger sends is logged first
    let (board, log) = logged_sim(&dir, "slow-board.sh", "while IFS= read -r l; do sleep 0.2; printf '%s\\n' \"$l\"; done | ");
    let out_dir = dir.join("out");
    let child = Command::new(env!("CARGO_BIN_EXE_finger"))
        .args(["--sim", "--sim-bin", board.to_str().unwrap(), "run", "--drive", scene.to_str().unwrap(), "--out", out_dir.to_str().unwrap()])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // once the board is armed, Ctrl-C
    let t0 = std::time::Instant::now();
    while !std::fs::read_to_string(&log).unwrap_or_default().lines().any(|l| l.trim() == "arm") {
        assert!(t0.elapsed() < std::time::Duration::from_secs(30), "never armed");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let kill = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(kill.success());
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(130), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("interrupted"));
    let sent = std::fs::read_to_string(&log).unwrap();
    let lines: Vec<&str> = sent.lines().map(str::trim).collect();
    assert_eq!(lines.last(), Some(&"stop"), "{sent}");
    assert!(!lines.contains(&"force 0.8"), "the run went on after Ctrl-C: {sent}");
    assert!(!out_dir.exists(), "an interrupted run wrote its files");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_run_without_out_writes_under_target_not_into_the_current_directory() {
    let cwd = scratch("run-cwd");
    let scene = root().join("scenes/paper-de-0v.toml");
    let out = Command::new(env!("CARGO_BIN_EXE_finger"))
        .current_dir(&cwd)
        .args(["--sim", "--sim-bin", sim().to_str().unwrap(), "run", scene.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(std::fs::read_dir(&cwd).unwrap().count(), 0, "the run wrote into the current directory");
    let csv = root().join("target/runs/paper-de-0v-board.csv");
    assert!(csv.is_file(), "no {}", csv.display());
    // git ignores where it went
    let st = Command::new("git").arg("-C").arg(root()).args(["check-ignore", "-q"]).arg(&csv).status().unwrap();
    assert!(st.success(), "{} is not git-ignored", csv.display());
    let _ = std::fs::remove_dir_all(&cwd);
}

/// The ceiling the simulated board holds with the paper preset, V (`limits`' first vmax).
fn sim_paper_ceiling() -> f64 {
    use std::io::Write;
    let mut c = Command::new(sim()).stdin(std::process::Stdio::piped()).stdout(std::process::Stdio::piped()).spawn().unwrap();
    c.stdin.take().unwrap().write_all(b"preset paper\nlimits\n").unwrap();
    let out = text(&c.wait_with_output().unwrap().stdout);
    let l = out.lines().find(|l| l.starts_with("ok vmax=")).unwrap_or_else(|| panic!("{out}"));
    l["ok vmax=".len()..].split(',').next().unwrap().parse().unwrap()
}

#[test]
fn every_shipped_scene_runs_on_the_board_or_says_it_is_the_papers_model() {
    let dir = scratch("run-shipped");
    let ceiling = sim_paper_ceiling();
    let mut scenes: Vec<_> =
        std::fs::read_dir(root().join("scenes")).unwrap().map(|e| e.unwrap().path()).filter(|p| p.extension().is_some_and(|x| x == "toml")).collect();
    scenes.sort();
    assert!(scenes.len() >= 7, "{scenes:?}");
    let (mut ran, mut labelled) = (0, 0);
    for path in &scenes {
        let s = finger_scene::read_file(path).unwrap();
        let top = finger_scene::scene::volts_of(&s.finger).unwrap().into_iter().fold(0.0f64, f64::max);
        let out = finger(&["--sim", "--sim-bin", sim().to_str().unwrap(), "run", path.to_str().unwrap(), "--out", dir.to_str().unwrap()]);
        let err = text(&out.stderr);
        if s.board {
            assert!(out.status.success(), "{}: {err}", path.display());
            assert!(dir.join(format!("{}-board.csv", s.name)).exists(), "{}", path.display());
            assert!(top < ceiling, "{}: {top} V", path.display());
            ran += 1;
        } else {
            // the label is true: the board's film cannot hold the scene's voltages
            assert!(top >= ceiling, "{}: labelled `board = false` but {top} V is under the board's {ceiling} V", path.display());
            assert_eq!(out.status.code(), Some(1), "{}: {err}", path.display());
            assert!(err.contains("`board = false`") && err.contains("paper's model") && err.contains("finger-scene"), "{err}");
            labelled += 1;
        }
    }
    assert!(ran >= 3 && labelled >= 1, "{ran} ran, {labelled} labelled");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_orientation_flags_give_the_host_and_the_board_the_scenes_finger_in_that_orientation() {
    let s = finger_scene::parse("o", DRIVE_SCENE).unwrap();
    assert_eq!(s.finger.params.grav, 0.0, "a scene's default finger has no gravity");
    let o = finger::run::oriented(s.clone(), Some(9.81), Some(-90.0)).unwrap();
    assert_eq!((o.finger.params.grav, o.finger.params.grav_dir), (9.81, -90.0));
    assert_eq!(finger::run::oriented(s.clone(), None, None).unwrap().finger.params, s.finger.params);
    for (grav, dir, flag) in [(None, Some(200.0), "--grav-dir"), (Some(-1.0), None, "--grav"), (None, Some(f64::NAN), "--grav-dir")] {
        let e = finger::run::oriented(s.clone(), grav, dir).unwrap_err().to_string();
        assert!(e.starts_with(flag) && e.contains(&flag[2..].replace('-', "_")), "{e}");
    }
    // out of range: refused before any board is touched (the named one does not exist)
    let (dir, scene) = drive_scene("run-oriented");
    let out_dir = dir.join("refused");
    let out = finger(&["--sim", "--sim-bin", "/nonexistent/board", "run", scene.to_str().unwrap(), "--grav-dir", "-200", "--out", out_dir.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1), "{}", text(&out.stderr));
    assert!(text(&out.stderr).contains("grav_dir"), "{}", text(&out.stderr));
    assert!(!out_dir.exists());
    // on the sim: the host's columns are the f64 model of the oriented finger, the board got it
    let (board, log) = logged_sim(&dir, "board.sh", "");
    let out = finger(&[
        "--sim",
        "--sim-bin",
        board.to_str().unwrap(),
        "run",
        scene.to_str().unwrap(),
        "--grav",
        "9.81",
        "--grav-dir",
        "-90",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    check_against_host(&dir.join("drive-board.csv"), o.finger.params, &[600.0, 300.0, 0.0], &o.tensions);
    let sent = std::fs::read_to_string(&log).unwrap();
    assert!(sent.lines().any(|l| l == "param grav_dir -90"), "{sent}");
    // without the flags the scene's finger (no gravity; the board's has it) is what it gets
    let out = finger(&["--sim", "--sim-bin", board.to_str().unwrap(), "run", scene.to_str().unwrap(), "--out", dir.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let sent = std::fs::read_to_string(&log).unwrap();
    assert!(sent.lines().any(|l| l == "param grav 0"), "{sent}");
    let _ = std::fs::remove_dir_all(&dir);
}
