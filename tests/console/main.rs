//! The console binary in a pseudo-terminal, and what it does when its
//! terminal goes away (`cargo test --test console terminal_loss::` runs one
//! file). Kept apart from `tests/cli`: these tests time how fast the
//! process exits, so they share the machine with few others.

mod console_e2e;
mod terminal_loss;
