//! libFuzzer target: finger_fuzz::model_contact::check (its header lists the invariants).
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| finger_fuzz::model_contact::check(data));
