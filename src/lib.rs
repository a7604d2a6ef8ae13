//! hapticlab: haptic texture classification with a Novint Falcon (or its
//! simulation), after G. A. Hidalgo Vázquez, *Supervised Learning for Haptics
//! Texture Classification Using Fourier Analysis*, master's thesis,
//! Tecnológico de Monterrey, 2011.
//!
//! This package holds the front ends: the command line (`cli`, `commands`),
//! the console (`console`), `doctor` and the terminal. They are the only code that prints, reads keys or knows clap.
//! The engine (devices, servo loop, recordings, import, analysis,
//! classifier, evaluation) is the `hapticlab-engine` crate in `engine/`, which cannot
//! see this package; its modules are re-exported here so that
//! `hapticlab::dataset` and `crate::dataset` name the same thing.

pub use hapticlab_engine::{
    acquire, analysis, classify, clock, dataset, device, evaluate, folds, import, io, predictor,
    profile, recorder, recording, servo, triggers, tune, version,
};

pub mod cli;
pub mod commands;
pub mod console;
pub mod doctor;
pub mod scratch;
pub mod support;
pub mod terminal;
