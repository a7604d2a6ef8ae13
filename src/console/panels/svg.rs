//! The console's picture in the docs (`docs/console.svg`): the 120×40
//! snapshot screen (the fixture app the insta snapshots draw) written as
//! an SVG of monospace text, one `<text>` per run of equally styled cells,
//! each character placed at its cell's x, so box drawing and Braille line
//! up whatever the viewer's font. Renderers that honour only a text's first
//! x (librsvg) still line up: a character a monospace font may lack
//! (Braille, arrows) is a `<text>` of its own. `HAPTICLAB_BLESS=1 cargo test -p hapticlab
//! --lib console_svg` writes it again; the test fails when it is stale.

use ratatui::Terminal;
use ratatui::backend::TestBackend;
use ratatui::buffer::{Buffer, Cell};
use ratatui::style::{Color, Modifier};

use crate::console::fixtures;

const CELL_W: f64 = 8.8;
const CELL_H: f64 = 17.0;
const FONT: f64 = 14.6;
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

/// Whether every monospace font draws `c` one cell wide: ASCII and box
/// drawing.
fn common(c: char) -> bool {
    c.is_ascii() || ('\u{2500}'..='\u{259f}').contains(&c)
}

/// A run's text cut into pieces, each with its offset in cells: runs of
/// common characters whole, any other character alone.
fn pieces(text: &str) -> Vec<(usize, String)> {
    let mut out: Vec<(usize, String)> = Vec::new();
    let mut last_common = false;
    for (i, c) in text.chars().enumerate() {
        match out.last_mut() {
            Some((_, piece)) if last_common && common(c) => piece.push(c),
            _ => out.push((i, c.to_string())),
        }
        last_common = common(c);
    }
    out
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
            let attrs = format!(
                "fill=\"{fg}\"{}{}",
                if *bold { " font-weight=\"bold\"" } else { "" },
                if *dim { " opacity=\"0.65\"" } else { "" },
            );
            let y_text = py + CELL_H * 0.78;
            for (offset, piece) in pieces(body) {
                let xs: Vec<String> = (0..piece.chars().count())
                    .map(|i| format!("{:.1}", px + (lead + offset + i) as f64 * CELL_W))
                    .collect();
                out.push_str(&format!(
                    "<text x=\"{}\" y=\"{y_text:.1}\" {attrs} xml:space=\"preserve\">{}</text>\n",
                    xs.join(" "),
                    escape(&piece),
                ));
            }
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
