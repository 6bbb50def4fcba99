//! The error reply and its codes.

use serde::{Deserialize, Serialize};
use std::fmt;

use super::ServerMsg;
use crate::types::Tick;

/// Stable error codes (the gRPC canonical names, in snake case).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ErrorCode {
    /// Malformed JSON, a missing or ill-typed field, a value out of range.
    InvalidArgument,
    /// The request is valid but not in this state: before `hello`, joining
    /// twice, a slot already taken, acting without a join, a finished match.
    FailedPrecondition,
    /// No such match.
    NotFound,
    /// Wrong token, or acting for a player the connection does not control.
    PermissionDenied,
    /// Unknown message type, or an unsupported protocol major version.
    Unimplemented,
    /// A frame over the cap, or the server is at its connection/match limit.
    ResourceExhausted,
    /// An action arrived after its tick was played (lockstep).
    DeadlineExceeded,
    /// The server is shutting down.
    Unavailable,
    /// A bug in the server.
    Internal,
    /// A code from a newer protocol version.
    #[serde(other)]
    Unknown,
}

impl ErrorCode {
    pub fn as_str(self) -> &'static str {
        match self {
            ErrorCode::InvalidArgument => "invalid_argument",
            ErrorCode::FailedPrecondition => "failed_precondition",
            ErrorCode::NotFound => "not_found",
            ErrorCode::PermissionDenied => "permission_denied",
            ErrorCode::Unimplemented => "unimplemented",
            ErrorCode::ResourceExhausted => "resource_exhausted",
            ErrorCode::DeadlineExceeded => "deadline_exceeded",
            ErrorCode::Unavailable => "unavailable",
            ErrorCode::Internal => "internal",
            ErrorCode::Unknown => "unknown",
        }
    }
}

impl fmt::Display for ErrorCode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// The error reply. `fatal: true` means the server closes the connection
/// right after sending it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ErrorMsg {
    pub code: ErrorCode,
    pub message: String,
    pub fatal: bool,
    /// The `type` of the message this answers, when known.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub in_reply_to: Option<String>,
    /// For rejected actions: the tick the action named.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tick: Option<Tick>,
}

impl ErrorMsg {
    pub fn new(code: ErrorCode, message: impl Into<String>) -> ErrorMsg {
        ErrorMsg {
            code,
            message: message.into(),
            fatal: false,
            in_reply_to: None,
            tick: None,
        }
    }
    pub fn fatal(mut self) -> ErrorMsg {
        self.fatal = true;
        self
    }
    pub fn in_reply_to(mut self, kind: &str) -> ErrorMsg {
        self.in_reply_to = Some(kind.to_owned());
        self
    }
}

impl fmt::Display for ErrorMsg {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.code, self.message)?;
        if self.fatal {
            f.write_str(" (fatal)")?;
        }
        Ok(())
    }
}

impl std::error::Error for ErrorMsg {}

impl From<ErrorMsg> for ServerMsg {
    fn from(e: ErrorMsg) -> ServerMsg {
        ServerMsg::Error(e)
    }
}
