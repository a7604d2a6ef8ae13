//! hapticlab: haptic texture classification with a Novint Falcon (or its
//! simulation), after G. A. Hidalgo Vázquez, *Supervised Learning for Haptics
//! Texture Classification Using Fourier Analysis*, master's thesis,
//! Tecnológico de Monterrey, 2011.
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
pub mod dataset;
pub mod device;
pub mod doctor;
pub mod evaluate;
pub mod import;
pub mod predictor;
pub mod profile;
pub mod recorder;
pub mod recording;
pub mod scratch;
pub mod servo;
pub mod support;
pub mod terminal;
pub mod triggers;
