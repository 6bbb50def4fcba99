//! The naosoccer command line: one binary for matches, the server, robot
//! clients, recordings, learning and benchmarks. Each subcommand lives in its
//! own module under `cmd/`; this file only parses and dispatches.

use clap::{Parser, Subcommand};

mod cmd;

#[derive(Parser, Debug)]
#[command(name = "naosoccer", version, about = "Headless 4v4 NAO-robot soccer: match server, clients, recordings and learning")]
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
    /// Benchmarks that print figures.
    #[command(subcommand)]
    Bench(cmd::bench::BenchCommand),
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Match(args) => cmd::play::run(args),
        Command::Server(args) => cmd::server::run(args),
        Command::Client(args) => cmd::client::run(args),
        Command::Bench(b) => cmd::bench::run(b),
    }
}
