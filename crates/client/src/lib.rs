//! The robot side of naosoccer: the `Policy` trait, the built-in policies
//! (scripted, random, idle) and, over the socket protocol, the client library
//! and the robot client loop.

pub mod policy;

pub use policy::{Policy, PolicyKind};
