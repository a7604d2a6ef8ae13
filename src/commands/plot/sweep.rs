//! `hapticlab plot sweep SWEEP.json`: the figure of `evaluate --sweep …
//! --json`. One swept key is a line of the pooled accuracy against its
//! values with the spread across folds; a two-key grid (two `--sweep`
//! flags) is a heat map, rows the first key's values and columns the
//! second's, each cell grey by its accuracy with the number written in, the
//! best outlined, points not evaluated left white. Reads the JSON only: the
//! figure can be drawn again without evaluating again.

use std::path::Path;

use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::{Area, Failure, GREYS, bad, fail, read_json, with_unit};

/// One point as the figure needs it.
pub struct Point {
    pub values: Vec<String>,
    /// Pooled accuracy, NaN when not evaluated.
    pub accuracy: f64,
    pub accuracy_std: f64,
    pub best: bool,
}

/// A sweep read from its JSON.
pub struct SweepFigure {
    pub keys: Vec<String>,
    pub method: String,
    pub points: Vec<Point>,
}

impl SweepFigure {
    /// Read `evaluate --sweep … --json` output (also the one-key JSON of
    /// earlier versions, without `keys`); more than two keys is bad input.
    pub fn load(path: &Path) -> Result<SweepFigure, Failure> {
        let v = read_json(path)?;
        let points = v["points"].as_array().ok_or_else(|| {
            bad(format!(
                "{}: no `points` (expected `evaluate --sweep … --json` output)",
                path.display()
            ))
        })?;
        let keys: Vec<String> = match v["keys"].as_array() {
            Some(k) => k
                .iter()
                .filter_map(|k| k.as_str().map(String::from))
                .collect(),
            None => vec![v["key"].as_str().unwrap_or("value").to_string()],
        };
        if keys.is_empty() || keys.len() > 2 {
            return Err(bad(format!(
                "{}: a sweep of {} keys; plot sweep draws one key (a line) or two (a heat map)",
                path.display(),
                keys.len()
            )));
        }
        let points: Vec<Point> = points
            .iter()
            .map(|p| Point {
                values: match p["values"].as_array() {
                    Some(vs) => vs
                        .iter()
                        .map(|v| v.as_str().unwrap_or("?").to_string())
                        .collect(),
                    None => vec![p["value"].as_str().unwrap_or("?").to_string()],
                },
                accuracy: p["accuracy"].as_f64().unwrap_or(f64::NAN),
                accuracy_std: p["accuracy_std"].as_f64().unwrap_or(0.0),
                best: p["best"].as_bool().unwrap_or(false),
            })
            .collect();
        if points.is_empty() {
            return Err(bad(format!("{}: the sweep has no points", path.display())));
        }
        // NaN stands for a point not evaluated; anything else must be a
        // share, or the axis would clamp it to 0 % or 100 % unseen.
        if let Some((i, p)) = points.iter().enumerate().find(|(_, p)| {
            !(p.accuracy.is_nan() || (0.0..=1.0).contains(&p.accuracy))
                || !(p.accuracy_std.is_finite() && (0.0..=1.0).contains(&p.accuracy_std))
        }) {
            return Err(bad(format!(
                "{}: points[{i}] ({}): accuracy {} ± {} is not a share from 0 to 1 \
                 (expected `evaluate --sweep … --json` output)",
                path.display(),
                p.values.join(", "),
                crate::profile::compact(p.accuracy),
                crate::profile::compact(p.accuracy_std)
            )));
        }
        if let Some(p) = points.iter().find(|p| p.values.len() != keys.len()) {
            return Err(bad(format!(
                "{}: a point has {} values for {} keys ({})",
                path.display(),
                p.values.len(),
                keys.len(),
                p.values.join(", ")
            )));
        }
        Ok(SweepFigure {
            keys,
            method: v["method"].as_str().unwrap_or("").to_string(),
            points,
        })
    }

    pub fn draw<DB: DrawingBackend>(&self, root: &Area<DB>) -> Result<(), Failure>
    where
        DB::ErrorType: 'static,
    {
        if self.keys.len() == 2 {
            self.draw_heat_map(root)
        } else {
            self.draw_line(root)
        }
    }

    /// Accuracy against the one swept key.
    fn draw_line<DB: DrawingBackend>(&self, root: &Area<DB>) -> Result<(), Failure>
    where
        DB::ErrorType: 'static,
    {
        let font = ("sans-serif", 18);
        let (key, method) = (&self.keys[0], &self.method);
        let points: Vec<(String, f64, f64)> = self
            .points
            .iter()
            .map(|p| (p.values[0].clone(), p.accuracy, p.accuracy_std))
            .collect();
        let n = points.len();
        let title = format!("Accuracy against {key} ({method})");
        let root = root.titled(&title, ("sans-serif", 20)).map_err(fail)?;
        let mut c = ChartBuilder::on(&root)
            .margin(20)
            .x_label_area_size(50)
            .y_label_area_size(70)
            .build_cartesian_2d(-0.5..(n as f64 - 0.5), 0.0..100.0)
            .map_err(fail)?;
        let names: Vec<String> = points.iter().map(|p| p.0.clone()).collect();
        c.configure_mesh()
            .light_line_style(WHITE)
            .x_labels(n.min(30))
            .x_label_formatter(&move |x| {
                let i = x.round();
                if (x - i).abs() < 1e-6 && i >= 0.0 {
                    names.get(i as usize).cloned().unwrap_or_default()
                } else {
                    String::new()
                }
            })
            .x_desc(with_unit(key))
            .y_desc("accuracy (%)")
            .label_style(font)
            .draw()
            .map_err(fail)?;
        // A value that could not be evaluated (NaN) is a cross on the axis.
        let missing: Vec<usize> = (0..n).filter(|&i| !points[i].1.is_finite()).collect();
        if !missing.is_empty() {
            c.draw_series(
                missing
                    .iter()
                    .map(|&i| Cross::new((i as f64, 0.0), 6, BLACK.stroke_width(2))),
            )
            .map_err(fail)?
            .label("not evaluated")
            .legend(|(x, y)| Cross::new((x + 10, y), 6, BLACK.stroke_width(2)));
        }
        let points: Vec<(usize, &(String, f64, f64))> = points
            .iter()
            .enumerate()
            .filter(|(_, p)| p.1.is_finite())
            .collect();
        c.draw_series(points.iter().map(|&(i, p)| {
            let sd = if p.2.is_finite() { p.2 } else { 0.0 };
            let (lo, hi) = (100.0 * (p.1 - sd), 100.0 * (p.1 + sd));
            PathElement::new(
                [(i as f64, lo.max(0.0)), (i as f64, hi.min(100.0))],
                GREYS[1].stroke_width(2),
            )
        }))
        .map_err(fail)?
        .label("± sd across folds")
        .legend(|(x, y)| {
            PathElement::new([(x + 10, y - 8), (x + 10, y + 8)], GREYS[1].stroke_width(2))
        });
        c.draw_series(LineSeries::new(
            points.iter().map(|&(i, p)| (i as f64, 100.0 * p.1)),
            BLACK.stroke_width(2),
        ))
        .map_err(fail)?
        .label("pooled accuracy")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 20, y)], BLACK.stroke_width(2)));
        c.draw_series(
            points
                .iter()
                .map(|&(i, p)| Circle::new((i as f64, 100.0 * p.1), 4, BLACK.filled())),
        )
        .map_err(fail)?;
        c.configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .background_style(WHITE.mix(0.9))
            .border_style(BLACK)
            .label_font(font)
            .draw()
            .map_err(fail)?;
        Ok(())
    }

    /// Rows the first key's values (top to bottom), columns the second's;
    /// greys spread from the lowest evaluated accuracy (lightest) to the
    /// highest (darkest), so small differences show.
    fn draw_heat_map<DB: DrawingBackend>(&self, root: &Area<DB>) -> Result<(), Failure>
    where
        DB::ErrorType: 'static,
    {
        let rows = unique(&self.points, 0);
        let cols = unique(&self.points, 1);
        let (nr, nc) = (rows.len(), cols.len());
        let cell = |r: &str, c: &str| {
            self.points
                .iter()
                .find(|p| p.values[0] == r && p.values[1] == c)
        };
        let scores: Vec<f64> = self
            .points
            .iter()
            .map(|p| p.accuracy)
            .filter(|a| a.is_finite())
            .collect();
        let lo = scores.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = scores.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let shade = |a: f64| {
            let frac = if hi > lo { (a - lo) / (hi - lo) } else { 0.5 };
            (235.0 - 190.0 * frac) as u8
        };
        let title = format!(
            "Accuracy over {} × {} ({})",
            self.keys[0], self.keys[1], self.method
        );
        let root = root.titled(&title, ("sans-serif", 20)).map_err(fail)?;
        let (w, h) = root.dim_in_pixel();
        let (chart, foot) = root.split_vertically(h.saturating_sub(30));
        let mut c = ChartBuilder::on(&chart)
            .margin(20)
            .x_label_area_size(60)
            .y_label_area_size(110)
            .build_cartesian_2d(
                (0..nc.saturating_sub(1)).into_segmented(),
                (0..nr.saturating_sub(1)).into_segmented(),
            )
            .map_err(fail)?;
        let (xl, yl) = (
            cols.iter().map(|s| s.to_string()).collect::<Vec<_>>(),
            rows.iter().map(|s| s.to_string()).collect::<Vec<_>>(),
        );
        c.configure_mesh()
            .disable_mesh()
            .x_labels(nc + 1)
            .y_labels(nr + 1)
            .x_label_formatter(&move |v| match v {
                SegmentValue::CenterOf(i) => xl.get(*i).cloned().unwrap_or_default(),
                _ => String::new(),
            })
            // The first row on top, as in the table.
            .y_label_formatter(&move |v| match v {
                SegmentValue::CenterOf(i) if *i < nr => yl[nr - 1 - *i].clone(),
                _ => String::new(),
            })
            .x_desc(with_unit(&self.keys[1]))
            .y_desc(with_unit(&self.keys[0]))
            .label_style(("sans-serif", 16))
            .draw()
            .map_err(fail)?;
        // Numbers small enough to fit their cell.
        let cell_px = (w.saturating_sub(170) / nc.max(1) as u32).min(h / nr.max(1) as u32);
        let size = (cell_px / 5).clamp(9, 20);
        for (i, r) in rows.iter().enumerate() {
            for (j, col) in cols.iter().enumerate() {
                let y = nr - 1 - i;
                let corners = [
                    (SegmentValue::Exact(j), SegmentValue::Exact(y)),
                    (SegmentValue::Exact(j + 1), SegmentValue::Exact(y + 1)),
                ];
                let p = cell(r, col);
                let (fill, text, text_colour) = match p {
                    Some(p) if p.accuracy.is_finite() => {
                        let g = shade(p.accuracy);
                        let mark = if p.best { " *" } else { "" };
                        (
                            RGBColor(g, g, g),
                            format!("{:.1}{mark}", 100.0 * p.accuracy),
                            if g < 128 { WHITE } else { BLACK },
                        )
                    }
                    Some(_) => (WHITE, "not evaluated".to_string(), GREYS[1]),
                    None => (WHITE, String::new(), BLACK),
                };
                c.draw_series(std::iter::once(Rectangle::new(
                    corners.clone(),
                    fill.filled(),
                )))
                .map_err(fail)?;
                c.draw_series(std::iter::once(Rectangle::new(
                    corners.clone(),
                    GREYS[2].stroke_width(1),
                )))
                .map_err(fail)?;
                if p.is_some_and(|p| p.best) {
                    c.draw_series(std::iter::once(Rectangle::new(
                        corners,
                        BLACK.stroke_width(4),
                    )))
                    .map_err(fail)?;
                }
                let style = ("sans-serif", size)
                    .into_font()
                    .color(&text_colour)
                    .pos(Pos::new(HPos::Center, VPos::Center));
                c.draw_series(std::iter::once(Text::new(
                    text,
                    (SegmentValue::CenterOf(j), SegmentValue::CenterOf(y)),
                    style,
                )))
                .map_err(fail)?;
            }
        }
        let any_best = self.points.iter().any(|p| p.best);
        let scale = if scores.is_empty() {
            "no point was evaluated".to_string()
        } else {
            let greys = if hi > lo {
                format!(
                    "grey from {:.1} % (lightest) to {:.1} % (darkest)",
                    100.0 * lo,
                    100.0 * hi
                )
            } else {
                format!("every evaluated point gives {:.1} %", 100.0 * hi)
            };
            let best = if any_best {
                "* best (outlined)"
            } else {
                "no best: every point ties"
            };
            format!("accuracy (%) pooled over the folds; {greys}; {best}")
        };
        foot.draw(&Text::new(
            scale,
            (20, 5),
            ("sans-serif", 15).into_font().color(&BLACK),
        ))
        .map_err(fail)?;
        Ok(())
    }
}

/// Key `j`'s values in the order they first appear.
fn unique(points: &[Point], j: usize) -> Vec<&str> {
    crate::evaluate::sweep::grid_axis(points.iter().map(|p| &p.values[..]), j)
}
