//! The bootstrap targets of DQN and Double DQN, as pure functions.
//!
//! The paper's eqs. 15/16 contain typos; these are the standard forms (docs/training.md).
//! `mask` marks the actions available in s' (tasks with room for the next robot);
//! a terminal transition has no bootstrap.

/// DQN: `r + max_{a ∈ mask} Q_target(s', a)`, or `r` at the end of an episode.
///
/// # Examples
/// ```
/// use afg_learn::train::dqn_target;
/// assert_eq!(dqn_target(1.0, &[3.0, 5.0], &[true, true], false), 6.0);
/// assert_eq!(dqn_target(1.0, &[3.0, 5.0], &[true, false], false), 4.0);
/// assert_eq!(dqn_target(1.0, &[3.0, 5.0], &[true, true], true), 1.0);
/// ```
pub fn dqn_target(reward: f32, next_q_target: &[f32], mask: &[bool], terminal: bool) -> f32 {
    if terminal {
        return reward;
    }
    reward + masked_argmax(next_q_target, mask).map_or(0.0, |a| next_q_target[a])
}

/// Double DQN: `r + Q_target(s', argmax_{a ∈ mask} Q_online(s', a))`, or `r` at the end.
/// The online network chooses, the target network evaluates.
///
/// # Examples
/// ```
/// use afg_learn::train::double_dqn_target;
/// // The online net prefers action 0, which the target net values at 3.
/// assert_eq!(double_dqn_target(1.0, &[9.0, 2.0], &[3.0, 5.0], &[true, true], false), 4.0);
/// ```
pub fn double_dqn_target(
    reward: f32,
    next_q_online: &[f32],
    next_q_target: &[f32],
    mask: &[bool],
    terminal: bool,
) -> f32 {
    if terminal {
        return reward;
    }
    reward + masked_argmax(next_q_online, mask).map_or(0.0, |a| next_q_target[a])
}

/// Index of the largest value among allowed entries, ties to the lowest index.
///
/// # Examples
/// ```
/// use afg_learn::train::masked_argmax;
/// assert_eq!(masked_argmax(&[1.0, 7.0, 7.0], &[true, true, true]), Some(1));
/// assert_eq!(masked_argmax(&[1.0, 7.0], &[true, false]), Some(0));
/// assert_eq!(masked_argmax(&[1.0], &[false]), None);
/// ```
pub fn masked_argmax(values: &[f32], mask: &[bool]) -> Option<usize> {
    let mut best: Option<usize> = None;
    for (j, (&v, &ok)) in values.iter().zip(mask).enumerate() {
        if ok && best.is_none_or(|b| v > values[b]) {
            best = Some(j);
        }
    }
    best
}
