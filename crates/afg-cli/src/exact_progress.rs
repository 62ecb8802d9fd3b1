//! The exact solver's progress line on stderr.

use std::sync::atomic::{AtomicU64, Ordering};

use afg_baseline::TeamProgress;

/// The exact search's progress on stderr, once a second after its first: the best
/// found, the bound, the gap and the nodes.
pub(crate) fn print_progress(p: &TeamProgress) {
    // the next whole second to print at; a new solve starts again from 1
    static NEXT: AtomicU64 = AtomicU64::new(1);
    let next = NEXT.load(Ordering::Relaxed);
    let second = p.seconds as u64;
    if second + 1 < next {
        NEXT.store(second.max(1), Ordering::Relaxed);
    } else if second >= next {
        NEXT.store(second + 1, Ordering::Relaxed);
        eprintln!(
            "opt {:>6.1} s  best {:.4}  bound {:.4}  gap {:.3} %  nodes {}  open {}",
            p.seconds,
            p.welfare,
            p.bound,
            100.0 * p.gap(),
            p.nodes,
            p.open
        );
    }
}
