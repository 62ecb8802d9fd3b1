//! `afg solve --from`: warm-start reallocation after robots or tasks changed.

use std::path::Path;

use afg_baseline::Method;
use afg_eval::realloc::{dynamics_after, reallocate};
use afg_game::Instance;
use afg_game::fs::{write_atomic, write_atomic_making_dirs};
use afg_game::realloc::PreviousAssignment;
use anyhow::{Context, Result, bail};

/// What `afg solve` writes and prints: its `--out`, `--svg` and `--json`.
pub struct Outputs<'a> {
    /// The assignment file.
    pub out: Option<&'a Path>,
    /// The map beside OPT from scratch.
    pub svg: Option<&'a Path>,
    /// JSON instead of text.
    pub json: bool,
}

/// `afg solve --from FILE`: the warm start from a previous assignment, against OPT
/// from scratch.
///
/// # Errors
/// More than one instance, a method other than da / da-balanced, or an assignment
/// file that does not fit the instance.
pub fn run(
    method: Option<Method>,
    from: &Path,
    instances: &[Instance],
    outputs: &Outputs,
) -> Result<()> {
    let Some(preference) = method
        .filter(|&m| m != Method::Opt)
        .and_then(dynamics_after)
    else {
        bail!("--from warm-starts best-response dynamics: use --method da-balanced or --method da")
    };
    let [instance] = instances else {
        bail!(
            "--from reallocates one instance; the input holds {}",
            instances.len()
        );
    };
    let text =
        std::fs::read_to_string(from).with_context(|| format!("reading {}", from.display()))?;
    let previous = PreviousAssignment::from_json(&text)
        .with_context(|| format!("reading {}", from.display()))?;
    let r = reallocate(instance, &previous, preference)
        .with_context(|| format!("carrying {} over", from.display()))?;
    let name = format!(
        "{} warm-started from {}",
        method.expect("checked"),
        from.display()
    );
    if let Some(out) = outputs.out {
        let line = r
            .assignment
            .to_json_with_summary(Some(serde_json::to_value(&r)?));
        write_atomic(out, format!("{line}\n").as_bytes())?;
    }
    if let Some(svg) = outputs.svg {
        let map = afg_eval::figures::beside_optimum_svg(
            instance,
            "OPT from scratch",
            "warm start",
            &r.assignment,
        )?;
        write_atomic_making_dirs(svg, map.as_bytes())?;
    }
    if outputs.json {
        println!("{}", serde_json::to_string_pretty(&r)?);
        return Ok(());
    }
    print!("{name}\n{r}");
    Ok(())
}
