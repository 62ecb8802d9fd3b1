//! The model identities against the committed models and the paper's tables.

use std::collections::HashSet;
use std::path::Path;

use afg_eval::dataset;
use xtask::{ModelSpec, paper};

fn root() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/.."))
}

#[test]
fn every_paper_model_of_table1_is_committed_with_its_own_directory_and_label() {
    let (mut dirs, mut labels) = (HashSet::new(), HashSet::new());
    for n in dataset::TABLE1_SIZES {
        for spec in ModelSpec::table1(n) {
            assert!(dirs.insert(spec.dir_name()), "{}", spec.dir_name());
            labels.insert(spec.label());
            let paper_welfare = paper::table1(n).unwrap().welfare_of(&spec);
            if spec.is_ours() {
                assert!(paper_welfare.is_none());
                continue;
            }
            assert!(paper_welfare.is_some());
            let run = spec.run_dir(root());
            assert!(run.has_weights(), "{} is not committed", spec.dir_name());
            let config = run.config().unwrap();
            assert_eq!((config.robots, config.algo), (n, spec.algo));
        }
    }
    // Labels name a model kind; the scale is the table's.
    assert_eq!(labels.len(), ModelSpec::table1(20).len());
}

#[test]
fn the_paper_tables_cover_the_dataset_sizes() {
    for n in dataset::TABLE1_SIZES {
        assert!(paper::table1(n).is_some(), "{n}");
    }
    for n in dataset::TABLE2_SIZES {
        assert!(paper::table2(n).is_some(), "{n}");
    }
    assert!(paper::table1(500).is_none() && paper::table2(20).is_none());
}

/// The committed price model, sequential and without repair, is above GRAPE DA and
/// greedy on the first instances of every test set, and its one-shot mode above Random
/// (the bars of the tables, on a sample small enough for a test).
#[test]
fn the_committed_price_model_beats_da_and_greedy_at_every_scale() {
    use afg_baseline::Method;
    use afg_eval::{evaluate, optima};
    use xtask::PriceSpec;
    let [sequential, one_shot] = PriceSpec::committed();
    let (sequential, one_shot) = (
        sequential.load(root()).unwrap(),
        one_shot.load(root()).unwrap(),
    );
    for n in dataset::SIZES {
        let insts: Vec<_> = dataset::load(root(), n)
            .unwrap()
            .into_iter()
            .take(10)
            .collect();
        let opt = optima(&insts).unwrap();
        let score =
            |a: &dyn afg_baseline::Allocator| evaluate("", a, &insts, &opt).unwrap().percent_of_opt;
        let ours = score(&sequential);
        for method in [Method::Da, Method::Greedy] {
            let theirs = score(method.allocator(0).as_ref());
            assert!(ours > theirs, "N = {n}: {ours} against {method} {theirs}");
        }
        let random = score(Method::Random.allocator(0).as_ref());
        assert!(score(&one_shot) > random, "N = {n}");
    }
}
