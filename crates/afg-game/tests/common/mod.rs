//! What the afg-game tests share.

use afg_game::{Point, Task};

/// A task at (x, y) with no capacity.
pub fn task(x: f64, y: f64, reward: f64, eps: f64) -> Task {
    Task {
        position: Point::new(x, y),
        reward,
        eps,
        capacity: None,
    }
}
