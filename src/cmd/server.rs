//! `naosoccer server`.
use clap::Args;

#[derive(Args, Debug)]
pub struct ServerArgs {}

pub fn run(_args: ServerArgs) -> anyhow::Result<()> {
    anyhow::bail!("`server` is being built")
}
