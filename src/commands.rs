//! The headless commands' dispatcher: [`Command`] (every command with its
//! arguments) and [`run`]. Each command is one file under `commands/`
//! holding its clap arguments and its `run`, which turns them into engine
//! calls and prints the result for people (or JSON for scripts); errors
//! come back as [`Failure`], which `main` maps to an exit code. What the
//! commands share (`Failure`, `--profile`, progress bars, finding
//! recordings) is in [`crate::support`], below every front end.

use clap::Subcommand;

use crate::support::Failure;

pub mod check;
pub mod classify;
pub mod completions;
pub mod console;
pub mod devices;
pub mod doctor;
pub mod evaluate;
pub mod features;
pub mod import;
pub mod inspect;
pub mod man;
pub mod plot;
pub mod profile;
pub mod replay;
pub mod scan;
pub mod simulate;
pub mod train;
pub mod tune;

/// Every command, each holding its arguments.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// Open the lab console (live position, force, traces, spectrum, prediction).
    #[command(
        after_help = "Example:\n  hapticlab console --profile profiles/thesis.toml --dataset recordings/session1"
    )]
    Console(console::ConsoleArgs),
    /// Simulate a dataset in virtual time: N scans of every texture in the profile.
    #[command(
        after_help = "Example:\n  hapticlab simulate --out recordings/my-sim --per-class 30 --seed 7"
    )]
    Simulate(simulate::SimulateArgs),
    /// Acquire live scans in real time on the profile's device; prints loop statistics per scan.
    #[command(
        after_help = "Example:\n  hapticlab scan --label S2 --count 3 --out recordings/session1"
    )]
    Scan(scan::ScanArgs),
    /// Compute the feature vector of each recording (the profile's features: spectrum bins, interval quantiles, kernels).
    #[command(
        after_help = "Example:\n  hapticlab features recordings/thesis-sim --out features.csv"
    )]
    Features(features::FeaturesArgs),
    /// Train the profile's classifier (k-NN, ridge or LDA) on recordings and save the model.
    #[command(
        after_help = "Example:\n  hapticlab train recordings/thesis-sim --out thesis.model.json"
    )]
    Train(train::TrainArgs),
    /// Classify recordings with a trained model.
    #[command(
        after_help = "Example:\n  hapticlab classify --model thesis.model.json recordings/thesis-sim/S3/S3_025.csv.gz"
    )]
    Classify(classify::ClassifyArgs),
    /// Train and test on a split of the recordings; print the confusion matrix (Table 4.1).
    #[command(
        after_help = "Examples:\n  hapticlab evaluate recordings/thesis-sim --json > report.json\n  hapticlab evaluate recordings/thesis-sim --folds 10 --seed 1\n  hapticlab evaluate recordings/lab --folds 5 --group-by session\n  hapticlab evaluate recordings/thesis-sim --folds 10 --sweep k=1..15\n  hapticlab evaluate recordings/thesis-sim --folds 5 --sweep spectrum=magnitude,welch   # welch: not evaluated, with the reason\n  hapticlab evaluate recordings/thesis-sim --folds 5 --sweep 'bins=[1,1],[1,2]' --sweep k=1,10   # a grid\n  hapticlab evaluate --profile thesis --simulate --folds 5 --sweep controller.stiffness_n_per_m[1]=90..540:90"
    )]
    Evaluate(evaluate::EvaluateArgs),
    /// Choose the analysis and classifier settings by nested validation; write them to a profile with the outer estimate.
    #[command(
        after_help = "Each setting is scored by 5-fold cross-validation inside the training part only; the best is tested once on what the profile's [evaluation] holds out (holdout: its test part; k-fold and leave-one-out: each outer fold tuned on its own training part). The accuracy reported is that outer estimate, never an inner score.\n\nExamples:\n  hapticlab tune rec/finger -p finger.toml --out finger-tuned.toml\n  hapticlab tune rec/sound -p sound.toml --out sound-tuned.toml --budget 480 --seed 3 --json"
    )]
    Tune(tune::TuneArgs),
    /// Play recordings back through the console's dashboard (1×, 4×, 16×, single steps).
    #[command(
        after_help = "Keys: ↑/↓ PgUp/PgDn Home/End recording, j jump to a label, W next wrong, f filter by label, space pause, +/- speed, . step, ← restart, p predict, ? all keys, q quit.\n\nExamples:\n  hapticlab replay recordings/thesis-sim\n  hapticlab replay recordings/thesis-sim/S2/S2_003.csv.gz"
    )]
    Replay(replay::ReplayArgs),
    /// List attached Novint Falcons and HID triggers, and whether they can be opened; --self-test checks a Falcon step by step.
    #[command(
        after_help = "With --self-test: open the profile's Falcon (loading its firmware if needed), cycle the LEDs, home, read the encoders while you move the grip, push it with 1 N pulses along each axis (asked first unless --yes) and check it moves the way it is pushed; a report to paste into an issue. Exit code 0 when every step passed, 1 when one did not, 2 for bad input.\n\nExamples:\n  hapticlab devices --profile profiles/thesis-falcon.toml\n  hapticlab devices --self-test --profile profiles/thesis-falcon.toml\n  hapticlab devices --self-test --profile profiles/thesis-emulator.toml --yes --json"
    )]
    Devices(devices::DevicesArgs),
    /// Is this PC ready for the profile? Falcon USB access, firmware, real-time limits, terminal, dataset folder; the fix for each.
    #[command(
        after_help = "Exit code 0 when nothing failed, 1 when a check failed.\n\nExamples:\n  hapticlab doctor --profile profiles/thesis-falcon.toml --dataset recordings/session1\n  hapticlab doctor --json"
    )]
    Doctor(doctor::DoctorArgs),
    /// A dataset's health: recordings per class, incomplete files, feature spread, outliers by file.
    #[command(
        after_help = "Example:\n  hapticlab inspect recordings/thesis-sim\n  hapticlab inspect recordings/lab --threshold 4 --json"
    )]
    Inspect(inspect::InspectArgs),
    /// Import other rigs' files (CSV, text, WAV, NumPy, MATLAB v5) as recordings v1.
    #[command(
        after_help = "Examples:\n  hapticlab import rig/*.csv --out recordings/rig --time-column time --channels ax,ay --label S2 --meta session=3\n  hapticlab import raw/S1/a.csv --out recordings/rig --rate 3200 --channels a0,a1,a2,a3 --burst 4 --names acc\n  hapticlab import sound/S3/*.wav --out recordings/sound"
    )]
    Import(import::ImportArgs),
    /// Draw figures (PNG or SVG): a trace and its spectrum, a confusion matrix, features per class, a sweep.
    #[command(
        after_help = "Examples:\n  hapticlab plot trace recordings/thesis-sim/S2/S2_001.csv.gz --out s2.png\n  hapticlab evaluate recordings/thesis-sim --folds 10 --json > r.json && hapticlab plot confusion r.json --out confusion.svg\n  hapticlab plot features recordings/thesis-sim --per-class 5 --out features.png\n  hapticlab evaluate recordings/thesis-sim --folds 5 --sweep k=1..15 --json > s.json && hapticlab plot sweep s.json --out sweep.png\n  hapticlab evaluate recordings/thesis-sim --folds 5 --sweep 'bins=[1,1],[1,2]' --sweep k=1,10 --json > g.json && hapticlab plot sweep g.json --out grid.svg"
    )]
    Plot(plot::PlotArgs),
    /// Write profiles: `profile new --from DIR --out P.toml`, an analysis-only profile for a folder of recordings.
    #[command(
        after_help = "Example:\n  hapticlab profile new --from recordings/rig --out profiles/rig.toml"
    )]
    Profile(profile::ProfileArgs),
    /// Check profiles: parse and validate every value.
    #[command(after_help = "Example:\n  hapticlab check profiles/*.toml")]
    Check(check::CheckArgs),
    /// Print the shell completion script for bash, zsh, fish, elvish or powershell.
    #[command(
        after_help = "Install (bash, zsh, fish):\n  hapticlab completions bash > ~/.local/share/bash-completion/completions/hapticlab\n  hapticlab completions zsh > ~/.zfunc/_hapticlab   # with fpath+=~/.zfunc before compinit in ~/.zshrc\n  hapticlab completions fish > ~/.config/fish/completions/hapticlab.fish\n\nExample:\n  hapticlab completions bash > hapticlab.bash"
    )]
    Completions(completions::CompletionsArgs),
    /// Print the manual page (roff), or write one page per command with --out DIR.
    #[command(
        after_help = "Install:\n  hapticlab man > ~/.local/share/man/man1/hapticlab.1\n  hapticlab man --out ~/.local/share/man/man1   # and hapticlab-evaluate.1, … for each command\n\nExamples:\n  hapticlab man > hapticlab.1\n  hapticlab man --out man"
    )]
    Man(man::ManArgs),
}

/// Run one command.
pub fn run(cmd: Command) -> Result<(), Failure> {
    match cmd {
        Command::Console(a) => console::run(a),
        Command::Replay(a) => replay::run(a),
        Command::Simulate(a) => simulate::run(a),
        Command::Scan(a) => scan::run(a),
        Command::Features(a) => features::run(a),
        Command::Train(a) => train::run(a),
        Command::Classify(a) => classify::run(a),
        Command::Evaluate(a) => evaluate::run(a),
        Command::Tune(a) => tune::run(a),
        Command::Check(a) => check::run(a),
        Command::Profile(a) => profile::run(a),
        Command::Devices(a) => devices::run(a),
        Command::Doctor(a) => doctor::run(a),
        Command::Plot(a) => plot::run(&a),
        Command::Import(a) => import::run(a),
        Command::Inspect(a) => inspect::run(a),
        Command::Completions(a) => completions::run(a),
        Command::Man(a) => man::run(a),
    }
}
