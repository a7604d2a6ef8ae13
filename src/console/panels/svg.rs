//! The console's picture in the docs (`docs/console.svg`): the 120×40
//! snapshot screen (the fixture app the insta snapshots draw) written as
//! an SVG of monospace text, one `<text>` per run of equally styled cells,
//! each stretched to its cells' width so box drawing and Braille line up
//! whatever the viewer's font. `HAPTICLAB_BLESS=1 cargo test -p hapticlab
//! --lib console_svg` writes it again; the test fails when it is stale.

use ratatui::Terminal;
use ratatui::backend::TestBackend;
use ratatui::buffer::{Buffer, Cell};
use ratatui::style::{Color, Modifier};

use crate::console::fixtures;

const CELL_W: f64 = 8.4;
const CELL_H: f64 = 17.0;
const FONT: f64 = 14.0;
const BACKGROUND: &str = "#1e1e1e";
const FOREGROUND: &str = "#d4d4d4";

fn colour(c: Color, default: &str) -> String {
    match c {
        Color::Reset => default,
        Color::Black => "#000000",
        Color::Red => "#f14c4c",
        Color::Green => "#23d18b",
        Color::Yellow => "#f5f543",
        Color::Blue => "#3b8eea",
        Color::Magenta => "#d670d6",
        Color::Cyan => "#29b8db",
        Color::Gray => "#cccccc",
        Color::DarkGray => "#767676",
        Color::White => "#ffffff",
        Color::Rgb(r, g, b) => return format!("#{r:02x}{g:02x}{b:02x}"),
        _ => default,
    }
    .to_string()
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// A cell's look: text colour, background (None: the terminal's), bold, dim.
fn look(c: &Cell) -> (String, Option<String>, bool, bool) {
    let m = c.modifier;
    let (mut fg, mut bg) = (colour(c.fg, FOREGROUND), colour(c.bg, BACKGROUND));
    if m.contains(Modifier::REVERSED) {
        std::mem::swap(&mut fg, &mut bg);
    }
    let bg = (bg != BACKGROUND).then_some(bg);
    (
        fg,
        bg,
        m.contains(Modifier::BOLD),
        m.contains(Modifier::DIM),
    )
}

/// The buffer as an SVG.
pub fn svg(buf: &Buffer) -> String {
    let a = buf.area;
    let (w, h) = (a.width as f64 * CELL_W, a.height as f64 * CELL_H);
    let mut out = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w:.0}\" height=\"{h:.0}\" \
         viewBox=\"0 0 {w:.0} {h:.0}\" font-family=\"'DejaVu Sans Mono', Menlo, Consolas, monospace\" \
         font-size=\"{FONT}\">\n<rect width=\"100%\" height=\"100%\" fill=\"{BACKGROUND}\"/>\n"
    );
    for y in a.y..a.bottom() {
        let mut x = a.x;
        while x < a.right() {
            let style = look(&buf[(x, y)]);
            let start = x;
            let mut text = String::new();
            while x < a.right() && look(&buf[(x, y)]) == style {
                text.push_str(buf[(x, y)].symbol());
                x += 1;
            }
            let (fg, bg, bold, dim) = &style;
            let (px, py) = ((start - a.x) as f64 * CELL_W, (y - a.y) as f64 * CELL_H);
            let width = (x - start) as f64 * CELL_W;
            if let Some(bg) = bg {
                out.push_str(&format!(
                    "<rect x=\"{px:.1}\" y=\"{py:.1}\" width=\"{width:.1}\" height=\"{CELL_H}\" fill=\"{bg}\"/>\n"
                ));
            }
            let trimmed = text.trim_end();
            if trimmed.trim_start().is_empty() {
                continue;
            }
            // Leading spaces become an offset, trailing ones are dropped.
            let lead = text.chars().take_while(|c| *c == ' ').count();
            let body = trimmed.trim_start();
            let cells = body.chars().count();
            out.push_str(&format!(
                "<text x=\"{:.1}\" y=\"{:.1}\" fill=\"{fg}\"{}{} textLength=\"{:.1}\" \
                 lengthAdjust=\"spacingAndGlyphs\" xml:space=\"preserve\">{}</text>\n",
                px + lead as f64 * CELL_W,
                py + CELL_H * 0.78,
                if *bold { " font-weight=\"bold\"" } else { "" },
                if *dim { " opacity=\"0.65\"" } else { "" },
                cells as f64 * CELL_W,
                escape(body),
            ));
        }
    }
    out.push_str("</svg>\n");
    out
}

#[test]
fn console_svg_is_current() {
    let app = fixtures::app(120, 40);
    let mut t = Terminal::new(TestBackend::new(120, 40)).unwrap();
    t.draw(|f| f.render_widget(&app, f.area())).unwrap();
    let drawn = svg(t.backend().buffer());
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/console.svg");
    if std::env::var_os("HAPTICLAB_BLESS").is_some() {
        std::fs::write(&path, &drawn).unwrap();
        return;
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == drawn,
        "docs/console.svg is not the console's 120x40 snapshot screen; \
         write it again with: HAPTICLAB_BLESS=1 cargo test -p hapticlab --lib console_svg"
    );
}
