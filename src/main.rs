//! The naosoccer command line: one binary for matches, the server, robot
//! clients, recordings, learning and benchmarks. Each subcommand lives in its
//! own module under `cmd/`; this file only parses and dispatches.

use clap::{Parser, Subcommand};

mod cmd;

use naosoccer::interrupt;

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
    #[cfg(feature = "train")]
    Train(Box<cmd::learn::TrainArgs>),
    /// Train a DQN or PPO team (needs the `train` feature, libtorch: run it
    /// for what to build).
    #[cfg(not(feature = "train"))]
    Train(cmd::not_built::NotBuilt),
    /// Play many matches between two teams; Table I with 95% CIs.
    Eval(cmd::eval::EvalArgs),
    /// Play every drill of the academy (scenarios with end conditions),
    /// many starts each: success rates with 95% intervals.
    Academy(cmd::academy::AcademyArgs),
    /// Play a round robin between teams; a Bradley–Terry rating per team
    /// with 95% intervals, W/D/L and goals by phase.
    League(cmd::league::LeagueArgs),
    /// Draw training curves (long-term average reward) as a PNG.
    #[cfg(feature = "train")]
    Plot(cmd::learn::PlotArgs),
    /// Draw training curves (needs the `train` feature: run it for what to
    /// build).
    #[cfg(not(feature = "train"))]
    Plot(cmd::not_built::NotBuilt),
    /// Benchmarks that print figures.
    #[command(subcommand)]
    Bench(cmd::bench::BenchCommand),
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    // Commands that write tables or JSON and talk over no socket end quietly
    // when their output pipe closes (`naosoccer eval | head`).
    let pipes_only = match &cli.command {
        Command::Match(a) => a.live.is_none(),
        Command::Eval(_) | Command::League(_) | Command::Academy(_) | Command::Render(_) => true,
        Command::Replay(a) => a.live.is_none(),
        _ => false,
    };
    if pipes_only {
        interrupt::default_sigpipe();
    }
    let result = match cli.command {
        // Replay's exit code says what it found, so it reports by itself.
        Command::Replay(args) => return cmd::record::replay_cmd(args),
        Command::Render(args) => cmd::record::render_cmd(args),
        Command::Match(args) => cmd::play::run(args),
        Command::Server(args) => cmd::server::run(args),
        Command::Client(args) => cmd::client::run(args),
        Command::Bench(b) => cmd::bench::run(b),
        Command::Eval(args) => cmd::eval::eval_cmd(args),
        Command::League(args) => cmd::league::league_cmd(args),
        Command::Academy(args) => cmd::academy::academy_cmd(args),
        #[cfg(feature = "train")]
        Command::Train(args) => cmd::learn::train_cmd(*args),
        #[cfg(feature = "train")]
        Command::Plot(args) => cmd::learn::plot_cmd(args),
        #[cfg(not(feature = "train"))]
        Command::Train(args) => cmd::not_built::run("train", args),
        #[cfg(not(feature = "train"))]
        Command::Plot(args) => cmd::not_built::run("plot", args),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) if e.downcast_ref::<interrupt::Interrupted>().is_some() => {
            eprintln!("{e}");
            std::process::ExitCode::from(interrupt::EXIT_INTERRUPTED)
        }
        Err(e) => {
            eprintln!("error: {}", cmd::error_text(&e));
            std::process::ExitCode::FAILURE
        }
    }
}
