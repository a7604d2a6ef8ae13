//! Where a key is written in a profile's text: the line and column that
//! every refusal names. Pure text scanning; no TOML parsing.

use std::collections::BTreeMap;

/// 1-based line and column of a byte offset.
pub fn line_col(text: &str, offset: usize) -> (Option<usize>, Option<usize>) {
    let offset = offset.min(text.len());
    let before = &text[..offset];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (Some(line), Some(col))
}

/// Find where a dotted key such as `path.waypoints_m[2]` or
/// `textures[1].surface.depth_m` is written, by scanning the table headers
/// and keys. Good for the layouts TOML is normally written in; `None` when
/// the key is not written (a default value) or written in another style.
pub fn locate_key(text: &str, key: &str) -> (Option<usize>, Option<usize>) {
    // Split "a.b[2].c" into segments with optional indices.
    let segments: Vec<(String, Option<usize>)> = key
        .split('.')
        .map(|s| match s.find('[') {
            Some(i) => (s[..i].to_string(), s[i + 1..s.len() - 1].parse().ok()),
            None => (s.to_string(), None),
        })
        .collect();
    // The table path is everything but the last segment (with array-of-table indices).
    let (last, table) = segments.split_last().expect("a key has a segment");
    let mut table_names: Vec<&str> = table.iter().map(|(n, _)| n.as_str()).collect();
    let mut counters: BTreeMap<String, usize> = BTreeMap::new();
    let mut current: Vec<String> = Vec::new();
    let mut current_idx: Vec<Option<usize>> = Vec::new();
    let want_idx: Vec<Option<usize>> = table.iter().map(|(_, i)| *i).collect();
    let mut fallback: (Option<usize>, Option<usize>) = (None, None);
    // Open brackets of a multi-line value being skipped.
    let mut depth: i64 = 0;
    for (ln, raw) in text.lines().enumerate() {
        let line = raw.trim_start();
        let indent = raw.len() - line.len();
        let code = line.split('#').next().unwrap_or("");
        if depth > 0 {
            depth += code.matches('[').count() as i64 - code.matches(']').count() as i64;
            continue;
        }
        if let Some(rest) = line.strip_prefix("[[") {
            let name = rest.split("]]").next().unwrap_or("").trim().to_string();
            let c = counters.entry(name.clone()).or_insert(0);
            let idx = *c;
            *c += 1;
            current = name.split('.').map(|s| s.trim().to_string()).collect();
            current_idx = vec![None; current.len()];
            if let Some(l) = current_idx.last_mut() {
                *l = Some(idx);
            }
            continue;
        }
        if let Some(rest) = line.strip_prefix('[') {
            let name = rest.split(']').next().unwrap_or("").trim().to_string();
            current = name.split('.').map(|s| s.trim().to_string()).collect();
            current_idx = vec![None; current.len()];
            // A sub-table of an array of tables refers to its latest element.
            for (i, seg) in current.iter().enumerate() {
                let prefix = current[..=i].join(".");
                if let Some(c) = counters.get(&prefix) {
                    let _ = seg;
                    current_idx[i] = Some(c.saturating_sub(1));
                }
            }
            continue;
        }
        // key = value, possibly a dotted key or an inline table.
        let Some(eq) = line.find('=') else { continue };
        let value = code.get(eq + 1..).unwrap_or("");
        depth = value.matches('[').count() as i64 - value.matches(']').count() as i64;
        let k = line[..eq].trim();
        let mut path: Vec<String> = current.clone();
        let mut pidx = current_idx.clone();
        for part in k.split('.') {
            path.push(part.trim().trim_matches('"').to_string());
            pidx.push(None);
        }
        let names_match = |upto: usize| -> bool {
            path.len() >= upto
                && path[..upto]
                    .iter()
                    .map(String::as_str)
                    .eq(table_names.iter().copied())
                && pidx[..upto]
                    .iter()
                    .zip(want_idx.iter())
                    .all(|(have, want)| want.is_none() || have == want)
        };
        let col = indent + 1;
        if names_match(table_names.len())
            && path.len() == table_names.len() + 1
            && path.last().map(String::as_str) == Some(last.0.as_str())
        {
            // An element of a multi-line array: the Nth line after the key that opens an element.
            if let Some(index) = last.1 {
                let rest = line[eq + 1..].trim();
                if rest == "[" {
                    let mut seen = 0;
                    for (j, next) in text.lines().enumerate().skip(ln + 1) {
                        let t = next.trim_start();
                        if t.starts_with(']') {
                            break;
                        }
                        if t.starts_with('[')
                            || t.starts_with(|c: char| c.is_ascii_digit() || c == '-' || c == '"')
                        {
                            if seen == index {
                                return (Some(j + 1), Some(next.len() - t.len() + 1));
                            }
                            seen += 1;
                        }
                    }
                }
            }
            return (Some(ln + 1), Some(col));
        }
        // An inline table holding the key: `surface = { kind = ..., depth_m = ... }`.
        if table_names.len() == path.len() && names_match(path.len()) {
            if let Some(pos) = line
                .find(&format!("{} ", last.0))
                .or_else(|| line.find(&format!("{}=", last.0)))
            {
                return (Some(ln + 1), Some(indent + pos + 1));
            }
            fallback = (Some(ln + 1), Some(col));
        }
        // The table itself, when the key is absent: point at its header's first key.
        if fallback.0.is_none() && names_match(table_names.len()) && !table_names.is_empty() {
            fallback = (Some(ln + 1), Some(col));
        }
    }
    table_names.clear();
    fallback
}

/// A duplicate key that TOML's parser reports at `offset` (its second
/// writing), said in full: the parser's message names no key, so the key
/// is read from the text there (dotted with its table) and quoted with
/// where it was first written. `None` when the text there is no key line.
pub fn duplicate_key(text: &str, offset: usize) -> Option<(String, String)> {
    let start = text.get(..offset)?.rfind('\n').map_or(0, |i| i + 1);
    let line = text[start..].lines().next()?.trim();
    let table = text[..start]
        .lines()
        .rev()
        .map(str::trim)
        .find(|l| l.starts_with('['))
        .map(|l| l.trim_matches(['[', ']']).trim());
    if line.starts_with('[') {
        // A table written twice: point at its first header.
        let first = text.lines().position(|l| l.trim() == line)? + 1;
        return Some((
            line.trim_matches(['[', ']']).trim().to_string(),
            format!(
                "the table `{line}` is written twice (first at line {first}); merge them into one"
            ),
        ));
    }
    let (key, _) = line.split_once('=')?;
    let key = key.trim().trim_matches('"');
    let (dotted, place) = match table {
        Some(t) if !t.is_empty() => (format!("{t}.{key}"), format!("[{t}]")),
        _ => (key.to_string(), "the top of the file".to_string()),
    };
    let first = match locate_key(text, &dotted) {
        (Some(l), _) if l != line_col(text, offset).0.unwrap_or(0) => {
            let earlier = text.lines().nth(l - 1).unwrap_or("").trim();
            format!(" (first as `{earlier}` at line {l})")
        }
        _ => String::new(),
    };
    Some((
        dotted,
        format!("duplicate key: `{line}` is a second `{key}` in {place}{first}; keep one of them"),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locates_keys() {
        let text = "name = \"x\"\n[path]\nspeed_m_per_s = 1\n[[textures]]\nlabel = \"a\"\n[[textures]]\nlabel = \"b\"\nsurface = { kind = \"sine\", period_m = 0 }\n";
        assert_eq!(locate_key(text, "path.speed_m_per_s"), (Some(3), Some(1)));
        assert_eq!(locate_key(text, "textures[1].label"), (Some(7), Some(1)));
        assert_eq!(locate_key(text, "textures[1].surface.period_m").0, Some(8));
    }
}
