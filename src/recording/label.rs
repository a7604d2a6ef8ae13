//! The one label rule. A label is a texture's name, and it names a folder
//! (`recordings/<set>/<label>/`) and a column of `inspect`'s table, so the
//! profile's textures, `import --label`, the console's label entry and the
//! reader of every recording check it here.

/// A label is used as a folder name: 1 to 64 letters, digits, `-`, `_` and
/// `.`, not starting with `.`. So it is never empty, holds no control
/// character, no path separator and no `..`.
pub fn check_label(label: &str) -> Result<(), String> {
    if label.is_empty() || label.len() > 64 {
        return Err(format!("label {label:?} must have 1 to 64 characters"));
    }
    if label.starts_with('.') {
        return Err(format!("label {label:?} must not start with '.'"));
    }
    if !label
        .chars()
        .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_' || c == '.')
    {
        return Err(format!(
            "label {label:?} may hold only letters, digits, '-', '_' and '.' (it names a folder)"
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_must_be_safe_file_names() {
        assert!(check_label("S2").is_ok());
        assert!(check_label("S-2_b.v1").is_ok());
        assert!(check_label("../etc").is_err());
        assert!(check_label("a/b").is_err());
        assert!(check_label("a\\b").is_err());
        assert!(check_label("").is_err());
        assert!(check_label(".hidden").is_err());
        assert!(check_label("S\n2").is_err());
        assert!(check_label("S\t2").is_err());
    }
}
