//! SVG maps of assignments (`solve --svg`, `realloc-study`, the map of reproduce-tables).

use std::path::Path;

use afg_game::Instance;
use anyhow::Result;

/// Draws assignments of one instance side by side as an SVG: robots coloured by task
/// (black if unassigned), tasks as squares sized by coalition, welfare in each title.
pub fn draw_assignments(
    inst: &Instance,
    panels: &[(&str, &afg_game::Assignment)],
    out: &Path,
) -> Result<()> {
    use plotters::prelude::*;
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
        for (area, (name, a)) in areas.iter().zip(panels) {
            let title = format!("{name}: welfare {:.2}", inst.welfare(a));
            let mut chart = ChartBuilder::on(area)
                .caption(title, ("sans-serif", 18))
                .margin(10)
                .x_label_area_size(25)
                .y_label_area_size(35)
                .build_cartesian_2d(x.0..x.1, y.0..y.1)?;
            chart.configure_mesh().disable_mesh().draw()?;
            for (i, p) in inst.robots().iter().enumerate() {
                let color =
                    a.tasks()[i].map_or(BLACK.to_rgba(), |j| Palette99::pick(j.index()).to_rgba());
                chart.draw_series(std::iter::once(Circle::new((p.x, p.y), 3, color.filled())))?;
            }
            for j in inst.task_ids() {
                let t = inst.task(j).position;
                let size = 4 + 2 * (a.size(j) as f64).sqrt() as i32;
                let color = Palette99::pick(j.index()).to_rgba();
                chart.draw_series(std::iter::once(Rectangle::new(
                    [
                        (t.x - 0.004 * size as f64, t.y - 0.004 * size as f64),
                        (t.x + 0.004 * size as f64, t.y + 0.004 * size as f64),
                    ],
                    color.stroke_width(3),
                )))?;
            }
        }
        root_area.present()?;
    }
    afg_game::io::write_atomic(out, svg.as_bytes())?;
    Ok(())
}
