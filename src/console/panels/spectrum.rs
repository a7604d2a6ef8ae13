//! The Spectrum panel: bars of the feature bins (|X_k| of the window's DFT)
//! of the scan on screen, every bar the same width, with the strongest bin
//! named in words.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::text::Line;
use ratatui::widgets::{Paragraph, Widget, Wrap};

use super::{fit_title, frame};
use crate::console::app::App;

/// Eighth blocks, from empty to full.
const EIGHTHS: [&str; 9] = [" ", "▁", "▂", "▃", "▄", "▅", "▆", "▇", "█"];

pub fn render(app: &App, area: Rect, buf: &mut Buffer) {
    let Some(s) = app.scan() else {
        Paragraph::new("no scan yet")
            .block(frame("Spectrum"))
            .render(area, buf);
        return;
    };
    let f = match &s.features {
        Ok(f) if !f.is_empty() => f,
        Ok(_) => {
            Paragraph::new("no feature bins")
                .block(frame("Spectrum"))
                .render(area, buf);
            return;
        }
        Err(e) => {
            Paragraph::new(format!("no spectrum: {e}"))
                .wrap(Wrap { trim: true })
                .block(frame("Spectrum"))
                .render(area, buf);
            return;
        }
    };
    let (peak_i, peak) = f
        .iter()
        .copied()
        .enumerate()
        .fold((0, f64::MIN), |a, (i, v)| if v > a.1 { (i, v) } else { a });
    let last = s.first_bin + f.len() - 1;
    let peak_bin = s.first_bin + peak_i;
    let title = fit_title(
        &[
            format!(
                "Spectrum: peak bin {peak_bin} (|X| {peak:.2e}), bins {}–{last}",
                s.first_bin
            ),
            format!("Spectrum: peak bin {peak_bin}, bins {}–{last}", s.first_bin),
            format!("Spectrum: peak bin {peak_bin}"),
            "Spectrum".into(),
        ],
        area.width,
    );
    let block = frame(&title);
    let inner = block.inner(area);
    block.render(area, buf);
    if inner.height < 2 || inner.width < 4 {
        return;
    }
    // Bars over all but the last row, which carries the bin numbers.
    let rows = inner.height - 1;
    let cols = usize::from(inner.width);
    let n = f.len();
    // Every bar the same width: whole columns per bin, or (max of) several
    // bins per column when there are more bins than columns.
    let per_col = n.div_ceil(cols).max(1);
    let bars = n.div_ceil(per_col);
    let width = (cols / bars).max(1);
    let left = |b: usize| inner.x + (b * width) as u16;
    // A gap between bars when they are wide enough.
    let drawn = if width > 2 { width - 1 } else { width } as u16;
    let top = if peak > 0.0 { peak } else { 1.0 };
    for b in 0..bars {
        let v = f[b * per_col..((b + 1) * per_col).min(n)]
            .iter()
            .copied()
            .fold(0.0, f64::max);
        let eighths = ((v / top) * f64::from(rows) * 8.0).round().max(0.0) as u32;
        let x0 = left(b);
        for r in 0..rows {
            let level = eighths.saturating_sub(u32::from(r) * 8).min(8) as usize;
            let y = inner.y + rows - 1 - r;
            for x in x0..(x0 + drawn).min(inner.right()) {
                buf[(x, y)].set_symbol(EIGHTHS[level]);
            }
        }
    }
    // Bin numbers under the first bar, the last bar and the peak.
    let axis_y = inner.y + rows;
    let mut put = |x: u16, text: String| {
        let len = text.chars().count() as u16;
        if x >= inner.x && x + len <= inner.right() {
            Line::raw(text).render(Rect::new(x, axis_y, len, 1), buf);
        }
    };
    put(inner.x, format!("{}", s.first_bin));
    let last_text = format!("{last}");
    let end = left(bars - 1) + drawn;
    put(end.saturating_sub(last_text.len() as u16), last_text);
    put(left(peak_i / per_col), format!("^{peak_bin}"));
}
