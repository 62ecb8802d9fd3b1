//! Network headers (`model.json`'s network) and training configurations: a typed error
//! or settings that pass their checks, never a panic. Nothing is built from them here.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(network) = serde_json::from_slice::<afg_learn::nets::NetworkConfig>(data) {
        let _ = network.check();
    }
    if let Ok(config) = serde_json::from_slice::<afg_learn::train::TrainConfig>(data) {
        let _ = config.check();
    }
});
