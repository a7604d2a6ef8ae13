//! Frame time of the console: a full frame (every panel, the large layout)
//! rendered into a 200×60 TestBackend, from a deterministic mid-session
//! state. The budget is 2 ms. And the live estimate's share of a frame: the
//! frame in which a sub-window completes, so it is analysed and classified
//! (a thesis scan, four 14.7 mm sub-windows, a model of the other 119
//! shipped scans × 4).

use std::path::{Path, PathBuf};

use criterion::{BatchSize, Criterion, criterion_group, criterion_main};
use ratatui::Terminal;
use ratatui::backend::TestBackend;

use hapticlab::classify::Model;
use hapticlab::console::estimate::Estimate;
use hapticlab::console::fixtures;
use hapticlab::dataset;
use hapticlab::profile::{LoadedProfile, Windows};
use hapticlab::servo::Mode;

fn frame(c: &mut Criterion) {
    for (w, h) in [(200u16, 60u16), (80, 24)] {
        let app = fixtures::app(w, h);
        let mut terminal = Terminal::new(TestBackend::new(w, h)).unwrap();
        c.bench_function(&format!("full frame {w}x{h}"), |b| {
            b.iter(|| {
                terminal.draw(|f| f.render_widget(&app, f.area())).unwrap();
            })
        });
    }
}

fn live_estimate(c: &mut Criterion) {
    let mut a = LoadedProfile::thesis().profile.analysis;
    a.bins = [1, 24];
    a.windows = Some(Windows {
        length: 0.0147,
        hop: 0.005,
    });
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("recordings/thesis-sim");
    let files: Vec<PathBuf> = dataset::find(&[dir]).unwrap();
    let (held, train) = files.split_last().unwrap();
    let loaded = dataset::load(train, &a, dataset::Options::default(), &|| {}).unwrap();
    let classifier = LoadedProfile::thesis().profile.classifier;
    let model = Model::train("bench", &a, &classifier, loaded.into_examples()).unwrap();
    let rec = hapticlab::recording::read(held).unwrap();
    let col = |name: &str| rec.column(name).unwrap();
    let (t, x, y) = (col("t_s"), col("x_m"), col("y_m"));
    let frames: Vec<_> = (0..rec.len())
        .map(|i| {
            let mut f = fixtures::telemetry(t[i], Mode::Test);
            f.pos_m = [x[i], y[i], -0.02];
            f
        })
        .collect();
    // The samples up to just past the first sub-window's end.
    let end = a.sub_windows()[0][1] + a.spacing;
    let upto = x.iter().position(|&v| v - x[0] > end).unwrap();
    c.bench_function("live estimate: the frame a sub-window completes", |b| {
        b.iter_batched(
            || {
                let mut e = Estimate::start(&model, &frames[0]);
                for f in &frames[1..upto] {
                    e.push(f);
                }
                e
            },
            |mut e| {
                assert!(e.update());
                e
            },
            BatchSize::SmallInput,
        )
    });
}

criterion_group!(benches, frame, live_estimate);
criterion_main!(benches);
