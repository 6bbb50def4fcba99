//! The naosoccer command line: one binary for matches, the server, robot
//! clients, recordings, learning and benchmarks. Each subcommand lives in its
//! own module under `cmd/`; this file only parses and dispatches.

use clap::{Parser, Subcommand};

mod cmd;

#[derive(Parser, Debug)]
#[command(
    name = "naosoccer",
    version,
    about = "Headless 4v4 NAO-robot soccer: match server, clients, recordings and learning"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Play a whole match in process and print the score and statistics.
    Match(cmd::play::MatchArgs),
    /// Run the match server.
    Server(cmd::server::ServerArgs),
    /// Run robot clients that join a match on a server.
    Client(cmd::client::ClientArgs),
    /// Re-simulate a recording and check every tick against it.
    Replay(cmd::record::ReplayArgs),
    /// Draw a recording as a top view of the pitch (PNG, or an animated GIF).
    Render(cmd::record::RenderArgs),
    /// Train a DQN or PPO team in process (checkpoints, metrics CSV).
    #[cfg(feature = "learn")]
    Train(cmd::learn::TrainArgs),
    /// Play many matches between two teams; Table I with 95% CIs.
    #[cfg(feature = "learn")]
    Eval(cmd::learn::EvalArgs),
    /// Draw training curves (long-term average reward) as a PNG.
    #[cfg(feature = "learn")]
    Plot(cmd::learn::PlotArgs),
    /// Benchmarks that print figures.
    #[command(subcommand)]
    Bench(cmd::bench::BenchCommand),
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        // Replay's exit code says what it found, so it reports by itself.
        Command::Replay(args) => return cmd::record::replay_cmd(args),
        Command::Render(args) => cmd::record::render_cmd(args),
        Command::Match(args) => cmd::play::run(args),
        Command::Server(args) => cmd::server::run(args),
        Command::Client(args) => cmd::client::run(args),
        Command::Bench(b) => cmd::bench::run(b),
        #[cfg(feature = "learn")]
        Command::Train(args) => cmd::learn::train_cmd(args),
        #[cfg(feature = "learn")]
        Command::Eval(args) => cmd::learn::eval_cmd(args),
        #[cfg(feature = "learn")]
        Command::Plot(args) => cmd::learn::plot_cmd(args),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::ExitCode::FAILURE
        }
    }
}
