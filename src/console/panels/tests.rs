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
    // The window fills the width: its ends are the x axis's ends.
    let axis = s.lines().nth(12).unwrap();
    assert!(
        axis.trim_start_matches('│')
            .trim_start()
            .starts_with("60.0")
            && axis.ends_with("89.7│"),
        "{s}"
    );
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

/// The panel titles of a screen, as drawn.
fn titles(s: &str) -> Vec<&str> {
    let mut v = Vec::new();
    for line in s.lines() {
        for part in line.split("┌ ").skip(1) {
            if let Some(end) = part.find(" ─") {
                v.push(&part[..end]);
            }
        }
    }
    v
}

#[test]
fn the_first_page_at_120x40_is_the_whole_dashboard() {
    let app = fixtures::app(120, 40);
    let s = screen(&app, 120, 40);
    let t = titles(&s);
    for want in [
        "Device",
        "Position",
        "Force",
        "Traces",
        "Surface trace",
        "Spectrum",
        "Prediction",
    ] {
        assert!(
            t.iter().any(|t| t.starts_with(want)),
            "no {want} on page 1 at 120x40: {t:?}\n{s}"
        );
    }
    // Every title is whole: it ends in a word, not in a corner.
    assert!(
        s.lines().all(|l| !l.contains("┌ ") || l.contains(" ─")),
        "{s}"
    );
    // Smaller terminals page: 80x24 has four pages, 120x40 two.
    assert_eq!(super::pages(120, 40).len(), 2);
    assert_eq!(super::pages(80, 24).len(), 4);
}

#[test]
fn long_paths_are_elided_in_the_middle_and_a_queue_has_its_own_row() {
    let mut app = fixtures::app(120, 40);
    app.dataset.dir =
        "/home/lab/experiments/2026-11-23/falcon-session-with-a-long-name/recordings".into();
    app.queue_total = 5;
    app.queue_stored = 2;
    app.queue_left = 2;
    let s = panel(Panel::Device, &app, 40, 11);
    let row = s.lines().find(|l| l.contains("Dataset")).unwrap();
    assert!(
        row.contains('…') && row.ends_with("name/recordings│"),
        "{s}"
    );
    assert!(row.starts_with("│Dataset  /home/lab"), "{s}");
    assert!(s.contains("Queue    2 of 5 stored, 2 to start"), "{s}");
    assert!(s.contains("stroke 50 % recorded  "), "{s}");
    let d = panel(Panel::Dataset, &app, 60, 14);
    assert!(d.contains("folder /home/lab") && d.contains("…"), "{d}");
    insta::assert_snapshot!("device_with_a_queue", s);
}

#[test]
fn elide_and_cut_keep_whole_words_and_both_ends() {
    assert_eq!(super::elide_middle("abc", 5), "abc");
    let e = super::elide_middle("recordings/session-test/S2/S2_031.csv", 20);
    assert_eq!(e.chars().count(), 20);
    assert!(e.starts_with("record") && e.ends_with("S2_031.csv"), "{e}");
    assert_eq!(
        super::cut_at_word("stroke 52 % recorded (+3 queued)", 25),
        "stroke 52 % recorded…"
    );
    assert_eq!(
        super::fit_title(&["a long title here".into(), "short".into()], 12),
        "short"
    );
}

/// A probe holding still at y = -5 mm, its encoder jittering one step.
fn holding_still() -> App {
    let mut app = fixtures::app(80, 24);
    app.live.clear();
    for i in 0..=3000 {
        let mut t = fixtures::telemetry(i as f64 * 0.001, Mode::Target);
        t.pos_m[1] = -0.005 + if i % 7 < 3 { 2e-6 } else { 0.0 };
        t.force_n[1] = -0.2 + if i % 5 < 2 { 1e-4 } else { 0.0 };
        app.on_telemetry(&t);
    }
    app
}

#[test]
fn traces_of_a_still_probe_are_flat_lines_with_their_labels_above() {
    let app = holding_still();
    let s = panel(Panel::Traces, &app, 80, 12);
    // At least 0.5 mm and 0.1 N of span, padded 8 %: the step is a hair.
    assert!(s.contains("-5.29") && s.contains("-4.71"), "{s}");
    assert!(s.contains("-0.26") && s.contains("-0.14"), "{s}");
    assert!(!s.contains('⣿'), "solid blocks:\n{s}");
    let curve_rows = s
        .lines()
        .filter(|l| l.chars().any(|c| ('\u{2801}'..='\u{28ff}').contains(&c)))
        .count();
    assert!(curve_rows <= 2, "{s}");
    // The name and value have a row of their own, above the plots.
    let top = s.lines().nth(1).unwrap();
    assert!(
        top.contains("y -5.000 mm") && top.contains("fy -0.200 N"),
        "{s}"
    );
    assert!(
        !top.chars().any(|c| ('\u{2801}'..='\u{28ff}').contains(&c)),
        "{s}"
    );
    insta::assert_snapshot!(s);
}

#[test]
fn a_flat_texture_is_a_flat_line_not_bars() {
    let mut app = fixtures::app(80, 24);
    let scan = app.last_scan.as_mut().unwrap();
    for (i, p) in scan.trace.iter_mut().enumerate() {
        p.1 = -4.8 + if i % 3 == 0 { 0.002 } else { 0.0 };
    }
    let s = panel(Panel::Surface, &app, 80, 14);
    let curve_rows = s
        .lines()
        .filter(|l| l.chars().any(|c| ('\u{2801}'..='\u{28ff}').contains(&c)))
        .count();
    assert!(curve_rows <= 2, "{s}");
    assert!(s.contains("-5.09") && s.contains("-4.51"), "{s}");
}

#[test]
fn every_spectrum_bin_is_drawn_the_same_width() {
    let mut app = fixtures::app(80, 24);
    let scan = app.last_scan.as_mut().unwrap();
    let n = 49;
    scan.features = Ok(vec![1.0; n]);
    for w in [40, 53, 60, 77, 100, 119, 160, 200] {
        let s = panel(Panel::Spectrum, &app, w, 8);
        // The top row of bars: every bin full height.
        let row: Vec<char> = s.lines().nth(1).unwrap().chars().collect();
        let runs: Vec<usize> = row
            .split(|c| *c != '█')
            .map(<[char]>::len)
            .filter(|l| *l > 0)
            .collect();
        let cols = usize::from(w) - 2;
        if cols >= n {
            let width = cols / n;
            let drawn = if width > 2 { width - 1 } else { width };
            assert_eq!(runs.iter().sum::<usize>(), n * drawn, "at {w}:\n{s}");
            if width > 2 {
                assert_eq!(runs.len(), n, "at {w}:\n{s}");
                assert!(runs.iter().all(|r| *r == drawn), "at {w}: {runs:?}\n{s}");
            }
        } else {
            // Two bins per column: as many columns as bars, one each.
            assert_eq!(
                runs.iter().sum::<usize>(),
                n.div_ceil(n.div_ceil(cols)),
                "at {w}:\n{s}"
            );
        }
    }
}

/// The thesis's analysis with the changes `f` makes, its synthetic scan on
/// screen.
fn spectrum_under(f: impl Fn(&mut crate::profile::Analysis)) -> App {
    let mut a = crate::profile::LoadedProfile::thesis().profile.analysis;
    f(&mut a);
    let mut app = fixtures::app(80, 24);
    app.last_scan = Some(fixtures::scan_view_under(&a));
    app
}

#[test]
fn a_log_spectrum_rises_from_its_smallest_value() {
    use crate::profile::SpectrumKind;
    let app = spectrum_under(|a| a.spectrum = SpectrumKind::LogPower);
    let f = app.last_scan.as_ref().unwrap().features.clone().unwrap();
    assert!(f.iter().all(|v| *v < 0.0), "log10 of a small power: {f:?}");
    let s = panel(Panel::Spectrum, &app, 104, 10);
    assert!(s.contains("Spectrum: peak bin 7 (log10 power -"), "{s}");
    // Two columns a bin: the peak's bar full height, the smallest's empty.
    let top: Vec<char> = s.lines().nth(1).unwrap().chars().collect();
    let bottom: Vec<char> = s.lines().nth(7).unwrap().chars().collect();
    let (lo, _) = f.iter().enumerate().fold(
        (0, f64::MAX),
        |a, (i, v)| if *v < a.1 { (i, *v) } else { a },
    );
    assert_eq!(top[1 + 2 * 6], '█', "bin 7 is the peak:\n{s}");
    assert_eq!(
        bottom[1 + 2 * lo],
        ' ',
        "the smallest bin is the floor:\n{s}"
    );
    assert!(bottom.iter().filter(|c| **c == '█').count() > 20, "{s}");
}

#[test]
fn bands_are_labelled_with_their_range() {
    use crate::profile::{BandScale, Bands, SpectrumKind};
    let app = spectrum_under(|a| {
        a.spectrum = SpectrumKind::LogPower;
        a.bands = Some(Bands {
            count: 8,
            from: 0.05,
            to: 1.5,
            scale: BandScale::Log,
        });
    });
    let s = panel(Panel::Spectrum, &app, 90, 10);
    // S2's 4.24 mm period is 0.236 cycles/mm: in the band from
    // 0.05 · 30^(3/8) = 0.179 to 0.05 · 30^(4/8) = 0.274.
    assert!(
        s.contains("Bands: peak 0.179–0.274 cycles/mm (log10 energy"),
        "{s}"
    );
    assert!(s.contains("8 bands 0.05–1.5 cycles/mm"), "{s}");
    insta::assert_snapshot!(s);
}

#[test]
fn cepstra_of_two_channels_are_named_per_channel() {
    use crate::profile::{BandScale, Bands, SpectrumKind};
    let app = spectrum_under(|a| {
        a.spectrum = SpectrumKind::Power;
        a.channels = vec!["fy_n".into()];
        a.bands = Some(Bands {
            count: 8,
            from: 0.05,
            to: 1.5,
            scale: BandScale::Log,
        });
        a.cepstra = Some(6);
    });
    let scan = app.last_scan.as_ref().unwrap();
    assert_eq!(scan.features.as_ref().unwrap().len(), 12);
    let s = panel(Panel::Spectrum, &app, 80, 10);
    assert!(
        s.contains("Cepstra: c0–c5 of the log band energies of y_m, fy_n"),
        "{s}"
    );
    let axis = s.lines().nth(8).unwrap();
    assert!(
        axis.contains("y_m c0") && axis.contains("fy_n c0") && axis.contains("c5"),
        "{s}"
    );
    insta::assert_snapshot!(s);
}

#[test]
fn bins_of_two_channels_name_the_channel_of_the_peak() {
    let app = spectrum_under(|a| {
        a.bins = [1, 24];
        a.channels = vec!["fy_n".into()];
    });
    let s = panel(Panel::Spectrum, &app, 120, 10);
    assert!(
        s.contains("Spectrum: peak fy_n bin 7 (|X|") && s.contains("bins 1–24 of y_m, fy_n"),
        "{s}"
    );
    let axis = s.lines().nth(8).unwrap();
    assert!(
        axis.contains("y_m 1") && axis.contains("fy_n 1") && axis.contains("24"),
        "{s}"
    );
}

#[test]
fn with_sub_windows_the_spectrum_says_which_it_shows() {
    let app = spectrum_under(|a| {
        a.bins = [1, 24];
        a.windows = Some(crate::profile::Windows {
            length: 0.0147,
            hop: 0.005,
        });
    });
    let s = panel(Panel::Spectrum, &app, 100, 8);
    assert!(s.contains("bins 1–24, sub-window 1 of 4"), "{s}");
}

/// The replay browser's footer shows its own keys (leaving, the list, the
/// curating keys) and, where they do not all fit, ends with the sign that
/// help lists the rest; leaving and help always show.
#[test]
fn the_browser_footer_shows_its_keys_and_says_when_more_exist() {
    let mut app = fixtures::app(80, 24);
    let files = vec!["ds/S1/S1_001.csv".into(), "ds/S2/S2_001.csv".into()];
    app.replay = Some(crate::console::replay::Replay::new("ds".into(), files));
    let hints = super::footer::hints(&app);
    for want in [
        "back",
        "quit",
        "to label",
        "next wrong",
        "filter",
        "delete",
        "undo",
    ] {
        assert!(hints.iter().any(|(_, w)| *w == want), "{want}: {hints:?}");
    }
    for (w, shows) in [(80, "j to label"), (120, "x exclude")] {
        app.resize(w, 24);
        let s = screen(&app, w, 24);
        let footer = s.lines().nth(22).unwrap();
        assert!(footer.starts_with("? help Esc back q quit"), "{footer}");
        assert!(footer.contains(shows), "{footer}");
        assert!(footer.contains("? more"), "{footer}");
    }
}
