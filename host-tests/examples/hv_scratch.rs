use host_tests::plant_runs::soft_film_history;
fn main() {
    let ts: f32 = std::env::args().nth(1).map(|x| x.parse().unwrap()).unwrap_or(30.0);
    let mut bad = 0;
    for s in 0..100 {
        let r = soft_film_history(2_000_000_000 + s, 3000, ts, true);
        if r.collapsed || r.s_min <= 2.0 / 3.0 {
            bad += 1;
            if bad < 6 { println!("seed {s}: {r:?}"); }
        }
    }
    println!("bad {bad}/100");
}
