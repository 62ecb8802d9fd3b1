pub fn run(_: SolveArgs) -> anyhow::Result<()> {
    Ok(())
}
#[derive(clap::Args)]
pub struct SolveArgs {}
