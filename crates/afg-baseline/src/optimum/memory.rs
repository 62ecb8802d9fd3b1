//! What the exact solvers need in memory, checked before any is taken: an allocation
//! that fails aborts the process (and a Python interpreter with it), after minutes.

use afg_game::Instance;

use crate::AllocError;

/// Bytes the exact solver takes per robot–task pair: its cost table, the movers'
/// heaps and the levels' copies. The peak resident size of `afg solve --method opt`
/// divided by N·M came to 21–53 bytes from 100 000 × 100 to 20 000 × 2 000; this is
/// the largest, rounded up.
pub const BYTES_PER_PAIR: u64 = 56;

/// Bytes taken whatever the size (the program, the instance, the threads).
const BYTES_FIXED: u64 = 64 << 20;

/// About how many bytes the exact solver needs for `instance` (at most
/// [`BYTES_PER_PAIR`] per robot–task pair, and a fixed part).
///
/// # Examples
/// ```
/// use afg_baseline::exact_memory;
/// let inst = afg_game::GeneratorConfig::paper(100_000, 5_000, 1).generate()?;
/// assert!(exact_memory(&inst) > 25 << 30); // 5 × 10⁸ pairs: above 25 GiB
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn exact_memory(instance: &Instance) -> u64 {
    let pairs = instance.num_robots() as u64 * instance.num_tasks() as u64;
    pairs
        .saturating_mul(BYTES_PER_PAIR)
        .saturating_add(BYTES_FIXED)
}

/// Refuses `instance` in one line where the exact solver would need more memory than
/// this machine has available ([`available_memory`]; nothing is refused where that is
/// unknown).
pub(crate) fn check_memory(instance: &Instance) -> Result<(), AllocError> {
    let needed = exact_memory(instance);
    match available_memory() {
        Some(available) if needed > available => Err(AllocError::TooLarge {
            robots: instance.num_robots(),
            tasks: instance.num_tasks(),
            needed,
            available,
        }),
        _ => Ok(()),
    }
}

/// The memory this process may still take, in bytes: the system's available memory
/// (`MemAvailable` of `/proc/meminfo`), or less where a control group limits it;
/// `None` where neither can be read (not Linux).
pub fn available_memory() -> Option<u64> {
    let read = |path: &str| std::fs::read_to_string(path).ok();
    let system = read("/proc/meminfo").and_then(|info| {
        let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
        let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
        Some(kb.saturating_mul(1024))
    });
    let group = read("/sys/fs/cgroup/memory.max").and_then(|max| {
        let max: u64 = max.trim().parse().ok()?; // "max": no limit
        let used: u64 = read("/sys/fs/cgroup/memory.current")?.trim().parse().ok()?;
        Some(max.saturating_sub(used))
    });
    match (system, group) {
        (Some(s), Some(g)) => Some(s.min(g)),
        (s, g) => s.or(g),
    }
}
