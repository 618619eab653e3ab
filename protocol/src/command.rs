//! Commands: the first word of a line (docs/console.md "Commands"). [`Command::parse`] reads
//! it (as the board's line buffer holds it: lowercase), [`Command::as_str`] writes it. A
//! command is added here: a variant, its text in `TEXT` (the build checks `TEXT` against
//! `NAMES`) and its row in `ALL`.
//!
//! What it is not: a command's arguments and what they mean (the firmware's src/app/*), nor
//! which build has a command (a build without one answers `err unknown`).

/// A console command.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Command {
    Help,
    Version,
    Status,
    Limits,
    Material,
    Solve,
    Shape,
    Arm,
    Disarm,
    Stop,
    Timing,
    Volt,
    Force,
    Pose,
    Contact,
    Plant,
    Param,
    Preset,
    Cal,
    Save,
    Factory,
    Config,
    Wait,
    Reset,
}

/// Each command's word, in the order of the enum.
const NAMES: [&str; 24] = [
    "help", "version", "status", "limits", "material", "solve", "shape", "arm", "disarm", "stop", "timing", "volt", "force", "pose", "contact", "plant",
    "param", "preset", "cal", "save", "factory", "config", "wait", "reset",
];

/// `NAMES` end to end and where each ends: what the image holds (one string and a byte per
/// command: the Cortex-M3 image's flash). The build checks it is `NAMES`.
const TEXT: &str = "helpversionstatuslimitsmaterialsolveshapearmdisarmstoptimingvoltforceposecontactplantparampresetcalsavefactoryconfigwaitreset";
const ENDS: [u8; NAMES.len() + 1] = crate::code::ends(TEXT, &NAMES);

impl Command {
    /// Every command, in the order of the enum.
    pub const ALL: [Command; NAMES.len()] = [
        Command::Help,
        Command::Version,
        Command::Status,
        Command::Limits,
        Command::Material,
        Command::Solve,
        Command::Shape,
        Command::Arm,
        Command::Disarm,
        Command::Stop,
        Command::Timing,
        Command::Volt,
        Command::Force,
        Command::Pose,
        Command::Contact,
        Command::Plant,
        Command::Param,
        Command::Preset,
        Command::Cal,
        Command::Save,
        Command::Factory,
        Command::Config,
        Command::Wait,
        Command::Reset,
    ];

    /// The command a line's first word names (exact: lowercase, as the board's line buffer
    /// holds it; a client lowercases first); `None` for any other word.
    pub fn parse(word: &[u8]) -> Option<Command> {
        let t = TEXT.as_bytes();
        (0..NAMES.len()).find(|&i| t.get(ENDS[i] as usize..ENDS[i + 1] as usize) == Some(word)).map(|i| Self::ALL[i])
    }

    /// The command's word.
    pub fn as_str(self) -> &'static str {
        let i = self as usize;
        TEXT.get(ENDS[i] as usize..ENDS[i + 1] as usize).unwrap_or("")
    }
}
