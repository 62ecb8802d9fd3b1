//! Build an instance of your own, score an assignment, check its stability and save
//! both as JSON.
//!
//! `cargo run -p afg-game --example my_instance`

use afg_game::{Assignment, Instance, Point, Preference, RobotId, Task, TaskId};

fn main() -> Result<(), afg_game::GameError> {
    // Four robots, two tasks; task 1 takes at most two robots.
    let robots = vec![
        Point::new(0.1, 0.1),
        Point::new(0.2, 0.3),
        Point::new(0.8, 0.9),
        Point::new(0.9, 0.7),
    ];
    let task = |x, y, reward, capacity| Task {
        position: Point::new(x, y),
        reward,
        eps: 2.0, // F(n) = r·log2(n + 1): concave, as eps ≥ φ requires
        capacity,
    };
    let tasks = vec![task(0.0, 0.0, 3.0, None), task(1.0, 1.0, 2.0, Some(2))];
    let instance = Instance::new(robots, tasks, 1.0)?;

    // Robots 0 and 1 on task 0, robots 2 and 3 on task 1.
    let mut a = Assignment::unassigned(4, 2);
    for (robot, t) in [(0, 0), (1, 0), (2, 1), (3, 1)] {
        a.set(RobotId(robot), Some(TaskId(t)));
    }
    instance.check(&a)?;
    println!("welfare            {:.4}", instance.welfare(&a));
    println!("coalition sizes    {:?}", a.sizes());
    println!(
        "balanced-stable    {} (NS_rate {:.0} %)",
        instance.is_stable(&a, Preference::Balanced),
        100.0 * instance.ns_rate(&a, Preference::Balanced)
    );

    // The versioned JSON formats that `afg solve --input` reads and writes.
    let dir = std::env::temp_dir();
    instance.write(&dir.join("my_instance.json"))?;
    println!(
        "instance           {}",
        dir.join("my_instance.json").display()
    );
    println!("assignment         {}", a.to_json());
    assert_eq!(Assignment::from_json(&a.to_json(), &instance)?, a);
    Ok(())
}
