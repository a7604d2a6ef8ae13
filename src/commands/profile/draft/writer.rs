//! The TOML writer of `profile new`, built from the option list
//! (`crate::profile::options`): the `[analysis]` lines group by group in
//! the list's order, each with the draft's reason or else the option's
//! advice, every group followed by its commented alternatives; the
//! `[classifier]` lines in the list's order, their values as the options
//! write them; the commented option groups of every table; and the reading
//! back of those groups ([`groups_of`]) and their putting in place
//! ([`apply_group`]).

use std::fmt::Write as _;

use crate::profile::Classifier;
pub use crate::profile::fitted::{ceil3, float, floor3};

/// A measured number for people, in a comment: six significant digits at
/// most (`1.999`, not the `1.9989999999999988` a difference of sample
/// times gives), written as TOML would (`1000.0`).
pub fn shown(x: f64) -> String {
    float(crate::profile::fitted::significant(x, 6))
}
use crate::profile::options::{ANALYSIS_OPTIONS, CLASSIFIER_OPTIONS, Group, in_group, option};

/// `text` broken at spaces into lines of at most `width` characters (a
/// word longer than that stands alone), for a comment.
pub fn wrap(text: &str, width: usize) -> String {
    let mut out = String::new();
    let mut line = 0;
    for word in text.split(' ').filter(|w| !w.is_empty()) {
        if line > 0 && line + 1 + word.chars().count() > width {
            out.push('\n');
            line = 0;
        } else if line > 0 {
            out.push(' ');
            line += 1;
        }
        out.push_str(word);
        line += word.chars().count();
    }
    out
}

/// One `key = value` line, with why it was chosen (a trailing comment;
/// `None`: an `[analysis]` option's advice) and a comment above it.
pub struct Line {
    pub key: &'static str,
    pub value: String,
    pub why: Option<String>,
    pub above: Option<String>,
}

/// A line with the reason it was chosen.
pub fn line(key: &'static str, value: impl Into<String>, why: impl Into<String>) -> Line {
    Line {
        key,
        value: value.into(),
        why: Some(why.into()),
        above: None,
    }
}

/// A line whose comment is its option's advice.
pub fn advised(key: &'static str, value: impl Into<String>) -> Line {
    Line {
        key,
        value: value.into(),
        why: None,
        above: None,
    }
}

impl Line {
    /// The line with a comment above it.
    pub fn below(mut self, comment: impl Into<String>) -> Line {
        self.above = Some(comment.into());
        self
    }
}

/// One commented option group: what it is for, and its `key = value` lines.
pub struct OptionGroup {
    pub when: String,
    pub keys: Vec<(&'static str, String)>,
}

/// What follows a group of `[analysis]` lines: an introduction and the
/// commented option groups, or why none is offered.
pub struct Alternatives {
    pub intro: Option<&'static str>,
    pub groups: Result<Vec<OptionGroup>, String>,
}

/// The keys a spectrum group replaces: every option of the spectrum group
/// (the group sets the spectrum anew).
pub fn spectrum_keys() -> impl Iterator<Item = &'static str> {
    in_group(Group::Spectrum).map(|o| o.field())
}

/// Where an `[analysis]` key stands in the option list (others last).
fn rank(key: &str) -> usize {
    ANALYSIS_OPTIONS
        .iter()
        .position(|o| o.field() == key)
        .unwrap_or(usize::MAX)
}

/// The TOML text being written: tables, commented lines, option groups.
#[derive(Default)]
pub struct Doc(pub String);

impl Doc {
    pub fn comment(&mut self, text: &str) {
        for l in text.lines() {
            let _ = writeln!(self.0, "# {l}");
        }
    }
    pub fn blank(&mut self) {
        self.0.push('\n');
    }
    /// One blank line before what follows, however the text ends.
    fn gap(&mut self) {
        if !self.0.ends_with("\n\n") {
            self.blank();
        }
    }
    pub fn table(&mut self, name: &str) {
        let _ = writeln!(self.0, "[{name}]");
    }
    pub fn lines(&mut self, lines: &[Line]) {
        for l in lines {
            if let Some(above) = &l.above {
                self.comment(above);
            }
            let why = l
                .why
                .as_deref()
                .or_else(|| option(l.key).map(|o| o.advice))
                .unwrap_or("");
            if why.is_empty() {
                let _ = writeln!(self.0, "{} = {}", l.key, l.value);
            } else {
                let _ = writeln!(self.0, "{} = {}   # {why}", l.key, l.value);
            }
        }
    }
    pub fn groups(&mut self, groups: &[OptionGroup]) {
        for g in groups {
            let _ = writeln!(self.0, "# -- {}", g.when);
            for (k, v) in &g.keys {
                let _ = writeln!(self.0, "# {k} = {v}");
            }
            self.blank();
        }
    }

    /// The `[analysis]` table from the option list: each group of options
    /// in turn (its title, its lines in list order, then `alternatives`
    /// for it); a group with neither lines nor alternatives is left out.
    pub fn analysis(
        &mut self,
        preamble: &str,
        mut lines: Vec<Line>,
        mut alternatives: Vec<(Group, Alternatives)>,
    ) {
        self.table("analysis");
        self.comment(preamble);
        lines.sort_by_key(|l| rank(l.key));
        for group in Group::ALL {
            let mine: Vec<Line> = lines
                .extract_if(.., |l| option(l.key).is_some_and(|o| o.group == group))
                .collect();
            let alt = alternatives
                .iter()
                .position(|(g, _)| *g == group)
                .map(|i| alternatives.remove(i).1);
            if mine.is_empty() && alt.is_none() {
                continue;
            }
            self.gap();
            self.comment(&format!("{}.", group.title()));
            self.lines(&mine);
            if let Some(alt) = alt {
                if !mine.is_empty() {
                    self.gap();
                }
                if let Some(intro) = alt.intro {
                    self.comment(intro);
                }
                match alt.groups {
                    Ok(mut groups) => {
                        for g in &mut groups {
                            g.keys.sort_by_key(|(k, _)| rank(k));
                        }
                        self.groups(&groups);
                    }
                    Err(why) => {
                        self.comment(&format!("(none offered: {why})"));
                        self.blank();
                    }
                }
            }
        }
        // A key of no group (none today) is still written.
        self.lines(&lines);
        self.gap();
    }
}

impl Doc {
    /// The `[classifier]` table from the option list: a line for each
    /// option the draft gives a reason for (`why`), in list order, its
    /// value as the option writes `c`'s; then the commented option groups,
    /// their keys in list order.
    pub fn classifier(
        &mut self,
        c: &Classifier,
        why: &[(&'static str, &str)],
        mut groups: Vec<OptionGroup>,
    ) {
        self.table("classifier");
        let lines: Vec<Line> = CLASSIFIER_OPTIONS
            .iter()
            .filter_map(|o| {
                let (_, why) = why.iter().find(|(k, _)| *k == o.field())?;
                Some(line(o.field(), o.written(c)?, *why))
            })
            .collect();
        debug_assert_eq!(
            lines.len(),
            why.len(),
            "a reason for no [classifier] option"
        );
        self.lines(&lines);
        self.blank();
        let rank = |key: &str| CLASSIFIER_OPTIONS.iter().position(|o| o.field() == key);
        for g in &mut groups {
            g.keys.sort_by_key(|(k, _)| rank(k));
        }
        self.groups(&groups);
    }
}

/// The option groups of a drafted profile: (table, key lines).
pub fn groups_of(text: &str) -> Vec<(String, Vec<(String, String)>)> {
    let mut out = Vec::new();
    let mut table = String::new();
    let mut current: Option<Vec<(String, String)>> = None;
    for line in text.lines() {
        if let Some(t) = line.strip_prefix('[') {
            table = t.trim_end_matches(']').to_string();
        }
        if line.starts_with("# -- ") {
            if let Some(g) = current.take() {
                out.push((table.clone(), g));
            }
            current = Some(Vec::new());
            continue;
        }
        match (
            line.strip_prefix("# ").and_then(|l| l.split_once(" = ")),
            &mut current,
        ) {
            (Some((k, v)), Some(g)) if !k.contains(' ') => g.push((k.to_string(), v.to_string())),
            (_, Some(_)) => {
                if let Some(g) = current.take() {
                    out.push((table.clone(), g));
                }
            }
            _ => {}
        }
    }
    if let Some(g) = current {
        out.push((table, g));
    }
    out
}

/// The profile `text` with an option group in place: its keys set in
/// `table`; a spectrum group first removes every spectrum key, an
/// evaluation group with a `method` the whole `[evaluation]`.
pub fn apply_group(text: &str, table: &str, keys: &[(String, String)]) -> Result<String, String> {
    let mut doc: toml::Table = toml::from_str(text).map_err(|e| e.to_string())?;
    let t = doc
        .get_mut(table)
        .and_then(|v| v.as_table_mut())
        .ok_or_else(|| format!("no [{table}]"))?;
    // A spectrum or another family replaces every spectrum line.
    if keys.iter().any(|(k, _)| k == "spectrum" || k == "features") {
        t.retain(|k, _| spectrum_keys().all(|s| s != k));
    }
    if table == "evaluation" && keys.iter().any(|(k, _)| k == "method") {
        t.clear();
    }
    for (k, v) in keys {
        let parsed: toml::Table =
            toml::from_str(&format!("v = {v}")).map_err(|e| format!("{k} = {v}: {e}"))?;
        t.insert(k.clone(), parsed["v"].clone());
    }
    toml::to_string(&doc).map_err(|e| e.to_string())
}
