//! `naosoccer bench ...`: benchmarks that print figures. Each benchmark's
//! body lives beside the subcommand it measures (`bench_sim` in play.rs, ...).
use clap::Subcommand;

#[derive(Subcommand, Debug)]
pub enum BenchCommand {
    /// Bare physics floor vs a full in-process match, and the real-time factor.
    ///
    /// Steps the bare rapier world (the match's very bodies, moved about by
    /// the cheapest possible driving: no gait model, no rules, no policies)
    /// as many times as a whole match does, then plays that match in process
    /// (physics, referee, scripted policies on both sides), and prints both
    /// wall times, their ratio and the real-time factor. Build with
    /// `--release` for meaningful figures.
    Sim(super::play::BenchSimArgs),
    /// The match server over loopback TCP, with real robot clients.
    ///
    /// One lockstep match with 8 robot clients (control ticks a second, and
    /// the same match in process for comparison), many lockstep matches at
    /// once (errors and missed ticks counted), and real-time matches at the
    /// configured rate (99th-percentile tick lateness). Build with
    /// `--release` for meaningful figures.
    Server(super::bench_server::BenchServerArgs),
    /// PPO training speed end to end, in robot transitions a second.
    ///
    /// Trains PPO against the scripted team (matches side by side, one
    /// batched forward pass for every robot of every match, the updates
    /// included), then steps the same environment with random actions alone,
    /// and prints both rates. Build with `--release` for meaningful figures.
    #[cfg(feature = "train")]
    Learn(super::bench_learn::BenchLearnArgs),
    /// PPO training speed (needs the `train` feature, libtorch: run it for
    /// what to build).
    #[cfg(not(feature = "train"))]
    Learn(super::not_built::NotBuilt),
    /// Many lockstep matches at once for a while, with well-behaved,
    /// reconnecting and misbehaving clients mixed in.
    ///
    /// Prints matches completed, ticks, errors by code, whether the server
    /// survived, peak RSS and RSS over time (is memory flat?). Build with
    /// `--release` for meaningful figures.
    Soak(super::soak::SoakArgs),
}

pub fn run(b: BenchCommand) -> anyhow::Result<()> {
    match b {
        BenchCommand::Sim(args) => super::play::bench_sim(args),
        BenchCommand::Server(args) => super::bench_server::bench(args),
        #[cfg(feature = "train")]
        BenchCommand::Learn(args) => super::bench_learn::bench_learn(args),
        #[cfg(not(feature = "train"))]
        BenchCommand::Learn(args) => super::not_built::run("bench learn", args),
        BenchCommand::Soak(args) => super::soak::soak(args),
    }
}
