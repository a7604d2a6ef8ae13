//! Allocation counts on the hot paths: feature extraction, the recording
//! writer, the servo tick, the Falcon driver. One binary with one counting
//! global allocator (`tests/common/counting_alloc.rs`); it counts per thread,
//! so the tests, each on its own thread, do not see each other's allocations.
//! `cargo test --test alloc servo_alloc::` runs one file.

#[path = "../common/counting_alloc.rs"]
mod counting_alloc;

mod falcon_alloc;
mod no_alloc;
mod recording_writer_alloc;
mod servo_alloc;
