//! Property tests over the documented domain (finger-model-testkit: model/testkit/src/domain.rs): forward,
//! fmax, the inverse round trip and contact, 10,000 cases in all. No panic, no NaN or inf in an
//! answer, no `NotConverged` or fault: every case answers or is refused with a typed reason.
//! The soak (`cargo run --example soak` in host-tests) runs the same cases by the
//! million and prints the count of each outcome.

use finger_model::Finger;
use finger_model_testkit::domain;
use proptest::prelude::*;

fn hinge() -> impl Strategy<Value = Finger<f64>> {
    (prop::bool::ANY, 1usize..=8, prop::bool::ANY, prop::bool::ANY).prop_map(|(paper, m, plate, flex)| domain::finger(paper, m, plate, flex))
}

fn ok(r: Result<&'static str, String>) -> Result<(), TestCaseError> {
    r.map(|_| ()).map_err(TestCaseError::fail)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 4000, failure_persistence: None, ..ProptestConfig::default() })]
    #[test]
    fn forward_answers_up_to_fmax(f in hinge(), frac in 0.0f64..=1.0, vfrac in prop::array::uniform3(0.0f64..=1.0)) {
        ok(domain::forward(&f, frac, vfrac))?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 3000, failure_persistence: None, ..ProptestConfig::default() })]
    #[test]
    fn fmax_answers(f in hinge(), vfrac in prop::array::uniform3(0.0f64..=1.0)) {
        ok(domain::fmax(&f, vfrac))?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1500, failure_persistence: None, ..ProptestConfig::default() })]
    #[test]
    fn inverse_round_trip_holds(f in hinge(), frac in 0.02f64..0.6, vfrac in prop::array::uniform3(0.0f64..0.9)) {
        ok(domain::inverse(&f, frac, vfrac))?;
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1500, failure_persistence: None, ..ProptestConfig::default() })]
    #[test]
    fn contact_answers_or_refuses_typed(p0 in 0.05f64..5.0, pfrac in 0.0f64..=1.0, vfrac in prop::array::uniform3(0.0f64..=1.0)) {
        let f = domain::finger(false, 8, true, true);
        ok(domain::contact(&f, p0, pfrac, vfrac))?;
    }
}
