//! Stopping cleanly: Ctrl-C (SIGINT) and SIGTERM for the commands that
//! keep what they have done so far (`match --record` finishes its recording,
//! `eval` and `league` report the matches already played), and the default
//! SIGPIPE for commands whose output may be piped into `head`.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, OnceLock};

static FLAG: OnceLock<Arc<AtomicBool>> = OnceLock::new();

/// The exit status of a command stopped by Ctrl-C (128 + SIGINT), as shells
/// report it.
pub const EXIT_INTERRUPTED: u8 = 130;

/// Starts watching for Ctrl-C and SIGTERM (once; later calls do nothing):
/// from then on a first signal sets [`interrupted`] instead of killing the
/// process, and a second one kills it at once, for a user who does not want
/// to wait. Fails only if the handlers cannot be installed.
pub fn watch() -> std::io::Result<()> {
    if FLAG.get().is_some() {
        return Ok(());
    }
    let flag = Arc::new(AtomicBool::new(false));
    #[cfg(unix)]
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        // Registered first, so it runs while the flag is still clear on the
        // first signal and exits on the second.
        signal_hook::flag::register_conditional_shutdown(sig, 130, Arc::clone(&flag))?;
        signal_hook::flag::register(sig, Arc::clone(&flag))?;
    }
    #[cfg(not(unix))]
    signal_hook::flag::register(signal_hook::consts::SIGINT, Arc::clone(&flag))?;
    let _ = FLAG.set(flag);
    Ok(())
}

/// Whether Ctrl-C or SIGTERM arrived since [`watch`] (false without it).
pub fn interrupted() -> bool {
    FLAG.get().is_some_and(|f| f.load(Ordering::Relaxed))
}

/// Restores the default action of SIGPIPE, which the Rust runtime ignores,
/// so that a command writing into a closed pipe (`naosoccer eval | head`)
/// ends quietly, as other command-line tools do, instead of panicking in
/// `println!`. Only for commands that write to no socket: a peer closing a
/// socket would then end the process too.
pub fn default_sigpipe() {
    #[cfg(unix)]
    // SAFETY: setting a signal's disposition to SIG_DFL at start-up, before
    // any thread is spawned; no handler function is involved.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// A command stopped by Ctrl-C after keeping what it had done: `main`
/// prints it and exits with [`EXIT_INTERRUPTED`].
#[derive(Debug)]
pub struct Interrupted(String);

impl Interrupted {
    /// `what` says what was kept, e.g. "eval stopped after 12 of 100 matches".
    pub fn new(what: impl Into<String>) -> Interrupted {
        Interrupted(what.into())
    }
}

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "interrupted: {}", self.0)
    }
}

impl std::error::Error for Interrupted {}
