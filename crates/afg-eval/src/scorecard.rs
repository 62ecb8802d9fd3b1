//! Anyone's assignment judged against the game (`afg score`, Python's `afg.score`):
//! its [`Score`] against the exact optimum, its coalitions, and which robots would
//! move under each preference, and where.

use afg_game::{Assignment, Instance, Preference, RobotId, TaskId};
use serde::{Deserialize, Serialize};

use crate::{EvalError, Score, optimum_welfare};

/// A robot that strictly prefers another place, and the best one it would take.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Move {
    /// The robot.
    pub robot: u32,
    /// Its task now (−1: none, the void task in GRAPE's game).
    pub from: i64,
    /// The task it would move to (−1: the void task).
    pub to: i64,
}

/// An assignment against the game: the [`Score`] (the field names of `afg solve
/// --json`), coalition sizes, robots in no coalition, stability under both
/// preferences and the robots that would move.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Scorecard {
    /// Welfare, OPT's welfare, % of OPT and both NS rates.
    #[serde(flatten)]
    pub score: Score,
    /// Robots in each task's coalition.
    pub coalition_sizes: Vec<usize>,
    /// Robots in no coalition.
    pub unassigned: usize,
    /// Whether no robot would move under the balanced preference (Def. 3).
    pub stable_balanced: bool,
    /// Whether no robot would move under the selfish preference (GRAPE's).
    pub stable_selfish: bool,
    /// The robots that would move under the balanced preference, in robot order.
    pub moves_balanced: Vec<Move>,
    /// The robots that would move under the selfish preference, in robot order.
    pub moves_selfish: Vec<Move>,
}

impl Scorecard {
    /// The scorecard of `assignment` whose [`Score`] is known.
    pub fn with_score(instance: &Instance, assignment: &Assignment, score: Score) -> Self {
        let moves_balanced = moves(instance, assignment, Preference::Balanced);
        let moves_selfish = moves(instance, assignment, Preference::Selfish);
        Scorecard {
            score,
            coalition_sizes: assignment.sizes().to_vec(),
            unassigned: assignment.tasks().iter().filter(|t| t.is_none()).count(),
            stable_balanced: moves_balanced.is_empty(),
            stable_selfish: moves_selfish.is_empty(),
            moves_balanced,
            moves_selfish,
        }
    }
}

/// The scorecard of `assignment` on `instance`, solving the exact optimum.
///
/// # Errors
/// [`EvalError::Unplaced`] for a robot in no coalition where the instance does not
/// allow the void task; the optimum's errors, and [`EvalError::BeatsOptimum`] if the
/// assignment scores above it (then the optimum is wrong).
///
/// # Examples
/// ```
/// use afg_baseline::{Allocator, Greedy, Optimum};
/// use afg_eval::scorecard::scorecard;
/// use afg_game::GeneratorConfig;
/// let inst = GeneratorConfig::paper(30, 4, 2).generate()?;
/// let opt = scorecard(&inst, &Optimum.allocate(&inst)?.assignment)?;
/// assert_eq!(opt.score.percent_of_opt, Some(100.0));
/// assert!(opt.stable_balanced && opt.moves_balanced.is_empty());
/// assert_eq!(opt.coalition_sizes.iter().sum::<usize>(), 30);
/// let greedy = scorecard(&inst, &Greedy.allocate(&inst)?.assignment)?;
/// assert_eq!(greedy.stable_selfish, greedy.moves_selfish.is_empty());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn scorecard(instance: &Instance, assignment: &Assignment) -> Result<Scorecard, EvalError> {
    if !instance.allows_void()
        && let Some(robot) = assignment.tasks().iter().position(Option::is_none)
    {
        return Err(EvalError::Unplaced { robot });
    }
    let opt = optimum_welfare(instance)?;
    let score = Score::of("the assignment", instance, assignment, opt)?;
    Ok(Scorecard::with_score(instance, assignment, score))
}

/// The robots that would move under `pref`, each to its best response.
fn moves(instance: &Instance, assignment: &Assignment, pref: Preference) -> Vec<Move> {
    let index = |t: Option<TaskId>| t.map_or(-1, |t| i64::from(t.0));
    instance
        .robot_ids()
        .filter_map(|robot: RobotId| {
            let to = instance.best_move(assignment, robot, pref)?;
            Some(Move {
                robot: robot.0,
                from: index(assignment.task_of(robot)),
                to: index(to),
            })
        })
        .collect()
}

/// The scorecard as `afg score` prints it.
impl std::fmt::Display for Scorecard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let s = &self.score;
        writeln!(
            f,
            "  welfare           {:>12.3}   (OPT {:.3})",
            s.welfare, s.opt_welfare
        )?;
        writeln!(
            f,
            "  % of OPT          {:>12}",
            crate::solve::percent_text(s.percent_of_opt)
        )?;
        writeln!(f, "  coalition sizes   {:?}", self.coalition_sizes)?;
        writeln!(f, "  unassigned        {:>12}", self.unassigned)?;
        for (name, rate, moves) in [
            ("balanced", s.ns_rate_balanced, &self.moves_balanced),
            ("selfish ", s.ns_rate_selfish, &self.moves_selfish),
        ] {
            writeln!(
                f,
                "  NS_rate {name}  {:>11.1} %   ({} would move{})",
                100.0 * rate,
                moves.len(),
                moves_text(moves)
            )?;
        }
        Ok(())
    }
}

/// `: robot 3 (task 1 → 2), …` for the first few moves.
fn moves_text(moves: &[Move]) -> String {
    const SHOWN: usize = 5;
    let task = |t: i64| {
        if t < 0 {
            "none".to_owned()
        } else {
            t.to_string()
        }
    };
    let mut text: Vec<String> = moves
        .iter()
        .take(SHOWN)
        .map(|m| format!("robot {} ({} → {})", m.robot, task(m.from), task(m.to)))
        .collect();
    if moves.len() > SHOWN {
        text.push(format!("and {} more", moves.len() - SHOWN));
    }
    if text.is_empty() {
        String::new()
    } else {
        format!(": {}", text.join(", "))
    }
}

#[cfg(test)]
mod tests {
    use afg_baseline::{Allocator, Optimum};
    use afg_game::GeneratorConfig;

    use super::*;

    /// One robot moved away from the optimum: every listed move is a strict
    /// improvement by hand, and every robot not listed has none.
    #[test]
    fn moves_are_exactly_the_robots_with_a_strictly_better_place() {
        let inst = GeneratorConfig::paper(12, 3, 4).generate().unwrap();
        let mut a = Optimum.allocate(&inst).unwrap().assignment;
        let here = a.task_of(RobotId(0)).unwrap();
        a.set(RobotId(0), Some(TaskId((here.0 + 1) % 3)));
        let card = scorecard(&inst, &a).unwrap();
        assert!(!card.stable_balanced);
        for pref in [Preference::Balanced, Preference::Selfish] {
            let moves = if pref == Preference::Balanced {
                &card.moves_balanced
            } else {
                &card.moves_selfish
            };
            for i in inst.robot_ids() {
                let now = inst.current_score(&a, i, pref);
                let better = inst.task_ids().any(|j| {
                    Some(j) != a.task_of(i)
                        && a.others_in(i, j) < inst.capacity(j)
                        && afg_game::strictly_better(inst.score(&a, i, j, pref), now)
                });
                assert_eq!(moves.iter().any(|m| m.robot == i.0), better, "robot {i}");
            }
        }
        let text = card.to_string();
        assert!(text.contains("would move: robot 0"), "{text}");
        assert_eq!(card.unassigned, 0);
        // A robot with no task is refused in the paper's game.
        a.set(RobotId(3), None);
        let err = scorecard(&inst, &a).unwrap_err();
        assert!(err.to_string().contains("robot 3 has no task"), "{err}");
    }
}
