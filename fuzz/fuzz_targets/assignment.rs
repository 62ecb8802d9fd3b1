//! Assignment and `--from` files against the first committed N = 20 instance: a typed
//! error or a valid assignment, never a panic.
#![no_main]

use std::sync::LazyLock;

use afg_game::io::parse_dataset;
use afg_game::realloc::PreviousAssignment;
use afg_game::{Assignment, Instance};
use libfuzzer_sys::fuzz_target;

static INSTANCE: LazyLock<Instance> = LazyLock::new(|| {
    let text = include_str!("../../datasets/n20.jsonl");
    parse_dataset(text)
        .expect("the committed dataset")
        .remove(0)
});

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(a) = Assignment::from_json(text, &INSTANCE) {
        assert!(INSTANCE.check(&a).is_ok());
    }
    if let Ok(previous) = PreviousAssignment::from_json(text)
        && let Ok(a) = previous.carry_over(&INSTANCE)
    {
        assert!(INSTANCE.check(&a).is_ok());
    }
});
