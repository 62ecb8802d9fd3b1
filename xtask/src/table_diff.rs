//! Comparing two renderings of Markdown tables: what `reproduce-tables --verify`
//! reports.

/// Relative difference below which two numbers of a table count as equal: the learned
/// rollouts' floating point can differ between CPUs (other SIMD kernels), and a tie
/// broken the other way moves a mean by far less than this; a retrained model or a
/// changed method moves it by far more.
pub const RELATIVE_NOISE: f64 = 5e-4;

/// The cells where two renderings of the tables differ, each named by its table
/// heading, row and column. Timings are skipped; numbers may differ by one unit of
/// their last printed digit or by [`RELATIVE_NOISE`] (floating-point noise between
/// machines).
///
/// # Examples
/// ```
/// use xtask::table_diff::table_differences;
/// let old = "**N = 20**\n\n| method | welfare | time |\n|---|---|---|\n| Greedy | 21.80 | 2 µs |\n";
/// assert!(table_differences(old, &old.replace("2 µs", "3 µs")).is_empty()); // a timing
/// assert_eq!(
///     table_differences(old, &old.replace("21.80", "21.70")),
///     ["**N = 20**, Greedy, welfare: 21.80 → 21.70"]
/// );
/// ```
pub fn table_differences(committed: &str, fresh: &str) -> Vec<String> {
    fn number(cell: &str) -> Option<(f64, f64)> {
        let t = cell.trim().trim_end_matches('%').trim();
        let value: f64 = t.parse().ok()?;
        let decimals = t.split_once('.').map_or(0, |(_, d)| d.len());
        Some((value, 10f64.powi(-(decimals as i32))))
    }
    let cells = |line: &str| -> Vec<String> {
        line.trim()
            .trim_matches('|')
            .split('|')
            .map(|c| c.trim().to_owned())
            .collect()
    };
    let (a, b): (Vec<&str>, Vec<&str>) = (committed.lines().collect(), fresh.lines().collect());
    let mut out = Vec::new();
    if a.len() != b.len() {
        out.push(format!(
            "the tables have {} lines in docs/RESULTS.md and {} in a fresh run",
            a.len(),
            b.len()
        ));
    }
    let (mut heading, mut header) = (String::new(), Vec::new());
    for (x, y) in a.iter().zip(&b) {
        if !x.starts_with('|') {
            if !x.trim().is_empty() {
                heading = x.trim().to_owned();
            }
            if x != y {
                out.push(format!("{heading}: \"{x}\" is now \"{y}\""));
            }
            continue;
        }
        let (cx, cy) = (cells(x), cells(y));
        if cx.first().is_some_and(|c| c == "method") {
            header = cx.clone();
        }
        if cx.len() != cy.len() {
            out.push(format!("{heading}: row \"{}\" changed shape", cx[0]));
            continue;
        }
        for (k, (u, v)) in cx.iter().zip(&cy).enumerate() {
            let column = header.get(k).map_or("?", String::as_str);
            if column.contains("time") || u == v {
                continue;
            }
            let close = match (number(u), number(v)) {
                (Some((p, du)), Some((q, dv))) => {
                    (p - q).abs() <= (du.max(dv) * 1.000_001).max(RELATIVE_NOISE * p.abs())
                }
                _ => false,
            };
            if !close {
                out.push(format!("{heading}, {}, {column}: {u} → {v}", cx[0]));
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_differences_name_the_cell_and_skip_timings_and_noise() {
        let committed = "**N = 20**\n\n| method | welfare | % of OPT | time / instance |\n|---|---|---|---|\n| OPT | 22.61 | 100.00 % | 1 ms |\n| Greedy | 21.80 | 96.43 % | 2 µs |\n";
        assert!(table_differences(committed, committed).is_empty());
        // Timings and last-digit noise pass.
        let noisy = committed
            .replace("1 ms", "3 ms")
            .replace("96.43 %", "96.44 %");
        assert!(table_differences(committed, &noisy).is_empty());
        // A real change is named by heading, row and column.
        let stale = committed.replace("21.80", "21.70");
        let d = table_differences(committed, &stale);
        assert_eq!(d, ["**N = 20**, Greedy, welfare: 21.80 → 21.70"]);
        // A new row is reported.
        let longer = format!("{committed}| Random | 15.00 | 70.00 % | 1 µs |\n");
        assert_eq!(table_differences(committed, &longer).len(), 1);
        let renamed = committed.replace("Greedy", "Greedy (v2)");
        assert_eq!(table_differences(committed, &renamed).len(), 1);
    }
}
