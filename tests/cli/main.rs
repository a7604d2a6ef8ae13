//! The real `hapticlab` binary, end to end, and the engine tests that run
//! beside it: one test binary, so the crate is linked once for all of them.
//! Each file below is one subject (`cargo test --test cli doctor::` runs one).

#[path = "../common/mod.rs"]
mod common;

mod bad_recordings;
mod cli;
mod completions_man;
mod console_windows;
mod docs;
mod doctor;
mod evaluate_windows;
mod falcon_emulator;
mod falcon_exit;
mod falcon_self_test;
mod families;
mod faults;
mod first_session;
mod golden;
mod help_examples;
mod import;
mod import_formats;
mod import_refusals;
mod import_split;
mod next_steps;
mod nothing_lost;
mod one_answer;
mod plot;
mod profile_new;
mod refusals;
mod rigless;
mod safe_io;
mod sweep_grid;
mod sweep_simulated;
mod tune;
mod validation;
mod version;
mod white_noise;
mod windows;
