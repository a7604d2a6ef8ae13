//! The one label rule. A label is a texture's name, and it names a folder
//! (`recordings/<set>/<label>/`) and a column of `inspect`'s table, so the
//! profile's textures, `import --label`, the console's label entry and the
//! reader of every recording check it here.

/// A label names a folder: 1 to 64 characters, none of them a control
/// character or a path separator (`/`, `\`), not starting with `.` (so
/// never `.`, `..` or a hidden folder). Spaces and letters of any script are
/// fine inside ("cork board", "Cartón"), not at either end (a blank label
/// would name a folder " ").
pub fn check_label(label: &str) -> Result<(), String> {
    let chars = label.chars().count();
    if chars == 0 || chars > 64 {
        return Err(format!("label {label:?} must have 1 to 64 characters"));
    }
    if label.trim() != label {
        // A blank label, or one that differs from another by a space, reads
        // the same to a person and names a different folder.
        return Err(format!(
            "label {label:?} must not start or end with a space"
        ));
    }
    if label.starts_with('.') {
        return Err(format!("label {label:?} must not start with '.'"));
    }
    if label.chars().any(char::is_control) {
        return Err(format!("label {label:?} must not hold a control character"));
    }
    if label.contains(['/', '\\']) {
        return Err(format!(
            "label {label:?} must not hold a path separator ('/' or '\\'): it names a folder"
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
        assert!(check_label(" ").is_err());
        assert!(check_label("S2 ").is_err());
        assert!(check_label("S 2").is_ok());
        assert!(check_label(".hidden").is_err());
        assert!(check_label("S\n2").is_err());
        assert!(check_label("S\t2").is_err());
        assert!(check_label("S\u{7f}2").is_err());
        assert!(check_label("cork board").is_ok());
        assert!(check_label("Cartón").is_ok());
        assert!(check_label(&"x".repeat(64)).is_ok());
        assert!(check_label(&"x".repeat(65)).is_err());
    }
}
