//! The listener: accepting, the connection limits, graceful shutdown.

use crate::config::ServerConfig;
use crate::handler;
use crate::observer::Hooks;
use crate::shared::{CreateError, Shared};
use naosoccer_proto::frame::encode;
use naosoccer_proto::msg::{CreateMatch, ErrorCode, ErrorMsg, ServerMsg};
use std::future::Future;
use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::Duration;
use tokio::io::AsyncWriteExt;
use tokio::net::{TcpListener, TcpStream};
use tokio::sync::{mpsc, watch, Semaphore};

/// Why the server could not run.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ServerError {
    #[error(transparent)]
    Config(#[from] crate::config::ConfigError),
    #[error("could not create match: {0}")]
    Match(#[from] naosoccer_referee::MatchError),
    #[error("i/o error: {0}")]
    Io(#[from] std::io::Error),
}

/// Serves until `shutdown` completes, then stops every match (clients get
/// `match_end` with reason `shutdown`, then an `unavailable` error) and
/// returns once all connections and matches are done.
pub async fn run(
    listener: TcpListener,
    config: ServerConfig,
    shutdown: impl Future,
) -> Result<(), ServerError> {
    run_with(listener, config, Hooks::default(), shutdown).await
}

/// [`run`] with extension points (per-match observers).
pub async fn run_with(
    listener: TcpListener,
    mut config: ServerConfig,
    hooks: Hooks,
    shutdown: impl Future,
) -> Result<(), ServerError> {
    config.validate()?;
    let tokens = config.resolve_tokens();
    let (shutdown_tx, shutdown_rx) = watch::channel(false);
    let (done_tx, mut done_rx) = mpsc::channel::<()>(1);
    let limit = Arc::new(Semaphore::new(config.max_connections));
    let auto_matches = config.matches;
    let shared = Arc::new(Shared::new(config, tokens, hooks, shutdown_rx, done_tx));
    for _ in 0..auto_matches {
        shared
            .create_match(&CreateMatch::default())
            .map_err(|e| match e {
                CreateError::Build(e) => ServerError::Match(e),
                CreateError::Refused(e) => ServerError::Io(std::io::Error::other(format!(
                    "creating the configured matches: {e}"
                ))),
            })?;
    }
    tracing::info!(addr = ?listener.local_addr().ok(), matches = auto_matches, "serving");

    tokio::pin!(shutdown);
    loop {
        let accepted = tokio::select! {
            _ = &mut shutdown => break,
            a = listener.accept() => a,
        };
        let (stream, peer) = match accepted {
            Ok(a) => a,
            Err(e) => {
                // Out of file descriptors and the like: back off instead of spinning.
                tracing::error!(error = %e, "accept failed");
                tokio::time::sleep(Duration::from_millis(100)).await;
                continue;
            }
        };
        let id = shared.next_conn.fetch_add(1, Ordering::Relaxed);
        let Ok(permit) = limit.clone().try_acquire_owned() else {
            tracing::warn!(%peer, "connection limit reached; refusing");
            let m = "the server is at its connection limit (max_connections); try again later";
            tokio::spawn(refuse(stream, m, shared.task_guard()));
            continue;
        };
        let Some(addr_slot) = shared.claim_addr(peer.ip()) else {
            tracing::warn!(%peer, "per-address connection limit reached; refusing");
            let m = "too many connections from your address (max_connections_per_addr)";
            tokio::spawn(refuse(stream, m, shared.task_guard()));
            continue;
        };
        set_keepalive(&stream, shared.config.limits.keepalive_s);
        let conn_shared = shared.clone();
        tokio::spawn(async move {
            let guard = conn_shared.task_guard();
            handler::serve(stream, peer, id, conn_shared).await;
            drop((permit, addr_slot, guard));
        });
    }

    tracing::info!("shutting down");
    drop(listener);
    let _ = shutdown_tx.send(true);
    drop(shared);
    // Every task holds a `done` sender; recv yields None once all have ended.
    let _ = done_rx.recv().await;
    tracing::info!("shut down");
    Ok(())
}

/// Dead peers (a machine that vanished) are found by the kernel's probes.
fn set_keepalive(stream: &TcpStream, secs: u64) {
    if secs == 0 {
        return;
    }
    let ka = socket2::TcpKeepalive::new().with_time(Duration::from_secs(secs));
    if let Err(e) = socket2::SockRef::from(stream).set_tcp_keepalive(&ka) {
        tracing::debug!(error = %e, "cannot set TCP keepalive");
    }
}

async fn refuse(mut stream: TcpStream, message: &'static str, guard: mpsc::Sender<()>) {
    let e = ErrorMsg::new(ErrorCode::ResourceExhausted, message).fatal();
    if let Ok(bytes) = encode(&ServerMsg::Error(e)) {
        // A refused peer that does not read cannot hold this task long.
        let _ = tokio::time::timeout(Duration::from_secs(5), stream.write_all(&bytes)).await;
    }
    let _ = stream.shutdown().await;
    drop(guard);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 15: a configured match whose world does not build stops the
    /// server with `ServerError::Match`, the referee's error, not an I/O error.
    #[tokio::test]
    async fn issue_15_a_match_that_does_not_build_is_a_match_error() {
        let mut config = ServerConfig::default();
        // The referee leaves dt to the sim, which refuses it when the
        // match builds its world; the server's own checks pass.
        config.match_cfg.sim.dt = 0.0;
        config
            .validate()
            .expect("the server config itself is valid");
        let listener = TcpListener::bind("127.0.0.1:0").await.unwrap();
        let r = run(listener, config, std::future::pending::<()>()).await;
        match r {
            Err(ServerError::Match(naosoccer_referee::MatchError::Sim(e))) => {
                assert!(e.to_string().contains("dt"), "{e}");
            }
            other => panic!("expected ServerError::Match, got {other:?}"),
        }
    }
}
