//! A start for the search: an assignment the caller already has.

use afg_game::{Assignment, Instance};

use crate::AllocError;

/// Refuses a start that is not an assignment of `instance`: another number of robots,
/// a task out of range or over its capacity, or a robot on no task in a game without
/// the void.
pub(super) fn check(instance: &Instance, start: &Assignment) -> Result<(), AllocError> {
    instance.check(start)?;
    let idle = (instance.robot_ids()).find(|&i| start.task_of(i).is_none());
    match idle {
        Some(i) if !instance.allows_void() => Err(AllocError::InvalidParameter(format!(
            "the start leaves robot {} on no task, and this game has no void task",
            i.index()
        ))),
        _ => Ok(()),
    }
}
