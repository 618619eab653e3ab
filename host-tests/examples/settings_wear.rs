//! Regenerates docs/firmware.md's settings wear figures (between the `settings-wear` markers):
//! the store on the board's geometry (three 16 KiB erase sectors, src/flash_chip.rs) over the
//! host's counting flash (host_tests::cut_flash), the firmware's `save` on the simulated board,
//! repeated: bytes written and sectors erased per save, and the saves the most-erased sector
//! lasts at the F405's rated 10,000 erase cycles (datasheet DS8626, "Flash memory endurance").
//!
//! `cd host-tests && cargo run --release --example settings_wear`
use finger_fw::flash_ram::{PAGE, PAGES};
use finger_fw::settings::FlashStore;
use finger_fw::sim::SimBoard;
use finger_fw::App;
use host_tests::cut_flash::CutFlash;
use host_tests::sim_console::cmd;

const SAVES: u64 = 20_000;
/// Rated program/erase cycles per sector (STM32F405, DS8626 Table "Flash memory endurance and
/// data retention", N_END at T_A -40..85 °C).
const ENDURANCE: u64 = 10_000;

fn main() {
    let flash = CutFlash::<PAGE>::new(PAGES);
    let store = Box::leak(Box::new(FlashStore::new(flash.clone(), 0..(PAGES * PAGE) as u32)));
    let mut a = App::with_store(SimBoard::default(), store);
    let mut bytes = 0;
    for k in 0..SAVES {
        // a different value each save (a calibration session)
        let r = cmd(&mut a, &format!("param slew {}", 1000 + k % 5000));
        assert!(r.starts_with("ok"), "{r}");
        let r = cmd(&mut a, "save");
        assert!(r.starts_with("ok saved="), "{r}");
        bytes = r.rsplit("bytes=").next().unwrap().parse::<u64>().unwrap();
    }
    let s = flash.state.borrow();
    let erases: u64 = s.page_erases.iter().sum();
    let worst = *s.page_erases.iter().max().unwrap();
    let per_save = erases as f64 / SAVES as f64;
    let saves_to_end = ENDURANCE as f64 * SAVES as f64 / worst as f64;
    let mut out = String::new();
    out.push_str("<!-- settings-wear:begin (cd host-tests && cargo run --release --example settings_wear) -->\n");
    out.push_str(&format!("| {SAVES} saves of a {bytes}-byte record on three 16 KiB sectors | figure |\n| --- | --- |\n"));
    out.push_str(&format!("| bytes written per save (record, the map's item header and page marks) | {:.1} |\n", s.bytes_written as f64 / SAVES as f64));
    out.push_str(&format!("| sector erases per save (all sectors) | {per_save:.4} (one erase every {:.0} saves) |\n", 1.0 / per_save));
    out.push_str(&format!("| erases of the most-erased sector | {worst} of {erases} (per sector: {:?}) |\n", s.page_erases));
    out.push_str(&format!("| saves until that sector reaches the rated {ENDURANCE} cycles | {:.2e} |\n", saves_to_end));
    out.push_str("<!-- settings-wear:end -->\n");
    print!("{out}");
    host_tests::report::write_section("docs/firmware.md", "settings-wear", &out);
}
