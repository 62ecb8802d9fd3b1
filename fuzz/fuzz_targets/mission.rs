//! Mission files: a typed error, or a valid mission that a short run (greedy in the
//! loop) plays to its end without a panic.
#![no_main]

use afg_baseline::Greedy;
use afg_mission::{Mission, Replan, RunOptions, simulate};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(mission) = Mission::from_json(text) else {
        return;
    };
    // Small missions only: the fuzzer looks for panics, not for slow runs.
    if mission.robots.len() * mission.tasks.len() <= 10_000 {
        let _ = simulate(&mission, Replan::Scratch(&Greedy), RunOptions::default());
    }
});
