//! The control core's faults: why it stopped the outputs, or why it never arms. Each one's
//! console text (`status`'s `fault=`, `arm`'s refusal) is [`Fault::text`].
//!
//! What it is not: the command side's own notes in `status` (a refused stored record, a model
//! that did not solve), which stop nothing.

/// A fault the control core latches (a stop clears it, a lock-out never does).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
#[cfg_attr(all(feature = "log", target_os = "none"), derive(defmt::Format))]
pub enum Fault {
    /// A duty or a target past its ceiling was refused.
    HvRefused,
    /// A PWM refused a duty.
    Pwm,
    /// The HV enable pin could not be set.
    Enable,
    /// The stacks' model refused a step.
    HvModel,
    /// The board constants give no valid stack law: never arms.
    BoardCard,
    /// The emulator image on a real chip (it has no watchdog): never arms.
    EmulatorOnChip,
    /// The read-back (docs/firmware.md "Faults of the read-back"; the Cortex-M3 image has
    /// the hard checks alone, `super::trip`): a stack's return current past the trip, or its
    /// voltage collapsing under a steady command.
    Breakdown,
    /// A measured voltage off its command longer than the loop's settling, or past the
    /// ceiling in force.
    HvMismatch,
    /// A stack's sensed capacitance far below the stack's: disconnected.
    StackOpen,
    /// A reading at its rail, out of its range, or stuck.
    Sensor,
    /// The leakage at a held voltage past its bound.
    Leakage,
}

/// Every fault's console text, in the enum's order, end to end; [`FAULT_ENDS`] splits it.
const FAULT_TEXT: &str = "hv-refusedpwmenablehv-modelboard cardqemu image on a real chipbreakdownhv-mismatchstack-opensensorleakage";
const FAULT_ENDS: [u8; 12] = [0, 10, 13, 19, 27, 37, 62, 71, 82, 92, 98, 105];

impl Fault {
    /// Every fault, in the enum's order.
    pub const ALL: [Fault; 11] = [
        Fault::HvRefused,
        Fault::Pwm,
        Fault::Enable,
        Fault::HvModel,
        Fault::BoardCard,
        Fault::EmulatorOnChip,
        Fault::Breakdown,
        Fault::HvMismatch,
        Fault::StackOpen,
        Fault::Sensor,
        Fault::Leakage,
    ];

    /// A fault of the read-back: re-arming after it runs the low-voltage check first.
    pub fn is_read_back(self) -> bool {
        matches!(self, Fault::Breakdown | Fault::HvMismatch | Fault::StackOpen | Fault::Sensor | Fault::Leakage)
    }

    /// The console's word for it (one string for all: the image's flash budget).
    pub fn text(self) -> &'static str {
        let k = self as usize;
        FAULT_TEXT.get(FAULT_ENDS[k] as usize..FAULT_ENDS[k + 1] as usize).unwrap_or("")
    }
}

/// The fault latched now, if any, as the core reports it ([`super::View::fault`]); it compares
/// equal to its console text (`Some("hv-refused")`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub struct Latched(pub Option<Fault>);

impl Latched {
    /// The fault, if any.
    pub fn get(self) -> Option<Fault> {
        self.0
    }
    /// Its console text, if any.
    pub fn text(self) -> Option<&'static str> {
        self.0.map(Fault::text)
    }
}

impl PartialEq<Option<&str>> for Latched {
    fn eq(&self, other: &Option<&str>) -> bool {
        self.text() == *other
    }
}
