//! hapticlab: haptic texture classification with a Novint Falcon (or its
//! simulation), after the thesis in `shared/reference/thesis.txt`.
//!
//! The engine (profile, device, servo, recorder/recording, analysis,
//! classifier) knows nothing of any user interface; the command line and the
//! console are front ends over it.

pub mod acquire;
pub mod analysis;
pub mod classify;
pub mod cli;
pub mod commands;
pub mod console;
pub mod device;
pub mod devices;
pub mod doctor;
pub mod evaluate;
pub mod import;
pub mod inspect;
pub mod plot;
pub mod profile;
pub mod recorder;
pub mod recording;
pub mod scratch;
pub mod servo;
pub mod study;
pub mod triggers;
