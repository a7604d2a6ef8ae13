#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    let _ = hapticlab_fuzz::import_numpy(data);
});
