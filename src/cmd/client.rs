//! `naosoccer client`.
use clap::Args;

#[derive(Args, Debug)]
pub struct ClientArgs {}

pub fn run(_args: ClientArgs) -> anyhow::Result<()> {
    anyhow::bail!("`client` is being built")
}
