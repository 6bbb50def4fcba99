//! The commands a build without the `train` feature leaves out (`train`,
//! `plot`, `bench learn`: they link libtorch). They still parse, whatever
//! their arguments, and say exactly what to run instead of failing obscurely.

use clap::Args;

/// A left-out command's arguments, taken as they come (`--help` included).
#[derive(Args, Debug)]
#[command(disable_help_flag = true)]
pub struct NotBuilt {
    #[arg(trailing_var_arg = true, allow_hyphen_values = true, num_args = 0..)]
    args: Vec<String>,
}

/// What to run for `naosoccer COMMAND ARGS...` in a build that has it.
pub fn instructions(command: &str, args: &[String]) -> String {
    let mut line = format!("target/release/naosoccer {command}");
    for a in args {
        line.push(' ');
        line.push_str(a);
    }
    format!(
        "naosoccer {command} needs libtorch, and this naosoccer was built without it \
         (the default build plays every team, trained ones included, but does not train). \
         From the repository, run:\n  \
         scripts/setup                            # once: libtorch (the PyPI torch wheel, about 4.7 GB)\n  \
         cargo build --release --features train   # naosoccer with training\n  \
         {line}"
    )
}

pub fn run(command: &str, a: NotBuilt) -> anyhow::Result<()> {
    anyhow::bail!("{}", instructions(command, &a.args))
}
