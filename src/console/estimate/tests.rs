//! The live estimate through the app, as the console's loop drives it: a
//! stored thesis scan replayed as the servo's telemetry, drained a frame's
//! worth at a time (33 ticks), then the file coming back. Deterministic: no
//! clock, no device.

use std::path::{Path, PathBuf};

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;

use super::source;
use crate::analysis::FeatureExtractor;
use crate::classify::Model;
use crate::console::app::{App, Source};
use crate::console::fixtures;
use crate::console::keymap::KeyMap;
use crate::console::panels::{Panel, render_panel};
use crate::console::scan::analyse;
use crate::dataset;
use crate::profile::{LoadedProfile, Windows};
use crate::recording::{self, Recording};
use crate::servo::{Mode, Telemetry};

/// Ticks a frame drains at 1 kHz and 30 frames a second.
const TICKS_PER_FRAME: usize = 33;

/// The thesis profile cutting its 29.7 mm window into four 14.7 mm
/// sub-windows every 5 mm (24 bins each).
fn windowed() -> LoadedProfile {
    let mut lp = LoadedProfile::thesis();
    lp.profile.analysis.bins = [1, 24];
    lp.profile.analysis.windows = Some(Windows {
        length: 0.0147,
        hop: 0.005,
    });
    lp
}

fn thesis_sim() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("recordings/thesis-sim");
    dataset::find(&[dir]).unwrap()
}

/// A model of every shipped thesis scan but those `keep` says no to.
fn model(lp: &LoadedProfile, keep: impl Fn(&Path) -> bool) -> Model {
    let a = &lp.profile.analysis;
    let files: Vec<PathBuf> = thesis_sim().into_iter().filter(|f| keep(f)).collect();
    let loaded = dataset::load(&files, a, dataset::Options::default(), &|| {}).unwrap();
    Model::train(
        "windowed",
        a,
        &lp.profile.classifier,
        loaded.into_examples(),
    )
    .unwrap()
}

/// The recording's samples as the servo's telemetry of its scan, on a loop
/// clock that started 12.5 s before the scan.
fn telemetry_of(rec: &Recording) -> Vec<Telemetry> {
    let col = |c: &str| rec.column(c).unwrap();
    let (t, x, y, z) = (col("t_s"), col("x_m"), col("y_m"), col("z_m"));
    let (fx, fy, fz) = (col("fx_n"), col("fy_n"), col("fz_n"));
    (0..rec.len())
        .map(|i| {
            let mut f = fixtures::telemetry(12.5 + t[i], Mode::Test);
            f.pos_m = [x[i], y[i], z[i]];
            f.force_n = [fx[i], fy[i], fz[i]];
            f.scanning = true;
            f
        })
        .collect()
}

fn app_with(lp: &LoadedProfile, model: Model) -> App {
    let mut app = App::new(
        lp.clone(),
        KeyMap::default(),
        Source::Live {
            backend: "sim".into(),
        },
        PathBuf::from("recordings/session-test"),
    );
    app.model = Some(model);
    app.scan_running = true;
    app
}

fn prediction_panel(app: &App) -> String {
    let area = Rect::new(0, 0, 64, 11);
    let mut buf = Buffer::empty(area);
    render_panel(Panel::Prediction, app, area, &mut buf);
    let a = buf.area;
    let mut out = String::new();
    for y in a.y..a.bottom() {
        let line: String = (a.x..a.right()).map(|x| buf[(x, y)].symbol()).collect();
        out.push_str(line.trim_end());
        out.push('\n');
    }
    out
}

/// The scan's end as the servo reports it: the first frame not scanning.
fn ended(app: &mut App, last: &Telemetry) {
    let mut f = *last;
    f.t_s += 0.001;
    f.scanning = false;
    f.mode = Mode::Manual;
    app.on_telemetry(&f);
    app.update_estimate();
}

#[test]
fn the_prediction_panel_follows_the_scan_window_by_window_and_ends_as_classify_says() {
    let lp = windowed();
    let held = |f: &Path| f.to_string_lossy().contains("_010.");
    let model = model(&lp, |f| !held(f));
    let file = thesis_sim()
        .into_iter()
        .find(|f| held(f) && f.to_string_lossy().contains("S2"))
        .unwrap();
    let rec = recording::read(&file).unwrap();
    let frames = telemetry_of(&rec);
    let mut app = app_with(&lp, model.clone());

    let mut seen = Vec::new();
    let mut mid = None;
    for chunk in frames.chunks(TICKS_PER_FRAME) {
        for f in chunk {
            app.on_telemetry(f);
        }
        app.update_estimate();
        let e = app
            .estimate
            .as_ref()
            .expect("a windowed model follows the scan");
        assert!(e.running && e.error.is_none(), "{:?}", e.error);
        if seen.last() != Some(&e.completed()) {
            seen.push(e.completed());
        }
        if e.completed() == 2 && mid.is_none() {
            mid = Some(prediction_panel(&app));
        }
    }
    assert_eq!(app.estimate.as_ref().unwrap().samples(), rec.len());
    // Window by window while the stroke runs: 0, 1, 2, 3 (the last ends
    // with the window, at the scan's very end).
    assert!(seen.starts_with(&[0, 1, 2, 3]), "{seen:?}");
    let mid = mid.unwrap();
    assert!(mid.contains("2 of 4 windows analysed"), "{mid}");
    insta::assert_snapshot!("live_estimate_mid_scan", mid);

    // What `classify` says of the stored recording.
    let mut ex = FeatureExtractor::new(&model.analysis);
    let classify = model
        .classify_windows(&dataset::window_features_of(&rec, &file, &mut ex).unwrap())
        .unwrap();

    ended(&mut app, frames.last().unwrap());
    let e = app.estimate.as_ref().unwrap();
    assert!(!e.running);
    assert_eq!(e.completed(), 4, "every sub-window once the stroke is over");
    // This telemetry carried the stored values exactly: the live vote over
    // all four is classify's already.
    assert_eq!(e.current.as_ref(), Some(&classify));
    let waiting = prediction_panel(&app);
    assert!(
        waiting.contains("stored recording's vote follows"),
        "{waiting}"
    );
    assert!(waiting.contains("4 of 4 windows analysed"), "{waiting}");

    // The file comes back: the final prediction is the stored recording's,
    // by the path `classify` takes.
    let mut ex = FeatureExtractor::new(&lp.profile.analysis);
    let view = analyse(&rec, &file, &mut ex);
    assert!(app.on_scan_saved(view).is_empty());
    assert!(app.estimate.is_none());
    let shown = app
        .last_scan
        .as_ref()
        .unwrap()
        .prediction
        .clone()
        .unwrap()
        .unwrap();
    assert!(!shown.left_out);
    assert_eq!(shown.windows.as_ref(), Some(&classify));
    assert_eq!(shown.prediction.label, classify.label);
    assert!(
        app.status
            .text
            .contains(&format!("predicted {}", classify.label)),
        "{}",
        app.status.text
    );
    let fin = prediction_panel(&app);
    assert!(
        fin.contains("Predicted ") && fin.contains("recorded as S2"),
        "{fin}"
    );
    insta::assert_snapshot!("live_estimate_final", fin);
}

#[test]
fn without_sub_windows_or_without_a_model_no_estimate_is_kept() {
    let thesis = LoadedProfile::thesis();
    let file = thesis_sim().into_iter().next().unwrap();
    let frames = telemetry_of(&recording::read(&file).unwrap());
    // A model without `windows`: Predict as before, nothing live.
    let plain = model(&thesis, |f| f != file);
    let mut app = app_with(&thesis, plain.clone());
    for f in &frames[..500] {
        app.on_telemetry(f);
    }
    app.update_estimate();
    assert!(app.estimate.is_none());
    let s = prediction_panel(&app);
    assert!(s.contains("no scan yet"), "{s}");
    // No model at all.
    let mut app = app_with(&windowed(), plain);
    app.model = None;
    for f in &frames[..500] {
        app.on_telemetry(f);
    }
    app.update_estimate();
    assert!(app.estimate.is_none());
}

#[test]
fn a_column_the_telemetry_lacks_is_named_and_the_scan_goes_on() {
    let mut lp = windowed();
    let m = model(&lp, |f| f.to_string_lossy().contains("_00"));
    let mut m2 = m.clone();
    m2.analysis.channel = "pac".into();
    lp.profile.analysis.channel = "pac".into();
    let mut app = app_with(&lp, m2);
    let file = thesis_sim().into_iter().next().unwrap();
    let frames = telemetry_of(&recording::read(&file).unwrap());
    for f in &frames[..100] {
        app.on_telemetry(f);
    }
    app.update_estimate();
    let e = app.estimate.as_ref().unwrap();
    assert_eq!(e.samples(), 0);
    let s = prediction_panel(&app);
    assert!(
        s.contains("no live estimate: the analysis reads pac, which the device's")
            && s.contains("telemetry does not carry"),
        "{s}"
    );
    assert_eq!(source("y_m"), Some(super::Source::Position(1)));
}
