//! One module per subcommand (or family of subcommands).
pub mod academy;
pub mod bench;
#[cfg(feature = "train")]
pub mod bench_learn;
pub mod bench_server;
pub mod client;
pub mod eval;
pub mod league;
#[cfg(feature = "train")]
pub mod learn;
#[cfg(not(feature = "train"))]
pub mod not_built;
pub mod play;
#[cfg(feature = "train")]
pub mod recipe;
pub mod record;
pub mod server;
pub mod soak;
pub mod team;

/// An error and its causes on one line, `error: cause: cause`, each cause
/// said once: many of our errors already put their cause's text in their
/// own message (and also hand it on as their `source`), so a cause whose
/// text the line already holds is left out.
pub fn error_text(e: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if text.is_empty() || line.contains(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line
}

#[cfg(test)]
mod tests {
    use super::error_text;

    #[test]
    fn a_cause_already_in_the_message_is_said_once() {
        let err =
            naosoccer_referee::MatchConfig::from_toml_str("[match]\nminutes = \"x\"").unwrap_err();
        let e = anyhow::Error::new(err).context("loading bad.toml");
        let text = error_text(&e);
        assert!(text.starts_with("loading bad.toml: invalid match config: TOML parse error"));
        assert_eq!(text.matches("TOML parse error").count(), 1, "{text}");
        // A cause not in the message is kept.
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "no such file");
        let e = anyhow::Error::new(io).context("reading x.toml");
        assert_eq!(error_text(&e), "reading x.toml: no such file");
    }
}
