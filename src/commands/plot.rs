//! `hapticlab plot`: figures for papers, as PNG or SVG (by the output's
//! extension), drawn with plotters and the bundled DejaVu Sans font (no
//! system fonts needed).
//!
//! - `trace FILE`: the recording's signal along the analysis axis with the
//!   analysis window shaded, and its spectrum with the kept bins marked
//!   (the thesis's Figs 4.5–4.8), a panel and a spectrum per channel;
//! - `confusion REPORT.json`: the confusion matrix of `evaluate --json` as a
//!   grey heat map with the counts written in, and the validation named;
//! - `features PATH… --per-class N`: the features of N recordings of each
//!   class, one panel per class (Fig 4.3); with `[analysis] windows`, each
//!   recording's first sub-window;
//! - `sweep SWEEP.json`: accuracy against the swept value from
//!   `evaluate --sweep … --json`, with the spread across folds; a two-key
//!   grid as a heat map (`plot/sweep.rs`).
//!
//! Everything is black, greys and line styles, so it prints in grey. This
//! module reads its inputs and writes only the figure.

use std::io::Write;
use std::path::{Path, PathBuf};

use clap::{Args, Subcommand};
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::analysis::FeatureExtractor;
use crate::dataset::{self, features_of, label_of};
use crate::profile::FeatureFamily;
use crate::recording;
use crate::support::{Existing, Failure, ProfileArg, load_profile};

mod sweep;
use sweep::SweepFigure;

static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans.ttf");
/// The font an SVG's text names: the bundled one, then the viewer's default.
pub const SVG_FONT: &str = "DejaVu Sans, sans-serif";

#[derive(Debug, Args, Clone)]
pub struct PlotArgs {
    #[command(subcommand)]
    pub figure: Figure,
    /// The figure to write: .png or .svg.
    #[arg(long, global = true, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Figure size in pixels, WIDTHxHEIGHT.
    #[arg(long, global = true, default_value = "1000x700", value_name = "WxH")]
    pub size: String,
    /// Replace --out when it exists (never a recording or an input).
    #[arg(long, global = true)]
    pub overwrite: bool,
}

#[derive(Debug, Subcommand, Clone)]
pub enum Figure {
    /// A recording's trace with its analysis window, and its spectrum (Figs 4.5–4.8).
    #[command(
        after_help = "The top half is the recorded trace against distance along the scan, with the profile's analysis window shaded and the resampled signal over it, one panel for each channel the profile analyses (`channel`, then `channels`); the bottom half is each channel's spectrum, with the bins the classifier is given in black (49 magnitudes under the thesis profile). The key is a line under the title.\n\nExamples:\n  hapticlab plot trace recordings/thesis-sim/S2/S2_001.csv.gz --out s2.png\n  hapticlab plot trace recordings/thesis-sim/S4/S4_001.csv.gz -p profiles/thesis.toml --out s4.svg"
    )]
    Trace {
        #[command(flatten)]
        profile: ProfileArg,
        /// The recording to draw (.csv or .csv.gz).
        #[arg(value_name = "FILE")]
        file: PathBuf,
    },
    /// The confusion matrix of `evaluate --json` as a heat map.
    #[command(
        after_help = "Rows are the true textures, columns what they were classified as; each cell holds its count and its share of the row. Draw again from the JSON without evaluating again.\n\nExamples:\n  hapticlab evaluate recordings/thesis-sim --folds 10 --json > r.json && hapticlab plot confusion r.json --out confusion.svg"
    )]
    Confusion {
        /// A report written by `hapticlab evaluate --json` (not a sweep's).
        #[arg(value_name = "REPORT.json")]
        report: PathBuf,
    },
    /// The features of N recordings per class (Fig 4.3); with `[analysis] windows`, each one's first window.
    #[command(
        after_help = "One panel per texture, one line per recording over the feature index: how alike a texture's recordings are, and how far apart the textures lie, before any classifier sees them.\n\nExamples:\n  hapticlab plot features recordings/thesis-sim --per-class 5 --out features.png\n  hapticlab plot features recordings/thesis-sim/S1 recordings/thesis-sim/S3 --per-class 3 --out s1-s3.svg"
    )]
    Features {
        #[command(flatten)]
        profile: ProfileArg,
        /// Recordings, or folders of them (one folder per texture, as `evaluate` reads them).
        #[arg(required = true, value_name = "PATH")]
        paths: Vec<PathBuf>,
        /// Recordings drawn per class, 1 to 1000.
        #[arg(long, default_value_t = 5, value_name = "N", value_parser = clap::value_parser!(u16).range(1..=1000))]
        per_class: u16,
    },
    /// Accuracy against the swept value from `evaluate --sweep … --json`; a two-key grid (two --sweep flags) as a heat map.
    #[command(
        after_help = "A one-key sweep is a line of the pooled accuracy against the value, with the spread across folds; a two-key grid is a heat map (rows the first --sweep's values, columns the second's, the best outlined, points not evaluated left white). Draw again from the JSON without evaluating again.\n\nExamples:\n  hapticlab evaluate recordings/thesis-sim --folds 5 --sweep k=1..15 --json > s.json && hapticlab plot sweep s.json --out sweep.png\n  hapticlab evaluate recordings/thesis-sim --folds 5 --sweep k=1,5,10 --sweep taper=none,hann --json > g.json && hapticlab plot sweep g.json --out grid.svg"
    )]
    Sweep {
        /// A report written by `hapticlab evaluate --sweep … --json`.
        #[arg(value_name = "SWEEP.json")]
        sweep: PathBuf,
    },
}

impl Figure {
    /// The files and folders the figure is drawn from.
    fn inputs(&self) -> Vec<PathBuf> {
        match self {
            Figure::Trace { profile, file } => vec![profile.profile.clone(), file.clone()],
            Figure::Confusion { report } => vec![report.clone()],
            Figure::Features { profile, paths, .. } => {
                let mut v = paths.clone();
                v.push(profile.profile.clone());
                v
            }
            Figure::Sweep { sweep } => vec![sweep.clone()],
        }
    }
}

fn bad(m: impl std::fmt::Display) -> Failure {
    Failure::BadInput(m.to_string())
}

fn fail<E: std::fmt::Debug>(e: E) -> Failure {
    Failure::Runtime(format!("cannot draw the figure: {e:?}"))
}

/// Axis unit of a column name, for labels.
fn unit_of(column: &str) -> (&'static str, f64) {
    if column.ends_with("_m") {
        ("mm", 1000.0)
    } else if column.ends_with("_s") {
        ("s", 1.0)
    } else if column.ends_with("_n") {
        ("N", 1.0)
    } else {
        ("", 1.0)
    }
}

/// The greys and dash patterns series cycle through.
const GREYS: [RGBColor; 4] = [
    RGBColor(0, 0, 0),
    RGBColor(90, 90, 90),
    RGBColor(150, 150, 150),
    RGBColor(200, 200, 200),
];

type Area<DB> = DrawingArea<DB, Shift>;

pub fn run(args: &PlotArgs) -> Result<(), Failure> {
    let _ = plotters::style::register_font("sans-serif", FontStyle::Normal, FONT);
    let out = args
        .out
        .clone()
        .ok_or_else(|| bad("--out FILE (.png or .svg) is required"))?;
    let (w, h) = args
        .size
        .split_once('x')
        .and_then(|(w, h)| Some((w.parse::<u32>().ok()?, h.parse::<u32>().ok()?)))
        .filter(|&(w, h)| (200..=10000).contains(&w) && (200..=10000).contains(&h))
        .ok_or_else(|| {
            bad(format!(
                "--size {:?}: expected WIDTHxHEIGHT, 200 to 10000 each",
                args.size
            ))
        })?;
    let ext = out
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    // Before any drawing: never over an input, a recording or a device.
    let (inputs, existing) = (args.figure.inputs(), Existing::replace_if(args.overwrite));
    crate::support::check_output(&out, &inputs, existing)?;
    let data = Data::load(&args.figure)?;
    let bytes = match ext.as_str() {
        "png" => {
            // Drawn in a scratch folder, then put in place by the one writer.
            let scratch = tempfile::tempdir()
                .map_err(|e| Failure::Runtime(format!("a scratch folder for the figure: {e}")))?;
            let png = scratch.path().join("figure.png");
            {
                let root = BitMapBackend::new(&png, (w, h)).into_drawing_area();
                data.draw(&root)?;
                root.present().map_err(fail)?;
            }
            std::fs::read(&png).map_err(|e| Failure::Runtime(format!("{}: {e}", png.display())))?
        }
        "svg" => {
            let mut svg = String::new();
            {
                let root = SVGBackend::with_string(&mut svg, (w, h)).into_drawing_area();
                data.draw(&root)?;
                root.present().map_err(fail)?;
            }
            // SVG text is drawn by the viewer: name the PNGs' bundled font
            // first, the viewer's sans-serif only as the fallback.
            svg.replace(
                "font-family=\"sans-serif\"",
                &format!("font-family=\"{SVG_FONT}\""),
            )
            .into_bytes()
        }
        _ => {
            return Err(bad(format!(
                "{}: the figure must end in .png or .svg",
                out.display()
            )));
        }
    };
    crate::support::write_atomically(&out, &inputs, existing, &bytes)?;
    crate::errln!("wrote {}", out.display());
    Ok(())
}

/// What a figure shows, loaded before any drawing: one type a figure.
enum Data {
    Trace(Trace),
    Confusion(Confusion),
    Features(Features),
    Sweep(SweepFigure),
}

/// A recording's signal with the analysis window, and its spectrum.
struct Trace {
    title: String,
    axis_name: String,
    axis: Vec<f64>,
    window: [f64; 2],
    /// The profile's `channel`, then each of its `channels`.
    channels: Vec<TraceChannel>,
    kept: [usize; 2],
    freq_unit: String,
    kind: String,
    /// The feature family: a spectrum's kept bins are the features; under
    /// the other families the spectrum is drawn grey, and the key says it
    /// is not the features.
    family: FeatureFamily,
}

/// One analysed channel of a trace: its recorded values, the points the
/// analysis resampled, and the spectrum it gives the classifier.
struct TraceChannel {
    name: String,
    signal: Vec<f64>,
    resampled: Vec<(f64, f64)>,
    spectrum: Vec<(f64, f64)>,
}

/// An evaluation's confusion matrix.
struct Confusion {
    labels: Vec<String>,
    confusion: Vec<Vec<f64>>,
    accuracy: f64,
    /// How the counts were made, as the report says it ("5-fold
    /// cross-validation, seed 0"; a holdout's sizes).
    validation: String,
}

/// A few recordings' features, class by class.
struct Features {
    classes: Vec<(String, Vec<Vec<f64>>)>,
    kind: String,
    /// The first feature's number, and what the features are (from the
    /// option that decides them: DFT bins, bands or cepstra).
    first_bin: usize,
    what: &'static str,
}

/// Where the features' axis starts and what it counts, as the option list
/// labels them.
fn feature_axis(a: &crate::profile::Analysis) -> (usize, &'static str) {
    use crate::profile::options::FeatureNames;
    match FeatureNames::of(a) {
        FeatureNames::Bins { .. } => (a.kept_bins()[0], "feature (DFT bin)"),
        FeatureNames::Bands { .. } => (0, "feature (band)"),
        FeatureNames::Cepstra { first } => (first, "feature (cepstral coefficient)"),
        FeatureNames::Points => (0, "feature (window point, for random kernels)"),
        FeatureNames::Quantiles => (0, "feature (interval quantile)"),
        FeatureNames::Hydra => (0, "feature (competing kernel's wins or losses)"),
    }
}

/// The style of axis descriptions and legends.
const LABELS: (&str, u32) = ("sans-serif", 18);

fn read_json(p: &Path) -> Result<serde_json::Value, Failure> {
    let bytes = crate::io::read_input(p).map_err(|e| {
        let m = format!("{}: {}", p.display(), crate::io::said(&e));
        // Missing, or not a regular file (a FIFO would block): the argument's fault.
        if crate::io::not_regular(&e) || e.kind() == std::io::ErrorKind::NotFound {
            bad(m)
        } else {
            Failure::Runtime(m)
        }
    })?;
    // Another encoding (UTF-16 from a Windows editor or PowerShell's `>`)
    // is the file's fault, as any other malformed input.
    let text = String::from_utf8(bytes).map_err(|_| {
        bad(format!(
            "{}: not UTF-8 JSON (saved in another encoding, UTF-16?): write it as UTF-8",
            p.display()
        ))
    })?;
    serde_json::from_str(&text).map_err(|e| bad(format!("{}: not JSON: {e}", p.display())))
}

impl Data {
    fn load(fig: &Figure) -> Result<Data, Failure> {
        match fig {
            Figure::Trace { profile, file } => {
                let lp = load_profile(profile)?;
                let a = &lp.profile.analysis;
                let rec = recording::read(file).map_err(bad)?;
                let axis_raw = rec.column(&a.axis).unwrap_or_default();
                // Distance along travel from the first sample, as the analysis sees it.
                let (o, l) = (axis_raw[0], axis_raw[axis_raw.len() - 1]);
                let s = if l >= o { 1.0 } else { -1.0 };
                let axis: Vec<f64> = axis_raw.iter().map(|x| s * (x - o)).collect();
                // Each channel analysed alone, as the analysis does it
                // before it puts their features side by side.
                let mut channels = Vec::new();
                for name in std::iter::once(&a.channel).chain(&a.channels) {
                    let one = crate::profile::Analysis {
                        channel: name.clone(),
                        channels: Vec::new(),
                        ..a.clone()
                    };
                    let mut fx = FeatureExtractor::new(&one);
                    features_of(&rec, file, &mut fx)?;
                    channels.push(TraceChannel {
                        name: name.clone(),
                        signal: rec.column(name).unwrap_or_default().to_vec(),
                        resampled: fx
                            .resampled()
                            .iter()
                            .enumerate()
                            .map(|(i, &v)| (fx.grid_position(i), v))
                            .collect(),
                        spectrum: fx
                            .spectrum()
                            .iter()
                            .enumerate()
                            .map(|(k, &v)| (fx.frequency(k), v))
                            .collect(),
                    });
                }
                Ok(Data::Trace(Trace {
                    title: format!("{} ({})", file.display(), label_of(&rec, file)?),
                    axis_name: a.axis.clone(),
                    axis,
                    window: a.window,
                    channels,
                    kept: a.kept_bins(),
                    freq_unit: a.frequency_unit().to_string(),
                    kind: format!("{:?}", a.spectrum).to_lowercase(),
                    family: a.features,
                }))
            }
            Figure::Confusion { report } => {
                let v = read_json(report)?;
                let labels: Vec<String> =
                    serde_json::from_value(v["labels"].clone()).map_err(|_| {
                        bad(format!(
                            "{}: no `labels` (expected `evaluate --json` output)",
                            report.display()
                        ))
                    })?;
                let confusion: Vec<Vec<f64>> = serde_json::from_value(v["confusion"].clone())
                    .map_err(|_| bad(format!("{}: no `confusion` matrix", report.display())))?;
                let accuracy = v["accuracy"].as_f64().unwrap_or(f64::NAN);
                // Checked before it is drawn: a figure never shows a report
                // that does not hold together.
                if let Some(fault) = crate::evaluate::confusion_fault(&labels, &confusion, accuracy)
                {
                    return Err(bad(format!(
                        "{}: {fault}; nothing was drawn (expected `evaluate --json` output)",
                        report.display()
                    )));
                }
                let files = |key: &str| v[key].as_array().map_or(0, Vec::len);
                let validation = match v["method"].as_str() {
                    Some(method) => method.to_string(),
                    None => format!(
                        "holdout: {} training, {} test recording(s)",
                        files("train"),
                        files("test")
                    ),
                };
                Ok(Data::Confusion(Confusion {
                    labels,
                    confusion,
                    accuracy,
                    validation,
                }))
            }
            Figure::Features {
                profile,
                paths,
                per_class,
            } => {
                let lp = load_profile(profile)?;
                let files = dataset::find(paths)?;
                let loaded = dataset::load(
                    &files,
                    &lp.profile.analysis,
                    dataset::Options::default(),
                    &|| {},
                )?;
                for skipped in &loaded.skipped {
                    let _ = writeln!(std::io::stderr(), "warning: {skipped}");
                }
                let mut classes: Vec<(String, Vec<Vec<f64>>)> = Vec::new();
                // With `[analysis] windows`, each recording's first
                // sub-window stands for it (one line per recording).
                for e in loaded
                    .entries
                    .into_iter()
                    .filter(|e| e.window.unwrap_or(0) == 0)
                {
                    let i = match classes.iter().position(|(l, _)| *l == e.label) {
                        Some(i) => i,
                        None => {
                            classes.push((e.label, Vec::new()));
                            classes.len() - 1
                        }
                    };
                    if classes[i].1.len() < usize::from(*per_class) {
                        classes[i].1.push(e.features);
                    }
                }
                if classes.is_empty() {
                    return Err(bad("no complete recordings to plot"));
                }
                classes.sort_by(|a, b| a.0.cmp(&b.0));
                let (first_bin, what) = feature_axis(&lp.profile.analysis);
                Ok(Data::Features(Features {
                    classes,
                    kind: format!("{:?}", lp.profile.analysis.spectrum).to_lowercase(),
                    first_bin,
                    what,
                }))
            }
            Figure::Sweep { sweep } => Ok(Data::Sweep(SweepFigure::load(sweep)?)),
        }
    }

    fn draw<DB: DrawingBackend>(&self, root: &Area<DB>) -> Result<(), Failure>
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE).map_err(fail)?;
        match self {
            Data::Trace(t) => t.draw(root),
            Data::Confusion(c) => c.draw(root),
            Data::Features(f) => f.draw(root),
            Data::Sweep(sweep) => sweep.draw(root),
        }
    }
}

/// The least and the greatest of the finite `values`; `None` when none is.
fn finite_range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    values.filter(|v| v.is_finite()).fold(None, |r, v| match r {
        None => Some((v, v)),
        Some((lo, hi)) => Some((v.min(lo), v.max(hi))),
    })
}

impl Trace {
    /// Each channel's signal over the analysis window above, one panel a
    /// channel; their spectra below, side by side (the thesis's Figs
    /// 4.5–4.8). The key is a line under the title, so it never covers
    /// the data.
    fn draw<DB: DrawingBackend>(&self, root: &Area<DB>) -> Result<(), Failure>
    where
        DB::ErrorType: 'static,
    {
        let root = root.titled(&self.title, ("sans-serif", 20)).map_err(fail)?;
        let spectra = self.channels.iter().any(|c| !c.spectrum.is_empty());
        let lines = "grey: recorded · black: resampled · shaded: analysis window";
        let family = match self.family {
            _ if !spectra => None,
            FeatureFamily::Spectrum => Some("spectrum bars: black kept as features, grey left out"),
            FeatureFamily::Kernels => Some(
                "the features are random kernels of the black line: the spectrum (grey) is not used",
            ),
            FeatureFamily::Quantiles => Some(
                "the features are interval quantiles of the black line: the spectrum (grey) is not used",
            ),
            FeatureFamily::Hydra => Some(
                "the features are competing kernels of the black line: the spectrum (grey) is not used",
            ),
        };
        let mut root = root.titled(lines, LABELS).map_err(fail)?;
        if let Some(family) = family {
            root = root.titled(family, LABELS).map_err(fail)?;
        }
        let (top, bottom) = if spectra {
            let (top, bottom) = root.split_vertically(root.dim_in_pixel().1 / 2);
            (top, Some(bottom))
        } else {
            (root, None)
        };
        let n = self.channels.len().max(1);
        let rows = top.split_evenly((n, 1));
        for (i, (area, channel)) in rows.iter().zip(&self.channels).enumerate() {
            self.draw_signal(area, channel, i + 1 == n)?;
        }
        if let Some(bottom) = bottom {
            let columns = bottom.split_evenly((1, n));
            for (area, channel) in columns.iter().zip(&self.channels) {
                self.draw_spectrum(area, channel, n > 1)?;
            }
        }
        Ok(())
    }

    /// One channel's recorded and resampled signal, the window shaded;
    /// the distance axis described under the last panel only.
    fn draw_signal<DB: DrawingBackend>(
        &self,
        area: &Area<DB>,
        channel: &TraceChannel,
        last: bool,
    ) -> Result<(), Failure>
    where
        DB::ErrorType: 'static,
    {
        let (axis_name, axis, window) = (&self.axis_name, &self.axis, &self.window);
        let TraceChannel {
            name,
            signal,
            resampled,
            ..
        } = channel;
        let (xu, xs) = unit_of(axis_name);
        let (yu, ys) = unit_of(name);
        let xmax = axis.iter().fold(f64::MIN, |m, v| m.max(*v)) * xs;
        let xmax = xmax.max(window[1] * xs);
        // Every value drawn is inside the axes: the range holds the
        // recorded and the resampled values (finite ones; a gap is a gap).
        let (ymin, ymax) = finite_range(
            signal
                .iter()
                .chain(resampled.iter().map(|(_, v)| v))
                .map(|v| v * ys),
        )
        .unwrap_or((-1.0, 1.0));
        let pad = (ymax - ymin).max(1e-12) * 0.05;
        let (lo, hi) = (ymin - pad, ymax + pad);
        let mut c = ChartBuilder::on(area)
            .margin(8)
            .x_label_area_size(if last { 45 } else { 25 })
            .y_label_area_size(70)
            .build_cartesian_2d(0.0..xmax, lo..hi)
            .map_err(fail)?;
        let x_desc = if last {
            format!("distance along {axis_name} from the scan's start ({xu})").replace(" ()", "")
        } else {
            String::new()
        };
        let rows = self.channels.len().max(1);
        c.configure_mesh()
            .disable_mesh()
            .y_labels((10 / rows).max(3))
            .x_desc(x_desc)
            .y_desc(if yu.is_empty() {
                name.clone()
            } else {
                format!("{name} ({yu})")
            })
            .label_style(LABELS)
            .draw()
            .map_err(fail)?;
        c.draw_series(std::iter::once(Rectangle::new(
            [(window[0] * xs, lo), (window[1] * xs, hi)],
            RGBColor(225, 225, 225).filled(),
        )))
        .map_err(fail)?;
        // A line is broken where a value is missing, never drawn through it.
        let runs = |points: Vec<(f64, f64)>| {
            points
                .split(|(x, y)| !(x.is_finite() && y.is_finite()))
                .filter(|run| !run.is_empty())
                .map(<[(f64, f64)]>::to_vec)
                .collect::<Vec<_>>()
        };
        for run in runs(
            axis.iter()
                .zip(signal)
                .map(|(a, v)| (a * xs, v * ys))
                .collect(),
        ) {
            c.draw_series(LineSeries::new(run, GREYS[1].stroke_width(1)))
                .map_err(fail)?;
        }
        for run in runs(resampled.iter().map(|(a, v)| (a * xs, v * ys)).collect()) {
            c.draw_series(LineSeries::new(run, BLACK.stroke_width(2)))
                .map_err(fail)?;
        }
        Ok(())
    }

    /// One channel's spectrum, the bins kept black and the rest grey.
    fn draw_spectrum<DB: DrawingBackend>(
        &self,
        area: &Area<DB>,
        channel: &TraceChannel,
        named: bool,
    ) -> Result<(), Failure>
    where
        DB::ErrorType: 'static,
    {
        let (kept, freq_unit, kind) = (&self.kept, &self.freq_unit, &self.kind);
        let spectrum = &channel.spectrum;
        let fmax = spectrum.last().map_or(1.0, |p| p.0).max(1e-12);
        let (smin, smax) = finite_range(spectrum.iter().map(|(_, v)| *v)).unwrap_or((0.0, 1.0));
        let smin = smin.min(0.0);
        let mut c = ChartBuilder::on(area)
            .margin(8)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(
                0.0..fmax,
                smin..(smax + (smax - smin).abs().max(1e-30) * 0.05),
            )
            .map_err(fail)?;
        let y_desc = if named {
            format!("{}: {kind} spectrum", channel.name)
        } else {
            format!("{kind} spectrum")
        };
        let columns = self.channels.len().max(1);
        c.configure_mesh()
            .disable_mesh()
            .x_labels((10 / columns).max(3))
            .x_desc(format!("frequency ({freq_unit})"))
            .y_desc(y_desc)
            .label_style(LABELS)
            .draw()
            .map_err(fail)?;
        c.draw_series(
            spectrum
                .iter()
                .enumerate()
                .filter(|(_, (_, v))| v.is_finite())
                .map(|(k, &(f, v))| {
                    let inside = k >= kept[0] && k <= kept[1];
                    let style = if inside {
                        BLACK.filled()
                    } else {
                        GREYS[2].filled()
                    };
                    let w = fmax / spectrum.len() as f64 * 0.35;
                    Rectangle::new([(f - w, smin), (f + w, v)], style)
                }),
        )
        .map_err(fail)?;
        Ok(())
    }
}

impl Confusion {
    /// A grey heat map with the counts and shares written in.
    fn draw<DB: DrawingBackend>(&self, root: &Area<DB>) -> Result<(), Failure>
    where
        DB::ErrorType: 'static,
    {
        let Confusion {
            labels,
            confusion,
            accuracy,
            validation,
        } = self;
        let n = labels.len();
        let title = format!("Confusion matrix (accuracy {:.1} %)", 100.0 * accuracy);
        let root = root.titled(&title, ("sans-serif", 22)).map_err(fail)?;
        let root = root.titled(validation, LABELS).map_err(fail)?;
        let mut c = ChartBuilder::on(&root)
            .margin(20)
            .x_label_area_size(50)
            .y_label_area_size(80)
            .build_cartesian_2d(
                (0..n.saturating_sub(1)).into_segmented(),
                (0..n.saturating_sub(1)).into_segmented(),
            )
            .map_err(fail)?;
        let l2 = labels.clone();
        let l3 = labels.clone();
        c.configure_mesh()
            .disable_mesh()
            .x_labels(n + 1)
            .y_labels(n + 1)
            .x_label_formatter(&move |v| match v {
                SegmentValue::CenterOf(i) => l2.get(*i).cloned().unwrap_or_default(),
                _ => String::new(),
            })
            .y_label_formatter(&move |v| match v {
                SegmentValue::CenterOf(i) if *i < n => l3[n - 1 - *i].clone(),
                _ => String::new(),
            })
            .x_desc("classified as")
            .y_desc("true class")
            .label_style(LABELS)
            .draw()
            .map_err(fail)?;
        for (i, row) in confusion.iter().enumerate() {
            let total: f64 = row.iter().sum::<f64>().max(1.0);
            for (j, &v) in row.iter().enumerate() {
                let frac = v / total;
                let g = (255.0 * (1.0 - 0.85 * frac)) as u8;
                let y = n - 1 - i;
                c.draw_series(std::iter::once(Rectangle::new(
                    [
                        (SegmentValue::Exact(j), SegmentValue::Exact(y)),
                        (SegmentValue::Exact(j + 1), SegmentValue::Exact(y + 1)),
                    ],
                    RGBColor(g, g, g).filled(),
                )))
                .map_err(fail)?;
                let text_colour = if frac > 0.5 { WHITE } else { BLACK };
                let style = ("sans-serif", 20)
                    .into_font()
                    .color(&text_colour)
                    .pos(Pos::new(HPos::Center, VPos::Center));
                c.draw_series(std::iter::once(Text::new(
                    format!("{v:.0} ({:.0} %)", 100.0 * frac),
                    (SegmentValue::CenterOf(j), SegmentValue::CenterOf(y)),
                    style,
                )))
                .map_err(fail)?;
            }
        }
        Ok(())
    }
}

impl Features {
    /// One panel a class, a line a recording (Fig 4.3).
    fn draw<DB: DrawingBackend>(&self, root: &Area<DB>) -> Result<(), Failure>
    where
        DB::ErrorType: 'static,
    {
        let Features {
            classes,
            kind,
            first_bin,
            what,
        } = self;
        let panels = root.split_evenly((classes.len().div_ceil(2), 2.min(classes.len())));
        let ymax = classes
            .iter()
            .flat_map(|(_, v)| v.iter().flatten())
            .fold(f64::MIN, |m, v| m.max(*v));
        let ymin = classes
            .iter()
            .flat_map(|(_, v)| v.iter().flatten())
            .fold(f64::MAX, |m, v| m.min(*v))
            .min(0.0);
        for ((label, rows), panel) in classes.iter().zip(panels.iter()) {
            let d = rows.first().map_or(1, Vec::len);
            let mut c = ChartBuilder::on(panel)
                .caption(
                    format!("{label}: {} recordings", rows.len()),
                    ("sans-serif", 18),
                )
                .margin(8)
                .x_label_area_size(40)
                .y_label_area_size(70)
                .build_cartesian_2d(
                    *first_bin as f64..(first_bin + d - 1).max(first_bin + 1) as f64,
                    ymin..ymax * 1.05,
                )
                .map_err(fail)?;
            c.configure_mesh()
                .disable_mesh()
                .x_desc(*what)
                .y_desc(format!("{kind} of the signal"))
                .label_style(("sans-serif", 14))
                .draw()
                .map_err(fail)?;
            for (i, r) in rows.iter().enumerate() {
                c.draw_series(LineSeries::new(
                    r.iter()
                        .enumerate()
                        .map(|(k, v)| ((first_bin + k) as f64, *v)),
                    GREYS[i % 3].stroke_width(1),
                ))
                .map_err(fail)?;
            }
        }
        Ok(())
    }
}
/// A swept key as an axis label: the unit its name ends with spelled out,
/// `controller.stiffness_n_per_m[1]` as `controller.stiffness_n_per_m[1] (N/m)`.
pub fn with_unit(key: &str) -> String {
    let field = key.split('[').next().unwrap_or(key);
    let unit = [
        ("_n_s_per_m", "N·s/m"),
        ("_n_per_m", "N/m"),
        ("_m_per_s", "m/s"),
        ("_hz", "Hz"),
        ("_kg", "kg"),
        ("_n", "N"),
        ("_m", "m"),
        ("_s", "s"),
        ("_us", "µs"),
    ]
    .iter()
    .find(|(suffix, _)| field.ends_with(suffix))
    .map(|(_, u)| *u);
    match unit {
        Some(u) => format!("{key} ({u})"),
        None => key.to_string(),
    }
}
