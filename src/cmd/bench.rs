//! `naosoccer bench ...`: benchmarks that print figures. Each benchmark's
//! body lives beside the subcommand it measures (`bench_sim` in play.rs, ...).
use clap::Subcommand;

#[derive(Subcommand, Debug)]
pub enum BenchCommand {
    /// Bare physics floor vs a full in-process match, and the real-time factor.
    Sim,
}

pub fn run(b: BenchCommand) -> anyhow::Result<()> {
    match b {
        BenchCommand::Sim => anyhow::bail!("`bench sim` is being built"),
    }
}
