//! Deterministic console states for the panel snapshots and the frame-time
//! benchmark: no clock, no randomness, no device. Not part of the console's
//! behaviour.

use std::path::{Path, PathBuf};

use crate::analysis::FeatureExtractor;
use crate::classify::{Neighbour, Prediction};
use crate::evaluate::{ClassRate, Report};
use crate::profile::LoadedProfile;
use crate::recording::Recording;
use crate::servo::stats::LoopStats;
use crate::servo::{Mode, Telemetry};

use super::app::{App, Source};
use super::dataset::ModelInfo;
use super::keymap::KeyMap;
use super::scan::{PredictionView, ScanView, analyse};

/// A synthetic S2-like scan: a 90 mm stroke over a 4.24 mm period.
pub fn scan_view(with_prediction: bool) -> ScanView {
    let mut v = scan_view_under(&LoadedProfile::thesis().profile.analysis);
    if with_prediction {
        v.prediction = Some(Ok(prediction()));
    }
    v
}

/// The synthetic scan of [`scan_view`] analysed under `analysis` (its
/// recording also has `fy_n`, the contact force over the corrugation).
pub fn scan_view_under(analysis: &crate::profile::Analysis) -> ScanView {
    let mut ex = FeatureExtractor::new(analysis);
    let n = 9000;
    let x: Vec<f64> = (0..n)
        .map(|i| -0.045 + 0.0897 * i as f64 / (n - 1) as f64)
        .collect();
    let y: Vec<f64> = x
        .iter()
        .map(|x| -0.0048 + 0.0004 * ((x + 0.045) * 2.0 * std::f64::consts::PI / 0.00424).sin())
        .collect();
    let t: Vec<f64> = (0..n).map(|i| i as f64 * 0.001).collect();
    let fy: Vec<f64> = x
        .iter()
        .map(|x| -0.216 + 0.05 * ((x + 0.045) * 2.0 * std::f64::consts::PI / 0.00424).cos())
        .collect();
    let rec = Recording {
        path: None,
        meta: vec![("label".into(), toml::Value::String("S2".into()))],
        columns: vec!["t_s".into(), "x_m".into(), "y_m".into(), "fy_n".into()],
        data: vec![t, x, y, fy],
        trailer_samples: Some(n),
        torn_last_row: false,
    };
    analyse(&rec, Path::new("ds/.unsaved/scan-001.csv"), &mut ex)
}

/// The prediction the panel snapshots show: S2 by 9 votes of 10.
fn prediction() -> PredictionView {
    PredictionView {
        prediction: Prediction {
            label: "S2".into(),
            votes: vec![
                ("S2".into(), 9),
                ("S3".into(), 1),
                ("S1".into(), 0),
                ("S4".into(), 0),
            ],
            neighbours: (0..10)
                .map(|i| Neighbour {
                    file: format!("ds/S2/S2_{:03}.csv", i + 1),
                    label: if i == 7 { "S3".into() } else { "S2".into() },
                    distance: 1.0e-3 * (1.0 + i as f64 * 0.1),
                })
                .collect(),
        },
        windows: None,
        left_out: false,
        incomplete: None,
    }
}

/// Telemetry at time `t_s` of a stroke along x over a corrugated surface.
pub fn telemetry(t_s: f64, mode: Mode) -> Telemetry {
    let x = -0.045 + 0.01 * t_s;
    let y = -0.0048 + 0.0004 * (t_s * 14.8).sin();
    Telemetry {
        tick: (t_s * 1000.0).round() as u64,
        t_s,
        pos_m: [x, y, -0.02],
        setpoint_m: [x, -0.0048, -0.02],
        force_n: [0.12, -0.216 + 0.1 * (t_s * 14.8).cos(), 0.0],
        mode,
        scanning: mode == Mode::Test,
        scan_progress: (t_s / 9.0).min(1.0),
        homed: true,
        speed_scale: 1.0,
        stats: LoopStats {
            ticks: (t_s * 1000.0) as u64,
            elapsed_s: t_s,
            rate_hz: 1000.0,
            period_error_p50_us: 4.0,
            period_error_p99_us: 21.0,
            period_error_max_us: 180.0,
            missed_deadlines: 2,
            longest_missed_streak: 1,
            dropped_telemetry: 0,
            dropped_events: 0,
            recorder_blocks_grown: 0,
            link: None,
        },
    }
}

/// Table 4.1's shape: four classes, ten test scans each.
pub fn report() -> Report {
    let labels: Vec<String> = ["S1", "S2", "S3", "S4"].map(String::from).to_vec();
    let confusion = vec![
        vec![10, 0, 0, 0],
        vec![0, 9, 1, 0],
        vec![0, 0, 8, 2],
        vec![0, 0, 1, 9],
    ];
    let per_class = labels
        .iter()
        .enumerate()
        .map(|(i, l)| ClassRate {
            label: l.clone(),
            n: 10,
            success_rate: confusion[i][i] as f64 / 10.0,
            error_rate: 1.0 - confusion[i][i] as f64 / 10.0,
        })
        .collect();
    Report {
        labels,
        confusion,
        accuracy: 36.0 / 40.0,
        per_class,
        train: vec![],
        test: vec![],
        predictions: vec![],
    }
}

/// A console mid-session: a stroke 4.5 s in, the last scan predicted, a
/// dataset with a model and an evaluation.
pub fn app(width: u16, height: u16) -> App {
    let lp = LoadedProfile::thesis();
    let mut app = App::new(
        lp,
        KeyMap::default(),
        Source::Live {
            backend: "sim".into(),
        },
        PathBuf::from("recordings/session-test"),
    );
    app.mounted = Some("S2".into());
    app.label = "S2".into();
    for i in 0..=4500 {
        app.on_telemetry(&telemetry(i as f64 * 0.001, Mode::Test));
    }
    app.scan_running = true;
    app.last_scan = Some(scan_view(true));
    app.dataset.counts = vec![
        ("S1".into(), 30),
        ("S2".into(), 31),
        ("S3".into(), 30),
        ("S4".into(), 30),
    ];
    app.dataset.unsaved = 1;
    app.dataset.model = Some(ModelInfo {
        examples: 121,
        labels: vec!["S1".into(), "S2".into(), "S3".into(), "S4".into()],
        k: 10,
        file: None,
        ..ModelInfo::default()
    });
    app.dataset.report = Some(report());
    app.info("scan complete: p predicts, w stores it");
    app.resize(width, height);
    app
}
