//! Times files of the Pinocchio comparison (`benches/pinocchio/run.sh`), shared by
//! `pinocchio_side_by_side.rs` and `pinocchio_free_flyer.rs`: one `key ns` line per timed
//! function and run, appended by each side; the tables take the best of the runs.

use std::collections::BTreeMap;
use std::path::Path;

/// Appends `text` to the file at `path` (created if missing).
pub fn append(path: &Path, text: &str) -> Result<(), String> {
    use std::io::Write as _;
    std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(path)
        .and_then(|mut f| f.write_all(text.as_bytes()))
        .map_err(|e| format!("{}: {e}", path.display()))
}

/// The smallest figure per key in a times file (`name ns` per line) and the number of runs.
pub fn best_times(path: &Path) -> Result<(BTreeMap<String, f64>, usize), String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut best: BTreeMap<String, f64> = BTreeMap::new();
    let mut counts: BTreeMap<String, usize> = BTreeMap::new();
    for (n, l) in text.lines().enumerate() {
        let mut it = l.split_whitespace();
        let (Some(name), Some(ns), None) = (it.next(), it.next(), it.next()) else {
            return Err(format!(
                "{}:{}: expected `name ns`, found `{l}`",
                path.display(),
                n + 1
            ));
        };
        let ns: f64 = ns
            .parse()
            .map_err(|e| format!("{}:{}: `{ns}`: {e}", path.display(), n + 1))?;
        let b = best.entry(name.to_owned()).or_insert(f64::INFINITY);
        *b = b.min(ns);
        *counts.entry(name.to_owned()).or_default() += 1;
    }
    let runs = counts.values().copied().min().unwrap_or(0);
    Ok((best, runs))
}
