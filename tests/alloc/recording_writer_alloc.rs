//! `RecordingWriter::write_row` must not allocate: it runs once a servo tick
//! during a scan. A counting allocator checks it (it counts per thread, so no
//! other test's allocations are counted).

use hapticlab::recording::RecordingWriter;

use crate::counting_alloc::allocations;

#[test]
fn write_row_and_flush_do_not_allocate() {
    let dir = tempfile::tempdir().unwrap();
    let columns = ["t_s", "x_m", "y_m", "z_m", "fx_n", "fy_n", "fz_n", "pac"];
    let mut writer = RecordingWriter::create(&dir.path().join("scan.csv"), &[], &columns).unwrap();
    let extremes = [
        -1e300,
        1e300,
        f64::NAN,
        f64::NEG_INFINITY,
        -0.0,
        5e-324,
        123456.789,
        0.1,
    ];
    let before = allocations();
    for i in 0..20_000 {
        let t = i as f64 * 1e-3;
        writer
            .write_row(&[t, t.sin(), -t, 0.02, t * 3.0, -0.31, 0.0, t.cos()])
            .unwrap();
        if i % 1000 == 0 {
            writer.write_row(&extremes).unwrap();
            writer.flush().unwrap();
        }
    }
    assert_eq!(allocations() - before, 0, "write_row or flush allocated");
    assert_eq!(writer.finish().unwrap(), 20_020);
}
