//! The criterion half of BENCHMARKS.md: one Markdown row per benchmark that
//! `cargo bench` has measured, read from criterion's own estimates
//! (`target/criterion/**/new/{benchmark,estimates}.json`): the median time per
//! iteration, its spread (median absolute deviation), the 95 % confidence
//! interval of the median, and the throughput where the bench declares one.
//!
//! cargo bench && cargo run --release --example bench_report

use std::path::{Path, PathBuf};

use serde_json::Value;

fn main() {
    let root = std::env::args()
        .nth(1)
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            let target = std::env::var_os("CARGO_TARGET_DIR").map_or_else(
                || Path::new(env!("CARGO_MANIFEST_DIR")).join("target"),
                PathBuf::from,
            );
            target.join("criterion")
        });
    let mut found = Vec::new();
    find(&root, &mut found);
    if found.is_empty() {
        eprintln!(
            "bench_report: no criterion results under {}: run `cargo bench` first",
            root.display()
        );
        std::process::exit(1);
    }
    found.sort();
    println!(
        "| benchmark | median | spread (MAD) | 95 % CI of the median | throughput at the median |"
    );
    println!("|---|---|---|---|---|");
    for dir in found {
        match row(&dir) {
            Ok(r) => println!("{r}"),
            Err(e) => eprintln!("bench_report: {}: {e}", dir.display()),
        }
    }
}

/// Every `new/` folder holding both files.
fn find(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if !p.is_dir() {
            continue;
        }
        if p.file_name().is_some_and(|n| n == "new")
            && p.join("estimates.json").is_file()
            && p.join("benchmark.json").is_file()
        {
            out.push(p);
        } else {
            find(&p, out);
        }
    }
}

fn read(path: &Path) -> Result<Value, String> {
    let text = std::fs::read_to_string(path).map_err(|e| e.to_string())?;
    serde_json::from_str(&text).map_err(|e| e.to_string())
}

fn row(dir: &Path) -> Result<String, String> {
    let bench = read(&dir.join("benchmark.json"))?;
    let est = read(&dir.join("estimates.json"))?;
    let num = |v: &Value, path: &[&str]| -> Result<f64, String> {
        path.iter()
            .try_fold(v, |v, k| v.get(k))
            .and_then(Value::as_f64)
            .ok_or_else(|| format!("no {} in the estimates", path.join(".")))
    };
    let median = num(&est, &["median", "point_estimate"])?;
    let lo = num(&est, &["median", "confidence_interval", "lower_bound"])?;
    let hi = num(&est, &["median", "confidence_interval", "upper_bound"])?;
    let mad = num(&est, &["median_abs_dev", "point_estimate"])?;
    let id = bench
        .get("full_id")
        .and_then(Value::as_str)
        .unwrap_or("?")
        .to_string();
    let throughput = match bench.get("throughput") {
        Some(Value::Object(t)) => {
            if let Some(b) = t.get("Bytes").and_then(Value::as_f64) {
                format!("{:.0} MiB/s", b / (median * 1e-9) / (1024.0 * 1024.0))
            } else if let Some(n) = t.get("Elements").and_then(Value::as_f64) {
                format!("{:.3e} elements/s", n / (median * 1e-9))
            } else {
                String::new()
            }
        }
        _ => String::new(),
    };
    Ok(format!(
        "| {id} | {} | ± {} ({:.1} %) | {} – {} | {throughput} |",
        time(median),
        time(mad),
        100.0 * mad / median,
        time(lo),
        time(hi)
    ))
}

/// Nanoseconds in the unit people read.
fn time(ns: f64) -> String {
    if ns >= 1e9 {
        format!("{:.3} s", ns * 1e-9)
    } else if ns >= 1e6 {
        format!("{:.3} ms", ns * 1e-6)
    } else if ns >= 1e3 {
        format!("{:.2} µs", ns * 1e-3)
    } else {
        format!("{ns:.0} ns")
    }
}
