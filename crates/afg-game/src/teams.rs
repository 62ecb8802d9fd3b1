//! The team games: tasks that earn nothing until their coalition is large enough
//! (`min_team`), and robots with skills that tasks require in given amounts.
//!
//! A coalition of n robots at task j earns `F_j(n)` only when `n ≥ k_j` (its
//! `min_team`, 1 by default) and, for every skill s, its robots hold at least
//! `requires_j[s]` of it together; otherwise it earns 0 and its robots still pay their
//! travel. Without either rule the game is the paper's.

use crate::{Assignment, GameError, Instance, RobotId, TaskId};

/// What the tasks need of their coalitions: a minimum team size per task, and a
/// skill matrix (S skills: one amount per robot and skill, one requirement per task and
/// skill). The default has neither: the paper's game.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct TeamRules {
    /// `k_j` of every task (all 1 when empty).
    pub(crate) min_team: Vec<usize>,
    /// S, the number of skills (0: no skill rule).
    pub(crate) num_skills: usize,
    /// Row-major N × S: robot i's amount of skill s.
    pub(crate) skills: Vec<u32>,
    /// Row-major M × S: what task j needs of skill s.
    pub(crate) requires: Vec<u32>,
}

/// The number of skills of the given lists: the length of the non-empty ones, which
/// must all agree (an empty list holds none of every skill).
fn skill_count(skills: &[Vec<u32>], requires: &[Vec<u32>]) -> Result<usize, GameError> {
    let mut count: Option<(usize, &'static str, usize)> = None;
    let lists = skills
        .iter()
        .enumerate()
        .map(|(i, s)| ("robot", i, s))
        .chain(requires.iter().enumerate().map(|(j, r)| ("task", j, r)));
    for (what, index, list) in lists {
        if list.is_empty() {
            continue;
        }
        match count {
            None => count = Some((list.len(), what, index)),
            Some((len, first, first_index)) if len != list.len() => {
                return Err(GameError::SkillLength {
                    what,
                    index,
                    len: list.len(),
                    expected: len,
                    first,
                    first_index,
                });
            }
            Some(_) => {}
        }
    }
    Ok(count.map_or(0, |(len, ..)| len))
}

/// Flattens per-row lists into a row-major matrix of `width` columns (empty rows: 0).
fn matrix(rows: &[Vec<u32>], width: usize) -> Vec<u32> {
    let mut flat = vec![0; rows.len() * width];
    for (row, list) in flat.chunks_mut(width.max(1)).zip(rows) {
        if !list.is_empty() {
            row.copy_from_slice(list);
        }
    }
    flat
}

impl TeamRules {
    /// Rules from per-task thresholds and per-robot / per-task skill lists, checked
    /// against N robots and M tasks.
    pub(crate) fn new(
        num_robots: usize,
        num_tasks: usize,
        min_team: Vec<usize>,
        skills: &[Vec<u32>],
        requires: &[Vec<u32>],
    ) -> Result<Self, GameError> {
        for (what, len, expected) in [
            ("min_team", min_team.len(), num_tasks),
            ("requires", requires.len(), num_tasks),
            ("skills", skills.len(), num_robots),
        ] {
            if len != 0 && len != expected {
                return Err(GameError::TeamListLength {
                    what,
                    len,
                    expected,
                });
            }
        }
        if let Some(task) = min_team.iter().position(|&k| k == 0) {
            return Err(GameError::InvalidMinTeam { task });
        }
        let num_skills = skill_count(skills, requires)?;
        let (skills, requires) = if num_skills == 0 {
            (Vec::new(), Vec::new())
        } else {
            let mut robots = skills.to_vec();
            robots.resize(num_robots, Vec::new());
            let mut tasks = requires.to_vec();
            tasks.resize(num_tasks, Vec::new());
            (matrix(&robots, num_skills), matrix(&tasks, num_skills))
        };
        let min_team = if min_team.iter().all(|&k| k == 1) {
            Vec::new()
        } else {
            min_team
        };
        Ok(TeamRules {
            min_team,
            num_skills,
            skills,
            requires,
        })
    }
}

impl Instance {
    /// The same game with team rules: task j earns `F_j(n)` only when its coalition has
    /// at least `min_team[j]` robots and, for every skill s, holds at least
    /// `requires[j][s]` of it (robot i holds `skills[i][s]`). An empty list leaves that
    /// rule out (all thresholds 1, no skills); an empty robot or task entry holds none
    /// of every skill. The robots' skills and the tasks' requirements must all have the
    /// same length S when not empty.
    ///
    /// # Errors
    /// [`GameError::InvalidMinTeam`] for a threshold of 0,
    /// [`GameError::TeamListLength`] for a list with neither 0 nor one entry per task
    /// (robot), [`GameError::SkillLength`] for skill lists of different lengths.
    ///
    /// # Examples
    /// ```
    /// use afg_game::{Assignment, Instance, Point, Task, TaskId};
    /// let task = Task { position: Point::new(0.0, 0.0), reward: 2.0, eps: 2.0, capacity: None };
    /// let robots = vec![Point::new(1.0, 0.0), Point::new(0.0, 1.0)];
    /// let inst = Instance::new(robots, vec![task], 1.0)?.with_teams(vec![2], &[], &[])?;
    /// let one = Assignment::from_tasks(&inst, vec![Some(TaskId(0)), None])?;
    /// assert_eq!(inst.welfare(&one), -1.0); // a team of one earns nothing
    /// let two = Assignment::from_tasks(&inst, vec![Some(TaskId(0)); 2])?;
    /// assert!((inst.welfare(&two) - (2.0 * 3f64.log2() - 2.0)).abs() < 1e-12);
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    pub fn with_teams(
        mut self,
        min_team: Vec<usize>,
        skills: &[Vec<u32>],
        requires: &[Vec<u32>],
    ) -> Result<Self, GameError> {
        self.teams = TeamRules::new(
            self.num_robots(),
            self.num_tasks(),
            min_team,
            skills,
            requires,
        )?;
        Ok(self)
    }

    /// Whether any task needs a team: a threshold above 1 or a skill requirement. Such
    /// games are NP-hard; allocators built for the paper's concave game refuse them.
    pub fn has_teams(&self) -> bool {
        !self.teams.min_team.is_empty() || self.has_skill_rules()
    }

    /// Whether any task requires a skill (then a coalition's value depends on which
    /// robots it holds, not only on how many).
    pub fn has_skill_rules(&self) -> bool {
        self.teams.requires.iter().any(|&r| r > 0)
    }

    /// Task j's threshold `k_j` (1 unless set).
    #[inline]
    pub fn min_team(&self, task: TaskId) -> usize {
        self.teams.min_team.get(task.index()).copied().unwrap_or(1)
    }

    /// S, the number of skills (0 without the skill rule).
    pub fn num_skills(&self) -> usize {
        self.teams.num_skills
    }

    /// Robot i's amount of every skill (empty when S = 0).
    pub fn skills(&self, robot: RobotId) -> &[u32] {
        let s = self.teams.num_skills;
        &self.teams.skills[robot.index() * s..][..s]
    }

    /// What task j requires of every skill (empty when S = 0).
    pub fn requires(&self, task: TaskId) -> &[u32] {
        let s = self.teams.num_skills;
        &self.teams.requires[task.index() * s..][..s]
    }

    /// Whether a coalition holding `held[s]` of every skill meets task j's requirements.
    pub fn skills_met(&self, task: TaskId, held: &[u64]) -> bool {
        self.requires(task)
            .iter()
            .zip(held)
            .all(|(&need, &have)| have >= u64::from(need))
    }

    /// Whether task j earns with a coalition of `size` robots holding `held[s]` of every
    /// skill: at or above its threshold and holding every skill it requires.
    ///
    /// # Examples
    /// ```
    /// use afg_game::{Instance, Point, Task, TaskId};
    /// let task = Task { position: Point::new(0.0, 0.0), reward: 1.0, eps: 2.0, capacity: None };
    /// let robots = vec![Point::new(1.0, 0.0), Point::new(2.0, 0.0)];
    /// let inst = Instance::new(robots, vec![task], 1.0)?.with_teams(vec![2], &[vec![0], vec![1]], &[vec![1]])?;
    /// assert!(!inst.earns(TaskId(0), 1, &[1])); // below the threshold of 2
    /// assert!(!inst.earns(TaskId(0), 2, &[0])); // without the skill
    /// assert!(inst.earns(TaskId(0), 2, &[1]));
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    pub fn earns(&self, task: TaskId, size: usize, held: &[u64]) -> bool {
        size >= self.min_team(task) && self.skills_met(task, held)
    }

    /// Which tasks earn in `assignment` ([`Instance::earns`] for every coalition).
    ///
    /// # Examples
    /// ```
    /// use afg_game::{Assignment, Instance, Point, Task, TaskId};
    /// let task = Task { position: Point::new(0.0, 0.0), reward: 1.0, eps: 2.0, capacity: None };
    /// let robots = vec![Point::new(1.0, 0.0), Point::new(2.0, 0.0)];
    /// let inst = Instance::new(robots, vec![task], 1.0)?.with_teams(vec![1], &[vec![0], vec![1]], &[vec![1]])?;
    /// let alone = Assignment::from_tasks(&inst, vec![Some(TaskId(0)), None])?;
    /// assert_eq!(inst.earning_tasks(&alone), [false]);
    /// let both = Assignment::from_tasks(&inst, vec![Some(TaskId(0)); 2])?;
    /// assert_eq!(inst.earning_tasks(&both), [true]);
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    pub fn earning_tasks(&self, assignment: &Assignment) -> Vec<bool> {
        let held = self.skills_held(assignment);
        let s = self.num_skills();
        self.task_ids()
            .map(|j| self.earns(j, assignment.size(j), &held[j.index() * s..][..s]))
            .collect()
    }

    /// The skills each coalition of `assignment` holds: row-major M × S totals.
    pub fn skills_held(&self, assignment: &Assignment) -> Vec<u64> {
        let s = self.teams.num_skills;
        let mut held = vec![0u64; self.num_tasks() * s];
        if s == 0 {
            return held;
        }
        for robot in self.robot_ids() {
            if let Some(task) = assignment.task_of(robot) {
                let row = &mut held[task.index() * s..][..s];
                for (h, &q) in row.iter_mut().zip(self.skills(robot)) {
                    *h += u64::from(q);
                }
            }
        }
        held
    }

    /// The fewest members with which a coalition at task j can earn: its threshold, or
    /// more where fewer robots cannot hold the skills it requires. Counted over the
    /// kinds of robot in the game (their skill rows), each kind as often as needed — a
    /// lower bound where a kind is rare; where the requirements are too many to search
    /// (more than 4 096 partial covers), the largest of `requires[s] / max_i skill[i][s]`
    /// rounded up. `None` where some required skill no robot holds.
    ///
    /// A game whose thresholds are raised to these is the same game (a smaller team
    /// never earns), but an exact solver's relaxation of it is tighter.
    ///
    /// # Examples
    /// ```
    /// use afg_game::{Instance, Point, Task, TaskId};
    /// let task = Task { position: Point::new(0.0, 0.0), reward: 1.0, eps: 2.0, capacity: None };
    /// let robots = vec![Point::new(0.0, 0.0); 3];
    /// // Robots hold skill 0, skill 1, and both; task 0 needs two of each, task 1 none.
    /// let inst = Instance::new(robots, vec![task; 3], 1.0)?.with_teams(
    ///     vec![1, 3, 1],
    ///     &[vec![1, 0], vec![0, 1], vec![1, 1]],
    ///     &[vec![2, 2], vec![], vec![0, 4]],
    /// )?;
    /// assert_eq!(inst.smallest_team(TaskId(0)), Some(2)); // two robots holding both
    /// assert_eq!(inst.smallest_team(TaskId(1)), Some(3)); // its threshold
    /// assert_eq!(inst.smallest_team(TaskId(2)), Some(4));
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    pub fn smallest_team(&self, task: TaskId) -> Option<usize> {
        self.smallest_team_of(task, &self.robot_kinds())
    }

    /// [`Instance::smallest_team`] of every task, the robots' kinds read once: O(N S)
    /// and then a small search per task that requires skills.
    ///
    /// # Examples
    /// ```
    /// use afg_game::{GeneratorKnobs, TaskId};
    /// let knobs = GeneratorKnobs { skills: Some(2), requires: Some((0, 3)), ..GeneratorKnobs::default() };
    /// let inst = knobs.config(20, 4, 1)?.generate()?;
    /// let all = inst.smallest_teams();
    /// assert!(inst.task_ids().all(|j| all[j.index()] == inst.smallest_team(j)));
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    pub fn smallest_teams(&self) -> Vec<Option<usize>> {
        let kinds = self.robot_kinds();
        self.task_ids()
            .map(|j| self.smallest_team_of(j, &kinds))
            .collect()
    }

    /// The distinct skill rows of the robots.
    fn robot_kinds(&self) -> Vec<&[u32]> {
        let mut kinds: Vec<&[u32]> = self.robot_ids().map(|i| self.skills(i)).collect();
        kinds.sort_unstable();
        kinds.dedup();
        kinds
    }

    /// [`Instance::smallest_team`] of task j among robots of `kinds` (distinct rows).
    fn smallest_team_of(&self, task: TaskId, robot_kinds: &[&[u32]]) -> Option<usize> {
        let k = self.min_team(task);
        let need = self.requires(task);
        if need.iter().all(|&r| r == 0) {
            return Some(k);
        }
        let s = need.len();
        // Each kind of robot, its amounts capped at the need; none that holds nothing
        // needed, none that another kind holds at least as much as of every skill.
        let mut kinds: Vec<Vec<u32>> = Vec::new();
        for row in robot_kinds {
            let kind: Vec<u32> = (row.iter().zip(need)).map(|(&q, &r)| q.min(r)).collect();
            let covers = |a: &[u32], b: &[u32]| a.iter().zip(b).all(|(x, y)| x >= y);
            if kind.iter().all(|&q| q == 0) || kinds.iter().any(|other| covers(other, &kind)) {
                continue;
            }
            kinds.retain(|other| !covers(&kind, other));
            kinds.push(kind);
        }
        if (0..s).any(|t| need[t] > 0 && kinds.iter().all(|kind| kind[t] == 0)) {
            return None;
        }
        let states = need
            .iter()
            .try_fold(1usize, |all, &r| all.checked_mul(r as usize + 1))
            .filter(|&states| states <= MAX_COVER_STATES);
        let fewest = match states {
            Some(states) => fewest_covering(need, &kinds, states),
            None => (0..s)
                .filter(|&t| need[t] > 0)
                .map(|t| {
                    let most = kinds.iter().map(|kind| kind[t]).max().unwrap_or(1);
                    need[t].div_ceil(most) as usize
                })
                .max()
                .unwrap_or(0),
        };
        Some(k.max(fewest))
    }

    /// The tasks no coalition can ever staff: a threshold above the number of robots
    /// or the task's capacity, or a skill that all the robots together hold less of
    /// than the task needs. Legal (they earn nothing); front ends warn about them.
    ///
    /// # Examples
    /// ```
    /// use afg_game::{Instance, Point, Task, TaskId};
    /// let task = Task { position: Point::new(0.0, 0.0), reward: 1.0, eps: 2.0, capacity: None };
    /// let inst = Instance::new(vec![Point::new(0.0, 0.0)], vec![task; 3], 1.0)?
    ///     .with_teams(vec![1, 2, 1], &[vec![1, 0]], &[vec![], vec![], vec![0, 1]])?;
    /// assert_eq!(inst.unstaffable_tasks(), vec![TaskId(1), TaskId(2)]);
    /// # Ok::<(), afg_game::GameError>(())
    /// ```
    pub fn unstaffable_tasks(&self) -> Vec<TaskId> {
        let s = self.teams.num_skills;
        let mut everyone = vec![0u64; s];
        for robot in self.robot_ids() {
            for (e, &q) in everyone.iter_mut().zip(self.skills(robot)) {
                *e += u64::from(q);
            }
        }
        self.task_ids()
            .filter(|&j| {
                let k = self.min_team(j);
                k > self.num_robots() || k > self.capacity(j) || !self.skills_met(j, &everyone)
            })
            .collect()
    }
}

/// The most partial covers [`Instance::smallest_team`] searches.
const MAX_COVER_STATES: usize = 4096;

/// The fewest of `kinds` (each as often as needed, each capped at `need`) whose sum
/// reaches `need`: a breadth-first search over the `states` partial sums (mixed radix,
/// skill 0 the lowest digit).
fn fewest_covering(need: &[u32], kinds: &[Vec<u32>], states: usize) -> usize {
    let digits = |mut state: usize| {
        need.iter().map(move |&r| {
            let radix = r as usize + 1;
            let digit = state % radix;
            state /= radix;
            digit as u32
        })
    };
    let encode = |sum: &mut dyn Iterator<Item = u32>| {
        let (mut state, mut scale) = (0, 1);
        for (d, &r) in sum.zip(need) {
            state += d as usize * scale;
            scale *= r as usize + 1;
        }
        state
    };
    let mut steps = vec![usize::MAX; states];
    steps[0] = 0;
    let mut queue = std::collections::VecDeque::from([0usize]);
    while let Some(state) = queue.pop_front() {
        if state == states - 1 {
            return steps[state];
        }
        for kind in kinds {
            let next = encode(
                &mut digits(state)
                    .zip(kind.iter().zip(need))
                    .map(|(d, (&q, &r))| (d + q).min(r)),
            );
            if steps[next] == usize::MAX {
                steps[next] = steps[state] + 1;
                queue.push_back(next);
            }
        }
    }
    unreachable!("every needed skill is held by some kind")
}

/// The warning front ends give of the tasks (by index) that no team can staff
/// ([`Instance::unstaffable_tasks`]); `None` where there are none.
///
/// # Examples
/// ```
/// assert_eq!(afg_game::unstaffable_warning(&[]), None);
/// assert!(afg_game::unstaffable_warning(&[0, 2]).unwrap().starts_with("no team can staff tasks 0, 2 "));
/// ```
pub fn unstaffable_warning(tasks: &[usize]) -> Option<String> {
    let names: Vec<String> = tasks.iter().map(ToString::to_string).collect();
    let (plural, they) = if tasks.len() == 1 {
        ("", "it will")
    } else {
        ("s", "they will")
    };
    (!tasks.is_empty()).then(|| {
        format!(
            "no team can staff task{plural} {} (a threshold above the robots or the capacity, or a skill the robots lack): {they} earn nothing",
            names.join(", ")
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn skill_lists_of_different_lengths_are_refused_naming_both() {
        let err = skill_count(&[vec![1, 0], vec![]], &[vec![1]]).unwrap_err();
        assert_eq!(
            err.to_string(),
            "task 0 lists 1 skills but robot 0 lists 2: every non-empty `skills` and `requires` list must have the same length"
        );
        assert_eq!(
            skill_count(&[vec![], vec![2, 0]], &[vec![0, 1]]).unwrap(),
            2
        );
        assert_eq!(skill_count(&[], &[]).unwrap(), 0);
    }

    #[test]
    fn empty_rows_hold_none_of_every_skill() {
        assert_eq!(
            matrix(&[vec![1, 2], vec![], vec![3, 4]], 2),
            [1, 2, 0, 0, 3, 4]
        );
    }
}
