//! `naosoccer match`: a whole match in process.
use clap::Args;

#[derive(Args, Debug)]
pub struct MatchArgs {}

pub fn run(_args: MatchArgs) -> anyhow::Result<()> {
    anyhow::bail!("`match` is being built")
}
