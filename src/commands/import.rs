//! `hapticlab import`: the flags, then the engine's conversion
//! ([`crate::import`]) with a progress bar, and the recordings written.

use std::path::PathBuf;

use clap::Args;
use indicatif::ProgressBar;

use crate::import::{Report, Request};
use crate::support::Failure;

#[derive(Debug, Args, Clone)]
pub struct ImportArgs {
    /// CSV, text, WAV, NumPy (.npy, .npz) or MATLAB v5 (.mat) files to import (the format is taken from the extension).
    #[arg(required = true, value_name = "FILE")]
    pub files: Vec<PathBuf>,
    /// Output folder; recordings go to OUT/<label>/<file stem>.csv.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// CSV: the column holding each row's time in seconds.
    #[arg(long, value_name = "NAME", conflicts_with = "rate")]
    pub time_column: Option<String>,
    /// The sampling rate in Hz, from 0.001 to 1e15 (CSV without a time column, headerless
    /// text, .npy, .npz and .mat; WAV files carry their own).
    #[arg(long, value_name = "HZ", allow_negative_numbers = true)]
    pub rate: Option<f64>,
    /// CSV: the channel columns, comma-separated (default: every column but the time and label columns).
    #[arg(long, value_name = "A,B,…", value_delimiter = ',')]
    pub channels: Vec<String>,
    /// Names of the recorded channels (default: the CSV column names, or ch1, ch2, … for WAV and bursts).
    #[arg(long, value_name = "A,B,…", value_delimiter = ',')]
    pub names: Vec<String>,
    /// CSV: samples of each channel per row (the columns of a channel consecutive).
    #[arg(long, default_value_t = 1, value_name = "N")]
    pub burst: usize,
    /// The texture's label.
    #[arg(long, value_name = "LABEL", conflicts_with = "label_column")]
    pub label: Option<String>,
    /// CSV: the column holding the label (one value per file).
    #[arg(long, value_name = "NAME")]
    pub label_column: Option<String>,
    /// Extra metadata, e.g. --meta session=3 --meta rig=\"bench A\".
    #[arg(long, value_name = "KEY=VALUE")]
    pub meta: Vec<String>,
    /// CSV field separator (default: `,`, or `;` or a tab when the header has one and no comma).
    #[arg(long, value_name = "CHAR")]
    pub delimiter: Option<char>,
    /// Replace the recordings already at the names this import writes
    /// (OUT/<label>/<stem>.csv or .csv.gz, the other of the two removed);
    /// without it a name taken is refused and nothing is imported. An
    /// earlier import's recordings of the same inputs cut another way
    /// (<stem>.csv beside --split's <stem>-segNNN, or trials this cut does
    /// not write again) are removed too, so each input is cut one way.
    #[arg(long)]
    pub force: bool,
    /// Compress each recording to OUT/<label>/<file stem>.csv.gz (gzip -9).
    #[arg(long)]
    pub gzip: bool,
    /// Cut each input into consecutive trials this many seconds long, at
    /// least 16 samples (<stem>-seg001.csv, …, in time order), for one long
    /// recording per material.
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    pub split: Option<f64>,
    /// With --split: seconds from one trial's start to the next, at least a
    /// tenth of the trial's length (default: the length, no overlap).
    #[arg(
        long,
        value_name = "SECONDS",
        requires = "split",
        allow_negative_numbers = true
    )]
    pub split_hop: Option<f64>,
    /// Files converted at once (default: the number of cores; 0 means the same).
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// Begin each recording's name with the name of the folder above its
    /// input's own, for inputs of one name in several session folders
    /// (days/day1/felt/trial1.txt → OUT/felt/day1-trial1.csv).
    #[arg(long)]
    pub prefix_parent: bool,
}

impl From<ImportArgs> for Request {
    fn from(a: ImportArgs) -> Request {
        Request {
            files: a.files,
            out: a.out,
            time_column: a.time_column,
            rate: a.rate,
            channels: a.channels,
            names: a.names,
            burst: a.burst,
            label: a.label,
            label_column: a.label_column,
            meta: a.meta,
            delimiter: a.delimiter,
            force: a.force,
            gzip: a.gzip,
            split: a.split,
            split_hop: a.split_hop,
            threads: a.threads,
            prefix_parent: a.prefix_parent,
        }
    }
}

/// Warnings on stderr, a bar on a terminal (hidden when piped).
struct Bar(ProgressBar);

impl Report for Bar {
    fn warn(&self, message: &str) {
        self.0.suspend(|| crate::errln!("{message}"));
    }
    fn file_done(&self) {
        self.0.inc(1);
    }
}

pub fn run(args: ImportArgs) -> Result<(), Failure> {
    let request = Request::from(args);
    let bar = Bar(crate::support::progress_bar(
        request.files.len() as u64,
        "importing",
    ));
    let written = crate::import::run(&request, &bar);
    bar.0.finish_and_clear();
    let written = written?;
    for p in &written {
        crate::outln!("{}", p.display());
    }
    crate::errln!("imported {} recording(s)", written.len());
    Ok(())
}
