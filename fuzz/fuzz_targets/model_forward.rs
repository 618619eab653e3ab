//! libFuzzer target: finger_fuzz::model_forward::check (its header lists the invariants).
#![no_main]
libfuzzer_sys::fuzz_target!(|data: &[u8]| finger_fuzz::model_forward::check(data));
