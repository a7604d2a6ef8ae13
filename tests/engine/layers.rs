//! The engine crate's walls, checked: it depends on none of the front ends'
//! crates, never prints or ends the process, and each of its modules
//! imports only modules of lower layers (so no import cycle can form).
//! Adding `clap` to engine/Cargo.toml, or a `use crate::evaluate` in
//! `device/`, fails here.

use std::path::{Path, PathBuf};

/// The front ends' crates: the engine must not know them.
const FRONT_END_CRATES: [&str; 4] = ["clap", "ratatui", "crossterm", "indicatif"];

/// The engine's top-level modules by layer: a module may import its own
/// layer's ground modules listed before it and any module of a lower layer.
/// Written as in engine/src/lib.rs's doc comment.
const LAYERS: [&[&str]; 8] = [
    &["version", "io", "recording", "profile", "folds"],
    &["clock", "analysis", "triggers", "recorder", "import"],
    &["device", "classify"],
    &["dataset", "servo"],
    &["predictor"],
    &["acquire"],
    &["evaluate"],
    &["tune"],
];

fn engine() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("engine")
}

fn layer_of(module: &str) -> Option<usize> {
    LAYERS.iter().position(|l| l.contains(&module))
}

/// Every product source file of the engine with its top-level module:
/// test files (`tests.rs`, `tests/`) are left out, and a file's inline
/// `#[cfg(test)]` module is cut off by [`product_lines`].
fn product_files() -> Vec<(String, PathBuf)> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                if p.file_name().unwrap() != "tests" {
                    walk(&p, out);
                }
            } else if p.extension().is_some_and(|x| x == "rs")
                && p.file_name().unwrap() != "tests.rs"
            {
                out.push(p);
            }
        }
    }
    let src = engine().join("src");
    let mut files = Vec::new();
    walk(&src, &mut files);
    files.sort();
    files
        .into_iter()
        .filter(|p| p.file_name().unwrap() != "lib.rs")
        .map(|p| {
            let first = p.strip_prefix(&src).unwrap().components().next().unwrap();
            let name = first.as_os_str().to_str().unwrap();
            (name.trim_end_matches(".rs").to_string(), p)
        })
        .collect()
}

/// The file's lines up to its `#[cfg(test)]` module, comments left out.
fn product_lines(path: &Path) -> Vec<(usize, String)> {
    let text = std::fs::read_to_string(path).unwrap();
    text.lines()
        .enumerate()
        .take_while(|(_, l)| l.trim() != "#[cfg(test)]")
        .filter(|(_, l)| !l.trim_start().starts_with("//"))
        .map(|(i, l)| (i + 1, l.to_string()))
        .collect()
}

#[test]
fn the_engine_depends_on_no_front_end_crate() {
    let manifest = std::fs::read_to_string(engine().join("Cargo.toml")).unwrap();
    let manifest: toml::Table = manifest.parse().unwrap();
    for section in ["dependencies", "dev-dependencies", "build-dependencies"] {
        let Some(deps) = manifest.get(section).and_then(|d| d.as_table()) else {
            continue;
        };
        for name in deps.keys() {
            assert!(
                !FRONT_END_CRATES.contains(&name.as_str()),
                "engine/Cargo.toml [{section}] has {name}: the engine must not know a front end's crate"
            );
        }
    }
}

#[test]
fn every_engine_module_has_a_layer() {
    let lib = std::fs::read_to_string(engine().join("src/lib.rs")).unwrap();
    for line in lib.lines() {
        if let Some(m) = line.strip_prefix("pub mod ") {
            let m = m.trim_end_matches(';');
            assert!(
                layer_of(m).is_some(),
                "engine module {m} is in no layer of tests/engine/layers.rs"
            );
        }
    }
}

#[test]
fn engine_modules_import_only_lower_layers() {
    let mut wrong = Vec::new();
    for (module, path) in product_files() {
        let own = layer_of(&module).unwrap_or_else(|| panic!("{module} has no layer"));
        for (n, line) in product_lines(&path) {
            for (at, _) in line.match_indices("crate::") {
                let rest = &line[at + "crate::".len()..];
                let used: String = rest
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                if used == module || used.is_empty() {
                    continue;
                }
                let ok = match layer_of(&used) {
                    Some(l) if l < own => true,
                    // Within the same layer only the ground may be used by its
                    // neighbour, in the table's order (profile uses recording).
                    Some(l) if l == own => {
                        let row = LAYERS[l];
                        let pos = |m: &str| row.iter().position(|x| *x == m);
                        l == 0 && pos(&used) < pos(&module)
                    }
                    _ => false,
                };
                if !ok {
                    wrong.push(format!("{}:{n}: {module} imports {used}", path.display()));
                }
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "imports against the layers:\n{}",
        wrong.join("\n")
    );
}

#[test]
fn the_engine_never_prints_nor_ends_the_process() {
    let mut wrong = Vec::new();
    for (_, path) in product_files() {
        for (n, line) in product_lines(&path) {
            for banned in [
                "println!",
                "eprintln!",
                "print!(",
                "eprint!(",
                "process::exit",
            ] {
                if line.contains(banned) {
                    wrong.push(format!("{}:{n}: {}", path.display(), line.trim()));
                }
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "the engine prints or exits:\n{}",
        wrong.join("\n")
    );
}
