//! libFuzzer target: finger_fuzz::model_fmax::check (its header lists the invariants).
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| finger_fuzz::model_fmax::check(data));
