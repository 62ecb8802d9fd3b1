//! What GRAPE and the auction share in a moving swarm: telling robots the news,
//! moving the radio with the robots, and bringing a robot back.

use std::borrow::Cow;

use afg_game::{Instance, Point};

use super::radio::Radio;
use super::task_news::TaskNews;
use crate::AllocError;

/// The living robots told of `task` appearing (or done) by `news` (none without).
pub(super) fn tell<M>(
    news: &mut Option<TaskNews>,
    radio: &Radio<M>,
    instance: &Instance,
    task: usize,
    done: bool,
) -> Vec<u32> {
    let Some(news) = news else {
        return Vec::new();
    };
    let told = news.event(task, done, instance.robots());
    told.into_iter().filter(|&a| radio.alive(a)).collect()
}

/// The robots are at `points` now: the game's distances are theirs, the links are
/// rebuilt, and robots see the tasks now in range. Returns the robots whose neighbours
/// changed and the living robots that saw a task anew (nothing if no robot moved).
///
/// # Errors
/// [`AllocError::Game`] for a point out of range, [`AllocError::Graph`] if the graph
/// cannot be built.
pub(super) fn move_swarm<M>(
    instance: &mut Cow<'_, Instance>,
    radio: &mut Radio<M>,
    news: &mut Option<TaskNews>,
    points: Vec<Point>,
) -> Result<(Vec<u32>, Vec<u32>), AllocError> {
    if points == instance.robots() {
        return Ok((Vec::new(), Vec::new()));
    }
    let relinked = radio.relink(&points)?;
    let saw = news
        .as_mut()
        .map_or_else(Vec::new, |news| news.sense(&points));
    let saw = saw.into_iter().filter(|&a| radio.alive(a)).collect();
    let robots: Vec<afg_game::RobotId> = instance.robot_ids().collect();
    *instance = Cow::Owned(instance.with_robots_at(&robots, points)?);
    Ok((relinked, saw))
}

/// `robot` is back, awake and linked; returns the robots whose neighbours changed (it
/// among them).
///
/// # Errors
/// [`AllocError::Graph`] if the graph cannot be built.
pub(super) fn revive<M>(
    radio: &mut Radio<M>,
    instance: &Instance,
    robot: u32,
) -> Result<Vec<u32>, AllocError> {
    radio.revive(robot);
    let mut relinked = radio.relink(instance.robots())?;
    relinked.push(robot);
    Ok(relinked)
}
