//! The Spectrum panel: bars of the scan's features, every bar the same
//! width, labelled by what they are — DFT bins (|X_k|, power or its log),
//! band energies with their frequency range, or cepstral coefficients
//! (c0…, or c1… without the level term); with several channels, each channel's features in turn, named
//! under their first bar. Bars rise from zero, or from the smallest
//! feature when some are negative (log spectra, cepstra). The strongest
//! bin or band is named in words.

use ratatui::buffer::Buffer;
use ratatui::layout::Rect;
use ratatui::text::Line;
use ratatui::widgets::{Paragraph, Widget, Wrap};

use super::{fit_title, frame};
use crate::console::app::App;
use crate::console::scan::{FeatureNames, ScanView};

/// Eighth blocks, from empty to full.
const EIGHTHS: [&str; 9] = [" ", "▁", "▂", "▃", "▄", "▅", "▆", "▇", "█"];

/// A number in at most three significant digits, no trailing zeros.
fn short(v: f64) -> String {
    let a = v.abs();
    let digits = if a >= 100.0 {
        0
    } else if a >= 10.0 {
        1
    } else if a >= 1.0 {
        2
    } else {
        3
    };
    let t = format!("{v:.digits$}");
    if t.contains('.') {
        t.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        t
    }
}

/// A value as the title shows it: logs plainly, the rest in exponent form.
fn value_text(names: &FeatureNames, v: f64) -> String {
    match names {
        FeatureNames::Bins { value, .. } | FeatureNames::Bands { value, .. }
            if value.starts_with("log") =>
        {
            format!("{value} {v:.2}")
        }
        FeatureNames::Bins { value } | FeatureNames::Bands { value, .. } => {
            format!("{value} {v:.2e}")
        }
        FeatureNames::Cepstra { .. } | FeatureNames::Quantiles | FeatureNames::Hydra => {
            format!("{v:.2}")
        }
        FeatureNames::Points => format!("{v:.2e}"),
    }
}

/// Feature `i` of a channel, as the axis row names it: the bin number, the
/// band's lower edge, or `c<i>`.
fn name(s: &ScanView, i: usize) -> String {
    match &s.names {
        FeatureNames::Bins { .. } => format!("{}", s.first_bin + i),
        FeatureNames::Bands { edges, .. } => short(edges[i]),
        FeatureNames::Cepstra { first } => format!("c{}", first + i),
        FeatureNames::Points => format!("{i}"),
        FeatureNames::Quantiles => format!("q{i}"),
        FeatureNames::Hydra => format!("h{i}"),
    }
}

/// The titles, longest first, for features `f` of `per` values a channel
/// whose largest is feature `peak_i`.
fn titles(s: &ScanView, f: &[f64], per: usize, peak_i: usize) -> Vec<String> {
    let peak = f[peak_i];
    let several = s.channels.len() > 1;
    let (ch, k) = (peak_i / per, peak_i % per);
    // With sub-windows the features shown are the first one's.
    let sub = match &s.windows {
        Some(Ok(w)) if w.len() > 1 => format!(", sub-window 1 of {}", w.len()),
        _ => String::new(),
    };
    let of = if several {
        format!(" of {}{sub}", s.channels.join(", "))
    } else {
        sub
    };
    // Which channel the peak is in, when there are several.
    let in_ch = if several {
        format!("{} ", s.channels[ch])
    } else {
        String::new()
    };
    match &s.names {
        FeatureNames::Bins { .. } => {
            let (first, last, pb) = (s.first_bin, s.first_bin + per - 1, s.first_bin + k);
            vec![
                format!(
                    "Spectrum: peak {in_ch}bin {pb} ({}), bins {first}–{last}{of}",
                    value_text(&s.names, peak)
                ),
                format!("Spectrum: peak {in_ch}bin {pb}, bins {first}–{last}"),
                format!("Spectrum: peak {in_ch}bin {pb}"),
                "Spectrum".into(),
            ]
        }
        FeatureNames::Bands { edges, unit, .. } => {
            let band = format!("{}–{} {unit}", short(edges[k]), short(edges[k + 1]));
            let all = format!(
                "{per} bands {}–{} {unit}",
                short(edges[0]),
                short(edges[per])
            );
            vec![
                format!(
                    "Bands: peak {in_ch}{band} ({}), {all}{of}",
                    value_text(&s.names, peak)
                ),
                format!("Bands: peak {in_ch}{band}, {all}"),
                format!("Bands: peak {in_ch}{band}"),
                "Bands".into(),
            ]
        }
        FeatureNames::Cepstra { first } => {
            let range = format!("c{first}–c{}", first + per - 1);
            vec![
                format!("Cepstra: {range} of the log band energies{of}"),
                format!("Cepstra: {range}{of}"),
                format!("Cepstra: {range}"),
                "Cepstra".into(),
            ]
        }
        // The model's random kernels see these points; the features are
        // theirs, made per window by the model.
        FeatureNames::Points => vec![
            format!("Window: {per} points {in_ch}for the model's random kernels{of}"),
            format!("Window: {per} points for random kernels"),
            format!("Window: {per} points"),
            "Window".into(),
        ],
        FeatureNames::Quantiles => vec![
            format!("Interval quantiles: {per} {in_ch}(signal, differences, spectrum){of}"),
            format!("Interval quantiles: {per}{of}"),
            format!("Interval quantiles: {per}"),
            "Quantiles".into(),
        ],
        FeatureNames::Hydra => vec![
            format!("Competing kernels: {per} wins and losses {in_ch}(signal, difference){of}"),
            format!("Competing kernels: {per}{of}"),
            format!("Competing kernels: {per}"),
            "Hydra".into(),
        ],
    }
}

pub fn render(app: &App, area: Rect, buf: &mut Buffer) {
    match app.scan() {
        Some(s) => render_view(s, area, buf),
        None if app.scan_running || app.scan_saving => {
            Paragraph::new("the first scan is running: its spectrum shows when it ends")
                .wrap(ratatui::widgets::Wrap { trim: true })
                .block(frame("Spectrum"))
                .render(area, buf);
        }
        None => Paragraph::new("no scan yet")
            .block(frame("Spectrum"))
            .render(area, buf),
    }
}

fn render_view(s: &ScanView, area: Rect, buf: &mut Buffer) {
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
    let n = f.len();
    // Features per channel (all of them in one when they do not split).
    let channels = s.channels.len().max(1);
    let (channels, per) = if n % channels == 0 {
        (channels, n / channels)
    } else {
        (1, n)
    };
    if let FeatureNames::Bands { edges, .. } = &s.names
        && edges.len() != per + 1
    {
        // Band edges that do not fit the features: number them instead.
        let mut plain = s.clone();
        plain.names = FeatureNames::Bins { value: "value" };
        plain.first_bin = 0;
        return render_view(&plain, area, buf);
    }
    let (peak_i, peak) = f
        .iter()
        .copied()
        .enumerate()
        .fold((0, f64::MIN), |a, (i, v)| if v > a.1 { (i, v) } else { a });
    let title = fit_title(&titles(s, f, per, peak_i), area.width);
    let block = frame(&title);
    let inner = block.inner(area);
    block.render(area, buf);
    if inner.height < 2 || inner.width < 4 {
        return;
    }
    // Bars over all but the last row, which carries the labels.
    let rows = inner.height - 1;
    let cols = usize::from(inner.width);
    // Every bar the same width: whole columns per feature, or (max of)
    // several features per column when there are more than columns.
    let per_col = n.div_ceil(cols).max(1);
    let bars = n.div_ceil(per_col);
    let width = (cols / bars).max(1);
    let left = |b: usize| inner.x + (b * width) as u16;
    // A gap between bars when they are wide enough.
    let drawn = if width > 2 { width - 1 } else { width } as u16;
    // From zero, or from the smallest value when some are negative.
    let low = f.iter().copied().fold(f64::INFINITY, f64::min);
    let base = if low < 0.0 { low } else { 0.0 };
    let span = if peak > base { peak - base } else { 1.0 };
    for b in 0..bars {
        let v = f[b * per_col..((b + 1) * per_col).min(n)]
            .iter()
            .copied()
            .fold(f64::NEG_INFINITY, f64::max);
        let eighths = (((v - base) / span) * f64::from(rows) * 8.0)
            .round()
            .max(0.0) as u32;
        let x0 = left(b);
        for r in 0..rows {
            let level = eighths.saturating_sub(u32::from(r) * 8).min(8) as usize;
            let y = inner.y + rows - 1 - r;
            for x in x0..(x0 + drawn).min(inner.right()) {
                buf[(x, y)].set_symbol(EIGHTHS[level]);
            }
        }
    }
    // Labels: the first feature's name (each channel's, with several),
    // the last's at the end, and the peak's.
    let axis_y = inner.y + rows;
    let mut put = |x: u16, text: String| {
        let len = text.chars().count() as u16;
        if x >= inner.x && x + len <= inner.right() {
            Line::raw(text).render(Rect::new(x, axis_y, len, 1), buf);
        }
    };
    let last_text = match &s.names {
        FeatureNames::Bands { edges, .. } => short(edges[per]),
        _ => name(s, per - 1),
    };
    let end = left(bars - 1) + drawn;
    put(
        end.saturating_sub(last_text.chars().count() as u16),
        last_text,
    );
    if channels > 1 {
        for (c, ch) in s.channels.iter().enumerate() {
            put(left(c * per / per_col), format!("{ch} {}", name(s, 0)));
        }
    } else {
        put(inner.x, name(s, 0));
    }
    if !matches!(s.names, FeatureNames::Cepstra { .. }) {
        put(
            left(peak_i / per_col),
            format!("^{}", name(s, peak_i % per)),
        );
    }
}
