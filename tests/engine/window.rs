//! The analysis window as a profile writes it: `[start, end]` along the
//! axis, or `"scan-leg"` for the whole scan leg; and no taper (a
//! rectangular window, the thesis's) or a Hann taper.

use std::path::Path;

use hapticlab::analysis::FeatureExtractor;
use hapticlab::evaluate::sweep::with_key;
use hapticlab::profile::{LoadedProfile, Taper};
use hapticlab::recording;

/// The thesis profile with `[analysis]` lines replaced.
fn thesis_with(replace: &[(&str, &str)]) -> Result<LoadedProfile, String> {
    let mut text = std::fs::read_to_string("profiles/thesis.toml").unwrap();
    for (from, to) in replace {
        assert!(text.contains(from), "{from}");
        text = text.replacen(from, to, 1);
    }
    LoadedProfile::from_str(&text, "test.toml", Path::new(".")).map_err(|e| e.to_string())
}

#[test]
fn scan_leg_takes_the_whole_leg_along_a_position_or_time_axis() {
    let lp = thesis_with(&[("window = [0.060, 0.0897]", "window = \"scan-leg\"")]).unwrap();
    assert_eq!(lp.profile.analysis.window, [0.0, 0.0897]);
    assert!(lp.profile.analysis.window_is_scan_leg);
    assert_eq!(lp.profile.analysis.points(), 300);

    // Along time: the leg's 8.97 cm at 1 cm/s, and the 0.3 s dwell.
    let lp = thesis_with(&[
        ("window = [0.060, 0.0897]", "window = \"scan-leg\""),
        ("axis = \"x_m\"", "axis = \"t_s\""),
        ("spacing = 0.0003", "spacing = 0.001"),
    ])
    .unwrap();
    let w = lp.profile.analysis.window;
    assert!(w[0] == 0.0 && (w[1] - 9.27).abs() < 1e-9, "{w:?}");
    // The window follows a sweep of the path's speed.
    let p = with_key(&lp.profile, "path.speed_m_per_s", &toml::Value::Float(0.02)).unwrap();
    assert!((p.analysis.window[1] - (0.0897 / 0.02 + 0.3)).abs() < 1e-9);
    // An explicit window does not.
    let lp2 = thesis_with(&[
        ("window = [0.060, 0.0897]", "window = [0.0, 4.0]"),
        ("axis = \"x_m\"", "axis = \"t_s\""),
        ("spacing = 0.0003", "spacing = 0.001"),
    ])
    .unwrap();
    let p = with_key(
        &lp2.profile,
        "path.speed_m_per_s",
        &toml::Value::Float(0.02),
    )
    .unwrap();
    assert_eq!(p.analysis.window, [0.0, 4.0]);
}

#[test]
fn the_shipped_recordings_analyse_over_the_whole_leg() {
    let files = recording::collect_files(&["recordings/thesis-sim/S3".into()]).unwrap();
    for (axis, spacing) in [("\"x_m\"", "0.0003"), ("\"t_s\"", "0.001")] {
        let lp = thesis_with(&[
            ("window = [0.060, 0.0897]", "window = \"scan-leg\""),
            ("axis = \"x_m\"", &format!("axis = {axis}")),
            ("spacing = 0.0003", &format!("spacing = {spacing}")),
        ])
        .unwrap();
        let mut fx = FeatureExtractor::try_new(&lp.profile.analysis).unwrap();
        for f in files.iter().take(5) {
            let rec = recording::read(f).unwrap();
            let t = rec.column(&lp.profile.analysis.axis).unwrap().to_vec();
            let y = rec.column("y_m").unwrap().to_vec();
            let feats = fx
                .features(&t, &y)
                .unwrap_or_else(|e| panic!("{axis} {}: {e}", f.display()));
            assert_eq!(feats.len(), 49);
            assert!(feats.iter().all(|v| v.is_finite()));
        }
    }
}

#[test]
fn a_window_that_is_neither_a_range_nor_scan_leg_is_refused() {
    for (w, expect) in [
        ("\"whole\"", "got \"whole\""),
        ("[0.06]", "two numbers"),
        ("[0.06, 0.2]", "window = \"scan-leg\" takes all of it"),
        ("[0.07, 0.06]", "0 <= start < end"),
    ] {
        let e = thesis_with(&[("window = [0.060, 0.0897]", &format!("window = {w}"))]).unwrap_err();
        assert!(e.contains(expect), "{w}: {e}");
    }
}

#[test]
fn no_taper_is_the_default_and_a_rectangular_window() {
    let lp =
        thesis_with(&[("detrend = \"mean\"", "detrend = \"mean\"\ntaper = \"none\"")]).unwrap();
    assert_eq!(lp.profile.analysis.taper, Taper::None);
    assert_eq!(
        lp.profile.analysis,
        LoadedProfile::thesis().profile.analysis
    );
    let lp =
        thesis_with(&[("detrend = \"mean\"", "detrend = \"mean\"\ntaper = \"hann\"")]).unwrap();
    assert_eq!(lp.profile.analysis.taper, Taper::Hann);
    let e = thesis_with(&[(
        "detrend = \"mean\"",
        "detrend = \"mean\"\ntaper = \"hamming\"",
    )])
    .unwrap_err();
    assert!(
        e.contains("hamming") && e.contains("none") && e.contains("hann"),
        "{e}"
    );

    // No taper: the features are |DFT| of the resampled, mean-removed
    // window itself; Hann changes them.
    let thesis = LoadedProfile::thesis().profile.analysis;
    let rec = recording::read(Path::new("recordings/thesis-sim/S2/S2_001.csv.gz")).unwrap();
    let (x, y) = (rec.column("x_m").unwrap(), rec.column("y_m").unwrap());
    let mut fx = FeatureExtractor::try_new(&thesis).unwrap();
    let feats = fx.features(x, y).unwrap().to_vec();
    let w = fx.resampled().to_vec();
    let m = w.iter().sum::<f64>() / w.len() as f64;
    for (k, f) in feats.iter().enumerate().map(|(i, f)| (i + 1, f)) {
        let (mut re, mut im) = (0.0, 0.0);
        for (j, v) in w.iter().enumerate() {
            let a = -2.0 * std::f64::consts::PI * (k * j) as f64 / w.len() as f64;
            re += (v - m) * a.cos();
            im += (v - m) * a.sin();
        }
        assert!((re.hypot(im) - f).abs() < 1e-9 * (1.0 + f), "bin {k}");
    }
    let mut hann = FeatureExtractor::try_new(&lp.profile.analysis).unwrap();
    assert_ne!(hann.features(x, y).unwrap().to_vec(), feats);
}
