//! The parts on a board: [`wire`] builds the command side and the control core and hands the
//! core its first setpoints. The chip (src/chip.rs), [`super::App`] and the on-target tests all
//! start from it.

use embedded_hal::pwm::SetDutyCycle;

use super::commands::Commands;
use super::params::CHANNELS;
use crate::board::Board;
use crate::control::Control;

/// The command side and the control core on `board`: HV enable low, every HV duty 0, cable
/// released, default parameters; the core holds the command side's first setpoints and the
/// command side its view.
pub fn wire<B: Board>(mut board: B) -> (Commands, Control<B>) {
    let mut hv_max = [0u16; CHANNELS];
    for (ch, m) in hv_max.iter_mut().enumerate() {
        *m = board.hv(ch).max_duty_cycle();
    }
    let servo_max = board.servo().max_duty_cycle();
    let mut cmds = Commands::new(board.name(), board.newline(), hv_max, servo_max);
    let sp = cmds.setpoints();
    let mut ctl = Control::new(board, sp.servo_released, sp.slew);
    ctl.apply(&sp);
    cmds.sync(&ctl.view());
    (cmds, ctl)
}
