//! SVG figures: validation curves of training runs and maps of assignments.

use afg_baseline::{Allocator, Method, Optimum, SwarmReport};
use afg_game::{Assignment, Instance};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

use crate::EvalError;
use crate::runs::Curve;

impl<E: std::error::Error + Send + Sync> From<DrawingAreaErrorKind<E>> for EvalError {
    fn from(e: DrawingAreaErrorKind<E>) -> Self {
        EvalError::Figure(e.to_string())
    }
}

/// Validation welfare against gradient steps as an SVG, one line per run, the
/// classical methods dashed.
///
/// # Errors
/// [`EvalError::Figure`] if no curve has a point, or drawing fails.
pub fn curves_svg(curves: &[Curve], title: &str) -> Result<String, EvalError> {
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
        return Err(EvalError::Figure(format!(
            "no validation points in {} run(s)",
            curves.len()
        )));
    }
    let pad = ((y_max - y_min) * 0.05).max(1e-6);
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
            palette_line(&mut chart, i, label, points.iter().copied())?;
        }
        // The classical methods on each distinct validation set, dashed, in greys.
        let mut drawn: Vec<(Method, f64)> = Vec::new();
        for c in curves {
            for (name, w) in &c.baselines {
                if drawn
                    .iter()
                    .any(|(n, v)| n == name && (v - w).abs() < 1e-12)
                {
                    continue;
                }
                drawn.push((*name, *w));
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
    Ok(svg)
}

/// A chart of lines over two `f64` axes, drawn into an SVG string.
type LineChart<'a, 'b> =
    ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Draws `points` as the `i`-th line of the palette, named `name` in the legend.
fn palette_line(
    chart: &mut LineChart<'_, '_>,
    i: usize,
    name: &str,
    points: impl IntoIterator<Item = (f64, f64)>,
) -> Result<(), EvalError> {
    let color = Palette99::pick(i).to_rgba();
    chart
        .draw_series(LineSeries::new(points, color.stroke_width(2)))?
        .label(name)
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2)));
    Ok(())
}

/// The legend box of the named lines, at `position`.
fn legend<'a, 'b: 'a>(
    chart: &mut LineChart<'a, 'b>,
    position: SeriesLabelPosition,
) -> Result<(), EvalError> {
    chart
        .configure_series_labels()
        .position(position)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()?;
    Ok(())
}

/// Assignments of one instance side by side as an SVG map: robots coloured by task
/// (a grey ring if in no coalition: the void task of GRAPE's game), tasks as squares
/// sized by coalition, welfare in each title (and, in GRAPE's game, how many robots
/// stay out).
///
/// # Errors
/// [`EvalError::Figure`] if drawing fails.
///
/// # Examples
/// ```
/// use afg_baseline::{Allocator, Optimum};
/// use afg_game::{GeneratorConfig, Instance, Point, Task};
/// let inst = GeneratorConfig::paper(10, 3, 1).generate()?;
/// let opt = Optimum.allocate(&inst)?.assignment;
/// let svg = afg_eval::figures::assignments_svg(&inst, &[("OPT", &opt)])?;
/// assert!(svg.starts_with("<svg"));
/// // GRAPE's game: the far robot stays out, drawn as a ring.
/// let task = Task { position: Point::new(0.0, 0.0), reward: 1.0, eps: 2.0, capacity: None };
/// let far = Instance::with_void(vec![Point::new(0.1, 0.0), Point::new(9.0, 9.0)], vec![task], 1.0)?;
/// let opt = Optimum.allocate(&far)?.assignment;
/// let svg = afg_eval::figures::assignments_svg(&far, &[("OPT", &opt)])?;
/// assert!(svg.contains("1 stay out") && svg.contains(r#"fill="none""#));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn assignments_svg(
    inst: &Instance,
    panels: &[(&str, &Assignment)],
) -> Result<String, EvalError> {
    let mut svg = String::new();
    {
        let width = 500 * panels.len().max(1) as u32;
        let root_area = SVGBackend::with_string(&mut svg, (width, 520)).into_drawing_area();
        root_area.fill(&WHITE)?;
        let areas = root_area.split_evenly((1, panels.len().max(1)));
        // The unit square, widened to hold every robot and task of other instances.
        let points = inst
            .robots()
            .iter()
            .chain(inst.tasks().iter().map(|t| &t.position));
        let (mut x, mut y) = ((0.0f64, 1.0f64), (0.0f64, 1.0f64));
        for p in points {
            x = (x.0.min(p.x), x.1.max(p.x));
            y = (y.0.min(p.y), y.1.max(p.y));
        }
        // A task's square grows with its coalition, in units of the drawing's extent.
        let unit = 0.004 * (x.1 - x.0).max(y.1 - y.0);
        for (area, (name, a)) in areas.iter().zip(panels) {
            let out = inst.num_robots() - a.num_assigned();
            let title = if inst.allows_void() {
                format!("{name}: welfare {:.2}, {out} stay out", inst.welfare(a))
            } else {
                format!("{name}: welfare {:.2}", inst.welfare(a))
            };
            let mut chart = ChartBuilder::on(area)
                .caption(title, ("sans-serif", 18))
                .margin(10)
                .x_label_area_size(25)
                .y_label_area_size(35)
                .build_cartesian_2d(x.0..x.1, y.0..y.1)?;
            chart.configure_mesh().disable_mesh().draw()?;
            for (i, p) in inst.robots().iter().enumerate() {
                // A robot in no coalition (the void task, or not yet placed): a grey ring.
                let style = a.tasks()[i].map_or(RGBColor(150, 150, 150).stroke_width(1), |j| {
                    Palette99::pick(j.index()).to_rgba().filled()
                });
                chart.draw_series(std::iter::once(Circle::new((p.x, p.y), 3, style)))?;
            }
            for j in inst.task_ids() {
                let t = inst.task(j).position;
                let size = 4 + 2 * (a.size(j) as f64).sqrt() as i32;
                let color = Palette99::pick(j.index()).to_rgba();
                chart.draw_series(std::iter::once(Rectangle::new(
                    [
                        (t.x - unit * size as f64, t.y - unit * size as f64),
                        (t.x + unit * size as f64, t.y + unit * size as f64),
                    ],
                    color.stroke_width(3),
                )))?;
            }
        }
        root_area.present()?;
    }
    Ok(svg)
}

/// The validation curves of the training runs in `dirs` (each with a log), as
/// [`curves_svg`] draws them: `afg plot-curves` and the paper's Fig. 1.
///
/// # Errors
/// A run without a readable log, or [`EvalError::Figure`] if drawing fails.
pub fn runs_curves_svg(dirs: &[std::path::PathBuf], title: &str) -> Result<String, EvalError> {
    let curves = dirs
        .iter()
        .map(|d| crate::runs::read_curve(d))
        .collect::<Result<Vec<_>, _>>()?;
    curves_svg(&curves, title)
}

/// `assignment` (named `name`) drawn beside the exact optimum of `inst` (named
/// `opt_name`), as [`assignments_svg`] draws them: the `--svg` map of `afg solve`.
///
/// # Errors
/// The optimum's errors, and [`EvalError::Figure`] if drawing fails.
///
/// # Examples
/// ```
/// use afg_baseline::{Allocator, Greedy};
/// use afg_game::GeneratorConfig;
/// let inst = GeneratorConfig::paper(10, 3, 1).generate()?;
/// let greedy = Greedy.allocate(&inst)?.assignment;
/// let svg = afg_eval::figures::beside_optimum_svg(&inst, "OPT", "greedy", &greedy)?;
/// assert!(svg.contains("greedy: welfare"));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn beside_optimum_svg(
    inst: &Instance,
    opt_name: &str,
    name: &str,
    assignment: &Assignment,
) -> Result<String, EvalError> {
    let opt = Optimum.allocate(inst)?.assignment;
    assignments_svg(inst, &[(opt_name, &opt), (name, assignment)])
}

/// Swarm runs against rounds as an SVG of two panels: the welfare of the highest view
/// among the living robots as % of the survivors' optimum (above), and the share of
/// the living robots that hold it (below); one line per run.
///
/// # Errors
/// [`EvalError::Figure`] if no run has a trace, or drawing fails.
///
/// # Examples
/// ```
/// use afg_baseline::{Network, Swarm};
/// use afg_game::{GeneratorConfig, Preference};
/// let inst = GeneratorConfig::paper(40, 3, 1).generate()?;
/// let mut swarm = Swarm::grape(Preference::Selfish, Network { loss: 0.3, ..Network::default() }, 1);
/// swarm.trace = true;
/// let report = swarm.run(&inst)?;
/// let svg = afg_eval::figures::swarm_svg(&[("loss 30 %".into(), report)], "GRAPE, N = 40")?;
/// assert!(svg.contains("loss 30 %"));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn swarm_svg(runs: &[(String, SwarmReport)], title: &str) -> Result<String, EvalError> {
    let percent = |r: &SwarmReport, w: f64| 100.0 * w / r.opt_welfare;
    let rounds = runs
        .iter()
        .flat_map(|(_, r)| r.trace.last().map(|p| p.round))
        .max()
        .ok_or_else(|| EvalError::Figure("no swarm run has a trace".into()))?;
    let lowest = runs
        .iter()
        .flat_map(|(_, r)| r.trace.iter().map(move |p| percent(r, p.welfare)))
        .filter(|p| p.is_finite())
        .fold(100.0f64, f64::min)
        .max(0.0);
    let x_max = rounds.max(1) as f64;
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (800, 700)).into_drawing_area();
        root.fill(&WHITE)?;
        let root = root.titled(title, ("sans-serif", 20))?;
        let (top, bottom) = root.split_vertically(360);
        let panels = [
            (top, "welfare, % of the survivors' OPT", lowest..100.5),
            (bottom, "share of living robots holding it", 0.0..1.02),
        ];
        for (panel, (area, label, y_range)) in panels.into_iter().enumerate() {
            let mut chart = ChartBuilder::on(&area)
                .margin(15)
                .x_label_area_size(40)
                .y_label_area_size(60)
                .build_cartesian_2d(0.0..x_max, y_range)?;
            chart
                .configure_mesh()
                .x_desc("round")
                .y_desc(label)
                .draw()?;
            for (i, (name, r)) in runs.iter().enumerate() {
                let points = r.trace.iter().map(|p| {
                    let y = if panel == 0 {
                        percent(r, p.welfare).max(lowest)
                    } else {
                        p.agreeing
                    };
                    (p.round as f64, y)
                });
                palette_line(&mut chart, i, name, points)?;
            }
            legend(&mut chart, SeriesLabelPosition::LowerRight)?;
        }
        root.present()?;
    }
    Ok(svg)
}

/// Mission runs against time as an SVG of three panels — tasks open, tasks done, and
/// the reward of the tasks done — one stepped line per run (a method, on one mission).
///
/// # Errors
/// [`EvalError::Figure`] if there is no run or drawing fails.
///
/// # Examples
/// ```
/// use afg_baseline::Method;
/// use afg_mission::{MissionConfig, MissionMethod, MissionPlan, Preset};
/// let mission = MissionConfig::new(Preset::Waves, 20, 6, 1).generate()?;
/// let greedy = MissionPlan { method: MissionMethod::Central(Method::Greedy), ..MissionPlan::default() };
/// let run = greedy.planner()?.run(&mission, Default::default(), |_| {})?;
/// let svg = afg_eval::figures::mission_svg(&[("greedy".into(), run)], "waves")?;
/// assert!(svg.contains("tasks done") && svg.contains("greedy"));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn mission_svg(
    runs: &[(String, afg_mission::MissionRun)],
    title: &str,
) -> Result<String, EvalError> {
    let end = runs
        .iter()
        .flat_map(|(_, r)| r.timeline.last().map(|p| p.time))
        .fold(f64::NAN, f64::max);
    if runs.is_empty() || !end.is_finite() {
        return Err(EvalError::Figure("no mission run to draw".into()));
    }
    type Value = fn(&afg_mission::TimelinePoint) -> f64;
    let panels: [(&str, Value); 3] = [
        ("tasks open", |p| p.open as f64),
        ("tasks done", |p| p.done as f64),
        ("reward of the tasks done", |p| p.reward),
    ];
    let mut svg = String::new();
    {
        let root = SVGBackend::with_string(&mut svg, (800, 900)).into_drawing_area();
        root.fill(&WHITE)?;
        let root = root.titled(title, ("sans-serif", 20))?;
        for (area, (label, value)) in root.split_evenly((3, 1)).iter().zip(panels) {
            let top = runs
                .iter()
                .flat_map(|(_, r)| r.timeline.iter().map(value))
                .fold(0.0, f64::max)
                .max(1.0)
                * 1.05;
            let mut chart = ChartBuilder::on(area)
                .margin(12)
                .x_label_area_size(35)
                .y_label_area_size(60)
                .build_cartesian_2d(0.0..end.max(1e-9), 0.0..top)?;
            chart.configure_mesh().x_desc("time").y_desc(label).draw()?;
            for (i, (name, r)) in runs.iter().enumerate() {
                // Stepped: each value holds until the next event.
                let mut points = Vec::with_capacity(2 * r.timeline.len());
                for (k, p) in r.timeline.iter().enumerate() {
                    if k > 0 {
                        points.push((p.time, value(&r.timeline[k - 1])));
                    }
                    points.push((p.time, value(p)));
                }
                palette_line(&mut chart, i, name, points)?;
            }
            legend(&mut chart, SeriesLabelPosition::UpperLeft)?;
        }
        root.present()?;
    }
    Ok(svg)
}

/// A self-contained HTML page that animates a mission run's frames (no server, no
/// network: the frames and a few lines of JavaScript are in the page): robots coloured
/// by their task (grey: none; a red cross: failed; a ring: waiting for the rest of its
/// team), tasks as squares sized by the work left with their coalition's size (over
/// the team they need, where it is more than one), with a play button and a time
/// slider.
///
/// # Errors
/// [`EvalError::Figure`] if the run has no frames.
///
/// # Examples
/// ```
/// use afg_baseline::Method;
/// use afg_mission::{MissionConfig, MissionMethod, MissionPlan, Preset, Recording};
/// let mission = MissionConfig::new(Preset::Attrition, 20, 6, 1).generate()?;
/// let greedy = MissionPlan { method: MissionMethod::Central(Method::Greedy), ..MissionPlan::default() };
/// let frames = Recording { frame_every: Some(0.5), ..Recording::default() };
/// let run = greedy.planner()?.run(&mission, frames, |_| {})?;
/// let html = afg_eval::figures::mission_html(&mission, &run, "greedy")?;
/// assert!(html.starts_with("<!DOCTYPE html>") && html.contains("\"frames\""));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn mission_html(
    mission: &afg_mission::Mission,
    run: &afg_mission::MissionRun,
    title: &str,
) -> Result<String, EvalError> {
    if run.frames.is_empty() {
        return Err(EvalError::Figure("the run has no frames to animate".into()));
    }
    let (lo, hi) = mission_bounds(mission);
    let tasks: Vec<[f64; 2]> = mission
        .tasks
        .iter()
        .map(|t| [t.position.x, t.position.y])
        .collect();
    let min_team: Vec<usize> = mission.tasks.iter().map(|t| t.min_team).collect();
    let data = serde_json::json!({
        "title": title,
        "bounds": [lo, hi],
        "tasks": tasks,
        "min_team": min_team,
        "frames": run.frames,
    });
    let escaped = serde_json::to_string(&data)
        .map_err(|e| EvalError::Figure(e.to_string()))?
        .replace("</", "<\\/");
    Ok(MISSION_PAGE
        .replace("__DATA__", &escaped)
        .replace("__TITLE__", &html_text(title)))
}

/// The box around a mission's robots' starts and tasks: what its drawings show.
pub(crate) fn mission_bounds(mission: &afg_mission::Mission) -> ([f64; 2], [f64; 2]) {
    let points = mission
        .robots
        .iter()
        .map(|r| r.position)
        .chain(mission.tasks.iter().map(|t| t.position));
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in points {
        lo = [lo[0].min(p.x), lo[1].min(p.y)];
        hi = [hi[0].max(p.x), hi[1].max(p.y)];
    }
    (lo, hi)
}

/// `text` safe inside HTML.
fn html_text(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// The page of [`mission_html`] (`mission_page.html`); `__DATA__` and `__TITLE__` are
/// filled in.
const MISSION_PAGE: &str = include_str!("mission_page.html");
