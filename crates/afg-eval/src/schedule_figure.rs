//! A schedule as an SVG: a Gantt chart of the robots (driving, waiting for the team,
//! working) beside a map of their routes.

use afg_schedule::{Evaluation, Place, Role, ScheduleInstance};
use plotters::prelude::*;

use crate::EvalError;

/// The light grey of driving, the orange of waiting for a team.
const DRIVING: RGBColor = RGBColor(200, 200, 200);
const WAITING: RGBColor = RGBColor(240, 150, 40);

/// Draws `run` (a schedule of `inst` played by the evaluator) as a Gantt chart and a map,
/// `title` above both.
///
/// # Errors
/// [`EvalError::Figure`] if drawing fails.
///
/// # Examples
/// ```
/// use afg_schedule::{Schedule, ScheduleInstance};
/// let inst = ScheduleInstance::from_json(r#"{"speed":1,"max_wait":10,"depots":[[0,0]],
///   "robots":[{"x":0,"y":0,"depot":0},{"x":0,"y":0,"depot":0}],
///   "tasks":[{"x":0,"y":1,"min_team":2,"duration":1},{"x":1,"y":1,"min_team":1,"duration":2}]}"#)?;
/// let run = inst.evaluate(&Schedule { routes: vec![vec![0, 1], vec![0]] })?;
/// let svg = afg_eval::schedule_figure::schedule_svg(&inst, &run, "two robots")?;
/// // Both at task 0 at 1, done at 2; robot 0 at task 1 at 3, done at 5, home at 5 + √2.
/// assert!(svg.starts_with("<svg") && svg.contains("makespan 6.41"));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn schedule_svg(
    inst: &ScheduleInstance,
    run: &Evaluation,
    title: &str,
) -> Result<String, EvalError> {
    let mut svg = String::new();
    {
        let rows = inst.num_robots() as u32;
        let height = (120 + 14 * rows).clamp(420, 2400);
        let root = SVGBackend::with_string(&mut svg, (1400, height)).into_drawing_area();
        root.fill(&WHITE)?;
        let root = root.titled(
            &format!(
                "{title}: makespan {:.2}, travel {:.2}, mean wait {:.2}, longest wait {:.2}",
                run.makespan, run.travel, run.waiting, run.longest_wait
            ),
            ("sans-serif", 18),
        )?;
        let (gantt, map) = root.split_horizontally(900);
        draw_gantt(&gantt, inst, run)?;
        draw_map(&map, inst, run)?;
        root.present()?;
    }
    Ok(svg)
}

fn draw_gantt(
    area: &DrawingArea<SVGBackend, plotters::coord::Shift>,
    inst: &ScheduleInstance,
    run: &Evaluation,
) -> Result<(), EvalError> {
    let n = inst.num_robots() as f64;
    let mut chart = ChartBuilder::on(area)
        .margin(10)
        .x_label_area_size(30)
        .y_label_area_size(40)
        .build_cartesian_2d(0.0..run.makespan.max(1e-9) * 1.02, -0.5..n - 0.5)?;
    chart
        .configure_mesh()
        .disable_y_mesh()
        .x_desc("time")
        .y_desc("robot")
        .draw()?;
    let bar = |i: usize, from: f64, to: f64, style: ShapeStyle| {
        let y = i as f64;
        Rectangle::new([(from, y - 0.35), (to, y + 0.35)], style)
    };
    for (i, visits) in run.visits.iter().enumerate() {
        let mut bars = Vec::new();
        for v in visits.iter().filter(|v| v.role != Role::Skipped) {
            bars.push(bar(i, v.depart, v.arrive, DRIVING.filled()));
            let colour = Palette99::pick(v.task).to_rgba();
            match v.role {
                Role::Team => {
                    bars.push(bar(i, v.arrive, run.start[v.task], WAITING.filled()));
                    bars.push(bar(i, run.start[v.task], v.leave, colour.filled()));
                }
                _ => bars.push(bar(
                    i,
                    v.arrive.min(v.leave),
                    v.leave,
                    colour.stroke_width(1),
                )),
            }
        }
        let last = visits
            .iter()
            .rev()
            .find(|v| v.role != Role::Skipped)
            .map_or(0.0, |v| v.leave);
        bars.push(bar(i, last, run.back[i], DRIVING.filled()));
        chart.draw_series(bars)?;
    }
    Ok(())
}

fn draw_map(
    area: &DrawingArea<SVGBackend, plotters::coord::Shift>,
    inst: &ScheduleInstance,
    run: &Evaluation,
) -> Result<(), EvalError> {
    let points = (0..inst.num_tasks())
        .map(|j| inst.point(Place::Task(j)))
        .chain(inst.depots.iter().copied())
        .chain((0..inst.num_robots()).map(|i| inst.point(Place::Start(i))));
    let (mut x, mut y) = (
        (f64::INFINITY, f64::NEG_INFINITY),
        (f64::INFINITY, f64::NEG_INFINITY),
    );
    for p in points {
        x = (x.0.min(p[0]), x.1.max(p[0]));
        y = (y.0.min(p[1]), y.1.max(p[1]));
    }
    let pad = 0.03 * (x.1 - x.0).max(y.1 - y.0).max(1e-9);
    let mut chart = ChartBuilder::on(area)
        .margin(10)
        .x_label_area_size(25)
        .y_label_area_size(35)
        .build_cartesian_2d(x.0 - pad..x.1 + pad, y.0 - pad..y.1 + pad)?;
    chart.configure_mesh().disable_mesh().draw()?;
    for (i, visits) in run.visits.iter().enumerate() {
        let mut path = vec![inst.point(Place::Start(i))];
        path.extend(
            visits
                .iter()
                .filter(|v| v.role != Role::Skipped)
                .map(|v| inst.point(Place::Task(v.task))),
        );
        if inst.return_to_depot {
            path.push(inst.point(inst.depot_place(i)));
        }
        let style = Palette99::pick(i).mix(0.45).stroke_width(1);
        chart.draw_series(std::iter::once(PathElement::new(
            path.into_iter().map(|p| (p[0], p[1])).collect::<Vec<_>>(),
            style,
        )))?;
    }
    for j in 0..inst.num_tasks() {
        let p = inst.point(Place::Task(j));
        let size = 3 + inst.fewest_robots(j) as i32;
        chart.draw_series(std::iter::once(Circle::new(
            (p[0], p[1]),
            size,
            Palette99::pick(j).to_rgba().filled(),
        )))?;
    }
    for d in &inst.depots {
        chart.draw_series(std::iter::once(Rectangle::new(
            [
                (d[0] - pad / 3.0, d[1] - pad / 3.0),
                (d[0] + pad / 3.0, d[1] + pad / 3.0),
            ],
            BLACK.filled(),
        )))?;
    }
    Ok(())
}
