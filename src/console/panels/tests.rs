//! Panels rendered into buffers and checked with insta snapshots (committed
//! under `src/console/panels/snapshots/`). The app comes from
//! [`crate::console::fixtures`]: no clock, no randomness.

use ratatui::Terminal;
use ratatui::backend::TestBackend;
use ratatui::buffer::Buffer;
use ratatui::layout::Rect;

use super::{Panel, render_panel};
use crate::console::app::App;
use crate::console::fixtures;
use crate::console::form::{Form, FormKind, Overlay};
use crate::servo::Mode;

/// The buffer as text, one line per row, trailing spaces trimmed.
pub fn text(buf: &Buffer) -> String {
    let a = buf.area;
    let mut out = String::new();
    for y in a.y..a.bottom() {
        let mut line = String::new();
        for x in a.x..a.right() {
            line.push_str(buf[(x, y)].symbol());
        }
        out.push_str(line.trim_end());
        out.push('\n');
    }
    out
}

fn panel(p: Panel, app: &App, w: u16, h: u16) -> String {
    let area = Rect::new(0, 0, w, h);
    let mut buf = Buffer::empty(area);
    render_panel(p, app, area, &mut buf);
    text(&buf)
}

fn screen(app: &App, w: u16, h: u16) -> String {
    let mut t = Terminal::new(TestBackend::new(w, h)).unwrap();
    t.draw(|f| f.render_widget(app, f.area())).unwrap();
    text(t.backend().buffer())
}

#[test]
fn device_panel() {
    let app = fixtures::app(80, 24);
    let s = panel(Panel::Device, &app, 40, 11);
    assert!(s.contains("yes (LED blue)"), "{s}");
    assert!(s.contains("p99 error 21 µs"), "{s}");
    insta::assert_snapshot!(s);
}

#[test]
fn device_panel_not_homed_says_so_in_words() {
    let mut app = fixtures::app(80, 24);
    let mut t = fixtures::telemetry(5.0, Mode::Manual);
    t.homed = false;
    app.on_telemetry(&t);
    let s = panel(Panel::Device, &app, 60, 11);
    assert!(s.contains("NO (LED red)"), "{s}");
}

#[test]
fn position_and_force_panels() {
    let mut app = fixtures::app(80, 24);
    let s = panel(Panel::Position, &app, 36, 6);
    assert!(s.contains("x       0.00    0.00"), "{s}");
    insta::assert_snapshot!("position", s);
    insta::assert_snapshot!("force", panel(Panel::Force, &app, 36, 5));
    // In Target mode the target column fills in.
    app.on_telemetry(&fixtures::telemetry(4.6, Mode::Target));
    app.target_m = Some([0.01, 0.02, -0.03]);
    let s = panel(Panel::Position, &app, 36, 6);
    assert!(s.contains("   1.00") && s.contains("  -3.00"), "{s}");
}

#[test]
fn traces_panel() {
    let app = fixtures::app(80, 24);
    insta::assert_snapshot!(panel(Panel::Traces, &app, 80, 12));
}

#[test]
fn surface_trace_panel_marks_the_window() {
    let app = fixtures::app(80, 24);
    let s = panel(Panel::Surface, &app, 80, 14);
    assert!(s.contains("window 60.0–89.7 mm"), "{s}");
    assert!(s.contains('•'), "{s}");
    insta::assert_snapshot!(s);
}

#[test]
fn spectrum_panel_names_the_peak() {
    let app = fixtures::app(80, 24);
    let s = panel(Panel::Spectrum, &app, 60, 10);
    assert!(s.contains("peak bin 7"), "{s}");
    insta::assert_snapshot!(s);
}

#[test]
fn prediction_panel() {
    let app = fixtures::app(80, 24);
    let s = panel(Panel::Prediction, &app, 60, 12);
    assert!(
        s.contains("Predicted S2 — corrugated cardboard, trapezoidal, fine"),
        "{s}"
    );
    assert!(s.contains("A 1.9 mm"), "{s}");
    assert!(s.contains("recorded as S2: right"), "{s}");
    insta::assert_snapshot!(s);
}

#[test]
fn workspace_panel() {
    let app = fixtures::app(80, 24);
    let s = panel(Panel::Workspace, &app, 60, 14);
    assert!(s.contains('@') && s.contains('5'), "{s}");
    insta::assert_snapshot!(s);
}

#[test]
fn dataset_panel_shows_the_confusion_matrix() {
    let app = fixtures::app(80, 24);
    let s = panel(Panel::Dataset, &app, 60, 14);
    assert!(s.contains("121 recordings"), "{s}");
    assert!(s.contains("SR(%)") && s.contains("ER(%)"), "{s}");
    insta::assert_snapshot!(s);
}

#[test]
fn whole_screen_at_80x24_every_page() {
    let mut app = fixtures::app(80, 24);
    for page in 0..4 {
        app.page = page;
        insta::assert_snapshot!(
            format!("screen_80x24_page{}", page + 1),
            screen(&app, 80, 24)
        );
    }
}

#[test]
fn whole_screen_at_120x40_and_200x60() {
    let app = fixtures::app(120, 40);
    insta::assert_snapshot!("screen_120x40", screen(&app, 120, 40));
    let app = fixtures::app(200, 60);
    let s = screen(&app, 200, 60);
    for title in [
        "Device",
        "Position",
        "Force",
        "Traces",
        "Surface trace",
        "Spectrum",
        "Prediction",
        "Workspace",
        "Dataset",
    ] {
        assert!(s.contains(&format!(" {title}")), "no {title} at 200x60");
    }
    insta::assert_snapshot!("screen_200x60", s);
}

#[test]
fn overlays() {
    let mut app = fixtures::app(80, 24);
    app.overlay = Some(Overlay::Help);
    insta::assert_snapshot!("help_80x24", screen(&app, 80, 24));
    let mut f = Form::target([1.0, -0.48, -2.0], "x, y, z in cm".into());
    f.error = Some("x = 9 cm is outside the workspace: -5 to 5 cm".into());
    app.overlay = Some(Overlay::Form(f));
    let s = screen(&app, 80, 24);
    assert!(s.contains("ERROR: x = 9 cm"), "{s}");
    app.overlay = Some(Overlay::Form(Form::text(
        FormKind::Store,
        "label",
        "S2",
        "hint".into(),
    )));
    assert!(screen(&app, 80, 24).contains("Store the last scan"));
}

#[test]
fn tiny_terminals_do_not_panic() {
    let app = fixtures::app(10, 5);
    for (w, h) in [(1, 1), (10, 5), (30, 8), (79, 23)] {
        screen(&app, w, h);
    }
}
