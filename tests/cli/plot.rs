//! Figures are written as PNG and SVG, with the bundled font, from the
//! shipped dataset and from `evaluate --json` output.

fn hapticlab(args: &[&str]) -> std::process::Output {
    crate::common::hapticlab().args(args).output().unwrap()
}

#[test]
fn every_figure_as_png_and_svg() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).display().to_string();
    let ok = |out: std::process::Output| {
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        out.stdout
    };
    ok(hapticlab(&[
        "plot",
        "trace",
        "recordings/thesis-sim/S2/S2_001.csv.gz",
        "--out",
        &p("t.png"),
    ]));
    ok(hapticlab(&[
        "plot",
        "trace",
        "recordings/thesis-sim/S3/S3_001.csv.gz",
        "--out",
        &p("t.svg"),
    ]));
    ok(hapticlab(&[
        "plot",
        "features",
        "recordings/thesis-sim",
        "--per-class",
        "3",
        "--out",
        &p("f.png"),
    ]));
    let report = ok(hapticlab(&[
        "evaluate",
        "recordings/thesis-sim",
        "--folds",
        "3",
        "--json",
    ]));
    std::fs::write(p("r.json"), report).unwrap();
    ok(hapticlab(&[
        "plot",
        "confusion",
        &p("r.json"),
        "--out",
        &p("c.svg"),
    ]));
    let sweep = ok(hapticlab(&[
        "evaluate",
        "recordings/thesis-sim",
        "--folds",
        "3",
        "--sweep",
        "k=1..5:2",
        "--json",
    ]));
    std::fs::write(p("s.json"), sweep).unwrap();
    ok(hapticlab(&[
        "plot",
        "sweep",
        &p("s.json"),
        "--out",
        &p("s.png"),
    ]));
    for f in ["t.png", "f.png", "s.png"] {
        let b = std::fs::read(p(f)).unwrap();
        assert!(b.starts_with(b"\x89PNG") && b.len() > 5000, "{f}");
    }
    for f in ["t.svg", "c.svg"] {
        let s = std::fs::read_to_string(p(f)).unwrap();
        assert!(s.contains("<svg") && s.contains("</svg>"), "{f}");
        // The text names the bundled font first, not only the viewer's default.
        assert!(
            s.contains("font-family=\"DejaVu Sans, sans-serif\"")
                && !s.contains("font-family=\"sans-serif\""),
            "{f}"
        );
    }
    let svg = std::fs::read_to_string(p("c.svg")).unwrap();
    assert!(svg.contains("classified as") && svg.contains("true class"));
    // Wrong inputs are bad input with a message.
    let out = hapticlab(&["plot", "sweep", &p("r.json"), "--out", &p("x.png")]);
    assert_eq!(out.status.code(), Some(2));
    let out = hapticlab(&["plot", "confusion", &p("r.json"), "--out", &p("x.jpg")]);
    assert_eq!(out.status.code(), Some(2));
}
