//! `cargo xtask plot-curves` and `cargo xtask training-report`: what training runs' logs show.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use afg_baseline::Method;
use afg_learn::{LogEvent, RunDir, ValidationLine};
use anyhow::{Context, Result, bail};
use clap::Args;

#[derive(Args)]
pub struct PlotArgs {
    /// Run directories (each with a log.jsonl).
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
    /// Output SVG.
    #[arg(long, default_value = "docs/figures/curves.svg")]
    out: PathBuf,
}

/// The validation curve of one run.
pub struct Curve {
    /// "net_algo (N = n)".
    pub label: String,
    /// (gradient step, mean validation welfare).
    pub points: Vec<(f64, f64)>,
    /// Mean welfare of the classical methods on the validation set, as logged.
    pub baselines: Vec<(String, f64)>,
}

/// Reads the validation curve from `dir/log.jsonl`.
pub fn read_curve(dir: &Path) -> Result<Curve> {
    let run = RunDir::new(dir);
    let (mut label, mut points, mut baselines) =
        (dir.display().to_string(), Vec::new(), Vec::new());
    for event in run.log()? {
        match event {
            LogEvent::Start {
                config,
                baselines: logged,
                ..
            } => {
                label = format!(
                    "{} ({}_{}, N = {})",
                    run.name(),
                    config.network.name(),
                    config.algo.name(),
                    config.robots
                );
                for m in [Method::Opt, Method::Greedy, Method::Nearest, Method::Random] {
                    if let Some(&w) = logged.get(m.name()) {
                        baselines.push((m.name().to_owned(), w));
                    }
                }
            }
            LogEvent::Validation(v) => points.push((v.step as f64, v.welfare)),
            _ => {}
        }
    }
    Ok(Curve {
        label,
        points,
        baselines,
    })
}

/// Draws validation welfare against gradient steps, one line per run, OPT dashed.
pub fn plot_curves(dirs: &[PathBuf], out: &Path, title: &str) -> Result<()> {
    use plotters::prelude::*;
    let curves = dirs
        .iter()
        .map(|d| read_curve(d))
        .collect::<Result<Vec<_>>>()?;
    let all = curves.iter().flat_map(|c| c.points.iter().copied()).chain(
        curves
            .iter()
            .flat_map(|c| c.baselines.iter().map(|b| (0.0, b.1))),
    );
    let (mut x_max, mut y_min, mut y_max) = (1.0f64, f64::INFINITY, f64::NEG_INFINITY);
    for (x, y) in all {
        x_max = x_max.max(x);
        y_min = y_min.min(y);
        y_max = y_max.max(y);
    }
    if !y_min.is_finite() {
        bail!("no validation points in {} run(s)", dirs.len());
    }
    let pad = ((y_max - y_min) * 0.05).max(1e-6);
    if let Some(parent) = out.parent() {
        std::fs::create_dir_all(parent)?;
    }
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (800, 500)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(15)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..x_max, (y_min - pad)..(y_max + pad))?;
        chart
            .configure_mesh()
            .x_desc("gradient step")
            .y_desc("validation welfare (mean)")
            .draw()?;
        for (i, Curve { label, points, .. }) in curves.iter().enumerate() {
            let color = Palette99::pick(i).to_rgba();
            chart
                .draw_series(LineSeries::new(
                    points.iter().copied(),
                    color.stroke_width(2),
                ))?
                .label(label.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                });
        }
        // The classical methods on each distinct validation set, dashed, in greys.
        let mut drawn: Vec<(String, f64)> = Vec::new();
        for c in &curves {
            for (name, w) in &c.baselines {
                if drawn
                    .iter()
                    .any(|(n, v)| n == name && (v - w).abs() < 1e-12)
                {
                    continue;
                }
                drawn.push((name.clone(), *w));
                let grey = 40 + 45 * (drawn.len() % 4) as u8;
                let shade = RGBColor(grey, grey, grey);
                chart
                    .draw_series(DashedLineSeries::new(
                        vec![(0.0, *w), (x_max, *w)],
                        6,
                        4,
                        shade.stroke_width(1),
                    ))?
                    .label(format!("{name}, {w:.2}"))
                    .legend(move |(x, y)| {
                        PathElement::new(vec![(x, y), (x + 20, y)], shade.stroke_width(1))
                    });
            }
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()?;
        root.present()?;
    }
    afg_game::io::write_atomic(out, svg.as_bytes())?;
    Ok(())
}

pub fn run_plot(args: PlotArgs) -> Result<()> {
    plot_curves(
        &args.dirs,
        &args.out,
        "Validation welfare during training (dashed: classical methods)",
    )?;
    println!("wrote {}", args.out.display());
    Ok(())
}

#[derive(Args)]
pub struct ReportArgs {
    /// Run directories (each with a log.jsonl).
    #[arg(required = true)]
    dirs: Vec<PathBuf>,
}

/// A Markdown table of finished runs: final and best validation welfare against the
/// classical methods on the same validation set (all read from the runs' logs).
pub fn run_report(args: ReportArgs) -> Result<()> {
    println!(
        "| run | N | steps | wall time | final validation welfare | % of OPT | best (step) | collapsed validations |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    // Keyed by the scale's name: N, with M when it is not the paper's 5.
    let mut baseline_rows: Vec<(String, BTreeMap<String, f64>)> = Vec::new();
    for dir in &args.dirs {
        let run = RunDir::new(dir);
        let events = run.log()?;
        let Some((config, logged)) = events.iter().find_map(|e| match e {
            LogEvent::Start {
                config, baselines, ..
            } => Some((config, baselines)),
            _ => None,
        }) else {
            bail!("{}: the log has no start event", dir.display());
        };
        let vals: Vec<&ValidationLine> = events
            .iter()
            .filter_map(|e| match e {
                LogEvent::Validation(v) => Some(v),
                _ => None,
            })
            .collect();
        let last = vals
            .last()
            .with_context(|| format!("{}: the log has no validation", dir.display()))?;
        let best = vals
            .iter()
            .max_by(|a, b| a.welfare.total_cmp(&b.welfare))
            .expect("non-empty");
        let wall = events
            .iter()
            .rev()
            .find_map(LogEvent::elapsed_s)
            .unwrap_or(0.0);
        let n = match config.network.tasks() {
            afg_eval::dataset::TASKS => config.robots.to_string(),
            m => format!("{} (M = {m})", config.robots),
        };
        // Validations where most robots took one task (logged since the collapse check
        // exists; "–" for older logs).
        let flagged: Vec<bool> = vals.iter().filter_map(|v| v.collapsed).collect();
        let collapsed = if flagged.is_empty() {
            "–".to_owned()
        } else {
            format!(
                "{} of {}",
                flagged.iter().filter(|&&c| c).count(),
                flagged.len()
            )
        };
        println!(
            "| {} | {n} | {} | {:.0} min | {:.3} | {:.2} % | {:.3} ({}) | {collapsed} |",
            run.name(),
            last.step,
            wall / 60.0,
            last.welfare,
            last.percent_of_opt,
            best.welfare,
            best.step
        );
        if !baseline_rows.iter().any(|(m, _)| *m == n) {
            baseline_rows.push((n.clone(), logged.clone()));
        }
    }
    println!("\nClassical methods on the same validation sets (mean welfare):\n");
    let methods = Method::CENTRALISED;
    let header: Vec<&str> = methods.iter().map(|m| m.label()).collect();
    println!("| N | {} |", header.join(" | "));
    println!("|---|{}", "---|".repeat(methods.len()));
    for (n, b) in baseline_rows {
        let cells: Vec<String> = methods
            .iter()
            .map(|m| b.get(m.name()).map_or("–".into(), |v| format!("{v:.3}")))
            .collect();
        println!("| {n} | {} |", cells.join(" | "));
    }
    Ok(())
}
