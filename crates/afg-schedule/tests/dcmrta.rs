//! DCMRTA's published test set: read exactly, and its published CTAS-D routes replayed to
//! the published makespan, travel and waiting.

use std::path::PathBuf;

use afg_schedule::{ScheduleInstance, read_instances, read_schedules};

fn dataset(file: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../datasets/dcmrta-20a50t")
        .join(file)
}

fn published() -> Vec<serde_json::Value> {
    std::fs::read_to_string(dataset("dcmrta-20a50t-published.jsonl"))
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

#[test]
fn every_line_reads_and_writes_back_exactly() {
    let text = std::fs::read_to_string(dataset("dcmrta-20a50t.jsonl")).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 50);
    for line in lines {
        let inst = ScheduleInstance::from_json(line).unwrap();
        assert_eq!((inst.num_robots(), inst.num_tasks()), (20, 50));
        // Every field and every float comes back exactly (the exponent of 6.0e-05 is
        // spelled e-5 on the way out: equal as JSON values, not as bytes).
        let written: serde_json::Value = serde_json::from_str(&inst.to_json()).unwrap();
        let read: serde_json::Value = serde_json::from_str(line).unwrap();
        assert_eq!(written, read);
    }
}

#[test]
fn the_published_ctas_d_routes_replay_to_the_published_numbers() {
    let instances = read_instances(&dataset("dcmrta-20a50t.jsonl")).unwrap();
    let routes = read_schedules(&dataset("dcmrta-20a50t-routes.jsonl")).unwrap();
    let published = published();
    let (mut valid_at_10, mut early) = (0, 0);
    for ((inst, record), row) in instances.iter().zip(&routes).zip(&published) {
        assert_eq!(record.index, inst.index);
        let run = inst.evaluate(&record.schedule()).unwrap();
        let ctas = &row["methods"]["CTAS-D_300s"];
        for (ours, theirs) in [
            (run.makespan, "makespan"),
            (run.travel, "travel_dist"),
            (run.waiting, "waiting_time"),
        ] {
            let theirs = ctas[theirs].as_f64().unwrap();
            assert!(
                (ours - theirs).abs() <= 1e-9,
                "instance {:?}: {ours} against {theirs}",
                inst.index
            );
        }
        assert!(
            run.long_waits.is_empty(),
            "every published schedule keeps its waits within max_wait 100"
        );
        early += run.released_before_arrival.len();
        valid_at_10 += usize::from(
            inst.evaluate_with(&record.schedule(), 10.0)
                .unwrap()
                .is_valid(),
        );
    }
    assert!(
        valid_at_10 < 50,
        "some published schedules wait longer than 10"
    );
    assert!(
        early > 0,
        "some published schedules rely on an extra released before it arrives"
    );
    println!(
        "valid at max_wait 10: {valid_at_10} of 50; extras released before they arrive: {early}"
    );
}

/// The bound on the first three instances lies just below the linear relaxation of its
/// transportation problem with the one-way limit between each two tasks (solved apart
/// by an LP solver: 25.852, 24.578, 24.616; without the limit the bound is 25.189,
/// 23.738, 23.835, and limits on three tasks' cycles add nothing on instance 0).
#[test]
fn the_bound_reaches_the_linear_relaxation_with_its_one_way_limits() {
    let instances = read_instances(&dataset("dcmrta-20a50t.jsonl")).unwrap();
    for (inst, relaxed) in instances.iter().zip([25.852, 24.578, 24.616]) {
        let bound = inst.lower_bound().makespan;
        assert!(
            (relaxed - 0.05..=relaxed + 1e-3).contains(&bound),
            "{bound} against {relaxed}"
        );
    }
}
