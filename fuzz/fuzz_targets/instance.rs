//! Instance files and JSON Lines datasets: a typed error or instances, never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = afg_game::io::parse_instances(text);
        let _ = afg_game::io::parse_dataset(text);
    }
});
