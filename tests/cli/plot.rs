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
    // The figure names how its counts were made.
    assert!(svg.contains("3-fold cross-validation"));
    // Wrong inputs are bad input with a message.
    let out = hapticlab(&["plot", "sweep", &p("r.json"), "--out", &p("x.png")]);
    assert_eq!(out.status.code(), Some(2));
    let out = hapticlab(&["plot", "confusion", &p("r.json"), "--out", &p("x.jpg")]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn a_trace_draws_every_channel_and_a_key_that_covers_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let p = |name: &str| dir.path().join(name).display().to_string();
    // Two labels of three-axis data at 100 Hz, 4 s each; z sits near 9.8.
    for label in ["A", "B"] {
        std::fs::create_dir_all(dir.path().join(label)).unwrap();
        for trial in 0..3 {
            let f = if label == "A" { 5.0 } else { 9.0 };
            let mut text = String::from("ax,ay,az\n");
            for i in 0..400 {
                let t = f64::from(i) / 100.0;
                let w = std::f64::consts::TAU * f * t + f64::from(trial);
                text += &format!(
                    "{:.5},{:.5},{:.5}\n",
                    w.sin(),
                    0.5 * w.cos(),
                    9.8 + 0.01 * w.sin()
                );
            }
            std::fs::write(
                dir.path().join(label).join(format!("{label}{trial}.csv")),
                text,
            )
            .unwrap();
        }
    }
    let ok = |out: std::process::Output| {
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    let mut import = vec!["import".to_string()];
    for label in ["A", "B"] {
        for trial in 0..3 {
            import.push(p(&format!("{label}/{label}{trial}.csv")));
        }
    }
    import.extend(["--rate", "100", "--out"].map(String::from));
    import.push(p("rec"));
    ok(hapticlab(
        &import.iter().map(String::as_str).collect::<Vec<_>>(),
    ));
    ok(hapticlab(&[
        "profile",
        "new",
        "--from",
        &p("rec"),
        "--out",
        &p("p.toml"),
    ]));
    let profile = std::fs::read_to_string(p("p.toml")).unwrap();
    assert!(profile.contains("channels = [\"ay\", \"az\"]"), "{profile}");
    ok(hapticlab(&[
        "plot",
        "trace",
        &p("rec/A/A0.csv"),
        "-p",
        &p("p.toml"),
        "--out",
        &p("t.svg"),
    ]));
    let svg = std::fs::read_to_string(p("t.svg")).unwrap();
    // A panel and a spectrum for each channel, not only the first.
    let text = |t: &str| svg.lines().any(|l| l.trim() == t);
    for name in ["ax", "ay", "az"] {
        assert!(text(name), "{name}");
        assert!(text(&format!("{name}: logwelch spectrum")), "{name}");
    }
    // The key is a line under the title, not a box over the data.
    assert!(svg.contains("grey: recorded · black: resampled · shaded: analysis window"));
    assert!(!text("recorded trace"));
    // A holdout's confusion figure names its validation.
    let report = hapticlab(&["evaluate", "recordings/thesis-sim", "--json"]);
    assert!(report.status.success());
    std::fs::write(p("r.json"), &report.stdout).unwrap();
    ok(hapticlab(&[
        "plot",
        "confusion",
        &p("r.json"),
        "--out",
        &p("c.svg"),
    ]));
    let svg = std::fs::read_to_string(p("c.svg")).unwrap();
    assert!(svg.contains("holdout: 80 training, 40 test recording(s)"));
}
