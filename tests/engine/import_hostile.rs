//! Hostile and wrong inputs to the NumPy, MATLAB and text readers, made
//! byte by byte: sizes a file declares are checked against what it holds
//! before anything is allocated, inflation is capped, a header is parsed
//! as numpy writes it, and what would be read wrong is refused naming it.

use std::io::Write as _;

use hapticlab::import::{ImportError, Request, parse_file};

fn rate(hz: f64) -> Request {
    Request {
        rate: Some(hz),
        ..Request::default()
    }
}

fn refused(bytes: Vec<u8>, ext: &str, args: &Request) -> String {
    match parse_file(bytes, "f", ext, args) {
        Err(ImportError::BadInput(m)) => m,
        Err(e) => panic!("a runtime failure, not bad input: {e}"),
        Ok(_) => panic!("accepted"),
    }
}

/// A `.npy` (format 1.0) with `header` (padded as numpy pads it) and `data`.
fn npy(header: &str, data: &[u8]) -> Vec<u8> {
    let mut h = header.as_bytes().to_vec();
    while !(10 + h.len() + 1).is_multiple_of(64) {
        h.push(b' ');
    }
    h.push(b'\n');
    let mut b = b"\x93NUMPY\x01\x00".to_vec();
    b.extend((h.len() as u16).to_le_bytes());
    b.extend(h);
    b.extend(data);
    b
}

fn f64s(v: &[f64]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

#[test]
fn an_npy_header_is_parsed_as_numpy_writes_it() {
    let data = f64s(&[1.0, 2.0, 3.0]);
    let good = npy(
        "{'descr': '<f8', 'fortran_order': False, 'shape': (3,), }",
        &data,
    );
    let ok = parse_file(good, "f", "npy", &rate(100.0)).unwrap();
    assert_eq!(ok.channels, [vec![1.0, 2.0, 3.0]]);
    // A string that holds `'shape': (1,)` is a string, and a key numpy
    // never writes is refused.
    for header in [
        "{'descr': '<f8', 'fortran_order': False, 'note': \"'shape': (1,)\", 'shape': (3,), }",
        "{'descr': '<f8', 'fortran_order': False, 'shape': (3,), 'x': \"'shape': (1,)\"}",
    ] {
        let m = refused(npy(header, &data), "npy", &rate(100.0));
        assert!(
            m.contains("a key") && m.contains("numpy does not write"),
            "{m}"
        );
    }
    let m = refused(
        npy("{'descr': '<f8', 'shape': (3,), }", &data),
        "npy",
        &rate(100.0),
    );
    assert!(m.contains("no 'fortran_order'"), "{m}");
    let m = refused(
        npy(
            "{'descr': '<f8', 'fortran_order': False, 'shape': (3), }",
            &data,
        ),
        "npy",
        &rate(100.0),
    );
    assert!(m.contains("without a comma"), "{m}");
    // A byte that is no text in the header is said as such.
    let mut b = npy(
        "{'descr': '<f8', 'fortran_order': False, 'shape': (3,), }",
        &data,
    );
    b[20] = 0xff;
    let m = refused(b, "npy", &rate(100.0));
    assert!(m.contains("not text") && m.contains("0xff"), "{m}");
}

#[test]
fn integers_a_sample_cannot_hold_exactly_are_refused() {
    let data: Vec<u8> = [1u64, u64::MAX]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let m = refused(
        npy(
            "{'descr': '<u8', 'fortran_order': False, 'shape': (2,), }",
            &data,
        ),
        "npy",
        &rate(100.0),
    );
    assert!(
        m.contains("18446744073709551615") && m.contains("2^53"),
        "{m}"
    );
    let m = refused(b"1\n9007199254740993\n".to_vec(), "txt", &rate(100.0));
    assert!(m.contains("f:2") && m.contains("2^53"), "{m}");
    // 2^53 itself is exact.
    let ok = parse_file(b"1\n9007199254740992\n".to_vec(), "f", "txt", &rate(100.0)).unwrap();
    assert_eq!(ok.channels[0][1], 9_007_199_254_740_992.0);
}

/// A zip of `(name, method, bytes stored, size claimed unpacked)`.
fn zip(entries: &[(&str, u16, Vec<u8>, u32)]) -> Vec<u8> {
    let mut b = Vec::new();
    let mut central = Vec::new();
    for (name, method, data, full) in entries {
        let local = b.len() as u32;
        b.extend(b"PK\x03\x04");
        b.extend(20u16.to_le_bytes());
        b.extend(0u16.to_le_bytes());
        b.extend(method.to_le_bytes());
        b.extend([0u8; 8]); // time, date, crc
        b.extend((data.len() as u32).to_le_bytes());
        b.extend(full.to_le_bytes());
        b.extend((name.len() as u16).to_le_bytes());
        b.extend(0u16.to_le_bytes());
        b.extend(name.as_bytes());
        b.extend(data);
        central.extend(b"PK\x01\x02");
        central.extend(20u16.to_le_bytes());
        central.extend(20u16.to_le_bytes());
        central.extend(0u16.to_le_bytes());
        central.extend(method.to_le_bytes());
        central.extend([0u8; 8]);
        central.extend((data.len() as u32).to_le_bytes());
        central.extend(full.to_le_bytes());
        central.extend((name.len() as u16).to_le_bytes());
        central.extend([0u8; 12]); // extra, comment, disk, attributes
        central.extend(local.to_le_bytes());
        central.extend(name.as_bytes());
    }
    let at = b.len() as u32;
    b.extend(&central);
    b.extend(b"PK\x05\x06");
    b.extend([0u8; 4]);
    b.extend((entries.len() as u16).to_le_bytes());
    b.extend((entries.len() as u16).to_le_bytes());
    b.extend((central.len() as u32).to_le_bytes());
    b.extend(at.to_le_bytes());
    b.extend(0u16.to_le_bytes());
    b
}

fn deflate(data: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::DeflateEncoder::new(Vec::new(), flate2::Compression::best());
    e.write_all(data).unwrap();
    e.finish().unwrap()
}

#[test]
fn npz_members_that_claim_or_unpack_to_too_much_are_refused() {
    // Members that each claim 4 GB: refused before anything is reserved.
    let small = deflate(&npy(
        "{'descr': '<f8', 'fortran_order': False, 'shape': (1,), }",
        &f64s(&[1.0]),
    ));
    let entries: Vec<(&str, u16, Vec<u8>, u32)> = ["a.npy", "b.npy", "c.npy"]
        .iter()
        .map(|n| (*n, 8, small.clone(), 0xFFFF_FFF0))
        .collect();
    let m = refused(zip(&entries), "npz", &rate(100.0));
    assert!(
        m.contains("claims") && m.contains("decompression bomb"),
        "{m}"
    );
    // A member that inflates past what it claims is stopped there.
    let zeros = vec![0u8; 8 << 20];
    let bomb = deflate(&zeros);
    let m = refused(
        zip(&[("a.npy", 8, bomb.clone(), 1000)]),
        "npz",
        &rate(100.0),
    );
    assert!(m.contains("more than the 1000 bytes it claims"), "{m}");
    // A member claiming what it unpacks to, beyond what the file may unpack
    // to (a hundred times its size, at least 64 MiB): refused as a bomb.
    let huge = vec![0u8; 80 << 20];
    let bomb = deflate(&huge);
    let m = refused(
        zip(&[("a.npy", 8, bomb, huge.len() as u32)]),
        "npz",
        &rate(100.0),
    );
    assert!(m.contains("decompression bomb"), "{m}");
}

/// A MATLAB level 5 header (little-endian unless `big`).
fn mat_header(big: bool) -> Vec<u8> {
    let mut h = b"MATLAB 5.0 MAT-file, made by a test".to_vec();
    h.resize(124, b' ');
    if big {
        h.extend([0x01, 0x00]);
        h.extend(b"MI");
    } else {
        h.extend([0x00, 0x01]);
        h.extend(b"IM");
    }
    h
}

/// A data element: tag (type, size) and data padded to 8 bytes.
fn element(kind: u32, data: &[u8]) -> Vec<u8> {
    let mut e = kind.to_le_bytes().to_vec();
    e.extend((data.len() as u32).to_le_bytes());
    e.extend(data);
    while !e.len().is_multiple_of(8) {
        e.push(0);
    }
    e
}

/// A double matrix variable `name` with dimensions `dims` (as int64) and `values`.
fn mat_variable(name: &str, dims: &[i64], values: &[f64]) -> Vec<u8> {
    let mut m = element(6, &[6, 0, 0, 0, 0, 0, 0, 0]); // flags: class double
    let dims: Vec<u8> = dims.iter().flat_map(|d| d.to_le_bytes()).collect();
    m.extend(element(12, &dims));
    m.extend(element(1, name.as_bytes()));
    m.extend(element(9, &f64s(values)));
    element(14, &m)
}

fn zlib(data: &[u8]) -> Vec<u8> {
    let mut e = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::best());
    e.write_all(data).unwrap();
    e.finish().unwrap()
}

#[test]
fn mat_dimensions_and_compressed_variables_are_checked_before_allocating() {
    let mut ok = mat_header(false);
    ok.extend(mat_variable("x", &[3, 1], &[1.0, 2.0, 3.0]));
    let r = parse_file(ok, "f", "mat", &rate(100.0)).unwrap();
    assert_eq!(r.channels, [vec![1.0, 2.0, 3.0]]);
    // Dimensions [2^32, 2^32] and no values: refused, nothing allocated.
    let mut dims = mat_header(false);
    dims.extend(mat_variable("x", &[1 << 32, 1 << 32], &[]));
    let m = refused(dims, "mat", &rate(100.0));
    assert!(m.contains("0 values for dimensions"), "{m}");
    // A compressed variable inflating past the cap.
    let mut inner = element(6, &[6, 0, 0, 0, 0, 0, 0, 0]);
    inner.extend(element(12, &[]));
    let mut big = vec![0u8; 80 << 20];
    big[..inner.len()].copy_from_slice(&inner);
    let packed = zlib(&big);
    let mut bomb = mat_header(false);
    bomb.extend(15u32.to_le_bytes());
    bomb.extend((packed.len() as u32).to_le_bytes());
    bomb.extend(&packed);
    let m = refused(bomb, "mat", &rate(100.0));
    assert!(m.contains("decompression bomb"), "{m}");
    // A big-endian header over little-endian data is said as such.
    let mut swapped = mat_header(true);
    swapped.extend(mat_variable("x", &[3, 1], &[1.0, 2.0, 3.0]));
    let m = refused(swapped, "mat", &rate(100.0));
    assert!(m.contains("big-endian") && m.contains("damaged"), "{m}");
}

#[test]
fn a_stated_rate_that_contradicts_rate_is_refused() {
    let mut b = mat_header(false);
    b.extend(mat_variable("x", &[4, 1], &[1.0, 2.0, 3.0, 4.0]));
    b.extend(mat_variable("fs", &[1, 1], &[2000.0]));
    let m = refused(b.clone(), "mat", &rate(1000.0));
    assert!(
        m.contains("`fs` = 2000") && m.contains("--rate 2000"),
        "{m}"
    );
    assert!(parse_file(b.clone(), "f", "mat", &rate(2000.0)).is_ok());
    // In kHz is the same rate.
    let mut k = mat_header(false);
    k.extend(mat_variable("x", &[4, 1], &[1.0, 2.0, 3.0, 4.0]));
    k.extend(mat_variable("fs", &[1, 1], &[2.0]));
    assert!(parse_file(k, "f", "mat", &rate(2000.0)).is_ok());
}

#[test]
fn flags_only_a_csv_takes_are_refused_on_other_files() {
    let args = Request {
        rate: Some(100.0),
        channels: vec!["a".into()],
        burst: 2,
        ..Request::default()
    };
    let mut mat = mat_header(false);
    mat.extend(mat_variable("x", &[3, 1], &[1.0, 2.0, 3.0]));
    let npy_file = npy(
        "{'descr': '<f8', 'fortran_order': False, 'shape': (3,), }",
        &f64s(&[1.0, 2.0, 3.0]),
    );
    for (bytes, ext) in [
        (b"1\n2\n3\n".to_vec(), "txt"),
        (npy_file, "npy"),
        (mat, "mat"),
    ] {
        let m = refused(bytes, ext, &args);
        assert!(
            m.contains("--channels, --burst apply to CSV files with a header only"),
            "{ext}: {m}"
        );
    }
}

#[test]
fn a_bom_before_headerless_text_is_no_sample_lost() {
    let args = Request {
        rate: Some(100.0),
        names: vec!["acc".into()],
        ..Request::default()
    };
    let r = parse_file("\u{feff}0.5\n0.25\n".as_bytes().to_vec(), "f", "txt", &args).unwrap();
    assert_eq!(r.names, ["acc"]);
    assert_eq!(r.channels, [vec![0.5, 0.25]]);
}
