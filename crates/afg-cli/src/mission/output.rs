//! What `afg mission run|compare` prints and draws besides the tables: the metrics
//! of one run, the still PNG, and the plans' advice.

use afg_mission::{Mission, MissionPlan, MissionRun};
use anyhow::Result;
use std::path::Path;

/// The PNG of `--still`: the recorded moment nearest to `at`, or else the first where
/// the most robots wait for their team.
pub(super) fn still(mission: &Mission, run: &MissionRun, at: Option<f64>) -> Result<Vec<u8>> {
    let frames = &run.frames;
    let chosen = match at {
        Some(t) => frames
            .iter()
            .min_by(|a, b| (a.time - t).abs().total_cmp(&(b.time - t).abs())),
        None => frames.iter().rev().max_by_key(|f| f.waiting.len()),
    };
    let frame = chosen.ok_or_else(|| anyhow::anyhow!("the run recorded no moment to draw"))?;
    const SIZE: usize = 720;
    let rgb = afg_eval::frame_image::frame_rgb(mission, frame, SIZE)?;
    Ok(afg_eval::frame_image::png(&rgb, SIZE))
}

/// Prints each plan's advice on the missions (`MissionPlan::advice`) once, on stderr.
pub(super) fn note(plans: &[MissionPlan], missions: &[Mission]) {
    let mut said = std::collections::BTreeSet::new();
    for plan in plans {
        for mission in missions {
            if let Some(advice) = plan.advice(mission)
                && said.insert(advice.clone())
            {
                eprintln!("note: {advice}");
            }
        }
    }
}

/// Prints one run's metrics, one per line.
pub(super) fn print_metrics(name: &str, path: &Path, run: &MissionRun) {
    let m = &run.metrics;
    let or_dash = |x: Option<f64>| x.map_or("—".into(), |v| format!("{v:.3}"));
    println!("{name} on {}", path.display());
    println!("  tasks done          {} / {}", m.tasks_done, m.tasks);
    println!(
        "  reward done         {:.3}   ({:.2} % of all tasks' {:.3})",
        m.reward_done,
        100.0 * m.reward_done / m.reward_total,
        m.reward_total
    );
    println!(
        "  latency             mean {}, p95 {}, max {}",
        or_dash(m.latency_mean),
        or_dash(m.latency_p95),
        or_dash(m.latency_max)
    );
    println!(
        "  makespan            {}   (run ended at {:.3})",
        or_dash(m.makespan),
        m.end
    );
    println!("  distance            {:.3}", m.distance);
    println!("  reassignments       {}", m.reassignments);
    if let Some(gap) = m.gap_max {
        println!(
            "  largest gap         {:.4} %   (the exact solver's, over its decisions)",
            100.0 * gap
        );
    }
    if let Some(w) = &m.waiting {
        println!(
            "  waiting             {:.3} robot-time units at tasks whose team was incomplete",
            w.total
        );
    }
    println!(
        "  decisions           {}   (compute {:.3} ms mean, {:.3} ms max, {:.3} ms in all)",
        m.decisions,
        1e3 * m.compute_mean_s,
        1e3 * m.compute_max_s,
        1e3 * m.compute_total_s
    );
    if let Some(s) = &m.swarm {
        println!(
            "  over the radio      {} rounds, {} messages, {:.1} kB",
            s.rounds,
            s.messages,
            s.bytes as f64 / 1e3
        );
        println!(
            "  response time       mean {}, max {}   ({} events never settled)",
            or_dash(s.response_mean),
            or_dash(s.response_max),
            s.unsettled
        );
    }
}
