//! What a long command shows while it runs and how it prints times: a progress bar on
//! stderr and durations with a unit.

use std::time::Duration;

/// A duration with three significant digits and a unit: `12.3 µs`, `4.56 ms`, `7.89 s`.
///
/// # Examples
/// ```
/// use std::time::Duration;
/// use afg_eval::report::duration;
/// assert_eq!(duration(Duration::from_nanos(12_345)), "12.3 µs");
/// assert_eq!(duration(Duration::from_micros(4_560)), "4.56 ms");
/// assert_eq!(duration(Duration::from_millis(7_890)), "7.89 s");
/// ```
pub fn duration(d: Duration) -> String {
    let s = d.as_secs_f64();
    if s < 1e-3 {
        format!("{:.1} µs", s * 1e6)
    } else if s < 1.0 {
        format!("{:.2} ms", s * 1e3)
    } else {
        format!("{s:.2} s")
    }
}

/// A progress bar on stderr (hidden when stderr is not a terminal). With the
/// `progress` feature, which the command lines turn on.
///
/// # Examples
/// ```
/// let bar = afg_eval::report::progress(10, "solving");
/// bar.inc(1);
/// bar.finish_and_clear();
/// ```
#[cfg(feature = "progress")]
pub fn progress(len: u64, message: &str) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::new(len);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} ({eta})")
            .expect("valid template")
            .progress_chars("=> "),
    );
    bar.set_message(message.to_owned());
    bar
}

/// The exit status of a command line that ran `result`: 0, or 1 after printing the error
/// and its causes on one line of stderr (`error: what failed: why`), whatever
/// `RUST_BACKTRACE` says. A cause whose text the line already holds is not repeated.
/// Usage errors exit with 2 before this (clap).
///
/// # Examples
/// ```
/// fn main() -> std::process::ExitCode {
///     let read = std::fs::read("/no/such/file").map(drop);
///     afg_eval::report::exit_code(read.map_err(Box::<dyn std::error::Error + Send + Sync>::from))
/// }
/// # let _ = main; // prints `error: No such file or directory (os error 2)`, exits 1
/// ```
pub fn exit_code<E>(result: Result<(), E>) -> std::process::ExitCode
where
    E: AsRef<dyn std::error::Error + Send + Sync + 'static>,
{
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {}", one_line(error.as_ref()));
            std::process::ExitCode::FAILURE
        }
    }
}

/// An error and its causes joined by `: `, each cause left out where the text so far
/// already holds it (errors that print their source in their own message).
fn one_line(error: &(dyn std::error::Error + 'static)) -> String {
    let mut line = error.to_string();
    let mut cause = error.source();
    while let Some(c) = cause {
        let text = c.to_string();
        if !line.contains(&text) {
            line = format!("{line}: {text}");
        }
        cause = c.source();
    }
    line
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, thiserror::Error)]
    #[error("{path}: {source}")]
    struct InFile {
        path: &'static str,
        #[source]
        source: std::io::Error,
    }

    #[derive(Debug, thiserror::Error)]
    #[error("reading the instances")]
    struct Reading(#[source] InFile);

    #[test]
    fn causes_join_on_one_line_without_repeats() {
        let io = std::io::Error::other("no such file");
        let error = Reading(InFile {
            path: "x.json",
            source: io,
        });
        assert_eq!(
            one_line(&error),
            "reading the instances: x.json: no such file"
        );
    }
}
