//! A change of a match's state from outside the play (protocol 1.5's
//! `set_state`, as rcssserver's trainer moves things): where the ball and
//! some robots go. World coordinates (blue's frame: blue attacks +x).

use serde::{Deserialize, Serialize};

/// Where the ball goes, and how fast it rolls from there.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BallPlacement {
    /// Metres from the centre spot.
    pub x: f32,
    pub y: f32,
    /// Velocity along the ground, m/s (0 when left out or `null`).
    #[serde(default, deserialize_with = "null_as_default")]
    pub vx: f32,
    #[serde(default, deserialize_with = "null_as_default")]
    pub vy: f32,
}

/// Where one robot goes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RobotPlacement {
    /// The robot, 0..=7: blue players 0..=3, then red players 0..=3 (as in
    /// events). A plain number on the wire, checked by the referee, so an
    /// error can name the entry it is in.
    pub robot: u64,
    /// Its torso, metres from the centre spot.
    pub x: f32,
    pub y: f32,
    /// Radians, 0 facing +x; `None`: the heading it has.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub heading: Option<f32>,
    /// Lying on its back (its legs toward its heading), to get up after
    /// the stand-up time, instead of standing.
    #[serde(default, deserialize_with = "null_as_default")]
    pub fallen: bool,
}

/// A `set_state`'s change: the ball and any robots, each optional.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct StateChange {
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ball: Option<BallPlacement>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub robots: Vec<RobotPlacement>,
}

/// An optional field that may also be given as `null`, which is the same as
/// leaving it out (docs/PROTOCOL.md, section 3).
pub(crate) fn null_as_default<'de, D, T>(d: D) -> Result<T, D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de> + Default,
{
    Ok(Option::<T>::deserialize(d)?.unwrap_or_default())
}
