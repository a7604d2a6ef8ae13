//! Frame time of the console: a full frame (every panel, the large layout)
//! rendered into a 200×60 TestBackend, from a deterministic mid-session
//! state. The budget is 2 ms.

use criterion::{Criterion, criterion_group, criterion_main};
use ratatui::Terminal;
use ratatui::backend::TestBackend;

use hapticlab::console::fixtures;

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

criterion_group!(benches, frame);
criterion_main!(benches);
