//! hapticlab's engine: haptic texture classification with a Novint Falcon
//! (or its simulation), after G. A. Hidalgo Vázquez, *Supervised Learning for
//! Haptics Texture Classification Using Fourier Analysis*, master's thesis,
//! Tecnológico de Monterrey, 2011.
//!
//! Layers, each using only those below it (no module imports one above):
//!
//! ```text
//! tune                             the nested search over analysis and k-NN settings
//! evaluate                         the one evaluation: holdout, folds, LOO, groups, sweeps
//! acquire                          simulate / scan
//! predictor                        a model's answer for a recording (windows, leave-out)
//! dataset · servo                  recordings → feature vectors on every core; the 1 kHz loop
//! device · classify                the Falcon, its emulator and simulation; k-NN and its model file
//! clock · analysis · triggers · recorder · import
//!                                  time and real-time scheduling; spectra; hands-free triggers;
//!                                  samples to disk; other rigs' files (CSV, text, WAV, NumPy,
//!                                  MATLAB) to recordings
//! recording · profile              ground: recording format v1 (and the files a command may read
//!                                  and write); the TOML schema, its checks, the list of options;
//!                                  version: the package version and the commit it was built from
//! ```
//!
//! It knows nothing of any user interface: it never prints, reads the
//! terminal or parses a command line, and depends on none of clap, ratatui,
//! crossterm or indicatif. Errors are `thiserror` enums; progress reaches the
//! caller through callbacks, and the work the caller may cancel (a simulated
//! sweep's scratch folder) through [`evaluate::sweep::Scratch`].

pub mod acquire;
pub mod analysis;
pub mod classify;
pub mod clock;
pub mod dataset;
pub mod device;
pub mod evaluate;
pub mod folds;
pub mod import;
pub mod io;
pub mod predictor;
pub mod profile;
pub mod recorder;
pub mod recording;
pub mod servo;
pub mod triggers;
pub mod tune;
pub mod version;
