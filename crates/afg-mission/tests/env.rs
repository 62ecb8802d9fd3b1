//! The mission as a multi-agent environment ([`MissionEnv`]): what each robot may do
//! and perceive, the team reward, failures leaving the episode, and one seed one
//! episode.

use afg_mission::{
    MissionConfig, MissionEnv, Perception, Preset, ROBOT_FEATURES, TASK_FEATURES, TEAM_FEATURES,
};

/// Plays an episode where every agent takes the first action its mask allows;
/// returns every epoch's (agents, observations, masks, reward).
type Epoch = (Vec<usize>, Vec<Vec<f32>>, Vec<Vec<bool>>, f64);

fn play(env: &mut MissionEnv) -> Vec<Epoch> {
    let mut epochs = Vec::new();
    loop {
        let agents = env.agents();
        let obs: Vec<Vec<f32>> = agents.iter().map(|&i| env.observe(i)).collect();
        let masks: Vec<Vec<bool>> = agents.iter().map(|&i| env.mask(i)).collect();
        let actions: Vec<(usize, usize)> = agents
            .iter()
            .zip(&masks)
            .map(|(&i, m)| (i, m.iter().position(|&ok| ok).unwrap()))
            .collect();
        let step = env.step(&actions).unwrap();
        for i in &step.failed {
            assert!(
                agents.contains(i) && !env.agents().contains(i),
                "{i} {agents:?} {:?} {step:?}",
                env.agents()
            );
        }
        epochs.push((agents, obs, masks, step.reward));
        if step.terminated || step.truncated {
            assert!(env.agents().is_empty());
            return epochs;
        }
    }
}

/// The rewards of an episode add up to the value of the work done; the same mission
/// gives the same episode; robots that fail leave it.
#[test]
fn rewards_add_up_and_a_seed_gives_one_episode() {
    let mission = MissionConfig::new(Preset::Attrition, 20, 6, 3)
        .generate()
        .unwrap();
    let mut env = MissionEnv::new(mission.clone(), Perception::default()).unwrap();
    let epochs = play(&mut env);
    let total: f64 = epochs.iter().map(|e| e.3).sum();
    let run = env.into_run();
    assert!((total - run.metrics.work_value).abs() < 1e-9);
    assert!(run.metrics.reward_done <= run.metrics.work_value + 1e-9);
    let mut again = MissionEnv::new(mission.clone(), Perception::default()).unwrap();
    assert_eq!(play(&mut again), epochs);
    // Attrition: some robots fail, and later epochs have fewer agents.
    assert!(epochs.last().unwrap().0.len() < 20);
    // Nobody ever moving does no work: every reward is 0.
    let mut idle = MissionEnv::new(mission, Perception::default()).unwrap();
    loop {
        let keep: Vec<(usize, usize)> = idle.agents().iter().map(|&i| (i, 6)).collect();
        let step = idle.step(&keep).unwrap();
        assert_eq!(step.reward, 0.0);
        if step.truncated {
            break;
        }
        assert!(!step.terminated);
    }
}

/// A robot knows the open tasks it sees, or that a neighbour knew at the last epoch;
/// its mask allows those and keeping its own; the observation has the task's features
/// exactly where it knows it, zeros elsewhere.
#[test]
fn robots_see_and_hear_only_what_is_in_range() {
    let mut config = MissionConfig::new(Preset::Static, 30, 5, 2);
    config.arena = 10.0;
    let mission = config.generate().unwrap();
    let deaf = Perception {
        sensing: Some(2.0),
        comm_radius: 0.0,
        ..Perception::default()
    };
    let env = MissionEnv::new(mission.clone(), deaf).unwrap();
    for i in env.agents() {
        let mask = env.mask(i);
        let obs = env.observe(i);
        assert_eq!(obs.len(), ROBOT_FEATURES + TASK_FEATURES * 5);
        assert!(mask[5], "keeping one's own is always allowed");
        for (j, t) in mission.tasks.iter().enumerate() {
            let seen = mission.robots[i].position.distance(t.position) <= 2.0;
            assert_eq!(mask[j], seen, "robot {i}, task {j}");
            let row = &obs[ROBOT_FEATURES + TASK_FEATURES * j..][..TASK_FEATURES];
            assert_eq!(row[0], f32::from(u8::from(seen)));
            if seen {
                let d = mission.robots[i].position.distance(t.position) as f32;
                assert!((row[3] - d).abs() < 1e-5);
            } else {
                assert!(row.iter().all(|&x| x == 0.0));
            }
        }
    }
    // Bad actions and knobs are refused with what is wrong.
    let mut env = MissionEnv::new(mission.clone(), Perception::default()).unwrap();
    let error = env.step(&[(0, 7)]).unwrap_err().to_string();
    assert!(error.contains("actions 0..=5"), "{error}");
    let error = env.step(&[(30, 0)]).unwrap_err().to_string();
    assert!(error.contains("robots are 0..30"), "{error}");
    let bad = Perception {
        sensing: Some(-1.0),
        ..Perception::default()
    };
    assert!(MissionEnv::new(mission, bad).is_err());
}

/// A step's reward computed by hand: robots already at their one task, epochs every
/// 0.5 time units; each epoch the coalition of n robots does `work_rate(n, eps)` units
/// of work per time unit, worth `r` each, until the workload is done.
#[test]
fn a_steps_reward_is_the_reward_rate_times_the_time() {
    for robots in [1usize, 2] {
        let mut mission = MissionConfig::new(Preset::Static, robots, 1, 4)
            .generate()
            .unwrap();
        let task = mission.tasks[0].clone();
        for robot in &mut mission.robots {
            robot.position = task.position;
        }
        let perception = Perception {
            decide_every: Some(0.5),
            ..Perception::default()
        };
        let mut env = MissionEnv::new(mission, perception).unwrap();
        let rate = afg_mission::work_rate(robots, task.eps);
        let (mut time, mut total) = (0.0, 0.0);
        loop {
            let go: Vec<(usize, usize)> = env.agents().iter().map(|&i| (i, 0)).collect();
            let step = env.step(&go).unwrap();
            let dt = (0.5f64).min(task.workload / rate - time);
            let expected = task.reward * rate * dt;
            assert!(
                (step.reward - expected).abs() < 1e-9,
                "{robots} robot(s) at t = {time}: reward {} for {expected}",
                step.reward
            );
            (time, total) = (time + 0.5, total + step.reward);
            if step.terminated {
                break;
            }
        }
        assert!((total - task.reward * task.workload).abs() < 1e-9);
    }
}

/// News spreads one hop per epoch, computed by hand: on a line, robot 0 stands on the
/// task (and sees it), robots 1 and 2 one and two units further (out of sight, each
/// within hearing of the one before), robot 3 far away. Robot 1 knows the task after
/// one epoch, robot 2 after two, robot 3 never.
#[test]
fn robots_hear_of_tasks_from_their_neighbours_one_hop_per_epoch() {
    let mut mission = MissionConfig::new(Preset::Static, 4, 1, 1)
        .generate()
        .unwrap();
    mission.tasks[0].workload = 1e6;
    let at = mission.tasks[0].position;
    for (i, robot) in mission.robots.iter_mut().enumerate() {
        let offset = if i == 3 { 50.0 } else { i as f64 };
        robot.position = afg_game::Point::new(at.x + offset, at.y);
    }
    let perception = Perception {
        sensing: Some(0.5),
        comm_radius: 1.2,
        decide_every: Some(0.5),
        ..Perception::default()
    };
    let mut env = MissionEnv::new(mission, perception).unwrap();
    let knows = |env: &MissionEnv| -> Vec<bool> { (0..4).map(|i| env.mask(i)[0]).collect() };
    assert_eq!(knows(&env), [true, false, false, false]);
    let keep: Vec<(usize, usize)> = (0..4).map(|i| (i, 1)).collect();
    env.step(&keep).unwrap();
    assert_eq!(knows(&env), [true, true, false, false]);
    env.step(&keep).unwrap();
    assert_eq!(knows(&env), [true, true, true, false]);
    env.step(&keep).unwrap();
    assert_eq!(knows(&env), [true, true, true, false]);
}

/// Teams in the observation, by hand: three robots, one holding the only skill; task 0
/// needs two robots and that skill, task 1 four robots (more than there are: masked).
/// Robot 0 stands on task 0, robot 1 is one unit away (speed 1); both head there.
#[test]
fn teams_are_observed_and_unstaffable_tasks_masked() {
    let mut mission = MissionConfig::new(Preset::Static, 3, 2, 1)
        .generate()
        .unwrap();
    let at = mission.tasks[0].position;
    mission.tasks[0].workload = 1e6;
    mission.tasks[0].min_team = 2;
    mission.tasks[0].requires = vec![1];
    mission.tasks[1].min_team = 4;
    mission.tasks[1].requires = vec![0];
    for (i, robot) in mission.robots.iter_mut().enumerate() {
        robot.skills = vec![u32::from(i == 0)];
        robot.speed = 1.0;
        robot.position = afg_game::Point::new(at.x + i as f64, at.y);
    }
    let perception = Perception {
        decide_every: Some(0.5),
        teams: true,
        ..Perception::default()
    };
    let mut env = MissionEnv::new(mission, perception).unwrap();
    let (robot, task) = (ROBOT_FEATURES + 1, TASK_FEATURES + TEAM_FEATURES + 1);
    assert_eq!(env.observation_len(), robot + 2 * task);
    assert_eq!(env.mask(0), [true, false, true]);
    let team = |env: &MissionEnv, i: usize| -> Vec<f32> {
        let obs = env.observe(i);
        assert_eq!(
            obs[ROBOT_FEATURES],
            if i == 0 { 1.0 } else { 0.0 },
            "own skill"
        );
        obs[robot + TASK_FEATURES..][..TEAM_FEATURES + 1].to_vec()
    };
    // k / N, present / k, heading or present / k, complete, the skill's missing share.
    assert_eq!(team(&env, 1), [2.0 / 3.0, 0.0, 0.0, 0.0, 1.0]);
    env.step(&[(0, 0), (1, 0), (2, 2)]).unwrap();
    // t = 0.5: robot 0 is there, robot 1 on its way; the two hold the skill.
    assert_eq!(team(&env, 2), [2.0 / 3.0, 0.5, 1.0, 0.0, 0.0]);
    env.step(&[(0, 2), (1, 2), (2, 2)]).unwrap();
    // t = 1: both are there, the team is complete.
    assert_eq!(team(&env, 2), [2.0 / 3.0, 1.0, 1.0, 1.0, 0.0]);
}
