//! The engine in process, without the binary: analysis, spectra, the
//! classifier, evaluation, profiles, the recording reader, imports, the
//! servo loop, and the fuzz targets' regressions. One test binary, so the
//! crate is linked once for all of them (`cargo test --test engine servo::`
//! runs one file).

#[path = "../common/mod.rs"]
mod common;

/// The fuzz targets' entry points (`fuzz/src/lib.rs`), shared by
/// `fuzz_regressions`, `import` and `profiles`.
#[path = "../../fuzz/src/lib.rs"]
#[allow(dead_code)]
mod entries;

mod analysis;
mod classify;
mod evaluate;
mod families;
mod fuzz_regressions;
mod import;
mod import_hostile;
mod knn_options;
mod layers;
mod profiles;
mod recording_reader;
mod servo;
mod servo_catch_up;
mod servo_watchdog;
mod spectra;
mod thesis;
mod window;
