//! The console's commands on the settings store (docs/firmware.md "Settings"): `save`,
//! `config`, `factory`, and the boot hook that puts a stored record in force
//! ([`Commands::boot_settings`], [`App::with_store`]). A record is checked as the console checks
//! each value (`super::stored`); `save` refuses what a boot would refuse.
//!
//! What it is not: the record's checks (`super::stored`), its bytes or the flash
//! (`crate::settings`).

use core::fmt::Write;

use finger_model::Finger;
use finger_protocol::{const_concat, field};

use super::commands::Commands;
use super::errors::{no_args, CmdError};
use super::help::Reply;
use super::host::App;
pub use super::params::default_finger;
use super::params::FwParams;
use super::stored::name_of;
pub use super::stored::{board_ceiling, record_of, record_with, settings_of, Boot, Reject};
use crate::board::Board;
use crate::control::Control;
use crate::num::{Fixed, Short};
use crate::settings::{ConfigStore, Record, FORMAT_VERSION, RECORD_MAX};

impl Commands {
    /// Put `finger` and `fw` in force (disarmed: the cable released if the servo cannot hold
    /// its tension there).
    fn put_settings(&mut self, finger: Finger<f32>, fw: FwParams) {
        self.hold_or_release(self.plan_servo(&finger, &fw, self.force, &self.target_v));
        self.planner.set_finger(finger);
        self.fw = fw;
        self.recompute();
    }

    /// At boot, before the control core starts: take `store`, and put its record in force if
    /// every check passes. What happened: [`Commands::config_boot`].
    pub fn boot_settings(&mut self, store: &'static mut dyn ConfigStore) -> Boot {
        let mut buf = [0u8; RECORD_MAX];
        let boot = match store.read(&mut buf) {
            Ok(None) => Boot::Empty,
            Err(e) => Boot::Rejected(Reject::Store(e)),
            Ok(Some(n)) => match Record::decode(&buf[..n]).map_err(Reject::Format).and_then(|r| settings_of(&r).map(|s| (r.counter, s))) {
                Ok((counter, (f, fw))) => {
                    self.put_settings(f, fw);
                    if let Ok(c) = Record::decode(&buf[..n]).map_err(|_| ()).and_then(|r| super::hv_cal::sense_cal_of(&r).map_err(|_| ())) {
                        self.sense_cal = c;
                        self.sense_cal_req = Some(c);
                    }
                    self.cfg.saves = counter;
                    Boot::Loaded
                }
                Err(e) => Boot::Rejected(e),
            },
        };
        self.cfg.store = Some(store);
        self.cfg.boot = boot;
        self.cfg.rejected = matches!(boot, Boot::Rejected(_));
        boot
    }

    /// What the boot found (the banner's `config=` word).
    pub fn config_boot(&self) -> Boot {
        self.cfg.boot
    }

    /// `fault=config-rejected` while a refused store's defaults are in force.
    pub(super) fn config_fault(&self) -> Option<&'static str> {
        if self.cfg.rejected {
            Some("config-rejected")
        } else {
            None
        }
    }

    /// `save`: the settings in force into the store, disarmed only. Refused (nothing
    /// written) when a boot would refuse them.
    #[inline(never)]
    pub(super) fn cmd_save(&mut self, args: &[&[u8]], r: &mut Reply) -> Result<(), CmdError> {
        no_args(args, "save")?;
        self.require_disarmed("save")?;
        if self.cfg.store.is_none() {
            return Err(err!(Unknown; "save: this board has no settings store"));
        }
        let rec = record_with(self.planner.finger(), &self.fw, &self.sense_cal, self.cfg.saves.wrapping_add(1));
        match settings_of(&rec) {
            Ok((f, fw)) if f.params() == self.planner.finger().params() && f.calibration() == self.planner.finger().calibration() && fw == self.fw => {}
            Ok(_) => return Err(err!(Usage; "save: the settings in force do not read back as themselves; not saved")),
            Err(Reject::Ceiling) => {
                let v = self.planner.finger().ceiling_in_force(None);
                return Err(
                    err!(Limit; "save: these settings raise the model's ceiling to ", Fixed(v, 1), " V, past the compiled ", Fixed(board_ceiling(), 1), " V; not saved"),
                );
            }
            Err(e) => return Err(err!(Usage; "save: a boot would refuse these settings (", e, "); not saved")),
        }
        let mut buf = [0u8; RECORD_MAX];
        let n = rec.encode(&mut buf);
        let Some(store) = self.cfg.store.as_mut() else { return Err(err!(Unknown; "save: no store")) };
        store.write(&buf[..n]).map_err(|e| err!(Store; "save failed (", e.name(), "): the store holds the previous record or none; see config"))?;
        self.cfg.saves = rec.counter;
        self.cfg.rejected = false;
        let _ = w!(r; field::SAVED.first(), rec.counter, field::BYTES.after(), n);
        Ok(())
    }

    /// `factory`: erase the store and put the compiled defaults in force, disarmed only.
    #[inline(never)]
    pub(super) fn cmd_factory(&mut self, args: &[&[u8]], r: &mut Reply) -> Result<(), CmdError> {
        no_args(args, "factory")?;
        self.require_disarmed("factory")?;
        if let Some(store) = self.cfg.store.as_mut() {
            store.erase().map_err(|e| err!(Store; "factory: erase failed (", e.name(), "); settings unchanged"))?;
        }
        self.put_settings(default_finger(), FwParams::default());
        self.sense_cal = super::hv_cal::SenseCal::NOMINAL;
        self.sense_cal_req = Some(self.sense_cal);
        self.cfg.saves = 0;
        self.cfg.rejected = false;
        // nothing is stored now, with a store or without one (the simulated board's)
        let _ = w!(r; const_concat!(field::FACTORY.first(), "1", field::STORE.after(), "empty"));
        Ok(())
    }

    /// `config`: the stored values that differ from the compiled defaults, one line each
    /// (armed, or the HV still on: read without a repair, refused `err armed` if one is
    /// needed)
    /// (`stored <name>=<value> default=<value>`), then `ok store=<none|empty|saved|unreadable>
    /// saves=<n> boot=<none|empty|loaded|rejected> [reason=<why>] fault=<config-rejected|none>
    /// format=<v> values=<n> differ=<n> preset=<default|paper>`.
    #[inline(never)]
    pub(super) fn cmd_config<W: Write>(&mut self, args: &[&[u8]], r: &mut Reply, out: &mut W) -> Result<(), CmdError> {
        no_args(args, "config")?;
        let nl = self.nl;
        let mut buf = [0u8; RECORD_MAX];
        // armed (or the HV still on), a read that may not repair: an erase stalls every fetch
        // from flash, the analog watchdog's handler included
        let armed = self.require_disarmed("config").is_err();
        let read = self.cfg.store.as_mut().map(|s| if armed { s.peek(&mut buf) } else { s.read(&mut buf) });
        if let Some(Err(crate::settings::StoreError::Repair)) = read {
            return Err(err!(Armed; "config: the store needs a repair (a flash erase, which stalls the chip); disarm first"));
        }
        let (state, rec) = match read {
            None => ("none", None),
            Some(Ok(None)) => ("empty", None),
            Some(Ok(Some(n))) => match Record::decode(&buf[..n]) {
                Ok(rec) => ("saved", Some(rec)),
                Err(_) => ("unreadable", None),
            },
            Some(Err(_)) => ("unreadable", None),
        };
        let mut differ = 0usize;
        if let Some(rec) = &rec {
            let defaults = record_of(&default_finger(), &FwParams::default(), 0);
            for &(t, v) in &rec.values {
                let d = defaults.values.iter().find(|(dt, _)| *dt == t).map(|&(_, d)| d);
                if d.map(|d| d.to_bits()) == Some(v.to_bits()) {
                    continue;
                }
                differ += 1;
                let _ = w!(out; "stored ", name_of(t), "=", Short(v), field::DEFAULT.after());
                let _ = match d {
                    Some(d) => w!(out; Short(d), nl),
                    None => w!(out; "-", nl),
                };
            }
        }
        let boot = match self.cfg.boot {
            Boot::NoStore => "none",
            Boot::Empty => "empty",
            Boot::Loaded => "loaded",
            Boot::Rejected(_) => "rejected",
        };
        let _ = w!(r; field::STORE.first(), state, field::SAVES.after(), rec.as_ref().map_or(self.cfg.saves, |r| r.counter), field::BOOT.after(), boot);
        if let Boot::Rejected(e) = self.cfg.boot {
            let _ = w!(r; field::REASON.after(), e);
        }
        let _ = w!(r; field::FAULT.after(), self.config_fault().unwrap_or("none"), field::FORMAT.after(), FORMAT_VERSION);
        if let Some(rec) = &rec {
            let _ = w!(r; field::VALUES.after(), rec.values.len(), field::DIFFER.after(), differ, field::PRESET.after(), if rec.preset == 1 { "paper" } else { "default" });
        }
        Ok(())
    }
}

/// At boot, after [`super::wire`]: the settings from `store` into the command side, then its
/// setpoints to the core. What the boot found.
pub fn boot<B: Board>(cmds: &mut Commands, ctl: &mut Control<B>, store: &'static mut dyn ConfigStore) -> Boot {
    let boot = cmds.boot_settings(store);
    if let Some(c) = cmds.take_sense_cal() {
        ctl.set_sense_cal(c.monitor, c.c0_pf);
    }
    let sp = cmds.setpoints();
    ctl.apply(&sp);
    cmds.sync(&ctl.view());
    boot
}

impl<B: Board> App<B> {
    /// Take the board as [`App::new`] does, then the settings from `store` (the boot hook).
    pub fn with_store(board: B, store: &'static mut dyn ConfigStore) -> Self {
        let mut app = Self::new(board);
        boot(&mut app.cmds, &mut app.ctl, store);
        app
    }

    /// What the boot found in the store.
    pub fn config_boot(&self) -> Boot {
        self.cmds.config_boot()
    }
}
