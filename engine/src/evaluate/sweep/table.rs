//! A sweep as text: one key as a list (a row per value), two keys as a
//! matrix (rows the first key's values, columns the second's, each cell the
//! pooled accuracy), three or more as a row per combination; then the best
//! point, or that every point ties.

use super::{Sweep, SweepPoint};

/// How many tied best points the verdict names before "and N more".
const NAMED: usize = 6;

impl Sweep {
    pub fn table(&self) -> String {
        let mut out = if self.keys.len() == 2 {
            self.matrix()
        } else {
            self.rows()
        };
        out.push_str(&self.verdict());
        out
    }

    /// `k = 3, spectrum = magnitude`.
    fn assignment(&self, p: &SweepPoint) -> String {
        self.keys
            .iter()
            .zip(&p.values)
            .map(|(k, v)| format!("{k} = {v}"))
            .collect::<Vec<_>>()
            .join(", ")
    }

    fn rows(&self) -> String {
        let widths: Vec<usize> = self
            .keys
            .iter()
            .enumerate()
            .map(|(j, k)| {
                self.points
                    .iter()
                    .map(|p| p.values.get(j).map_or(0, |v| v.chars().count()))
                    .chain([k.chars().count()])
                    .max()
                    .unwrap_or(1)
            })
            .collect();
        let lead = |cells: &mut dyn Iterator<Item = &str>| {
            cells
                .zip(&widths)
                .map(|(c, w)| format!("{c:<w$}  "))
                .collect::<String>()
        };
        let mut out = lead(&mut self.keys.iter().map(String::as_str));
        out.push_str("accuracy  per-fold mean ± sd  macro-F1\n");
        for p in &self.points {
            out.push_str(&lead(&mut p.values.iter().map(String::as_str)));
            if !p.evaluated {
                let reason = p.reason.as_deref().unwrap_or("no reason given");
                out.push_str(&format!("not evaluated: {reason}\n"));
                continue;
            }
            out.push_str(&format!(
                "{:>7.1}%  {:>8.1} ± {:<5.1} %  {:>8.3}",
                100.0 * p.accuracy,
                100.0 * p.accuracy_mean,
                100.0 * p.accuracy_std,
                p.macro_f1
            ));
            if p.incomplete > 0 {
                out.push_str(&format!(
                    "  ({} of {} scans did not finish)",
                    p.incomplete,
                    p.incomplete + p.recordings
                ));
            }
            if p.best {
                out.push_str("  best");
            }
            out.push('\n');
            if let Some(n) = &p.k_notice {
                out.push_str(&format!("{:w$}({n})\n", "", w = lead_width(&widths)));
            }
        }
        out
    }

    /// Rows the first key's values, columns the second's; each cell the
    /// pooled accuracy in %, `*` on the best, `–` and a numbered reason
    /// below for a point not evaluated.
    fn matrix(&self) -> String {
        let (rows, cols) = (unique(&self.points, 0), unique(&self.points, 1));
        let mut reasons: Vec<&str> = Vec::new();
        let mut cells: Vec<Vec<String>> = Vec::new();
        for r in &rows {
            let mut line = Vec::new();
            for c in &cols {
                let text = match self.points.iter().find(|p| p.values == [*r, *c]) {
                    None => String::new(),
                    Some(p) if p.evaluated => {
                        format!(
                            "{:.1}{}",
                            100.0 * p.accuracy,
                            if p.best { " *" } else { "  " }
                        )
                    }
                    Some(p) => {
                        let reason = p.reason.as_deref().unwrap_or("no reason given");
                        let n = match reasons.iter().position(|x| *x == reason) {
                            Some(i) => i + 1,
                            None => {
                                reasons.push(reason);
                                reasons.len()
                            }
                        };
                        format!("– ({n})")
                    }
                };
                line.push(text);
            }
            cells.push(line);
        }
        let corner = format!("{} \\ {}", self.keys[0], self.keys[1]);
        let w0 = rows
            .iter()
            .map(|r| r.chars().count())
            .chain([corner.chars().count()])
            .max()
            .unwrap_or(1);
        let widths: Vec<usize> = cols
            .iter()
            .enumerate()
            .map(|(j, c)| {
                cells
                    .iter()
                    .map(|row| row[j].chars().count())
                    .chain([c.chars().count()])
                    .max()
                    .unwrap_or(1)
            })
            .collect();
        let mut out = format!(
            "accuracy (%) pooled over the folds: rows {}, columns {}{}\n",
            self.keys[0],
            self.keys[1],
            if self.best().next().is_some() {
                "; * best"
            } else {
                ""
            }
        );
        out.push_str(&format!("{corner:<w0$}"));
        for (c, w) in cols.iter().zip(&widths) {
            out.push_str(&format!("  {c:>w$}"));
        }
        out.push('\n');
        for (r, row) in rows.iter().zip(&cells) {
            out.push_str(&format!("{r:<w0$}"));
            for (c, w) in row.iter().zip(&widths) {
                out.push_str(&format!("  {c:>w$}"));
            }
            out.push('\n');
        }
        for (i, r) in reasons.iter().enumerate() {
            out.push_str(&format!("({}) not evaluated: {r}\n", i + 1));
        }
        let mut notes: Vec<&str> = Vec::new();
        for n in self.points.iter().filter_map(|p| p.k_notice.as_deref()) {
            if !notes.contains(&n) {
                notes.push(n);
                out.push_str(&format!("note: {n}\n"));
            }
        }
        // No padding after the last column.
        out.lines().map(|l| format!("{}\n", l.trim_end())).collect()
    }

    /// The best point(s), or why there is none.
    fn verdict(&self) -> String {
        let what = if self.keys.len() == 1 {
            "value"
        } else {
            "combination"
        };
        let best: Vec<&SweepPoint> = self.best().collect();
        match best.as_slice() {
            [] if self.evaluated() == 0 => format!("no {what} could be evaluated\n"),
            [] if self.points.len() > 1 => format!(
                "no best: every {what} gives {:.1} %\n",
                100.0 * self.points[0].accuracy
            ),
            [] => String::new(),
            [p] => format!(
                "best: {} ({:.1} %), {}\n",
                self.assignment(p),
                100.0 * p.accuracy,
                self.method
            ),
            [p, ..] => {
                let mut named: Vec<String> = best
                    .iter()
                    .take(NAMED)
                    .map(|p| self.assignment(p))
                    .collect();
                if best.len() > NAMED {
                    named.push(format!("and {} more", best.len() - NAMED));
                }
                format!(
                    "best ({} tie at {:.1} %): {}, {}\n",
                    best.len(),
                    100.0 * p.accuracy,
                    named.join("; "),
                    self.method
                )
            }
        }
    }
}

fn lead_width(widths: &[usize]) -> usize {
    widths.iter().map(|w| w + 2).sum()
}

fn unique(points: &[SweepPoint], j: usize) -> Vec<&str> {
    grid_axis(points.iter().map(|p| &p.values[..]), j)
}

/// A grid's axis: key `j`'s values in the order they first appear among
/// the points' values (the table's rows or columns, the heat map's too).
pub fn grid_axis<'a>(values: impl IntoIterator<Item = &'a [String]>, j: usize) -> Vec<&'a str> {
    let mut out: Vec<&str> = Vec::new();
    for vs in values {
        if let Some(v) = vs.get(j)
            && !out.contains(&v.as_str())
        {
            out.push(v);
        }
    }
    out
}
