//! `finger`: the host client. One console contract, three ways to reach a board:
//! `--port /dev/ttyACM0` (the real board), `--sim` (finger-sim), `--qemu` (the emulator image),
//! or `--socket PATH` (a QEMU started by hand). Exit status: 0 ok, 1 the board refused
//! (`err <code>: ...` on stderr), 2 the link failed or timed out.
use std::io::{IsTerminal, Read, Write};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Duration;

use clap::{Args, Parser, Subcommand};
use finger::{CommandError, Console, Link, LinkError};

#[derive(Parser)]
#[command(name = "finger", version, about = "Host client for the finger driver board (the console of docs/console.md)")]
struct Cli {
    #[command(flatten)]
    to: Target,
    /// Seconds to wait for each reply before the board is reported as not answering.
    #[arg(long, global = true, default_value_t = 10.0)]
    timeout: f64,
    /// With --qemu: where QEMU writes the defmt log (`finger log --file` decodes it).
    #[arg(long, global = true, default_value = "target/defmt-client.bin")]
    defmt_log: PathBuf,
    /// With --sim: the finger-sim program (default: the finger-sim next to this program, else
    /// on PATH).
    #[arg(long, global = true)]
    sim_bin: Option<PathBuf>,
    /// The firmware image, for --qemu and `log` (default: the release image `cargo build
    /// --release` writes at the top of the repository).
    #[arg(long, global = true)]
    elf: Option<PathBuf>,
    #[command(subcommand)]
    what: What,
}

#[derive(Args)]
#[group(multiple = false)]
struct Target {
    /// The real board's serial port (115200 8N1 unless --baud).
    #[arg(long, global = true)]
    port: Option<String>,
    #[arg(long, global = true, default_value_t = 115_200)]
    baud: u32,
    /// finger-sim, the application on a simulated board (the program: --sim-bin).
    #[arg(long, global = true)]
    sim: bool,
    /// The emulator firmware image booted in QEMU netduinoplus2 (the image: --elf).
    #[arg(long, global = true)]
    qemu: bool,
    /// A console on a Unix socket (a QEMU started with -chardev socket,...,server=on).
    #[arg(long, global = true)]
    socket: Option<PathBuf>,
}

#[derive(Subcommand)]
enum What {
    /// Send each argument as one command line; print each reply.
    Cmd {
        #[arg(required = true)]
        lines: Vec<String>,
    },
    /// Send each line of a script file (blank lines and `#` comments skipped); stop at the
    /// first refusal unless --keep-going. `-` reads the script from stdin.
    Script {
        file: PathBuf,
        #[arg(long)]
        keep_going: bool,
    },
    /// Run a scene file (docs/scenes.md) on the board: every posture through `solve` (model
    /// only), and with --drive also armed through `volt` and `force` (`stop` at the end);
    /// writes NAME-board.csv and NAME-board.svg: the board's answers next to the host's f64 model.
    Run {
        scene: PathBuf,
        /// Also drive the outputs: arm, `volt` and `force` to each posture, `status`, then `stop`.
        #[arg(long)]
        drive: bool,
        /// Where to write the CSV and SVG (default: target/runs/ at the repo top, which git
        /// ignores).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Gravity's magnitude for the scene's finger, m/s² (0..20, 0: off; default: the
        /// scene's `grav`).
        #[arg(long)]
        grav: Option<f64>,
        /// The finger's orientation, degrees from its straight axis toward the cable side (0
        /// hanging straight down, 90 held horizontally curling downward, -90 curling upward;
        /// default: the scene's `grav_dir`).
        #[arg(long, allow_negative_numbers = true)]
        grav_dir: Option<f64>,
    },
    /// Keep the settings in force across resets (`save`; the board refuses while armed, and
    /// settings that would raise a ceiling).
    Save,
    /// What the board has stored (`config`): the stored values that differ from the compiled
    /// defaults, the save counter, what the boot loaded or why it refused the store.
    Config,
    /// `status` at a fixed rate as a live view.
    Monitor {
        /// Polls per second.
        #[arg(long, default_value_t = 5.0)]
        rate: f64,
        /// Stop after this many polls (default: until Ctrl-C).
        #[arg(long)]
        count: Option<u64>,
    },
    /// The firmware's defmt log, decoded: a QEMU semihosting log file (followed as it grows),
    /// or with --probe the board's RTT through probe-rs.
    /// The image whose defmt table decodes the log is --elf.
    Log {
        /// The log file (default: target/defmt-qemu.bin, which scripts/run writes).
        #[arg(long)]
        file: Option<PathBuf>,
        /// Decode what is there and stop, instead of following the file.
        #[arg(long)]
        no_follow: bool,
        /// Read a real board's RTT through probe-rs (`probe-rs attach`).
        #[arg(long)]
        probe: bool,
    },
    /// The serial ports this machine has.
    Ports,
}

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn default_elf() -> PathBuf {
    repo_root().join("target/thumbv7em-none-eabihf/release/finger-fw")
}

fn find_sim() -> PathBuf {
    let next = std::env::current_exe().ok().and_then(|p| Some(p.parent()?.join("finger-sim")));
    match next {
        Some(p) if p.exists() => p,
        _ => PathBuf::from("finger-sim"),
    }
}

fn connect(cli: &Cli, timeout: Duration) -> Result<Link, LinkError> {
    let t = &cli.to;
    if let Some(p) = &t.port {
        return Link::serial(p, t.baud);
    }
    if let Some(s) = &t.socket {
        return Link::socket(s);
    }
    if t.qemu {
        let elf = cli.elf.clone().unwrap_or_else(default_elf);
        let log = if cli.defmt_log.is_absolute() { cli.defmt_log.clone() } else { repo_root().join(&cli.defmt_log) };
        return Link::qemu(&elf, &log, timeout.max(Duration::from_secs(20)));
    }
    if t.sim {
        return Link::sim(&cli.sim_bin.clone().unwrap_or_else(find_sim)).map_err(|e| match e {
            LinkError::Open(m) if cli.sim_bin.is_none() => {
                LinkError::Open(format!("{m} (build it: cd tools/finger-sim && cargo build; or name it with --sim-bin)"))
            }
            e => e,
        });
    }
    Err(LinkError::Open("name a board: --port DEV, --sim, --qemu or --socket PATH".into()))
}

/// Print a reply (its lines, then the final line) or the board's refusal; true when ok.
fn show(line: &str, r: &Result<finger::Reply, CommandError>) -> bool {
    match r {
        Ok(rep) => {
            for l in &rep.before {
                println!("{l}");
            }
            println!("{}", rep.line);
            true
        }
        Err(e) => {
            eprintln!("{line}: {e}");
            false
        }
    }
}

fn exit_of(e: &CommandError) -> ExitCode {
    match e {
        CommandError::Board { .. } => ExitCode::from(1),
        CommandError::Link(_) => ExitCode::from(2),
    }
}

/// `finger run`: the scene on the board, its CSV and SVG written only when the run succeeded.
fn run_scene(con: &mut Console, path: &Path, host: finger_scene::SceneResult, drive: bool, out: &Path) -> ExitCode {
    let name = host.scene.name.clone();
    // Ctrl-C: the run stops at its next command and a driven board still gets `stop`; a
    // second Ctrl-C quits at once
    let _ = ctrlc::set_handler(|| {
        if finger::run::interrupt() {
            std::process::exit(130);
        }
    });
    let bar = indicatif::ProgressBar::new(0);
    if !std::io::stderr().is_terminal() {
        bar.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    let r = finger::run::run(con, host, drive, |i, n| {
        bar.set_length(n as u64);
        bar.set_position(i as u64);
    });
    bar.finish_and_clear();
    let r = match r {
        Ok(r) => r,
        Err(e) => {
            eprintln!("finger run: {}: {e}", path.display());
            return match e {
                finger::run::RunError::Command { error: CommandError::Link(_), .. } => ExitCode::from(2),
                finger::run::RunError::Interrupted => ExitCode::from(130),
                _ => ExitCode::from(1),
            };
        }
    };
    if let Err(e) = std::fs::create_dir_all(out) {
        eprintln!("finger run: {}: {e}", out.display());
        return ExitCode::from(2);
    }
    for (name, text) in [(format!("{name}-board.csv"), finger::run::csv(&r)), (format!("{name}-board.svg"), finger::run::svg(&r))] {
        let p = out.join(name);
        if let Err(e) = std::fs::write(&p, text) {
            eprintln!("finger run: {}: {e}", p.display());
            return ExitCode::from(2);
        }
        println!("wrote {}", p.display());
    }
    let worst = r
        .host
        .postures
        .iter()
        .filter(|p| p.kind != finger_scene::Kind::MatchTarget)
        .zip(&r.board)
        .flat_map(|(h, b)| h.joint_angles().iter().zip(&b.joints_deg).map(|(a, d)| (d - a.to_degrees()).abs()))
        .fold(0.0, f64::max);
    println!("{} postures; board minus host model: joints within {worst:.4} deg", r.board.len());
    ExitCode::SUCCESS
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let timeout = Duration::from_secs_f64(cli.timeout.clamp(0.1, 3600.0));
    if let What::Ports = cli.what {
        return match serialport::available_ports() {
            Ok(ports) => {
                for p in ports {
                    println!("{}", p.port_name);
                }
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("finger: {e}");
                ExitCode::from(2)
            }
        };
    }
    if let What::Log { file, no_follow, probe } = &cli.what {
        let elf = cli.elf.clone().unwrap_or_else(default_elf);
        if *probe {
            let st = std::process::Command::new("probe-rs").args(["attach", "--chip", "STM32F405RGTx"]).arg(&elf).status();
            return match st {
                Ok(s) if s.success() => ExitCode::SUCCESS,
                Ok(_) => ExitCode::from(2),
                Err(e) => {
                    eprintln!("finger log --probe: probe-rs: {e} (install it: cargo install probe-rs-tools)");
                    ExitCode::from(2)
                }
            };
        }
        let file = file.clone().unwrap_or_else(|| repo_root().join("target/defmt-qemu.bin"));
        return match finger::log::follow(&elf, &file, !no_follow, &mut std::io::stdout().lock()) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("finger log: {e}");
                ExitCode::from(2)
            }
        };
    }
    // a scene is read and run on the host model (and refused) before any board is touched
    let scene = match &cli.what {
        What::Run { scene, grav, grav_dir, .. } => match finger_scene::read_file(scene)
            .map_err(finger::run::RunError::Scene)
            .and_then(|s| finger::run::oriented(s, *grav, *grav_dir))
            .and_then(|s| finger::run::host(&s))
        {
            Ok(s) if !s.scene.board => {
                eprintln!(
                    "finger run: {}: `board = false`: this scene is the paper's model, past what the board's film holds (docs/scenes.md \"The shipped scenes\"); run it on the host: cd tools/finger-scene && cargo run -- {}",
                    scene.display(),
                    scene.display()
                );
                return ExitCode::from(1);
            }
            Ok(s) => Some(s),
            Err(e) => {
                eprintln!("finger run: {}: {e}", scene.display());
                return ExitCode::from(1);
            }
        },
        _ => None,
    };
    let link = match connect(&cli, timeout) {
        Ok(l) => l,
        Err(e) => {
            eprintln!("finger: {e}");
            return ExitCode::from(2);
        }
    };
    let mut con = Console::new(link, timeout);
    let what = match cli.what {
        What::Save => What::Cmd { lines: vec!["save".into()] },
        What::Config => What::Cmd { lines: vec!["config".into()] },
        w => w,
    };
    match what {
        What::Cmd { lines } => {
            for line in &lines {
                let r = con.command(line);
                if !show(line, &r) {
                    return exit_of(r.as_ref().unwrap_err());
                }
            }
            ExitCode::SUCCESS
        }
        What::Script { file, keep_going } => {
            let text = if file.as_os_str() == "-" {
                let mut t = String::new();
                std::io::stdin().read_to_string(&mut t).map(|_| t)
            } else {
                std::fs::read_to_string(&file)
            };
            let text = match text {
                Ok(t) => t,
                Err(e) => {
                    eprintln!("finger: {}: {e}", file.display());
                    return ExitCode::from(2);
                }
            };
            let lines: Vec<&str> = text.lines().map(str::trim).filter(|l| !l.is_empty() && !l.starts_with('#')).collect();
            let bar = indicatif::ProgressBar::new(lines.len() as u64);
            if !std::io::stderr().is_terminal() || lines.len() < 20 {
                bar.set_draw_target(indicatif::ProgressDrawTarget::hidden());
            }
            let mut status = ExitCode::SUCCESS;
            for line in lines {
                println!("> {line}");
                let r = con.command(line);
                bar.inc(1);
                if !show(line, &r) {
                    let e = r.unwrap_err();
                    if matches!(e, CommandError::Link(_)) || !keep_going {
                        bar.abandon();
                        return exit_of(&e);
                    }
                    status = ExitCode::from(1);
                }
            }
            bar.finish_and_clear();
            status
        }
        What::Monitor { rate, count } => {
            if !(rate > 0.0 && rate <= 100.0) {
                eprintln!("finger monitor: --rate must be in (0, 100] Hz");
                return ExitCode::from(2);
            }
            let live = std::io::stdout().is_terminal();
            let demo = cli.to.sim;
            if demo {
                eprintln!("{}", finger::monitor::DEMO);
            }
            let mut out = std::io::stdout().lock();
            match finger::monitor::run(&mut con, rate, count, live, demo, &mut out) {
                Ok(()) => {
                    let _ = out.flush();
                    ExitCode::SUCCESS
                }
                Err(e) => {
                    eprintln!("finger monitor: {e}");
                    exit_of(&e)
                }
            }
        }
        What::Run { scene: path, drive, out, .. } => {
            let out = out.unwrap_or_else(|| repo_root().join("target").join("runs"));
            run_scene(&mut con, &path, scene.expect("read above"), drive, &out)
        }
        What::Log { .. } | What::Ports | What::Save | What::Config => unreachable!("handled above"),
    }
}
