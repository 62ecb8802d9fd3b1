//! Where a node branches: on a task between 0 and its threshold, or on a robot that
//! could bring a skill an earning task lacks.

use afg_game::{RobotId, TaskId};

use super::{Decision, Node, Pair, Search};

/// Where a node branches.
#[derive(Clone, Copy, Debug)]
pub(in super::super) enum Branch {
    /// An open task between 0 and its threshold, or an earning task that no robot may
    /// any longer bring a missing skill to: staffed, or not.
    Task(usize),
    /// An earning task short of a skill, and the cheapest robot free to bring it: it
    /// joins the task, or it may not.
    Pair(RobotId, TaskId),
}

impl Search<'_> {
    /// Where a node branches: first an open task that the node's Lagrangian relaxation
    /// (where skills are priced) holds a share of, neither none nor all of its team
    /// (the most value at stake: the smaller share times the team's value), as a
    /// MILP solver branches on its LP's fractions; then an open task whose envelope
    /// coalition is between 0 and its threshold (the most envelope value at stake), then
    /// the earning task short of a skill with the most value at stake — the task itself
    /// where it is open, else
    /// the cheapest robot free to bring the skill; where the relaxation prices earning
    /// tasks and fewer earn in it than may, an open task (module `count`); `None` when
    /// there is none of these (the relaxation is a real assignment, worth its bound).
    pub(super) fn branch(&self, node: &Node) -> Option<Branch> {
        let inst = self.instance;
        let sizes = &node.sizes;
        let split = (inst.task_ids().zip(&node.skill_earns))
            .filter(|&(j, &e)| {
                node.decisions[j.index()] == Decision::Open && e > 1e-9 && e < 1.0 - 1e-9
            })
            .map(|(j, &e)| {
                let team = inst.value_function(j).value(self.threshold(j));
                (j.index(), e.min(1.0 - e) * team)
            })
            .max_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((j, _)) = split {
            return Some(Branch::Task(j));
        }
        let task = inst
            .task_ids()
            .filter(|j| node.decisions[j.index()] == Decision::Open)
            .filter_map(|j| {
                let (n, k) = (sizes[j.index()], self.threshold(j));
                (n > 0 && n < k).then(|| {
                    let at_stake = n as f64 * inst.value_function(j).value(k) / k as f64;
                    (j.index(), at_stake)
                })
            })
            .max_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((j, _)) = task {
            return Some(Branch::Task(j));
        }
        // An open task short of a skill is decided first: not staffed, or staffed
        // (then its skills are branched on robot by robot).
        match self.skill_branch(node) {
            Some(Branch::Pair(_, j)) if node.decisions[j.index()] == Decision::Open => {
                Some(Branch::Task(j.index()))
            }
            Some(branch) => Some(branch),
            None => self.count_branch(node),
        }
    }

    /// The earning task short of a skill with the most value at stake, and the
    /// cheapest robot free to bring that skill there (the task itself where none is).
    pub(super) fn skill_branch(&self, node: &Node) -> Option<Branch> {
        let inst = self.instance;
        let a = node.assignment.as_ref()?; // kept in games with skills only
        let s = inst.num_skills();
        let held = inst.skills_held(a);
        let (j, _) = inst
            .task_ids()
            .filter(|&j| node.decisions[j.index()] != Decision::Unstaffed)
            .filter(|&j| a.size(j) >= self.threshold(j))
            .filter(|&j| !inst.skills_met(j, &held[j.index() * s..][..s]))
            .map(|j| (j, inst.coalition_value(j, a.size(j))))
            .max_by(|x, y| x.1.total_cmp(&y.1))?;
        let row = &held[j.index() * s..][..s];
        let short = (0..s).find(|&k| row[k] < u64::from(inst.requires(j)[k]))?;
        // A robot the node fixed somewhere, or kept out of j, is decided.
        let barred = self.barred(&node.pairs);
        let robot = inst
            .robot_ids()
            .filter(|&i| inst.skills(i)[short] > 0 && a.task_of(i) != Some(j))
            .filter(|&i| self.free(&barred, i, j))
            .min_by(|&x, &y| inst.cost(x, j).total_cmp(&inst.cost(y, j)));
        // Where every robot that could bring the skill was ruled out since the node was
        // made (a better assignment found), the task is staffed (no longer possible) or
        // not.
        Some(robot.map_or(Branch::Task(j.index()), |i| Branch::Pair(i, j)))
    }

    /// The two children of a branch: its decisions and fixed robots.
    pub(super) fn children(&self, node: &Node, branch: Branch) -> [(Vec<Decision>, Vec<Pair>); 2] {
        let with = |decision: Option<(usize, Decision)>, pair: Option<Pair>| {
            let mut decisions = node.decisions.clone();
            if let Some((j, d)) = decision {
                decisions[j] = d;
            }
            let mut pairs = node.pairs.clone();
            pairs.extend(pair);
            (decisions, pairs)
        };
        match branch {
            Branch::Task(j) => [
                with(Some((j, Decision::Staffed)), None),
                with(Some((j, Decision::Unstaffed)), None),
            ],
            Branch::Pair(i, j) => [
                with(None, Some((i, j, true))),
                with(None, Some((i, j, false))),
            ],
        }
    }

    /// A node's children, solved, that the best found does not close (none where the
    /// node's relaxation is a real assignment: it was offered to the best found when
    /// solved).
    pub(in super::super) fn expand(&mut self, node: &Node) -> Vec<Node> {
        let Some(branch) = self.branch(node) else {
            return Vec::new();
        };
        self.children(node, branch)
            .into_iter()
            .filter_map(|(decisions, pairs)| {
                let child = self.node(decisions, pairs, Some(node))?;
                (!self.closes(child.bound)).then_some(child)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use afg_game::{Family, Instance, Point, RobotId, Task, TaskId};

    use super::super::{Decision, Search};
    use super::Branch;

    /// A child's assignments are its parent's too, so its bound is never above its
    /// parent's, however the subgradient steps from the parent's skill prices land: in
    /// the first nodes of a best-first search of `sparse-skills` games (where those
    /// steps alone leave some children above).
    #[test]
    fn no_child_is_bounded_above_its_parent() {
        let mut children = 0;
        for seed in [6, 7] {
            let inst = (Family::SparseSkills.config(100, 20, seed).unwrap())
                .generate()
                .unwrap();
            let mut search = Search::exact(&inst);
            let mut root = search
                .node(search.root_decisions(), Vec::new(), None)
                .unwrap();
            search.price_root(&mut root, &|| false);
            let mut open = std::collections::BinaryHeap::from([root]);
            for _ in 0..300 {
                let Some(parent) = open.pop() else { break };
                for child in search.expand(&parent) {
                    assert!(child.bound <= parent.bound, "seed {seed}");
                    children += 1;
                    open.push(child);
                }
            }
        }
        assert!(children >= 300, "{children} children");
    }

    /// An open task short of a skill is branched on itself first; once it is staffed,
    /// on the cheapest robot that could bring the skill; and where every such robot
    /// has been ruled out since its node was made (a better assignment found), on the
    /// task again — staffed, which no assignment can be, or not — rather than closing
    /// as though the node's relaxation were a real assignment.
    #[test]
    fn a_task_short_of_a_skill_is_decided_then_its_robots() {
        let task = |x| Task {
            position: Point::new(x, 0.0),
            reward: 1.0,
            eps: 2.0,
            capacity: None,
        };
        // Robot 0 lacks the skill task 0 requires; robot 1, nearer task 1, holds it.
        let robots = vec![Point::new(0.1, 0.0), Point::new(0.9, 0.0)];
        let inst = Instance::new(robots, vec![task(0.0), task(1.0)], 1.0)
            .unwrap()
            .with_teams(vec![1, 1], &[vec![0], vec![1]], &[vec![1], vec![]])
            .unwrap();
        let mut search = Search::new(&inst);
        let root = search
            .node(search.root_decisions(), Vec::new(), None)
            .unwrap();
        let Some(Branch::Task(0)) = search.branch(&root) else {
            panic!("an open task short of a skill is decided first")
        };
        let [(decisions, pairs), _] = search.children(&root, Branch::Task(0));
        assert_eq!(decisions[0], Decision::Staffed);
        let staffed = search.node(decisions, pairs, Some(&root)).unwrap();
        assert!(matches!(
            search.branch(&staffed),
            Some(Branch::Pair(RobotId(1), TaskId(0)))
        ));
        search.forbidden = vec![false, false, true, false]; // robot 1 may not join task 0
        let Some(Branch::Task(0)) = search.branch(&staffed) else {
            panic!("closed, or a pair the search ruled out")
        };
        let [again, unstaffed] = search.children(&staffed, Branch::Task(0));
        assert!(search.node(again.0, again.1, Some(&staffed)).is_none());
        assert!(
            search
                .node(unstaffed.0, unstaffed.1, Some(&staffed))
                .is_some()
        );
    }

    /// A task that the Lagrangian relaxation holds a share of is branched on before
    /// any the envelope splits, the larger value at stake first; where it holds none
    /// or all of every team, the envelope's choice stands.
    #[test]
    fn a_share_of_a_team_in_the_lagrangian_relaxation_is_branched_on_first() {
        let task = |x, reward| Task {
            position: Point::new(x, 0.0),
            reward,
            eps: 2.0,
            capacity: None,
        };
        let robots = vec![Point::new(0.1, 0.0), Point::new(0.9, 0.0)];
        let tasks = vec![task(0.0, 1.0), task(1.0, 1.0), task(0.5, 3.0)];
        let inst = Instance::new(robots, tasks, 1.0)
            .unwrap()
            .with_teams(
                vec![1, 1, 1],
                &[vec![0], vec![1]],
                &[vec![1], vec![], vec![]],
            )
            .unwrap();
        let mut search = Search::new(&inst);
        let mut root = search
            .node(search.root_decisions(), Vec::new(), None)
            .unwrap();
        let envelope = format!("{:?}", search.branch(&root));
        root.skill_earns = vec![0.0, 0.5, 0.1];
        assert!(matches!(search.branch(&root), Some(Branch::Task(1))));
        root.skill_earns = vec![0.0, 0.5, 0.4]; // 0.4 of 3 is more at stake than 0.5 of 1
        assert!(matches!(search.branch(&root), Some(Branch::Task(2))));
        root.decisions[2] = Decision::Staffed;
        assert!(matches!(search.branch(&root), Some(Branch::Task(1))));
        root.decisions[2] = Decision::Open;
        root.skill_earns = vec![1.0, 0.0, 1.0];
        assert_eq!(format!("{:?}", search.branch(&root)), envelope);
    }
}
