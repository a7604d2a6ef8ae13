//! The profile-key reference (`docs/reference/profile-keys.md`), rendered
//! from the one list of options, so the page cannot drift from the code.
//! Only text: the front end's test compares it with the committed page.

use super::{ANALYSIS_OPTIONS, CLASSIFIER_OPTIONS, Group, Kind};
use crate::profile::LoadedProfile;

/// The command that writes the page again after an option changes.
pub const REGENERATE: &str = "HAPTICLAB_BLESS=1 cargo test --test cli docs::profile_keys";

fn kind(k: Kind) -> &'static str {
    match k {
        Kind::Text => "text",
        Kind::Number => "number",
        Kind::Integer => "integer",
        Kind::Flag => "true / false",
        Kind::Choice => "one of",
        Kind::Pair => "[a, b]",
        Kind::List => "list",
        Kind::Table => "table",
    }
}

/// A markdown table cell: pipes escaped, values as code.
fn cell(text: &str) -> String {
    text.replace('|', "\\|")
}

fn code_list(values: &[&str]) -> String {
    values
        .iter()
        .map(|v| format!("`{}`", cell(v)))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Words are listed as code, descriptions as text.
fn allowed(kind: Kind, values: &[&str]) -> String {
    match kind {
        Kind::Choice | Kind::Flag => code_list(values),
        _ => values
            .iter()
            .map(|v| cell(v))
            .collect::<Vec<_>>()
            .join("; "),
    }
}

fn yes(b: bool) -> &'static str {
    if b { "yes" } else { "no" }
}

fn searched(values: &[&str]) -> String {
    if values.is_empty() {
        "—".into()
    } else {
        code_list(values)
    }
}

/// The whole page, as `docs/reference/profile-keys.md` holds it.
pub fn profile_keys_markdown() -> String {
    let thesis = LoadedProfile::thesis().profile;
    let mut out = String::new();
    out.push_str("# Profile keys: `[analysis]` and `[classifier]`\n\n");
    out.push_str(
        "Generated from the one list of options (`ANALYSIS_OPTIONS` and \
         `CLASSIFIER_OPTIONS` in `engine/src/profile/options.rs`); do not edit \
         by hand. After changing an option, write it again with\n\n",
    );
    out.push_str(&format!("```\n{REGENERATE}\n```\n\n"));
    out.push_str(
        "What the options compute: [profiles.md](profiles.md). **thesis** is the \
         built-in thesis profile's value (`none`: left out). **sweep**: \
         `evaluate --sweep` may vary it. **model**: a model trained under \
         another value does not fit a profile with this one. **tune \
         searches**: the values `tune` tries, simplest first (`points/4`: the \
         largest power of two within a quarter of the (sub-)window's points; \
         `window/4`: sub-windows a quarter of the window). Units: `axis` is \
         the analysis axis's unit (m along a position column, s along `t_s`).\n",
    );
    out.push_str("\n## `[analysis]`\n");
    for group in Group::ALL {
        out.push_str(&format!("\n### {}\n\n", group.title()));
        out.push_str(
            "| key | kind | values | unit | thesis | sweep | model | tune searches | advice |\n\
             |---|---|---|---|---|---|---|---|---|\n",
        );
        for o in ANALYSIS_OPTIONS.iter().filter(|o| o.group == group) {
            out.push_str(&format!(
                "| `{}` | {} | {} | {} | `{}` | {} | {} | {} | {} |\n",
                o.name,
                kind(o.kind),
                allowed(o.kind, o.allowed),
                if o.unit.is_empty() { "—" } else { o.unit },
                cell(&o.text(&thesis.analysis)),
                yes(o.sweepable),
                yes(o.changes_features),
                searched(o.search),
                cell(o.advice),
            ));
        }
    }
    out.push_str("\n## `[classifier]`\n\n");
    out.push_str(
        "| key | kind | values | thesis | tune searches | advice |\n\
         |---|---|---|---|---|---|\n",
    );
    for o in CLASSIFIER_OPTIONS {
        out.push_str(&format!(
            "| `{}` | {} | {} | `{}` | {} | {} |\n",
            o.name,
            kind(o.kind),
            allowed(o.kind, o.allowed),
            cell(&o.text(&thesis.classifier)),
            searched(o.search),
            cell(o.advice),
        ));
    }
    out
}
