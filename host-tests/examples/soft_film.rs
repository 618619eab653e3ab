//! A film softer than the card, held at the largest voltage the board takes, at real time:
//! each minute the channel's ceiling, the sensed and the true thickness, `film_check`
//! (docs/firmware.md "The thickness guard"). `cargo run --release --example soft_film [G_EQ_KPA] [SECONDS]`.
use finger_fw::control::Control;
use finger_fw::plant::Plant;
use finger_fw::sim::SimBoard;
use host_tests::hv::setpoints;
use host_tests::plant_runs::run;

fn main() {
    let mut args = std::env::args().skip(1);
    let g: f32 = args.next().map_or(6.7, |a| a.parse().expect("G_eq, kPa"));
    let secs: u32 = args.next().map_or(300, |a| a.parse().expect("seconds"));
    let mut plant = Plant::new(1).expect("plant");
    plant.set_film(g, 1.0).expect("film");
    let mut c = Control::new(SimBoard::with_plant(plant), 2000, 2000.0);
    let v = c.hold_ceiling_v() - 0.1;
    assert!(c.apply(&setpoints(&c, [v; 3], false, 2000.0)), "{v} V refused");
    println!("G_eq {g} kPa, held at {v:.1} V");
    println!("| t (s) | ceiling (V) | volts (V) | s sensed | s true | s model | film_check |");
    println!("| --- | --- | --- | --- | --- | --- | --- |");
    for t in 1..=secs {
        run(&mut c, 1000);
        if t % 30 == 0 || t == 10 {
            let view = c.view();
            let sense = view.sense.expect("read-back");
            let truth = view.plant.expect("plant");
            println!(
                "| {t} | {:.0} | {:.0} | {:.4} | {:.4} | {:.4} | {} |",
                sense.ceiling_v[0],
                view.volts[0],
                sense.stack_ratio[0],
                truth.s[0],
                view.stack_ratio[0],
                if sense.disagreed[0] { "thinner" } else { "ok" }
            );
        }
    }
    let view = c.view();
    println!(
        "fault {:?}, thinnest true film {:.4}",
        view.fault.get(),
        c.board().plant.as_ref().expect("plant").truth().iter().map(|t| t.s_min).fold(1.0, f32::min)
    );
}
