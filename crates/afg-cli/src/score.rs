//! `afg score`: anyone's assignment (yours, GRAPE's, another tool's) judged against
//! the game: welfare, % of OPT, coalitions, stability, the robots that would move.

use std::path::PathBuf;

use afg_eval::scorecard::{Scorecard, scorecard};
use afg_game::Assignment;
use afg_game::io::read_instances;
use anyhow::{Context, Result, bail};
use clap::Args;

/// `afg score`: the instances and the assignments to judge.
#[derive(Args)]
pub struct ScoreArgs {
    /// The instances: one instance JSON file, or JSON Lines; "-" reads standard input.
    #[arg(long)]
    input: PathBuf,
    /// The assignments, one JSON document per line in the order of the instances
    /// (format "afg-assignment": `tasks[i]` is robot i's task, -1 for none), as
    /// `afg solve --out` writes them.
    #[arg(long)]
    assignment: PathBuf,
    /// Print JSON (one object per instance, the field names of `afg solve --json`)
    /// instead of text.
    #[arg(long)]
    json: bool,
}

/// Scores every assignment against its instance and prints the scorecards.
///
/// # Errors
/// An unreadable file, an assignment that does not fit its instance (a task out of
/// range, a wrong length, a capacity exceeded), or a different number of assignments
/// and instances.
pub fn run(args: ScoreArgs) -> Result<()> {
    let instances = read_instances(&args.input)?;
    let text = std::fs::read_to_string(&args.assignment)
        .with_context(|| format!("reading {}", args.assignment.display()))?;
    let lines: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .collect();
    if lines.len() != instances.len() {
        bail!(
            "{} holds {} assignment(s) for the {} instance(s) of {}",
            args.assignment.display(),
            lines.len(),
            instances.len(),
            args.input.display()
        );
    }
    let cards = instances
        .iter()
        .zip(&lines)
        .map(|(instance, &(i, line))| {
            let where_ = || format!("{} line {}", args.assignment.display(), i + 1);
            let assignment = Assignment::from_json(line, instance).with_context(where_)?;
            scorecard(instance, &assignment).with_context(where_)
        })
        .collect::<Result<Vec<Scorecard>>>()?;
    for (k, card) in cards.iter().enumerate() {
        if args.json {
            println!("{}", serde_json::to_string(card)?);
        } else {
            println!("instance {k}\n{card}");
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use afg_baseline::{Allocator, Greedy, Optimum};
    use afg_game::GeneratorConfig;

    fn temp(name: &str) -> std::path::PathBuf {
        let d = std::env::temp_dir().join(format!("afg-score-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn solve_out_files_score_back_and_bad_assignments_are_refused() {
        let dir = temp("files");
        let insts: Vec<_> = (0..2)
            .map(|s| GeneratorConfig::paper(15, 3, s).generate().unwrap())
            .collect();
        let input = dir.join("in.jsonl");
        std::fs::write(&input, afg_game::io::dataset_to_jsonl(&insts)).unwrap();
        let lines: String = insts
            .iter()
            .zip([true, false])
            .map(|(inst, opt)| {
                let a = if opt {
                    Optimum.allocate(inst)
                } else {
                    Greedy.allocate(inst)
                };
                a.unwrap().assignment.to_json() + "\n"
            })
            .collect();
        let out = dir.join("a.jsonl");
        std::fs::write(&out, &lines).unwrap();
        let line = format!(
            "score --input {} --assignment {}",
            input.display(),
            out.display()
        );
        crate::afg(&line).unwrap();
        crate::afg(&format!("{line} --json")).unwrap();

        for (bad, needle) in [
            (
                r#"{"format":"afg-assignment","version":1,"tasks":[7,0,0,0,0,0,0,0,0,0,0,0,0,0,0]}"#,
                "task 7",
            ),
            (
                r#"{"format":"afg-assignment","version":1,"tasks":[0,0]}"#,
                "2 entries",
            ),
        ] {
            std::fs::write(&out, format!("{bad}\n{bad}\n")).unwrap();
            let err = crate::afg(&line).unwrap_err();
            let text = format!("{err:#}");
            assert!(text.contains("line 1") && text.contains(needle), "{text}");
        }
        std::fs::write(&out, lines.lines().next().unwrap()).unwrap();
        let err = crate::afg(&line).unwrap_err();
        assert!(
            err.to_string()
                .contains("1 assignment(s) for the 2 instance(s)"),
            "{err}"
        );
    }
}
