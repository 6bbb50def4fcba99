//! Sim configuration the referee derives its timing from (the pitch's
//! shape is [`crate::Field::from_sim`]'s).

use naosoccer_sim::SimConfig;

/// Physics steps in one control tick (at least one).
pub(crate) fn steps_per_tick(cfg: &SimConfig, control_hz: f32) -> u32 {
    ((1.0 / (f64::from(control_hz) * f64::from(cfg.dt))).round() as u32).max(1)
}
