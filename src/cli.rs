//! The command line (clap derive): what each command takes, with an example.

use std::path::PathBuf;

use clap::{Args, Parser, Subcommand};

#[derive(Debug, Parser)]
#[command(
    name = "hapticlab",
    version,
    about = "Haptic texture classification with a Novint Falcon (or its simulation)",
    long_about = "Haptic texture classification with a Novint Falcon (or its physical simulation): \
                  stroke a texture along a waypoint path, record the probe's trace, and name the \
                  texture from its Fourier spectrum with k-NN.\n\n\
                  Without a command, hapticlab opens the lab console on the built-in thesis profile \
                  and the simulated Falcon.",
    after_help = "Examples:\n  hapticlab simulate --out recordings/my-sim\n  hapticlab evaluate recordings/thesis-sim\n  hapticlab check profiles/thesis.toml"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
}

#[derive(Debug, Args, Clone)]
pub struct ProfileArg {
    /// Experiment profile (TOML); `thesis` names the built-in thesis profile.
    #[arg(long, short = 'p', default_value = "thesis", value_name = "PROFILE")]
    pub profile: PathBuf,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Open the lab console (live position, force, traces, spectrum, prediction).
    #[command(
        after_help = "Example:\n  hapticlab console --profile profiles/thesis.toml --dataset recordings/session1"
    )]
    Console {
        #[command(flatten)]
        profile: ProfileArg,
        /// Folder where stored scans go, one subfolder per label.
        #[arg(long, value_name = "DIR")]
        dataset: Option<PathBuf>,
    },
    /// Simulate a dataset in virtual time: N scans of every texture in the profile.
    #[command(
        after_help = "Example:\n  hapticlab simulate --out recordings/my-sim --per-class 30 --seed 7"
    )]
    Simulate {
        #[command(flatten)]
        profile: ProfileArg,
        /// Output folder; scans go to OUT/<label>/<label>_NNN.csv.
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// Scans per texture.
        #[arg(long, default_value_t = 30, value_name = "N")]
        per_class: usize,
        /// Dataset seed (default: the profile's simulator.seed).
        #[arg(long, value_name = "S")]
        seed: Option<u64>,
        /// Worker threads (default: the number of cores).
        #[arg(long, value_name = "N")]
        threads: Option<usize>,
        /// Compress each recording (Zopfli gzip, about a second per recording) to OUT/<label>/<label>_NNN.csv.gz.
        #[arg(long)]
        gzip: bool,
        /// Replace recordings already in OUT under the same names (by default that is an error).
        #[arg(long)]
        overwrite: bool,
        /// Print the result as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Acquire live scans in real time on the profile's device; prints loop statistics per scan.
    #[command(
        after_help = "Example:\n  hapticlab scan --label S2 --count 3 --out recordings/session1"
    )]
    Scan {
        #[command(flatten)]
        profile: ProfileArg,
        /// The texture's label; scans go to OUT/<label>/.
        #[arg(long, value_name = "LABEL")]
        label: String,
        /// Number of scans.
        #[arg(long, default_value_t = 1, value_name = "N")]
        count: usize,
        #[arg(long, default_value = "recordings", value_name = "DIR")]
        out: PathBuf,
        /// Simulator only: the texture under the probe (default: the label).
        #[arg(long, value_name = "LABEL")]
        texture: Option<String>,
        /// Simulator only: the seed.
        #[arg(long, value_name = "S")]
        seed: Option<u64>,
    },
    /// Compute the feature vector (spectrum bins) of each recording.
    #[command(
        after_help = "Example:\n  hapticlab features recordings/thesis-sim --out features.csv"
    )]
    Features {
        #[command(flatten)]
        profile: ProfileArg,
        /// Recordings or folders of recordings.
        #[arg(required = true, value_name = "PATH")]
        paths: Vec<PathBuf>,
        /// Write `file,label,f1,…,fN` rows here instead of standard output.
        #[arg(long, value_name = "FILE")]
        out: Option<PathBuf>,
    },
    /// Train a k-NN model on recordings and save it.
    #[command(
        after_help = "Example:\n  hapticlab train recordings/thesis-sim --out thesis.model.json"
    )]
    Train {
        #[command(flatten)]
        profile: ProfileArg,
        #[arg(required = true, value_name = "PATH")]
        paths: Vec<PathBuf>,
        /// Model file to write (JSON).
        #[arg(long, value_name = "MODEL")]
        out: PathBuf,
    },
    /// Classify recordings with a trained model.
    #[command(
        after_help = "Example:\n  hapticlab classify --model thesis.model.json recordings/thesis-sim/S3/S3_025.csv"
    )]
    Classify {
        /// The profile whose analysis settings the model must have been trained under.
        #[command(flatten)]
        profile: ProfileArg,
        #[arg(long, value_name = "MODEL")]
        model: PathBuf,
        #[arg(required = true, value_name = "FILE")]
        files: Vec<PathBuf>,
        /// Print JSON for scripts.
        #[arg(long)]
        json: bool,
    },
    /// Train and test on a split of the recordings; print the confusion matrix (Table 4.1).
    #[command(
        after_help = "Examples:\n  hapticlab evaluate recordings/thesis-sim --json > report.json\n  hapticlab evaluate recordings/thesis-sim --folds 10 --seed 1\n  hapticlab evaluate recordings/lab --folds 5 --group-by session\n  hapticlab evaluate recordings/thesis-sim --folds 10 --sweep k=1..15\n  hapticlab evaluate --profile thesis --simulate --folds 5 --sweep controller.stiffness_n_per_m[1]=90..540:90"
    )]
    Evaluate {
        #[command(flatten)]
        profile: ProfileArg,
        /// Recordings or folders of recordings (none with --simulate).
        #[arg(
            required_unless_present = "simulate",
            conflicts_with = "simulate",
            value_name = "PATH"
        )]
        paths: Vec<PathBuf>,
        /// Shuffle each class with this seed before the split (default: file-name order).
        #[arg(long, value_name = "S")]
        shuffle_seed: Option<u64>,
        /// Print JSON for scripts.
        #[arg(long)]
        json: bool,
        #[command(flatten)]
        validation: crate::study::ValidationArgs,
    },
    /// Play recordings back through the console's dashboard (1×, 4×, 16×, single steps).
    #[command(
        after_help = "Keys: ↑/↓ recording, space pause, +/- speed, . step, ← restart, p predict, q quit.\n\nExample:\n  hapticlab replay recordings/thesis-sim\n  hapticlab replay recordings/thesis-sim/S2/S2_003.csv"
    )]
    Replay {
        #[command(flatten)]
        profile: ProfileArg,
        /// A recording, or a folder of recordings.
        #[arg(value_name = "FILE|DIR")]
        path: PathBuf,
        /// Recordings to train the model on (default: the folder replayed,
        /// or the folder above a recording's label folder).
        #[arg(long, value_name = "DIR")]
        dataset: Option<PathBuf>,
    },
    /// List attached Novint Falcons and HID triggers, and whether they can be opened.
    #[command(after_help = "Example:\n  hapticlab devices --profile profiles/thesis-falcon.toml")]
    Devices {
        #[command(flatten)]
        profile: ProfileArg,
    },
    /// Is this PC ready for the profile? Falcon USB access, firmware, real-time limits, terminal, dataset folder; the fix for each.
    #[command(
        after_help = "Exit code 0 when nothing failed, 1 when a check failed.\n\nExamples:\n  hapticlab doctor --profile profiles/thesis-falcon.toml --dataset recordings/session1\n  hapticlab doctor --json"
    )]
    Doctor {
        #[command(flatten)]
        profile: ProfileArg,
        /// The dataset folder to check (default: the console's, recordings/session-<date>).
        #[arg(long, value_name = "DIR")]
        dataset: Option<PathBuf>,
        /// Print JSON for scripts: {checks: [{name, status, finding, fix}], ok}.
        #[arg(long)]
        json: bool,
    },
    /// A dataset's health: recordings per class, incomplete files, feature spread, outliers by file.
    #[command(
        after_help = "Example:\n  hapticlab inspect recordings/thesis-sim\n  hapticlab inspect recordings/lab --threshold 4 --json"
    )]
    Inspect {
        #[command(flatten)]
        profile: ProfileArg,
        #[arg(required = true, value_name = "PATH")]
        paths: Vec<PathBuf>,
        /// Outlier threshold t: distance d to the class centroid beyond median + t x 1.4826 x MAD, on the scale d^(2/3).
        #[arg(long, default_value_t = 3.0, value_name = "T")]
        threshold: f64,
        /// Print JSON for scripts.
        #[arg(long)]
        json: bool,
    },
    /// Import CSV or WAV files from other rigs as recordings v1.
    #[command(
        after_help = "Examples:\n  hapticlab import rig/*.csv --out recordings/rig --time-column time --channels ax,ay --label S2 --meta session=3\n  hapticlab import raw/S1/a.csv --out recordings/rig --rate 3200 --channels a0,a1,a2,a3 --burst 4 --names acc\n  hapticlab import sound/S3/*.wav --out recordings/sound"
    )]
    Import(crate::import::ImportArgs),
    /// Draw figures (PNG or SVG): a trace and its spectrum, a confusion matrix, features per class, a sweep.
    #[command(
        after_help = "Examples:\n  hapticlab plot trace recordings/thesis-sim/S2/S2_001.csv.gz --out s2.png\n  hapticlab evaluate recordings/thesis-sim --folds 10 --json > r.json && hapticlab plot confusion r.json --out confusion.svg\n  hapticlab plot features recordings/thesis-sim --per-class 5 --out features.png\n  hapticlab evaluate recordings/thesis-sim --folds 5 --sweep k=1..15 --json > s.json && hapticlab plot sweep s.json --out sweep.png"
    )]
    Plot(crate::plot::PlotArgs),
    /// Check profiles: parse and validate every value.
    #[command(after_help = "Example:\n  hapticlab check profiles/*.toml")]
    Check {
        #[arg(required = true, value_name = "PROFILE")]
        profiles: Vec<PathBuf>,
    },
}
