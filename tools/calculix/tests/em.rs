//! The electromechanical FE (`em`): the voltage applied, not the model's thicknesses.
use finger_calculix::em::{free_film, FixedPoint};
use finger_model::Params;

#[test]
fn a_free_film_reproduces_the_free_film_balance() {
    let p = Params::<f64>::vhb4905();
    for v in [2000.0, 5395.0] {
        let t = std::time::Instant::now();
        let (s_fe, s_model, sol) = free_film(&p, v, FixedPoint::default()).unwrap();
        eprintln!(
            "{v} V: s_fe {s_fe:.6} s_model {s_model:.6} err {:.4} % iters {} update {:.1e} {:?}",
            100.0 * (s_fe / s_model - 1.0),
            sol.iterations,
            sol.update,
            t.elapsed()
        );
        assert!((s_fe / s_model - 1.0).abs() < 1e-3);
    }
}
