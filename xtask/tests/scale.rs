//! `cargo xtask bench-scale`'s plan: sizes, task counts and pass counts of zero are
//! refused.

use std::path::PathBuf;

use xtask::scale::{Plan, cases};

#[test]
fn a_size_task_count_or_pass_count_of_zero_is_refused() {
    let plan = Plan {
        sizes: vec![100],
        tasks: vec![5],
        passes: vec![10],
        max_work: 1000,
        burn_up_to: 0,
        decentralised_up_to: 0,
        model: PathBuf::from("none"),
        price_model: PathBuf::from("none"),
        price_headed: Vec::new(),
        seed: 0,
    };
    assert!(!cases(&plan).unwrap().is_empty());
    for bad in [
        Plan {
            sizes: vec![100, 0],
            ..plan.clone()
        },
        Plan {
            tasks: vec![0],
            ..plan.clone()
        },
        Plan {
            passes: vec![0],
            ..plan.clone()
        },
    ] {
        let err = cases(&bad).unwrap_err();
        assert!(err.to_string().contains("at least 1"), "{err}");
    }
}
