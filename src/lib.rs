//! hapticlab: haptic texture classification with a Novint Falcon (or its
//! simulation), after the thesis in `shared/reference/thesis.txt`.
//!
//! The engine (profile, device, servo, recording, analysis, classifier) knows
//! nothing of any user interface; the command line and the console are front
//! ends over it.

pub mod analysis;
pub mod classify;
pub mod evaluate;
pub mod profile;
pub mod recording;
