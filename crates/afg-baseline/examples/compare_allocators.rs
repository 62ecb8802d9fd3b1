//! Draw an instance from the paper's distribution and compare every allocator with the
//! exact optimum.
//!
//! `cargo run --release -p afg-baseline --example compare_allocators -- 200`

use afg_baseline::{Allocator, Method, Optimum};
use afg_game::{GeneratorConfig, Preference};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let robots: usize = std::env::args().nth(1).map_or(Ok(100), |s| s.parse())?;
    let instance = GeneratorConfig::paper(robots, 5, 42).generate()?;
    let opt = instance.welfare(&Optimum.allocate(&instance)?.assignment);
    println!("N = {robots}, M = 5, OPT welfare {opt:.3}\n");
    println!(
        "{:<18} {:>10} {:>9} {:>16} {:>10}",
        "method", "welfare", "% of OPT", "NS_rate (bal.)", "time"
    );
    for method in Method::ALL {
        let out = method.allocator(0).allocate(&instance)?;
        let welfare = instance.welfare(&out.assignment);
        println!(
            "{:<18} {:>10.3} {:>8.2}% {:>15.1}% {:>8.2}ms",
            method.name(),
            welfare,
            100.0 * welfare / opt,
            100.0 * instance.ns_rate(&out.assignment, Preference::Balanced),
            1e3 * out.stats.wall_time.as_secs_f64()
        );
    }
    Ok(())
}
